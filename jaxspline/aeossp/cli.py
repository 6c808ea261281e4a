"""``jaxspline aeossp solve|check``: the aeossp_standard benchmark adapter.

``jaxspline aeossp check CASE_DIR solution.json [--json OUT]`` prints the readable
report and the JSON result (to OUT, or stdout when OUT is ``-``); exit code 0 if the
solution is valid, 1 if not. ``jaxspline aeossp solve CASE_DIR -o solution.json
[--time-limit S] [--seed N] [--force]`` plans the case through :func:`jaxspline.plan`
(:mod:`jaxspline.aeossp.adapter`), prints the plan's bound and gap, writes the solution
atomically, then checks it with the independent checker (exit code as for ``check``).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from jaxspline.cli.case_commands import check_and_print, check_case_paths
from jaxspline.cli.flags import MAX_SEED, check_int, check_output_file, check_path, check_seconds

__all__ = ["register"]


def _check_and_print(case, solution: dict, json_out: str | None) -> int:
    from jaxspline.aeossp.check import check_solution, format_report

    return check_and_print(check_solution, format_report, case, solution, json_out)


def _cmd_check(args) -> int:
    from jaxspline.aeossp.case import load_case, load_solution

    check_case_paths(args)
    check_path("SOLUTION", args.solution, kind="file", exists=True)
    case = load_case(args.case_dir)
    solution = load_solution(args.solution)
    return _check_and_print(case, solution, args.json)


def _cmd_solve(args) -> int:
    from jaxspline.aeossp.case import load_case, write_solution

    check_seconds("--time-limit", args.time_limit)
    check_int("--seed", args.seed, 0, MAX_SEED)
    check_output_file("-o/--output", args.output, force=args.force)
    check_case_paths(args)
    out = Path(args.output)
    case = load_case(args.case_dir)
    from jaxspline.aeossp.adapter import solve_case

    t0 = time.perf_counter()
    solution, result = solve_case(case, time_limit=args.time_limit, seed=args.seed)
    elapsed = time.perf_counter() - t0
    write_solution(out, solution, force=args.force)
    tw = result.total_value or 1.0
    print(
        f"wrote {out} ({len(solution['actions'])} actions, planned in {elapsed:.1f} s): "
        f"WCR {result.value / tw:.4f}, bound {result.bound / tw:.4f} "
        f"({result.stats['bound_status']}), gap {result.gap / tw:.4f}",
        file=sys.stderr,
    )
    return _check_and_print(case, solution, args.json)


def register(sub) -> None:
    """Register ``aeossp check`` and ``aeossp solve`` on the ``jaxspline`` sub-parsers.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser("aeossp", help="aeossp_standard benchmark: solve or check a case")
    asub = p.add_subparsers(dest="aeossp_command", required=True)

    c = asub.add_parser("check", help="check a solution against RULES.md (exit 0 valid, 1 not)")
    c.add_argument("case_dir", help="case directory with mission/satellites/tasks.yaml")
    c.add_argument("solution", help="solution JSON file")
    c.add_argument("--json", metavar="OUT", help="write the JSON result to OUT ('-' = stdout)")
    c.set_defaults(func=_cmd_check)

    s = asub.add_parser("solve", help="plan a case, write the solution, then check it")
    s.add_argument("case_dir", help="case directory with mission/satellites/tasks.yaml")
    s.add_argument("-o", "--output", required=True, help="solution JSON file to write")
    s.add_argument("--time-limit", type=float, default=60.0, help="seconds (default 60)")
    s.add_argument("--seed", type=int, default=0, help="search seed (default 0)")
    s.add_argument("--force", action="store_true", help="overwrite an existing output file")
    s.add_argument("--json", metavar="OUT", help="write the check result to OUT ('-' = stdout)")
    s.set_defaults(func=_cmd_solve)
