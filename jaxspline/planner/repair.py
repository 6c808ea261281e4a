"""After the search: refinement, independent check, flown joins and refill as one repair loop.

The search returns a plan in its own option table (grid starts, screened pairs, slew
tables with margins). :func:`repair` turns it into a plan that passes the independent
check (:func:`jaxspline.planner.plan_check.check_plan`) and, with ``flown_joins``, the
degree-7 join check (:func:`jaxspline.planner.flown_joins.reject_unflyable`). One round:

1. **refine** (per-channel satellites, when asked and the set of observations grew):
   :func:`jaxspline.planner.refine_starts.refine_starts` on the current set, always from
   the search's table; the refined table is in force only if the whole plan passes the
   check in it, else the search's table is;
2. **check** in the table in force; each violation names one observation (the later
   one of a failing transition, see :mod:`jaxspline.planner.plan_check`), which is
   dropped, until the check passes;
3. **joins** (``flown_joins``): observations whose joins exceed a limit are dropped and
   withdrawn from the search for good; in the first ``_REFILL_ROUNDS`` rounds the
   search's timeline then fills the freed time (greedy; in the first refill also a
   short LNS) and a new round starts.

Invariants:

* the timeline ``tl`` of the search holds the plan in the search's table whenever the
  refill runs (it is restored from the current set), so every insertion test sees the
  data the search screened; refined times never enter it;
* refinement is a function of the current set: it re-runs after a refill added
  observations, so refined and refilled observations are never mixed unchecked;
* every round ends with a plan that passes the check in the table in force; the
  loop ends after a round with no join rejection, so the returned plan passes every
  check that ran;
* every dropped observation is charged to one violation: ``sum(dropped) <= violations``.

The loop terminates: a round either adds observations (at most ``_REFILL_ROUNDS``
times) or only removes them.
"""

from __future__ import annotations

import random
import time
from typing import NamedTuple

from jaxspline.planner.flown_joins import reject_unflyable
from jaxspline.planner.plan_check import check_plan
from jaxspline.planner.refine_starts import refine_starts
from jaxspline.search import clock, greedy, lns

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


def dropped_line(dropped: dict) -> str:
    """Human-readable drop counts: '1 check, 0 battery, 36 joins'.

    Args:
      dropped: reason -> count (:attr:`Repaired.dropped`, ``report["dropped"]``).
    Returns:
      str.
    """
    return ", ".join(f"{n} {reason}" for reason, n in dropped.items())


def _refine(sc, scene, table_ok, opp0, chosen, battery, steps):
    """Refined table if the whole plan passes the check in it, else ``opp0``; and stats."""
    opp_r, refined = refine_starts(sc, scene, opp0, chosen, steps)
    kept, det = False, None
    if opp_r is not opp0:
        bad, det = check_plan(sc, scene, table_ok, opp_r, chosen, battery)
        kept = not bad
    for v in refined.values():
        v["kept"] = kept
    return (opp_r, det) if kept else (opp0, None), refined


def _drop_until_clean(sc, scene, table_ok, opp, chosen, battery, det, dropped):
    """Check, drop one observation per violation, repeat; returns (chosen, details, found)."""
    found = 0
    while True:
        if det is None:
            bad, det = check_plan(sc, scene, table_ok, opp, chosen, battery)
        else:
            bad = sorted(det["reasons"])
        if not bad:
            return chosen, det, found
        found += len(det["violations"])
        for c in bad:
            dropped[_CHECK_REASON.get(det["reasons"][c], "check")] += 1
        gone = set(bad)
        chosen = [c for c in chosen if c not in gone]
        det = None


def drop_failing(sc, scene, table_ok, opp, chosen, battery):
    """Step 2 of the repair alone: check ``chosen``, drop one observation per violation, repeat.

    Args:
      sc: Scenario.
      scene: Scene of the scenario's satellites.
      table_ok: callable (sat [M], t [M]) -> bool [M], the orbit table is usable there.
      opp: Opportunities (``chosen`` indexes them).
      chosen: option ids of the plan.
      battery: BatteryModel of the scenario.
    Returns:
      (kept option ids, which pass :func:`check_plan`; dropped per reason, keys
      :data:`DROP_REASONS`).
    """
    dropped = dict.fromkeys(DROP_REASONS, 0)
    kept, _, _ = _drop_until_clean(sc, scene, table_ok, opp, list(chosen), battery, None, dropped)
    return kept, dropped


