"""Upper bound on the best achievable WCR of aeossp_standard cases (Lagrangian relaxation).

Usage: python scripts/aeossp_upper_bound.py [--budget SECONDS] [--achieved WCR] CASE_DIR...

Why it is an upper bound: every valid plan consists of grid-aligned observations, each of
which is a candidate of the solver's candidate model built here with margins LOOSER than
the rules (off-nadir +1e-5 deg, slew gap -0.01 s, horizon 0), and its per-satellite
sequence (including the first slew from nadir) is a path of the per-satellite exact DP.
Only two constraints are relaxed: "each task at most once across satellites" (priced with
multipliers lambda >= 0) and the battery (dropped). For any valid plan,
weight = sum(w - lambda) over its actions + sum(lambda) over completed tasks
      <= sum of per-satellite DP optima + sum(lambda),
so every iteration gives a valid bound; the smallest is reported. Multipliers follow
Polyak subgradient steps aimed at ``--achieved`` (a WCR some plan reaches; it only sets
the step size, not the validity of the bound).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np


def upper_bound(case_dir: str, budget_s: float, achieved: float) -> dict:
    """Smallest Lagrangian bound on WCR found within ``budget_s`` seconds for one case."""
    from jaxspline.aeossp.case import load_case
    from jaxspline.aeossp.solve import Margins, _dp_paths, _dp_prepare, _prepare

    t0 = time.monotonic()
    case = load_case(case_dir)
    pb = _prepare(case, Margins(off_nadir_deg=-1e-5, horizon=0.0, gap_s=-0.01), thin=1)
    dp = _dp_prepare(pb)
    w = np.asarray(pb.weight, float)
    total = w.sum()
    ctask = np.asarray(pb.c_task, np.int64)
    has = np.zeros(w.size, bool)
    has[ctask] = True
    trivial = w[has].sum()  # tasks without any candidate can never be completed
    target = achieved * total
    lam = np.zeros(w.size)
    best, best_lam, step, stall, it = math.inf, lam.copy(), 1.0, 0, 0
    while time.monotonic() - t0 < budget_s:
        it += 1
        paths, vals = _dp_paths(pb, dp, w[ctask] - lam[ctask])
        bound = float(sum(vals) + lam.sum())
        if bound < best - 1e-9:
            best, best_lam, stall = bound, lam.copy(), 0
        else:
            stall += 1
            if stall >= 6:  # halve the step and restart from the best multipliers
                step, stall, lam = 0.5 * step, 0, best_lam.copy()
                continue
        count = np.zeros(w.size)
        for p in paths:
            np.add.at(count, ctask[p], 1.0)
        g = count - 1.0
        g[(lam <= 0.0) & (g < 0.0)] = 0.0
        gn = float(g @ g)
        if gn == 0.0:  # the relaxed optimum is feasible: the bound is the optimum
            break
        lam = np.maximum(0.0, lam + step * max(bound - target, 1e-3) / gn * g)
    return {
        "case": case.case_id,
        "ub_wcr": min(best, trivial) / total,
        "trivial_wcr": trivial / total,
        "iterations": it,
        "seconds": time.monotonic() - t0,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="+", help="case directories")
    ap.add_argument("--budget", type=float, default=280.0, help="seconds per case (280)")
    ap.add_argument(
        "--achieved",
        type=float,
        default=0.75,
        help="a WCR known to be reachable (step-size target only; default 0.75)",
    )
    args = ap.parse_args(argv)
    import jax

    jax.config.update("jax_enable_x64", True)
    bounds = []
    for c in args.cases:
        r = upper_bound(c, args.budget, args.achieved)
        bounds.append(r["ub_wcr"])
        print(
            f"{r['case']}: WCR <= {r['ub_wcr']:.4f} ({r['iterations']} iterations, "
            f"{r['seconds']:.0f} s; tasks with any candidate: {r['trivial_wcr']:.4f})",
            flush=True,
        )
    print(f"mean upper bound: {np.mean(bounds):.4f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
