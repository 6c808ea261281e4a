"""The LNS moves on area options: pass re-plans, destroy and repair, local moves.

Next to the point and strip targets' moves of :mod:`jaxspline.search.lns`, on the one
:class:`jaxspline.search.timeline.Timeline`:

* :func:`area_move` - one move: re-plan the passes able to cover one open sample
  (:func:`reopt_related`), re-plan one pass (:func:`reopt_pass`, exactly with
  :func:`jaxspline.search.pass_dp.best_runs`), or destroy a few strips (random, least
  marginal contribution, one area's, one satellite's, those overlapping a random one)
  and repair with :func:`jaxspline.search.area_fill.fill`; every :data:`LOCAL_EVERY`
  moves local moves (a strip's roll moved to a neighbouring group of its pass, an end
  moved by one slot).
"""

from __future__ import annotations

import math

import numpy as np

from jaxspline.search.area_fill import (
    MIN_GAIN,
    AreaIndex,
    area_strips,
    fill,
    fit,
    free_slots,
)
from jaxspline.search.cover import gather_ranges
from jaxspline.search.pass_dp import best_runs
from jaxspline.search.timeline import Timeline

__all__ = [
    "LOCAL_EVERY",
    "drop_idle_strips",
    "AreaWalk",
    "area_move",
    "local_moves",
    "reopt_pass",
    "reopt_related",
]

#: Probability that an area move first removes a few point observations (room for strips).
ROOM_PROB = 0.1
#: Most strips removed by one destroy.
MAX_DESTROY = 4
#: Moves between exact recomputations of the row gains.
REFRESH_EVERY = 100
#: Probability that a destroy's removed groups are banned from its repair.
BAN_PROB = 0.5
#: Moves between rounds of local moves.
LOCAL_EVERY = 50
#: Groups on each side (by roll, same pass) a local move tries.
ROLL_NEIGHBOURS = 3
#: Probability that a move re-plans one pass; of re-planning the passes of an open sample.
PASS_PROB, RELATED_PROB = 0.2, 0.6
#: Most passes a related move re-plans.
RELATED_MOST = 3
#: Most strips a pass re-plan puts in one pass.
MAX_RUNS_PER_PASS = 8
#: Most groups (those of most open value) a pass re-plan chooses among.
DP_GROUPS = 48
#: Value below which a run is not worth an action.
RUN_PRICE = 1e-10


