"""Upper bound on the best achievable WCR of aeossp_standard cases (Lagrangian relaxation).

Usage: python scripts/aeossp_upper_bound.py [--iterations 300] [--achieved WCR]
       [--mip SECONDS] CASE_DIR...

Why it is an upper bound of every VALID plan (not only of the planner's candidate
model): the case is turned into a Scenario (:func:`jaxspline.aeossp.adapter.case_scenario`)
with margins LOOSER than the rules (off-nadir limit + 1e-5 deg, maneuver gap - 0.01 s,
horizon 0), so every grid-aligned observation of a valid plan is an option here (the
frame differences to the official chain are < 4e-7 deg; the slew table over-estimates
by < 1e-3 s), and each satellite's sequence, first slew from nadir included, is a path
of the per-satellite DP. Only "each task counts once" (priced with 0 <= lambda <= w, see
:mod:`jaxspline.search.lagrangian` for the argument that covers repeats) and the battery
(dropped) are relaxed, so every iteration's value bounds the optimum; the smallest is
reported. ``--achieved`` (a WCR some plan reaches) only sets the step size.

``--mip SECONDS`` also solves the same candidate model as a 0/1 program with HiGHS
(:func:`jaxspline.search.mip_bound`, repeats counted once, battery dropped) and reports
its dual bound after that many seconds: cuts and branching close gaps the Lagrangian
(= linear) relaxation cannot. Needs scipy.

Deterministic: a fixed number of subgradient iterations (``--iterations``); the
output says whether the iteration converged (zero projected subgradient or step
below its floor) or stopped at the cap.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from jaxspline.readers.config import Margins

LOOSE = Margins(off_nadir=math.radians(-1e-5), horizon=0.0, gap=-0.01)


def upper_bound(case_dir: str, iterations: int, achieved: float, mip: float = 0.0) -> dict:
    """Smallest Lagrangian bound on WCR within ``iterations`` for one case (and the
    HiGHS dual bound after ``mip`` seconds if > 0)."""
    from jaxspline.aeossp.adapter import case_scenario
    from jaxspline.aeossp.case import load_case
    from jaxspline.planner.build import build_problem
    from jaxspline.search import mip_bound
    from jaxspline.search import upper_bound as lagrangian_bound

    t0 = time.monotonic()
    case = load_case(case_dir)
    sc = case_scenario(case, margins=LOOSE)
    pb = build_problem(sc).problem
    w = np.asarray(pb.target_value, float)
    total = w.sum()
    has = np.zeros(w.size, bool)
    has[np.asarray(pb.option_target, np.int64)] = True
    trivial = w[has].sum()  # tasks without any option can never be completed
    res = lagrangian_bound(pb, achieved * total, math.inf, max_iters=iterations)
    out = {}
    if mip > 0.0:
        m = mip_bound(pb, mip)
        out = {
            "mip_wcr": min(m.bound, trivial) / total,
            "mip_plan_wcr": m.value / total,
            "mip_status": m.status,
            "mip_seconds": m.seconds,
        }
    return out | {
        "case": case.case_id,
        "ub_wcr": min(res.bound, trivial) / total,
        "trivial_wcr": trivial / total,
        "iterations": res.iterations,
        "status": res.status,
        "seconds": time.monotonic() - t0,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", help="case directories")
    ap.add_argument("--iterations", type=int, default=300, help="subgradient iterations (300)")
    ap.add_argument(
        "--achieved",
        type=float,
        default=0.70,
        help="a WCR some plan reaches (step-size target; default 0.70): a target above "
        "the optimum stalls the bound at the target",
    )
    ap.add_argument(
        "--mip", type=float, default=0.0, help="HiGHS seconds for the 0/1 program (0: skip)"
    )
    args = ap.parse_args(argv)
    bounds = []
    for c in args.cases:
        r = upper_bound(c, args.iterations, args.achieved, args.mip)
        bounds.append(r["ub_wcr"])
        print(
            f"{r['case']}: WCR <= {r['ub_wcr']:.4f} ({r['iterations']} iterations, "
            f"{r['status']}, {r['seconds']:.0f} s; tasks with any option: "
            f"{r['trivial_wcr']:.4f})",
            flush=True,
        )
        if "mip_wcr" in r:
            print(
                f"{r['case']}: MIP WCR <= {r['mip_wcr']:.4f} ({r['mip_status']}, "
                f"{r['mip_seconds']:.0f} s; HiGHS plan {r['mip_plan_wcr']:.4f})",
                flush=True,
            )
    print(f"mean upper bound: {np.mean(bounds):.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
