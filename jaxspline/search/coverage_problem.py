"""The coverage problem the search and the bound work on: slices, samples, rules.

Candidate strips are built from **slices**: a *group* is one satellite at one roll over
a contiguous range of action-grid slots (slot ``k`` = ``[k dt, (k+1) dt]``, ``dt`` the
case's ``time_step_s``); its rows in a CSR table list the samples each slot's swept
quadrilaterals cover. A strip of group ``g`` over slots ``[a, b)`` starts at ``a dt``,
lasts ``(b - a) dt`` and covers exactly the union of its slots' rows (the rule samples
the strip edges every 5 s from start to end; with starts and durations on the 10 s grid
the strip is the union of its 10 s slices, each made of the same quadrilaterals).

Sample weights: ``weight_j = (W_r / sum W) * weight_m2_j / total_r`` so that the summed
weight of the covered samples IS the benchmark's ``coverage_ratio`` (``r`` the sample's
region, ``W`` region weights, ``total_r`` the region's ``total_weight_m2``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jaxspline.search.coverage_rules import Margins

__all__ = ["CoverProblem", "group_passes", "sample_weights", "strip_rows"]


@dataclass(frozen=True)
class CoverProblem:
    """Slices, samples and per-satellite rules of one case.

    Attributes:
      indptr: int64 [rows+1], CSR row pointers (one row per group slot).
      indices: int32 [nnz], covered sample indices of each row (unique within a row).
      group_sat: int32 [G], satellite index of each group.
      group_roll: float64 [G], roll of each group [deg] (as written in the solution).
      group_slot0: int64 [G], absolute slot of the group's first row.
      group_nslots: int64 [G], number of rows (slots) of the group.
      group_row0: int64 [G], first row of the group (rows of a group are contiguous).
      weight: float64 [N], score weight of each sample (sums to coverage_ratio).
      ratio_weight: float64 [N], weight of each sample in its own region's ratio.
      region: int32 [N], region index of each sample.
      region_min: float64 [R], minimum region coverage ratio (NaN = none).
      rules: tuple of S SatRules.
      mesh_s: float64 [K+1], battery mesh instants [s].
      sunlit_iv: bool [S, K], charging flag per satellite and mesh interval.
      slot_s: action-grid step [s].
      horizon_s: horizon length [s].
      max_actions: action cap (all satellites).
      margins: Margins the search keeps.
    """

    indptr: np.ndarray
    indices: np.ndarray
    group_sat: np.ndarray
    group_roll: np.ndarray
    group_slot0: np.ndarray
    group_nslots: np.ndarray
    group_row0: np.ndarray
    weight: np.ndarray
    ratio_weight: np.ndarray
    region: np.ndarray
    region_min: np.ndarray
    rules: tuple
    mesh_s: np.ndarray
    sunlit_iv: np.ndarray
    slot_s: float
    horizon_s: float
    max_actions: int
    margins: Margins = Margins()

    @property
    def n_rows(self) -> int:
        """Number of CSR rows (group slots)."""
        return int(self.indptr.shape[0] - 1)

    @property
    def n_groups(self) -> int:
        """Number of groups G."""
        return int(self.group_sat.shape[0])

    @property
    def n_samples(self) -> int:
        """Number of samples N."""
        return int(self.weight.shape[0])

    def min_slots(self, sat: int) -> int:
        """Fewest slots a strip of satellite ``sat`` may span (min duration, rounded up)."""
        return max(1, int(np.ceil(self.rules[sat].min_dur_s / self.slot_s - 1e-9)))

    def max_slots(self, sat: int) -> int:
        """Most slots a strip of satellite ``sat`` may span (max duration, rounded down)."""
        return int(np.floor(self.rules[sat].max_dur_s / self.slot_s + 1e-9))

    def validate(self) -> None:
        """Check shapes and index ranges.

        Raises:
          ValueError: naming the inconsistent field.
        """
        g = self.n_groups
        for name in ("group_roll", "group_slot0", "group_nslots", "group_row0"):
            if getattr(self, name).shape != (g,):
                raise ValueError(f"CoverProblem.{name}: expected shape ({g},)")
        if self.indptr[0] != 0 or np.any(np.diff(self.indptr) < 0):
            raise ValueError("CoverProblem.indptr: must start at 0 and not decrease")
        if self.indptr[-1] != self.indices.shape[0]:
            raise ValueError("CoverProblem.indptr: last entry must equal len(indices)")
        if self.indices.size and (self.indices.min() < 0 or self.indices.max() >= self.n_samples):
            raise ValueError("CoverProblem.indices: sample index out of range")
        if g and np.any(self.group_row0 + self.group_nslots > self.n_rows):
            raise ValueError("CoverProblem.group_row0/group_nslots: rows out of range")
        if g and np.any(self.group_sat >= len(self.rules)):
            raise ValueError("CoverProblem.group_sat: satellite index out of range")
        if self.sunlit_iv.shape != (len(self.rules), self.mesh_s.shape[0] - 1):
            raise ValueError("CoverProblem.sunlit_iv: expected shape (S, len(mesh_s) - 1)")


def strip_rows(prob: CoverProblem, g: int, a: int, b: int) -> tuple[int, int]:
    """The CSR rows ``[r0, r1)`` of strip (group ``g``, slots ``[a, b)``) inside its group.

    Args:
      prob: CoverProblem.
      g: group index.
      a, b: absolute slots, ``a < b``.
    Returns:
      (r0, r1), possibly empty when the strip lies outside the group's slots.
    """
    s0 = int(prob.group_slot0[g])
    n = int(prob.group_nslots[g])
    lo = min(max(a - s0, 0), n)
    hi = min(max(b - s0, 0), n)
    r0 = int(prob.group_row0[g])
    return r0 + lo, r0 + max(hi, lo)


def sample_weights(region: np.ndarray, weight_m2: np.ndarray, region_total_m2, region_weight):
    """Score and per-region ratio weights of the samples.

    Args:
      region: int [N], region index of each sample.
      weight_m2: float [N], sample weights [m^2].
      region_total_m2: float [R], each region's ``total_weight_m2`` [m^2].
      region_weight: float [R], each region's weight.
    Returns:
      (weight, ratio_weight): float64 [N] each; ``sum(weight[covered])`` is the
      coverage_ratio, ``sum(ratio_weight[covered & region == r])`` region r's ratio.
    """
    total = np.asarray(region_total_m2, dtype=np.float64)
    rw = np.asarray(region_weight, dtype=np.float64)
    ratio = np.asarray(weight_m2, dtype=np.float64) / np.where(total > 0, total, 1.0)[region]
    norm = rw.sum()
    share = rw / norm if norm > 0 else np.full(rw.shape, 1.0 / max(len(rw), 1))
    return ratio * share[region], ratio


def group_passes(prob: CoverProblem) -> np.ndarray:
    """Pass index of every group: per satellite, groups whose slot ranges overlap chain.

    Args:
      prob: CoverProblem.
    Returns:
      int64 [G], passes numbered 0.. in (satellite, first slot) order.
    """
    g = prob.n_groups
    out = np.zeros(g, dtype=np.int64)
    order = np.lexsort((prob.group_slot0, prob.group_sat))
    cur, end, sat = -1, None, None
    for i in order:
        s0 = int(prob.group_slot0[i])
        s1 = s0 + int(prob.group_nslots[i])
        if sat != int(prob.group_sat[i]) or s0 >= end:
            cur += 1
            sat, end = int(prob.group_sat[i]), s1
        else:
            end = max(end, s1)
        out[i] = cur
    return out
