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
cumulative level, the clamped one is ``S_k - M_k``, ``M_k = max(0, max_{j<=k} (S_j -
capacity))`` (the energy spilled at capacity so far), so a profile is a few
vectorized numpy passes.

Incremental test of a load change (:meth:`BatteryModel.change_ok`). A change adds
``d_k`` (any sign) to the load of the steps of a window ``[a, z)`` of a profile with
levels ``b``. Before ``a`` nothing changes; inside, the clamped recursion is
re-run from ``b_a``. After ``z`` the loads are the old ones, and a deficit ``D_k =
b_k - b'_k >= 0`` evolves as ``D_{k+1} = max(0, D_k - (M_{k+1} - M_k))``: only energy
the old profile spilled at capacity absorbs it. Hence for ``k >= z``

    b'_k = b_k - max(0, D_z - (M_k - M_z)) = min(b_k, S_k - M_z - D_z),

and the new profile stays ``>= m`` after ``z`` iff ``min_{k>=z} b_k >= m`` and
``min_{k>=z} S_k - M_z - D_z >= m``: two suffix minima cached with the profile
(:class:`Levels`). The test costs one window, not the horizon.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["BatteryModel", "Levels"]

_EPS_STEPS = 1e-9  # tolerance when converting times to step indices
_LEVEL_TOL = 1e-9  # [Wh] incremental levels must clear the margin by this (rounding)


class Levels(NamedTuple):
    """Battery profile of one satellite's timeline with the data of incremental tests.

    Attributes:
      level: float [n + 1], clamped level ``b_k`` at the grid instants [Wh].
      raw: float [n + 1], unclamped cumulative level ``S_k`` [Wh] (``S_k - b_k`` is the
        energy spilled at capacity up to k).
      net: float [n], net energy of each step (charge - idle - loads) [Wh].
      head_min: float [n + 1], ``min_{j<=k} b_j`` [Wh].
      tail_min: float [n + 1], ``min_{j>=k} b_j`` [Wh].
      tail_raw: float [n + 1], ``min_{j>=k} S_j`` [Wh].
    """

    level: np.ndarray
    raw: np.ndarray
    net: np.ndarray
    head_min: np.ndarray
    tail_min: np.ndarray
    tail_raw: np.ndarray


