"""The :class:`PlanResult` of a planner run, assembled from what its stages returned.

:func:`jaxspline.planner.pipeline.plan` runs the stages (problem, search, repair, the
optional HiGHS certificate); :func:`assemble_result` only reads their outputs: the
observations in the re-check's order with their maneuver times and slacks, the value
and the bound (the search's, capped by the value of the targets that have an option,
lowered by the HiGHS bound when that is smaller), the battery profiles, the check
report and the statistics.
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.planner.context import PlanContext
from jaxspline.planner.result import Observations, PlanResult
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
    obs = _observations(sc.targets, rep.opp, det)
    value = float(np.sum(obs.value))
    bound, converged = _search_bound(sc.targets, rep.opp, res)
    mip_stats = None
    if mip is not None:
        mip_stats, bound, converged = _with_certificate(mip, bound, converged)
    return PlanResult(
        scenario=sc,
        observations=obs,
        value=value,
        bound=max(bound, value),
        gap=max(bound, value) - value,
        bound_converged=converged,
        report=_report(rep, obs, flown_joins, interrupted),
        stats=_stats(ctx, rep, res, mip_stats, peak_rss_mb),
        timings=timings,
        battery=_battery_profiles(sc.satellites, ctx.battery, det),
    )


def _observations(tg, opp, det) -> Observations:
    """The checked observations of the options ``opp`` in the re-check's order
    (``det["order"]``), with its maneuver times and slacks and the targets' values."""
    o = opp.options
    idx = np.asarray(det["order"], np.int64)
    return Observations(
        sat=np.asarray(o.sat)[idx],
        target=np.asarray(o.route)[idx],
        start=np.asarray(o.t_start)[idx],
        end=np.asarray(o.t_end)[idx],
        maneuver=det["maneuver"],
        slack=det["slack"],
        value=np.asarray(tg.value)[np.asarray(o.route)[idx]],
        speed=opp.speed[idx],
    )


def _search_bound(tg, opp, res):
    """The search's bound capped by the total value of the targets that have an option
    (every plan images only those), and whether the bound converged. Returns (bound,
    converged)."""
    reachable = float(np.sum(np.asarray(tg.value)[np.unique(np.asarray(opp.options.route))]))
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
        "pair_bytes": round(pb.pairs.nbytes / max(len(pb.pairs), 1), 2),
        "peak_rss_mb": peak_rss_mb,
        "bound_status": res.bound_status,
        "refined": rep.refined,
        "exact": res.exact,
        "mip": mip_stats,
        **res.stats,
    }
