"""How low the path relaxation's bound can go on a scenario, and how high it is.

Usage: python scripts/relaxation_floor.py [SCENARIO.toml] [--plan-value V]
       [--time-limit S] [--max-iters N] [--fw-iters N] [--joins] [--json OUT.json]
       [--force]

Screens the scenario like ``jaxspline bound`` and ``jaxspline plan --no-aem`` (stages
1-4; ``--joins``: also the flown-join screening of a plan with AEM files, which keeps
fewer transitions), iterates the strengthened Lagrangian bound (battery dropped, as the
bound worker does: a plan's bound that prices the battery may be lower) and then builds a
fractional plan of the same relaxation by Frank-Wolfe steps
(:func:`jaxspline.search.floor.relaxation_floor`). The fractional plan's value is the
*floor*: the relaxation's optimum is at least that, so no price vector, however well
iterated, gives a bound below it. A plan worth ``V`` then has a gap of at least
``1 - V / floor`` against any bound of this relaxation; closing more needs a better
plan or a stronger relaxation than the linear one. Prints one line, writes ``--json``
(atomic; an existing file only with ``--force``).
"""

from __future__ import annotations

import argparse
import json
import math
import time

from jaxspline.cli.flags import (
    MAX_ITERS,
    check_int,
    check_output_file,
    check_path,
    check_seconds,
    check_value,
)
from jaxspline.planner.files import atomic_write_text


def measure(scenario, plan_value, time_limit, max_iters, fw_iters, joins=False) -> dict:
    """Floor and bound of ``scenario`` (path or None: the built-in one) as a dict."""
    from jaxspline.planner.build import build_problem
    from jaxspline.readers.scenario import default_scenario, load_scenario
    from jaxspline.search import Timeline, greedy
    from jaxspline.search.floor import relaxation_floor

    t0 = time.monotonic()
    sc = default_scenario() if scenario is None else load_scenario(scenario)
    pb = build_problem(sc, joins=joins).problem
    built = time.monotonic() - t0
    if plan_value is None:  # the step size's target: a greedy plan's value
        tl = Timeline(pb)
        greedy(tl, math.inf)
        plan_value = tl.value
    deadline = time.monotonic() + time_limit
    res = relaxation_floor(pb, plan_value, deadline, max_iters, fw_iters)
    return {
        "scenario": sc.name,
        "options": int(pb.n_options),
        "joins": bool(joins),
        "floor": res.floor,
        "bound": res.bound,
        "bound_iterations": res.iterations,
        "fw_iterations": res.fw_iterations,
        "plan_value": plan_value,
        "build_seconds": built,
        "seconds": res.seconds,
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenario", nargs="?", default=None, help="scenario TOML (default: built-in)")
    ap.add_argument(
        "--plan-value",
        type=float,
        default=None,
        help="a value some plan reaches (the bound's step size; default a greedy plan's)",
    )
    ap.add_argument(
        "--time-limit",
        type=float,
        default=600.0,
        help="budget of the bound's iterations [s] (600; the Frank-Wolfe steps come after)",
    )
    ap.add_argument("--max-iters", type=int, default=None, help="cap on the bound's iterations")
    ap.add_argument("--fw-iters", type=int, default=200, help="Frank-Wolfe steps (200)")
    ap.add_argument(
        "--joins", action="store_true", help="screen transitions with the flown joins too"
    )
    ap.add_argument("--json", default=None, help="write the result here (-: standard output)")
    ap.add_argument("--force", action="store_true", help="overwrite --json")
    args = ap.parse_args(argv)
    try:  # every flag by its name, before any work (the CLI's checks)
        check_path("SCENARIO", args.scenario, kind="file", exists=True)
        check_value("--plan-value", args.plan_value)
        check_seconds("--time-limit", args.time_limit)
        check_int("--max-iters", args.max_iters, 1, MAX_ITERS)
        check_int("--fw-iters", args.fw_iters, 0, MAX_ITERS)
        check_output_file("--json", args.json, force=args.force)
    except (ValueError, OSError) as exc:
        ap.error(str(exc))
    r = measure(
        args.scenario, args.plan_value, args.time_limit, args.max_iters, args.fw_iters, args.joins
    )
    print(
        f"{r['scenario']}: floor {r['floor']:.1f} <= relaxation optimum <= bound "
        f"{r['bound']:.1f} ({r['bound_iterations']} iterations, {r['fw_iterations']} "
        f"Frank-Wolfe steps, {r['seconds']:.0f} s)",
        flush=True,
    )
    text = json.dumps(r, indent=1) + "\n"
    if args.json == "-":
        print(text, end="")
    elif args.json is not None:
        atomic_write_text(args.json, text, force=args.force)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
