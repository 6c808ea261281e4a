"""Maneuver models as transition kernels: what a satellite needs between two observations.

Every model answers, for a batch of option pairs (i -> j, same satellite, gap
``T = t_start[j] - t_end[i]``): is the transfer feasible in exactly T, and what time
``t_req`` does it need (the maneuver duration reported in the plan and loaded on
the battery)? A pair is feasible iff ``t_req <= T`` (``t_req = inf`` marks an
infeasible pair). The models (``Satellite.model``):

* ``per_channel`` - each channel (roll, pitch, yaw) goes from the end state of i to
  the start state of j in exactly T under its rate and acceleration bound: the
  reachable sets of SPEC section 1 (:mod:`jaxspline.kernels.reach`, screened by
  :func:`jaxspline.screen.pairs.screen_pairs`). ``t_req`` is the largest per-channel shortest
  transfer time; the exact-T test decides feasibility (durations above ``t_min`` can
  still be blocked), so ``t_req = inf`` when it fails.
* ``eigen_axis`` - rest-to-rest bang-coast-bang slew through the angle between the
  two lines of sight plus settling plus the gap margin
  (:func:`jaxspline.kernels.slew.bang_coast_bang_time`).
* ``flexible`` - rest-to-rest slew with the profile of SPEC section 2 whose ramp
  tau suppresses the structural mode to its tolerance
  (:func:`jaxspline.kernels.flex.tau_for_tolerance`,
  :func:`jaxspline.kernels.slew.slew_profile_time`),
  plus settling plus the gap margin.

Rest-to-rest models are evaluated through a per-satellite *slew table*: on the angle
grid ``theta_k = pi (k / N)^2`` (fine near 0, where the time grows like sqrt(theta)) an
angle theta is read at the next grid angle above it (one index, one load). Entry k is
an UPPER BOUND of the exact time (:func:`slew_time`) over the whole cell
``(theta_{k-1}, theta_k]`` that reads it, so the planner never needs the plan's final
check (which uses the kernel itself) to reject a slew the table allowed. The exact time
is not monotone: it is non-decreasing on pieces, but the flexible profile drops at the
A -> C switch ``7/6 omega^2/eps`` (from ``sqrt(28/3) b`` to ``3 b``, ``b = omega/eps``,
SPEC section 2), so the entry is the larger of the time at the cell's upper end and the
left limits of the drops inside the cell (:func:`_time_drops`), evaluated a little
beyond both (``_ANGLE_SLACK``: lookup and angle rounding) plus ``_TIME_PAD``. The excess
is the rise of the time over one cell (below 3e-3 s for the aeossp limits), except in
the single cell holding a drop, which keeps the whole drop (0.055 b). The table is not
monotone; :func:`far_gap` uses its running maximum.

Far gaps: :func:`far_gap` gives per satellite a gap beyond which every pair is
feasible, so the engine only screens pairs closer than that.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from jaxspline.geometry.frames import angle_between
from jaxspline.kernels._batch import pad_rows, round_up
from jaxspline.kernels.limits import AxisLimits

__all__ = ["SlewTable", "far_gap", "first_requirements", "slew_table"]

_TABLE_SIZE = 1 << 16  # points of a slew table
_PAD = 1 << 12  # batch sizes are padded to multiples of this (few compiled shapes)
_FAR_SAFETY = 1.0 + 1e-9  # relative safety of the per-channel far gap
_FIXED_POINT_ITERS = 200  # iterations of the rest-to-rest far-gap fixed point
#: A slew-table entry bounds the time up to ``theta (1 + rel) + abs`` [rad] above its cell:
#: covers the lookup's index guard (angles up to ``theta_k (1 + 2e-12 / k)`` read entry
#: k) and the ~1e-16 rad differences between the angle formulas of the screen, the search
#: and the plan check (near 0 the time grows like sqrt(theta): 1e-14 rad costs ~3e-6 s).
_ANGLE_SLACK = (1e-9, 1e-14)
#: Added to every slew-table entry [s]: the kernels' own rounding (~1e-13 s).
_TIME_PAD = 1e-9
REST_TO_REST = ("eigen_axis", "flexible")


class SlewTable(NamedTuple):
    """Conservative rest-to-rest slew time of one satellite, including settle and margin.

    Attributes:
      time: [N + 1] required time [s] read by the angles of the cell
        ``(theta_{k-1}, theta_k]``, ``theta_k = pi (k/N)^2``: an upper bound of the
        exact time over the cell (module docstring); not monotone in k.
      size: N.
    """

    time: np.ndarray
    size: int

    def __call__(self, theta) -> np.ndarray:
        """Required time [s] for angles theta [rad] (numpy, never below :func:`slew_time`)."""
        return self.time[_cell(theta, self.size)]

    def scalar(self, theta: float) -> float:
        """Same as calling the table, for one Python float (the search's hot loop).

        Args:
          theta: float, slew angle [rad] (clipped to [0, pi]).
        Returns:
          float, required time [s].
        """
        k = math.ceil(self.size * math.sqrt(min(max(theta, 0.0), math.pi) / math.pi) - 1e-12)
        return float(self.time[min(k, self.size)])


def slew_time(sat, theta, gap_margin: float = 0.0):
    """Exact rest-to-rest required time [s] of satellite ``sat`` for angles theta [rad].

    slew + ``sat.settle`` + ``gap_margin``; the kernel behind :class:`SlewTable`.
    """
    from jaxspline.kernels.slew import bang_coast_bang_time, slew_profile_time

    theta = np.abs(np.asarray(theta, np.float64))
    rate, accel = float(sat.limits.rate), float(sat.limits.accel)
    if sat.model == "eigen_axis":
        t = bang_coast_bang_time(theta, rate, accel)
    elif sat.model == "flexible":
        t = slew_profile_time(theta, rate, accel, flex_tau(sat))
    else:
        raise ValueError(f"satellite {sat.name!r}: model {sat.model!r} is not rest-to-rest")
    return np.asarray(t, np.float64) + sat.settle + gap_margin


def flex_tau(sat) -> float:
    """Ramp time tau [s] of a flexible satellite's profile (its mode at its tolerance)."""
    from jaxspline.kernels.flex import tau_for_tolerance

    f = sat.flex
    tau = float(
        tau_for_tolerance(f.tolerance, f.freq, f.damping, sat.limits.rate, sat.limits.accel)
    )
    if not math.isfinite(tau):
        raise ValueError(
            f"satellite {sat.name!r}: flex mode freq={f.freq!r} rad/s is too low for "
            f"tolerance={f.tolerance!r} at these limits (no ramp time suppresses it)"
        )
    return tau


def _time_drops(sat, gap_margin: float, rel: float, abs_: float):
    """Where the exact time of ``sat`` drops, with a bound of its left limit there.

    :func:`slew_time` is non-decreasing in the angle on pieces, with a downward jump
    only where the flexible profile switches from A to C, at
    ``theta_s = 7/6 omega^2/eps`` (A: ``T_d = sqrt(8 phi/eps)``, increasing, up to
    ``sqrt(28/3) omega/eps``; C then D from ``3 omega/eps``, increasing and continuous;
    SPEC section 2, :func:`jaxspline.kernels.slew.slew_profile_kernel`). Bang-coast-bang
    (eigen_axis) is continuous and non-decreasing: no drop.

    Args:
      sat: Satellite with a rest-to-rest model.
      gap_margin: float [s], as :func:`slew_time`.
      rel, abs_: the angle window ``theta_s (1 -+ rel) -+ abs_`` [rad] the switch may
        fall in after rounding (of the kernel's test ``a <= 7/6 b^2`` and of the angle).
    Returns:
      list of ``(lo, hi, t)``: the drop lies in ``[lo, hi]`` [rad], and every angle there
      that the kernel evaluates with profile A needs at most t [s] (profile A forced at
      hi, increasing in the angle), settle and margin included.
    """
    if sat.model != "flexible":
        return []
    from jaxspline.kernels.slew import slew_profile_time

    rate, accel = float(sat.limits.rate), float(sat.limits.accel)
    theta_s = 7.0 / 6.0 * rate * rate / accel
    lo, hi = theta_s * (1.0 - rel) - abs_, min(math.pi, theta_s * (1.0 + rel) + abs_)
    t_a = float(slew_profile_time(hi, rate, accel, flex_tau(sat), kind="A"))
    return [(lo, hi, t_a + sat.settle + gap_margin)] if lo < math.pi else []


def _cell(theta, size: int):
    """Table index read by angles theta [rad] (numpy; the formula of :class:`SlewTable`)."""
    theta = np.clip(np.asarray(theta, np.float64), 0.0, math.pi)
    k = np.minimum(np.ceil(size * np.sqrt(theta / math.pi) - 1e-12), size)
    return k.astype(np.int64)


def slew_table(sat, gap_margin: float = 0.0, size: int = _TABLE_SIZE) -> SlewTable:
    """Tabulate an upper bound of :func:`slew_time` of a rest-to-rest satellite.

    ``time[k] = max(t(theta_k (1 + rel) + abs), left limits of the drops of t in the
    cell) + _TIME_PAD`` with t = :func:`slew_time`, ``(rel, abs) = _ANGLE_SLACK`` and the
    drops of :func:`_time_drops` (t is non-decreasing between them): so ``time[k] >= t``
    on the whole cell ``(theta_{k-1}, theta_k]`` that reads entry k (module docstring).

    Args:
      sat: Satellite with a rest-to-rest model.
      gap_margin: float, extra time added to every slew [s].
      size: int N, the table has N + 1 entries at theta_k = pi (k/N)^2.
    Returns:
      SlewTable (not monotone in the angle; :func:`far_gap` takes its running maximum).
    Raises:
      ValueError: naming the satellite if the time drops in a cell where no drop is
        known (the bound would not hold: the profile changed, update ``_time_drops``).
    """
    rel, abs_ = _ANGLE_SLACK
    theta = math.pi * (np.arange(size + 1) / size) ** 2
    t = slew_time(sat, np.minimum(theta * (1.0 + rel) + abs_, math.pi), gap_margin)
    known = np.zeros(size + 1, bool)
    for lo, hi, t_left in _time_drops(sat, gap_margin, rel, abs_):
        k0, k1 = _cell([lo, hi], size)
        t[k0 : k1 + 1] = np.maximum(t[k0 : k1 + 1], t_left)
        known[k0 : k1 + 2] = True  # the drop may also show at the next node
    drop = np.flatnonzero(np.diff(t) < 0.0) + 1
    if np.any(~known[drop]):
        k = int(drop[~known[drop]][0])
        raise ValueError(
            f"satellite {sat.name!r}: model {sat.model!r} slew time drops between "
            f"{theta[k - 1]!r} and {theta[k]!r} rad, where no drop is known: the table "
            "would not bound it"
        )
    return SlewTable(t + _TIME_PAD, size)


def rest_to_rest(table: SlewTable, frm, i, to, j, available):
    """Table time of the slew from direction ``frm[i]`` to ``to[j]``; inf if over ``available``."""
    t_req = table(angle_between(np.asarray(frm)[i], np.asarray(to)[j]))
    return np.where(available >= t_req, t_req, np.inf)


def first_requirements(sat, options, idx, table: SlewTable | None = None):
    """Required time before each option as the satellite's first observation.

    Rest-to-rest models slew from nadir (``start_nadir``) at the option's start; the
    per-channel model starts at t = 0 at rest with zero angles and must reach the
    option's start state in exactly ``t_start``.

    Args:
      sat: Satellite.
      options: RouteOptions.
      idx: int [K], option indices.
      table: SlewTable of ``sat`` (rest-to-rest models).
    Returns:
      numpy float [K], required time [s]; inf where the option cannot come first.
    """
    idx = np.asarray(idx, np.int64)
    t0 = np.asarray(options.t_start)[idx]
    if idx.size == 0:
        return np.zeros(0)
    if sat.model in REST_TO_REST:
        return rest_to_rest(table, options.start_nadir, idx, options.start_los, idx, t0)
    from jaxspline.kernels.reach import is_reachable
    from jaxspline.kernels.reach_durations import min_transfer_time

    n = idx.size
    size = round_up(n, _PAD)
    a2 = pad_rows(np.asarray(options.start_angle)[idx], size)
    b2 = pad_rows(np.asarray(options.start_rate)[idx], size)
    zero = np.zeros_like(a2)
    T = np.broadcast_to(pad_rows(t0, size)[:, None], a2.shape)
    ok = np.asarray(is_reachable(zero, zero, a2, b2, T, sat.limits)).all(-1)[:n] & (t0 > 0)
    tmin = np.asarray(min_transfer_time(zero, zero, a2, b2, sat.limits)).max(-1)[:n]
    return np.where(ok, np.minimum(tmin, t0), np.inf)


def far_gap(sat, options, idx, nadir_rate: float, table: SlewTable | None = None) -> float:
    """A gap beyond which every transition between options idx of ``sat`` is feasible.

    per_channel: with every channel's angles (incl. the initial 0) inside a range R_c
    and rates bounded by b_c, a transfer can brake to rest (b/d), cross R_c at rate
    b_c (R_c/b_c + b_c/d_c), accelerate to the target rate (b/d) and wait at rest
    for any remainder, so it takes at most ``(R_c + 4 b_c^2/d_c) / b_c``; exact-T
    feasibility also needs T above the blocked interval, whose upper end is at most
    ``4 b_c / d_c`` (SPEC section 1). Rest-to-rest: two lines of sight inside the
    off-nadir cone at instants g apart are at most ``2 eta + omega g`` apart (omega =
    ``nadir_rate``, the inertial turn rate of nadir), so the fixed point of
    ``g = T(min(pi, 2 eta + omega g))`` bounds every required gap, with T(theta) the
    largest table time over ``[0, theta]`` (the running maximum: the table itself is
    not monotone, see :func:`slew_table`).

    Args:
      sat: Satellite.
      options: RouteOptions.
      idx: int [K], option indices of ``sat``.
      nadir_rate: float, inertial turn rate of nadir [rad/s].
      table: SlewTable of ``sat`` (rest-to-rest models).
    Returns:
      float, the gap [s].
    """
    if sat.model in REST_TO_REST:
        g = 0.0
        eta = float(sat.off_nadir_max)
        up_to = SlewTable(np.maximum.accumulate(table.time), table.size)  # max over [0, theta]
        for _ in range(_FIXED_POINT_ITERS):
            g_new = up_to.scalar(min(math.pi, 2.0 * eta + nadir_rate * g))
            if abs(g_new - g) < 1e-12:
                break
            g = g_new
        return g * _FAR_SAFETY + 1e-9
    lim: AxisLimits = sat.limits
    b = np.asarray(lim.rate, np.float64)
    d = np.asarray(lim.accel, np.float64)
    idx = np.asarray(idx, np.int64)
    angles = np.concatenate(
        [
            np.asarray(options.start_angle)[idx],
            np.asarray(options.end_angle)[idx],
            np.zeros((1, b.size)),
        ]
    )
    span = angles.max(0) - angles.min(0)
    need = np.maximum(4.0 * b / d, (span + 4.0 * b * b / d) / b)
    return float(need.max()) * _FAR_SAFETY
