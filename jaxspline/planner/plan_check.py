"""Independent re-check of a plan: geometry, maneuvers and battery from scratch.

The search works with margins, slew tables and screened pairs; this module re-derives
every constraint of the scenario *without* margins from the kernels:

* geometry: at the start, at every geometry knot inside and at the end of each
  observation, the aim point is above its horizon (elevation sine > 0) and the
  off-nadir angle is within the satellite's limit
  (:func:`jaxspline.geometry.pointing.aim_geometry`); imaging windows, the horizon and the
  sensor type hold;
* imaging time: the midpoint ``(start + end) / 2`` lies in the target's
  ``[mid_lo, mid_hi]`` (desired time +- tolerance) and ``end - start`` reaches its
  ``min_duration`` (both to 1e-6 s);
* maneuvers: rest-to-rest models need the exact slew time
  (``sat.maneuver.slew_time``) plus settling within the gap; per-channel
  satellites' transfers (from rest at zero angles at t = 0 for the first one) are
  checked by sampling their Theorem-1 trajectories (:func:`jaxspline.sequences.check_steps`);
* battery: the conservative profile (:class:`jaxspline.search.BatteryModel`) with
  margin 0 stays >= 0;
* areas: an area's strips keep their edges inside the satellite's edge band (where it
  has one and a field of view), any number of them may image one area (every other
  target is imaged once), and a satellite's imaging time in any window of one orbital
  period ending at an observation's start or end stays within its duty (where it has
  one); the plan holds at most the planner's ``max_actions`` observations.

Failing observations are reported by index, each with the reason it fails: one
observation per violated rule (the later observation of a failing transition, the
first observation a battery overdraw follows), so dropping them never takes more
than the violations.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxspline.geometry.frames import angle_between
from jaxspline.geometry.orbit import orbit_period
from jaxspline.geometry.routes import AREA
from jaxspline.kernels.batch import pad_rows, round_up
from jaxspline.kernels.reach_durations import min_transfer_time
from jaxspline.planner.context import PlanContext
from jaxspline.planner.opportunities import evaluate, geometry_batched, observation_samples
from jaxspline.readers.mission import HELD_KINDS
from jaxspline.screen.options import RouteOptions, take_options
from jaxspline.sequences.steps_check import check_steps

__all__ = ["check_plan"]

_SAMPLES = 201  # Theorem-1 samples per per-channel maneuver
_TIME_TOL = 1e-6  # [s] slack of the midpoint-window and minimum-duration tests
_PAD = 1 << 10  # kernel batches are padded to multiples of this (few compiled shapes)
_BAND_TOL = 1e-9  # [rad] slack of the edge-band test


def check_plan(ctx: PlanContext, chosen, opp=None):
    """Re-check the options ``chosen`` (ids into ``opp``) from scratch.

    Args:
      ctx: PlanContext: the scenario (its rules, without margins), the scene, the
        usable orbit table and the battery model.
      chosen: int [K], option ids of the plan.
      opp: the Opportunities ``chosen`` indexes (default: ``ctx.opportunities``; the
        repair passes a refined table).
    Returns:
      (bad, details): the sorted option ids that fail, and a dict with the
      per-observation required maneuver time and slack [s] (exact kernels), the
      battery profile and minimum of every powered satellite that has observations,
      the human-readable violations, the checked order and ``reasons`` (option id ->
      "geometry", "timing", "repeat", "maneuver", "duty", "cap" or "battery", the first
      rule it broke).
    """
    sc, battery = ctx.scenario, ctx.battery
    opp = ctx.opportunities if opp is None else opp
    o = opp.options
    chosen = np.asarray(sorted(chosen, key=lambda c: (o.sat[c], o.t_start[c])), np.int64)
    n = chosen.size
    man = np.zeros(n)
    slack = np.zeros(n)
    if n == 0:
        empty = {"maneuver": man, "slack": slack, "violations": [], "reasons": {}}
        return [], {**empty, "battery_min": {}, "battery": {}, "order": chosen}
    pl = _plan_rows(o, chosen)
    found = [
        _geometry_findings(ctx, opp, pl),
        _timing_findings(sc, pl),
        _repeat_findings(sc, pl),
        _band_findings(sc, opp, pl),
        _duty_findings(sc, pl),
        _cap_findings(sc, pl),
    ]
    bat_min, levels = {}, {}
    for k, s in enumerate(sc.satellites):
        m = np.flatnonzero(pl.sat == k)
        if m.size == 0:
            continue
        check = _rest_to_rest_maneuvers if s.maneuver.rest_to_rest else _per_channel_maneuvers
        man[m], slack[m], f = check(sc, o, pl, s, m)
        found.append(f)
        if battery.has(k):
            lev, f = _battery_findings(battery, k, s, pl, m, man[m])
            levels[s.name] = lev
            bat_min[s.name] = float(lev.min())
            found.append(f)
    viol, bad = _merged(found)
    details = {
        "maneuver": man,
        "slack": slack,
        "violations": viol,
        "battery_min": bat_min,
        "battery": levels,
        "order": chosen,
        "reasons": bad,
    }
    return sorted(bad), details


class _PlanRows(NamedTuple):
    """The checked plan in satellite-then-start order, one row per observation: its
    option ``chosen``, satellite ``sat``, target ``tgt``, start ``t0`` and end ``t1``
    [s], whether it is its satellite's ``first``, the option ``prev`` it follows (itself
    for a first one) and the ``gap`` [s] since that option's end (since t = 0 for a
    first one)."""

    chosen: np.ndarray
    sat: np.ndarray
    tgt: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    first: np.ndarray
    prev: np.ndarray
    gap: np.ndarray


class _Findings(NamedTuple):
    """What one rule found: the human-readable ``violations`` and the ``(option id,
    reason)`` pairs it blames, both in the order found."""

    violations: list
    bad: list


def _plan_rows(o, chosen) -> _PlanRows:
    """The rows of the options ``chosen`` (already in satellite-then-start order) of the
    option table ``o``, with each row's predecessor on its satellite and the gap to it."""
    sat, tgt = o.sat[chosen], o.route[chosen]
    t0, t1 = o.t_start[chosen], o.t_end[chosen]
    first = np.ones(chosen.size, bool)
    first[1:] = sat[1:] != sat[:-1]
    prev = np.where(first, chosen, np.roll(chosen, 1))
    gap = np.where(first, t0, t0 - np.roll(t1, 1))
    return _PlanRows(chosen, sat, tgt, t0, t1, first, prev, gap)


