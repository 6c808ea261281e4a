"""``jaxspline stereo ...``: the stereo_imaging benchmark adapter's commands.

``jaxspline stereo check CASE_DIR SOLUTION.json [--json OUT]`` checks a solution with the
independent checker (:mod:`jaxspline.stereo.check`), prints validity, coverage_ratio,
normalized_quality, the product counts, the covered targets and the violations, and
writes the JSON report to OUT (``-`` = stdout). Exit code 0 if the solution is valid,
1 if not, 2 on unreadable input files or a malformed solution (the ``jaxspline`` entry
point maps ``ValueError`` to 2, with a one-line message naming the file and the field).

``jaxspline stereo solve CASE_DIR -o solution.json [--time-limit S] [--seed N] [--force]
[--json OUT]`` translates the case (:func:`jaxspline.stereo.adapter.case_scenario`),
plans it with :func:`jaxspline.plan` within S seconds counted from the command's start,
writes the solution atomically, prints coverage, quality, looks, bound and gap, then
checks the solution as ``check`` does; the run lifecycle is the one of
:func:`jaxspline.cli.case_commands.run_solve`.

Each sub-command is one ``_cmd_*`` function plus a few lines in :func:`register`; the
checking and printing are :mod:`jaxspline.cli.case_commands`, shared with the other
adapters.
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


def _cmd_check(args) -> int:
    from jaxspline.stereo.case import load_case, load_solution
    from jaxspline.stereo.check import check_solution, format_report

    check_case_paths(args)
    check_path("SOLUTION", args.solution, kind="file", exists=True)
    case = load_case(args.case_dir)
    solution = load_solution(args.solution, case)
    return check_and_print(check_solution, format_report, case, solution, args.json)


def _summary(result) -> str:
    """The plan's line in the benchmark's units: covered targets and their quality."""
    rep = result.report.get("stereo", [])
    n = max(len(rep), 1)
    covered = sum(1 for r in rep if r.get("quality") is not None)
    coverable = sum(1 for r in rep if r.get("candidates"))
    quality = sum(r.get("quality") or 0.0 for r in rep)
    looks = int(sum(1 for r in result.observations.roll if r == r))
    return (
        f"coverage_ratio {covered / n:.5f} (bound {coverable / n:.5f}), quality "
        f"{quality / n:.5f}, {looks} looks; value {result.value:.6g}, bound "
        f"{result.bound:.6g} ({result.stats['bound_status']}), gap {result.gap:.6g}"
    )


def _cmd_solve(args) -> int:
    from jaxspline.stereo.adapter import case_scenario, solution_of
    from jaxspline.stereo.case import load_case, parse_solution
    from jaxspline.stereo.check import check_solution, format_report

    adapter = CaseAdapter(
        load_case=load_case,
        case_scenario=lambda case, limit: case_scenario(case, time_limit=limit),
        solution_of=solution_of,
        check_solution=lambda case, sol: check_solution(case, parse_solution(sol, case)),
        format_report=format_report,
        summary=_summary,
        tle_file="satellites.yaml",
    )
    return run_solve(args, adapter)


def register(sub) -> None:
    """Register ``stereo check`` on the ``jaxspline`` sub-parsers.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser("stereo", help="stereo_imaging benchmark: solve a case or check a solution")
    ssub = p.add_subparsers(dest="stereo_command", required=True)
    c = ssub.add_parser(
        "check", help="check a solution against RULES.md (exit 0 valid, 1 invalid, 2 bad input)"
    )
    c.add_argument("case_dir", help="case directory (mission.yaml, satellites.yaml, targets.yaml)")
    c.add_argument("solution", help="solution JSON file")
    c.add_argument("--json", metavar="OUT", help="write the JSON report to OUT ('-' = stdout)")
    c.set_defaults(func=_cmd_check)
    add_solve_parser(ssub, "mission.yaml, satellites.yaml, targets.yaml", 120.0, _cmd_solve)
