"""Rest-to-rest slews: the shared part of the eigen-axis and flexible models.

A transition slews from the line of sight at the end of option i to the one at the start
of option j, at rest at both ends, then settles: required time = profile time of the
angle + ``sat.settle`` + the planner's gap margin. The screen and the search read it
from the satellite's :class:`~jaxspline.screen.slew_table.SlewTable` (an upper bound of
the exact time, one lookup per pair); the plan check uses the exact
:meth:`RestToRest.slew_time`. A subclass gives :meth:`RestToRest.profile_time` (and
:meth:`RestToRest.time_drops` where the profile time jumps down).
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.base.models import FAR_SAFETY
from jaxspline.screen.slew_table import SlewTable, slew_table, table_time

__all__ = ["RestToRest"]

_FIXED_POINT_ITERS = 200  # iterations of the far-gap fixed point


class RestToRest:
    """Base class of rest-to-rest models (see the module docstring)."""

    name = "rest_to_rest"
    rest_to_rest = True
    limit_shape = ()
    extra_fields = ()
    los_frame = "inertial"
    tracks_points = True
    first_from_nadir = True
    attitude_law = "zero_yaw"

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"

    def check(self, sat) -> None:
        """Nothing beyond the common fields (subclasses add theirs)."""

    def profile_time(self, sat, theta) -> np.ndarray:
        """Slew time [s] through angles theta [rad] (numpy), without settling or margin."""
        raise NotImplementedError

    def time_drops(self, sat, gap_margin: float, rel: float, abs_: float) -> list:
        """Where :meth:`slew_time` jumps down (see :func:`jaxspline.screen.slew_table.slew_table`).

        Returns:
          list of ``(lo, hi, t)``: a drop lies in ``[lo, hi]`` [rad] and every angle there
          needs at most t [s]; empty for a profile that is continuous and non-decreasing.
        """
        return []

    def slew_time(self, sat, theta, gap_margin: float = 0.0) -> np.ndarray:
        """Exact required time [s] for angles theta [rad]: profile + settle + gap margin."""
        theta = np.abs(np.asarray(theta, np.float64))
        t = np.asarray(self.profile_time(sat, theta), np.float64)
        return t + sat.settle + gap_margin

    def screen_model(self, sat, gap_margin: float) -> SlewTable:
        """The satellite's slew table (an upper bound of :meth:`slew_time`)."""
        return slew_table(sat, gap_margin)

    def need(self, t_min, T):
        """Required time of feasible screened pairs: the table time."""
        return t_min

    def pair_requirements(self, sat, options, src, dst, screen_model):
        """Table time [P] [s] of the slews src -> dst of ``sat``; inf over the gap.

        Args:
          sat: the satellite (all pairs belong to it).
          options: RouteOptions with numpy ``end_los`` / ``start_los``.
          src: int [P] source option indices.
          dst: int [P] destination option indices.
          screen_model: the satellite's SlewTable.
        """
        src = np.asarray(src, np.int64)
        dst = np.asarray(dst, np.int64)
        if src.size == 0:
            return np.zeros(0)
        T = np.asarray(options.t_start)[dst] - np.asarray(options.t_end)[src]
        return table_time(screen_model, options.end_los, src, options.start_los, dst, T)

    def first_requirements(self, sat, options, idx, screen_model):
        """Required time before each option as the first observation: a slew from nadir.

        Args:
          sat: the satellite.
          options: RouteOptions (``start_nadir``, ``start_los``).
          idx: int [K], option indices.
          screen_model: the satellite's SlewTable.
        Returns:
          numpy float [K], required time [s]; inf where the slew does not fit before the
          option's start.
        """
        idx = np.asarray(idx, np.int64)
        if idx.size == 0:
            return np.zeros(0)
        t0 = np.asarray(options.t_start)[idx]
        return table_time(screen_model, options.start_nadir, idx, options.start_los, idx, t0)

    def far_gap(self, sat, options, idx, nadir_rate: float, screen_model) -> float:
        """A gap beyond which every slew between options of ``sat`` fits.

        Two lines of sight inside the off-nadir cone at instants g apart are at most
        ``2 eta + omega g`` apart (omega = ``nadir_rate``, the inertial turn rate of
        nadir), so the fixed point of ``g = T(min(pi, 2 eta + omega g))`` bounds every
        required gap, with T(theta) the largest table time over ``[0, theta]`` (the
        running maximum: the table itself is not monotone).

        Args:
          sat: the satellite.
          options: unused (the bound holds for any pair of the cone).
          idx: unused.
          nadir_rate: float, inertial turn rate of nadir [rad/s].
          screen_model: the satellite's SlewTable.
        Returns:
          float, the gap [s].
        """
        g = 0.0
        eta = float(sat.off_nadir_max)
        up_to = SlewTable(np.maximum.accumulate(screen_model.time), screen_model.size)
        for _ in range(_FIXED_POINT_ITERS):
            g_new = up_to.scalar(min(math.pi, 2.0 * eta + nadir_rate * g))
            if abs(g_new - g) < 1e-12:
                break
            g = g_new
        return g * FAR_SAFETY + 1e-9

    def jerk_limit(self, sat) -> float:
        """No jerk bound unless the subclass sets one."""
        return float("inf")