def _merged(found):
    """The violations of all findings in order, and the reason of every blamed option:
    the first one found (a dict in the order the options were first blamed)."""
    viol, bad = [], {}
    for f in found:
        viol.extend(f.violations)
        for c, reason in f.bad:
            bad.setdefault(c, reason)
    return viol, bad


def _geometry_findings(ctx: PlanContext, opp, pl: _PlanRows) -> _Findings:
    """Observations that break the geometry at any sample (start, knots inside, end: the
    off-nadir limit, the aim point above its horizon, the orbit table usable) or their
    window (the target's imaging window, the horizon [0, duration], the sensor type):
    reason "geometry"."""
    sc = ctx.scenario
    tg = sc.targets
    sat, tgt, t0, t1 = pl.sat, pl.tgt, pl.t0, pl.t1
    owner, ts = observation_samples(t0, t1, sc.planner.geometry_step, tol=0.0)
    offn, elev, _, _ = evaluate(
        geometry_batched, ctx.scene, sat[owner], opp.params[pl.chosen][owner], t0[owner], ts
    )
    lim = np.array([s.off_nadir_max for s in sc.satellites])
    ok_s = (offn <= lim[sat[owner]]) & (elev > 0.0) & ctx.usable(sat[owner], ts)
    geo_ok = np.ones(pl.chosen.size, bool)
    np.logical_and.at(geo_ok, owner, ok_s)
    sensors = np.array([s.sensor for s in sc.satellites])
    time_ok = (
        (t0 >= tg.t_lo[tgt] - 1e-9)
        & (t1 <= tg.t_hi[tgt] + 1e-9)
        & (t0 >= 0.0)
        & (t1 <= sc.duration + 1e-9)
        & ((tg.sensor[tgt] == "") | (tg.sensor[tgt] == sensors[sat]))
    )
    f = _Findings([], [])
    for i in np.flatnonzero(~(geo_ok & time_ok)):
        f.bad.append((int(pl.chosen[i]), "geometry"))
        f.violations.append(f"{sc.satellites[sat[i]].name} {tg.name[tgt[i]]}: geometry / window")
    return f


