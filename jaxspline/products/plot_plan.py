"""Figures of a whole plan: ground tracks on a world map, a Gantt timeline, slack histogram.

Each function takes a :class:`jaxspline.planner.result.PlanResult` and writes one PNG
atomically with :func:`jaxspline.products.plot.save_figure` (matplotlib, imported lazily, Agg
backend). Satellite k is drawn in ``SATELLITE_COLORS[k]`` (shared with the CZML export,
:mod:`jaxspline.products.czml`).

Coastlines are drawn offline from the land mask of the ``global_land_mask`` package,
streamed by :func:`jaxspline.base.land.land_fraction` (blocks of
:data:`jaxspline.base.land.COAST_BLOCK` cells, 0.25 deg), contoured at land fraction 0.5.
"""

from __future__ import annotations

import numpy as np

from jaxspline.base.land import land_fraction
from jaxspline.geometry.frames import ecef_to_geodetic
from jaxspline.products.czml import SATELLITE_COLORS, satellite_tracks
from jaxspline.products.plot import pyplot, save_figure

__all__ = ["land_fraction", "plot_plan_ground_tracks", "plot_plan_slack", "plot_plan_timeline"]

SECONDS_PER_HOUR = 3600.0
NOT_IMAGED_COLOR = "0.6"  # targets the plan does not image
LAND_COLOR = "#efeae0"
COAST_COLOR = "0.35"
MANEUVER_COLOR = "0.2"
IMAGING_HEIGHT = 0.6  # Gantt bar height of an imaging interval (row pitch 1)
MANEUVER_HEIGHT = 0.18  # Gantt bar height of a maneuver
SLACK_FLOOR = 1e-3  # [s]: slacks below are counted in the first bin of a log axis
LOG_SLACK_RATIO = 100.0  # log-x when max / min positive slack exceeds this
SLACK_BINS = 40


def _color(k: int) -> str:
    return SATELLITE_COLORS[k % len(SATELLITE_COLORS)]


def _break_antimeridian(lon_deg, lat_deg, ok):
    """Copies of a track with NaN inserted where it wraps at +-180 deg or is not ok."""
    lon = np.where(ok, lon_deg, np.nan)
    lat = np.where(ok, lat_deg, np.nan)
    jump = np.flatnonzero(np.abs(np.diff(lon)) > 180.0) + 1
    return np.insert(lon, jump, np.nan), np.insert(lat, jump, np.nan)


def _title(result) -> str:
    gap = float(result.gap)
    rel = f" ({100.0 * gap / result.bound:.2g} %)" if result.bound > 0 else ""
    return (
        f"{result.scenario.name}: {len(result.observations)} observations, "
        f"value {result.value:.6g} / bound {result.bound:.6g}, gap {gap:.3g}{rel}"
    )


