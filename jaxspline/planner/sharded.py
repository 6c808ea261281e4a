"""The Lagrangian bound and the plan search, sharded by satellite across processes.

**Bound.** Under target prices the bound splits into one longest-path DP per satellite
(:mod:`jaxspline.search.lagrangian`). Here every process owns some satellites:
it screens and stores only their options and near pairs (its own
:class:`jaxspline.search.Problem`, so memory is split too) and solves only their
DPs. Once per iteration the processes exchange one float64 vector through
``jax.distributed`` (:func:`jax.experimental.multihost_utils.process_allgather`):

    [DP value of every satellite (0 where not owned) | takers per target | stop flag]

Owned values are combined by satellite (adding exact zeros) and summed in satellite
order, takers are integers, so every process holds the same bound and subgradient as
a single process would and takes the same projected Polyak step: the prices, the bound
and the iteration count equal :func:`jaxspline.search.upper_bound` (battery
relaxed) bit for bit. A process that reaches its deadline raises the stop flag; all
stop together at the end of that iteration (no process waits for a missing peer).

**Plan** (:func:`sharded_plan`). After the bound phase every process holds the same
best prices. The merge rule gives every target exactly one owner process
(:func:`target_owners`, computed identically everywhere from one all-gather of two
per-target vectors): the process whose satellites' DP paths at the best prices take the
target most often; among equals the one holding most of the target's options; then the
lowest index. Each process then runs the ordinary search
(:func:`jaxspline.search.solve`: greedy, Lagrangian with repaired plans, LNS,
earliest pass) on its problem restricted to the targets it owns
(:func:`restrict_targets`). A target that no process imaged is handed to the best other
process by the same rule (when that one has options of it), which inserts it in a
second round (greedy, then LNS on :data:`_SECOND_SHARE` of the budget) on its plan
restricted to its new set of targets. Each process optionally checks its plan
(``check``), and one more all-gather of a per-target vector (satellite, option, start,
end) merges the plans. The processes' plans are disjoint in satellites and in targets,
every transition is between two observations of one satellite, the battery is per
satellite: their union is a plan of the whole scenario that images each target at most
once, valid wherever each part is, of value the sum of the parts. Its value can be
below a single process's plan (a target is only tried on the satellites of its owner
and then of one other process, and no move exchanges targets across processes); the
bound is the single-process one.

Satellite ``k`` belongs to process ``k % process_count``.
"""

from __future__ import annotations

import math
import random
import resource
import time
from typing import NamedTuple

import numpy as np

from jaxspline.base import clock
from jaxspline.search import Timeline, greedy, lns, solve
from jaxspline.search.dp import dp_paths
from jaxspline.search.lagrangian import BOUND_MU_MIN, BoundResult, Prices
from jaxspline.search.problem import Problem
from jaxspline.search.status import BoundStatus
from jaxspline.search.store import NearPairs

__all__ = [
    "ShardedPlan",
    "jax_allgather",
    "owned_satellites",
    "restrict_targets",
    "sharded_plan",
    "sharded_upper_bound",
    "target_owners",
]

# per-process figures gathered with the plans (ShardedPlan.processes); the real-valued ones
_STATS = (
    "tasks",
    "handed_in",
    "searched",
    "dropped",
    "lns_iterations",
    "options",
    "near_pairs",
    "peak_rss_mb",
)
_REAL_STATS = ("searched", "peak_rss_mb")
_SECOND_SHARE = 0.25  # share of the search budget (time, LNS iterations) of the second round


def owned_satellites(n_sats: int, index: int, count: int) -> list[int]:
    """Satellites of process ``index`` among ``count``: ``k % count == index``.

    Args:
      n_sats: number of satellites of the scenario.
      index: this process (0-based).
      count: number of processes.
    Returns:
      sorted list of satellite indices (possibly empty).
    """
    if not (0 <= index < count):
        raise ValueError(f"process index {index!r} outside [0, {count})")
    return list(range(index, n_sats, count))


