"""The search state: chosen strips, per-sample coverage counts, per-row open gains.

:class:`PlanState` holds a set of strips (group, slots ``[a, b)``) with, kept up to
date on every change:

* ``cnt[j]``: how many chosen strips cover sample ``j``; ``value`` = the summed score
  weight of the samples with ``cnt > 0`` (the coverage_ratio of the plan);
* ``row_gain[row]``: summed weight of the row's still-uncovered samples (through the
  transposed table, updated only for the samples whose count crosses 0), so the open
  gain of any strip is bounded above by a difference of prefix sums (exact up to samples
  shared by two slots of one strip);
* per satellite, the strips sorted by start, and the lowest battery level.

Adding a strip goes through :meth:`PlanState.fit` (the best sub-window that the
satellite's timeline admits) and :meth:`PlanState.resources_ok` (duty, battery).
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.screen.models.roll_only import roll_slew_time
from jaxspline.search.coverage_problem import CoverProblem, strip_rows
from jaxspline.search.coverage_rules import (
    battery_min_mesh,
    duty_ok,
    gaps_ok,
    maneuver_s,
    maneuver_scalar,
    timeline_ok,
)

__all__ = ["PlanState", "SatTiming", "Transpose", "better", "gather_ranges", "transpose"]


class Transpose:
    """The table transposed: for each sample, the rows that cover it (CSC of the CSR).

    Attributes:
      ptr: int64 [N+1].
      rows: int64 [nnz].
    """

    def __init__(self, ptr: np.ndarray, rows: np.ndarray):
        """Store the arrays (see :func:`transpose`)."""
        self.ptr = ptr
        self.rows = rows


def transpose(prob: CoverProblem) -> Transpose:
    """Build the sample -> rows index of a problem.

    Args:
      prob: CoverProblem.
    Returns:
      Transpose.
    """
    row_of = np.repeat(np.arange(prob.n_rows, dtype=np.int64), np.diff(prob.indptr))
    order = np.argsort(prob.indices, kind="stable")
    counts = np.bincount(prob.indices, minlength=prob.n_samples)
    ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return Transpose(ptr, row_of[order])


def gather_ranges(ptr: np.ndarray, items: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions ``ptr[i] .. ptr[i+1]-1`` of every ``i`` in ``items``, concatenated.

    Args:
      ptr: int [M+1], range pointers.
      items: int [k], which ranges.
    Returns:
      (pos, owner): int64 positions and, for each, its index into ``items``.
    """
    lo = ptr[items]
    lens = ptr[items + 1] - lo
    total = int(lens.sum())
    owner = np.repeat(np.arange(items.size), lens)
    start = np.repeat(lo - np.concatenate([[0], np.cumsum(lens)[:-1]]), lens)
    return start + np.arange(total), owner