def plot_plan_ground_tracks(result, path, *, step: float = 30.0) -> None:
    """World map (equirectangular) of the satellites' ground tracks and the targets.

    Coastlines from :func:`land_fraction`; each satellite's sub-satellite track over
    the horizon in its colour (broken at the antimeridian); targets as small grey dots,
    imaged ones in the colour of the (first) satellite imaging them. Title:
    observations, value, bound and gap.

    Args:
      result: PlanResult.
      path: str or Path of the image.
      step: track sampling step [s].
    """
    plt = pyplot()
    sc = result.scenario
    obs = result.observations
    t, r, ok = satellite_tracks(sc, step)
    lat, lon, _ = ecef_to_geodetic(r)
    fig, ax = plt.subplots(figsize=(13, 7))
    lat_c, lon_c, land = land_fraction()
    ax.contourf(lon_c, lat_c, land, levels=[0.5, 1.5], colors=[LAND_COLOR], zorder=0)
    ax.contour(lon_c, lat_c, land, levels=[0.5], colors=COAST_COLOR, linewidths=0.5, zorder=1)
    for k, sat in enumerate(sc.satellites):
        x, y = _break_antimeridian(np.degrees(lon[k]), np.degrees(lat[k]), ok[k])
        ax.plot(x, y, "-", color=_color(k), lw=1.0, alpha=0.85, zorder=2, label=sat.name)
        i0 = np.flatnonzero(ok[k])[:1]
        x0, y0 = np.degrees(lon[k, i0]), np.degrees(lat[k, i0])
        ax.plot(x0, y0, ">", color=_color(k), ms=6, mec="k", mew=0.5, zorder=4)
    ax.plot([], [], ">", color="w", mec="k", mew=0.5, label="track start (t = 0)")
    tg = sc.targets
    tlon, tlat = np.degrees(tg.lon), np.degrees(tg.lat)
    tlon = (tlon + 180.0) % 360.0 - 180.0
    by = np.full(len(tg), -1)
    for i in range(len(obs) - 1, -1, -1):  # first imaging satellite wins
        by[int(obs.target[i])] = int(obs.sat[i])
    free = by < 0
    ax.plot(tlon[free], tlat[free], ".", color=NOT_IMAGED_COLOR, ms=3, zorder=3, ls="none")
    ax.plot([], [], ".", color=NOT_IMAGED_COLOR, ms=6, label=f"target not imaged ({free.sum()})")
    for k in np.unique(by[~free]):
        m = by == k
        ax.plot(tlon[m], tlat[m], "o", color=_color(int(k)), ms=5, mec="k", mew=0.5, zorder=4)
    if (~free).any():
        ax.plot([], [], "o", color="w", mec="k", mew=0.5, label=f"imaged ({(~free).sum()})")
    ax.set_xlim(-180.0, 180.0)
    ax.set_ylim(-90.0, 90.0)
    ax.set_aspect("equal")
    ax.set_xticks(np.arange(-180, 181, 30))
    ax.set_yticks(np.arange(-90, 91, 30))
    ax.set_xlabel("longitude [deg]")
    ax.set_ylabel("latitude [deg]")
    ax.grid(alpha=0.3)
    hours = (t[-1] - t[0]) / SECONDS_PER_HOUR
    ax.set_title(f"{_title(result)}\nground tracks over {hours:.3g} h", fontsize=10)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_plan_timeline(result, path) -> None:
    """Gantt chart of the plan: one row per satellite, battery levels below (if any).

    Imaging intervals are bars in the satellite's colour, the maneuver ending at each
    start a thin dark bar before it; x in hours from the epoch. A second panel draws
    ``result.battery`` (satellite name -> (t [s], level [Wh])) when it is not empty.

    Args:
      result: PlanResult.
      path: str or Path of the image.
    """
    plt = pyplot()
    sc = result.scenario
    obs = result.observations
    battery = {k: v for k, v in (result.battery or {}).items() if len(v[0])}
    n_sat = len(sc.satellites)
    h = SECONDS_PER_HOUR
    if battery:
        fig, (ax, axb) = plt.subplots(
            2,
            1,
            figsize=(12, 2.0 + 0.45 * n_sat + 2.8),
            sharex=True,
            gridspec_kw={"height_ratios": [max(1.0, 0.45 * n_sat), 2.5]},
        )
    else:
        fig, ax = plt.subplots(figsize=(12, 1.6 + 0.45 * n_sat))
        axb = None
    for k in range(n_sat):
        m = obs.sat == k
        start, end, man = obs.start[m] / h, obs.end[m] / h, obs.maneuver[m] / h
        ax.broken_barh(
            list(zip(start - man, man, strict=True)),
            (k - MANEUVER_HEIGHT / 2, MANEUVER_HEIGHT),
            color=MANEUVER_COLOR,
        )
        ax.broken_barh(
            list(zip(start, end - start, strict=True)),
            (k - IMAGING_HEIGHT / 2, IMAGING_HEIGHT),
            color=_color(k),
        )
    ax.set_yticks(range(n_sat), [s.name for s in sc.satellites])
    ax.set_ylim(n_sat - 0.5, -0.5)
    ax.set_xlim(0.0, sc.duration / h)
    ax.grid(axis="x", alpha=0.3)
    from matplotlib.patches import Patch

    ax.legend(
        handles=[
            Patch(color=_color(0), label="imaging (satellite colour)"),
            Patch(color=MANEUVER_COLOR, label="maneuver"),
        ],
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        fontsize=8,
    )
    ax.set_title(f"{_title(result)}\ntimeline", fontsize=10)
    names = [s.name for s in sc.satellites]
    if axb is not None:
        for name, (tb, level) in battery.items():
            k = names.index(name) if name in names else 0
            axb.plot(np.asarray(tb) / h, np.asarray(level), color=_color(k), lw=1.2, label=name)
        axb.set_ylabel("battery [Wh]")
        axb.grid(alpha=0.3)
        axb.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
        axb.set_xlabel("time [h from epoch]")
    else:
        ax.set_xlabel("time [h from epoch]")
    fig.tight_layout()
    save_figure(fig, path)


def plot_plan_slack(result, path) -> None:
    """Histogram of the observations' slack (gap minus required maneuver) [s], per model.

    One step histogram per maneuver model. The x axis is logarithmic when all slacks
    are >= 0 and the positive ones span more than :data:`LOG_SLACK_RATIO`; slacks below
    :data:`SLACK_FLOOR` are then counted at the floor. Non-finite slacks are dropped.

    Args:
      result: PlanResult.
      path: str or Path of the image.
    """
    plt = pyplot()
    sc = result.scenario
    obs = result.observations
    slack = np.asarray(obs.slack, np.float64)
    model = np.array([sc.satellites[int(k)].model for k in obs.sat], dtype=object)
    fin = np.isfinite(slack)
    slack, model = slack[fin], model[fin]
    fig, ax = plt.subplots(figsize=(8, 4.5))
    if slack.size:
        pos = slack[slack > 0]
        lo = max(pos.min(), SLACK_FLOOR) if pos.size else 0.0
        wide = bool(pos.size) and slack.min() >= 0 and pos.max() / lo > LOG_SLACK_RATIO
        raw = slack
        if wide:
            slack = np.maximum(slack, lo)
            bins = np.geomspace(lo, pos.max() * (1.0 + 1e-9), SLACK_BINS + 1)
            ax.set_xscale("log")
        else:
            lo, hi = slack.min(), slack.max()
            bins = np.linspace(lo, hi if hi > lo else lo + 1.0, SLACK_BINS + 1)
        for name in sorted(set(model)):
            m = model == name
            ax.hist(
                slack[m],
                bins=bins,
                histtype="stepfilled",
                alpha=0.5,
                edgecolor="k",
                lw=0.6,
                label=f"{name} ({int(m.sum())}, min {raw[m].min():.3g} s)",
            )
        if slack.min() < 0:
            ax.axvline(0.0, color="tab:red", ls="--", lw=1, label="0 (violation below)")
        ax.legend(fontsize=8)
        floor = f"; slack < {lo:.3g} s counted at {lo:.3g} s" if wide else ""
        ax.set_xlabel(f"slack [s]{floor}")
    else:
        ax.text(0.5, 0.5, "no observations", ha="center", va="center", transform=ax.transAxes)
        ax.set_xlabel("slack [s]")
    ax.set_ylabel("observations")
    ax.set_title(f"{_title(result)}\nmaneuver slack", fontsize=10)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)