class BatteryModel:
    """Battery profiles of the satellites that have a power model.

    Args:
      sunlit: bool [S, n+1], sunlit at grid instants ``k dt``, k = 0..n.
      powers: list of S :class:`jaxspline.readers.mission.Power` or None (no battery rule).
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
          sat: satellite index.
          starts: observation start times [s].
          ends: observation end times [s].
          maneuver: maneuver durations [s] ending at each start.
        """
        starts = np.asarray(starts, np.float64)
        s0, e0, s1 = self.step_windows(starts, ends)
        return self.step_loads(sat, s0, e0, self.slew_steps(starts, maneuver), s1)

    def slew_steps(self, starts, maneuver) -> np.ndarray:
        """First step of each maneuver window ``[start - maneuver, start)`` (:meth:`loads`).

        Args:
          starts: float [K], observation starts [s].
          maneuver: float [K], maneuver times [s] (inf: from the horizon start).
        Returns:
          int64 [K].
        """
        t = np.asarray(starts, np.float64) - np.asarray(maneuver, np.float64)
        return np.clip(np.floor(t / self.dt + _EPS_STEPS), 0, self.n).astype(np.int64)

    def step_loads(self, sat: int, s0, e0, m0, s1) -> np.ndarray:
        """:meth:`loads` from the observations' step windows.

        Args:
          sat: satellite index.
          s0: int [K], first step of each observation's imaging load.
          e0: int [K], end (exclusive) of its imaging load: the steps ``[s0, e0)``.
          m0: int [K], first step of the maneuver into it.
          s1: int [K], end (exclusive) of that maneuver's load: the steps ``[m0, s1)``.
        Returns:
          float [n], load energy per step [Wh].
        """
        k = len(s0)
        if not k:
            return np.zeros(self.n)
        p = self.powers[sat]
        h = self.dt / 3600.0
        w = np.repeat([p.imaging_w * h, -p.imaging_w * h, p.slew_w * h, -p.slew_w * h], k)
        # one sequential pass in the order of four np.add.at calls (same sums, bit for bit)
        d = np.bincount(np.concatenate((s0, e0, m0, s1)), w, minlength=self.n + 1)
        return np.cumsum(d)[: self.n]

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

    def levels(self, sat: int, starts, ends, maneuver) -> Levels:
        """:meth:`profile` with the suffix minima of :meth:`change_ok` (same arguments).

        Returns:
          Levels.
        """
        return self.levels_of(sat, self.loads(sat, starts, ends, maneuver))

    def levels_of(self, sat: int, loads) -> Levels:
        """:meth:`levels` of the load energy per step.

        Args:
          sat: int, satellite index.
          loads: float [n], :meth:`loads` [Wh].
        Returns:
          Levels.
        """
        p = self.powers[sat]
        net = self.base[sat] - loads
        raw = p.initial_wh + np.concatenate([[0.0], np.cumsum(net)])
        level = raw - np.maximum.accumulate(np.maximum(raw - p.capacity_wh, 0.0))
        return Levels(
            level,
            raw,
            net,
            np.minimum.accumulate(level),
            np.minimum.accumulate(level[::-1])[::-1],
            np.minimum.accumulate(raw[::-1])[::-1],
        )

    def step_windows(self, starts, ends):
        """Step windows of observations, as :meth:`loads` charges them.

        Args:
          starts: float [K], observation start times [s].
          ends: float [K], observation end times [s].
        Returns:
          three int64 [K] arrays ``(s0, e0, s1)`` of step indices: imaging loads the
          steps ``[s0, e0)``, the maneuver into the observation ends before step ``s1``.
        """
        n, dt = self.n, self.dt
        s = np.asarray(starts, np.float64)
        e = np.asarray(ends, np.float64)
        s0 = np.clip(np.floor(s / dt + _EPS_STEPS), 0, n).astype(np.int64)
        e0 = np.clip(np.ceil(e / dt - _EPS_STEPS), 0, n).astype(np.int64)
        s1 = np.clip(np.ceil(s / dt - _EPS_STEPS), 0, n).astype(np.int64)
        return s0, e0, s1

    def slew_step(self, start: float, maneuver: float) -> int:
        """First step of the maneuver window ``[start - maneuver, start)``, as in :meth:`loads`.

        Args:
          start: observation start [s].
          maneuver: maneuver time [s] (inf: from the horizon start).
        Returns:
          int.
        """
        t = start - maneuver
        return min(max(math.floor(t / self.dt + _EPS_STEPS), 0), self.n) if t > 0.0 else 0

    def change_ok(self, sat: int, lv: Levels, changes) -> bool | None:
        """Whether the profile ``lv`` stays >= the margin after a load change.

        Exact (module docstring), no assumption on ``lv`` itself. Two O(1) bounds come
        first: with ``E+`` the added and ``E`` the net energy, no level drops by more
        than ``E+`` (accept), and the deficit at the window end is at least ``E`` less
        the energy the old profile spilled inside the window (reject).

        Args:
          sat: int, satellite index.
          lv: Levels of the current loads.
          changes: iterable of ``(lo, hi, watts)``: ``watts`` more load on the steps
            ``[lo, hi)`` (negative: less).
        Returns:
          True / False; None when it cannot tell cheaply (the old profile dips below
          the margin after a change that raises the level): re-simulate.
        """
        m = self.margin_wh + _LEVEL_TOL
        h = self.dt / 3600.0
        segs = [(lo, hi, w * h) for lo, hi, w in changes if hi > lo and w != 0.0]
        if not segs:
            return bool(lv.tail_min[0] >= m)
        a = min(s[0] for s in segs)
        z = max(s[1] for s in segs)
        if lv.head_min[a] < m:
            return False
        level, raw = lv.level, lv.raw
        e_pos = sum((hi - lo) * e for lo, hi, e in segs if e > 0.0)
        if lv.tail_min[a] - e_pos >= m:
            return True
        spill_z = raw[z] - level[z]
        low = sum((hi - lo) * e for lo, hi, e in segs) - (spill_z - raw[a] + level[a])
        if low > 0.0 and lv.tail_raw[z] - spill_z - low < m:
            return False
        d = lv.net[a:z].copy()
        for lo, hi, e in segs:
            d[lo - a : hi - a] -= e
        run = level[a] + np.cumsum(d)
        new = run - np.maximum.accumulate(np.maximum(run - self.powers[sat].capacity_wh, 0.0))
        if new.min() < m:
            return False
        deficit = level[z] - new[-1]
        if lv.tail_min[z] < m:
            return False if deficit >= 0.0 else None
        if deficit <= 0.0:
            return True
        return bool(lv.tail_raw[z] - spill_z - deficit >= m)
