"""Greedy construction, large-neighbourhood search and the earliest-start pass.

* Greedy (the strategy of :mod:`jaxspline.search.construct`, one decision per target):
  targets by value (heaviest first; fewest satellites, then fewest options first among
  equals) are inserted at the feasible option that consumes the least timeline time
  (maneuver in + imaging + maneuver out minus the maneuver it replaces), earlier end
  as tie-break.
* LNS until the deadline: destroy a window of one satellite's timeline (80 %: around
  an option of an unscheduled target picked with probability proportional to its
  value, that option then forced in; 20 %: around a random scheduled observation),
  then re-insert the removed targets anywhere together with the unscheduled targets that
  have an option in the free time the destroy left (only those options are tried: the
  rest of the satellite's timeline did not change), heaviest first with 20 % noise
  (the same greedy pass, on insertion costs with 30 % noise); threshold acceptance
  (a step may lose up to ``temp * U(0, 1)`` value early on, nothing at the end); the
  best plan is kept. Where a battery binds, the moves weigh energy
  (:mod:`jaxspline.search.lns_energy`): targets by value times value per Wh,
  the destroy around the cheapest of a few observations, re-insertion by value per Wh,
  and a forced option that fails on the battery alone gets room by removing the
  observations of least value per Wh that can reach it.
* Areas: where the problem has area options, their moves
  (:func:`jaxspline.search.area_moves.area_move`: lazy greedy by marginal coverage,
  pass re-plans, destroy and repair, local moves) take turns with the moves above, in
  proportion to the areas' share of the plan's possible value; such a move is kept when
  the plan's score (:meth:`Timeline.score`: areas' shortfall, value, count) did not drop.
  :func:`greedy` fills the areas after the targets the same way.
* Earliest pass: each observation moves to the earliest feasible option of its target.
"""

from __future__ import annotations

import bisect
import itertools
import math
import time

from jaxspline.base import clock
from jaxspline.search.area_fill import area_index, fill
from jaxspline.search.area_moves import AreaWalk, area_move, drop_idle_strips
from jaxspline.search.construct import greedy_pass
from jaxspline.search.lns_energy import EnergyRank, make_room
from jaxspline.search.stereo import drop_stray_looks, upgrade_product
from jaxspline.search.timeline import Timeline

__all__ = ["adopt", "earliest_pass", "greedy", "greedy_order", "lns"]

_RAD_TARGET = (30.0, 60.0, 90.0, 150.0)  # destroy half-widths [s] around an unscheduled target
_RAD_RANDOM = (60.0, 120.0, 240.0)  # ... around a random scheduled observation
_P_TARGETED = 0.8  # share of targeted destroy moves
_POOL_REACH = 400.0  # [s] waiting targets are offered from options this close to a window
_ORDER_NOISE = 0.2  # relative noise of the re-insertion order
_REPORT_EVERY = 5.0  # [s] between progress reports
_REFRESH_EVERY = 16  # iterations between refreshes of the unscheduled list
_TEMPERATURE = 1.0  # threshold-acceptance start value [value units]
_POLL_EVERY = 0.5  # [s] between two looks at the plans offered from outside (``incoming``)
_P_UPGRADE = 0.2  # share of a stereo problem's moves that trade a product for a better one
_CEILING_TOL = 1e-9  # relative: a plan this close to every value within reach is optimal


def greedy_order(tl: Timeline):
    """Point and strip targets with options on offer, heaviest first, fewest satellites /
    options first among equals (an area's options are :func:`greedy`'s second step).

    Args:
      tl: Timeline.
    Returns:
      list of target indices.
    """
    pb, options = tl.pb, tl.target_options
    return sorted(
        (t for t in pb.exclusive_targets() if options[t]),
        key=lambda t: (
            -pb.target_value[t],
            len({pb.option_sat[c] for c in options[t]}),
            len(options[t]),
            t,
        ),
    )


