"""The planning pipeline: one entry point for the CLI, the benchmark and the aeossp adapter.

``plan(scenario) -> PlanResult`` runs, in float64 (inside ``jax.enable_x64``, the
process-wide setting is left alone):

1. **orbits** - every satellite on common ephemeris knots (SGP4 for TLEs), the Sun
   and the Earth's shadow at the knots;
2. **windows** - every visibility window of every target over the horizon
   (:mod:`jaxspline.geometry.windows`);
3. **options** - the valid (target, satellite, start) options on the action grid
   with their boundary states (:mod:`jaxspline.planner.opportunities`);
4. **screening** - per satellite, every option pair closer than the always-feasible
   gap through the satellite's maneuver model (:mod:`jaxspline.screen.models`);
5. **search** - greedy, Lagrangian/DP bound, exact search on tiny instances, LNS
   (:mod:`jaxspline.search`) until the time limit;
6. **repair** - start-time refinement, an independent re-check without margins
   (:mod:`jaxspline.planner.plan_check`), the flown joins and refills as one loop
   (:mod:`jaxspline.planner.repair`): failing observations are dropped, one per
   violation, so the returned plan is valid under every check that ran.

Ctrl-C or SIGTERM during stages 5-6 stops the search: the best plan so far goes
through the repair and is returned with ``report["interrupted"]`` set. Given a
``deadline`` (``jaxspline plan`` passes one), stages 1-4 check it
(:mod:`jaxspline.planner.deadline`): when it passes there, the call stops with
:class:`jaxspline.planner.deadline.TimeLimitError` (what was done, an estimate of the
time needed, the remedy) instead of searching past it; the search then leaves a
reserve for stage 6 and the caller's outputs, and stage 6 leaves out its optional
steps past the limit (:mod:`jaxspline.planner.budget`).
"""

from __future__ import annotations

import math
import numbers
import os
import time

import jax

from jaxspline.base import clock as search_clock
from jaxspline.planner.assemble import assemble_result
from jaxspline.planner.budget import Budget, deadline_budget, default_budget, refine_steps
from jaxspline.planner.build import StageClock, build_problem
from jaxspline.planner.context import PlanContext
from jaxspline.planner.deadline import StageDeadline
from jaxspline.planner.memory_guard import (
    MemoryGuard,
)
from jaxspline.planner.repair import dropped_line, repair
from jaxspline.planner.result import PlanResult
from jaxspline.readers.mission import Scenario
from jaxspline.search import mip_bound, solve

__all__ = ["plan"]

_REFILL_S = 2.0  # [s] budget of one refill after join rejections
_REFILL_ITERS = 2000  # LNS iterations of one refill in iteration-capped runs
_WORKER_MIN_CPUS = 2  # the bound worker runs only with a second CPU


