"""Pass-level moves of the search: re-plan one pass, or several related passes, exactly.

* :class:`PassIndex`: the groups of each pass (by roll), its slot span, gap matrices.
* :func:`reopt_pass`: remove a pass's strips and put back the best set of strips of that
  pass given everything else (:func:`jaxspline.search.coverage_passdp.best_runs` on the rows'
  open weights, which within one pass add up almost exactly).
* :func:`reopt_related`: the passes able to cover one still-open sample (drawn by weight)
  are cleared together and re-planned one after the other in random order, then once
  more each (block coordinate ascent), so their strips can trade the area between them.
"""

from __future__ import annotations

import numpy as np

from jaxspline.search.coverage_passdp import best_runs, gap_slots
from jaxspline.search.coverage_problem import CoverProblem, group_passes
from jaxspline.search.coverage_state import PlanState, gather_ranges

__all__ = [
    "MAX_RUNS_PER_PASS",
    "PassIndex",
    "related_passes",
    "reopt_pass",
    "reopt_related",
]

#: Most strips the pass re-optimization puts in one pass.
MAX_RUNS_PER_PASS = 8
#: Value below which a run is not worth an action (coverage_ratio units).
RUN_PRICE = 1e-10


class PassIndex:
    """Groups of each pass, sorted by roll, with their slot span and gap matrices (lazy).

    Attributes:
      of_group: int64 [G], pass of each group.
      groups: list of int arrays, per pass its groups by roll.
      span: int64 [P, 2], first slot and end slot of each pass.
    """

    def __init__(self, prob: CoverProblem):
        """Index the passes of ``prob``."""
        self.prob = prob
        self.of_group = group_passes(prob)
        n = int(self.of_group.max()) + 1 if self.of_group.size else 0
        order = np.lexsort((prob.group_roll, self.of_group))
        cuts = np.searchsorted(self.of_group[order], np.arange(n + 1))
        self.groups = [order[cuts[i] : cuts[i + 1]] for i in range(n)]
        self.span = np.array(
            [
                [prob.group_slot0[g].min(), (prob.group_slot0[g] + prob.group_nslots[g]).max()]
                for g in self.groups
            ],
            dtype=np.int64,
        ).reshape(-1, 2)
        self._gaps = {}

    def gaps(self, p: int) -> np.ndarray:
        """The gap matrix [slots] of pass ``p`` (cached)."""
        if p not in self._gaps:
            prob = self.prob
            g = self.groups[p]
            sat = int(prob.group_sat[g[0]])
            self._gaps[p] = gap_slots(
                prob.rules[sat], prob.group_roll[g], prob.slot_s, prob.margins
            )
        return self._gaps[p]

    def open_weight(self, state: PlanState) -> np.ndarray:
        """Per pass, the summed open weight of its rows (an upper bound of what it can add)."""
        prob = self.prob
        row_pass = np.repeat(self.of_group, prob.group_nslots)
        return np.bincount(row_pass, weights=state.row_gain, minlength=len(self.groups))


def reopt_pass(state: PlanState, index: PassIndex, p: int) -> int:
    """Replace the strips of pass ``p`` by the best set of strips of that pass.

    The pass's strips are removed, :func:`jaxspline.search.coverage_passdp.best_runs` picks the
    runs of best open value (at most the actions left once they are removed;
    other passes' strips of the satellite block their maneuver gaps), and each run is
    added if the satellite's duty and battery still hold.

    Args:
      state: PlanState, modified in place; index: PassIndex; p: pass.
    Returns:
      number of strips added.
    """
    prob = state.prob
    groups = index.groups[p]
    sat = int(prob.group_sat[groups[0]])
    p0, p1 = (int(x) for x in index.span[p])
    mine = [i for i in state.by_sat[sat] if index.of_group[state.strips[i][0]] == p]
    for i in mine:
        state.remove(i)
    t_n = p1 - p0
    vals = np.zeros((groups.size, t_n))
    allowed = np.zeros((groups.size, t_n), dtype=bool)
    reach = state.timing.reach[sat]
    others = any(
        state.strips[i][2] >= p0 - reach and state.strips[i][1] <= p1 + reach
        for i in state.by_sat[sat]
    )
    for k, g in enumerate(groups):
        s0, n, r0 = int(prob.group_slot0[g]), int(prob.group_nslots[g]), int(prob.group_row0[g])
        vals[k, s0 - p0 : s0 - p0 + n] = state.row_gain[r0 : r0 + n]
        if others:
            for lo, hi in state.free_slots(int(g), lo=s0, hi=s0 + n):
                allowed[k, max(lo, s0) - p0 : min(hi, s0 + n) - p0] = True
        else:
            allowed[k, s0 - p0 : s0 - p0 + n] = True
    rmax = prob.max_actions - state.n_actions()
    rmax = min(rmax, (t_n + 1) // (state.timing.min_slots[sat] + 1))
    useful = np.nonzero((vals * allowed).sum(axis=1) > RUN_PRICE)[0]
    if useful.size == 0:
        return 0
    _, runs = best_runs(
        vals[useful],
        allowed[useful],
        index.gaps(p)[np.ix_(useful, useful)],
        prob.min_slots(sat),
        prob.max_slots(sat),
        min(rmax, MAX_RUNS_PER_PASS),
        price=RUN_PRICE,
    )
    added = 0
    for k, s, t in runs:
        g = int(groups[useful[k]])
        if state.n_actions() >= prob.max_actions:
            break
        ok, low = state.resources_ok(g, p0 + s, p0 + t)
        if ok and state.fit(g, p0 + s, p0 + t) == (p0 + s, p0 + t):
            state.add(g, p0 + s, p0 + t, low=low)
            added += 1
    return added


def related_passes(state: PlanState, index: PassIndex, rng, most: int) -> list:
    """Up to ``most`` passes able to cover one open sample drawn by weight (random order).

    Args:
      state: PlanState; index: PassIndex; rng: numpy Generator; most: cap.
    Returns:
      list of pass indices (empty when everything is covered).
    """
    prob = state.prob
    open_w = np.where(state.cnt == 0, prob.weight, 0.0)
    total = open_w.sum()
    if total <= 0:
        return []
    j = int(rng.choice(open_w.size, p=open_w / total))
    pos, _ = gather_ranges(state.tr.ptr, np.array([j]))
    rows = state.tr.rows[pos]
    group_of_row = np.searchsorted(prob.group_row0, rows, side="right") - 1
    passes = np.unique(index.of_group[group_of_row])
    return [int(p) for p in rng.permutation(passes)[:most]]


def reopt_related(state: PlanState, index: PassIndex, rng, most: int = 3, sweeps: int = 2):
    """Clear the passes related to one open sample and re-plan them one by one.

    Args:
      state: PlanState, modified in place; index: PassIndex; rng: numpy Generator.
      most: most passes; sweeps: rounds of single-pass re-planning.
    Returns:
      the passes re-planned.
    """
    passes = related_passes(state, index, rng, most)
    for p in passes:
        sat = int(state.prob.group_sat[index.groups[p][0]])
        for i in [i for i in state.by_sat[sat] if index.of_group[state.strips[i][0]] == p]:
            state.remove(i)
    for _ in range(sweeps):
        for p in passes:
            reopt_pass(state, index, p)
    return passes