def greedy(tl: Timeline, deadline: float, order=None):
    """Insert the targets greedily (see module docstring) until done or the deadline,
    then the area strips by marginal coverage.

    The greedy strategy of :func:`jaxspline.search.construct.greedy_pass`: one decision
    per target of ``order``, the target's options that fit as candidates, their
    :meth:`Timeline.insert_choices` costs; then, where the problem has areas, the lazy
    greedy of :func:`jaxspline.search.area_fill.fill` (always complete when the
    deadline is infinite).

    Args:
      tl: Timeline (targets already assigned stay).
      deadline: float, ``time.monotonic()`` value at which to stop [s].
      order: target order; None uses :func:`greedy_order`.
    """
    targets = order if order is not None else greedy_order(tl)
    greedy_pass(targets, tl.insert_choices, tl.insert, deadline)
    if tl.cover is None:
        tl.commit()
        return
    ix = area_index(tl.pb)
    fill(tl, ix, deadline)
    tl.commit()
    if tl.pb.max_actions is None:
        return
    first = (tl.score(), tl.plan())  # with a cap, the strips first may be worth more
    tl.restore([c for c in first[1] if tl.pb.is_closed(c) and not tl.pb.is_area(c)])
    fill(tl, ix, deadline)
    greedy_pass(targets, tl.insert_choices, tl.insert, deadline)
    if tl.score() < first[0]:
        tl.restore(first[1])
    tl.commit()


def _destroy(tl: Timeline, k: int, lo: float, hi: float):
    """Remove satellite k's observations touching [lo, hi]; None if that is infeasible."""
    pb = tl.pb
    line = tl.lines[k]
    b = bisect.bisect_right(tl.line_starts[k], hi)
    a = b
    while a > 0 and pb.option_end[line[a - 1]] >= lo:
        a -= 1
    removed = line[a:b]
    for c in removed:
        tl.remove(c)
    return removed if (not removed or tl.removal_ok(k, a)) else None


def _gap(tl: Timeline, k: int, lo: float):
    """The free time ``(g0, g1)`` around ``lo`` on satellite k: from the end of the
    observation before it to the start of the one after it (+-inf: none)."""
    starts, ends = tl.line_starts[k], tl.line_ends[k]
    pos = bisect.bisect_left(starts, lo)
    return (
        ends[pos - 1] if pos > 0 else -math.inf,
        starts[pos] if pos < len(starts) else math.inf,
    )


class _Walk:
    """The LNS's state between iterations: the unscheduled targets and the best plan.

    Attributes:
      has: the targets with options.
      er: :class:`EnergyRank` of the problem.
      un: the unscheduled targets (refreshed every :data:`_REFRESH_EVERY` iterations).
      cw: cumulative picking odds of ``un`` (:meth:`EnergyRank.target_weights`).
      dirty: whether the plan changed since ``un`` was refreshed.
      best_key: :func:`_key` of the best plan.
      best: its options (:meth:`Timeline.plan`).
      improved: number of improvements of the best plan.
    """

    def __init__(self, tl: Timeline, has, er: EnergyRank | None = None):
        self.has = has
        self.er = EnergyRank(tl.pb, tl.target_options) if er is None else er
        self.best_key = _key(tl)
        self.best = tl.plan()
        self.improved = 0
        self.dirty = False
        self.refresh(tl)

    def refresh(self, tl: Timeline):
        """Recompute the unscheduled targets and their cumulative picking odds."""
        self.un = [t for t in self.has if tl.assigned[t] < 0]
        self.cw = list(itertools.accumulate(self.er.target_weights(tl, self.un)))


def _key(tl: Timeline) -> tuple:
    """What the LNS keeps the best plan by: (value, count), after the areas' shortfall."""
    if tl.cover is None:
        return (tl.value, tl.n_observations)
    return tl.score()[:3]


