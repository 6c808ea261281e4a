"""What the benchmark adapters' ``check`` and ``solve`` commands share.

``jaxspline aeossp ...``, ``jaxspline regional ...`` and ``jaxspline stereo ...`` take a
case folder and an optional ``--json OUT`` report (``-`` = stdout), check a solution
with their own independent checker, print its report and exit 0 when it is valid, 1
when not.

Their ``solve`` commands share one run lifecycle (:func:`run_solve`), the one of
``jaxspline plan``:

1. every flag is checked before any work; the output file's folder must take a new
   file of :data:`ROOM_BYTES` (written, synced and removed), and an existing file is
   replaced only with ``--force``;
2. the case is read and translated (:class:`CaseAdapter`: case -> :class:`Scenario`);
   a TLE whose epoch lies farther than the documented age from the horizon is refused,
   naming the case's file and the ages (:func:`tle_age_problem`);
3. :func:`jaxspline.plan` plans it under one deadline counted from the process's
   start (``--time-limit`` bounds the whole command: the stages before the search stop
   with exit 3 and a remedy, the search ends early enough to write and check);
4. Ctrl-C or SIGTERM stops the search: the best plan so far is repaired, written and
   checked, said so on stderr, and the command exits 130;
5. the solution is written atomically (:func:`write_solution`, the one writer) and
   checked by the adapter's independent checker.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import NamedTuple

from jaxspline.cli.flags import MAX_SEED, check_int, check_output_file, check_path, check_seconds
from jaxspline.cli.startup import EXIT_INTERRUPTED

__all__ = [
    "ROOM_BYTES",
    "CaseAdapter",
    "check_and_print",
    "check_case_paths",
    "run_solve",
    "tle_age_problem",
    "write_report",
    "write_solution",
]

#: A solution's folder must take this much before planning starts [bytes].
ROOM_BYTES = 1 << 20
#: Seconds kept after the search for writing and checking the solution.
WRITE_AND_CHECK_S = 5.0


class CaseAdapter(NamedTuple):
    """What a benchmark adapter gives :func:`run_solve`.

    Attributes:
      load_case: ``path -> case``.
      case_scenario: ``(case, time_limit) -> Scenario``.
      solution_of: ``(case, PlanResult) -> dict``, the solution document.
      check_solution: ``(case, solution) -> report`` (the independent checker).
      format_report: ``report -> str``.
      summary: ``PlanResult -> str``, the plan's line in the benchmark's units.
      tle_file: the case file that holds the TLEs (named in the age error).
    """

    load_case: object
    case_scenario: object
    solution_of: object
    check_solution: object
    format_report: object
    summary: object
    tle_file: str


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


def write_solution(path, solution: dict, *, force: bool = False) -> Path:
    """Write a benchmark solution document as JSON, atomically (the adapters' one writer).

    Args:
      path: destination; solution: ``{"actions": [...], ...}`` (JSON-ready, no NaN);
      force: replace an existing file.
    Returns:
      Path written.
    Raises:
      FileExistsError: the file exists and ``force`` is false.
      ValueError: ``solution`` has no list of actions.
    """
    import json

    from jaxspline.planner.files import atomic_write_text

    if not isinstance(solution, dict) or not isinstance(solution.get("actions"), list):
        raise ValueError("solution: expected a document with a list of actions")
    text = json.dumps(solution, indent=2, allow_nan=False) + "\n"
    return atomic_write_text(Path(path), text, force=force)


def tle_age_problem(sc, where: str) -> str | None:
    """What is wrong with the TLEs of a translated case, or None: each satellite's TLE
    epoch must lie within :data:`jaxspline.readers.ranges.MAX_TLE_AGE_DAYS` of every
    instant of the horizon.

    Args:
      sc: the case's Scenario; where: the case file that holds the TLEs.
    Returns:
      str (the file, the satellite, the TLE's epoch and its age at the horizon's far end)
      or None.
    """
    import datetime as dt

    from jaxspline.readers.ranges import MAX_TLE_AGE_DAYS
    from jaxspline.readers.satellites import tle_epoch

    end = sc.epoch + dt.timedelta(seconds=sc.duration)
    for s in sc.satellites:
        if not isinstance(s.orbit, tuple):
            continue
        t = tle_epoch(s.orbit[0])
        age = max(abs((sc.epoch - t).total_seconds()), abs((end - t).total_seconds())) / 86400.0
        if age > MAX_TLE_AGE_DAYS:
            return (
                f"{where}: satellite {s.name}: the TLE's epoch {t:%Y-%m-%d %H:%M} UTC is "
                f"{age:.1f} days from the horizon ({sc.epoch:%Y-%m-%d %H:%M} to "
                f"{end:%Y-%m-%d %H:%M} UTC); SGP4 is meaningful within {MAX_TLE_AGE_DAYS:g} "
                "days: use TLEs of the case's dates"
            )
    return None


def add_solve_parser(sub, case_help: str, default_limit: float, func):
    """Register a benchmark's ``solve`` sub-command (the flags :func:`run_solve` reads).

    Args:
      sub: the benchmark's sub-parsers; case_help: what the case directory holds;
      default_limit: the default ``--time-limit`` [s]; func: the command's function.
    Returns:
      the sub-parser.
    """
    s = sub.add_parser("solve", help="plan a case, write the solution, check it (exit 0 if valid)")
    s.add_argument("case_dir", help=f"case directory ({case_help})")
    s.add_argument("-o", "--output", required=True, help="solution JSON file to write")
    s.add_argument("--time-limit", type=float, default=default_limit,
                   help=f"seconds for the whole command (default {default_limit:g})")  # fmt: skip
    s.add_argument("--seed", type=int, default=0, help="search seed (default 0)")
    s.add_argument("--force", action="store_true", help="overwrite an existing output file")
    s.add_argument("--json", metavar="OUT", help="write the check report to OUT ('-' = stdout)")
    s.set_defaults(func=func)
    return s


def run_solve(args, adapter: CaseAdapter) -> int:
    """A benchmark ``solve`` command (module docstring).

    Args:
      args: the parsed arguments (``case_dir``, ``output``, ``time_limit``, ``seed``,
        ``force``, ``json``; ``started``: the process's start, set by the command).
      adapter: the benchmark's :class:`CaseAdapter`.
    Returns:
      exit code: 0 valid, 1 invalid, 130 interrupted (the best plan so far written).
    Raises:
      ValueError: a bad flag or case file (naming it).
      FileExistsError: the output exists and ``--force`` is not given.
      jaxspline.planner.deadline.TimeLimitError: the limit ran out before the search.
    """
    t0 = getattr(args, "started", None) or time.monotonic()
    check_seconds("--time-limit", args.time_limit)
    check_int("--seed", args.seed, 0, MAX_SEED)
    check_output_file("-o/--output", args.output, force=args.force, room=ROOM_BYTES)
    check_case_paths(args)
    case = adapter.load_case(args.case_dir)
    sc = adapter.case_scenario(case, args.time_limit)
    problem = tle_age_problem(sc, str(Path(args.case_dir) / adapter.tle_file))
    if problem:
        raise ValueError(problem)
    result = _plan_case(sc, args, t0)
    solution = adapter.solution_of(case, result)
    out = write_solution(args.output, solution, force=args.force)
    print(f"wrote {out}: {adapter.summary(result)} ({time.monotonic() - t0:.1f} s)")
    code = check_and_print(adapter.check_solution, adapter.format_report, case, solution, args.json)
    stop = result.report.get("interrupted")
    if stop:
        print(
            f"jaxspline: {stop}: the search was stopped; {out} holds the best plan found "
            "so far (checked above)",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    return code


def _plan_case(sc, args, t0: float):
    """:func:`jaxspline.plan` of a case's scenario under the command's deadline."""
    from jaxspline.planner.deadline import RunSize, StageDeadline
    from jaxspline.planner.pipeline import plan

    limit = float(args.time_limit)
    scale = f"{len(sc.targets)} targets, {len(sc.satellites)} satellites, {sc.duration / 3600:g} h"
    size = RunSize(len(sc.targets), len(sc.satellites), sc.duration, sc.planner.time_step)
    deadline = StageDeadline(t0, limit, scale, after_s=WRITE_AND_CHECK_S,
                             must_s=WRITE_AND_CHECK_S, size=size,
                             flags="--time-limit")  # fmt: skip
    left = max(deadline.end - time.monotonic(), 1e-3)
    return plan(sc, time_limit=left, seed=args.seed, progress=True, deadline=deadline)
