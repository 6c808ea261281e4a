"""``jaxspline stereo ...``: the stereo_imaging benchmark adapter's commands.

``jaxspline stereo check CASE_DIR SOLUTION.json [--json OUT]`` checks a solution with the
independent checker (:mod:`jaxspline.stereo.check`), prints validity, coverage_ratio,
normalized_quality, the product counts, the covered targets and the violations, and
writes the JSON report to OUT (``-`` = stdout). Exit code 0 if the solution is valid,
1 if not, 2 on unreadable input files or a malformed solution (the ``jaxspline`` entry
point maps ``ValueError`` to 2, with a one-line message naming the file and the field).

Each sub-command is one ``_cmd_*`` function plus a few lines in :func:`register`; the
checking and printing are :mod:`jaxspline.cli.case_commands`, shared with the other
adapters. ``solve`` is added the same way (its parser next to ``check`` in
:func:`register`, its function ``_cmd_solve``).
"""

from __future__ import annotations

from jaxspline.cli.case_commands import check_and_print, check_case_paths
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


def register(sub) -> None:
    """Register ``stereo check`` on the ``jaxspline`` sub-parsers.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser("stereo", help="stereo_imaging benchmark: check a solution")
    ssub = p.add_subparsers(dest="stereo_command", required=True)
    c = ssub.add_parser(
        "check", help="check a solution against RULES.md (exit 0 valid, 1 invalid, 2 bad input)"
    )
    c.add_argument("case_dir", help="case directory (mission.yaml, satellites.yaml, targets.yaml)")
    c.add_argument("solution", help="solution JSON file")
    c.add_argument("--json", metavar="OUT", help="write the JSON report to OUT ('-' = stdout)")
    c.set_defaults(func=_cmd_check)
    # ``stereo solve`` registers here: ssub.add_parser("solve", ...), func=_cmd_solve