def _refill(tl, chosen, seconds, iters, seed):
    """Fill the freed time of ``chosen`` in the search's timeline: a greedy pass, then
    a short LNS (``iters`` iterations or until ``seconds`` have passed).

    Returns (option ids of the plan, observations added).
    """
    assigned = [-1] * tl.pb.n_targets
    for c in chosen:
        assigned[tl.pb.option_target[c]] = c
    tl.restore(assigned)
    deadline = time.monotonic() + seconds
    greedy(tl, deadline)
    if iters is None or iters > 0:
        lns(tl, deadline, random.Random(seed), iters)
    new = [c for c in tl.assigned if c >= 0]
    return new, len(new) - len(chosen)


def _withdraw(pb, rejected):
    """Take rejected options out of their tasks' candidates, so no refill brings them back."""
    for c in rejected:
        cands = pb.target_options[pb.option_target[c]]
        if c in cands:
            cands.remove(c)


def repair(
    sc,
    scene,
    table_ok,
    opp0,
    tl,
    battery,
    *,
    refine_steps: int = 0,
    flown_joins: bool = False,
    refill_s: float = 2.0,
    refill_iters: int | None = None,
    seed: int = 0,
    report=None,
) -> Repaired:
    """Run the repair loop (module docstring) on the search's final timeline.

    Args:
      sc: Scenario.
      scene: Scene of the scenario's satellites.
      table_ok: callable (sat [M], t [M]) -> bool [M], the orbit table is usable there.
      opp0: the search's Opportunities (the timeline's option ids index it).
      tl: the search's :class:`jaxspline.search.Timeline` (modified by refills).
      battery: BatteryModel of the scenario.
      refine_steps: Adam steps of the start-time refinement (0: no refinement).
      flown_joins: also check the degree-7 joins and refill after rejections.
      refill_s: budget of one refill [s] (greedy pass, then LNS).
      refill_iters: LNS iterations of one refill (None: ``refill_s`` alone; give a
        number with ``refill_s = inf`` for reproducible runs).
      seed: seed of the refills' LNS.
      report: callable ``report(stage, message)`` or None.
    Returns:
      Repaired.
    """
    say = report or (lambda stage, msg: None)
    chosen = [c for c in tl.assigned if c >= 0]
    dropped = dict.fromkeys(DROP_REASONS, 0)
    found = refilled = rounds = 0
    opp, det, refined, joins = opp0, None, {}, {}
    refine = refine_steps > 0
    refills_left = _REFILL_ROUNDS
    while True:
        rounds += 1
        if refine and not clock.stop_requested():
            (opp, det), refined = _refine(
                sc, scene, table_ok, opp0, chosen, battery, int(refine_steps)
            )
            kept = opp is not opp0
            say("refine", f"{len(refined)} per-channel satellites, kept: {kept}")
        refine = False
        chosen, det, n = _drop_until_clean(sc, scene, table_ok, opp, chosen, battery, det, dropped)
        found += n
        if not flown_joins:
            break
        bad, joins = reject_unflyable(sc, scene, opp, chosen)
        if not bad:
            break
        found += len(bad)
        dropped["joins"] += len(bad)
        _withdraw(tl.pb, bad)
        gone = set(bad)
        chosen = [c for c in chosen if c not in gone]
        det = None
        if refills_left > 0 and not clock.stop_requested():
            refills_left -= 1
            # LNS in the first refill only: a later one would pack new joins that the
            # last round can only drop
            iters = refill_iters if refills_left == _REFILL_ROUNDS - 1 else 0
            chosen, gain = _refill(tl, chosen, refill_s, iters, seed + rounds)
            refilled += gain
            refine = refine_steps > 0 and gain > 0  # refined times follow the new set
    return Repaired(chosen, opp, det, dropped, found, refined, joins, refilled, rounds)
