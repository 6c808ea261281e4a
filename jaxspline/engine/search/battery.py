"""Conservative per-satellite battery profiles on the geometry grid (aeossp RULES.md rule 8).

The reference semantics integrate, from the initial level, load = idle + imaging
(inside an observation) + slew (inside the maneuver window ``[start - t_req, start)``)
and charge (while sunlit, cylindrical shadow), clamping at capacity; the level must
never drop below zero.

Here the horizon is cut into the uniform grid of the ephemeris (step ``dt``); in each
step ``[k dt, (k+1) dt]``:

* load = idle + imaging if the step meets an observation + slew if it meets a
  maneuver window (intervals widened outward to whole steps);
* charge only if the satellite is sunlit at every grid instant from ``k - guard`` to
  ``k + 1 + guard`` (a shadow-entry timing error of up to ``guard`` steps never
  credits charge the reference would not give);
* ``b_{k+1} = min(capacity, b_k + (charge - load) dt)``.

Every step's load is >= and its charge <= the reference's on each sub-interval, so
the level is a lower bound of the reference's up to what the capacity clamp can
shift inside one step; ``margin_wh`` covers that. With ``S_k`` the unclamped
cumulative level, the clamped one is ``S_k - max(0, max_{j<=k} (S_j - capacity))``,
so a profile is a few vectorized numpy passes.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BatteryModel"]

_EPS_STEPS = 1e-9  # tolerance when converting times to step indices


class BatteryModel:
    """Battery profiles of the satellites that have a power model.

    Args:
      sunlit: bool [S, n+1], sunlit at grid instants ``k dt``, k = 0..n.
      powers: list of S :class:`jaxspline.engine.mission.Power` or None (no battery rule).
      dt: grid step [s].
      margin_wh: the level must stay >= this [Wh].
      guard: shadow guard [steps].
    """

    def __init__(self, sunlit, powers, dt: float, margin_wh: float = 0.0, guard: int = 0):
        self.powers = list(powers)
        self.dt = float(dt)
        self.margin_wh = float(margin_wh)
        n = sunlit.shape[1] - 1
        self.n = n
        lit = np.asarray(sunlit, bool)
        ok = np.ones((lit.shape[0], n), bool)
        for off in range(-guard, guard + 2):
            ok &= lit[:, np.clip(np.arange(n) + off, 0, n)]
        self.charging = ok  # [S, n]: the step counts charge
        h = self.dt / 3600.0
        self.base = np.zeros((len(self.powers), n))
        for k, p in enumerate(self.powers):
            if p is not None:
                self.base[k] = (ok[k] * p.charge_w - p.idle_w) * h

    def has(self, sat: int) -> bool:
        """True if satellite ``sat`` has a power model.

        Args:
          sat: int, satellite index.
        Returns:
          bool.
        """
        return self.powers[sat] is not None

    def step_index(self, t: float) -> int:
        """Index of the step containing time t (floor).

        Args:
          t: float, seconds from the epoch.
        Returns:
          int.
        """
        return int(np.floor(t / self.dt + _EPS_STEPS))

    def loads(self, sat: int, starts, ends, maneuver):
        """Extra load energy per step [Wh] (imaging + slew) of these observations of ``sat``.

        Args:
          starts, ends: observation intervals [s].
          maneuver: maneuver durations [s] ending at each start.
        """
        n = self.n
        d = np.zeros(n + 1)
        starts = np.asarray(starts, np.float64)
        if starts.size:
            p = self.powers[sat]
            h = self.dt / 3600.0
            s0 = np.clip(np.floor(starts / self.dt + _EPS_STEPS), 0, n).astype(np.int64)
            e0 = np.clip(np.ceil(np.asarray(ends) / self.dt - _EPS_STEPS), 0, n).astype(np.int64)
            m0 = np.floor((starts - np.asarray(maneuver, np.float64)) / self.dt + _EPS_STEPS)
            m0 = np.clip(m0, 0, n).astype(np.int64)
            s1 = np.clip(np.ceil(starts / self.dt - _EPS_STEPS), 0, n).astype(np.int64)
            np.add.at(d, s0, p.imaging_w * h)
            np.add.at(d, e0, -p.imaging_w * h)
            np.add.at(d, m0, p.slew_w * h)
            np.add.at(d, s1, -p.slew_w * h)
        return np.cumsum(d)[:n]

    def profile(self, sat: int, starts, ends, maneuver):
        """Battery level at the grid instants 0..n for these observations.

        Args:
          sat: int, satellite index.
          starts: float [K], observation starts [s].
          ends: float [K], observation ends [s].
          maneuver: float [K], maneuver time before each observation [s].
        Returns:
          float [n + 1], level [Wh].
        """
        p = self.powers[sat]
        net = self.base[sat] - self.loads(sat, starts, ends, maneuver)
        s = p.initial_wh + np.concatenate([[0.0], np.cumsum(net)])
        return s - np.maximum.accumulate(np.maximum(s - p.capacity_wh, 0.0))

    def extra_energy(self, sat: int, imaging_s: float, slew_s: float) -> float:
        """Upper bound of the load added by imaging and maneuvers.

        Each of at most two windows is widened to whole steps.

        Args:
          sat: int, satellite index.
          imaging_s: imaging time [s].
          slew_s: maneuver time [s].
        Returns:
          float, energy [Wh].
        """
        p = self.powers[sat]
        return (
            p.imaging_w * (imaging_s + 2.0 * self.dt) + p.slew_w * (slew_s + 4.0 * self.dt)
        ) / 3600.0
