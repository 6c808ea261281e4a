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
  checked by sampling their Theorem-1 trajectories (:func:`jaxspline.check_steps`);
* battery: the conservative profile (:class:`jaxspline.search.BatteryModel`) with
  margin 0 stays >= 0.

Failing observations are reported by index, each with the reason it fails: one
observation per violated rule (the later observation of a failing transition, the
first observation a battery overdraw follows), so dropping them never takes more
than the violations.
"""

from __future__ import annotations

import numpy as np

from jaxspline.geometry.frames import angle_between
from jaxspline.kernels._batch import pad_rows, round_up
from jaxspline.kernels.reach_durations import min_transfer_time
from jaxspline.planning.mission import Scenario
from jaxspline.planning.opportunities import evaluate, geometry_batched, observation_samples
from jaxspline.planning.steps_check import check_steps
from jaxspline.screen.options import RouteOptions, take_options

__all__ = ["check_plan"]

_SAMPLES = 201  # Theorem-1 samples per per-channel maneuver
_TIME_TOL = 1e-6  # [s] slack of the midpoint-window and minimum-duration tests
_PAD = 1 << 10  # kernel batches are padded to multiples of this (few compiled shapes)


def check_plan(sc: Scenario, scene, table_ok, opp, chosen, battery):
    """Re-check the options ``chosen`` (ids into ``opp``) from scratch.

    Args:
      sc: Scenario.
      scene: Scene of the scenario's satellites.
      table_ok: callable (sat int [M], t float [M] [s]) -> bool [M], the orbit table is
        usable there.
      opp: Opportunities.
      chosen: int [K], option ids of the plan.
      battery: BatteryModel of the scenario.
    Returns:
      (bad, details): the sorted option ids that fail, and a dict with the
      per-observation required maneuver time and slack [s] (exact kernels), the
      battery profile and minimum of every powered satellite that has observations,
      the human-readable violations, the checked order and ``reasons`` (option id ->
      "geometry", "timing", "repeat", "maneuver" or "battery", the first rule it broke).
    """
    o = opp.options
    chosen = np.asarray(sorted(chosen, key=lambda c: (o.sat[c], o.t_start[c])), np.int64)
    n = chosen.size
    viol, bad = [], {}
    man = np.zeros(n)
    slack = np.zeros(n)
    if n == 0:
        empty = {"maneuver": man, "slack": slack, "violations": viol, "reasons": {}}
        return [], {**empty, "battery_min": {}, "battery": {}, "order": chosen}
    sat, tgt = o.sat[chosen], o.route[chosen]
    t0, t1 = o.t_start[chosen], o.t_end[chosen]
    tg = sc.targets
    step = sc.planner.geometry_step
    # --- geometry at every sample
    owner, ts = observation_samples(t0, t1, step, tol=0.0)
    offn, elev, _, _ = evaluate(
        geometry_batched, scene, sat[owner], opp.params[chosen][owner], t0[owner], ts
    )
    lim = np.array([s.off_nadir_max for s in sc.satellites])
    ok_s = (offn <= lim[sat[owner]]) & (elev > 0.0) & table_ok(sat[owner], ts)
    geo_ok = np.ones(n, bool)
    np.logical_and.at(geo_ok, owner, ok_s)
    sensors = np.array([s.sensor for s in sc.satellites])
    time_ok = (
        (t0 >= tg.t_lo[tgt] - 1e-9)
        & (t1 <= tg.t_hi[tgt] + 1e-9)
        & (t0 >= 0.0)
        & (t1 <= sc.duration + 1e-9)
        & ((tg.sensor[tgt] == "") | (tg.sensor[tgt] == sensors[sat]))
    )
    for i in np.flatnonzero(~(geo_ok & time_ok)):
        bad.setdefault(int(chosen[i]), "geometry")
        viol.append(f"{sc.satellites[sat[i]].name} {tg.name[tgt[i]]}: geometry / window")
    mid = 0.5 * (t0 + t1)
    mid_ok = (mid >= tg.mid_lo[tgt] - _TIME_TOL) & (mid <= tg.mid_hi[tgt] + _TIME_TOL)
    for i in np.flatnonzero(~mid_ok):
        bad.setdefault(int(chosen[i]), "timing")
        viol.append(
            f"{sc.satellites[sat[i]].name} {tg.name[tgt[i]]}: imaging midpoint {mid[i]:.3f} s "
            f"outside the desired time window [{tg.mid_lo[tgt[i]]:g}, {tg.mid_hi[tgt[i]]:g}] s"
        )
    for i in np.flatnonzero(t1 - t0 < tg.min_duration[tgt] - _TIME_TOL):
        bad.setdefault(int(chosen[i]), "timing")
        viol.append(
            f"{sc.satellites[sat[i]].name} {tg.name[tgt[i]]}: imaging time "
            f"{t1[i] - t0[i]:.3f} s < min_duration {tg.min_duration[tgt[i]]:g} s"
        )
    dup = np.unique(tgt, return_counts=True)
    for r in dup[0][dup[1] > 1]:
        again = np.flatnonzero(tgt == r)
        for i in again[np.argsort(t0[again], kind="stable")][1:]:  # keep the earliest
            viol.append(f"target {tg.name[r]} imaged more than once")  # one per repeat
            bad.setdefault(int(chosen[i]), "repeat")
    # --- maneuvers
    first = np.ones(n, bool)
    first[1:] = sat[1:] != sat[:-1]
    prev = np.where(first, chosen, np.roll(chosen, 1))
    gap = np.where(first, t0, t0 - np.roll(t1, 1))
    bat_min, levels = {}, {}
    for k, s in enumerate(sc.satellites):
        m = np.flatnonzero(sat == k)
        if m.size == 0:
            continue
        if s.maneuver.rest_to_rest:
            frm = np.where(first[m, None], o.start_nadir[chosen[m]], o.end_los[prev[m]])
            th = angle_between(frm, o.start_los[chosen[m]])
            need = s.maneuver.slew_time(s, th)
            man[m], slack[m] = need, gap[m] - need
            for i in m[gap[m] < need]:
                bad.setdefault(int(chosen[i]), "maneuver")
                viol.append(
                    f"{s.name} {tg.name[tgt[i]]}: maneuver {man[i]:.3f} s > gap {gap[i]:.3f} s"
                )
        else:
            steps = take_options(o, chosen[m])
            rest = RouteOptions(
                *(
                    None if x is None else np.concatenate([np.zeros_like(np.asarray(x)[:1]), x])
                    for x in steps
                )
            )
            rest = rest._replace(
                route=np.concatenate([[int(tg.kind.size)], steps.route]),
                scan_ok=np.ones(m.size + 1, bool),
            )
            rep = check_steps(rest, s.limits, samples=_SAMPLES)
            if not rep.ok:
                for v in rep.violations:
                    viol.append(f"{s.name}: {v}")
                # step 0 of ``rest`` is the rest state before the first observation
                for step in rep.bad_steps:
                    bad.setdefault(int(chosen[m[max(step - 1, 0)]]), "maneuver")
            size = round_up(m.size, _PAD)  # few compiled shapes across checks
            frm_a = np.where(first[m, None], 0.0, o.end_angle[prev[m]])
            frm_b = np.where(first[m, None], 0.0, o.end_rate[prev[m]])
            args = (frm_a, frm_b, o.start_angle[chosen[m]], o.start_rate[chosen[m]])
            tmin = np.asarray(min_transfer_time(*(pad_rows(x, size) for x in args), s.limits)).max(
                -1
            )[: m.size]
            man[m], slack[m] = np.minimum(tmin, gap[m]), gap[m] - np.minimum(tmin, gap[m])
        if battery.has(k):
            lev = battery.profile(k, t0[m], t1[m], man[m])
            levels[s.name] = lev
            bat_min[s.name] = float(lev.min())
            if lev.min() < 0.0:
                kv = int(np.argmax(lev < 0.0))
                before = m[t0[m] <= kv * battery.dt]
                i = before[-1] if before.size else m[0]
                bad.setdefault(int(chosen[i]), "battery")
                viol.append(f"{s.name}: battery below 0 Wh at t = {kv * battery.dt:.0f} s")
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
