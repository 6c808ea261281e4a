"""Coverage search: lazy greedy by marginal gain, then large-neighbourhood search.

* :func:`candidate_windows`: per group, the window of its non-empty slots (clipped to the
  maximum strip duration: longer groups give every max-length window, one slot apart).
* :func:`greedy_fill`: CELF lazy greedy. A window's open gain is bounded above by prefix
  sums of the state's per-row open gains; the top of the heap is re-evaluated exactly
  (after :meth:`PlanState.fit` cuts it to the satellite's free time) and taken when it
  still beats the next bound. Taken strips are trimmed to the shortest window of the same
  gain; strips with no gain are never taken (ties go to fewer actions).
* :func:`lns`: until the deadline, destroy a few strips (random, least marginal
  contribution, one region's, one satellite's, the strips overlapping a random one) and
  repair with the greedy (the removed groups banned half the time); then local moves (a
  strip's roll moved to a neighbouring group of its pass, its ends moved by one slot).
  A trial replaces the current plan when its :meth:`PlanState.score` is not lower
  (shortfall, coverage, fewer actions, higher battery minimum); the best is kept.

Deterministic for a given seed and for a given number of iterations (the deadline stops
the loop between iterations).
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np

from jaxspline.regional.passdp import best_runs, gap_slots
from jaxspline.regional.problem import CoverProblem, group_passes, strip_rows
from jaxspline.regional.state import PlanState

__all__ = [
    "PassIndex",
    "SearchConfig",
    "Windows",
    "candidate_windows",
    "greedy_fill",
    "lns",
    "local_moves",
    "reopt_pass",
]

#: Gains at or below this count as zero (coverage_ratio units).
MIN_GAIN = 1e-10
#: Most strips the pass re-optimization puts in one pass.
MAX_RUNS_PER_PASS = 8


@dataclass(frozen=True)
class SearchConfig:
    """Knobs of the LNS.

    Attributes:
      seed: random seed.
      max_destroy: most strips removed per iteration.
      refresh_every: iterations between exact recomputations of the row gains.
      ban_prob: probability that the removed strips' groups are banned from the repair.
      local_every: iterations between rounds of local moves.
      roll_neighbours: how many groups on each side (by roll, same pass) a local move tries.
      pass_prob: probability that an iteration re-optimizes one pass (:func:`reopt_pass`)
        instead of destroying and repairing.
    """

    seed: int = 0
    max_destroy: int = 4
    refresh_every: int = 100
    ban_prob: float = 0.5
    local_every: int = 50
    roll_neighbours: int = 3
    pass_prob: float = 0.5


@dataclass(frozen=True)
class Windows:
    """Candidate strip windows.

    Attributes:
      g: int64 [W] group; a, b: int64 [W] absolute slots ``[a, b)``; r0, r1: int64 [W]
      CSR rows of the window.
    """

    g: np.ndarray
    a: np.ndarray
    b: np.ndarray
    r0: np.ndarray
    r1: np.ndarray

    @property
    def size(self) -> int:
        """Number of windows."""
        return int(self.g.shape[0])


def candidate_windows(prob: CoverProblem) -> Windows:
    """The greedy's windows: each group's non-empty slots, clipped to the max duration.

    Args:
      prob: CoverProblem.
    Returns:
      Windows (a window shorter than the minimum duration grows inside its group).
    """
    nonempty = np.diff(prob.indptr) > 0
    out = []
    for g in range(prob.n_groups):
        r0 = int(prob.group_row0[g])
        n = int(prob.group_nslots[g])
        rows = np.nonzero(nonempty[r0 : r0 + n])[0]
        if rows.size == 0:
            continue
        sat = int(prob.group_sat[g])
        lo, hi = int(rows[0]), int(rows[-1]) + 1
        need, most = prob.min_slots(sat), prob.max_slots(sat)
        if hi - lo < need:
            hi = min(n, lo + need)
            lo = max(0, hi - need)
            if hi - lo < need:
                continue
        s0 = int(prob.group_slot0[g])
        for k in range(lo, max(lo, hi - most) + 1):
            out.append((g, s0 + k, s0 + min(hi, k + most)))
    arr = np.array(out, dtype=np.int64).reshape(-1, 3)
    r = np.array([strip_rows(prob, *w) for w in arr], dtype=np.int64).reshape(-1, 2)
    return Windows(arr[:, 0], arr[:, 1], arr[:, 2], r[:, 0], r[:, 1])


def window_bounds(state: PlanState, win: Windows) -> np.ndarray:
    """Upper bounds of every window's open gain (sums of its rows' open gains).

    Args:
      state: PlanState; win: Windows.
    Returns:
      float64 [W].
    """
    cum = np.concatenate([[0.0], np.cumsum(state.row_gain)])
    return cum[win.r1] - cum[win.r0]


def _trim(state: PlanState, g: int, a: int, b: int, gain: float) -> tuple[int, int]:
    need = state.prob.min_slots(int(state.prob.group_sat[g]))
    while b - a > need and state.gain(g, a + 1, b) >= gain - 1e-15:
        a += 1
    while b - a > need and state.gain(g, a, b - 1) >= gain - 1e-15:
        b -= 1
    return a, b


def greedy_fill(
    state: PlanState,
    win: Windows,
    deadline: float,
    banned: set | None = None,
    weights_bound: np.ndarray | None = None,
) -> int:
    """Add strips by largest exact marginal gain until none gains or the cap is reached.

    Args:
      state: PlanState, modified in place.
      win: Windows.
      deadline: ``time.perf_counter()`` instant to stop at.
      banned: optional set of groups not to use.
      weights_bound: optional precomputed window bounds (else :func:`window_bounds`).
    Returns:
      number of strips added.
    """
    prob = state.prob
    ub = window_bounds(state, win) if weights_bound is None else weights_bound
    cand = np.nonzero(ub > MIN_GAIN)[0]
    heap = list(zip((-ub[cand]).tolist(), cand.tolist(), strict=True))
    heapq.heapify(heap)
    cum = np.concatenate([[0.0], np.cumsum(state.row_gain)])
    added = 0
    while heap and state.n_actions() < prob.max_actions:
        if time.perf_counter() > deadline:
            break
        _, i = heapq.heappop(heap)
        g = int(win.g[i])
        if banned and g in banned:
            continue
        top = -heap[0][0] if heap else 0.0
        now = float(cum[win.r1[i]] - cum[win.r0[i]])
        if now <= MIN_GAIN:
            continue
        if now < top - 1e-15:
            heapq.heappush(heap, (-now, i))
            continue
        fit = state.fit(g, int(win.a[i]), int(win.b[i]))
        if fit is None:
            continue
        gain = state.gain(g, *fit)
        if gain <= MIN_GAIN:
            continue
        if gain < top - 1e-15:
            heapq.heappush(heap, (-gain, i))
            continue
        a, b = _trim(state, g, fit[0], fit[1], gain)
        ok, low = state.resources_ok(g, a, b)
        if not ok:
            continue
        state.add(g, a, b, low=low)
        cum = np.concatenate([[0.0], np.cumsum(state.row_gain)])
        added += 1
    return added


def _destroy(state: PlanState, rng: np.random.Generator, passes: np.ndarray) -> list:
    """Remove a few strips by one of five rules; returns the removed (g, a, b)."""
    ids = list(state.strips)
    if not ids:
        return []
    k = int(rng.integers(1, 1 + min(len(ids), 4)))
    rule = int(rng.integers(5))
    prob = state.prob
    if rule == 1:  # least marginal contribution (randomised)
        loss = np.array([state.loss(i) for i in ids])
        p = 1.0 / (1e-6 + loss / max(loss.max(), 1e-12))
        pick = rng.choice(len(ids), size=k, replace=False, p=p / p.sum())
        chosen = [ids[j] for j in pick]
    elif rule == 2:  # one region's strips
        r = int(rng.integers(len(prob.region_min)))
        mine = [i for i in ids if np.any(prob.region[state.strip_samples[i]] == r)]
        chosen = list(rng.permutation(mine)[:k]) if mine else [ids[int(rng.integers(len(ids)))]]
    elif rule == 3:  # one satellite's strips near one of them
        i0 = ids[int(rng.integers(len(ids)))]
        sat = int(prob.group_sat[state.strips[i0][0]])
        lst = state.by_sat[sat]
        j = lst.index(i0)
        chosen = lst[max(0, j - k // 2) : j - k // 2 + k] or [i0]
    elif rule == 4:  # the strips sharing most samples with a random one
        i0 = ids[int(rng.integers(len(ids)))]
        s0 = state.strip_samples[i0]
        share = [
            (len(np.intersect1d(s0, state.strip_samples[i], assume_unique=True)), i) for i in ids
        ]
        share.sort(reverse=True)
        chosen = [i for _, i in share[:k]]
    else:
        chosen = [ids[j] for j in rng.choice(len(ids), size=k, replace=False)]
    removed = []
    for i in chosen:
        removed.append(state.strips[i])
        state.remove(i)
    return removed


def local_moves(state: PlanState, passes: np.ndarray, roll_order: np.ndarray, nb: int) -> int:
    """One round of first-improvement local moves over all strips.

    For each strip: its group replaced by one of the ``nb`` nearest-roll groups on each
    side in the same pass (same slots, then cut to fit), or one end moved by one slot.
    A move is kept when the exact gain exceeds the strip's loss.

    Args:
      state: PlanState, modified in place.
      passes: int [G] pass of each group; roll_order: int [G] groups sorted by (pass,
        roll); nb: neighbours per side.
    Returns:
      number of moves kept.
    """
    pos = np.empty_like(roll_order)
    pos[roll_order] = np.arange(roll_order.size)
    kept = 0
    for sid in sorted(state.strips):
        if sid not in state.strips:
            continue
        g, a, b = state.strips[sid]
        base = state.loss(sid)
        state.remove(sid)
        options = [(g, a - 1, b), (g, a + 1, b), (g, a, b + 1), (g, a, b - 1)]
        p0 = pos[g]
        for d in range(-nb, nb + 1):
            j = p0 + d
            if d and 0 <= j < roll_order.size and passes[roll_order[j]] == passes[g]:
                options.append((int(roll_order[j]), a, b))
        best, best_gain = (g, a, b), base + 1e-12
        for og, oa, ob in options:
            fit = state.fit(og, oa, ob)
            if fit is None:
                continue
            gain = state.gain(og, *fit)
            if gain > best_gain and state.resources_ok(og, *fit)[0]:
                best, best_gain = (og, *fit), gain
        state.add(*best)
        kept += best != (g, a, b)
    return kept


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

    The pass's strips are removed, :func:`jaxspline.regional.passdp.best_runs` picks the
    runs of best open value (at most as many as the removed ones plus the unused actions;
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
    others = bool(state.by_sat[sat])
    for k, g in enumerate(groups):
        s0, n, r0 = int(prob.group_slot0[g]), int(prob.group_nslots[g]), int(prob.group_row0[g])
        vals[k, s0 - p0 : s0 - p0 + n] = state.row_gain[r0 : r0 + n]
        if others:
            for lo, hi in state.free_slots(int(g), lo=s0, hi=s0 + n):
                allowed[k, max(lo, s0) - p0 : min(hi, s0 + n) - p0] = True
        else:
            allowed[k, s0 - p0 : s0 - p0 + n] = True
    rmax = len(mine) + prob.max_actions - state.n_actions()
    _, runs = best_runs(
        vals,
        allowed,
        index.gaps(p),
        prob.min_slots(sat),
        prob.max_slots(sat),
        min(rmax, MAX_RUNS_PER_PASS),
        price=MIN_GAIN,
    )
    added = 0
    for k, s, t in runs:
        g = int(groups[k])
        ok, low = state.resources_ok(g, p0 + s, p0 + t)
        if ok and state.fit(g, p0 + s, p0 + t) == (p0 + s, p0 + t):
            state.add(g, p0 + s, p0 + t, low=low)
            added += 1
    return added


def lns(
    state: PlanState,
    win: Windows,
    deadline: float,
    config: SearchConfig = SearchConfig(),
    log=None,
) -> tuple[PlanState, dict]:
    """Improve a plan by destroy-and-repair until the deadline.

    Args:
      state: PlanState (the start; not modified).
      win: Windows.
      deadline: ``time.perf_counter()`` instant to stop at.
      config: SearchConfig.
      log: optional callable(str) for progress lines.
    Returns:
      (best PlanState, stats dict: iterations, accepted, improved, local moves).
    """
    rng = np.random.default_rng(config.seed)
    prob = state.prob
    passes = group_passes(prob)
    roll_order = np.lexsort((prob.group_roll, passes))
    index = PassIndex(prob)
    cur, best = state.copy(), state.copy()
    stats = {"iterations": 0, "accepted": 0, "improved": 0, "local_moves": 0, "pass_moves": 0}
    last_log = time.perf_counter()
    while time.perf_counter() < deadline:
        it = stats["iterations"] = stats["iterations"] + 1
        trial = cur.copy()
        if rng.random() < config.pass_prob:
            ow = index.open_weight(trial) + 1e-9
            p = int(rng.choice(ow.size, p=ow / ow.sum()))
            reopt_pass(trial, index, p)
            greedy_fill(trial, win, deadline)
            stats["pass_moves"] += 1
        else:
            removed = _destroy(trial, rng, passes)
            banned = {g for g, _, _ in removed} if rng.random() < config.ban_prob else None
            greedy_fill(trial, win, deadline, banned=banned)
            if banned:
                greedy_fill(trial, win, deadline)
        if it % config.local_every == 0:
            stats["local_moves"] += local_moves(trial, passes, roll_order, config.roll_neighbours)
        if it % config.refresh_every == 0:
            trial.refresh_gains()
        if trial.score() >= cur.score():
            stats["accepted"] += 1
            cur = trial
            if cur.score() > best.score():
                stats["improved"] += 1
                best = cur.copy()
        if log is not None and time.perf_counter() - last_log > 10.0:
            last_log = time.perf_counter()
            log(
                f"  lns it {it}: best {best.value:.5f} ({best.n_actions()} strips), "
                f"current {cur.value:.5f}"
            )
    return best, stats
