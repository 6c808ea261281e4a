"""``jaxspline aeossp solve|check``: the aeossp_standard benchmark adapter.

``jaxspline aeossp check CASE_DIR solution.json [--json OUT]`` prints the readable
report and the JSON result (to OUT, or stdout when OUT is ``-``); exit code 0 if the
solution is valid, 1 if not. ``jaxspline aeossp solve CASE_DIR -o solution.json
[--time-limit S] [--seed N] [--force]`` plans the case through :func:`jaxspline.plan`
(:mod:`jaxspline.aeossp.adapter`), prints the plan's bound and gap, writes the solution
atomically, then checks it with the independent checker (exit code as for ``check``);
its run lifecycle (output checked before planning, Ctrl-C or SIGTERM writes the best
plan so far and exits 130, the TLEs' age) is
:func:`jaxspline.cli.case_commands.run_solve`'s.
"""

from __future__ import annotations

from jaxspline.cli.case_commands import (
    CaseAdapter,
    add_solve_parser,
    check_and_print,
    check_case_paths,
    run_solve,
)
from jaxspline.cli.flags import check_path

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


def _summary(result) -> str:
    """The plan's line in the benchmark's units (the weighted completion ratio)."""
    tw = result.total_value or 1.0
    return (
        f"{len(result.observations)} actions, WCR {result.value / tw:.4f}, bound "
        f"{result.bound / tw:.4f} ({result.stats['bound_status']}), gap {result.gap / tw:.4f}"
    )


def _cmd_solve(args) -> int:
    from jaxspline.aeossp.adapter import case_scenario, solution_of
    from jaxspline.aeossp.case import load_case
    from jaxspline.aeossp.check import check_solution, format_report

    adapter = CaseAdapter(
        load_case=load_case,
        case_scenario=lambda case, limit: case_scenario(case, time_limit=limit),
        solution_of=solution_of,
        check_solution=check_solution,
        format_report=format_report,
        summary=_summary,
        tle_file="satellites.yaml",
    )
    return run_solve(args, adapter)


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

    add_solve_parser(asub, "mission/satellites/tasks.yaml", 60.0, _cmd_solve)
