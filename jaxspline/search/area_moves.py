"""The search's moves on area options: lazy greedy by marginal coverage, pass re-plans, local moves.

Area options (:mod:`jaxspline.search.cover`) are strips of a roll group over slots; a
plan covers each sample once however often it is imaged, so these moves value an
option by the open weight it adds. They work on the one
:class:`jaxspline.search.timeline.Timeline` (every insertion passes its full check:
transitions through the satellite's maneuver model, duty, action cap, battery), next to
the point and strip targets' moves of :mod:`jaxspline.search.lns`:

* :func:`fill` - CELF lazy greedy: a window's open gain is bounded above by prefix sums
  of the rows' open gains (rows of slots under or next to an observation of the same
  satellite count 0); the top of the heap is cut to the part the satellite's timeline
  admits (:func:`fit`), re-evaluated exactly, and taken when it still beats the next
  bound, trimmed to the shortest window of the same gain. Strips with no gain are
  never taken.
* :func:`area_move` - one move of the large-neighbourhood search: re-plan the passes able
  to cover one open sample (:func:`reopt_related`), re-plan one pass
  (:func:`reopt_pass`, exactly with :func:`jaxspline.search.pass_dp.best_runs`), or
  destroy a few strips (random, least marginal contribution, one area's, one
  satellite's, those overlapping a random one) and repair with :func:`fill`; every
  :data:`LOCAL_EVERY` moves local moves (a strip's roll moved to a neighbouring group
  of its pass, an end moved by one slot).

Transition times between a strip and its neighbours are the problem's own
(:meth:`jaxspline.search.problem.Problem.need`); where a pass must be laid out before
its options are known, the time is bounded from above by the largest over the group's
slot boundaries (:func:`need_bound`, rest-to-rest models; other models rely on the
exact check).
"""

from __future__ import annotations

import heapq
import math
import time
from typing import NamedTuple

import numpy as np

from jaxspline.search.cover import gather_ranges
from jaxspline.search.pass_dp import best_runs
from jaxspline.search.timeline import Timeline

__all__ = [
    "LOCAL_EVERY",
    "AreaIndex",
    "AreaWalk",
    "area_index",
    "area_move",
    "fill",
    "fit",
    "local_moves",
    "need_bound",
    "reopt_pass",
    "reopt_related",
]

#: Gains at or below this count as zero (value units).
MIN_GAIN = 1e-10
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
#: Value below which a run is not worth an action.
RUN_PRICE = 1e-10
#: Extra weight per unit of an area's share while areas miss their least share.
MIN_BOOST = 10.0


class Windows(NamedTuple):
    """The greedy's candidate windows: per group its non-empty slots, cut to the longest strip.

    Attributes:
      g, a, b: int64 [W], group and slots ``[a, b)``; r0, r1: int64 [W], their rows.
    """

    g: np.ndarray
    a: np.ndarray
    b: np.ndarray
    r0: np.ndarray
    r1: np.ndarray