def jax_allgather(x: np.ndarray) -> np.ndarray:
    """[P, ...] stack of every process's ``x`` (jax.distributed must be initialized).

    Args:
      x: this process's array (the same shape in every process).
    Returns:
      float64 [P, ...], row p from process p.
    """
    from jax.experimental import multihost_utils

    return np.asarray(multihost_utils.process_allgather(np.asarray(x)), np.float64)


class _ShardPrices(Prices):
    """:class:`Prices` whose DP covers the owned satellites and whose totals are gathered."""

    def __init__(self, pb: Problem, sat_ids, n_sats: int, allgather):
        super().__init__(pb, energy=False, merge_repeats=True, mu_min=BOUND_MU_MIN,
                         price_cap=False)  # fmt: skip
        self.sat_ids = np.asarray(sat_ids, np.int64)
        self.n_sats = int(n_sats)
        self.allgather = allgather
        self.stop = False

    def solve_dp(self, want_stop: bool = False):
        self.it += 1
        n_tg = self.target_value.size
        w = self.target_value[self.option_target] - self.lam[self.option_target]
        paths, vals = dp_paths(self.pb, self.d, w, merge_repeats=True)
        local = np.zeros(self.n_sats + n_tg + 1)
        local[self.sat_ids] = vals
        local[self.n_sats : -1] = self._takers(paths)
        local[-1] = float(want_stop)
        every = self.allgather(local)
        vals_all = every[:, : self.n_sats].sum(axis=0)  # one owner each: exact
        self.cnt = every[:, self.n_sats : -1].sum(axis=0)
        self.stop = bool(every[:, -1].max() > 0.0)
        self._record(vals_all.tolist(), paths)
        return paths

    def _subgradient(self) -> np.ndarray:
        return self.cnt - 1.0


def _iterate(pb, sat_ids, n_sats, plan_value, deadline, max_iters, allgather):
    """The sharded subgradient iteration; returns (prices state, BoundResult)."""
    if len(sat_ids) != pb.n_sats:
        raise ValueError(f"sat_ids has {len(sat_ids)} entries for {pb.n_sats} satellites")
    pr = _ShardPrices(pb, sat_ids, n_sats, allgather)
    status = BoundStatus.TIME
    while max_iters is None or pr.it < max_iters:
        pr.solve_dp(want_stop=not clock.now() < deadline)
        if pr.stop:
            break
        if not pr.step(plan_value):
            status = BoundStatus.CONVERGED
            break
    ub = pr.ub if pr.it else math.inf
    return pr, BoundResult([], ub, pr.it, status)


def sharded_upper_bound(
    pb: Problem,
    sat_ids,
    n_sats: int,
    plan_value: float,
    deadline: float,
    max_iters=None,
    allgather=jax_allgather,
) -> BoundResult:
    """The Lagrangian bound (battery relaxed) of a scenario whose satellites are sharded.

    Every process calls it with its own problem; all return the same result.

    Args:
      pb: this process's Problem (its satellites only, all the scenario's targets).
      sat_ids: the scenario-wide index of each of ``pb``'s satellites.
      n_sats: satellites of the whole scenario.
      plan_value: a value some plan reaches (sets the step size only; any value gives a
        bound);
        must be the same in every process.
      deadline: ``time.monotonic()`` value at which this process asks to stop [s].
      max_iters: cap on the iterations (None: the deadlines alone).
      allgather: callable ``x [L] -> [P, L]`` over the processes (default: through
        ``jax.distributed``); a single process passes ``lambda x: x[None]``.
    Returns:
      BoundResult (``best`` empty), status ``CONVERGED`` or ``TIME``.
    """
    return _iterate(pb, sat_ids, n_sats, plan_value, deadline, max_iters, allgather)[1]


