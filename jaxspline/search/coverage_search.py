"""Coverage search: lazy greedy by marginal gain, then large-neighbourhood search.

* :func:`candidate_windows`: per group, the window of its non-empty slots (clipped to the
  maximum strip duration: longer groups give every max-length window, one slot apart).
* :func:`greedy_fill`: CELF lazy greedy. A window's open gain is bounded above by prefix
  sums of the state's per-row open gains (rows of slots under or next to a strip of the
  same satellite count 0: no piece that fits can use them, :meth:`PlanState.open_rows`);
  the top of the heap is re-evaluated exactly
  (after :meth:`PlanState.fit` cuts it to the satellite's free time) and taken when it
  still beats the next bound. Taken strips are trimmed to the shortest window of the same
  gain; strips with no gain are never taken (ties go to fewer actions).
* :func:`lns`: until the deadline, one move per iteration on a copy of the current plan:
  re-plan the passes able to cover one open sample (:func:`reopt_related`), re-plan one
  pass (:func:`reopt_pass`), or destroy a few strips (random, least marginal contribution,
  one region's, one satellite's, the strips overlapping a random one) and repair with the
  greedy (the removed groups banned half the time); every ``local_every`` iterations
  local moves (a strip's roll moved to a neighbouring group of its pass, an end moved by
  one slot). A trial replaces the current plan when it is not worse (:func:`better`:
  shortfall, coverage, fewer actions, higher battery minimum); the best is kept.
* :func:`meet_minimums`: while a region misses its minimum coverage, the same search on
  weights raised for the regions with a minimum (:func:`boosted`).

Deterministic for a given seed and for a given number of iterations (the deadline stops
the loop between iterations).
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass

import numpy as np

from jaxspline.search.coverage_passmoves import PassIndex, reopt_pass, reopt_related
from jaxspline.search.coverage_problem import CoverProblem, group_passes, strip_rows
from jaxspline.search.coverage_state import PlanState, better

__all__ = [
    "SearchConfig",
    "Windows",
    "candidate_windows",
    "greedy_fill",
    "boosted",
    "lns",
    "local_moves",
    "meet_minimums",
]

#: Gains at or below this count as zero (coverage_ratio units).
MIN_GAIN = 1e-10
#: Extra weight (per unit of region ratio) on regions with a minimum coverage while
#: any of them misses it.
MIN_BOOST = 10.0


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
      pass_prob: probability that an iteration re-plans one pass (:func:`reopt_pass`).
      related_prob: probability that it re-plans the passes related to an open sample
        (:func:`reopt_related`, at most ``related_most``); otherwise destroy and repair.
      temp0: start temperature of the acceptance (a worse trial is taken with probability
        ``exp(delta / T)``, ``T`` falling linearly to 0 at the deadline; 0 = only not worse).
    """

    seed: int = 0
    max_destroy: int = 4
    refresh_every: int = 100
    ban_prob: float = 0.5
    local_every: int = 50
    roll_neighbours: int = 3
    pass_prob: float = 0.2
    related_prob: float = 0.6
    related_most: int = 3
    temp0: float = 0.0


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
    need = state.timing.min_slots[int(state.prob.group_sat[g])]
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
    fails: dict | None = None,
) -> int:
    """Add strips by largest exact marginal gain until none gains or the cap is reached.

    Args:
      state: PlanState, modified in place.
      win: Windows.
      deadline: ``time.perf_counter()`` instant to stop at.
      banned: optional set of groups not to use.
      weights_bound: optional precomputed window bounds (else :func:`window_bounds`).
      fails: optional dict window -> satellite signature at which it did not fit (shared
        across calls: a window is skipped while its satellite's timeline is unchanged).
    Returns:
      number of strips added.
    """
    prob = state.prob
    if weights_bound is None:
        c0 = np.concatenate([[0.0], np.cumsum(state.open_rows())])
        ub = c0[win.r1] - c0[win.r0]
    else:
        ub = weights_bound
    cand = np.nonzero(ub > MIN_GAIN)[0]
    heap = list(zip((-ub[cand]).tolist(), cand.tolist(), strict=True))
    heapq.heapify(heap)
    cum = np.concatenate([[0.0], np.cumsum(state.open_rows())])
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
        sat = int(prob.group_sat[g])
        if fails is not None and i in fails and fails[i] == state.signature(sat):
            continue
        fit = state.fit(g, int(win.a[i]), int(win.b[i]))
        if fit is None:
            if fails is not None:
                fails[i] = state.signature(sat)
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
        cum = np.concatenate([[0.0], np.cumsum(state.open_rows())])
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


def boosted(prob: CoverProblem, factor: float = MIN_BOOST) -> CoverProblem:
    """The problem with the samples of regions that have a minimum coverage weighted up.

    Args:
      prob: CoverProblem; factor: extra weight per unit of region ratio.
    Returns:
      CoverProblem (the same object when no region has a minimum).
    """
    from dataclasses import replace

    has = np.isfinite(prob.region_min)
    if not has.any():
        return prob
    extra = np.where(has[prob.region], factor * prob.ratio_weight, 0.0)
    return replace(prob, weight=prob.weight + extra)


