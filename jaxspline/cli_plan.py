"""``jaxspline plan [SCENARIO.toml]``: plan a scenario and write the plan and its figures.

Parses the arguments, loads the scenario (default: the built-in constellation job),
calls :func:`jaxspline.plan` and writes into the output directory:

* ``plan.json`` - summary, bound and gap, check report, statistics, stage timings and
  every observation; ``plan.csv`` - one row per observation;
* ``plan.czml`` - satellites, targets and imaging intervals for Cesium;
* ``ground_track.png`` (world map with coastlines), ``timeline.png`` (per-satellite
  Gantt chart and battery), ``slack.png`` (maneuver slack per model).

Existing outputs are never overwritten unless ``--force``; every file is written
atomically.
"""

from __future__ import annotations

import sys
from pathlib import Path

from jaxspline.engine._io import refuse_overwrite

__all__ = ["OUTPUT_FILES", "register", "run_plan"]

OUTPUT_FILES = (
    "plan.json",
    "plan.csv",
    "plan.czml",
    "ground_track.png",
    "timeline.png",
    "slack.png",
)
_PLOTS = OUTPUT_FILES[3:]


def register(sub) -> None:
    """Register the ``plan`` sub-command."""
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
        "--certify",
        type=float,
        default=0.0,
        metavar="SECONDS",
        help="extra seconds for a tighter bound by HiGHS (needs scipy; default 0: skip)",
    )
    p.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=_main)


def _main(args) -> int:
    result = run_plan(
        args.scenario,
        args.outdir,
        force=args.force,
        time_limit=args.time_limit,
        seed=args.seed,
        certify=args.certify,
        plots=not args.no_plots,
        progress=not args.quiet,
    )
    return 0 if result.report["valid"] else 1


def run_plan(
    scenario=None,
    outdir="plan_out",
    *,
    force: bool = False,
    time_limit: float | None = None,
    seed: int = 0,
    certify: float = 0.0,
    plots: bool = True,
    progress: bool = True,
):
    """Load ``scenario`` (path, Scenario or None = default), plan it, write the outputs.

    Returns the :class:`jaxspline.engine.result.PlanResult`.
    """
    from jaxspline.engine.mission import Scenario
    from jaxspline.engine.planner import plan
    from jaxspline.scenario import default_scenario, load_scenario

    out = Path(outdir)
    names = OUTPUT_FILES if plots else OUTPUT_FILES[:3]
    for name in names:  # fail before planning, not after
        refuse_overwrite(out / name, force)
    if scenario is None:
        sc = default_scenario()
    elif isinstance(scenario, Scenario):
        sc = scenario
    else:
        sc = load_scenario(scenario)
    result = plan(sc, time_limit=time_limit, seed=seed, progress=progress, certify=certify)
    result.to_json(out / "plan.json", force=force)
    result.to_csv(out / "plan.csv", force=force)
    from jaxspline.czml import write_czml

    write_czml(result, out / "plan.czml", force=True)
    if plots:
        from jaxspline.plot_plan import plot_plan_ground_tracks, plot_plan_slack, plot_plan_timeline

        plot_plan_ground_tracks(result, out / "ground_track.png")
        plot_plan_timeline(result, out / "timeline.png")
        plot_plan_slack(result, out / "slack.png")
    _print_summary(result, out, names)
    return result


def _print_summary(r, out: Path, names) -> None:
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
        f"check         {'valid' if s['valid'] else 'INVALID'} ({r.report['dropped']} dropped)",
        "wall time [s]  " + ", ".join(f"{k} {v:.2f}" for k, v in r.timings.items()),
        f"outputs       {out}/ ({', '.join(names)})",
    ]
    print("\n".join(lines), file=sys.stdout)