def target_owners(takes, options) -> np.ndarray:
    """The merge rule: the one process that may image each target.

    For each target, the process with the most DP paths taking it at the best prices;
    among equals the one with the most options of the target; then the lowest index.

    Args:
      takes: [P, T] per process, the number of its satellites' DP paths that take
        each target at the best prices.
      options: [P, T] per process, its options of each target.
    Returns:
      int64 [T], the owner process of each target.
    """
    takes = np.asarray(takes, np.float64)
    options = np.asarray(options, np.float64)
    if takes.ndim != 2 or takes.shape != options.shape or not takes.shape[0]:
        raise ValueError(
            f"takes {takes.shape} and options {options.shape} must be one [P, T] shape, P >= 1"
        )
    best = takes == takes.max(axis=0)
    opts = np.where(best, options, -1.0)
    best &= opts == opts.max(axis=0)
    return np.argmax(best, axis=0).astype(np.int64)  # the first True: lowest index


def restrict_targets(pb: Problem, keep) -> tuple[Problem, np.ndarray]:
    """``pb`` with only the options of the kept targets (the others keep no option).

    Targets keep their indices and values; options keep their order (satellite, then
    start), data and near pairs among themselves. A plan of the result is a plan of
    ``pb`` (through ``ids``) that images kept targets only.

    Args:
      pb: Problem.
      keep: bool [T], the targets to keep.
    Returns:
      (Problem, ids): the restricted problem and int64 [N'] the ``pb`` option id of
      each of its options (ascending).
    """
    keep = np.asarray(keep, bool)
    if keep.shape != (pb.n_targets,):
        raise ValueError(
            f"keep has shape {keep.shape}, expected one flag a target ({pb.n_targets},)"
        )
    on = keep[np.asarray(pb.option_target, np.int64)] if pb.n_options else np.zeros(0, bool)
    ids = np.flatnonzero(on)
    new = np.full(pb.n_options, -1, np.int64)
    new[ids] = np.arange(ids.size)
    p = pb.pairs
    row_on = on[p.rows]
    pair_on = on[p.src] & np.repeat(row_on, np.diff(p.ptr))
    kept = np.r_[0, np.cumsum(pair_on)]
    per_row = (kept[p.ptr[1:]] - kept[p.ptr[:-1]])[row_on]
    del kept
    pairs = NearPairs(
        np.r_[0, np.cumsum(per_row)], new[p.src[pair_on]], p.need[pair_on], new[p.rows[row_on]]
    )
    sat = np.asarray(pb.option_sat, np.int64)[ids]
    lo = np.searchsorted(sat, np.arange(pb.n_sats), side="left").tolist()
    hi = np.searchsorted(sat, np.arange(pb.n_sats), side="right").tolist()
    sel = ids.tolist()
    starts = [pb.option_start[c] for c in sel]
    newl = new.tolist()
    sub = Problem(
        n_sats=pb.n_sats,
        target_value=list(pb.target_value),
        option_target=[pb.option_target[c] for c in sel],
        option_sat=sat.tolist(),
        option_start=starts,
        option_end=[pb.option_end[c] for c in sel],
        option_first=[pb.option_first[c] for c in sel],
        option_start_los=[pb.option_start_los[c] for c in sel],
        option_end_los=[pb.option_end_los[c] for c in sel],
        tables=list(pb.tables),
        pairs=pairs,
        far=list(pb.far),
        battery=pb.battery,
        target_options=[
            [newl[c] for c in opts] if keep[t] else [] for t, opts in enumerate(pb.target_options)
        ],
        sat_lo=lo,
        sat_hi=hi,
        sat_starts=[starts[a:b] for a, b in zip(lo, hi, strict=True)],
        near_slack=pb.near_slack,
        lookup=list(pb.lookup),
    )
    return sub, ids


