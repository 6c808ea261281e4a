"""After the search: refinement, independent check, flown joins and refill as one repair loop.

The search returns a plan in its own option table (grid starts, screened pairs, slew
tables with margins). :func:`repair` turns it into a plan that passes the independent
check (:func:`jaxspline.planner.plan_check.check_plan`) and, with ``flown_joins``, the
degree-7 join check (:func:`jaxspline.planner.flown_joins.reject_unflyable`). One round:

1. **refine** (per-channel satellites, when asked and the set of observations grew):
   :func:`jaxspline.planner.refine_starts.refine_starts` on the current set, always from
   the search's table; the refined table is in force only if the whole plan passes the
   check in it, else the search's table is. After the last refill (no refill can follow)
   it is in force only if the plan it leaves after the join rejections is worth at least
   the one the search's table leaves (both are settled; refined times can make joins
   fail that the grid times pass);
2. **check** in the table in force; each violation names one observation (the later
   one of a failing transition, see :mod:`jaxspline.planner.plan_check`), which is
   dropped, until the check passes;
3. **joins** (``flown_joins``): observations whose joins exceed a limit are dropped and
   their options withdrawn from the search for good (a mask, :attr:`Repaired.withdrawn`;
   the search's :class:`jaxspline.search.Problem` is never changed); in the first
   ``_REFILL_ROUNDS`` rounds a re-search then fills the freed time (a timeline of the
   current set without the withdrawn options: greedy; in the first refill also a short
   LNS) and a new round starts.

Invariants:

* the refill's timeline holds the plan in the search's table (it is restored from the
  current set), so every insertion test sees the data the search screened; refined
  times never enter it;
* refinement is a function of the current set: it re-runs after a refill added
  observations, so refined and refilled observations are never mixed unchecked;
* every round ends with a plan that passes the check in the table in force; the
  loop ends after a round with no join rejection, so the returned plan passes every
  check that ran;
* every dropped observation is charged to one violation: ``sum(dropped) <= violations``.

The loop terminates: a round either adds observations (at most ``_REFILL_ROUNDS``
times) or only removes them.

Given a ``deadline``, the optional steps stop there: past it no refill starts (a
refill's budget ends at it) and a refinement due after a refill is left out (the
table in force stays, as after Ctrl-C); the checks and the join rejections always
run, so the plan stays valid. :attr:`Repaired.skipped` names what was left out.
"""

from __future__ import annotations

import random
import time
from typing import NamedTuple

import numpy as np

from jaxspline.base import clock
from jaxspline.planner.context import PlanContext
from jaxspline.planner.flown_joins import reject_unflyable
from jaxspline.planner.plan_check import check_plan
from jaxspline.planner.refine_starts import refine_starts
from jaxspline.search import Timeline, greedy, lns
from jaxspline.search.stereo import add_backups

__all__ = ["DROP_REASONS", "Repaired", "drop_failing", "dropped_line", "repair"]

_REFILL_ROUNDS = 2  # join rejections followed by a greedy refill (later rounds only drop)
DROP_REASONS = ("check", "battery", "joins")  # keys of Repaired.dropped
_CHECK_REASON = {"battery": "battery"}  # check_plan reasons -> DROP_REASONS (else "check")


class Repaired(NamedTuple):
    """Outcome of :func:`repair`.

    Attributes:
      chosen: option ids of the final plan (ids of ``opp``).
      opp: the option table in force (refined rows replaced, or the search's table).
      details: :func:`check_plan` details of the final plan.
      dropped: observations dropped per reason: "check" (geometry, timing, repeats,
        maneuvers), "battery", "joins" (degree-7 joins over a limit).
      violations: violations found over all rounds (checks and join rejections).
      refined: per refined satellite the refinement statistics (with "kept").
      joins: join summary of the final plan ({} without ``flown_joins``).
      refilled: observations the refills added (net of the rejected ones).
      rounds: repair rounds run.
      withdrawn: bool [N], the options withdrawn from the search for good (their joins
        failed); a later re-search of the problem passes it to
        :class:`jaxspline.search.Timeline`.
      skipped: ``(step, when [s, time.monotonic])`` of each optional step left out
        because the deadline had passed (``"refill"``, ``"start-time refinement after
        a refill"``).
    """

    chosen: list
    opp: object
    details: dict
    dropped: dict
    violations: int
    refined: dict
    joins: dict
    refilled: int
    rounds: int
    withdrawn: np.ndarray
    skipped: tuple = ()


def dropped_line(dropped: dict) -> str:
    """Human-readable drop counts: '1 check, 0 battery, 36 joins'.

    Args:
      dropped: reason -> count (:attr:`Repaired.dropped`, ``report["dropped"]``).
    Returns:
      str.
    """
    return ", ".join(f"{n} {reason}" for reason, n in dropped.items())


