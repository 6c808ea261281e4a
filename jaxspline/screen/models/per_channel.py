"""The ``per_channel`` model: every channel meets the next observation's exact state.

Each channel (roll, pitch, yaw) goes from the end state of option i to the start state
of option j in exactly ``T = t_start[j] - t_end[i]`` under its rate and acceleration
bound: the reachable sets of SPEC section 1 (:mod:`jaxspline.kernels.reach`, screened by
:func:`jaxspline.screen.pairs.screen_pairs`). The required time is the largest
per-channel shortest transfer time; the exact-T test decides feasibility (durations
above ``t_min`` can still be blocked), so it is inf when the test fails. Between
observations the observation's own pointing law carries on.
"""

from __future__ import annotations

import numpy as np

from jaxspline.base.models import FAR_SAFETY
from jaxspline.kernels.batch import pad_rows, round_up
from jaxspline.kernels.limits import AxisLimits
from jaxspline.screen.pairs import screen_pairs

__all__ = ["PerChannel"]

_PAD = 1 << 12  # batch sizes are padded to multiples of this (few compiled shapes)


class PerChannel:
    """Exact-T per-channel transfers (see the module docstring)."""

    name = "per_channel"
    rest_to_rest = False
    limit_shape = (3,)
    extra_fields = ()
    los_frame = "inertial"
    tracks_points = True
    first_from_nadir = True
    attitude_law = "pointing"

    def __repr__(self) -> str:
        return "PerChannel()"

    def check(self, sat) -> None:
        """Nothing beyond the common fields."""

    def screen_model(self, sat, gap_margin: float) -> AxisLimits:
        """The satellite's channel limits (the screen's per-channel kernel; no margin)."""
        return sat.limits

    def need(self, t_min, T):
        """Required time of feasible screened pairs: the shortest transfer, at most T."""
        return np.minimum(t_min, T)

    def pair_requirements(self, sat, options, src, dst, screen_model=None):
        """Required time [P] [s] of pairs src -> dst of ``sat`` (inf: infeasible).

        Args:
          sat: the satellite (all pairs belong to it).
          options: RouteOptions with numpy fields.
          src: int [P] source option indices.
          dst: int [P] destination option indices.
          screen_model: unused (the satellite's limits are screened).
        """
        src = np.asarray(src, np.int64)
        dst = np.asarray(dst, np.int64)
        if src.size == 0:
            return np.zeros(0)
        T = np.asarray(options.t_start)[dst] - np.asarray(options.t_end)[src]
        tr = screen_pairs(options, sat.limits, src, dst)
        return np.where(tr.feasible & (T > 0), np.minimum(tr.t_min, T), np.inf)

    def first_requirements(self, sat, options, idx, screen_model=None):
        """Required time before each option as the first observation.

        The satellite starts at t = 0 at rest with zero angles and must reach the
        option's start state in exactly ``t_start``.

        Args:
          sat: the satellite.
          options: RouteOptions.
          idx: int [K], option indices.
          screen_model: unused.
        Returns:
          numpy float [K], required time [s]; inf where the option cannot come first.
        """
        from jaxspline.kernels.reach import is_reachable
        from jaxspline.kernels.reach_durations import min_transfer_time

        idx = np.asarray(idx, np.int64)
        if idx.size == 0:
            return np.zeros(0)
        t0 = np.asarray(options.t_start)[idx]
        n = idx.size
        size = round_up(n, _PAD)
        a2 = pad_rows(np.asarray(options.start_angle)[idx], size)
        b2 = pad_rows(np.asarray(options.start_rate)[idx], size)
        zero = np.zeros_like(a2)
        T = np.broadcast_to(pad_rows(t0, size)[:, None], a2.shape)
        ok = np.asarray(is_reachable(zero, zero, a2, b2, T, sat.limits)).all(-1)[:n] & (t0 > 0)
        tmin = np.asarray(min_transfer_time(zero, zero, a2, b2, sat.limits)).max(-1)[:n]
        return np.where(ok, np.minimum(tmin, t0), np.inf)

    def far_gap(self, sat, options, idx, nadir_rate: float, screen_model=None) -> float:
        """A gap beyond which every transition between options idx of ``sat`` is feasible.

        With every channel's angles (incl. the initial 0) inside a range R_c and rates
        bounded by b_c, a transfer can brake to rest (b/d), cross R_c at rate b_c
        (R_c/b_c + b_c/d_c), accelerate to the target rate (b/d) and wait at rest for
        any remainder, so it takes at most ``(R_c + 4 b_c^2/d_c) / b_c``; exact-T
        feasibility also needs T above the blocked interval, whose upper end is at most
        ``4 b_c / d_c`` (SPEC section 1).

        Args:
          sat: the satellite.
          options: RouteOptions.
          idx: int [K], option indices of ``sat``.
          nadir_rate: unused (the bound holds for any geometry).
          screen_model: unused.
        Returns:
          float, the gap [s].
        """
        b = np.asarray(sat.limits.rate, np.float64)
        d = np.asarray(sat.limits.accel, np.float64)
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
        return float(need.max()) * FAR_SAFETY

    def jerk_limit(self, sat) -> float:
        """No eigen-axis jerk bound (the channels carry the limits)."""
        return float("inf")
