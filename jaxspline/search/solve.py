""":func:`solve` runs the stages on a :class:`Problem` until a deadline:

1. the start: satellite sweeps (:func:`sweeps`) from the empty plan, each round giving
   every satellite its best DP path over the targets the others leave it, then a greedy
   fill (:func:`greedy`) of what the paths left; the fill is always completed, even
   past the deadline. When the battery binds on most satellites, a greedy by value per
   Wh (:class:`EnergyRank`, :data:`_PER_WH_SHARE`) is built too and the better plan
   kept (built by the worker, below, when it publishes plans). A caller's ``retime``
   then sets the deadline from the start's size. The start beats a greedy by value
   alone: constellation day 86,839 in 12 s against 81,770 in 8.6 s; unseen 12 x 12 h
   41,388 in 6 s against 34,133 in 2 s;
2. Lagrangian phase (``lagrangian_share`` of the budget): per-satellite exact DP under
   target prices, repaired plans, and the upper bound (:func:`lagrangian`); left out
   when a bound worker that publishes plans runs (below);
3. satellite sweeps from the plan so far, while they gain;
   exact branch and bound when the instance is tiny (``exact_max_options``);
4. large-neighbourhood search until the deadline (:func:`lns`);
5. earliest-start pass (:func:`earliest_pass`).

With ``bound_worker``, a forked process iterates the bound alone over the whole search
budget (:class:`BoundWorker`, sharing the DP layout the Lagrangian phase uses) and the
smaller of the two bounds is reported. Without ``max_iters`` the worker also repairs its
DP paths into plans now and then, so it does all the phase would do, on the other CPU:
the phase is left out and the LNS starts at once from the start; it continues
from a worker's plan whenever that beats the LNS's best (``stats.worker_plans``: how
many were taken); the last one is looked at once more before the earliest-start pass.
Such a worker also builds the value-per-Wh greedy start itself, first. Every stage
uses the one DP layout the start prepared (:func:`jaxspline.search.dp.dp_prepare`; the
worker's fork shares it copy-on-write).
Once its bound converged, the worker runs an LNS of its own and publishes its plans the
same way (:class:`BoundWorker`).
"""

from __future__ import annotations

import math
import random
import time
from dataclasses import dataclass
from typing import NamedTuple

from jaxspline.base import clock
from jaxspline.search.bound_worker import BoundWorker
from jaxspline.search.dp import dp_prepare
from jaxspline.search.exact import exact_search
from jaxspline.search.lagrangian import BoundResult, lagrangian
from jaxspline.search.lns import adopt, earliest_pass, greedy, greedy_order, lns, plan_ceiling
from jaxspline.search.lns_energy import EnergyRank
from jaxspline.search.memory import trim_heap
from jaxspline.search.problem import Problem
from jaxspline.search.status import BoundStatus
from jaxspline.search.stereo import add_backups
from jaxspline.search.sweep import sweeps
from jaxspline.search.timeline import Timeline

__all__ = ["SearchResult", "solve"]

_EARLIEST_SHARE = 0.05  # share of the budget reserved for the earliest-start pass
_EARLIEST_MAX = 2.0  # ... at most this many seconds
_EXACT_SHARE = 0.5  # share of the remaining budget the exact search may use
_EXACT_MAX_S = 60.0  # [s] budget cap of the exact search when the deadline is +inf
_OPTIMAL_TOL = 1e-9  # relative bound - plan below which the plan is optimal
_WORKER_ITERS = 3  # the bound worker's iteration cap, in Lagrangian-phase caps
#: the value-per-Wh greedy start is built when the battery binds on at least this share
#: of the satellites: it reorders every target, so where most satellites have energy to
#: spare it loses (constellation day, 8 of 24 binding: 64,471 against 81,770; unseen
#: 12 x 12 h, 4 of 12: 22,094 against 34,133)
_PER_WH_SHARE = 0.5


@dataclass
class SearchResult:
    """Outcome of :func:`solve`.

    Attributes:
      timeline: the final :class:`Timeline` (the plan).
      bound: Lagrangian upper bound of the option model (battery relaxed).
      bound_status: :class:`BoundStatus` of the bound (see :class:`BoundResult`).
      exact: True when the exact search proved the plan optimal (tiny instances).
      stats: per-stage values and iteration counts.
    """

    timeline: Timeline
    bound: float
    bound_status: BoundStatus
    exact: bool
    stats: dict


