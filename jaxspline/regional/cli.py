"""``jaxspline regional ...``: the regional_coverage benchmark adapter's commands.

``jaxspline regional check CASE_DIR SOLUTION.json [--json OUT]`` checks a solution with
the independent checker (:mod:`jaxspline.regional.check`), prints coverage_ratio,
weighted_coverage_ratio, num_actions, the lowest battery level and the violations, and
writes the JSON report to OUT (``-`` = stdout). Exit code 0 if the solution is valid,
1 if not, 2 on unreadable input files.

``jaxspline regional solve CASE_DIR -o solution.json [--time-limit S] [--seed N] [--force]
[--json OUT]`` translates the case (:func:`jaxspline.regional.adapter.case_scenario`),
plans it with :func:`jaxspline.plan` within S seconds counted from the command's start,
writes the solution atomically, prints coverage, actions, bound and gap, then checks the
solution as ``check`` does; the run lifecycle (output checked before planning, Ctrl-C or
SIGTERM writes the best plan so far and exits 130, the TLEs' age) is the one of
:func:`jaxspline.cli.case_commands.run_solve`.
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


def _summary(result) -> str:
    """The plan's line in the benchmark's units (coverage_ratio is the plan's value)."""
    actions = int(sum(1 for r in result.observations.roll if r == r))
    return (
        f"coverage_ratio {result.value:.5f}, {actions} actions, bound {result.bound:.5f} "
        f"({result.stats['bound_status']}), gap {result.gap:.5f}"
    )


def _cmd_solve(args) -> int:
    from jaxspline.regional.adapter import case_scenario, solution_of
    from jaxspline.regional.case import load_case
    from jaxspline.regional.check import check_solution, format_report

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
    """Register ``regional check`` and ``regional solve`` on the ``jaxspline`` sub-parsers.

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
    add_solve_parser(rsub, "manifest.json, satellites.yaml, ...", 120.0, _cmd_solve)