def plan(
    scenario: Scenario,
    *,
    time_limit: float | None = None,
    seed: int = 0,
    progress: bool = True,
    max_iters: int | None = None,
    certify: float = 0.0,
    flown_joins: bool = False,
    deadline: StageDeadline | None = None,
    memory: MemoryGuard | None = None,
) -> PlanResult:
    """Plan a scenario: the best observations found within ``time_limit`` seconds.

    Args:
      scenario: a :class:`jaxspline.readers.mission.Scenario`.
      time_limit: wall-clock budget [s] for the whole call (default
        ``scenario.planner.default_time_limit``).
      seed: random seed of the search (runs are deterministic for a seed and
        ``max_iters``; a time limit only truncates the search).
      progress: stage lines on stderr.
      max_iters: optional cap on search iterations: the search and the refills then
        run to their caps whatever the clock says, and the plan is identical on every
        run (``time_limit`` only sizes the reserved shares; Ctrl-C still stops).
      certify: extra seconds, after the time limit, for a tighter certificate: the
        option model solved as a 0/1 program by HiGHS
        (:func:`jaxspline.search.mip_bound`, needs scipy); the reported bound is the
        smaller of its dual bound and the Lagrangian one. 0 (default): skip.
      flown_joins: also drop observations whose degree-7 joins (SPEC section 3) exceed
        the limits after re-timing (:func:`jaxspline.planner.flown_joins.reject_unflyable`),
        so the plan is flyable as :func:`jaxspline.products.attitude_history.attitude_history`
        exports it; off by default: the satellites' maneuver models alone decide (as the
        aeossp rules). The transitions are then also screened with the joins
        (:mod:`jaxspline.planner.join_screen`).
      deadline: optional :class:`jaxspline.planner.deadline.StageDeadline` (``jaxspline
        plan`` passes one): the stages before the search check it and stop with
        :class:`jaxspline.planner.deadline.TimeLimitError` once it has passed; the
        search leaves a reserve estimated for the repair and the caller's outputs
        (:func:`jaxspline.planner.budget.deadline_budget`); the result's
        ``report["time_limit"]`` records the split and what was left out. Without it
        (the default) the search leaves a fixed share of ``time_limit``
        (:func:`jaxspline.planner.budget.default_budget`).
      memory: optional :class:`jaxspline.planner.memory_guard.MemoryGuard`: the stages
        before the search stop before they allocate more than it allows.
    Returns:
      :class:`jaxspline.planner.result.PlanResult`.
    Raises:
      jaxspline.planner.deadline.TimeLimitError: ``deadline`` passed before the search.
      jaxspline.planner.memory_guard.MemoryLimitError: a stage would not fit ``memory``.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"scenario must be a jaxspline Scenario, got {type(scenario).__name__}")
    limit = scenario.planner.default_time_limit if time_limit is None else time_limit
    if not (isinstance(limit, int | float) and math.isfinite(limit) and limit > 0):
        raise ValueError(f"time_limit must be a number > 0, got {time_limit!r}")
    if not (isinstance(certify, int | float) and math.isfinite(certify) and certify >= 0):
        raise ValueError(f"certify must be a number of seconds >= 0, got {certify!r}")
    if max_iters is not None and (
        isinstance(max_iters, bool) or not isinstance(max_iters, numbers.Integral) or max_iters < 1
    ):
        raise ValueError(f"max_iters must be an integer >= 1, got {max_iters!r}")
    with jax.enable_x64(True):
        args = (float(limit), int(seed), bool(progress), max_iters, certify, flown_joins)
        return _plan(scenario, *args, deadline, memory)


def _cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def _search(pb, budget: Budget, seed, max_iters, pc, clock):
    """Stage 5 with a progress bar over the search budget (re-sized when the budget's
    ``retime`` moves the search's end)."""
    clock.bar = clock.search_bar(budget.search_end - time.monotonic())
    clock.bar_t0 = time.monotonic()

    def retime(per_sat) -> float:
        end = budget.retime(per_sat)
        if clock.bar is not None:
            clock.bar.total = round(max(end - clock.bar_t0, 0.0), 1)
        return end

    try:
        return solve(
            pb,
            budget.search_end,
            seed=seed,
            lagrangian_share=pc.lagrangian_share,
            exact_max_options=pc.exact_max_options,
            max_iters=max_iters,
            bound_worker=pc.bound_worker and _cpus() >= _WORKER_MIN_CPUS,
            report=clock.say,
            retime=None if budget.retime is None else retime,
        )
    finally:
        if clock.bar is not None:
            clock.bar.close()
        clock.bar = None


def _plan(
    sc: Scenario, limit, seed, progress, max_iters, certify, flown_joins, deadline, memory=None
) -> PlanResult:
    """:func:`plan` after its argument checks (inside ``jax.enable_x64``): stages 1-4,
    then search and repair under the signal guard, the optional HiGHS certificate, and
    the result."""
    clock = StageClock(sc.name, progress)
    budget = default_budget(sc, limit, clock.t0)
    ctx = build_problem(sc, joins=flown_joins, deadline=deadline, memory=memory, _clock=clock)
    if deadline is not None:
        budget = deadline_budget(
            ctx, deadline, flown_joins=flown_joins, refill_s=_REFILL_S, capped=max_iters is not None
        )
    res, rep, interrupted = _search_and_repair(ctx, budget, seed, max_iters, flown_joins, clock)
    for what, at in rep.skipped if deadline is not None else ():
        deadline.skip("repair", what, "give a longer --time-limit (or planner.time_limit_s)", at)
    clock.lap(
        "repair",
        f"{len(rep.chosen)} observations valid, dropped {dropped_line(rep.dropped)}"
        + (f", {rep.refilled} refilled" if flown_joins else ""),
    )
    mip = None
    if certify > 0:
        mip = mip_bound(ctx.problem, certify)
        clock.lap("certify", f"HiGHS bound {mip.bound:.6g} ({mip.status})")
    result = assemble_result(
        ctx,
        res,
        rep,
        mip,
        flown_joins=flown_joins,
        interrupted=interrupted,
        timings=clock.timings,
        peak_rss_mb=clock.peak_rss_mb,
    )
    if deadline is not None:  # the caller adds what its outputs leave out
        result.report["time_limit"] = deadline.record()
    if memory is not None:  # beside the measured peaks (stats.peak_rss_mb)
        result.stats["memory_estimate_mb"] = dict(memory.estimates_mb)
    return result


def _search_and_repair(ctx: PlanContext, budget: Budget, seed, max_iters, flown_joins, clock):
    """Stages 5-6 under the signal guard: the first Ctrl-C or SIGTERM stops the search
    and the best plan so far goes through the repair, whose optional steps end by
    ``budget.repair_end`` in time-bound runs. Returns (search result,
    :class:`jaxspline.planner.repair.Repaired`, the signal's name or None)."""
    pc = ctx.scenario.planner
    search_clock.clear_stop()

    def stopping(name):
        search_clock.request_stop()
        clock.say(
            "stop",
            f"{name}: stopping the search; the best plan so far is checked "
            "and returned (Ctrl-C again to abort)",
        )

    with search_clock.catch_signals(stopping, abort_on_second=True) as stop:
        res = _search(ctx.problem, budget, seed, max_iters, pc, clock)
        tl = res.timeline
        clock.lap("search", f"value {tl.value:.6g}, bound {res.bound:.6g} ({res.bound_status})")
        steps, t_steps = refine_steps(pc, budget, max_iters, clock.say), time.monotonic()
        capped = max_iters is not None
        rep = repair(
            ctx,
            tl.plan(),
            refine_steps=steps,
            flown_joins=flown_joins,
            refill_s=math.inf if capped else _REFILL_S,
            refill_iters=_REFILL_ITERS if capped else None,
            seed=seed,
            report=clock.say,
            deadline=None if capped else budget.repair_end,
        )
        if budget.refining and not steps:
            first = ("start-time refinement", t_steps)
            rep = rep._replace(skipped=(first, *rep.skipped))
    search_clock.clear_stop()
    return res, rep, stop["signal"]