def _refine(ctx: PlanContext, chosen, steps):
    """Refined table if the whole plan passes the check in it, else the search's; and stats."""
    opp_r, refined = refine_starts(ctx, chosen, steps)
    kept, det = False, None
    if opp_r is not ctx.opportunities:
        bad, det = check_plan(ctx, chosen, opp_r)
        kept = not bad
    for v in refined.values():
        v["kept"] = kept
    return (opp_r, det) if kept else (ctx.opportunities, None), refined


def _drop_until_clean(ctx: PlanContext, opp, chosen, det, dropped):
    """Check, drop one observation per violation, repeat; returns (chosen, details, found)."""
    found = 0
    while True:
        if det is None:
            bad, det = check_plan(ctx, chosen, opp)
        else:
            bad = sorted(det["reasons"])
        if not bad:
            return chosen, det, found
        found += len(det["violations"])
        for c in bad:
            dropped[_CHECK_REASON.get(det["reasons"][c], "check")] += 1
        chosen, det = _without(chosen, bad), None


def drop_failing(ctx: PlanContext, chosen, opp=None):
    """Step 2 of the repair alone: check ``chosen``, drop one observation per violation, repeat.

    Args:
      ctx: PlanContext of the planned scenario.
      chosen: option ids of the plan.
      opp: the Opportunities ``chosen`` indexes (default: ``ctx.opportunities``).
    Returns:
      (kept option ids, which pass :func:`check_plan`; dropped per reason, keys
      :data:`DROP_REASONS`).
    """
    dropped = dict.fromkeys(DROP_REASONS, 0)
    opp = ctx.opportunities if opp is None else opp
    kept, _, _ = _drop_until_clean(ctx, opp, list(chosen), None, dropped)
    return kept, dropped


def _refill(pb, chosen, withdrawn, seconds, iters, seed):
    """Re-search of the problem ``pb`` from the plan ``chosen`` without the ``withdrawn``
    options: a greedy pass fills the freed time, then a short LNS (``iters`` iterations
    or until ``seconds`` have passed). The repair runs the LNS in its first refill only:
    a later one would pack new joins that the last round can only drop.

    Returns (option ids of the plan, observations added).
    """
    tl = Timeline(pb, withdrawn)
    tl.restore(chosen)
    deadline = time.monotonic() + seconds
    greedy(tl, deadline)
    if iters is None or iters > 0:
        lns(tl, deadline, random.Random(seed), iters)
    add_backups(tl)  # stereo targets that could lose their product
    new = tl.plan()
    return new, len(new) - len(chosen)


def repair(
    ctx: PlanContext,
    chosen,
    *,
    refine_steps: int = 0,
    flown_joins: bool = False,
    refill_s: float = 2.0,
    refill_iters: int | None = None,
    seed: int = 0,
    report=None,
    deadline: float | None = None,
) -> Repaired:
    """Run the repair loop (module docstring) on the search's plan.

    Args:
      ctx: PlanContext of the planned scenario (read only).
      chosen: option ids of the search's plan (ids of ``ctx.opportunities``).
      refine_steps: Adam steps of the start-time refinement (0: no refinement).
      flown_joins: also check the degree-7 joins and refill after rejections.
      refill_s: budget of one refill [s] (greedy pass, then LNS).
      refill_iters: LNS iterations of one refill (None: ``refill_s`` alone; give a
        number with ``refill_s = inf`` for reproducible runs).
      seed: seed of the refills' LNS.
      report: callable ``report(stage, message)`` or None.
      deadline: when the optional steps (refills, refinements after a refill) must end
        [s, ``time.monotonic``]; None: no end (module docstring).
    Returns:
      Repaired.
    """
    say = report or (lambda stage, msg: None)
    end = np.inf if deadline is None else deadline
    skipped = []
    chosen = list(chosen)
    withdrawn = np.zeros(ctx.problem.n_options, bool)
    dropped = dict.fromkeys(DROP_REASONS, 0)
    found = refilled = rounds = 0
    opp, det, refined, joins = ctx.opportunities, None, {}, {}
    refine = refine_steps > 0
    refills_left = _REFILL_ROUNDS
    while True:
        rounds += 1
        if refine and rounds > 1 and time.monotonic() >= end:
            _skip(skipped, say, "start-time refinement after a refill")
        elif refine and not clock.stop_requested():
            (opp, det), refined = _refine(ctx, chosen, int(refine_steps))
            if opp is not ctx.opportunities and flown_joins and refills_left == 0:
                opp, tail = _last_round(ctx, chosen, opp, det, refined)  # nothing refills after
                say("refine", f"{len(refined)} per-channel satellites, kept: {tail.kept}")
                chosen, det, joins = tail.chosen, tail.details, tail.joins
                found, rounds = _absorb(tail, withdrawn, dropped, found, rounds)
                break
            kept = opp is not ctx.opportunities
            say("refine", f"{len(refined)} per-channel satellites, kept: {kept}")
        refine = False
        (chosen, det, joins), n, rejected = _round(
            ctx, opp, chosen, det, dropped, withdrawn, flown_joins
        )
        found += n
        if not rejected:
            break
        if refills_left > 0 and time.monotonic() >= end:
            refills_left = 0
            _skip(skipped, say, "refill")
        if refills_left > 0 and not clock.stop_requested():
            refills_left -= 1
            iters = refill_iters if refills_left == _REFILL_ROUNDS - 1 else 0  # see _refill
            seconds = min(refill_s, end - time.monotonic())
            chosen, gain = _refill(ctx.problem, chosen, withdrawn, seconds, iters, seed + rounds)
            refilled += gain
            refine = refine_steps > 0 and gain > 0  # refined times follow the new set
    return Repaired(
        chosen, opp, det, dropped, found, refined, joins, refilled, rounds, withdrawn,
        tuple(skipped),
    )  # fmt: skip