def solve(
    pb: Problem,
    deadline: float,
    *,
    seed: int = 0,
    lagrangian_share: float = 0.3,
    exact_max_options: int = 0,
    max_iters: int | None = None,
    bound_worker: bool = False,
    report=None,
    retime=None,
) -> SearchResult:
    """Run the search stages (module docstring) until ``deadline``.

    Args:
      pb: Problem.
      deadline: float, ``time.monotonic()`` value at which to stop [s].
      seed: int, seed of the randomized stages.
      lagrangian_share: float in [0, 1], share of the time budget given to the
        Lagrangian phase.
      exact_max_options: int, run the exact search when the problem has at most this
        many options (0: never).
      max_iters: caps the LNS iterations and (at 1/10) the Lagrangian iterations;
        the stages then run to their caps and the deadline no longer cuts them (only
        a stop request does, :mod:`jaxspline.base.clock`), so the plan is a
        function of the problem, ``seed`` and ``max_iters`` alone. None: the deadline
        alone.
      report: callable ``report(stage, message)`` receiving progress lines, or None.
      retime: optional callable ``retime(per_sat) -> deadline``, called once when the
        start is built (time-bound runs only) with its number of observations
        per satellite: the search runs until the deadline it returns (the caller's
        reserve for the later stages, re-estimated from the plan's size).
    Returns:
      SearchResult.
    """
    say = report or (lambda stage, msg: None)
    if max_iters is not None:  # iteration-bound: reproducible, the clock does not cut
        deadline = math.inf
    tl = Timeline(pb)
    order = greedy_order(tl)
    now = time.monotonic()
    tail = _tail(deadline, now)
    dp, start_stats = _start(tl, order, deadline - tail, seed, say)
    er = EnergyRank(pb)
    # a worker that publishes plans builds the second greedy start on its core
    offload = bool(bound_worker and pb.n_options and max_iters is None)
    second = None
    if _most_bind(er, tl):  # energy is scarce on most satellites: value per Wh
        second = er.order(order, None)
        if not offload:
            tl2 = Timeline(pb)
            greedy(tl2, deadline - tail, second)
            if tl2.score() > tl.score():
                tl, order = tl2, second
            del tl2  # the losing greedy's timeline (its cache: ~90 MB at 80 M pairs)
            second = None
    if retime is not None and max_iters is None:
        deadline = retime([len(line) for line in tl.lines])
        tail = _tail(deadline, now)
    stats = {"greedy_value": tl.value, **start_stats}
    say("greedy", f"value {tl.value:.6g}")
    t_dp = time.monotonic() + lagrangian_share * max(0.0, deadline - tail - time.monotonic())
    cap = None if max_iters is None else max(10, max_iters // 10)
    worker, shared = None, [] if dp is None else [dp]
    del dp  # one DP layout: the start's, the worker's, the Lagrangian phase's and the sweeps'
    if bound_worker and pb.n_options:
        w_cap = None if cap is None else _WORKER_ITERS * cap
        # plans from the worker depend on timing; such a worker stands for the phase
        worker = BoundWorker(pb, tl.value, deadline - tail, w_cap, shared[0], plans=offload,
                             first=second)  # fmt: skip
    try:
        budget = _Budget(deadline, now, tail, t_dp, cap, max_iters)
        return _stages(pb, tl, order, budget, seed, exact_max_options, stats, worker, shared, say)
    finally:
        if worker is not None:
            worker.stop()


def _start(tl: Timeline, order, deadline: float, seed: int, say):
    """Stage 1 (module docstring) up to the value-per-Wh greedy: sweeps from the empty
    plan of ``tl`` until ``deadline``, then the greedy fill in ``order`` (always
    complete). Returns the problem's DP layout (None: no options) and the sweeps'
    statistics."""
    pb = tl.pb
    dp = dp_prepare(pb) if pb.n_options else None
    stats = {}
    if dp is not None:
        t_sw = time.monotonic()
        rounds = sweeps(tl, dp, deadline, random.Random(f"{seed}:start"))
        say("start", f"{rounds} sweeps from the empty plan: value {tl.value:.6g}")
        stats = {"start_sweep_rounds": rounds, "start_sweep_value": tl.value,
                 "start_sweep_seconds": round(time.monotonic() - t_sw, 3)}  # fmt: skip
    greedy(tl, math.inf, order)  # always complete: a plan even when the budget is spent
    return dp, stats


def _most_bind(er: EnergyRank, tl: Timeline) -> bool:
    """Whether the battery binds on at least :data:`_PER_WH_SHARE` of the satellites in the
    plan of ``tl`` (the value-per-Wh greedy start is then built too)."""
    binding = sum(er.binds(tl, k) for k in range(tl.pb.n_sats))
    return binding > 0 and binding >= _PER_WH_SHARE * tl.pb.n_sats


def _tail(deadline: float, now: float) -> float:
    """Time kept for the earliest-start pass of a search ending at ``deadline`` [s]."""
    return min(_EARLIEST_MAX, _EARLIEST_SHARE * max(0.0, deadline - now))


class _Budget(NamedTuple):
    """Clock and iteration caps of one :func:`solve` call (its docstring)."""

    deadline: float  # end of the whole search [monotonic s]
    now: float  # start of the search [monotonic s]
    tail: float  # time kept for the earliest-pass stage [s]
    t_dp: float  # end of the Lagrangian phase [monotonic s]
    cap: int | None  # Lagrangian iteration cap
    max_iters: int | None  # LNS iteration cap


def _stages(pb, tl, order, budget, seed, exact_max_options, stats, worker, shared, say):
    """Stages 2-5 of :func:`solve` and the bound worker's result.

    ``shared`` holds the problem's DP layout (shared with the worker), or nothing (no
    options); it is taken out here, so the LNS runs without it resident.
    """
    deadline, now, tail, t_dp, cap, max_iters = budget
    dp = shared.pop() if shared else None
    if worker is not None and worker.plans:  # the worker's bound and plans stand for the phase
        res = BoundResult(tl.plan(), math.inf, 0, BoundStatus.TIME)
    else:
        res = lagrangian(
            tl,
            t_dp,
            order,
            max_iters=cap,
            report=lambda it, ub, lb: say("bound", f"it {it}: bound {ub:.6g}, best plan {lb:.6g}"),
            dp=dp,
        )
    stats.update(
        lagrangian_value=tl.value,
        lagrangian_iterations=res.iterations,
        lagrangian_bound=res.bound,
    )
    if dp is not None and res.status != BoundStatus.OPTIMAL:
        t_sw = time.monotonic()
        rounds = sweeps(tl, dp, deadline - tail, random.Random(seed))
        stats.update(sweep_rounds=rounds, sweep_value=tl.value,
                     sweep_seconds=round(time.monotonic() - t_sw, 3))  # fmt: skip
        say("sweep", f"{rounds} rounds: value {tl.value:.6g}")
    del dp
    trim_heap()  # the bound phase's freed arrays: the LNS runs without them resident
    exact = False
    if pb.n_options <= exact_max_options and pb.closed_options() is None:
        start = tl.plan()
        tl.restore([])
        # at most half of what is left: a search that cannot finish still leaves the LNS time
        left = max(0.0, min(deadline, now + _EXACT_MAX_S) - tail - time.monotonic())
        t_exact = time.monotonic() + _EXACT_SHARE * left
        value, exact = exact_search(tl, t_exact)
        if value < sum(pb.target_value[pb.option_target[c]] for c in start):
            tl.restore(start)
        stats["exact_proven"] = exact
    its = 0 if exact or res.status == BoundStatus.OPTIMAL else max_iters  # 0: no LNS
    _lns_stage(tl, deadline - tail, random.Random(seed), its, worker, stats, say)
    earliest_pass(tl, deadline)
    add_backups(tl)  # stereo targets that could lose their product
    bound, status = res.bound, res.status
    ceiling = plan_ceiling(tl)
    if tl.value >= ceiling - _OPTIMAL_TOL * max(1.0, ceiling):  # everything within reach
        bound, status = min(bound, ceiling), BoundStatus.OPTIMAL
    if worker is not None:
        done = status == BoundStatus.OPTIMAL
        wr = worker.result(wait=not (clock.stop_requested() or done))
        if wr is not None:
            stats.update(
                worker_bound=wr.bound,
                worker_iterations=wr.iterations,
                worker_status=wr.status.value,
                worker_dp_per_s=wr.iterations / wr.seconds if wr.seconds > 0 else None,
            )
            if wr.bound < bound:
                bound, status = wr.bound, wr.status
                if bound - tl.value <= _OPTIMAL_TOL * max(1.0, bound):
                    status = BoundStatus.OPTIMAL
    return SearchResult(tl, bound, status, exact, stats)


def _lns_stage(tl, end: float, rng, max_iters, worker, stats, say) -> None:
    """The LNS until ``end`` (monotonic [s]) with its statistics; with a worker that
    publishes plans, it continues from any of them that beats its best."""
    taken = []

    def incoming(value):
        offer = worker.plan(value)
        if offer is not None:
            taken.append(offer[0])
        return offer

    offers = worker is not None and worker.plans
    t_lns, cpu_lns = time.monotonic(), time.process_time()
    its = lns(
        tl,
        end,
        rng,
        max_iters,
        report=lambda it, imp: say("lns", f"it {it}: value {tl.value:.6g} ({imp} improvements)"),
        incoming=incoming if offers else None,
    )
    if offers:
        adopt(tl, None, incoming(tl.value))  # the worker's last plan
        stats.update(worker_plans=len(taken), worker_plan_value=max(taken, default=None))
    stats.update(
        lns_iterations=its,
        lns_value=tl.value,
        lns_seconds=round(time.monotonic() - t_lns, 3),
        lns_cpu_seconds=round(time.process_time() - cpu_lns, 3),
    )