def _timing_findings(sc, pl: _PlanRows) -> _Findings:
    """Observations whose imaging midpoint lies outside the target's ``[mid_lo,
    mid_hi]``, then those shorter than its ``min_duration`` (both to ``_TIME_TOL``):
    reason "timing"."""
    tg = sc.targets
    sat, tgt, t0, t1 = pl.sat, pl.tgt, pl.t0, pl.t1
    f = _Findings([], [])
    mid = 0.5 * (t0 + t1)
    mid_ok = (mid >= tg.mid_lo[tgt] - _TIME_TOL) & (mid <= tg.mid_hi[tgt] + _TIME_TOL)
    for i in np.flatnonzero(~mid_ok):
        f.bad.append((int(pl.chosen[i]), "timing"))
        f.violations.append(
            f"{sc.satellites[sat[i]].name} {tg.name[tgt[i]]}: imaging midpoint {mid[i]:.3f} s "
            f"outside the desired time window [{tg.mid_lo[tgt[i]]:g}, {tg.mid_hi[tgt[i]]:g}] s"
        )
    for i in np.flatnonzero(t1 - t0 < tg.min_duration[tgt] - _TIME_TOL):
        f.bad.append((int(pl.chosen[i]), "timing"))
        f.violations.append(
            f"{sc.satellites[sat[i]].name} {tg.name[tgt[i]]}: imaging time "
            f"{t1[i] - t0[i]:.3f} s < min_duration {tg.min_duration[tgt[i]]:g} s"
        )
    return f


def _repeat_findings(sc, pl: _PlanRows) -> _Findings:
    """Every observation of a point or strip target but its earliest one (one violation
    per repeat; an area or a stereo target takes any number): reason "repeat"."""
    tg = sc.targets
    f = _Findings([], [])
    dup = np.unique(pl.tgt[~np.isin(tg.kind[pl.tgt], HELD_KINDS)], return_counts=True)
    for r in dup[0][dup[1] > 1]:
        again = np.flatnonzero(pl.tgt == r)
        for i in again[np.argsort(pl.t0[again], kind="stable")][1:]:  # keep the earliest
            f.violations.append(f"target {tg.name[r]} imaged more than once")
            f.bad.append((int(pl.chosen[i]), "repeat"))
    return f


def _rest_to_rest_maneuvers(sc, o, pl: _PlanRows, s, m):
    """Maneuvers of the rest-to-rest satellite ``s`` (plan rows ``m``): the exact slew
    time plus settling from the previous end line of sight (the nadir at the start for
    the first one). Returns (required time [s], slack [s], findings: each observation
    whose gap is shorter, reason "maneuver")."""
    chosen, first, prev, gap = pl.chosen, pl.first, pl.prev, pl.gap
    frm = np.where(first[m, None], o.start_nadir[chosen[m]], o.end_los[prev[m]])
    th = angle_between(frm, o.start_los[chosen[m]])
    need = np.asarray(s.maneuver.slew_time(s, th), np.float64)
    if not s.maneuver.first_from_nadir:  # the model's first observation needs no slew
        need = np.where(first[m], 0.0, need)
    man = need
    f = _Findings([], [])
    for j in np.flatnonzero(gap[m] < need):
        i = m[j]
        f.bad.append((int(chosen[i]), "maneuver"))
        f.violations.append(
            f"{s.name} {sc.targets.name[pl.tgt[i]]}: maneuver {man[j]:.3f} s > gap {gap[i]:.3f} s"
        )
    return need, gap[m] - need, f


def _per_channel_maneuvers(sc, o, pl: _PlanRows, s, m):
    """Maneuvers of the per-channel satellite ``s`` (plan rows ``m``): its Theorem-1
    trajectories sampled from rest at zero angles (:func:`jaxspline.sequences.check_steps`), and the
    exact minimum transfer times. Returns (required time min(t_min, gap) [s], slack [s],
    findings: the later observation of each failing transition, reason "maneuver")."""
    chosen, first, prev, gap = pl.chosen, pl.first, pl.prev, pl.gap
    f = _Findings([], [])
    rep = check_steps(_from_rest(sc, o, chosen[m]), s.limits, samples=_SAMPLES)
    if not rep.ok:
        for v in rep.violations:
            f.violations.append(f"{s.name}: {v}")
        # step 0 of the table is the rest state before the first observation
        for step in rep.bad_steps:
            f.bad.append((int(chosen[m[max(step - 1, 0)]]), "maneuver"))
    size = round_up(m.size, _PAD)  # few compiled shapes across checks
    frm_a = np.where(first[m, None], 0.0, o.end_angle[prev[m]])
    frm_b = np.where(first[m, None], 0.0, o.end_rate[prev[m]])
    args = (frm_a, frm_b, o.start_angle[chosen[m]], o.start_rate[chosen[m]])
    padded = (pad_rows(x, size) for x in args)
    tmin = np.asarray(min_transfer_time(*padded, s.limits)).max(-1)[: m.size]
    return np.minimum(tmin, gap[m]), gap[m] - np.minimum(tmin, gap[m]), f