class ShardedPlan(NamedTuple):
    """Outcome of :func:`sharded_plan`, the same in every process.

    Attributes:
      bound: BoundResult of the sharded bound phase (``best`` empty).
      owner: int64 [T], the process allowed to image each target (after the hand-over).
      sat: int64 [T], the scenario-wide satellite imaging each target (-1: none).
      option: int64 [T], that option's index among its satellite's options in start
        order (the planner's option table of that satellite; -1: none).
      start, end: float64 [T], its imaging interval [s] (nan: none).
      value: total value of the merged plan.
      processes: per process a dict: ``tasks`` (owned targets with options there),
        ``handed_in`` (targets received in the second round), ``searched`` (value of its
        plan before ``check``), ``dropped`` (observations ``check`` removed),
        ``lns_iterations`` (both rounds), ``options`` and ``near_pairs`` (of its first
        restricted problem), ``peak_rss_mb`` (before the merge).
    """

    bound: BoundResult
    owner: np.ndarray
    sat: np.ndarray
    option: np.ndarray
    start: np.ndarray
    end: np.ndarray
    value: float
    processes: list


def sharded_plan(
    pb: Problem,
    sat_ids,
    n_sats: int,
    index: int,
    plan_value: float,
    bound_deadline: float,
    search_time: float,
    *,
    bound_iters: int | None = None,
    search_iters: int | None = None,
    seed: int = 0,
    lagrangian_share: float = 0.3,
    exact_max_options: int = 0,
    check=None,
    allgather=jax_allgather,
) -> ShardedPlan:
    """Bound, owners, per-process search and merged plan (module docstring).

    Every process calls it with its own problem and the same other arguments (except
    ``index``); all return the same result. After the bound phase come three
    all-gathers: the owner rule's inputs, the first round's imaged targets (more than
    one process) and the plans; each process searches alone in between.

    Args:
      pb: this process's Problem (its satellites only, all the scenario's targets).
      sat_ids: the scenario-wide index of each of ``pb``'s satellites.
      n_sats: satellites of the whole scenario.
      index: this process's row in ``allgather``'s result.
      plan_value: sets the step size of the bound (as :func:`sharded_upper_bound`).
      bound_deadline: ``time.monotonic()`` value at which the bound phase stops [s].
      search_time: budget of this process's search after the bound phase [s]
        (``inf`` with ``search_iters``).
      bound_iters: cap on the bound iterations (None: ``bound_deadline`` alone).
      search_iters: cap of the search (``max_iters`` of
        :func:`jaxspline.search.solve` in the first round, a quarter of it for
        the second round's LNS; None: ``search_time`` alone). With both caps the
        result is a function of the inputs alone.
      seed: seed of every process's search.
      lagrangian_share, exact_max_options: as :func:`jaxspline.search.solve`.
      check: optional callable ``option ids of pb -> the ids that pass``, run on this
        process's plan before the merge (e.g. the independent check, dropping
        violations); None: the search's plan as it is.
      allgather: callable ``x [L] -> [P, L]`` over the processes.
    Returns:
      ShardedPlan.
    """
    if not search_time >= 0:  # nan and negatives out; +inf with search_iters
        raise ValueError(f"search_time must be a number of seconds >= 0, got {search_time!r}")
    pr, bound = _iterate(pb, sat_ids, n_sats, plan_value, bound_deadline, bound_iters, allgather)
    takes, options = _owner_inputs(pb, pr, index, allgather)
    owner = target_owners(takes, options)
    first_end, search_end = _search_ends(search_time, search_iters, takes.shape[0])
    budget = _Budget(seed, lagrangian_share, exact_max_options, search_iters)
    sub, ids = restrict_targets(pb, owner == index)  # first round: the targets it owns
    chosen, its = _first_round(sub, ids, first_end, budget)
    owner, chosen, handed, its2 = _hand_over_round(
        pb, chosen, _Owners(owner, takes, options), index, search_end, budget, allgather
    )
    searched = float(pr.target_value[[pb.option_target[c] for c in chosen]].sum())
    kept = chosen if check is None else [int(c) for c in check(chosen)]
    local = _plan_rows(pb, kept, sat_ids, pr.target_value.size)
    rss = round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)  # Linux: KiB
    targets = sum(1 for t in range(pr.target_value.size) if sub.target_options[t])
    stats = [targets, handed, searched, len(chosen) - len(kept), its + its2, sub.n_options]
    stats += [len(sub.pairs), rss]
    every = allgather(np.r_[local.ravel(), stats])
    return _merge(every, owner, pr.target_value, bound)