class AreaIndex:
    """What the area moves precompute for one problem.

    Attributes:
      pb: the Problem; cv: its CoverTable.
      windows: :class:`Windows`.
      passes: per pass its groups sorted by (pitch, roll); span: int64 [P, 2] its slots.
      roll_order: groups sorted by (pass, pitch, roll); roll_pos: each group's place there.
      los: per group the unit lines of sight at its slot boundaries ([n + 1, 3]), from its
        options (None where the satellite's model needs no lines of sight).
    """

    def __init__(self, pb):
        self.pb = pb
        cv = self.cv = pb.cover
        self.windows = _windows(cv)
        n = int(cv.group_pass.max()) + 1 if cv.n_groups else 0
        order = np.lexsort((cv.group_roll, cv.group_pitch, cv.group_pass))
        cuts = np.searchsorted(cv.group_pass[order], np.arange(n + 1))
        self.passes = [order[cuts[i] : cuts[i + 1]] for i in range(n)]
        end = cv.group_slot0 + cv.group_nslots
        self.span = np.array(
            [[cv.group_slot0[g].min(), end[g].max()] for g in self.passes], np.int64
        ).reshape(-1, 2)
        self.roll_order = order
        self.roll_pos = np.empty_like(order)
        self.roll_pos[order] = np.arange(order.size)
        self.los = _group_los(pb)
        self._gaps = {}
        nrow = cv.group_nslots
        group_of_row = np.repeat(np.arange(cv.n_groups), nrow)
        within = np.arange(cv.n_rows) - np.repeat(cv.group_row0, nrow)
        #: flat index ``sat * (n_slots + 2) + slot + 1`` of every row (busy masks)
        self.row_key = cv.group_sat[group_of_row] * (cv.n_slots + 2) + (
            cv.group_slot0[group_of_row] + within + 1
        )
        self.row_pass = cv.group_pass[group_of_row]

    def gaps(self, p: int) -> np.ndarray:
        """Slots between two strips of pass p's groups (int [G, G], >= 1; cached)."""
        if p not in self._gaps:
            self._gaps[p] = pass_gaps(self, self.passes[p])
        return self._gaps[p]


def area_index(pb) -> AreaIndex:
    """The problem's :class:`AreaIndex`, built on first use and kept on the problem."""
    if pb.area_index is None:
        pb.area_index = AreaIndex(pb)
    return pb.area_index


def _windows(cv) -> Windows:
    """Each group's non-empty slots, clipped to the longest strip (every such window)."""
    nonempty = np.diff(cv.indptr) > 0
    out = []
    for g in range(cv.n_groups):
        r0, n = int(cv.group_row0[g]), int(cv.group_nslots[g])
        rows = np.nonzero(nonempty[r0 : r0 + n])[0]
        if rows.size == 0:
            continue
        sat = int(cv.group_sat[g])
        lo, hi = int(rows[0]), int(rows[-1]) + 1
        need, most = int(cv.min_slots[sat]), int(cv.max_slots[sat])
        if hi - lo < need:
            hi = min(n, lo + need)
            lo = max(0, hi - need)
            if hi - lo < need:
                continue
        s0 = int(cv.group_slot0[g])
        for k in range(lo, max(lo, hi - most) + 1):
            out.append((g, s0 + k, s0 + min(hi, k + most)))
    arr = np.array(out, dtype=np.int64).reshape(-1, 3)
    r = np.array([cv.rows(*w) for w in arr], dtype=np.int64).reshape(-1, 2)
    return Windows(arr[:, 0], arr[:, 1], arr[:, 2], r[:, 0], r[:, 1])


def _group_los(pb) -> list:
    """Per group the lines of sight at its slot boundaries, read off its options."""
    cv = pb.cover
    out = [None] * cv.n_groups
    ids = np.flatnonzero(cv.option_group >= 0)
    by_group = {}
    for c in ids.tolist():
        g = int(cv.option_group[c])
        if pb.tables[int(cv.group_sat[g])] is None:
            continue
        d = by_group.setdefault(g, {})
        d.setdefault(int(cv.option_a[c]), pb.option_start_los[c])
        d.setdefault(int(cv.option_b[c]), pb.option_end_los[c])
    for g, d in by_group.items():
        s0, n = int(cv.group_slot0[g]), int(cv.group_nslots[g])
        known = sorted(d)
        rows = []
        for s in range(s0, s0 + n + 1):  # a boundary no option touches: its nearest one
            j = min(known, key=lambda x, s=s: abs(x - s))
            rows.append(d[j])
        out[g] = np.asarray(rows, np.float64)
    return out