def _window(tl: Timeline, w: _Walk, rng):
    """The destroy window ``(k, lo, hi, forced)`` of one move, None to skip the move.

    80 %: around an option of an unscheduled target (value-weighted), that option then
    ``forced`` in; else around a scheduled observation of a random satellite
    (``forced`` -1).
    """
    pb, er = tl.pb, w.er
    if w.un and rng.random() < _P_TARGETED:
        t = rng.choices(w.un, cum_weights=w.cw, k=1)[0]
        if tl.assigned[t] >= 0:
            return None
        c = rng.choice(tl.target_options[t])
        rad = rng.choice(_RAD_TARGET)
        forced = -1 if pb.is_look(c) else c  # a look alone is worth nothing: its product
        return pb.option_sat[c], pb.option_start[c] - rad, pb.option_end[c] + rad, forced
    k = rng.randrange(pb.n_sats)
    if not tl.lines[k]:
        return None
    c0 = er.cheap_pick(tl, k, rng) if er.binds(tl, k) else rng.choice(tl.lines[k])
    rad = rng.choice(_RAD_RANDOM)
    return k, pb.option_start[c0] - rad, pb.option_end[c0] + rad, -1


def _force(tl: Timeline, forced: int, removed, er: EnergyRank, rng):
    """Insert option ``forced`` when it fits (making battery room if that is all it
    lacks); the observations removed for it join ``removed``."""
    if tl.check(forced) is not None:
        tl.insert(forced)
    elif tl.battery_failed:
        m2 = len(tl.log)
        room = make_room(tl, forced, er, rng)
        if room is None:
            tl.undo_to(m2)
        else:
            removed += room
            tl.insert(forced)
    return removed


def _reinsert(tl: Timeline, er: EnergyRank, k: int, lo: float, hi: float, removed, gap, rng):
    """Re-insert the removed targets anywhere and the waiting targets with an option in
    the free time ``gap`` the destroy left on satellite k (within :data:`_POOL_REACH`
    of the window) on k, options starting in that free time only, heaviest (or most
    value per Wh) first, noisy."""
    pb = tl.pb
    moved = {pb.option_target[c] for c in removed}
    pool = set(moved)
    assigned, option_target, option_end = tl.assigned, pb.option_target, pb.option_end
    g0, g1 = gap
    first, starts = pb.sat_lo[k], pb.sat_starts[k]
    span = first + bisect.bisect_left(starts, g0), first + bisect.bisect_left(starts, g1)
    a = first + bisect.bisect_left(starts, max(g0, lo - _POOL_REACH))
    b = first + bisect.bisect_left(starts, min(g1, hi + _POOL_REACH))
    pool.update(
        option_target[c]
        for c in range(a, b)
        if option_end[c] <= g1 and assigned[option_target[c]] < 0
    )
    if er.binds(tl, k):
        pool = er.order(pool, rng)
    else:
        pool = sorted(
            pool, key=lambda t: (-pb.target_value[t] * (1 + _ORDER_NOISE * rng.random()), t)
        )
    # the greedy on noisy costs; only satellite k has new room for a target that was waiting
    greedy_pass(pool, lambda t: tl.insert_choices(t, rng, None if t in moved else span), tl.insert)
    if pb.stereo is not None:
        drop_stray_looks(tl, [t for t in pool if pb.stereo.target_products[t]])


def _move(tl: Timeline, w: _Walk, mark: int, rng) -> bool:
    """One destroy-and-repair move (module docstring); False when it was skipped."""
    win = _window(tl, w, rng)
    if win is None:
        return False
    k, lo, hi, forced = win
    removed = _destroy(tl, k, lo, hi)
    if removed is None:
        tl.undo_to(mark)
        return False
    gap = _gap(tl, k, lo)
    if forced >= 0:
        removed = _force(tl, forced, removed, w.er, rng)
    _reinsert(tl, w.er, k, lo, hi, removed, gap, rng)
    return True