def _from_rest(sc, o, ids) -> RouteOptions:
    """The steps of the options ``ids`` (one satellite's, in order) after a rest step:
    zero angles and rates at t = 0, each step on a route of its own, every scan flyable."""
    steps = take_options(o, ids)
    rest = RouteOptions(
        *(
            None if x is None else np.concatenate([np.zeros_like(np.asarray(x)[:1]), x])
            for x in steps
        )
    )
    # one route a step: repeats are the repeat rule's business (an area takes many)
    return rest._replace(route=np.arange(ids.size + 1), scan_ok=np.ones(ids.size + 1, bool))


def _band_findings(sc, opp, pl: _PlanRows) -> _Findings:
    """Area strips of satellites with an edge band and a field of view whose edges
    ``|roll| -+ fov / 2`` leave the band (1e-9 rad): reason "geometry"."""
    f = _Findings([], [])
    area = sc.targets.kind[pl.tgt] == AREA
    for i in np.flatnonzero(area):
        s = sc.satellites[pl.sat[i]]
        if s.edge_band is None or s.fov is None:
            continue
        r = abs(float(opp.params[pl.chosen[i], 0]))
        lo, hi = (float(x) for x in s.edge_band)
        if r - s.fov / 2 < lo - _BAND_TOL or r + s.fov / 2 > hi + _BAND_TOL:
            f.bad.append((int(pl.chosen[i]), "geometry"))
            f.violations.append(
                f"{s.name} {sc.targets.name[pl.tgt[i]]}: strip edges outside the edge band"
            )
    return f


def _duty_findings(sc, pl: _PlanRows) -> _Findings:
    """Imaging time over a satellite's duty in a window of one orbital period ending at
    an observation's start or end: the observation ending the window, reason "duty"."""
    f = _Findings([], [])
    for k, s in enumerate(sc.satellites):
        m = np.flatnonzero(pl.sat == k)
        if s.duty is None or m.size == 0:
            continue
        period = orbit_period(s.orbit)
        a, b = pl.t0[m], pl.t1[m]
        ends = sorted((float(x), i) for i in range(m.size) for x in (a[i], b[i]))
        for t, j in ends:
            used = float(np.sum(np.clip(np.minimum(b, t) - np.maximum(a, t - period), 0.0, None)))
            if used > s.duty + _TIME_TOL:
                f.bad.append((int(pl.chosen[m[j]]), "duty"))
                f.violations.append(
                    f"{s.name}: {used:.3f} s imaging in the orbit before t = {t:.1f} s > duty "
                    f"{s.duty:g} s"
                )
                break
    return f


def _cap_findings(sc, pl: _PlanRows) -> _Findings:
    """Observations past the planner's ``max_actions`` (the latest ones): reason "cap"."""
    f = _Findings([], [])
    cap = sc.planner.max_actions
    if cap is None or pl.chosen.size <= cap:
        return f
    late = np.argsort(pl.t0, kind="stable")[cap:]
    for i in late:
        f.bad.append((int(pl.chosen[i]), "cap"))
    f.violations.append(f"{pl.chosen.size} observations > max_actions {cap}")
    return f


def _battery_findings(battery, k, s, pl: _PlanRows, m, man):
    """The battery profile of satellite ``k`` (``s``, plan rows ``m``, required maneuver
    times ``man`` [s]) with margin 0: the model's level must stay >= ``clamp_wh``, what
    it may exceed the reference's by. Returns (levels, findings: when it drops below
    that, the last observation starting at or before that instant - the first one when
    none does - reason "battery")."""
    lev = battery.profile(k, pl.t0[m], pl.t1[m], man)
    f = _Findings([], [])
    if lev.min() < battery.clamp_wh:
        kv = int(np.argmax(lev < battery.clamp_wh))
        before = m[pl.t0[m] <= kv * battery.dt]
        i = before[-1] if before.size else m[0]
        f.bad.append((int(pl.chosen[i]), "battery"))
        f.violations.append(f"{s.name}: battery below 0 Wh at t = {kv * battery.dt:.0f} s")
    return lev, f