class _Tail(NamedTuple):
    """The rounds after the last refill, run to their end (:func:`_settle`)."""

    chosen: list
    details: dict
    joins: dict
    dropped: dict
    found: int
    rounds: int
    withdrawn: np.ndarray
    kept: bool = False


def _round(ctx: PlanContext, opp, chosen, det, dropped: dict, withdrawn, flown_joins: bool):
    """Steps 2 and 3 of a round, without the refill: check and drop until clean, then
    (``flown_joins``) drop the observations whose joins fail, counting them in
    ``dropped`` and marking their options in ``withdrawn`` (both in place). Returns
    ((chosen, check details or None after a rejection, join summary or {}), violations
    found, whether a join was rejected)."""
    chosen, det, found = _drop_until_clean(ctx, opp, chosen, det, dropped)
    if not flown_joins:
        return (chosen, det, {}), found, False
    bad, joins = reject_unflyable(ctx.scenario, ctx.scene, opp, chosen)
    if bad:
        dropped["joins"] += len(bad)
        withdrawn[bad] = True
        chosen, det = _without(chosen, bad), None
    return (chosen, det, joins), found + len(bad), bool(bad)


def _settle(ctx: PlanContext, opp, chosen, det) -> _Tail:
    """Rounds without refill (:func:`_round`) until one rejects no join: the end of the
    repair once no refill is left, on the table ``opp``, on an account of its own."""
    dropped = dict.fromkeys(DROP_REASONS, 0)
    withdrawn = np.zeros(ctx.problem.n_options, bool)
    found = rounds = 0
    rejected = True
    while rejected:
        rounds += 1
        (chosen, det, joins), n, rejected = _round(ctx, opp, chosen, det, dropped, withdrawn, True)
        found += n
    return _Tail(chosen, det, joins, dropped, found, rounds, withdrawn)


def _without(chosen, bad) -> list:
    """``chosen`` without the option ids ``bad`` (order kept)."""
    gone = set(bad)
    return [c for c in chosen if c not in gone]


def _absorb(tail: _Tail, withdrawn, dropped: dict, found: int, rounds: int):
    """Add the settled rounds ``tail`` to the repair's account: marks its rejected options
    in ``withdrawn`` and adds its drops to ``dropped`` (both in place). Returns the
    violations found and the rounds run, the tail's included."""
    withdrawn |= tail.withdrawn
    for reason, n in tail.dropped.items():
        dropped[reason] += n
    return found + tail.found, rounds + tail.rounds - 1


def _last_round(ctx: PlanContext, chosen, opp_r, det_r, refined):
    """The last refinement (no refill follows it) is kept only if the plan it leaves after
    the join rejections is worth at least the one the search's table leaves: refined
    times can make joins fail that the search's grid times pass. Returns (the table
    in force, its :class:`_Tail`); marks ``refined`` accordingly."""
    on_r = _settle(ctx, opp_r, chosen, det_r)
    on_s = _settle(ctx, ctx.opportunities, chosen, None)
    value = ctx.problem.target_value
    target = ctx.problem.option_target
    worth = [sum(value[target[c]] for c in t.chosen) for t in (on_r, on_s)]
    kept = worth[0] >= worth[1]
    for v in refined.values():
        v["kept"] = kept
    return (opp_r, on_r._replace(kept=True)) if kept else (ctx.opportunities, on_s)


def _skip(skipped: list, say, what: str) -> None:
    """Record (and say) that ``what`` was left out: the deadline has passed."""
    skipped.append((what, time.monotonic()))
    say("repair", f"{what} left out: the time limit has passed")