def adopt(tl: Timeline, w, offer) -> bool:
    """Continue from an offered plan ``(value, assigned)`` when it beats the best one.

    Args:
      tl: Timeline (between two moves: nothing to undo).
      w: the walk's state (or None outside the LNS: the plan is compared with ``tl``).
      offer: ``(value, assigned)`` or None.
    Returns:
      bool, whether ``tl`` now holds the offered plan.
    """
    best = tl.value if w is None else w.best_key[-2]
    if offer is None or offer[0] <= best:
        return False
    tl.restore(offer[1])
    if w is not None:
        w.improved += 1
        w.best_key = _key(tl)
        w.best = tl.plan()
        w.refresh(tl)
        w.dirty = False
    return True


def _accept(tl: Timeline, w: _Walk, base, mark: int, thr: float, it: int, rng):
    """Threshold acceptance of a move (loses at most ``thr * U(0, 1)``) and the
    bookkeeping of the best plan and of the unscheduled list."""
    if tl.value < base[-3] - thr * rng.random() - 1e-9:  # the score's value entry
        tl.undo_to(mark)
        return
    w.dirty |= tl.score() != base
    if w.dirty and it % _REFRESH_EVERY == 0:
        w.refresh(tl)
        w.dirty = False
    _keep_best(tl, w)
    tl.commit()


def _keep_best(tl: Timeline, w: _Walk) -> None:
    """Keep the plan of ``tl`` as the walk's best when it beats it."""
    key = _key(tl)
    if key > w.best_key:
        w.improved += 1
        w.best_key = key
        w.best = tl.plan()


def _area_step(tl: Timeline, w: _Walk, aw: AreaWalk, deadline: float) -> None:
    """One area move, kept when the plan's score did not drop, else undone."""
    base = tl.score()
    mark = len(tl.log)
    area_move(tl, aw, deadline)
    if tl.score() < base:
        tl.undo_to(mark)
        return
    w.dirty |= tl.score() != base
    _keep_best(tl, w)
    tl.commit()


def lns(
    tl: Timeline,
    deadline: float,
    rng,
    max_iters=None,
    report=None,
    incoming=None,
    rank=None,
    areas=None,
) -> int:
    """Large-neighbourhood search until ``deadline`` (or ``max_iters``).

    Args:
      tl: Timeline holding the start plan; it ends at the best plan.
      deadline: float, ``time.monotonic()`` value at which to stop [s].
      rng: ``random.Random`` (the stream of every random choice of the moves).
      max_iters: cap on the iterations (None: the deadline alone).
      report: callable ``report(it, improved)`` called every few seconds (progress
        display), or None.
      incoming: optional callable ``incoming(value)`` polled every :data:`_POLL_EVERY`
        seconds: ``(value, assigned)`` of a feasible plan worth more than ``value``
        (per target its option id, -1: none), which the walk then continues from as its
        best plan, or None (the bound worker's plans, :meth:`BoundWorker.plan`).
      rank: the :class:`EnergyRank` of ``tl``'s problem and options, for a caller that
        runs the LNS in several calls (one pass over every option); None: built here.
      areas: the :class:`jaxspline.search.area_moves.AreaWalk` of the area moves, for a
        caller that keeps it between calls; None: made here (seeded from ``rng``) when
        the problem has areas.
    Returns:
      int, the number of iterations.
    """
    pb = tl.pb
    t_start = time.monotonic()
    has = [t for t in pb.exclusive_targets() if tl.target_options[t]]
    if tl.cover is not None and areas is None:
        ix = area_index(pb)
        areas = AreaWalk(ix, rng.getrandbits(32)) if ix.windows.g.size else None
    share = _area_share(tl, has) if areas is not None else 0.0
    if not has and areas is None:
        return 0
    w = _Walk(tl, has, rank)
    it = 0
    last = polled = time.monotonic()
    ceiling = plan_ceiling(tl) - _CEILING_TOL * max(1.0, plan_ceiling(tl))
    while (max_iters is None or it < max_iters) and clock.now() < deadline:
        if w.best_key[-2] >= ceiling:  # every target and every coverable sample: optimal
            break
        it += 1
        if incoming is not None and time.monotonic() - polled > _POLL_EVERY:
            polled = time.monotonic()
            adopt(tl, w, incoming(w.best_key[-2]))
        if share > 0.0 and (share >= 1.0 or rng.random() < share):
            _area_step(tl, w, areas, deadline)
            if report is not None and time.monotonic() - last > _REPORT_EVERY:
                last = time.monotonic()
                report(it, w.improved)
            continue
        if pb.stereo is not None and rng.random() < _P_UPGRADE:
            _upgrade_step(tl, w, rng)
            continue
        base = tl.score()
        mark = len(tl.log)
        if not _move(tl, w, mark, rng):
            continue
        if max_iters is not None:
            frac = it / max_iters
        else:
            frac = (time.monotonic() - t_start) / max(1e-9, deadline - t_start)
        _accept(tl, w, base, mark, _TEMPERATURE * max(0.0, 1.0 - frac), it, rng)
        if report is not None and time.monotonic() - last > _REPORT_EVERY:
            last = time.monotonic()
            report(it, w.improved)
    _finish(tl, w)
    return it