def _angles(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Angles [rad] between unit vectors u [..., 3] and v [..., 3]."""
    c = np.cross(u, v)
    return np.arctan2(np.sqrt(np.sum(c * c, axis=-1)), np.sum(u * v, axis=-1))


def need_bound(ix: AreaIndex, c: int, g: int, before: bool) -> float:
    """An upper bound of the transition time between option c and any strip of group g.

    Args:
      ix: AreaIndex; c: option id; g: group; before: c comes before the strip.
    Returns:
      float [s]: the satellite's slew table at the largest angle between c's line of
      sight and the group's boundary ones (0 when the model needs no lines of sight:
      the exact check decides).
    """
    pb = ix.pb
    k = int(ix.cv.group_sat[g])
    table, los = pb.tables[k], ix.los[g]
    if table is None or los is None:
        return 0.0
    u = np.asarray(pb.option_end_los[c] if before else pb.option_start_los[c])
    return float(table.scalar(float(_angles(u[None, :], los).max())))


def pass_gaps(ix: AreaIndex, groups) -> np.ndarray:
    """Slots needed between a strip of ``groups[i]`` and a later one of ``groups[j]``: the
    slew table at the largest angle between their boundary lines of sight (>= 1); for a
    model that needs no lines of sight, the fewest slots after which the problem's own
    transition (:meth:`Problem.need`) from an option of ``groups[i]`` ending mid-pass to
    one of ``groups[j]`` fits (:func:`_exact_gaps`)."""
    pb = ix.pb
    cv = ix.cv
    k = int(cv.group_sat[groups[0]])
    table = pb.tables[k]
    n = len(groups)
    if table is None or any(ix.los[g] is None for g in groups):
        return _exact_gaps(ix, groups)
    b = max(ix.los[g].shape[0] for g in groups)
    los = np.stack([np.pad(ix.los[g], ((0, b - ix.los[g].shape[0]), (0, 0)), mode="edge")
                    for g in groups])  # fmt: skip
    dots = np.einsum("ibc,jdc->ijbd", los, los).reshape(n, n, -1).min(axis=-1)
    need = table(np.arccos(np.clip(dots, -1.0, 1.0)))
    return np.maximum(np.ceil(np.asarray(need) / cv.slot_s - 1e-9).astype(np.int64), 1)


def _exact_gaps(ix: AreaIndex, groups, most: int = 8) -> np.ndarray:
    """The gap matrix of :func:`pass_gaps` from exact transitions: per pair of groups, an
    option of the first ending at a boundary shared by both and options of the second
    starting 1, 2, ... slots later (at most ``most``; never feasible: ``most``)."""
    pb, cv = ix.pb, ix.cv
    n = len(groups)
    ends, starts = {}, {}
    for c in np.flatnonzero(np.isin(cv.option_group, groups)).tolist():
        g = int(cv.option_group[c])
        ends.setdefault((g, int(cv.option_b[c])), c)
        starts.setdefault((g, int(cv.option_a[c])), c)
    out = np.full((n, n), most, np.int64)
    for i, gi in enumerate(groups):
        lo_i, hi_i = int(cv.group_slot0[gi]), int(cv.group_slot0[gi] + cv.group_nslots[gi])
        for j, gj in enumerate(groups):
            lo_j = int(cv.group_slot0[gj])
            t = max(lo_i + 1, min(hi_i, lo_j + 1))  # the end slot the test is made at
            c = ends.get((int(gi), t))
            if c is None:
                continue
            for k in range(1, most):
                d = starts.get((int(gj), t + k))
                if d is not None and k * cv.slot_s >= pb.need(c, d):
                    out[i, j] = k
                    break
    return out


# ---------------------------------------------------------------- fitting one strip
def _area_ids(tl: Timeline, k: int) -> list:
    """Satellite k's area observations, in time order."""
    og = tl.pb.cover.option_group
    return [c for c in tl.lines[k] if og[c] >= 0]


