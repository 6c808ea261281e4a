"""How a call's time limit is split between the search and the stages after it.

:func:`jaxspline.plan` runs the stages before the search, the search, then the repair
(:mod:`jaxspline.planner.repair`: start-time refinement, the independent check, the
flown-join check, refills); ``jaxspline plan`` then writes its outputs. The search is
the only stage that can stop at any time, so it gets what the others leave:

* without a :class:`jaxspline.planner.deadline.StageDeadline` (a library call):
  :func:`default_budget`, a share of the limit (:data:`RESERVE_SHARE`, at least
  :data:`RESERVE_MIN_S`) kept for the check and the output, plus one for the
  refinement (:data:`REFINE_SHARE`, at most :data:`REFINE_MAX_S`);
* with one (``jaxspline plan``): :func:`deadline_budget`, once the problem is built.
  The repair works on the plan, so its estimate (:func:`repair_seconds`: CPU seconds
  per round and per observation of the plan, the refinement's per observation of a
  per-channel satellite, the only ones it moves; measured on the default job, the
  12 x 12 h preset and the constellation day) is made twice: first for a plan of every
  target that has an option, split between the satellites as their options are (the
  plan is not known yet), then once more when the search's greedy start is built
  (:attr:`Budget.retime`, called by :func:`jaxspline.search.solve` with the start's
  observations per satellite), for :data:`PLAN_GROWTH` times them (the search adds
  some).
  The outputs are estimated by the caller (:attr:`StageDeadline.after_s`). Both are
  scaled by the pace of the call so far (:meth:`StageDeadline.pace`: a loaded machine
  runs them slower). The search ends that long before the limit, but gets at least
  :data:`SEARCH_MIN_SHARE` of the time left at its start: when the estimates do not
  fit, the later stages leave out what does not fit (the repair its refinement and
  refills, the outputs their optional files), they never leave out a check.

One more check before the search starts: when the stages before it have used the
limit up (their compile allowance lets them run past it), the checks the repair can
never leave out (:func:`mandatory_seconds`, at the pace, for a plan of
:data:`TYPICAL_PLAN_SHARE` of the targets that have an option) would end the run more
than :data:`LATE_MAX_S` past the limit; a time-bound call then stops with
:class:`jaxspline.planner.deadline.TimeLimitError` (exit 3 of ``jaxspline plan``, with
the estimate and the remedy) rather than plan that late.

The repair's optional steps (refinement, refills) end by :attr:`Budget.repair_end`,
the limit less the outputs' share; ``None`` there (iteration-capped runs) lets them
run whatever the clock says, so such runs stay reproducible.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from jaxspline.planner.context import PlanContext
from jaxspline.planner.deadline import StageDeadline, TimeLimitError, suggested_limit

__all__ = [
    "CHECK_FIRST_S",
    "CHECK_ROUND_S",
    "CHECK_S_PER_OBS",
    "JOINS_FIRST_S",
    "JOINS_S_PER_OBS",
    "LATE_MAX_S",
    "PLAN_GROWTH",
    "REFINE_FIRST_S",
    "REFINE_MAX_S",
    "REFINE_MIN_S",
    "REFINE_ROUND_S",
    "REFINE_SHARE",
    "REFINE_S_PER_OBS",
    "REFILL_OVERHEAD_S",
    "RESERVE_MIN_S",
    "RESERVE_SHARE",
    "SEARCH_MIN_SHARE",
    "TYPICAL_PLAN_SHARE",
    "Budget",
    "deadline_budget",
    "default_budget",
    "mandatory_seconds",
    "refine_steps",
    "repair_seconds",
]

RESERVE_SHARE = 0.12  # share of the time limit kept for the final check and output
RESERVE_MIN_S = 1.0  # [s]
REFINE_SHARE = 0.25  # share of the time limit kept for start-time refinement (if it runs)
REFINE_MAX_S = 10.0  # [s] ... at most (warm: ~1-3 s a round; a cold compile 6-12 s)
REFINE_MIN_S = 10.0  # [s] refinement runs only with this much time left (cold compile: 6-12 s)
SEARCH_MIN_SHARE = 0.25  # share of the time left at its start the search always gets
LATE_MAX_S = 20.0  # [s] past the limit the checks after the search may end, at most
#: The plan size the repair's estimate assumes, as a multiple of the greedy start's
#: observations (the search's later stages add observations: +21 % in a 30 s search
#: of a 20,000-target 12-satellite day).
PLAN_GROWTH = 1.3
#: Share of the targets that have an option that a plan is taken to observe before the
#: search (the default job's: ~half of its 950), in :func:`mandatory_seconds`.
TYPICAL_PLAN_SHARE = 0.5

# CPU seconds of the repair's steps: a fixed part per round (each round's plan is a new
# size, so its programs load from the compile cache again) plus a part per observation,
# fitted to the default job (517 observations, a third on per-channel satellites,
# flown joins: three rounds and two refills, 14-17 s measured) and to warm calls on
# the 12 x 12 h preset (3,490 observations, 1,446 per-channel: refinement 3.8 s, check
# 1.8 s) and the constellation day (11,945 observations, 5,561 per-channel: refinement
# 9.7 s, check 5.3 s), 2-core machine, compiled programs in the cache; the parts per
# observation exceed these by 20-50 %. The first calls load their programs, one set
# per maneuver model (0.6 and 3.0 s for a 12-target scenario with three models):
CHECK_S_PER_OBS = 3e-4  # one independent check (plan_check), per round and observation
CHECK_ROUND_S = 0.8  # ... per round
CHECK_FIRST_S = 0.8  # its first call
JOINS_S_PER_OBS = 2.4e-3  # one flown-join check (reject_unflyable), per round
JOINS_FIRST_S = 3.0  # its first call
#: one start-time refinement, per round and observation of a per-channel satellite
REFINE_S_PER_OBS = 1.5e-3
REFINE_ROUND_S = 1.15  # ... per round
REFINE_FIRST_S = 2.5  # its first call
#: [s] a refill's greedy pass and restore besides its budget, and the refinement after
#: it on a plan of a new size (the default job's second round: ~2 s more than a warm one)
REFILL_OVERHEAD_S = 2.0
_ROUNDS_WITH_JOINS = 3  # repair rounds with the flown joins (two refills, the last check)
_MANDATORY_ROUNDS = 2  # check and join rounds with no refill: a rejection, then the last


class Budget(NamedTuple):
    """The clock of one :func:`jaxspline.plan` call after the stages before the search.

    Attributes:
      search_end: when the search stops [s, ``time.monotonic``] (until :attr:`retime`).
      repair_end: when the repair's optional steps (refinement, refills) must end
        [s, monotonic]; None: they run whatever the clock says (iteration-capped runs
        set this when they pass it on).
      refining: the start-time refinement runs (refine steps and a per-channel satellite).
      split: the split, for ``plan.json`` (empty without a deadline).
      retime: None, or ``retime(per_sat) -> search_end``: the search's end re-estimated
        for a greedy start of ``per_sat`` observations per satellite (module
        docstring); it updates :attr:`split`.
    """

    search_end: float
    repair_end: float | None
    refining: bool
    split: dict
    retime: Callable[[int], float] | None = None


def _refining(sc) -> bool:
    return sc.planner.refine_steps > 0 and bool(_refined_satellites(sc).any())


def default_budget(sc, limit: float, t0: float) -> Budget:
    """The budget of a call started at ``t0`` (monotonic [s]) with ``limit`` seconds and
    no deadline: a share of the limit (at least :data:`RESERVE_MIN_S`) kept for the check
    and output, plus one for start-time refinement (at most :data:`REFINE_MAX_S`).

    Args:
      sc: the Scenario.
      limit: the time limit [s].
      t0: the call's start [s, monotonic].
    Returns:
      Budget.
    """
    refining = _refining(sc)
    reserve = max(RESERVE_MIN_S, RESERVE_SHARE * limit)
    reserve += refining * min(REFINE_SHARE * limit, REFINE_MAX_S)
    return Budget(t0 + limit - reserve, t0 + limit, refining, {})


def _refined_satellites(sc) -> np.ndarray:
    """Per satellite whether the start-time refinement moves its observations (a
    per-channel satellite: its maneuvers are not rest-to-rest)."""
    return np.array([not s.maneuver.rest_to_rest for s in sc.satellites], bool)


def _targets(ctx: PlanContext) -> int:
    """The most observations a plan can have: the targets that have an option, and per
    pass of an area the strips it can hold (capped by the plan's action cap)."""
    pb = ctx.problem
    route = np.asarray(ctx.opportunities.options.route)
    if pb.cover is None:
        return int(np.unique(route).size)
    cv = pb.cover
    area = cv.option_group >= 0
    n_pass = int(cv.group_pass.max()) + 1 if cv.n_groups else 0
    lo = np.full(n_pass, np.iinfo(np.int64).max)
    hi = np.zeros(n_pass, np.int64)
    np.minimum.at(lo, cv.group_pass, cv.group_slot0)
    np.maximum.at(hi, cv.group_pass, cv.group_slot0 + cv.group_nslots)
    need = np.asarray(cv.min_slots, np.int64)[_pass_sat(cv, n_pass)]
    strips = int(((hi - lo + 1) // (need + 1)).sum())
    if pb.max_actions is not None:
        strips = min(strips, int(pb.max_actions))
    return int(np.unique(route[~area]).size) + strips


def _pass_sat(cv, n_pass: int) -> np.ndarray:
    """The satellite of every pass of a CoverTable."""
    sat = np.zeros(n_pass, np.int64)
    sat[cv.group_pass] = cv.group_sat
    return sat


def _movable_share(ctx: PlanContext, targets: int) -> float:
    """The share of a plan's observations the start-time refinement may move: all but the
    area strips (they hold their slots)."""
    pb = ctx.problem
    if pb.cover is None or not targets:
        return 1.0
    route = np.asarray(ctx.opportunities.options.route)
    return float(np.unique(route[pb.cover.option_group < 0]).size) / targets


def repair_seconds(
    observations: float, flown_joins: bool, refining: bool, refill_s: float, refined=None
):
    """Estimated CPU seconds of the repair (module docstring) of a plan of ``observations``.

    Args:
      observations: the plan's size (observations).
      flown_joins: the flown joins are checked (three rounds, two refills).
      refining: the start-time refinement runs (each round with the joins).
      refill_s: the budget of one refill [s].
      refined: the observations the refinement moves (those of per-channel
        satellites); None: all of them.
    Returns:
      float [s].
    """
    n = float(observations)
    m = n if refined is None else float(refined)
    rounds = _ROUNDS_WITH_JOINS if flown_joins else 1
    need = CHECK_FIRST_S + rounds * (CHECK_ROUND_S + CHECK_S_PER_OBS * n)
    if flown_joins:
        need += JOINS_FIRST_S + rounds * JOINS_S_PER_OBS * n + refill_s + REFILL_OVERHEAD_S
    if refining:
        need += REFINE_FIRST_S + rounds * (REFINE_ROUND_S + REFINE_S_PER_OBS * m)
    return need


def mandatory_seconds(ctx: PlanContext, flown_joins: bool, after_s: float = 0.0) -> float:
    """Estimated CPU seconds of what follows the search and is never left out: the
    independent check and the flown-join check (two rounds each) of a plan of
    :data:`TYPICAL_PLAN_SHARE` of the targets that have an option, plus ``after_s``.
    It leaves out the per-round part (:data:`CHECK_ROUND_S`): a run is refused only
    when even this lower estimate ends it far past the limit.

    Args:
      ctx: PlanContext (stages 1-4).
      flown_joins: the flown joins are checked.
      after_s: the caller's part that is never left out [s] (``plan.json``, ``plan.csv``).
    Returns:
      float [s].
    """
    n = TYPICAL_PLAN_SHARE * _targets(ctx)
    need = CHECK_FIRST_S + _MANDATORY_ROUNDS * CHECK_S_PER_OBS * n + after_s
    if flown_joins:
        need += JOINS_FIRST_S + _MANDATORY_ROUNDS * JOINS_S_PER_OBS * n
    return need


def _refuse_late(deadline: StageDeadline, need: float) -> None:
    """Raise TimeLimitError when ``need`` seconds from now end past the limit by more than
    :data:`LATE_MAX_S`."""
    elapsed = time.monotonic() - deadline.t0
    late = elapsed + need - deadline.limit
    if late <= LATE_MAX_S:
        return
    raise TimeLimitError(
        f"time limit of {deadline.limit:.4g} s: the stages before the search took "
        f"{elapsed:.1f} s and the checks after it (~{need:.0f} s at this pace) would end "
        f"{late:.0f} s past the limit{'; ' + deadline.scale if deadline.scale else ''}: give a "
        f"time limit of {suggested_limit(elapsed + need)} s or more (--time-limit or "
        "planner.time_limit_s), or plan fewer targets or satellites, a shorter horizon, "
        "or a coarser planner.time_step_s",
        "search",
        elapsed,
        elapsed + need,
    )


def deadline_budget(
    ctx: PlanContext,
    deadline: StageDeadline,
    *,
    flown_joins: bool,
    refill_s: float,
    capped: bool = False,
) -> Budget:
    """The budget of a call with a deadline, once its problem is built (module docstring).

    Args:
      ctx: PlanContext (stages 1-4).
      deadline: the call's StageDeadline (its ``after_s``: the caller's outputs); its
        ``split`` is set here, and again by the budget's :attr:`Budget.retime`.
      flown_joins: the flown joins are checked.
      refill_s: the budget of one refill [s].
      capped: an iteration-capped run (its search and repair run whole whatever the
        clock says, so it is not refused for :data:`LATE_MAX_S` either, and its
        search's end is not re-estimated).
    Returns:
      Budget.
    Raises:
      TimeLimitError: the checks after the search would end more than
        :data:`LATE_MAX_S` past the limit (module docstring).
    """
    refining = _refining(ctx.scenario)
    if not capped:
        _refuse_late(
            deadline, deadline.pace() * mandatory_seconds(ctx, flown_joins, deadline.must_s)
        )
    targets = _targets(ctx)
    movable = _movable_share(ctx, targets)
    now = time.monotonic()
    earliest = now + SEARCH_MIN_SHARE * max(deadline.end - now, 0.0)
    deadline.split = {"before_search_s": round(now - deadline.t0, 2)}

    moved = _refined_satellites(ctx.scenario)

    def retime(per_sat) -> float:
        """The search's end for a plan of ``per_sat`` observations per satellite (the
        greedy start's, grown by :data:`PLAN_GROWTH`; at most every target that has an
        option)."""
        per_sat = np.asarray(per_sat, np.float64)
        observations = float(per_sat.sum())
        size = min(PLAN_GROWTH * observations, targets)
        refined = size * movable * (per_sat[moved].sum() / observations if observations else 0.0)
        pace = deadline.pace()
        repair = repair_seconds(size, flown_joins, refining and refined > 0, refill_s, refined)
        repair *= pace
        outputs = deadline.after_s * pace
        end = max(deadline.end - repair - outputs, earliest)
        deadline.split.update(
            search_s=round(end - now, 2),
            reserve_s={"repair": round(repair, 2), "outputs": round(outputs, 2)},
            observations=round(size),
        )
        return end

    sats = np.asarray(ctx.opportunities.options.sat, np.int64)
    end = retime(targets * np.bincount(sats, minlength=moved.size) / max(sats.size, 1))
    return Budget(end, deadline.end - deadline.after_s * deadline.pace(), refining,
                  deadline.split, None if capped else retime)  # fmt: skip


def refine_steps(pc, budget: Budget, max_iters, say) -> int:
    """The start-time refinement steps of the repair: the scenario's when refining, none
    when a time-limited run has less than :data:`REFINE_MIN_S` left before
    :attr:`Budget.repair_end` (said through ``say(stage, message)``).

    Args:
      pc: the scenario's planner settings.
      budget: Budget.
      max_iters: the search's iteration cap (None: time-bound).
      say: callable ``say(stage, message)``.
    Returns:
      int.
    """
    steps = int(pc.refine_steps) if budget.refining else 0
    left = budget.repair_end - time.monotonic()
    if steps and max_iters is None and left < REFINE_MIN_S:
        steps = 0
        say("refine", f"skipped: {max(left, 0.0):.1f} s left < {REFINE_MIN_S:.0f} s")
    return steps
