"""What the benchmark adapters' ``check`` and ``solve`` commands share.

``jaxspline aeossp ...`` and ``jaxspline regional ...`` both take a case folder and an
optional ``--json OUT`` report (``-`` = stdout), check a solution with their own
independent checker, print its report and exit 0 when it is valid, 1 when not.
"""

from __future__ import annotations

import time
from pathlib import Path

from jaxspline.cli.flags import check_output_file, check_path

__all__ = ["check_and_print", "check_case_paths", "write_report"]


def write_report(target: str, text: str) -> None:
    """Write ``text`` and a newline to ``target`` atomically, or print it for ``-``.

    Args:
      target: path, or ``-`` for stdout.
      text: the content, without its final newline.
    """
    if target == "-":
        print(text)
        return
    from jaxspline.planner.files import atomic_write_text

    atomic_write_text(Path(target), text + "\n")


def check_case_paths(args) -> None:
    """``CASE_DIR`` and ``--json`` of a check or solve command, each by its name.

    Raises:
      ValueError: naming the flag and the value.
    """
    check_path("CASE_DIR", args.case_dir, kind="dir", exists=True)
    check_output_file("--json", args.json)


def check_and_print(check_solution, format_report, case, solution: dict, json_out) -> int:
    """Check ``solution``, print the report, write its JSON to ``json_out`` if given.

    Args:
      check_solution: the adapter's checker, ``(case, solution) -> report`` with
        ``valid`` and ``to_json()``.
      format_report: ``report -> str``, the readable report.
      case: the loaded case.
      solution: the solution document.
      json_out: path, ``-`` or None.
    Returns:
      int, exit code: 0 valid, 1 invalid.
    """
    t0 = time.perf_counter()
    report = check_solution(case, solution)
    print(format_report(report))
    print(f"checked in {time.perf_counter() - t0:.1f} s")
    if json_out:
        write_report(json_out, report.to_json())
    return 0 if report.valid else 1