def free_slots(tl: Timeline, ix: AreaIndex, g: int, lo: int, hi: int, skip=-1) -> list:
    """The free slot ranges ``[a, b)`` meeting ``[lo, hi)`` where a strip of group g may lie
    between the satellite's other observations (``skip`` left out; only those near
    ``[lo, hi)`` are looked at), each neighbour kept at least :func:`need_bound` away,
    inside the horizon."""
    pb, cv = tl.pb, ix.cv
    k = int(cv.group_sat[g])
    slot = cv.slot_s
    t_lo, t_hi = lo * slot, hi * slot
    bounds = [0.0]
    starts, ends, line = tl.line_starts[k], tl.line_ends[k], tl.lines[k]
    reach = float(pb.far[k])
    for i, c in enumerate(line):
        if c == skip or ends[i] < t_lo - reach or starts[i] > t_hi + reach:
            continue
        bounds += [
            starts[i] - need_bound(ix, c, g, before=False),
            ends[i] + need_bound(ix, c, g, before=True),
        ]
    bounds.append(cv.n_slots * slot)
    out = []
    for lo_s, hi_s in zip(bounds[0::2], bounds[1::2], strict=True):
        a = max(int(math.ceil(lo_s / slot - 1e-9)), 0)
        b = min(int(math.floor(hi_s / slot + 1e-9)), cv.n_slots)
        if b > a and b > lo and a < hi:
            out.append((a, b))
    return out


def _transitions_ok(tl: Timeline, c: int) -> str:
    """Whether option c fits between its satellite's observations by time and maneuvers
    alone: "" when it does, else "in" / "out" (the transition that fails) or "overlap"."""
    pb = tl.pb
    k, s, e = pb.option_sat[c], pb.option_start[c], pb.option_end[c]
    pos = tl._slot(k, s, e)
    if pos < 0:
        return "overlap"
    line = tl.lines[k]
    if pos > 0:
        if s - tl.line_ends[k][pos - 1] < tl.need(line[pos - 1], c):
            return "in"
    elif s < pb.option_first[c]:
        return "in"
    if pos < len(line) and tl.line_starts[k][pos] - e < tl.need(c, line[pos]):
        return "out"
    return ""


def fit(tl: Timeline, ix: AreaIndex, g: int, a: int, b: int, skip=-1):
    """The best sub-window of the strip (group g, slots ``[a, b)``) that the satellite's
    timeline admits by time and maneuvers, and its option.

    The window is cut by :func:`free_slots`; a piece shorter than the shortest strip grows
    inside its free range and the group's slots; each piece then shrinks from the side
    whose transition fails (exact, :meth:`Problem.need`) until it fits; of the pieces the
    one of largest exact gain is returned (duty, cap and battery are :meth:`Timeline.check`'s).

    Args:
      tl: Timeline; ix: AreaIndex; g: group; a, b: wanted slots; skip: an option ignored.
    Returns:
      ``(a', b', option)`` or None.
    """
    cv = ix.cv
    k = int(cv.group_sat[g])
    lo_g = int(cv.group_slot0[g])
    hi_g = lo_g + int(cv.group_nslots[g])
    need = int(cv.min_slots[k])
    best, best_gain = None, -1.0
    for lo, hi in free_slots(tl, ix, g, a, b, skip):
        pa, pb_ = max(a, lo), min(b, hi)
        if pb_ <= pa:
            continue
        if pb_ - pa < need:
            lo2, hi2 = max(lo, lo_g), min(hi, hi_g)
            pb_ = min(hi2, pa + need)
            pa = max(lo2, pb_ - need)
        got = _shrink(tl, cv, g, pa, pb_, need)
        if got is None:
            continue
        gain = tl.cover.gain(g, got[0], got[1])
        if gain > best_gain:
            best, best_gain = got, gain
    return best


def _shrink(tl: Timeline, cv, g: int, a: int, b: int, need: int):
    """``(a, b, option)`` of the largest window inside ``[a, b)`` that fits, shrinking from
    the failing side; None when none of at least ``need`` slots does."""
    while b - a >= need:
        c = cv.option_of(g, a, b)
        if c < 0:
            c = _nearest(cv, g, a, b, need)
            if c < 0:
                return None
            a, b = int(cv.option_a[c]), int(cv.option_b[c])
        why = _transitions_ok(tl, c)
        if not why:
            return a, b, c
        if why == "in":
            a += 1
        elif why == "out":
            b -= 1
        else:
            return None
    return None