class _Budget(NamedTuple):
    """The search settings every round shares: the ``seed``, the Lagrangian share and
    exact-solve threshold of :func:`jaxspline.search.solve`, and the iteration cap
    ``iters`` of the first round (None: the clock alone)."""

    seed: int
    lagrangian_share: float
    exact_max_options: int
    iters: int | None


class _Owners(NamedTuple):
    """The owner rule's state: ``owner`` int64 [T] (the process of each target) and its
    gathered inputs ``takes``, ``options`` [P, T] (:func:`target_owners`)."""

    owner: np.ndarray
    takes: np.ndarray
    options: np.ndarray


def _owner_inputs(pb: Problem, pr: _ShardPrices, index: int, allgather):
    """Gather the owner rule's inputs from every process: per target, how many of its
    satellites' DP paths take the target at the best prices and how many options it has.
    Returns (takes, options), each float64 [P, T]; ValueError when ``index`` is not
    one of the P processes."""
    n_tg = pr.target_value.size
    paths, _ = dp_paths(pb, pr.d, pr.target_value[pr.option_target] - pr.best_lam[pr.option_target])
    opts = np.bincount(pr.option_target, minlength=n_tg).astype(np.float64)
    every = allgather(np.r_[pr._takers(paths), opts])
    n_p = every.shape[0]
    if not (0 <= index < n_p):
        raise ValueError(f"index {index!r} outside the {n_p} processes")
    return every[:, :n_tg], every[:, n_tg:]


def _search_ends(search_time: float, search_iters, n_p: int) -> tuple[float, float]:
    """The deadlines ``(first round, whole search)`` as ``time.monotonic()`` values [s]:
    the first round leaves :data:`_SECOND_SHARE` of ``search_time`` to the second when
    there is more than one process; both infinite with an iteration cap (the clock does
    not cut, as :func:`jaxspline.search.solve`)."""
    if search_iters is not None:
        return math.inf, math.inf
    t0 = time.monotonic()
    return t0 + (1.0 - _SECOND_SHARE * (n_p > 1)) * search_time, t0 + search_time


def _first_round(sub: Problem, ids: np.ndarray, deadline: float, budget: _Budget):
    """The ordinary search (:func:`jaxspline.search.solve`) on ``sub``, this process's
    problem restricted to the targets it owns (``ids``: ``pb``'s id of each option of
    ``sub``). Returns (its plan as option ids of ``pb``, its LNS iterations)."""
    res = solve(
        sub,
        deadline,
        seed=budget.seed,
        lagrangian_share=budget.lagrangian_share,
        exact_max_options=budget.exact_max_options,
        max_iters=budget.iters,
    )
    return [int(ids[c]) for c in res.timeline.assigned if c >= 0], res.stats["lns_iterations"]


def _hand_over_round(pb, chosen, own: _Owners, index, deadline, budget: _Budget, allgather):
    """With more than one process: gather which targets the first round imaged anywhere,
    hand every target left out to the best other process (:func:`_hand_over`), and when
    this process received some, insert them in its plan (:func:`_second_round`).
    Returns (owners after the hand-over, the plan as option ids of ``pb``, the targets
    handed in, the second round's LNS iterations); a single process keeps its owners
    and plan."""
    if own.takes.shape[0] == 1:
        return own.owner, chosen, 0, 0
    imaged = np.zeros(own.owner.size)
    imaged[[pb.option_target[c] for c in chosen]] = 1.0
    left = allgather(imaged).sum(axis=0) == 0.0
    owner = _hand_over(own.owner, left, own.takes, own.options)
    handed = int(((owner == index) & (own.owner != index)).sum())
    if not handed:
        return owner, chosen, 0, 0
    chosen, its = _second_round(pb, chosen, owner == index, deadline, budget.iters, budget.seed)
    return owner, chosen, handed, its


