"""The :class:`PlanResult` of a planner run, assembled from what its stages returned.

:func:`jaxspline.planner.pipeline.plan` runs the stages (problem, search, repair, the
optional HiGHS certificate); :func:`assemble_result` only reads their outputs: the
observations in the re-check's order with their maneuver times and slacks, the value
(an area counted by the share of its samples the plan's strips cover,
:mod:`jaxspline.planner.area_report`) and the bound (the search's, capped by the value
within reach of the options, lowered by the HiGHS bound when that is smaller), the
battery profiles, the check report and the statistics.
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.planner.area_report import area_report, area_samples, strip_footprints
from jaxspline.planner.context import PlanContext
from jaxspline.planner.result import Observations, PlanResult
from jaxspline.planner.stereo_report import look_values, stereo_report
from jaxspline.search import BoundStatus

__all__ = ["assemble_result"]


def assemble_result(
    ctx: PlanContext, res, rep, mip, *, flown_joins: bool, interrupted, timings, peak_rss_mb
) -> PlanResult:
    """The result of a planner run from its stages' outputs.

    Args:
      ctx: :class:`jaxspline.planner.context.PlanContext`, stages 1-4 (with the planned
        scenario).
      res: :class:`jaxspline.search.SearchResult`, stage 5.
      rep: :class:`jaxspline.planner.repair.Repaired`, stage 6 (its ``details`` are the
        final re-check's).
      mip: :class:`jaxspline.search.mip.MipBound` of the HiGHS certificate, or None.
      flown_joins: the plan's joins were checked (the report gets their summary).
      interrupted: name of the signal that stopped the search, or None.
      timings: wall time per stage [s].
      peak_rss_mb: process peak RSS at the end of each stage [MB].
    Returns:
      PlanResult.
    """
    sc = ctx.scenario
    det = rep.details
    obs = _observations(sc.targets, rep.opp, det, ctx.problem.cover, ctx.problem.stereo)
    value = float(np.sum(obs.value))
    bound, converged = _search_bound(sc.targets, rep.opp, res, ctx.problem.cover)
    mip_stats = None
    if mip is not None:
        mip_stats, bound, converged = _with_certificate(mip, bound, converged)
    report = _report(rep, obs, flown_joins, interrupted)
    areas, footprints = [], []
    if ctx.problem.stereo is not None:
        report["stereo"] = stereo_report(sc, ctx.problem.stereo, ctx.stereo[1].products,
                                         det["order"])  # fmt: skip
    if ctx.problem.cover is not None:
        report["areas"] = area_report(sc, ctx.problem.cover, det["order"])
        areas = area_samples(ctx.areas, ctx.problem.cover, det["order"])
        footprints = strip_footprints(ctx, obs)
    return PlanResult(
        scenario=sc,
        observations=obs,
        value=value,
        bound=max(bound, value),
        gap=max(bound, value) - value,
        bound_converged=converged,
        report=report,
        stats=_stats(ctx, rep, res, mip_stats, peak_rss_mb),
        timings=timings,
        battery=_battery_profiles(sc.satellites, ctx.battery, det),
        areas=areas,
        footprints=footprints,
    )


def _observations(tg, opp, det, cover, stereo=None) -> Observations:
    """The checked observations of the options ``opp`` in the re-check's order
    (``det["order"]``), with its maneuver times and slacks, the targets' values (an
    area strip's or a look's: what it adds to the earlier ones) and the held roll and
    pitch of area strips and looks."""
    o = opp.options
    idx = np.asarray(det["order"], np.int64)
    value = np.asarray(tg.value, np.float64)[np.asarray(o.route)[idx]]
    roll, pitch = np.full(idx.size, np.nan), np.full(idx.size, np.nan)
    if cover is not None:
        area = cover.option_group[idx] >= 0
        value[area] = _strip_values(cover, idx[area], np.asarray(o.t_start)[idx[area]])
        roll[area] = opp.params[idx[area], 0]
        pitch[area] = opp.params[idx[area], 1]
    if stereo is not None:
        look = stereo.is_look[idx]
        value[look] = look_values(stereo, idx, np.asarray(o.t_start)[idx])[look]
        roll[look] = opp.params[idx[look], 0]
        pitch[look] = opp.params[idx[look], 1]
    return Observations(
        sat=np.asarray(o.sat)[idx],
        target=np.asarray(o.route)[idx],
        start=np.asarray(o.t_start)[idx],
        end=np.asarray(o.t_end)[idx],
        maneuver=det["maneuver"],
        slack=det["slack"],
        value=value,
        speed=opp.speed[idx],
        roll=roll,
        pitch=pitch,
    )


def _strip_values(cover, ids, starts) -> np.ndarray:
    """The value each area option ``ids`` adds to the ones starting before it."""
    hit = np.zeros(cover.n_samples, bool)
    out = np.zeros(ids.size)
    for j in np.argsort(starts, kind="stable"):
        c = int(ids[j])
        s = cover.samples(
            int(cover.option_group[c]), int(cover.option_a[c]), int(cover.option_b[c])
        )
        new = s[~hit[s]]
        out[j] = float(cover.weight[new].sum())
        hit[new] = True
    return out


def _search_bound(tg, opp, res, cover):
    """The search's bound capped by the value within reach of the options (the targets
    that have one; of an area, the share its candidate strips cover), and whether the
    bound converged. Returns (bound, converged)."""
    routes = np.unique(np.asarray(opp.options.route))
    value = np.asarray(tg.value, np.float64)
    if cover is None:
        reachable = float(np.sum(value[routes]))
    else:
        areas = set(cover.area_target.tolist())
        reachable = float(sum(value[r] for r in routes.tolist() if r not in areas))
        reachable += cover.union_weight()
    bound = min(float(res.bound), reachable)
    return bound, res.bound_status in (BoundStatus.OPTIMAL, BoundStatus.CONVERGED)


def _with_certificate(mip, bound: float, converged: bool):
    """The HiGHS certificate ``mip`` as the stats entry, and the bound: its dual bound
    (converged when HiGHS proved optimality) when smaller than ``bound``. Returns
    (stats entry, bound, converged)."""
    found = mip.value if math.isfinite(mip.value) else None
    stats = {"bound": mip.bound, "plan_value": found, "status": mip.status, "seconds": mip.seconds}
    if mip.bound < bound:
        bound, converged = mip.bound, mip.status == BoundStatus.OPTIMAL
    return stats, bound, converged


def _battery_profiles(sats, battery, det) -> dict:
    """Per powered satellite's name, ``(t [s], level [Wh])`` of its checked battery
    profile (the idle profile when it has no observations)."""
    bat = {}
    for k, s in enumerate(sats):
        if battery.has(k):
            lev = det["battery"].get(s.name)
            if lev is None:  # no observations: the idle profile
                lev = battery.profile(k, [], [], [])
            bat[s.name] = (np.arange(lev.size) * battery.dt, lev)
    return bat


def _report(rep, obs: Observations, flown_joins: bool, interrupted) -> dict:
    """The check report: validity and violations of the final re-check, what the repair
    dropped and found, the smallest slack and battery levels, the joins' summary (with
    ``flown_joins``) and the stopping signal (when ``interrupted``)."""
    det = rep.details
    report = {
        "valid": not det["violations"],
        "checked": len(obs),
        "dropped": rep.dropped,
        "dropped_total": sum(rep.dropped.values()),
        "violations_found": rep.violations,
        "repair_rounds": rep.rounds,
        "violations": det["violations"],
        "min_slack_s": float(obs.slack.min()) if len(obs) else None,
        "min_battery_wh": det["battery_min"],
    }
    if flown_joins:
        report["joins"] = {**rep.joins, "rejected": rep.dropped["joins"], "refilled": rep.refilled}
    if interrupted:
        report["interrupted"] = interrupted
    return report


def _stats(ctx: PlanContext, rep, res, mip_stats, peak_rss_mb) -> dict:
    """The run's statistics: problem sizes, pair store, far gaps, peak memory, the
    bound's status, refinement, exact search and certificate, and the search's own."""
    pb = ctx.problem
    return {
        "windows": len(ctx.windows),
        "options": len(rep.opp),
        "near_pairs": len(pb.pairs),
        "pair_store_bytes": pb.pairs.nbytes,
        "far_gap_s": ctx.far.tolist(),
        "pair_bytes": round(pb.pairs.nbytes / len(pb.pairs), 2) if len(pb.pairs) else None,
        "peak_rss_mb": peak_rss_mb,
        "bound_status": res.bound_status,
        "refined": rep.refined,
        "exact": res.exact,
        "mip": mip_stats,
        **res.stats,
    }