def _nearest(cv, g: int, a: int, b: int, need: int) -> int:
    """An option of group g inside ``[a, b)`` (the longest, earliest), or -1."""
    for length in range(min(b - a, int(cv.max_slots[cv.group_sat[g]])), need - 1, -1):
        for s in range(a, b - length + 1):
            c = cv.option_of(g, s, s + length)
            if c >= 0:
                return c
    return -1


def _trim(tl: Timeline, cv, g: int, a: int, b: int, gain: float):
    """The shortest window inside ``[a, b)`` with the same gain that is an option."""
    need = int(cv.min_slots[cv.group_sat[g]])
    gain_of = tl.cover.gain
    while b - a > need and cv.option_of(g, a + 1, b) >= 0 and gain_of(g, a + 1, b) >= gain - 1e-15:
        a += 1
    while b - a > need and cv.option_of(g, a, b - 1) >= 0 and gain_of(g, a, b - 1) >= gain - 1e-15:
        b -= 1
    return a, b, cv.option_of(g, a, b)


# ---------------------------------------------------------------- the lazy greedy
def _busy(tl: Timeline, cv) -> np.ndarray:
    """bool [S, n_slots + 2]: slot ``k`` (column ``k + 1``) under an observation of the
    satellite or next to one (no strip that fits can use it)."""
    busy = np.zeros((tl.pb.n_sats, cv.n_slots + 2), bool)
    for k in range(tl.pb.n_sats):
        for s, e in zip(tl.line_starts[k], tl.line_ends[k], strict=True):
            _mark(busy, cv, k, s, e)
    return busy


def _mark(busy: np.ndarray, cv, k: int, s: float, e: float) -> None:
    """Mark the slots of ``[s, e]`` on satellite k and one on each side busy."""
    a = max(int(math.floor(s / cv.slot_s + 1e-9)), 0)
    b = min(int(math.ceil(e / cv.slot_s - 1e-9)), cv.n_slots)
    busy[k, a : b + 2] = True


def _open_cum(tl: Timeline, ix: AreaIndex, busy: np.ndarray, boost) -> np.ndarray:
    """Prefix sums of the rows' open gains (busy rows 0; plus the areas' boost)."""
    gain = tl.cover.row_gain if boost is None else tl.cover.row_gain + boost
    return np.concatenate([[0.0], np.cumsum(np.where(busy.ravel()[ix.row_key], 0.0, gain))])


def _boost(tl: Timeline, ix: AreaIndex):
    """Extra row weight for the areas still short of their least share (None: none are):
    :data:`MIN_BOOST` per unit of the open samples' share of such areas."""
    cover = tl.cover
    cv = ix.cv
    has = np.isfinite(cv.area_min)
    if not has.any():
        return None
    short = has & (cover.area_share < cv.area_min - 1e-12)
    if not short.any():
        return None
    extra = np.where(short[cv.area] & (cover.cnt == 0), MIN_BOOST * cv.share, 0.0)
    return cv.row_values(extra)


def _gain(tl: Timeline, cv, g: int, a: int, b: int, boosted: bool) -> float:
    """The exact gain of a strip (with the boost's share of areas short of their least)."""
    gain = tl.cover.gain(g, a, b)
    if not boosted:
        return gain
    s = cv.samples(g, a, b)
    s = s[tl.cover.cnt[s] == 0]
    short = np.isfinite(cv.area_min) & (tl.cover.area_share < cv.area_min - 1e-12)
    return gain + MIN_BOOST * float(np.sum(np.where(short[cv.area[s]], cv.share[s], 0.0)))


