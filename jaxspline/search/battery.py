"""Conservative per-satellite battery profiles on the geometry grid (aeossp RULES.md rule 8).

The reference semantics integrate, from the initial level, load = idle + imaging
(inside an observation) + slew (inside the maneuver window ``[start - t_req, start)``)
and charge (while sunlit, cylindrical shadow), clamping at capacity; the level must
never drop below zero.

Here the horizon is cut into the uniform grid of the ephemeris (step ``dt``); in each
step ``[k dt, (k+1) dt]``:

* load = idle + imaging times the step's overlap with the observations + slew times its
  overlap with the maneuver windows (exact shares, :meth:`BatteryModel.loads`);
* charge only if the satellite is sunlit at every grid instant from ``k - guard`` to
  ``k + 1 + guard`` (a shadow-entry timing error of up to ``guard`` steps never
  credits charge the reference would not give);
* ``b_{k+1} = min(capacity, b_k + (charge - load) dt)``.

Every step's load energy equals and its charge is <= the reference's, so the level at
the grid instants is a lower bound of the reference's up to what the capacity clamp can
shift inside one step (the reference clamps after each segment, the step model once:
at most one step's load energy, ``(idle + imaging + slew) dt``, and the difference
never grows past it, since each clamp of the reference resets it) and what the
reference dips inside a step (another step's load at most): the model keeps its level
``clamp_wh`` (twice that energy) above the caller's margin. An earlier version charged
every step an observation or a maneuver window meets in full: on the unseen 12 x 12 h
instance its eigen-axis satellites' plans used ~22 % more energy in the model than in
the reference (docs/scale.md). With ``S_k`` the unclamped cumulative level, the clamped
one is ``S_k - M_k``, ``M_k = max(0, max_{j<=k} (S_j - capacity))`` (the energy spilled
at capacity so far), so a profile is a few vectorized numpy passes.

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
      margin_wh: the reference's level must stay >= this [Wh].
      guard: shadow guard [steps].

    Attributes:
      clamp_wh: what the model's level at the grid instants may exceed the reference's
        level at any instant by (module docstring): twice the largest load energy of
        one step, ``2 (idle + imaging + slew) dt`` [Wh].
      margin_wh: the level the model keeps, ``margin_wh + clamp_wh`` [Wh].
    """

    def __init__(self, sunlit, powers, dt: float, margin_wh: float = 0.0, guard: int = 0):
        self.powers = list(powers)
        self.dt = float(dt)
        watts = [p.idle_w + p.imaging_w + p.slew_w for p in self.powers if p is not None]
        self.clamp_wh = 2.0 * max(watts, default=0.0) * self.dt / 3600.0
        self.margin_wh = float(margin_wh) + self.clamp_wh
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

        Exact: each step carries ``imaging_w`` times its overlap with the observations
        and ``slew_w`` times its overlap with the maneuver windows ``[start - maneuver,
        start)`` (clipped to the horizon).

        Args:
          sat: satellite index.
          starts: observation start times [s].
          ends: observation end times [s].
          maneuver: maneuver durations [s] ending at each start (inf: from the horizon
            start).
        """
        p = self.powers[sat]
        s = np.asarray(starts, np.float64)
        e = np.asarray(ends, np.float64)
        m = np.asarray(maneuver, np.float64)
        if not s.size:
            return np.zeros(self.n)
        a = np.concatenate((s, np.maximum(s - m, 0.0))) / self.dt
        b = np.concatenate((e, s)) / self.dt
        w = np.repeat([p.imaging_w, p.slew_w], s.size) * (self.dt / 3600.0)
        return self._overlaps(a, b, w)

    def _overlaps(self, a, b, w) -> np.ndarray:
        """Per step k, ``sum_i w_i |[a_i, b_i) & [k, k + 1)|`` (intervals in steps).

        ``C(x) = sum_i w_i |[a_i, b_i) & [0, x)|`` is piecewise linear with kinks at the
        ends; at whole ``x`` it is a cumulative count and sum of the ends passed, so
        the steps' shares are ``C(k + 1) - C(k)``: two bincounts, no loop.
        """
        n = self.n
        a = np.clip(a, 0.0, n)
        b = np.clip(b, 0.0, n)
        keep = b > a
        a, b, w = a[keep], b[keep], w[keep]
        ends = np.concatenate((a, b))
        sign = np.concatenate((w, -w))
        idx = np.minimum(np.floor(ends).astype(np.int64) + 1, n + 1)
        cnt = np.cumsum(np.bincount(idx, sign, minlength=n + 2))[: n + 1]
        tot = np.cumsum(np.bincount(idx, sign * ends, minlength=n + 2))[: n + 1]
        c = np.arange(n + 1) * cnt - tot  # C(k), k = 0..n
        return np.maximum(np.diff(c), 0.0)

    def segments(self, t0: float, t1: float, watts: float) -> list:
        """A load of ``watts`` on ``[t0, t1)`` [s] as :meth:`change_ok` changes
        ``(lo, hi, watts)``: the whole steps inside, and the steps it meets in part with
        the watts scaled by their overlap (:meth:`loads`' exact shares).

        Args:
          t0: float, start [s] (clipped to the horizon).
          t1: float, end [s].
          watts: float, power (negative: a load taken off).
        Returns:
          list of ``(lo, hi, watts)``, empty when the interval is.
        """
        n = self.n
        a = min(max(t0 / self.dt, 0.0), n)
        b = min(max(t1 / self.dt, 0.0), n)
        if b <= a:
            return []
        i = min(math.floor(a), n - 1)
        j = max(math.ceil(b) - 1, i)  # the last step it meets
        if i == j:
            return [(i, i + 1, watts * (b - a))]
        out = [(i, i + 1, watts * (i + 1 - a))]
        if j > i + 1:
            out.append((i + 1, j, watts))
        out.append((j, j + 1, watts * (b - j)))
        return out

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