def _upgrade_step(tl: Timeline, w: _Walk, rng) -> None:
    """One stereo quality move (:func:`jaxspline.search.stereo.upgrade_product`)."""
    if upgrade_product(tl, rng):
        w.dirty = True
        _keep_best(tl, w)
    tl.commit()


def _finish(tl: Timeline, w: _Walk) -> None:
    """The walk's best plan, without area strips or looks that add nothing."""
    if _key(tl) < w.best_key:
        tl.restore(w.best)
    drop_idle_strips(tl)
    if tl.pb.stereo is not None:
        drop_stray_looks(tl, tl.pb.stereo.stereo_targets.tolist())
    tl.commit()


def plan_ceiling(tl: Timeline) -> float:
    """The most value any plan can have: every target with an option on offer (a stereo
    target its best product), every sample some area option covers.

    Args:
      tl: Timeline (its options on offer).
    Returns:
      float, a bound that every plan meets.
    """
    pb = tl.pb
    most = sum(pb.target_value[t] for t in pb.exclusive_targets() if tl.target_options[t])
    if pb.cover is not None:
        most += pb.cover.union_weight()
    return float(most)


def _area_share(tl: Timeline, has) -> float:
    """The share of the LNS's moves made on areas: the areas' covered weight within
    reach over all value within reach (1 without point or strip targets)."""
    if not has:
        return 1.0
    pb = tl.pb
    areas = pb.cover.union_weight()
    points = sum(pb.target_value[t] for t in has)
    return areas / max(areas + points, 1e-300)


def earliest_pass(tl: Timeline, deadline: float):
    """Move each observation to the earliest feasible option of its target (value unchanged).

    Args:
      tl: Timeline, modified in place.
      deadline: float, ``time.monotonic()`` value at which to stop [s].
    """
    pb = tl.pb
    for t in range(pb.n_targets):
        if clock.now() > deadline:
            return
        c = tl.assigned[t]
        if c < 0 or pb.is_look(c):
            continue
        mark = len(tl.log)
        base = tl.score()
        k = pb.option_sat[c]
        pos0 = tl.lines[k].index(c)
        tl.remove(c)
        if not tl.removal_ok(k, pos0):
            tl.undo_to(mark)
            continue
        best = -1
        for c2 in sorted(tl.target_options[t], key=lambda x: pb.option_end[x]):
            if pb.option_end[c2] >= pb.option_end[c]:
                break
            if tl.check(c2) is not None:
                best = c2
                break
        tl.insert(best if best >= 0 else c)
        if tl.score() < base:
            tl.undo_to(mark)
        tl.commit()