def _plan_rows(pb: Problem, kept, sat_ids, n_tg: int) -> np.ndarray:
    """This process's plan as the per-target rows the merge gathers: float64 [4, T] of
    (scenario-wide satellite, option index among that satellite's options, start,
    end) for each target of an option in ``kept`` (-1, -1, nan, nan elsewhere)."""
    local = np.full((4, n_tg), -1.0)
    local[2:] = np.nan
    for c in kept:
        k = pb.option_sat[c]
        local[:, pb.option_target[c]] = (
            sat_ids[k],
            c - pb.sat_lo[k],
            pb.option_start[c],
            pb.option_end[c],
        )
    return local


def _hand_over(owner, left, takes, options) -> np.ndarray:
    """Owners after the first round: a target its owner left out goes to the best other
    process by :func:`target_owners` when that process has options of it."""
    n_p, n_tg = takes.shape
    other = owner[None] != np.arange(n_p)[:, None]
    nxt = target_owners(np.where(other, takes, -1.0), np.where(other, options, -1.0))
    go = left & (options[nxt, np.arange(n_tg)] > 0.0)
    return np.where(go, nxt, owner)


def _second_round(pb, chosen, keep, deadline, search_iters, seed):
    """The first round's plan (``pb`` option ids) on the targets ``keep``, then a greedy
    pass and a short LNS; returns (option ids of ``pb``, LNS iterations)."""
    sub, ids = restrict_targets(pb, keep)
    tl = Timeline(sub)
    at = np.minimum(np.searchsorted(ids, chosen), max(ids.size - 1, 0)).astype(np.int64)
    if len(chosen) and not np.array_equal(ids[at], chosen):
        raise RuntimeError("the second round lost a target of the first round's plan")
    assigned = [-1] * pb.n_targets
    for c, a in zip(chosen, at.tolist(), strict=True):
        assigned[pb.option_target[c]] = a
    tl.restore(assigned)
    greedy(tl, math.inf)  # complete, as the first greedy of solve
    iters = None if search_iters is None else int(_SECOND_SHARE * search_iters)
    its = lns(tl, deadline, random.Random(seed), iters)
    return [int(ids[c]) for c in tl.assigned if c >= 0], its


def _merge(every, owner, target_value, bound) -> ShardedPlan:
    """The merged plan from the gathered per-target vectors (see :func:`sharded_plan`)."""
    n_p, n_tg = every.shape[0], target_value.size
    per = every[:, : 4 * n_tg].reshape(n_p, 4, n_tg)
    taken = per[:, 0] >= 0.0
    if (taken & (owner[None] != np.arange(n_p)[:, None])).any():
        raise RuntimeError("a process imaged a target it does not own: the merge rule is broken")
    pick = per[owner, :, np.arange(n_tg)]  # [T, 4]: the owner's row of each target
    sat = pick[:, 0].astype(np.int64)
    processes = []
    for row in every[:, 4 * n_tg :].tolist():
        st = dict(zip(_STATS, row, strict=True))
        processes.append({k: v if k in _REAL_STATS else int(v) for k, v in st.items()})
    return ShardedPlan(
        bound=bound,
        owner=owner,
        sat=sat,
        option=pick[:, 1].astype(np.int64),
        start=pick[:, 2].copy(),
        end=pick[:, 3].copy(),
        value=float(target_value[sat >= 0].sum()),
        processes=processes,
    )