class SatTiming:
    """Per-problem caches of the timeline arithmetic (shared by all copies of a state).

    Attributes:
      man: list per satellite of dict ``round(|dr|, 6) -> smallest maneuver gap [s]``.
      reach: int per satellite, slots beyond which a neighbour's gap cannot matter.
      min_slots, max_slots: int per satellite.
      n_total: number of slots in the horizon.
    """

    def __init__(self, prob: CoverProblem):
        """Build the caches of ``prob``."""
        self.prob = prob
        self.man = [self._gaps_of(k, r) for k, r in enumerate(prob.rules)]
        self.min_slots = [prob.min_slots(s) for s in range(len(prob.rules))]
        self.max_slots = [prob.max_slots(s) for s in range(len(prob.rules))]
        self.n_total = int(np.floor(prob.horizon_s / prob.slot_s + 1e-9))
        nrow = prob.group_nslots
        group_of_row = np.repeat(np.arange(prob.n_groups), nrow)
        within = np.arange(prob.n_rows) - np.repeat(prob.group_row0, nrow)
        #: flat index ``sat * (n_total + 2) + slot + 1`` of every row (for busy masks)
        self.row_key = prob.group_sat[group_of_row].astype(np.int64) * (self.n_total + 2) + (
            prob.group_slot0[group_of_row] + within + 1
        )
        step = float(prob.mesh_s[1] - prob.mesh_s[0])
        z = np.zeros(0)
        self.idle_min = [
            battery_min_mesh(r, step, prob.sunlit_iv[k], z, z, z, prob.margins)
            for k, r in enumerate(prob.rules)
        ]
        self.reach = [
            int(math.ceil(maneuver_scalar(r, 2.0 * r.max_edge_deg, prob.margins) / prob.slot_s)) + 2
            for r in prob.rules
        ]

    def _gaps_of(self, sat: int, rules) -> dict:
        """The maneuver cache of ``sat`` filled for every roll change between its groups.

        One vectorized :func:`maneuver_s` call instead of one per cache miss; the keys and
        values are the ones :meth:`maneuver` would compute.
        """
        rolls = np.unique(self.prob.group_roll[self.prob.group_sat == sat])
        diffs = np.unique(np.abs(rolls[:, None] - rolls[None, :]))
        keys = sorted({round(float(d), 6) for d in diffs})
        gaps = maneuver_s(rules, np.array(keys, dtype=np.float64), self.prob.margins)
        return dict(zip(keys, gaps.tolist(), strict=True))

    def battery_floor(self, sat: int, starts, ends) -> float:
        """A quick lower bound of a timeline's lowest battery level [Wh].

        The idle profile's minimum minus all the extra energy the strips draw (imaging,
        plus slew power over at most ``min(gap, slew(180 deg) + settling + margin)`` before
        each strip): extra loads lower the clamped level by at most their running sum.

        Args:
          sat: satellite; starts, ends: the timeline [s] (sorted by start).
        Returns:
          float [Wh].
        """
        rules = self.prob.rules[sat]
        s = np.sort(np.asarray(starts, dtype=np.float64))
        e = np.sort(np.asarray(ends, dtype=np.float64))
        extra = rules.imaging_w * float(np.sum(e - s))
        if s.size > 1:
            cap = float(roll_slew_time(180.0, rules.rate_deg_s, rules.accel_deg_s2))
            cap += rules.settle_s + self.prob.margins.gap_s
            extra += rules.slew_w * float(np.sum(np.minimum(s[1:] - e[:-1], cap)))
        return self.idle_min[sat] - extra / 3600.0

    def maneuver(self, sat: int, delta_deg: float) -> float:
        """Smallest gap [s] after a roll change of ``delta_deg`` on satellite ``sat``."""
        key = round(abs(delta_deg), 6)
        cache = self.man[sat]
        if key not in cache:
            cache[key] = maneuver_scalar(self.prob.rules[sat], key, self.prob.margins)
        return cache[key]


