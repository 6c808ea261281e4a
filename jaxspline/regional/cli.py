"""``jaxspline regional ...``: the regional_coverage benchmark adapter's commands.

``jaxspline regional check CASE_DIR SOLUTION.json [--json OUT]`` checks a solution with
the independent checker (:mod:`jaxspline.regional.check`), prints coverage_ratio,
weighted_coverage_ratio, num_actions, the lowest battery level and the violations, and
writes the JSON report to OUT (``-`` = stdout). Exit code 0 if the solution is valid,
1 if not, 2 on unreadable input files (the ``jaxspline`` entry point maps ``ValueError``
to 2).

``jaxspline regional solve CASE_DIR -o solution.json [--time-limit S] [--seed N] [--force]
[--json OUT]`` plans the case (:func:`jaxspline.regional.solve.solve_case`) within S seconds
counted from the command's start, writes the solution atomically (an existing file only
with ``--force``), prints coverage, actions, bound and gap, then checks the solution as
``check`` does (same exit codes).

Each sub-command is one ``_cmd_*`` function plus a few lines in :func:`register`; a new
one adds its parser there; the checking and printing are
:mod:`jaxspline.cli.case_commands`, shared with the aeossp adapter.
"""

from __future__ import annotations

import time
from pathlib import Path

from jaxspline.cli.case_commands import check_and_print, check_case_paths, write_report
from jaxspline.cli.flags import MAX_SEED, check_int, check_output_file, check_path, check_seconds


def _check_and_print(case, solution, json_out: str | None) -> int:
    from jaxspline.regional.check import check_solution, format_report

    return check_and_print(check_solution, format_report, case, solution, json_out)


def _cmd_check(args) -> int:
    from jaxspline.regional.case import load_case, load_solution

    check_case_paths(args)
    check_path("SOLUTION", args.solution, kind="file", exists=True)
    case = load_case(args.case_dir)
    solution = load_solution(args.solution)
    return _check_and_print(case, solution, args.json)


def _cmd_solve(args) -> int:
    import json

    from jaxspline.regional.case import load_case
    from jaxspline.regional.solve import solve_case

    t0 = time.perf_counter()
    check_seconds("--time-limit", args.time_limit)
    check_int("--seed", args.seed, 0, MAX_SEED)
    check_output_file("-o/--output", args.output, force=args.force)
    check_case_paths(args)
    out = Path(args.output)
    case = load_case(args.case_dir)
    solution, st = solve_case(case, time_limit=args.time_limit, seed=args.seed, t_start=t0)
    write_report(str(out), json.dumps(solution, indent=1))
    print(
        f"wrote {out}: coverage_ratio {st['coverage_ratio']:.5f}, weighted "
        f"{st['weighted_coverage_ratio']:.5f}, {st['actions']} actions, bound {st['bound']:.5f}, "
        f"gap {st['gap']:.5f} ({time.perf_counter() - t0:.1f} s)"
    )
    return _check_and_print(case, solution, args.json)


def register(sub) -> None:
    """Register ``regional check`` on the ``jaxspline`` sub-parsers.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser(
        "regional", help="regional_coverage benchmark: solve a case or check a solution"
    )
    rsub = p.add_subparsers(dest="regional_command", required=True)
    c = rsub.add_parser(
        "check", help="check a solution against RULES.md (exit 0 valid, 1 invalid, 2 bad input)"
    )
    c.add_argument("case_dir", help="case directory (manifest.json, satellites.yaml, ...)")
    c.add_argument("solution", help="solution JSON file")
    c.add_argument("--json", metavar="OUT", help="write the JSON report to OUT ('-' = stdout)")
    c.set_defaults(func=_cmd_check)
    s = rsub.add_parser("solve", help="plan a case, write the solution, check it (exit 0 if valid)")
    s.add_argument("case_dir", help="case directory")
    s.add_argument("-o", "--output", required=True, help="solution JSON to write")
    s.add_argument("--time-limit", type=float, default=120.0, help="wall-clock budget [s]")
    s.add_argument("--seed", type=int, default=0, help="random seed of the search")
    s.add_argument("--force", action="store_true", help="overwrite an existing output file")
    s.add_argument("--json", metavar="OUT", help="write the check report to OUT ('-' = stdout)")
    s.set_defaults(func=_cmd_solve)
