"""Per-satellite battery simulation for aeossp_standard (RULES.md rule 8), conservative.

The checker integrates, from ``initial_battery_wh``, over segments cut at every
resource-grid instant and every action / maneuver-window boundary, with load =
idle + imaging (inside an observation) + slew (inside a maneuver window
``[start - (t_slew + settle), start)``) and charge = ``sunlit_charge_power_w``
when sunlit, clamping at capacity; the level must never drop below zero.

Here the horizon is cut into the uniform fine grid of the geometry (5 s); in
each step ``[k, k+1]``:

* load = idle + imaging if the step lies inside an observation + slew if the
  step intersects a maneuver window (windows are widened to whole steps);
* charge only if the satellite is sunlit at every grid instant from
  ``k - guard`` to ``k + 1 + guard`` (a shadow-entry/exit timing error of up to
  ``guard`` steps never credits charge the checker would not give);
* ``b_{k+1} = min(capacity, b_k + (charge - load) dt)``.

Every step's load is >= and its charge <= the checker's on each of its
sub-segments, so the level here is a lower bound of the checker's up to the
energy the capacity clamp can shift inside one step (< 1 Wh); a margin
``margin_wh`` (default 10 Wh) covers that. With ``S_k`` the unclamped cumulative
level, the clamped one is ``b_k = S_k - max(0, max_{j<=k} (S_j - capacity))``
(one-sided reflection), so a profile is a few vectorized numpy passes.
"""

from __future__ import annotations

import numpy as np

__all__ = ["BatteryModel"]


class BatteryModel:
    """Conservative battery profiles on the fine grid (see module docstring).

    Args:
      sunlit: [S, n+1] bool, sunlit at each grid instant (``GridGeometry.sunlit``).
      sp: :class:`jaxspline.aeossp.candidates.SatParams`.
      step_s: grid step [s].
      margin_wh: the level must stay >= this [Wh].
      guard: shadow guard [grid steps].
    """

    def __init__(self, sunlit, sp, step_s: float, margin_wh: float = 10.0, guard: int = 1):
        self.sp = sp
        self.step_s = float(step_s)
        self.margin_wh = float(margin_wh)
        n = sunlit.shape[1] - 1
        self.n = n
        lit = sunlit.astype(bool)
        ok = np.ones((lit.shape[0], n), dtype=bool)
        for off in range(-guard, guard + 2):
            idx = np.clip(np.arange(n) + off, 0, n)
            ok &= lit[:, idx]
        self.lit_step = ok
        dt_h = self.step_s / 3600.0
        # base net energy per step [Wh]: charge - idle
        self.base = (ok * sp.charge[:, None] - sp.idle[:, None]) * dt_h

    def loads(self, sat: int, starts, ends, maneuver_s):
        """Extra load energy per step [Wh] (imaging + slew) for the given actions of ``sat``.

        Args:
          starts, ends: grid indices of the observations.
          maneuver_s: maneuver-window lengths [s] before each start (t_slew + settle + margin).
        """
        n = self.n
        d = np.zeros(n + 1)
        starts = np.asarray(starts, dtype=np.int64)
        ends = np.asarray(ends, dtype=np.int64)
        if starts.size:
            dt_h = self.step_s / 3600.0
            p_img = self.sp.imaging[sat] * dt_h
            p_slew = self.sp.slew[sat] * dt_h
            np.add.at(d, starts, p_img)
            np.add.at(d, ends, -p_img)
            m0 = np.floor(starts - np.asarray(maneuver_s, float) / self.step_s + 1e-9).astype(
                np.int64
            )
            m0 = np.clip(m0, 0, n)
            np.add.at(d, m0, p_slew)
            np.add.at(d, starts, -p_slew)
        return np.cumsum(d)[:n]

    def profile(self, sat: int, starts, ends, maneuver_s):
        """Battery level [Wh] at the grid instants 0..n (length n+1) for these actions."""
        net = self.base[sat] - self.loads(sat, starts, ends, maneuver_s)
        cap = self.sp.capacity[sat]
        s = self.sp.initial[sat] + np.concatenate([[0.0], np.cumsum(net)])
        over = np.maximum.accumulate(np.maximum(s - cap, 0.0))
        return s - over

    def consumption_wh(self, sat: int, starts, ends, maneuver_s) -> float:
        """Gross energy consumed [Wh] (idle + imaging + slew) under this model."""
        dt_h = self.step_s / 3600.0
        return float(
            self.sp.idle[sat] * self.n * dt_h + self.loads(sat, starts, ends, maneuver_s).sum()
        )

    def feasible(self, level) -> bool:
        """True if the profile never drops below the margin."""
        return bool(level.min() >= self.margin_wh)
