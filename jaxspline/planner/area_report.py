"""What a plan covers of its areas: the report per area, the samples, the strips' footprints.

:func:`area_report` is the ``report["areas"]`` of a plan (covered share and value per
area, the share within reach of its candidates); :func:`area_samples` the sample grid
of every area with a flag per sample (covered by a planned strip); and
:func:`strip_footprints` the ground each planned area strip sweeps, a ring through its
edge points (:func:`jaxspline.screen.coverage.strip_quads`) at every geometry knot of
its imaging time, out along the inner edge and back along the outer one.
"""

from __future__ import annotations

import numpy as np

from jaxspline.planner.area_options import earth_fixed_tracks
from jaxspline.screen.coverage import strip_quads

__all__ = ["area_report", "area_samples", "strip_footprints"]


def _plan_samples(cover, chosen) -> tuple[np.ndarray, np.ndarray]:
    """(covered bool [N], area strips per area int [A]) of the plan's options ``chosen``."""
    hit = np.zeros(cover.n_samples, bool)
    strips = np.zeros(cover.n_areas, np.int64)
    for c in chosen:
        if cover.option_group[c] < 0:
            continue
        s = cover.samples(
            int(cover.option_group[c]), int(cover.option_a[c]), int(cover.option_b[c])
        )
        hit[s] = True
        strips[np.unique(cover.area[s])] += 1
    return hit, strips


def area_report(sc, cover, chosen) -> list:
    """Per area what the plan covers of it.

    Args:
      sc: Scenario; cover: the problem's :class:`jaxspline.search.cover.CoverTable`;
      chosen: option ids of the plan.
    Returns:
      list of dict per area: ``area`` (name), ``priority``, ``samples``,
      ``samples_covered``, ``covered_share`` (summed weight of its covered samples),
      ``value`` (priority times the share), ``strips`` (area strips planned that cover
      it), ``reachable_share`` (the share all its candidate strips cover together: no
      plan covers more) and ``min_share`` (None: no minimum).
    """
    ids = np.asarray([c for c in chosen if cover.option_group[c] >= 0], np.int64)
    hit = np.zeros(cover.n_samples, bool)
    strips = np.zeros(cover.n_areas, np.int64)
    for c in ids.tolist():
        s = cover.samples(
            int(cover.option_group[c]), int(cover.option_a[c]), int(cover.option_b[c])
        )
        hit[s] = True
        strips[np.unique(cover.area[s])] += 1
    reach = np.zeros(cover.n_samples, bool)
    reach[cover.indices] = True
    out = []
    for a, area in enumerate(sc.areas):
        m = cover.area == a
        share = float(cover.share[m & hit].sum())
        out.append(
            {
                "area": area.name,
                "priority": float(sc.targets.value[area.target]),
                "samples": int(m.sum()),
                "samples_covered": int((m & hit).sum()),
                "covered_share": share,
                "value": float(sc.targets.value[area.target]) * share,
                "strips": int(strips[a]),
                "reachable_share": float(cover.share[m & reach].sum()),
                "min_share": None if np.isnan(area.min_share) else float(area.min_share),
            }
        )
    return out


def area_samples(areas, cover, chosen) -> list:
    """Per area its samples and which of them the plan covers.

    Args:
      areas: the planner's :class:`jaxspline.planner.area_options.AreaOptions`;
      cover: the problem's CoverTable; chosen: option ids of the plan.
    Returns:
      list of dict per area: ``lon_deg``, ``lat_deg`` (float [N]) and ``covered`` (bool [N]).
    """
    hit, _ = _plan_samples(cover, chosen)
    out, at = [], 0
    for g in areas.grids:
        n = len(g)
        out.append({"lon_deg": g.lon_deg, "lat_deg": g.lat_deg, "covered": hit[at : at + n]})
        at += n
    return out


def strip_footprints(ctx, obs) -> list:
    """The ground each area strip of the plan sweeps (module docstring).

    Args:
      ctx: the PlanContext; obs: the plan's Observations.
    Returns:
      list per observation: ``(lon [deg], lat [deg])`` of the ring (closed), or None for
      an observation of a point or strip target.
    """
    sc = ctx.scenario
    step = sc.planner.geometry_step
    out = [None] * len(obs)
    area = np.flatnonzero(np.isfinite(obs.roll))
    if area.size == 0:
        return out
    pos, vel, _ = earth_fixed_tracks(sc, ctx.orbits, ctx.scene)
    for i in area.tolist():
        k = int(obs.sat[i])
        a = int(round(float(obs.start[i]) / step))
        b = int(round(float(obs.end[i]) / step))
        roll, pitch = float(np.degrees(obs.roll[i])), float(np.degrees(obs.pitch[i]))
        inner, outer, _ = strip_quads(
            pos[k, a : b + 1],
            vel[k, a : b + 1],
            roll,
            ctx.areas.fov_deg[k],
            pitch,
        )
        ring = np.concatenate([inner, outer[::-1], inner[:1]])
        out[i] = (ring[:, 0], ring[:, 1])
    return out
