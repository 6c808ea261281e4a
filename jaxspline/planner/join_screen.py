"""Screening transitions with the degree-7 join the plan flies (SPEC section 3).

A satellite's maneuver model (:mod:`jaxspline.screen.models`) says whether a
time-optimal transfer fits the gap; the attitude history of a plan
(:mod:`jaxspline.planner.flown_joins`) flies instead the degree-7 join between the scan
laws, which needs 1.5-1.9 times the peak rate or acceleration of those profiles.
Screening with the join itself keeps the search away from transitions the flown
profile cannot make.

The screen works in the per-channel angles of the orbital frame (roll, pitch, yaw of
:mod:`jaxspline.planner.attitude_laws`; yaw zeroed for the rest-to-rest models, all
zero for nadir): every option's angle, rate, acceleration and jerk at its start and
end (:func:`channel_states`, the jerk by a central difference of the exact
acceleration over +-:data:`jaxspline.planner.attitude_laws.JERK_STEP_S`) give the
channel-wise degree-7 join of every pair
(:func:`jaxspline.kernels.channel_join.channel_join_peaks`), and its peaks go
against the join limits of :func:`jaxspline.planner.flown_joins.join_limits` with the
same sampling margin: per channel for ``per_channel``, as norms over the
channels for ``eigen_axis`` and ``flexible`` (whose jerk bound is accel / tau).

The spatial join (an MRP polynomial) and the channel-wise one agree at both ends
to every derivative and differ inside by the nonlinearity of the angles: on the
default scenario the channel-wise acceleration peaks are within 7 % of the flown
ones, rate peaks agree to a few per cent for the rest-to-rest models and within
-12 / +60 % for per-channel yaw. The screen is therefore a filter, not the check:
the flown joins of the final plan are planned and checked exactly
(:func:`jaxspline.planner.flown_joins.reject_unflyable`), which drops the few
transitions the screen let through.

Range: a join needs more time than the satellite's own profile, so the engine
screens pairs up to :func:`join_far_gap` instead of the model's far gap: the time
of the rest-to-rest septic join (zero rate, acceleration and jerk at both ends)
over the largest turn, times :data:`JOIN_FAR_SAFETY` for the motion of the scan
laws at the ends (on the default scenario pairs beyond 1.5 septic times fail the
screen in 0-0.9 % of random samples, between 1 and 1.5 in 2-7 %). Gaps over
:data:`jaxspline.planner.flown_joins.DIRECT_MAX_S` pass: the plan returns to nadir in
between over :data:`jaxspline.planner.flown_joins.RETURN_S`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import numpy as np

from jaxspline.kernels.batch import map_chunked
from jaxspline.kernels.channel_join import DEFAULT_JOIN_SAMPLES, channel_join_peaks
from jaxspline.planner.attitude_laws import JERK_STEP_S, LAW_POINTING, law_modes
from jaxspline.planner.flown_joins import DIRECT_MAX_S, RETURN_S, SAMPLING_MARGIN, join_limits
from jaxspline.planner.opportunities import evaluate, state_batched
from jaxspline.search.problem import septic_time

__all__ = [
    "JOIN_FAR_SAFETY",
    "ChannelStates",
    "channel_states",
    "join_far_gap",
    "screen_first_joins",
    "screen_joins",
]

# max over [0, 1] of |p'|, |p''|, |p'''| of the septic 35τ⁴ - 84τ⁵ + 70τ⁶ - 20τ⁷ (0 -> 1)
JOIN_FAR_SAFETY = 1.5  # screened range: this times the septic time of the largest turn
_TURN_ITERS = 50  # fixed-point iterations of the rest-to-rest turn bound

_CHUNK = 1 << 14  # transitions per compiled evaluation (padded)
_peaks_batched = jax.jit(
    jax.vmap(lambda *a: channel_join_peaks(*a, n_samples=DEFAULT_JOIN_SAMPLES))
)


class ChannelStates(NamedTuple):
    """Per option the per-channel state of its flown law at its start and its end.

    Attributes:
      start, end: 4-tuples (angle [rad], rate [rad/s], acceleration [rad/s²],
        jerk [rad/s³]) of float [N, 3] arrays (roll, pitch, yaw).
    """

    start: tuple
    end: tuple


def channel_states(scene, sats, opp) -> ChannelStates:
    """Per-channel states of every option's flown law at its start and end (numpy).

    Args:
      scene: Scene of the scenario's satellites.
      sats: the scenario's satellites.
      opp: :class:`jaxspline.planner.opportunities.Opportunities`.
    Returns:
      :class:`ChannelStates`.
    """
    o = opp.options
    sat = np.asarray(o.sat, np.int64)
    pointing = (law_modes(sats) == LAW_POINTING)[sat]
    keep = np.stack([np.ones_like(pointing)] * 2 + [pointing], -1)
    t0 = np.asarray(o.t_start, np.float64)

    def at(t):
        state = evaluate(state_batched, scene, sat, opp.params, t0, t)
        return [np.where(keep, x, 0.0) for x in state]

    def full(t):
        ang, rate, acc = at(t)
        plus, minus = at(t + JERK_STEP_S)[2], at(t - JERK_STEP_S)[2]
        return ang, rate, acc, (plus - minus) / (2.0 * JERK_STEP_S)

    if sat.size == 0:
        z = (np.zeros((0, 3)),) * 4
        return ChannelStates(z, z)
    return ChannelStates(full(t0), full(np.asarray(o.t_end, np.float64)))


def join_far_gap(sat, far: float, nadir_rate: float) -> float:
    """The gap up to which the join screen runs for satellite ``sat`` (module docstring).

    Rest-to-rest models: two lines of sight g apart differ by at most
    ``2 eta + omega g`` (as the rest-to-rest models' ``far_gap``); the fixed point
    of g = septic time of that turn, times :data:`JOIN_FAR_SAFETY`. ``per_channel``:
    the model's far gap, whose braking terms already exceed that for the roll and
    pitch spans (on the default scenario 0.6-0.9 % of random pairs up to 1.5 times
    beyond it fail the screen, none further out); yaw turns by the short way in the
    flown join, so its unwrapped span would over-state the turn.

    Args:
      sat: Satellite.
      far: its model's far gap [s] (``sat.maneuver.far_gap``).
      nadir_rate: inertial turn rate of nadir [rad/s].
    Returns:
      float [s].
    """
    norm, per = join_limits(sat)
    if per is not None:
        return float(far)
    septic = 0.0
    for _ in range(_TURN_ITERS):
        theta = min(math.pi, 2.0 * float(sat.off_nadir_max) + nadir_rate * septic)
        septic = septic_time(theta, norm.rate, norm.accel, norm.jerk)
    return max(float(far), JOIN_FAR_SAFETY * septic)


def _passes(sats, sat, begin, finish, T):
    """bool [P]: the channel-wise join from ``begin`` to ``finish`` (4-tuples [P, 3]) in T."""
    if sat.size == 0:
        return np.zeros(0, bool)
    args = [*begin, *finish, np.asarray(T, np.float64)]
    rate, accel, jerk, rate_n, accel_n, jerk_n = map_chunked(_peaks_batched, args, _CHUNK)
    ok = np.zeros(sat.size, bool)
    keep = 1.0 - SAMPLING_MARGIN
    for k, s in enumerate(sats):
        m = sat == k
        if not m.any():
            continue
        norm, per = join_limits(s)
        if per is not None:
            r_lim = np.broadcast_to(np.asarray(per.rate, np.float64), (3,))
            a_lim = np.broadcast_to(np.asarray(per.accel, np.float64), (3,))
            ok[m] = np.all((rate[m] <= keep * r_lim) & (accel[m] <= keep * a_lim), -1)
        else:
            ok[m] = (
                (rate_n[m] <= keep * norm.rate)
                & (accel_n[m] <= keep * norm.accel)
                & (jerk_n[m] <= keep * norm.jerk)
            )
    return ok


def screen_joins(sats, opp, states: ChannelStates, src, dst) -> np.ndarray:
    """Which transitions src -> dst (same satellite) the channel-wise join screen passes.

    Args:
      sats: the scenario's satellites.
      opp: Opportunities (the options src and dst index).
      states: :func:`channel_states` of ``opp``.
      src, dst: int [P], option indices.
    Returns:
      bool [P]; gaps over DIRECT_MAX_S pass (module docstring).
    """
    o = opp.options
    src, dst = np.asarray(src, np.int64), np.asarray(dst, np.int64)
    gap = np.asarray(o.t_start)[dst] - np.asarray(o.t_end)[src]
    out = np.ones(src.size, bool)
    near = np.flatnonzero(gap <= DIRECT_MAX_S)
    i, j = src[near], dst[near]
    begin = tuple(x[i] for x in states.end)
    finish = tuple(x[j] for x in states.start)
    out[near] = _passes(sats, np.asarray(o.sat)[j], begin, finish, gap[near])
    return out


def screen_first_joins(sats, opp, states: ChannelStates, idx) -> np.ndarray:
    """Which options the join from nadir can reach as their satellite's first observation.

    The first join leaves nadir (zero angles, at rest in the orbital frame) at t = 0,
    or :data:`RETURN_S` before a start later than :data:`DIRECT_MAX_S`.

    Args:
      sats: the scenario's satellites.
      opp: Opportunities.
      states: :func:`channel_states` of ``opp``.
      idx: int [K], option indices.
    Returns:
      bool [K].
    """
    o = opp.options
    idx = np.asarray(idx, np.int64)
    t = np.asarray(o.t_start)[idx]
    T = np.where(t > DIRECT_MAX_S, RETURN_S, t)
    nadir = (np.zeros((idx.size, 3)),) * 4
    finish = tuple(x[idx] for x in states.start)
    return _passes(sats, np.asarray(o.sat)[idx], nadir, finish, T)