def meet_minimums(state: PlanState, win: Windows, deadline: float, config, log=None):
    """Search on :func:`boosted` weights until no region misses its minimum coverage.

    Args:
      state: PlanState (not modified); win: Windows; deadline: perf_counter instant;
      config: SearchConfig; log: optional callable(str).
    Returns:
      PlanState on the original problem holding the strips found (the start state when
      nothing misses its minimum).
    """
    if state.shortfall() <= 0:
        return state
    prob = state.prob
    boost = PlanState(boosted(prob), state.tr)
    for g, a, b in state.strips.values():
        boost.add(g, a, b)
    greedy_fill(boost, win, deadline)
    if boost.shortfall() > 0:
        boost, _ = lns(boost, win, deadline, config, log=log, stop=lambda b: b.shortfall() <= 0)
    out = PlanState(prob, state.tr)
    for g, a, b in boost.strips.values():
        out.add(g, a, b)
    greedy_fill(out, win, deadline)
    if log is not None:
        log(f"minimum coverage phase: shortfall {state.shortfall():.4f} -> {out.shortfall():.4f}")
    return out if better(out, state) else state


def _accept(trial: PlanState, cur: PlanState, temp0, t_begin, deadline, rng) -> bool:
    """Not worse (score), or worse in coverage by delta with probability exp(delta / T)."""
    if better(trial, cur, strict=False):
        return True
    a, b = trial.score(), cur.score()
    if temp0 <= 0 or a[0] < b[0]:
        return False
    frac = (deadline - time.perf_counter()) / max(deadline - t_begin, 1e-9)
    temp = temp0 * max(frac, 0.0)
    return temp > 0 and rng.random() < np.exp((trial.value - cur.value) / temp)


def lns(
    state: PlanState,
    win: Windows,
    deadline: float,
    config: SearchConfig = SearchConfig(),
    log=None,
    max_iter: int | None = None,
    stop=None,
) -> tuple[PlanState, dict]:
    """Improve a plan by destroy-and-repair until the deadline.

    Args:
      state: PlanState (the start; not modified).
      win: Windows.
      deadline: ``time.perf_counter()`` instant to stop at.
      config: SearchConfig.
      log: optional callable(str) for progress lines.
      max_iter: optional iteration cap (the run is then reproducible whatever the clock).
      stop: optional callable(best PlanState) -> bool, checked after every improvement.
    Returns:
      (best PlanState, stats dict: iterations, accepted, improved, moves by kind).
    """
    rng = np.random.default_rng(config.seed)
    prob = state.prob
    passes = group_passes(prob)
    roll_order = np.lexsort((prob.group_roll, passes))
    index = PassIndex(prob)
    cur, best = state.copy(), state.copy()
    stats = {
        "iterations": 0,
        "accepted": 0,
        "improved": 0,
        "local_moves": 0,
        "pass_moves": 0,
        "related_moves": 0,
    }
    last_log = time.perf_counter()
    t_begin = time.perf_counter()
    fails: dict = {}
    while time.perf_counter() < deadline and prob.n_groups:
        if max_iter is not None and stats["iterations"] >= max_iter:
            break
        it = stats["iterations"] = stats["iterations"] + 1
        trial = cur.copy()
        u = rng.random()
        if u < config.pass_prob:
            ow = index.open_weight(trial) + 1e-9
            p = int(rng.choice(ow.size, p=ow / ow.sum()))
            reopt_pass(trial, index, p)
            greedy_fill(trial, win, deadline, fails=fails)
            stats["pass_moves"] += 1
        elif u < config.pass_prob + config.related_prob:
            reopt_related(trial, index, rng, config.related_most)
            greedy_fill(trial, win, deadline, fails=fails)
            stats["related_moves"] += 1
        else:
            removed = _destroy(trial, rng, passes)
            banned = {g for g, _, _ in removed} if rng.random() < config.ban_prob else None
            greedy_fill(trial, win, deadline, banned=banned, fails=fails)
            if banned:
                greedy_fill(trial, win, deadline, fails=fails)
        if it % config.local_every == 0:
            stats["local_moves"] += local_moves(trial, passes, roll_order, config.roll_neighbours)
        if it % config.refresh_every == 0:
            trial.refresh_gains()
        if _accept(trial, cur, config.temp0, t_begin, deadline, rng):
            stats["accepted"] += 1
            cur = trial
            if better(cur, best):
                stats["improved"] += 1
                best = cur.copy()
                if stop is not None and stop(best):
                    break
        if log is not None and time.perf_counter() - last_log > 10.0:
            last_log = time.perf_counter()
            log(
                f"  lns it {it}: best {best.value:.5f} ({best.n_actions()} strips), "
                f"current {cur.value:.5f}"
            )
    return best, stats
