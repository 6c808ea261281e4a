"""``jaxspline plan [SCENARIO.toml]``: plan a scenario and write the plan and its figures.

Parses the arguments, loads the scenario (default: the built-in constellation job),
calls :func:`jaxspline.plan` and writes into the output directory:

* ``plan.json`` - summary, bound and gap, check report (with ``areas``: the covered
  share of every area target, :func:`jaxspline.planner.area_report`), statistics,
  stage timings and every observation; ``plan.csv`` - one row per observation;
* ``plan.czml`` - satellites, targets, areas, imaging intervals and sensor footprints
  for Cesium;
* ``plan.html`` (``--no-html`` skips it) - one self-contained page (Bokeh, no network):
  map, per-satellite timeline and battery, headline figures (:mod:`jaxspline.products.plan_html`;
  ``jaxspline view plan.json`` rebuilds it from the ``"view"`` section of ``plan.json``);
* ``ground_track.png`` (world map with coastlines), ``timeline.png`` (per-satellite
  Gantt chart and battery), ``slack.png`` (maneuver slack per model);
* by default (``--aem``; ``--no-aem`` skips it) a flyable plan: transitions are
  screened with the degree-7 joins the spacecraft flies and the joins of the plan
  are checked (observations whose join still exceeds a limit are dropped), and
  ``attitude_<satellite>.aem.xml``, one CCSDS AEM per satellite (:mod:`jaxspline.products.aem`)
  sampled every ``--aem-step`` seconds plus every junction instant, and
  ``attitude.png`` (flown rate / acceleration / jerk against the limits).

The outputs are one set (:mod:`jaxspline.products.outputs`): before planning the
output directory is checked, locked against a second run and probed for room; the
files are written into a staging directory beside it and moved into place at once, so
a failure leaves the previous set or none. An earlier set is replaced only with
``--force``. Every flag is checked before any work (:mod:`jaxspline.cli.flags`).

Time limit: ``--time-limit`` (default: the scenario's ``planner.time_limit_s``) bounds
the whole command, from the start of its process: the stages before the search stop
the run with exit 3, an estimate and the remedy when it runs out there (up to 20 s of
compiling are not counted: :mod:`jaxspline.planner.deadline`); the search ends at the
limit less a reserve estimated for the repair and the asked outputs
(:mod:`jaxspline.planner.budget`, :mod:`jaxspline.products.output_budget`); past the
limit the repair leaves out its refills and refinements (never a check) and the
outputs the optional files that no longer fit (``plan.json`` and ``plan.csv`` are
always written). With ``--max-iters`` the work is fixed: the search, the repair and
the outputs run whole (the same plan and the same files on every run). What was
left out is said on stderr and recorded in ``plan.json``
(``report.time_limit``); a run that ends past its limit says so on stderr. The
scenario's files are read under the same clock (every 10,000 CSV rows or GeoJSON
features).

Memory: before the stages that allocate in proportion to the scenario (reading its
files, the orbits, the windows, the options, the near pairs) the run estimates their
bytes and stops with exit 3, the estimate and the remedy when they do not fit the
memory it may take (``--max-memory``, else 80 % of the available memory:
:mod:`jaxspline.planner.memory_guard`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from jaxspline.cli.flags import (
    MAX_ITERS,
    MAX_SECONDS,
    MAX_SEED,
    check_int,
    check_path,
    check_seconds,
    check_value,
)
from jaxspline.cli.startup import EXIT_INTERRUPTED  # exit code after Ctrl-C / SIGTERM
from jaxspline.products.outputs import ATTITUDE_FIGURE, OUTPUT_FILES
from jaxspline.products.plan_html import HTML_FILE

__all__ = [
    "AEM_STEP_S",
    "ATTITUDE_FIGURE",
    "EXIT_INTERRUPTED",
    "MAX_AEM_STATES",
    "OUTPUT_FILES",
    "default_aem_step",
    "register",
    "run_plan",
]

# AEM sample step of the plan command [s]: ccsds-ndm serializes ~2,000 states/s, so
# 1 s over the default 6 h x 6 satellites would take a minute (junctions are exact anyway)
AEM_STEP_S = 10.0
# steps [s] the default is raised to when it would exceed MAX_AEM_STATES (the first that fits)
_AEM_STEPS_S = (15.0, 20.0, 30.0, 45.0, 60.0, 90.0, 120.0, 180.0, 300.0, 600.0, 900.0, 1800.0)
MAX_MEMORY_RANGE_GB = (0.25, 65536.0)  # --max-memory [GB]: a quarter GB runs nothing
AEM_STEP_RANGE_S = (1e-3, 86400.0)
MAX_AEM_STATES = 50_000  # attitude states over all AEM files (~30-60 s to compute and write)


def register(sub) -> None:
    """Register the ``plan`` sub-command.

    Args:
      sub: the ``argparse`` sub-parsers object of the ``jaxspline`` command.
    """
    p = sub.add_parser(
        "plan",
        help="plan imaging for a scenario (default: the built-in constellation job)",
        description=__doc__,
    )
    p.add_argument("scenario", nargs="?", help="scenario TOML (default: built-in scenario)")
    p.add_argument("-o", "--outdir", default="plan_out", help="output directory (default plan_out)")
    p.add_argument("--force", action="store_true", help="replace an earlier set of outputs")
    p.add_argument(
        "--time-limit", type=float, default=None, help="planning budget [s] (default: scenario's)"
    )
    p.add_argument("--seed", type=int, default=0, help="search seed (default 0)")
    p.add_argument(
        "--max-iters",
        type=int,
        default=None,
        metavar="N",
        help="cap the search at N LNS iterations (N/10 Lagrangian): the run ignores the "
        "clock inside the search and gives the same plan every time (default: time-bound)",
    )
    p.add_argument(
        "--certify",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="extra seconds for a tighter bound by HiGHS (needs scipy; default 0: skip)",
    )
    p.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    p.add_argument(
        "--html",
        action=argparse.BooleanOptionalAction,
        default=True,
        help=f"write the self-contained web page {HTML_FILE} (default; --no-html: skip it)",
    )
    p.add_argument(
        "--aem",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="flyable plan: screen and check the degree-7 joins against the limits, "
        "write one CCSDS AEM per satellite and attitude.png (default; --no-aem: the "
        "maneuver models alone, no attitude files)",
    )
    p.add_argument(
        "--aem-step",
        type=float,
        default=None,
        help=f"attitude sample step of the AEM files [s] (default {AEM_STEP_S:g}, coarser "
        f"when that would be more than {MAX_AEM_STATES:,} attitude states, said on stderr)",
    )
    p.add_argument(
        "--max-memory",
        type=float,
        default=None,
        metavar="GB",
        help="memory the run may hold [GiB] (default: 80 %% of the available memory); a "
        "scenario whose estimate does not fit stops before it allocates (exit 3)",
    )
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=_main)


def _main(args) -> int:
    result = run_plan(
        args.scenario,
        args.outdir,
        force=args.force,
        time_limit=args.time_limit,
        seed=args.seed,
        max_iters=args.max_iters,
        certify=args.certify,
        plots=not args.no_plots,
        html=args.html,
        progress=not args.quiet,
        aem=args.aem,
        aem_step=args.aem_step,
        t_start=getattr(args, "started", None),
        max_memory=args.max_memory,
    )
    if result.report.get("interrupted"):
        return EXIT_INTERRUPTED
    return 0 if result.report["valid"] else 1


def _check_flags(scenario, time_limit, seed, max_iters, certify, aem_step, max_memory) -> None:
    """The flags of ``jaxspline plan``, each by its name (ValueError), before any work."""
    lo, hi = MAX_MEMORY_RANGE_GB
    if check_value("--max-memory", max_memory) is not None and not lo <= max_memory <= hi:
        raise ValueError(f"--max-memory: must be within [{lo:g}, {hi:g}] GB, got {max_memory:g}")
    if isinstance(scenario, str):
        check_path("SCENARIO", scenario, kind="file")
    check_seconds("--time-limit", time_limit)
    check_int("--seed", seed, 0, MAX_SEED)
    check_int("--max-iters", max_iters, 1, MAX_ITERS)
    check_seconds("--certify", certify, zero=True, hi=MAX_SECONDS)
    check_seconds("--aem-step", aem_step, hi=AEM_STEP_RANGE_S[1])
    if aem_step is not None and aem_step < AEM_STEP_RANGE_S[0]:
        raise ValueError(f"--aem-step: must be >= {AEM_STEP_RANGE_S[0]:g} s, got {aem_step:g}")


def default_aem_step(sc) -> tuple[float, str]:
    """The AEM sample step of a run without ``--aem-step``: :data:`AEM_STEP_S`, or the first
    coarser step that keeps the states within :data:`MAX_AEM_STATES` (at most the horizon).

    Args:
      sc: the scenario.
    Returns:
      (step [s], a note for stderr: empty when the step is the default).
    """
    n = max(len(sc.satellites), 1)
    if sc.duration / AEM_STEP_S * n <= MAX_AEM_STATES:
        return min(AEM_STEP_S, sc.duration), ""
    least = sc.duration * n / MAX_AEM_STATES
    step = min(next((x for x in _AEM_STEPS_S if x >= least), least), sc.duration)
    return step, (
        f"jaxspline: note: AEM files sampled every {step:g} s: the default {AEM_STEP_S:g} s "
        f"over the {sc.duration:g} s horizon and {n} satellites would be "
        f"{sc.duration / AEM_STEP_S * n:,.0f} attitude states (at most {MAX_AEM_STATES:,}); "
        "--aem-step sets the step"
    )


def _aem_step(sc, asked: float | None, aem: bool) -> float:
    """The AEM step of the run: ``asked``, else :func:`default_aem_step` (its note said on
    stderr when the AEM files are written)."""
    if asked is not None:
        return asked
    step, note = default_aem_step(sc)
    if note and aem:
        print(note, file=sys.stderr)
    return step


def _check_aem(sc, aem_step: float) -> tuple[str, ...]:
    """The AEM file names of the satellites: distinct, a step within the horizon (two
    samples at least), and not too many states to write."""
    from jaxspline.products.aem import aem_file_name

    names = tuple(aem_file_name(s.name) for s in sc.satellites)
    for k, n in enumerate(names):
        if n in names[:k]:
            other = sc.satellites[names.index(n)].name
            raise ValueError(
                f"satellites {other!r} and {sc.satellites[k].name!r} would share the AEM "
                f"file {n}: give them names that differ in letters, digits, '_', '.' or '-'"
            )
    if aem_step > sc.duration:  # one sample a satellite: not an AEM
        raise ValueError(
            f"--aem-step: {aem_step:g} s is longer than the {sc.duration:g} s horizon; use at "
            f"most {sc.duration:g} (or --no-aem)"
        )
    states = sc.duration / aem_step * len(names)
    if states > MAX_AEM_STATES:
        least = sc.duration * len(names) / MAX_AEM_STATES
        raise ValueError(
            f"--aem-step: {aem_step:g} s over the {sc.duration:g} s horizon and "
            f"{len(names)} satellites is {states:.3g} attitude states (at most "
            f"{MAX_AEM_STATES:,}); use --aem-step {least:.3g} or more, or --no-aem"
        )
    return names


def run_plan(
    scenario=None,
    outdir="plan_out",
    *,
    force: bool = False,
    time_limit: float | None = None,
    seed: int = 0,
    max_iters: int | None = None,
    certify: float = 0.0,
    plots: bool = True,
    html: bool = True,
    progress: bool = True,
    aem: bool = True,
    aem_step: float | None = None,
    t_start: float | None = None,
    max_memory: float | None = None,
):
    """Load ``scenario``, plan it, write the outputs as one set (module docstring).

    The arguments and the output directory are checked before the scenario is loaded,
    the directory is locked and probed before planning.

    Args:
      scenario: path of a scenario TOML file, a Scenario, or None (the default scenario).
      outdir: str or Path of the output folder.
      force: replace an earlier set of outputs.
      time_limit: wall-clock budget [s] from this call on; None: the scenario default.
      seed: int, seed of the randomized search.
      max_iters: iteration cap of the search (reproducible plans); None: time-bound.
      certify: extra seconds after the time limit for a tighter certificate (0: none).
      plots: write the PNG figures.
      html: write the web page ``plan.html``.
      progress: show progress bars.
      aem: write one CCSDS AEM per satellite (and check the flown joins).
      aem_step: sampling step of the AEM files [s]; None: :func:`default_aem_step`.
      t_start: when the time limit starts [s, ``time.monotonic``] (the command passes
        its process's start); None: now.
      max_memory: memory the run may hold [GiB] (None: :data:`MEMORY_SHARE` of the
        available memory, :mod:`jaxspline.planner.memory_guard`).
    Returns:
      :class:`jaxspline.planner.result.PlanResult`.
    Raises:
      FileExistsError: an earlier set exists and ``force`` is false.
      ValueError: a bad flag or scenario file (naming it).
      jaxspline.planner.deadline.TimeLimitError: the limit ran out before the search.
      jaxspline.planner.memory_guard.MemoryLimitError: a stage would not fit the memory.
      jaxspline.products.outputs.OutputError: the outputs cannot be written
        (``OutputBusyError``: another run holds the directory).
    """
    from jaxspline.planner.memory_guard import GB, MemoryGuard
    from jaxspline.products.outputs import OutputSet
    from jaxspline.readers.fields import READ_CLOCK
    from jaxspline.readers.scenario import scenario_from

    t_start = time.monotonic() if t_start is None else t_start
    _check_flags(scenario, time_limit, seed, max_iters, certify, aem_step, max_memory)
    outputs = OutputSet(outdir, force=force)
    outputs.check()  # fail before loading, nothing written
    memory = MemoryGuard(None if max_memory is None else max_memory * GB)
    token = READ_CLOCK.set(_reading_clock(t_start, time_limit, memory))
    try:
        sc = scenario_from(scenario)
    finally:
        READ_CLOCK.reset(token)
    aem_step = _aem_step(sc, aem_step, aem)
    aems = _check_aem(sc, aem_step) if aem else ()
    limit = sc.planner.default_time_limit if time_limit is None else time_limit
    names = OUTPUT_FILES if plots else OUTPUT_FILES[:3]
    names += (HTML_FILE,) * html + ((ATTITUDE_FIGURE,) * plots + aems if aem else ())
    deadline = _deadline(sc, limit, t_start, plots=plots, html=html, aem=aem, aem_step=aem_step)
    with outputs:  # locked, staged and probed: planning starts only now
        result = _plan(sc, deadline, seed, max_iters, certify, progress, aem, memory)
        # --max-iters: fixed work, the whole set is written whatever the clock says
        timed = deadline if max_iters is None else None
        page, t_write = _write(result, outputs, plots, aem, aem_step, html, timed)
    names = tuple(n for n in names if (Path(outdir) / n).exists())
    _print_summary(result, Path(outdir), names, page)
    _say_late(result, limit, time.monotonic() - t_start, t_write)
    return result


def _reading_clock(t_start: float, limit: float | None, memory):
    """The clock of the scenario's files while they are read
    (:data:`jaxspline.readers.fields.READ_CLOCK`): ``clock(file, share read)`` raises
    ``TimeLimitError`` past ``--time-limit`` (``limit``; None: the scenario's limit is
    checked once it is read) and ``MemoryLimitError`` when the memory the file's rows
    take, from its first tick on, projected over the rest of it, does not fit
    ``memory`` (the file's text, read before, is not projected)."""
    from jaxspline.planner.deadline import TimeLimitError, suggested_limit
    from jaxspline.planner.memory_guard import rss_bytes

    t0, first = time.monotonic(), {}  # file -> (share, resident set) at its first tick

    def clock(label: str, share: float) -> None:
        now, share = time.monotonic(), max(share, 1e-6)
        rows = f"{100 * share:.0f} % of {label} read"
        if limit is not None and now - t_start > limit:
            est = (t0 - t_start) + (now - t0) / share
            raise TimeLimitError(
                f"time limit of {limit:.4g} s reached while reading the scenario "
                f"({rows} after {now - t_start:.1f} s): reading it alone needs ~{est:.0f} s "
                f"at this pace; give a time limit of {suggested_limit(est)} s or more "
                "(--time-limit or planner.time_limit_s), or split the file",
                "loading",
                now - t_start,
                est,
            )
        share0, rss0 = first.setdefault(label, (share, rss_bytes()))
        if share <= share0:
            return
        more = (rss_bytes() - rss0) / (share - share0) * (1.0 - share)

        def remedy(f):
            return f"read a file about {f:.2g} times smaller (fewer targets)"

        memory.check("loading", (more, f"{rows}, its rows growing as they are read", remedy))

    return clock


def _deadline(sc, limit, t_start, **asked):
    """The run's :class:`jaxspline.planner.deadline.StageDeadline` from ``t_start`` on,
    with the estimated time of the asked outputs (``asked``: plots, html, aem, aem_step)
    kept out of the search."""
    from jaxspline.planner.deadline import RunSize, StageDeadline
    from jaxspline.products.output_budget import RESERVE_FACTOR, output_seconds

    scale = f"{len(sc.targets)} targets, {len(sc.satellites)} satellites, {sc.duration / 3600:g} h"
    cost = output_seconds(sc, **asked)
    return StageDeadline(
        t_start,
        limit,
        scale,
        after_s=RESERVE_FACTOR * sum(cost.values()),
        must_s=cost["plan files"],
        size=RunSize(
            len(sc.targets),
            len(sc.satellites),
            sc.duration,
            sc.planner.time_step,
            joins=asked["aem"],
        ),
    )


def _plan(sc, deadline, seed, max_iters, certify, progress, aem, memory):
    """:func:`jaxspline.plan` with what is left of the limit after loading the scenario,
    every stage bound by ``deadline`` and ``memory``."""
    from jaxspline.planner.pipeline import plan

    deadline.check("loading", 1.0)
    left = max(deadline.end - time.monotonic(), 1e-3)  # the search's share (may be none)
    # with --aem the flown joins are checked: the AEM files never exceed a limit
    return plan(sc, time_limit=left, seed=seed, progress=progress, max_iters=max_iters,
                certify=certify, flown_joins=aem, deadline=deadline, memory=memory)  # fmt: skip


def _write(result, outputs, plots, aem, aem_step, html, deadline=None):
    """Write the set into the staging folder and publish it, signals held until it is
    whole; a signal during writing is recorded in plan.json. Returns (page, seconds)."""
    from jaxspline.base.clock import catch_signals
    from jaxspline.products.outputs import rewrite_plan_json, write_plan_outputs

    def late(name):  # plan.json says so
        result.report.setdefault("interrupted", name)

    t0 = time.monotonic()
    with catch_signals(late):  # signals wait: the set is written whole
        before = result.report.get("interrupted")
        page = write_plan_outputs(result, outputs.staging, plots=plots, aem=aem,
                                  aem_step=aem_step, html=html, deadline=deadline)  # fmt: skip
        if result.report.get("interrupted") != before:
            rewrite_plan_json(result, outputs.staging)
        before = result.report.get("interrupted")
        outputs.publish()
        if result.report.get("interrupted") != before:  # during the rename itself
            rewrite_plan_json(result, outputs.target)
    if result.report.get("interrupted"):
        print(
            f"jaxspline: interrupted ({result.report['interrupted']}): the best plan found "
            f"so far was checked and written to {outputs.outdir}/",
            file=sys.stderr,
        )
    return page, time.monotonic() - t0


def _say_late(result, limit: float, elapsed: float, t_write: float) -> None:
    """Lines on stderr naming what the time limit left out, and when the run ended past
    it (never silently)."""
    skipped = result.report.get("time_limit", {}).get("skipped", [])
    if skipped:
        left_out = "; ".join(f"{s['what']} [{s['remedy']}]" for s in skipped)
        print(f"jaxspline: note: left out for the time limit: {left_out}", file=sys.stderr)
    if elapsed <= limit:
        return
    after = {k: v for k, v in result.timings.items() if k in _AFTER_SEARCH}
    parts = ", ".join(f"{k} {v:.1f} s" for k, v in after.items())
    print(
        f"jaxspline: note: the run took {elapsed:.1f} s, {elapsed - limit:.1f} s past its "
        f"{limit:g} s time limit; after the search: {parts + ', ' if parts else ''}"
        f"writing {t_write:.1f} s",
        file=sys.stderr,
    )


_AFTER_SEARCH = ("repair", "certify", "coverage", "attitude")


def _print_summary(r, out: Path, names, page=None) -> None:
    from jaxspline.planner.repair import dropped_line

    s, st = r.summary(), r.stats
    n_imaged = len(set(r.observations.target.tolist()))
    lines = [
        f"scenario      {s['scenario']}: {s['satellites']} satellites, {s['targets']} targets, "
        f"{r.scenario.duration / 3600:g} h from {r.scenario.epoch:%Y-%m-%d %H:%M} UTC",
        f"windows       {st['windows']}; options {st['options']}; "
        f"feasible near pairs {st['near_pairs']}",
        f"plan          {s['observations']} observations of {n_imaged} targets, value "
        f"{s['value']:g} of {s['total_value']:g}",
        f"bound         {s['bound']:.6g} ({st['bound_status']}); gap {s['gap']:.6g} "
        f"({100 * s['gap'] / max(s['bound'], 1e-300):.2f} % of the bound)",
        f"check         {'valid' if s['valid'] else 'INVALID'} "
        f"(dropped: {dropped_line(r.report['dropped'])})",
        "wall time [s]  " + ", ".join(f"{k} {v:.2f}" for k, v in r.timings.items()),
        f"outputs       {out}/ ({', '.join(names)})",
    ]
    if page:
        lines.append(f"page          {HTML_FILE}: {page[0] / 1e6:.2f} MB in {page[1]:.2f} s")
    if r.report.get("areas"):
        lines.insert(5, f"areas         {coverage_line(r.report['areas'])}")
    if r.report.get("stereo"):
        lines.insert(5, f"stereo        {stereo_line(r.report['stereo'])}")
    j = r.report.get("joins")  # only when the flown joins were checked (--aem)
    if j:
        lines.insert(
            5,
            f"joins         {j['joins']} degree-7 joins, {j['retimed']} re-timed, "
            f"{j['rejected']} rejected; peak ratios rate {j['max_rate_ratio']:.3f}, "
            f"accel {j['max_accel_ratio']:.3f}, jerk {j['max_jerk_ratio']:.3f}",
        )
    print("\n".join(lines), file=sys.stdout)


def stereo_line(stereo: list[dict]) -> str:
    """One line on the stereo targets of a plan: how many have a product, of which
    triples, and the mean quality over all of them.

    Args:
      stereo: ``report["stereo"]`` of a plan
        (:func:`jaxspline.planner.stereo_report.stereo_report`).
    Returns:
      str, e.g. ``128 of 131 stereo targets with a product (12 triples), mean quality 0.962``.
    """
    got = [s for s in stereo if s["product"]]
    tri = sum(1 for s in got if s["product"] == "tri")
    quality = sum(s["quality"] for s in got) / max(len(stereo), 1)
    return (
        f"{len(got)} of {len(stereo)} stereo targets with a product ({tri} triples), "
        f"mean quality {quality:.3f}"
    )


def coverage_line(areas: list[dict], limit: int = 6) -> str:
    """One line on the areas of a plan: each area's covered share and strips.

    Args:
      areas: ``report["areas"]`` of a plan (:func:`jaxspline.planner.area_report.area_report`).
      limit: most areas named (the rest are counted).
    Returns:
      str, e.g. ``2 areas covered: karst 87.5 % (6 strips), ...``.
    """
    parts = [
        f"{a['area']} {100 * a['covered_share']:.1f} % ({a['strips']} strips)"
        for a in areas[:limit]
    ]
    more = f", {len(areas) - limit} more" if len(areas) > limit else ""
    return f"{len(areas)} areas covered: " + ", ".join(parts) + more