class PlanState:
    """A plan under construction (see the module docstring).

    Attributes:
      prob: CoverProblem.
      cnt: int32 [N] coverage counts.
      row_gain: float64 [rows] open weight per row.
      value: float, summed weight of covered samples.
      strips: dict id -> (g, a, b).
      by_sat: list per satellite of strip ids sorted by start slot.
      low_wh: float64 [S], lowest battery level per satellite (NaN: not computed since the
        last change; :meth:`min_battery` fills it in).
      busy: bool [S, n_total + 2], slot ``k`` (column ``k + 1``) taken by a strip or the
        slot on either side of one (every neighbour needs at least one slot of gap).
    """

    def __init__(self, prob: CoverProblem, tr: Transpose | None = None):
        """An empty plan.

        Args:
          prob: CoverProblem.
          tr: its Transpose (built when None).
        """
        self.prob = prob
        self.tr = tr if tr is not None else transpose(prob)
        self.timing = SatTiming(prob)
        self.cnt = np.zeros(prob.n_samples, dtype=np.int32)
        self.region_cov = np.zeros(len(prob.region_min), dtype=np.float64)
        self.value = 0.0
        self.strips: dict[int, tuple[int, int, int]] = {}
        self.strip_samples: dict[int, np.ndarray] = {}
        self.by_sat: list[list[int]] = [[] for _ in prob.rules]
        self.low_wh = np.array([r.initial_wh for r in prob.rules], dtype=np.float64)
        self.busy = np.zeros((len(prob.rules), self.timing.n_total + 2), dtype=bool)
        self._next = 0
        self.refresh_gains()

    # ------------------------------------------------------------------ bookkeeping
    def copy(self) -> PlanState:
        """An independent copy (arrays and lists copied, problem shared)."""
        new = PlanState.__new__(PlanState)
        new.prob, new.tr, new.timing = self.prob, self.tr, self.timing
        new.cnt = self.cnt.copy()
        new.region_cov = self.region_cov.copy()
        new.value = self.value
        new.strips = dict(self.strips)
        new.strip_samples = dict(self.strip_samples)
        new.by_sat = [list(x) for x in self.by_sat]
        new.low_wh = self.low_wh.copy()
        new.busy = self.busy.copy()
        new.row_gain = self.row_gain.copy()
        new._next = self._next
        return new

    def refresh_gains(self) -> None:
        """Recompute ``row_gain`` from scratch (removes accumulated rounding)."""
        p = self.prob
        open_w = np.where(self.cnt == 0, p.weight, 0.0)
        vals = open_w[p.indices]
        cum = np.concatenate([[0.0], np.cumsum(vals)])
        self.row_gain = cum[p.indptr[1:]] - cum[p.indptr[:-1]]

    def samples(self, g: int, a: int, b: int) -> np.ndarray:
        """Unique sample indices covered by strip (g, [a, b)).

        Args:
          g: group; a, b: absolute slots.
        Returns:
          int32 array.
        """
        r0, r1 = strip_rows(self.prob, g, a, b)
        p = self.prob
        return np.unique(p.indices[p.indptr[r0] : p.indptr[r1]])

    def gain(self, g: int, a: int, b: int) -> float:
        """Exact weight the strip would add to the plan."""
        p = self.prob
        r0, r1 = strip_rows(p, g, a, b)
        idx = p.indices[p.indptr[r0] : p.indptr[r1]]
        idx = idx[self.cnt[idx] == 0]
        if r1 - r0 > 1 and idx.size > 1:
            idx = np.unique(idx)
        return float(np.sum(p.weight[idx]))

    def loss(self, sid: int) -> float:
        """Exact weight the plan would lose without strip ``sid``."""
        s = self.strip_samples[sid]
        return float(np.sum(self.prob.weight[s[self.cnt[s] == 1]]))

    def _change(self, s: np.ndarray, delta: int) -> None:
        p = self.prob
        if delta > 0:
            flip = s[self.cnt[s] == 0]
        else:
            flip = s[self.cnt[s] == 1]
        self.cnt[s] += delta
        if flip.size == 0:
            return
        w = p.weight[flip]
        self.value += delta * float(w.sum())
        np.add.at(self.region_cov, p.region[flip], delta * p.ratio_weight[flip])
        pos, owner = gather_ranges(self.tr.ptr, flip)
        self.row_gain -= delta * np.bincount(
            self.tr.rows[pos], weights=w[owner], minlength=p.n_rows
        )

    def add(self, g: int, a: int, b: int, low: float | None = None) -> int:
        """Add strip (g, [a, b)) without any check; returns its id.

        Args:
          g, a, b: the strip.
          low: its satellite's new lowest battery level if known (else recomputed) [Wh].
        """
        sid = self._next
        self._next += 1
        self.strips[sid] = (int(g), int(a), int(b))
        sat = int(self.prob.group_sat[g])
        lst = self.by_sat[sat]
        starts = [self.strips[i][1] for i in lst]
        lst.insert(int(np.searchsorted(starts, a)), sid)
        smp = self.samples(g, a, b)
        self.strip_samples[sid] = smp
        self.busy[sat, a : b + 2] = True
        self._change(smp, +1)
        self.low_wh[sat] = np.nan if low is None else low
        return sid

    def remove(self, sid: int) -> None:
        """Remove strip ``sid`` (its satellite's battery minimum is recomputed)."""
        g, a, b = self.strips.pop(sid)
        sat = int(self.prob.group_sat[g])
        self.by_sat[sat].remove(sid)
        self._change(self.strip_samples.pop(sid), -1)
        self.busy[sat] = False
        for i in self.by_sat[sat]:
            _, ai, bi = self.strips[i]
            self.busy[sat, ai : bi + 2] = True
        self.low_wh[sat] = np.nan

    # ------------------------------------------------------------------ timelines
    def timeline(self, sat: int, extra=None, skip=None):
        """Starts, ends [s] and rolls [deg] of a satellite's strips.

        Args:
          sat: satellite index.
          extra: optional (g, a, b) added.
          skip: optional strip id left out.
        Returns:
          (starts, ends, rolls) float arrays.
        """
        p = self.prob
        items = [self.strips[i] for i in self.by_sat[sat] if i != skip]
        if extra is not None:
            items.append(extra)
        if not items:
            z = np.zeros(0)
            return z, z, z
        arr = np.array(items, dtype=np.float64)
        g = arr[:, 0].astype(np.int64)
        return arr[:, 1] * p.slot_s, arr[:, 2] * p.slot_s, p.group_roll[g]

    def battery_low(self, sat: int, extra=None, skip=None) -> float:
        """Lowest battery level of a satellite's timeline (with ``extra``, without ``skip``)."""
        p = self.prob
        s, e, r = self.timeline(sat, extra, skip)
        step = float(p.mesh_s[1] - p.mesh_s[0])
        return battery_min_mesh(p.rules[sat], step, p.sunlit_iv[sat], s, e, r, p.margins)

    def resources_ok(self, g: int, a: int, b: int, skip=None) -> tuple[bool, float]:
        """Duty and battery (and gaps, rechecked) with strip (g, [a, b)) added.

        Args:
          g, a, b: the strip.
          skip: optional strip id left out.
        Returns:
          (ok, lowest battery level [Wh]).
        """
        p = self.prob
        sat = int(p.group_sat[g])
        s, e, r = self.timeline(sat, (g, a, b), skip)
        rules = p.rules[sat]
        if not duty_ok(rules, s, e, p.margins):
            return False, float("nan")
        if not gaps_ok(rules, s, e, r, p.margins):
            return False, float("nan")
        quick = self.timing.battery_floor(sat, s, e)
        if quick >= p.margins.battery_wh:
            return True, float("nan")
        return timeline_ok(rules, p.mesh_s, p.sunlit_iv[sat], s, e, r, p.margins)

    def free_slots(self, g: int, skip=None, lo: int = 0, hi: int | None = None):
        """Slot ranges ``[lo, hi)`` where a strip of group ``g`` fits between the others.

        Each range leaves slew + settling + margin to the neighbours (their rolls vs the
        group's) and stays inside the horizon; only strips near ``[lo, hi)`` are looked at.

        Args:
          g: group.
          skip: optional strip id ignored.
          lo, hi: the slots of interest (default: the whole horizon).
        Returns:
          list of (lo, hi) absolute slots covering ``[lo, hi)``'s free parts.
        """
        p = self.prob
        tm = self.timing
        sat = int(p.group_sat[g])
        roll = float(p.group_roll[g])
        n_total = tm.n_total
        hi = n_total if hi is None else hi
        reach = tm.reach[sat]
        slot = p.slot_s
        bounds = [0.0]
        for i in self.by_sat[sat]:
            if i == skip:
                continue
            gi, ai, bi = self.strips[i]
            if bi < lo - reach or ai > hi + reach:
                continue
            m = tm.maneuver(sat, float(p.group_roll[gi]) - roll)
            bounds += [ai * slot - m, bi * slot + m]
        bounds.append(n_total * slot)
        out = []
        for lo_s, hi_s in zip(bounds[0::2], bounds[1::2], strict=True):
            a = int(math.ceil(lo_s / slot - 1e-9))
            b = int(math.floor(hi_s / slot + 1e-9))
            if b > a:
                out.append((a, b))
        return out

    def open_rows(self) -> np.ndarray:
        """Row open gains with the rows of busy slots zeroed (see ``busy``)."""
        return np.where(self.busy.ravel()[self.timing.row_key], 0.0, self.row_gain)

    def signature(self, sat: int) -> tuple:
        """The satellite's strips as a hashable value (equal iff the timelines are equal)."""
        return tuple(self.strips[i] for i in self.by_sat[sat])

    def fit(self, g: int, a: int, b: int, skip=None) -> tuple[int, int] | None:
        """The best sub-window of (g, [a, b)) that the satellite's gaps admit.

        The window is cut by the free ranges (:meth:`free_slots`); a piece shorter than the
        minimum duration grows inside its free range and the group's slots; among the
        pieces the one of largest exact gain is returned (duty and battery are not checked
        here: :meth:`resources_ok`).

        Args:
          g: group; a, b: wanted slots; skip: optional strip id ignored.
        Returns:
          (a', b') or None.
        """
        p = self.prob
        sat = int(p.group_sat[g])
        lo_g = int(p.group_slot0[g])
        hi_g = lo_g + int(p.group_nslots[g])
        need = self.timing.min_slots[sat]
        best, best_gain = None, -1.0
        for lo, hi in self.free_slots(g, skip, a, b):
            pa, pb = max(a, lo), min(b, hi)
            if pb <= pa:
                continue
            lo2, hi2 = max(lo, lo_g), min(hi, hi_g)
            if pb - pa < need:
                pb = min(hi2, pa + need)
                pa = max(lo2, pb - need)
            if pb - pa < need:
                continue
            gain = self.gain(g, pa, pb)
            if gain > best_gain:
                best, best_gain = (pa, pb), gain
        return best

    def shortfall(self) -> float:
        """Summed shortfall of the regions below their minimum coverage ratio."""
        m = self.prob.region_min
        has = np.isfinite(m)
        return float(np.sum(np.clip(m[has] - self.region_cov[has], 0.0, None)))

    def n_actions(self) -> int:
        """Number of strips."""
        return len(self.strips)

    def min_battery(self) -> float:
        """Lowest battery level over all satellites [Wh] (stale entries recomputed)."""
        for sat in np.nonzero(np.isnan(self.low_wh))[0]:
            self.low_wh[sat] = self.battery_low(int(sat))
        return float(np.min(self.low_wh)) if self.low_wh.size else 0.0

    def score(self) -> tuple[float, float, int]:
        """Lexicographic key, larger is better: (-shortfall, value, -actions).

        Ties are broken by :meth:`min_battery` (see :func:`better`).
        """
        return (-round(self.shortfall(), 12), round(self.value, 12), -self.n_actions())


def better(a: PlanState, b: PlanState, strict: bool = True) -> bool:
    """Whether plan ``a`` beats (``strict``) or equals-or-beats plan ``b``.

    Order: smaller shortfall, larger coverage, fewer actions, higher lowest battery.

    Args:
      a, b: PlanState; strict: ask for a strict improvement.
    Returns:
      bool.
    """
    sa, sb = a.score(), b.score()
    if sa != sb:
        return sa > sb
    la, lb = a.min_battery(), b.min_battery()
    return la > lb + 1e-9 if strict else la >= lb - 1e-9
