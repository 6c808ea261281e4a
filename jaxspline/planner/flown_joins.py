"""Degree-7 joins between the observations of a plan, checked against the limits, re-timed.

Between two consecutive observations of one satellite the attitude follows the
degree-7 MRP join of SPEC section 3 (:func:`jaxspline.kernels.joins.maneuver_plan`) from the
end state (q, ω, ε, ε') of the first scan law to the start state of the next, so
attitude, rate, acceleration and jerk are continuous at both junctions
(:mod:`jaxspline.planner.attitude_laws` for the laws and frames). Timing of the joins:

* gap <= :data:`DIRECT_MAX_S`: one join over the exact gap;
* longer gaps: a join to the nadir law over :data:`RETURN_S`, nadir hold, and a
  join from nadir over :data:`RETURN_S` ending at the next start (a single join
  over a long gap would rotate by more than 180 deg inertially, where the
  midpoint chart takes the short way round);
* before the first observation: nadir, then a join from nadir over the exact time
  from t = 0 (the per-channel model's initial rest at zero angles) or over
  :data:`RETURN_S` when the first start is later than :data:`DIRECT_MAX_S`;
* after the last observation: a join back to nadir over :data:`RETURN_S`.

Check (:func:`join_limits`): every join is sampled at :data:`JOIN_SAMPLES` instants and
passes when each sampled peak is below (1 - :data:`SAMPLING_MARGIN`) times its limit;
``eigen_axis`` and ``flexible``: |ω| <= rate and |ε| <= accel (the eigen-axis bounds of
the model); ``flexible`` also |ε'| <= accel / tau, the jerk of its own slew profile
(the ramp tau suppresses the structural mode, SPEC section 2); ``eigen_axis`` has no
jerk limit (its bang-coast-bang profile has unbounded jerk; the peak is reported);
``per_channel``: the roll, pitch and yaw rates and accelerations of the join seen in
the orbital frame against the per-channel bounds (the model of SPEC section 1; no
jerk limit, the peak |ε'| is reported).

Re-timing: a violating join may start later and / or end earlier inside its
interval, the laws on either side being followed for longer (the scan continues
tracking its target, nadir holds): extensions of :data:`RETIME_FRACTIONS` of the
interval on each side, at most :data:`RETIME_MAX_SHARE` in total; the passing
candidate with the smallest worst peak ratio is kept. A join that no candidate
fixes is *rejected*: :func:`reject_unflyable` names the observation to drop (the
later one of the pair) so that :func:`jaxspline.plan` keeps the plan flyable.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from jaxspline.kernels.batch import map_chunked
from jaxspline.kernels.join_check import maneuver_check
from jaxspline.kernels.joins import Maneuver, maneuver_eval, maneuver_plan
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.attitude_laws import (
    NADIR_LAW,
    law_modes,
    law_states,
    state_angles,
)

__all__ = [
    "DIRECT_MAX_S",
    "JOIN_SAMPLES",
    "RETURN_S",
    "Joins",
    "join_limits",
    "join_summary",
    "plan_joins",
    "reject_unflyable",
]

JOIN_SAMPLES = 129  # samples per join of the limit check (as maneuver_check's default)
DIRECT_MAX_S = 600.0  # [s] gaps up to this get one join (nadir turns ~36 deg inertially)
RETURN_S = 300.0  # [s] duration of a join to / from nadir around a longer gap
RETIME_FRACTIONS = (0.0, 0.125, 0.25, 0.375)  # law extension on each side, share of the join
RETIME_MAX_SHARE = 0.5  # at most this share of a join is given to the extensions
# sampled peaks can miss an interior maximum by O((T/n)^2) relatively (2e-4 seen on the
# test plan against 4001-sample brute force): a join passes with peak <= (1 - this) limit
SAMPLING_MARGIN = 2e-3
NO_LIMIT = float(np.finfo(np.float64).max)  # a norm that is not limited (finite for validation)
NADIR = -1  # observation index of the nadir law
_JOIN_CHUNK = 1 << 11  # joins per compiled plan / check call (fixed shape: one compile)
_CHECK_CHUNK_MIN = 1 << 5  # the check's smallest call: 32, 128, 512 or 2048 joins (_check_chunk)
_SAMPLE_CHUNK = 1 << 15  # join samples per compiled evaluation


class Joins(NamedTuple):
    """J joins of a plan (numpy), sorted by (satellite, start).

    Attributes:
      sat: [J] satellite index.
      before, after: [J] observation index (into the arrays given to :func:`plan_joins`)
        of the law before / after the join, :data:`NADIR` for the nadir law.
      t_start, t_end: [J] the join interval [s from the epoch] after re-timing.
      hold_before, hold_after: [J] extension [s] of the law before (after) into the
        interval the timing rules gave the join (0 unless re-timed).
      q_ref, coeffs: [J, 4], [J, 3, 8] the :class:`jaxspline.kernels.joins.Maneuver` rows.
      peak_rate, peak_accel, peak_jerk: [J] sampled max |ω| [rad/s], |ε| [rad/s²],
        |ε'| [rad/s³] (norms of body rates relative to TEME).
      ratio: [J, 3] checked peak / limit for (rate, accel, jerk) (per-channel: the
        largest channel ratio; 0 where the model has no such limit).
      retimed, ok: [J] bool.
    """

    sat: np.ndarray
    before: np.ndarray
    after: np.ndarray
    t_start: np.ndarray
    t_end: np.ndarray
    hold_before: np.ndarray
    hold_after: np.ndarray
    q_ref: np.ndarray
    coeffs: np.ndarray
    peak_rate: np.ndarray
    peak_accel: np.ndarray
    peak_jerk: np.ndarray
    ratio: np.ndarray
    retimed: np.ndarray
    ok: np.ndarray

    def __len__(self) -> int:
        return int(self.sat.shape[0])


def join_limits(sat) -> tuple[AxisLimits, AxisLimits]:
    """(norm limits, per-channel limits) checked on the joins of satellite ``sat``.

    Norm limits bound |ω|, |ε|, |ε'| (:data:`NO_LIMIT` / inf where the model sets
    none); per-channel limits bound the roll, pitch, yaw rates and accelerations
    (per_channel model only; ``None`` otherwise). See the module docstring.

    Args:
      sat: Satellite.
    Returns:
      (AxisLimits of scalars [rad/s, rad/s², rad/s³], AxisLimits of float [3] or None).
    """
    lim = sat.limits
    if not sat.maneuver.rest_to_rest:
        return AxisLimits(NO_LIMIT, NO_LIMIT), AxisLimits(
            np.asarray(lim.rate, np.float64), np.asarray(lim.accel, np.float64)
        )
    rate, accel = float(lim.rate), float(lim.accel)
    return AxisLimits(rate, accel, sat.maneuver.jerk_limit(sat)), None


def _layout(sat, start, end, n_sats):
    """Join rows (sat, before, after, t_start, t_end) of the timing rules (module docstring)."""
    rows = []
    order = np.lexsort((start, sat))
    for k in range(n_sats):
        ids = order[sat[order] == k]
        prev, t_prev = NADIR, 0.0
        for i in ids:
            gap = start[i] - t_prev
            if gap <= DIRECT_MAX_S:
                rows.append((k, prev, i, t_prev, start[i]))
            else:
                if prev != NADIR:
                    rows.append((k, prev, NADIR, t_prev, t_prev + RETURN_S))
                rows.append((k, NADIR, i, start[i] - RETURN_S, start[i]))
            prev, t_prev = i, end[i]
        if prev != NADIR:
            rows.append((k, prev, NADIR, t_prev, t_prev + RETURN_S))
    if not rows:
        return (np.zeros(0, np.int64),) * 3 + (np.zeros(0),) * 2
    s, b, a, t0, t1 = (np.asarray(c) for c in zip(*rows, strict=True))
    return s.astype(np.int64), b.astype(np.int64), a.astype(np.int64), t0, t1


def _laws(idx, start, params, mode):
    """(law [n, 9], law start [n]) of observation indices (NADIR: the nadir law from t = 0).

    ``mode`` [n]: yaw mode of each row's satellite (:mod:`jaxspline.planner.attitude_laws`).
    """
    obs = idx != NADIR
    law = np.tile(NADIR_LAW, (idx.size, 1))
    law[obs, :8] = params[idx[obs]]
    law[obs, 8] = mode[obs]
    s0 = np.zeros(idx.size)
    s0[obs] = start[idx[obs]]
    return law, s0


def _plan_rows(q0, w0, e0, j0, q1, w1, e1, j1, T):
    return maneuver_plan(q0, w0, e0, q1, w1, e1, T, j0=j0, j1=j1)


def _check_chunk(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk):
    lim = AxisLimits(rate, accel, jerk)
    return maneuver_check(q0, w0, e0, q1, w1, e1, T, lim, j0=j0, j1=j1, n_samples=JOIN_SAMPLES)


def _eval_rows(q_ref, coeffs, T, t):
    return maneuver_eval(Maneuver(q_ref, coeffs, T), t)


def _check_chunk_size(n: int) -> int:
    """Joins per check call for n joins: the smallest of 2048, 512, 128, 32 that holds them.

    The sampled check is the costly kernel of a small plan's joins; its rows are
    computed independently, with the same bits at each of these sizes.
    """
    size = _JOIN_CHUNK
    while size > _CHECK_CHUNK_MIN and size // 4 >= n:
        size //= 4
    return size


def _check_rows(scene, sats, sat, law0, s0, law1, s1, ta, tb):
    """Plan and check joins [ta, tb] between laws (law0 from s0, law1 from s1); all [n] rows.

    Kernels run in chunks of fixed size (one compilation each, whatever n).
    Returns (Maneuver rows, peaks [n, 3] of |ω|, |ε|, |ε'|, ratios [n, 3], ok [n]).
    """
    n = sat.size
    st = law_states(
        scene,
        np.concatenate([sat, sat]),
        np.concatenate([law0, law1]),
        np.concatenate([s0, s1]),
        np.concatenate([ta, tb]),
    )
    ends = [x[:n] for x in st] + [x[n:] for x in st] + [tb - ta]
    man = Maneuver(*map_chunked(_plan_rows, ends, _JOIN_CHUNK))
    lims = [join_limits(s) for s in sats]
    norm = np.array([list(x[0]) for x in lims], np.float64).reshape(-1, 3)[sat]
    chk = map_chunked(_check_chunk, [*ends, *norm.T], _check_chunk_size(n))
    peaks = np.stack([np.asarray(x, np.float64) for x in chk[:3]], -1)
    ratio = np.where(np.isinf(norm), 0.0, peaks / norm)
    pc = np.flatnonzero(np.array([x[1] is not None for x in lims], bool)[sat])
    if pc.size:
        own = np.repeat(pc, JOIN_SAMPLES)
        tau = np.tile(np.linspace(0.0, 1.0, JOIN_SAMPLES), pc.size) * man.duration[own]
        q, w, e, _ = map_chunked(
            _eval_rows, [man.q_ref[own], man.coeffs[own], man.duration[own], tau], _SAMPLE_CHUNK
        )
        _, rate, acc = state_angles(scene, sat[own], q, w, e, ta[own] + tau)
        per = [x[1] or AxisLimits(np.nan, np.nan) for x in lims]
        r_lim = np.stack([np.broadcast_to(x.rate, (3,)) for x in per])[sat[own]]
        a_lim = np.stack([np.broadcast_to(x.accel, (3,)) for x in per])[sat[own]]
        for col, x in ((0, np.abs(rate) / r_lim), (1, np.abs(acc) / a_lim)):
            worst = np.zeros(n)
            np.maximum.at(worst, own, np.where(np.isfinite(x), x, np.inf).max(-1))
            ratio[pc, col] = worst[pc]
    ok = np.all(ratio <= 1.0 - SAMPLING_MARGIN, -1) & np.isfinite(peaks).all(-1)
    return man, peaks, ratio, ok


def plan_joins(scene, sats, sat, start, end, params) -> Joins:
    """Joins of a plan's observations, checked and re-timed (module docstring).

    Args:
      scene: multi-satellite :class:`jaxspline.geometry.pointing.Scene`.
      sats: the scenario's satellites (sequence of :class:`jaxspline.readers.mission.Satellite`).
      sat: [K] satellite index of every observation.
      start: [K] imaging start [s].
      end: [K] imaging end [s].
      params: [K, 8] aim laws (:func:`jaxspline.geometry.pointing.aim_params`) started at ``start``.
    Returns:
      :class:`Joins`.
    """
    sat = np.asarray(sat, np.int64)
    start, end = np.asarray(start, np.float64), np.asarray(end, np.float64)
    params = np.asarray(params, np.float64).reshape(-1, 8)
    if not (sat.shape == start.shape == end.shape == params.shape[:1]):
        raise ValueError(
            f"sat, start, end, params must describe the same K observations, got shapes "
            f"{sat.shape}, {start.shape}, {end.shape}, {params.shape}"
        )
    if sat.size and (sat.min() < 0 or sat.max() >= len(sats)):
        raise ValueError(f"sat must index the {len(sats)} satellites, got {sat.tolist()}")
    js, jb, ja, ta, tb = _layout(sat, start, end, len(sats))
    n = js.size
    if n == 0:
        z = np.zeros(0)
        return Joins(js, jb, ja, z, z, z, z, np.zeros((0, 4)), np.zeros((0, 3, 8)), z, z, z,
                     np.zeros((0, 3)), np.zeros(0, bool), np.zeros(0, bool))  # fmt: skip
    mode = law_modes(sats)
    law0, s0 = _laws(jb, start, params, mode[js])
    law1, s1 = _laws(ja, start, params, mode[js])
    man, peaks, ratio, ok = _check_rows(scene, sats, js, law0, s0, law1, s1, ta, tb)
    q_ref, coeffs = np.array(man.q_ref), np.array(man.coeffs)
    hb, ha = np.zeros(n), np.zeros(n)
    t0, t1 = ta.copy(), tb.copy()
    retimed = np.zeros(n, bool)
    bad = np.flatnonzero(~ok)
    if bad.size:
        fr = [
            (a, b)
            for a, b in itertools.product(RETIME_FRACTIONS, repeat=2)
            if 0 < a + b <= RETIME_MAX_SHARE
        ]
        rows = np.repeat(bad, len(fr))
        fa = np.tile([f[0] for f in fr], bad.size)
        fb = np.tile([f[1] for f in fr], bad.size)
        T = tb[rows] - ta[rows]
        ca, cb = ta[rows] + fa * T, tb[rows] - fb * T
        m2, p2, r2, ok2 = _check_rows(
            scene, sats, js[rows], law0[rows], s0[rows], law1[rows], s1[rows], ca, cb
        )
        worst = np.where(ok2, r2.max(-1), np.inf).reshape(bad.size, len(fr))
        best = np.argmin(worst, -1)
        for i, j in enumerate(bad):
            c = i * len(fr) + best[i]
            if not ok2[c]:
                continue
            retimed[j], ok[j] = True, True
            t0[j], t1[j] = ca[c], cb[c]
            hb[j], ha[j] = ca[c] - ta[j], tb[j] - cb[c]
            q_ref[j], coeffs[j] = np.asarray(m2.q_ref)[c], np.asarray(m2.coeffs)[c]
            peaks[j], ratio[j] = p2[c], r2[c]
    return Joins(js, jb, ja, t0, t1, hb, ha, q_ref, coeffs, peaks[:, 0], peaks[:, 1],
                 peaks[:, 2], ratio, retimed, ok)  # fmt: skip


def join_summary(joins: Joins) -> dict:
    """Counts and worst ratios of checked joins (JSON-ready).

    Args:
      joins: Joins of a plan.
    Returns:
      dict of plain Python numbers.
    """
    worst = joins.ratio.max(0) if len(joins) else np.zeros(3)
    return {
        "joins": len(joins),
        "retimed": int(joins.retimed.sum()),
        "violating": int((~joins.ok).sum()),
        "max_rate_ratio": float(worst[0]),
        "max_accel_ratio": float(worst[1]),
        "max_jerk_ratio": float(worst[2]),
    }


def reject_unflyable(sc, scene, opp, chosen) -> tuple[list, dict]:
    """Option ids of ``chosen`` to drop so that every join of the plan passes its check.

    Joins are planned and re-timed (:func:`plan_joins`); for each join that still
    violates a limit the later observation of the pair is dropped (the earlier one if
    the join leads back to nadir), and the joins are planned again, until none
    violates. The caller re-checks the remaining plan (a per-channel transfer over the
    longer gap must be re-verified).

    Args:
      sc: Scenario.
      scene: Scene of the scenario's satellites.
      opp: Opportunities.
      chosen: int [K], option ids of the plan.
    Returns:
      (dropped option ids, join_summary of the kept plan).
    """
    o = opp.options
    ids = np.asarray(sorted(chosen), np.int64)
    dropped: list[int] = []
    while True:  # every round drops at least one observation
        joins = plan_joins(
            scene, sc.satellites, o.sat[ids], o.t_start[ids], o.t_end[ids], opp.params[ids]
        )
        bad = ~joins.ok
        if not bad.any():
            return dropped, join_summary(joins)
        drop = np.unique(np.where(joins.after[bad] != NADIR, joins.after[bad], joins.before[bad]))
        dropped += ids[drop].tolist()
        ids = np.delete(ids, drop)