def fill(tl: Timeline, ix: AreaIndex, deadline: float, banned=None, fails=None) -> int:
    """Add area strips by largest exact marginal gain until none gains or the cap is reached.

    Args:
      tl: Timeline, modified in place (not committed).
      ix: AreaIndex.
      deadline: ``time.monotonic()`` instant to stop at.
      banned: optional set of groups not to use.
      fails: optional dict window -> satellite's area observations at which it did not
        fit (shared across calls: a window is skipped while that timeline is unchanged).
    Returns:
      number of strips added.
    """
    pb, cv, win = tl.pb, ix.cv, ix.windows
    busy = _busy(tl, cv)
    boost = _boost(tl, ix)
    cum = _open_cum(tl, ix, busy, boost)
    ub = cum[win.r1] - cum[win.r0]
    cand = np.nonzero(ub > MIN_GAIN)[0]
    heap = list(zip((-ub[cand]).tolist(), cand.tolist(), strict=True))
    heapq.heapify(heap)
    added = 0
    cap = math.inf if pb.max_actions is None else pb.max_actions
    while heap and tl.n_observations < cap and time.monotonic() < deadline:
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
        k = int(cv.group_sat[g])
        sig = None
        if fails is not None:
            sig = tuple(tl.lines[k])
            if fails.get(i) == sig:
                continue
        got = fit(tl, ix, g, int(win.a[i]), int(win.b[i]))
        if got is None:
            if fails is not None:
                fails[i] = sig
            continue
        gain = _gain(tl, cv, g, got[0], got[1], boost is not None)
        if gain <= MIN_GAIN:
            continue
        if gain < top - 1e-15:
            heapq.heappush(heap, (-gain, i))
            continue
        a, b, c = _trim(tl, cv, g, got[0], got[1], tl.cover.gain(g, got[0], got[1]))
        if c < 0 or tl.check(c) is None:
            continue
        tl.insert(c)
        _mark(busy, cv, k, a * cv.slot_s, b * cv.slot_s)
        if boost is not None:
            boost = _boost(tl, ix)
        cum = _open_cum(tl, ix, busy, boost)
        added += 1
    return added


# ---------------------------------------------------------------- pass re-plans
def reopt_pass(tl: Timeline, ix: AreaIndex, p: int) -> int:
    """Replace the strips of pass p by the best set of strips of that pass.

    The pass's strips are removed; :func:`jaxspline.search.pass_dp.best_runs` picks the
    runs of best open value (at most the actions left, other observations of the
    satellite blocking their maneuver gaps, :func:`free_slots`), and each run goes in if
    :meth:`Timeline.check` passes.

    Args:
      tl: Timeline, modified in place; ix: AreaIndex; p: pass.
    Returns:
      number of strips added.
    """
    pb, cv = tl.pb, ix.cv
    groups = ix.passes[p]
    k = int(cv.group_sat[groups[0]])
    p0, p1 = (int(x) for x in ix.span[p])
    for c in _area_ids(tl, k):
        if cv.group_pass[cv.option_group[c]] == p:
            _remove(tl, c)
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
    useful = np.nonzero((vals * allowed).sum(axis=1) > RUN_PRICE)[0]
    if useful.size == 0 or rmax < 1:
        return 0
    _, runs = best_runs(
        vals[useful],
        allowed[useful],
        ix.gaps(p)[np.ix_(useful, useful)],
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
        for c in _area_ids(tl, k):
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
        line = _area_ids(tl, tl.pb.option_sat[c0])
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
        self.stats = {"pass_moves": 0, "related_moves": 0, "destroy_moves": 0, "local_moves": 0}


def area_move(tl: Timeline, walk: AreaWalk, deadline: float) -> None:
    """One move on the area strips (module docstring); the caller accepts or undoes it."""
    ix, rng = walk.ix, walk.rng
    walk.moves += 1
    u = rng.random()
    if u < PASS_PROB and ix.passes:
        ow = np.bincount(ix.row_pass, weights=tl.cover.row_gain, minlength=len(ix.passes))
        ow = ow + 1e-9
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
