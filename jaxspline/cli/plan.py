"""``jaxspline plan [SCENARIO.toml]``: plan a scenario and write the plan and its figures.

Parses the arguments, loads the scenario (default: the built-in constellation job),
calls :func:`jaxspline.plan` and writes into the output directory:

* ``plan.json`` - summary, bound and gap, check report (with ``areas``: the covered
  fraction of every area target, :func:`jaxspline.readers.areas.area_coverage`), statistics,
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

Existing outputs are never overwritten unless ``--force``; every file is written
atomically.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from jaxspline.planner.files import refuse_overwrite
from jaxspline.products.plan_html import HTML_FILE
from jaxspline.search.clock import catch_signals

__all__ = [
    "AEM_STEP_S",
    "ATTITUDE_FIGURE",
    "EXIT_INTERRUPTED",
    "OUTPUT_FILES",
    "register",
    "run_plan",
]

EXIT_INTERRUPTED = 130  # exit code after Ctrl-C / SIGTERM (128 + SIGINT, the shell convention)

# AEM sample step of the plan command [s]: ccsds-ndm serializes ~2,000 states/s, so
# 1 s over the default 6 h x 6 satellites would take a minute (junctions are exact anyway)
AEM_STEP_S = 10.0

OUTPUT_FILES = (
    "plan.json",
    "plan.csv",
    "plan.czml",
    "ground_track.png",
    "timeline.png",
    "slack.png",
)
ATTITUDE_FIGURE = "attitude.png"  # with --aem (the default)
_PLOTS = OUTPUT_FILES[3:]


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
    p.add_argument("--force", action="store_true", help="overwrite existing outputs")
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
        default=AEM_STEP_S,
        help=f"attitude sample step of the AEM files [s] (default {AEM_STEP_S:g})",
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
    )
    if result.report.get("interrupted"):
        return EXIT_INTERRUPTED
    return 0 if result.report["valid"] else 1


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
    aem_step: float = AEM_STEP_S,
):
    """Load ``scenario``, plan it, write the outputs.

    Every output name is checked before planning, so an existing file fails fast.

    Args:
      scenario: path of a scenario TOML file, a Scenario, or None (the default scenario).
      outdir: str or Path of the output folder.
      force: overwrite existing outputs.
      time_limit: wall-clock budget of the planner [s]; None: the scenario default.
      seed: int, seed of the randomized search.
      max_iters: iteration cap of the search (reproducible plans); None: time-bound.
      certify: extra seconds after the time limit for a tighter certificate (0: none).
      plots: write the PNG figures.
      html: write the web page ``plan.html``.
      progress: show progress bars.
      aem: write one CCSDS AEM per satellite (and check the flown joins).
      aem_step: sampling step of the AEM files [s].
    Returns:
      :class:`jaxspline.planner.result.PlanResult`.
    Raises:
      FileExistsError: an output exists and ``force`` is false.
      ValueError: a bad scenario file (naming the field).
    """
    from jaxspline.planner.pipeline import plan
    from jaxspline.products.aem import aem_file_name
    from jaxspline.readers.scenario import scenario_from

    out = Path(outdir)
    sc = scenario_from(scenario)
    names = OUTPUT_FILES if plots else OUTPUT_FILES[:3]
    names += (HTML_FILE,) * html
    if aem:
        names += (ATTITUDE_FIGURE,) * plots + tuple(aem_file_name(s.name) for s in sc.satellites)
    for name in names:  # fail before planning, not after
        refuse_overwrite(out / name, force)
    # with --aem the flown joins are checked: the AEM files never exceed a limit
    result = plan(
        sc,
        time_limit=time_limit,
        seed=seed,
        progress=progress,
        max_iters=max_iters,
        certify=certify,
        flown_joins=aem,
    )

    def late(name):  # plan.json says so if it is not written yet
        result.report.setdefault("interrupted", name)

    with catch_signals(late):  # signals wait: every output is written whole
        _write_outputs(result, sc, out, names, force, plots, aem, aem_step, html)
    if result.report.get("interrupted"):
        print(
            f"jaxspline: interrupted ({result.report['interrupted']}): the best plan found "
            f"so far was checked and written to {out}/",
            file=sys.stderr,
        )
    return result


def _write_outputs(result, sc, out, names, force, plots, aem, aem_step, html):
    from jaxspline.products.aem import write_aems
    from jaxspline.products.attitude_history import attitude_history

    if sc.areas:  # covered fraction per area, into plan.json's report
        from jaxspline.readers.areas import area_coverage

        t0 = time.monotonic()
        result.report["areas"] = area_coverage(result)
        result.timings["coverage"] = round(time.monotonic() - t0, 3)
    if aem:
        t0 = time.monotonic()
        attitude = attitude_history(result, aem_step)
        write_aems(result, attitude, out, force=force)
        result.timings["attitude"] = round(time.monotonic() - t0, 3)
    from jaxspline.products.plan_view import view_data

    view = {"view": view_data(result)}  # what plan.html draws: `jaxspline view` rebuilds it
    result.to_json(out / "plan.json", force=force, extra=view)
    result.to_csv(out / "plan.csv", force=force)
    from jaxspline.products.czml import write_czml

    write_czml(result, out / "plan.czml", force=True)
    if plots:
        from jaxspline.products.plot_plan import (
            plot_plan_ground_tracks,
            plot_plan_slack,
            plot_plan_timeline,
        )

        plot_plan_ground_tracks(result, out / "ground_track.png")
        plot_plan_timeline(result, out / "timeline.png")
        plot_plan_slack(result, out / "slack.png")
        if aem:
            from jaxspline.products.plot_attitude import plot_attitude_profile

            plot_attitude_profile(result, attitude, out / ATTITUDE_FIGURE)
    page = None
    if html:
        from jaxspline.products.plan_html import write_plan_html

        t0 = time.monotonic()
        path = write_plan_html(result.to_dict(extra=view), out / HTML_FILE, force=force)
        page = (path.stat().st_size, time.monotonic() - t0)
    _print_summary(result, out, names, page)


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
        from jaxspline.readers.areas import coverage_line

        lines.insert(5, f"areas         {coverage_line(r.report['areas'])}")
    j = r.report.get("joins")  # only when the flown joins were checked (--aem)
    if j:
        lines.insert(
            5,
            f"joins         {j['joins']} degree-7 joins, {j['retimed']} re-timed, "
            f"{j['rejected']} rejected; peak ratios rate {j['max_rate_ratio']:.3f}, "
            f"accel {j['max_accel_ratio']:.3f}, jerk {j['max_jerk_ratio']:.3f}",
        )
    print("\n".join(lines), file=sys.stdout)
