"""The coverage part of a problem: area samples, the slot rows that cover them, the area options.

The planner's one objective is the weight of samples covered at least once. A point or
strip target is one sample carrying its value (the problem's ``target_value``: imaged
at most once, it counts once); an area is its sample grid (:class:`CoverTable`), whose
weights sum to its priority, and any number of its options may be planned.

Area options are strips at a held roll over whole slots of the action grid
(``slot_s``). They come in **groups** (one satellite at one roll over a contiguous range
of slots); row ``group_row0[g] + i`` of the CSR table (``indptr``, ``indices``) lists the
samples that slot ``group_slot0[g] + i`` of group g sweeps, so an option of group g over
slots ``[a, b)`` covers exactly the union of its rows. Every option of a group (each
start and length the satellite allows, whose rows cover something) is an option of the
problem: ``option_group`` / ``option_a`` / ``option_b`` name it (-1 for the options of
point and strip targets), :meth:`CoverTable.option_of` finds it back.

:class:`CoverCounts` is the coverage state of one plan (kept by its
:class:`jaxspline.search.timeline.Timeline`): how often each sample is covered, the
covered weight, each row's still-open weight (so the open gain of any option is bounded
above by a difference of prefix sums) and each area's covered share.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["CoverCounts", "CoverTable", "gather_ranges", "group_passes"]


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


def group_passes(sat, slot0, nslots) -> np.ndarray:
    """Pass index of every group: per satellite, groups whose slot ranges overlap chain.

    Args:
      sat, slot0, nslots: int [G], each group's satellite, first slot and slot count.
    Returns:
      int64 [G], passes numbered 0.. in (satellite, first slot) order.
    """
    g = len(sat)
    out = np.zeros(g, dtype=np.int64)
    order = np.lexsort((slot0, sat))
    cur, end, last = -1, None, None
    for i in order:
        s0 = int(slot0[i])
        s1 = s0 + int(nslots[i])
        if last != int(sat[i]) or s0 >= end:
            cur += 1
            last, end = int(sat[i]), s1
        else:
            end = max(end, s1)
        out[i] = cur
    return out


@dataclass
class CoverTable:
    """Samples, groups and rows of a problem's areas (module docstring).

    Attributes:
      indptr: int64 [R + 1], CSR row pointers (one row per group slot).
      indices: int32 [nnz], the samples of each row (unique within a row).
      group_sat: int64 [G], satellite of each group.
      group_roll: float64 [G], roll of each group [deg].
      group_pitch: float64 [G], pitch of each group [deg] (0: the roll-only law).
      group_slot0: int64 [G], first slot of each group.
      group_nslots: int64 [G], slots (rows) of each group.
      group_area: int64 [G], the area (index into ``area_target``) a group was found for.
      weight: float64 [N], value of each sample (an area's samples sum to its priority).
      area: int64 [N], area index of each sample.
      share: float64 [N], share of its area each sample stands for (sums to 1 per area).
      area_target: int64 [A], the problem's target id of each area.
      area_min: float64 [A], least covered share each area asks for (NaN: none).
      slot_s: action-grid step [s].
      n_slots: slots of the horizon.
      min_slots, max_slots: int64 [S], per satellite the fewest and most slots of a strip.
      option_group, option_a, option_b: int64 [n_options], per option of the problem its
        group and slots ``[a, b)`` (-1: not an area option).
      group_row0: int64 [G], first row of each group (derived).
      group_pass: int64 [G], pass of each group (:func:`group_passes`, derived).
    """

    indptr: np.ndarray
    indices: np.ndarray
    group_sat: np.ndarray
    group_roll: np.ndarray
    group_pitch: np.ndarray
    group_slot0: np.ndarray
    group_nslots: np.ndarray
    group_area: np.ndarray
    weight: np.ndarray
    area: np.ndarray
    share: np.ndarray
    area_target: np.ndarray
    area_min: np.ndarray
    slot_s: float
    n_slots: int
    min_slots: np.ndarray
    max_slots: np.ndarray
    option_group: np.ndarray
    option_a: np.ndarray
    option_b: np.ndarray
    group_row0: np.ndarray = field(init=False)
    group_pass: np.ndarray = field(init=False)

    def __post_init__(self):
        self.group_row0 = (np.cumsum(self.group_nslots) - self.group_nslots).astype(np.int64)
        self.group_pass = group_passes(self.group_sat, self.group_slot0, self.group_nslots)
        if self.indptr[-1] != self.indices.size or self.indptr.size != self.n_rows + 1:
            raise ValueError(
                f"CoverTable: {self.indptr.size - 1} rows with {self.indices.size} entries "
                f"do not match {self.n_rows} group slots"
            )
        areas = np.flatnonzero(self.option_group >= 0)
        self._window = dict(
            zip(
                zip(
                    self.option_group[areas].tolist(),
                    self.option_a[areas].tolist(),
                    self.option_b[areas].tolist(),
                    strict=True,
                ),
                areas.tolist(),
                strict=True,
            )
        )
        self._transpose = None

    @property
    def n_rows(self) -> int:
        """Number of rows R (the groups' slots)."""
        return int(np.sum(self.group_nslots))

    @property
    def n_groups(self) -> int:
        """Number of groups G."""
        return int(self.group_sat.shape[0])

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.weight.shape[0])

    @property
    def n_areas(self) -> int:
        """Number of areas A."""
        return int(self.area_target.shape[0])

    def option_of(self, g: int, a: int, b: int) -> int:
        """The option of group g over slots ``[a, b)``, or -1 when the problem has none."""
        return self._window.get((g, a, b), -1)

    def rows(self, g: int, a: int, b: int) -> tuple[int, int]:
        """The rows ``[r0, r1)`` of the strip (group g, slots ``[a, b)``) inside its group."""
        s0 = int(self.group_slot0[g])
        n = int(self.group_nslots[g])
        lo = min(max(a - s0, 0), n)
        hi = min(max(b - s0, 0), n)
        r0 = int(self.group_row0[g])
        return r0 + lo, r0 + max(hi, lo)

    def option_rows(self, c: int) -> tuple[int, int]:
        """The rows ``[r0, r1)`` of area option c."""
        return self.rows(int(self.option_group[c]), int(self.option_a[c]), int(self.option_b[c]))

    def samples(self, g: int, a: int, b: int) -> np.ndarray:
        """Unique samples (int32) covered by the strip (group g, slots ``[a, b)``)."""
        r0, r1 = self.rows(g, a, b)
        idx = self.indices[self.indptr[r0] : self.indptr[r1]]
        return np.unique(idx) if r1 - r0 > 1 else idx

    def transpose(self) -> tuple[np.ndarray, np.ndarray]:
        """For each sample, the rows that cover it: (ptr int64 [N + 1], rows int64 [nnz])."""
        if self._transpose is None:
            row_of = np.repeat(np.arange(self.n_rows, dtype=np.int64), np.diff(self.indptr))
            order = np.argsort(self.indices, kind="stable")
            counts = np.bincount(self.indices, minlength=self.n_samples)
            ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
            self._transpose = (ptr, row_of[order])
        return self._transpose

    def row_values(self, sample_value: np.ndarray) -> np.ndarray:
        """``sum(sample_value[row])`` of every row (float64 [R])."""
        vals = np.asarray(sample_value, np.float64)[self.indices]
        cum = np.concatenate([[0.0], np.cumsum(vals)])
        return cum[self.indptr[1:]] - cum[self.indptr[:-1]]

    def union_weight(self) -> float:
        """Weight of the samples any row covers: no plan of these options covers more."""
        hit = np.zeros(self.n_samples, bool)
        hit[self.indices] = True
        return float(self.weight[hit].sum())


class CoverCounts:
    """How often a plan covers each sample (module docstring).

    Attributes:
      table: the :class:`CoverTable`.
      cnt: int32 [N], coverage count of each sample.
      value: float, covered weight.
      row_gain: float64 [R], each row's open (uncovered) weight.
      area_share: float64 [A], each area's covered share.
    """

    def __init__(self, table: CoverTable):
        self.table = table
        self.cnt = np.zeros(table.n_samples, np.int32)
        self.value = 0.0
        self.area_share = np.zeros(table.n_areas)
        self._samples: dict[int, np.ndarray] = {}
        self.refresh()

    def copy(self) -> CoverCounts:
        """An independent copy (the table shared)."""
        new = CoverCounts.__new__(CoverCounts)
        new.table, new._samples = self.table, self._samples
        new.cnt, new.value = self.cnt.copy(), self.value
        new.area_share, new.row_gain = self.area_share.copy(), self.row_gain.copy()
        return new

    def refresh(self) -> None:
        """Recompute ``row_gain`` from the counts (removes accumulated rounding)."""
        self.row_gain = self.table.row_values(np.where(self.cnt == 0, self.table.weight, 0.0))

    def option_samples(self, c: int) -> np.ndarray:
        """The unique samples of area option c (cached)."""
        s = self._samples.get(c)
        if s is None:
            t = self.table
            s = t.samples(int(t.option_group[c]), int(t.option_a[c]), int(t.option_b[c]))
            self._samples[c] = s
        return s

    def change(self, c: int, delta: int) -> float:
        """Count area option c in (``delta`` = 1) or out (-1); returns the value change."""
        t = self.table
        s = self.option_samples(c)
        flip = s[self.cnt[s] == (0 if delta > 0 else 1)]
        self.cnt[s] += delta
        if flip.size == 0:
            return 0.0
        w = t.weight[flip]
        dv = delta * float(w.sum())
        self.value += dv
        np.add.at(self.area_share, t.area[flip], delta * t.share[flip])
        ptr, rows = t.transpose()
        pos, owner = gather_ranges(ptr, flip)
        self.row_gain -= delta * np.bincount(rows[pos], weights=w[owner], minlength=t.n_rows)
        return dv

    def gain(self, g: int, a: int, b: int) -> float:
        """Exact weight the strip (group g, slots ``[a, b)``) would add."""
        t = self.table
        r0, r1 = t.rows(g, a, b)
        idx = t.indices[t.indptr[r0] : t.indptr[r1]]
        idx = idx[self.cnt[idx] == 0]
        if r1 - r0 > 1 and idx.size > 1:
            idx = np.unique(idx)
        return float(np.sum(t.weight[idx]))

    def loss(self, c: int) -> float:
        """Exact weight the plan would lose without area option c."""
        s = self.option_samples(c)
        return float(np.sum(self.table.weight[s[self.cnt[s] == 1]]))

    def shortfall(self) -> float:
        """Summed shortfall of the areas below their least covered share."""
        m = self.table.area_min
        has = np.isfinite(m)
        return float(np.sum(np.clip(m[has] - self.area_share[has], 0.0, None)))