def reopt_pass(tl: Timeline, ix: AreaIndex, p: int) -> int:
    """Replace the strips of pass p by the best set of strips of that pass.

    The pass's strips are removed; :func:`jaxspline.search.pass_dp.best_runs` picks the
    runs of best open value (at most the actions left, other observations of the
    satellite blocking their maneuver gaps, :func:`free_slots`), and each run goes in if
    :meth:`Timeline.check` passes. In a pass of several pitches a sample may lie in rows
    of different slots, which the DP would count twice: there the pass is refilled by the
    lazy greedy (:func:`fill`) on its own windows.

    Args:
      tl: Timeline, modified in place; ix: AreaIndex; p: pass.
    Returns:
      number of strips added.
    """
    pb, cv = tl.pb, ix.cv
    groups = ix.passes[p]
    k = int(cv.group_sat[groups[0]])
    p0, p1 = (int(x) for x in ix.span[p])
    for c in area_strips(tl, k):
        if cv.group_pass[cv.option_group[c]] == p:
            _remove(tl, c)
    if ix.pitched[p]:  # rows of different slots overlap: the DP would count them twice
        return fill(tl, ix, math.inf, only=ix.pass_windows[p])
    t_n = p1 - p0
    vals = np.zeros((groups.size, t_n))
    allowed = np.zeros((groups.size, t_n), dtype=bool)
    for j, g in enumerate(groups):
        s0, n, r0 = int(cv.group_slot0[g]), int(cv.group_nslots[g]), int(cv.group_row0[g])
        vals[j, s0 - p0 : s0 - p0 + n] = tl.cover.row_gain[r0 : r0 + n]
        for lo, hi in free_slots(tl, ix, int(g), s0, s0 + n):
            allowed[j, max(lo, s0) - p0 : min(hi, s0 + n) - p0] = True
    cap = math.inf if pb.max_actions is None else pb.max_actions - tl.n_observations
    need = int(cv.min_slots[k])
    rmax = int(min(cap, (t_n + 1) // (need + 1), MAX_RUNS_PER_PASS))
    worth = (vals * allowed).sum(axis=1)
    useful = np.nonzero(worth > RUN_PRICE)[0]
    if useful.size == 0 or rmax < 1:
        return 0
    if useful.size > DP_GROUPS:  # the DP is quadratic in the groups: the most open value
        useful = np.sort(useful[np.argsort(-worth[useful], kind="stable")[:DP_GROUPS]])
    _, runs = best_runs(
        vals[useful],
        allowed[useful],
        ix.gaps(p, useful),
        need,
        int(cv.max_slots[k]),
        rmax,
        price=RUN_PRICE,
    )
    added = 0
    for j, s, t in runs:
        c = cv.option_of(int(groups[useful[j]]), p0 + s, p0 + t)
        if c >= 0 and tl.check(c) is not None:
            tl.insert(c)
            added += 1
    return added


def _remove(tl: Timeline, c: int) -> bool:
    """Remove observation c when the plan stays feasible without it (else leave it)."""
    k = tl.pb.option_sat[c]
    pos = tl.lines[k].index(c)
    mark = len(tl.log)
    tl.remove(c)
    if tl.removal_ok(k, pos):
        return True
    tl.undo_to(mark)
    return False


def related_passes(tl: Timeline, ix: AreaIndex, rng, most: int) -> list:
    """Up to ``most`` passes able to cover one open sample drawn by weight (random order)."""
    cv = ix.cv
    open_w = np.where(tl.cover.cnt == 0, cv.weight, 0.0)
    total = open_w.sum()
    if total <= 0:
        return []
    j = int(rng.choice(open_w.size, p=open_w / total))
    ptr, rows = cv.transpose()
    pos, _ = gather_ranges(ptr, np.array([j]))
    passes = np.unique(ix.row_pass[rows[pos]])
    return [int(p) for p in rng.permutation(passes)[:most]]


def reopt_related(tl: Timeline, ix: AreaIndex, rng, most: int = RELATED_MOST, sweeps: int = 2):
    """Clear the passes related to one open sample and re-plan them one by one, twice.

    Returns:
      the passes re-planned.
    """
    cv = ix.cv
    passes = related_passes(tl, ix, rng, most)
    for p in passes:
        k = int(cv.group_sat[ix.passes[p][0]])
        for c in area_strips(tl, k):
            if cv.group_pass[cv.option_group[c]] == p:
                _remove(tl, c)
    for _ in range(sweeps):
        for p in passes:
            reopt_pass(tl, ix, p)
    return passes


# ---------------------------------------------------------------- destroy, local moves
def _destroy(tl: Timeline, ix: AreaIndex, rng) -> list:
    """Remove a few area strips by one of five rules; returns their groups."""
    cv = ix.cv
    ids = [c for line in tl.lines for c in line if cv.option_group[c] >= 0]
    if not ids:
        return []
    n = int(rng.integers(1, 1 + min(len(ids), MAX_DESTROY)))
    rule = int(rng.integers(5))
    cover = tl.cover
    if rule == 1:  # least marginal contribution (randomised)
        loss = np.array([cover.loss(c) for c in ids])
        w = 1.0 / (1e-6 + loss / max(loss.max(), 1e-12))
        chosen = [ids[j] for j in rng.choice(len(ids), size=n, replace=False, p=w / w.sum())]
    elif rule == 2:  # one area's strips
        a = int(rng.integers(cv.n_areas))
        mine = [c for c in ids if np.any(cv.area[cover.option_samples(c)] == a)]
        chosen = list(rng.permutation(mine)[:n]) if mine else [ids[int(rng.integers(len(ids)))]]
    elif rule == 3:  # one satellite's strips near one of them
        c0 = ids[int(rng.integers(len(ids)))]
        line = area_strips(tl, tl.pb.option_sat[c0])
        j = line.index(c0)
        chosen = line[max(0, j - n // 2) : j - n // 2 + n] or [c0]
    elif rule == 4:  # the strips sharing most samples with a random one
        s0 = cover.option_samples(ids[int(rng.integers(len(ids)))])
        share = [
            (len(np.intersect1d(s0, cover.option_samples(c), assume_unique=True)), c) for c in ids
        ]
        share.sort(reverse=True)
        chosen = [c for _, c in share[:n]]
    else:
        chosen = [ids[j] for j in rng.choice(len(ids), size=n, replace=False)]
    return [int(cv.option_group[c]) for c in chosen if _remove(tl, int(c))]


def local_moves(tl: Timeline, ix: AreaIndex) -> int:
    """One round of first-improvement local moves over all area strips.

    For each strip: its group replaced by one of the :data:`ROLL_NEIGHBOURS` nearest-roll
    groups on each side in the same pass and at the same pitch (same slots, then
    fitted), or one end moved by one slot; a move is kept when its exact gain exceeds
    the strip's loss.

    Returns:
      number of moves kept.
    """
    cv = ix.cv
    kept = 0
    for c in sorted(c for line in tl.lines for c in line if cv.option_group[c] >= 0):
        if c not in tl.lines[tl.pb.option_sat[c]]:
            continue
        g, a, b = int(cv.option_group[c]), int(cv.option_a[c]), int(cv.option_b[c])
        base = tl.cover.loss(c)
        mark = len(tl.log)
        if not _remove(tl, c):
            continue
        tries = [(g, a - 1, b), (g, a + 1, b), (g, a, b + 1), (g, a, b - 1)]
        p0 = ix.roll_pos[g]
        for d in range(-ROLL_NEIGHBOURS, ROLL_NEIGHBOURS + 1):
            j = p0 + d
            if d and 0 <= j < ix.roll_order.size:
                h = int(ix.roll_order[j])
                if cv.group_pass[h] == cv.group_pass[g] and cv.group_pitch[h] == cv.group_pitch[g]:
                    tries.append((h, a, b))
        best, best_gain = c, base + 1e-12
        for og, oa, ob in tries:
            got = fit(tl, ix, og, oa, ob)
            if got is None:
                continue
            gain = tl.cover.gain(og, got[0], got[1])
            if gain > best_gain and tl.check(got[2]) is not None:
                best, best_gain = got[2], gain
        if best == c:
            tl.undo_to(mark)
        else:
            tl.insert(best)
            kept += 1
    return kept


# ---------------------------------------------------------------- one LNS move
class AreaWalk:
    """The area moves' state between LNS iterations.

    Attributes:
      ix: AreaIndex; rng: numpy Generator of the moves; moves: moves made;
      fails: the greedy's memo of windows that did not fit; stats: moves by kind.
    """

    def __init__(self, ix: AreaIndex, seed: int):
        self.ix = ix
        self.rng = np.random.default_rng(seed)
        self.moves = 0
        self.fails: dict = {}
        self.stats = {"pass_moves": 0, "related_moves": 0, "destroy_moves": 0, "local_moves": 0,
                      "room_moves": 0}  # fmt: skip


def area_move(tl: Timeline, walk: AreaWalk, deadline: float) -> None:
    """One move on the area strips (module docstring); the caller accepts or undoes it."""
    ix, rng = walk.ix, walk.rng
    walk.moves += 1
    if rng.random() < ROOM_PROB:  # points give way to strips (the cap, a pass's time)
        freed = _free_points(tl, rng)
        if freed:
            fill(tl, ix, deadline, fails=walk.fails)
            for t in freed:
                tl.best_insert(t)
            walk.stats["room_moves"] += 1
            return
    u = rng.random()
    if u < PASS_PROB and ix.passes:
        ow = np.bincount(ix.row_pass, weights=tl.cover.row_gain, minlength=len(ix.passes))
        ow = np.maximum(ow, 0.0) + 1e-9  # the row gains' rounding may dip below 0
        reopt_pass(tl, ix, int(rng.choice(ow.size, p=ow / ow.sum())))
        fill(tl, ix, deadline, fails=walk.fails)
        walk.stats["pass_moves"] += 1
    elif u < PASS_PROB + RELATED_PROB:
        reopt_related(tl, ix, rng)
        fill(tl, ix, deadline, fails=walk.fails)
        walk.stats["related_moves"] += 1
    else:
        removed = _destroy(tl, ix, rng)
        banned = set(removed) if rng.random() < BAN_PROB else None
        fill(tl, ix, deadline, banned=banned, fails=walk.fails)
        if banned:
            fill(tl, ix, deadline, fails=walk.fails)
        walk.stats["destroy_moves"] += 1
    if walk.moves % LOCAL_EVERY == 0:
        walk.stats["local_moves"] += local_moves(tl, ix)
    if walk.moves % REFRESH_EVERY == 0:
        tl.cover.refresh()


def _free_points(tl: Timeline, rng) -> list:
    """Remove 1 to :data:`MAX_DESTROY` point or strip observations, the least valuable
    most likely; returns their targets (those removed)."""
    pb = tl.pb
    ids = [c for line in tl.lines for c in line if not pb.is_closed(c)]
    if not ids:
        return []
    n = int(rng.integers(1, 1 + min(len(ids), MAX_DESTROY)))
    value = np.array([pb.target_value[pb.option_target[c]] for c in ids]) + 1e-12
    w = 1.0 / value
    chosen = [ids[j] for j in rng.choice(len(ids), size=n, replace=False, p=w / w.sum())]
    return [pb.option_target[c] for c in chosen if _remove(tl, int(c))]


def drop_idle_strips(tl: Timeline) -> int:
    """Remove the area strips that cover no sample alone (they only spend an action),
    latest first, each kept out only when the plan stays feasible. Returns how many went."""
    pb = tl.pb
    if tl.cover is None:
        return 0
    gone = 0
    strips = sorted((c for c in tl.plan() if pb.is_area(c)), key=lambda c: -pb.option_start[c])
    for c in strips:
        if tl.cover.loss(c) > MIN_GAIN:
            continue
        k = pb.option_sat[c]
        pos = tl.lines[k].index(c)
        mark = len(tl.log)
        tl.remove(c)
        if tl.removal_ok(k, pos):
            gone += 1
        else:
            tl.undo_to(mark)
    return gone
