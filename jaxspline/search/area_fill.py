"""Area options in the search: their index, exact fitting, the lazy greedy by marginal gain.

Area options (:mod:`jaxspline.search.cover`) are strips of a roll group over slots; a
plan covers each sample once however often it is imaged, so a strip is valued by the
open weight it adds. Everything works on the one
:class:`jaxspline.search.timeline.Timeline` (every insertion passes its full check:
transitions through the satellite's maneuver model, duty, action cap, battery):

* :class:`AreaIndex` (:func:`area_index`, cached on the problem): per group its slot
  runs, lines of sight and the areas it covers;
* :func:`fit` - the part of a window the satellite's timeline admits, cut exactly;
  :func:`free_slots` its free time;
* :func:`fill` - CELF lazy greedy: a window's open gain is bounded above by prefix sums
  of the rows' open gains (rows of slots under or next to an observation of the same
  satellite count 0); the top of the heap is cut by :func:`fit`, re-evaluated exactly,
  and taken when it still beats the next bound, trimmed to the shortest window of the
  same gain. Strips with no gain are never taken.

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

from jaxspline.search.timeline import Timeline

__all__ = [
    "MIN_GAIN",
    "AreaIndex",
    "SlotRuns",
    "area_index",
    "area_strips",
    "fill",
    "fit",
    "free_slots",
    "need_bound",
    "pass_gaps",
]

#: Gains at or below this count as zero (value units).
MIN_GAIN = 1e-10
#: [rad] added to an angle read off a dot product (its rounding near 0 is ~1e-8 rad).
ANGLE_GUARD = 1e-7
#: Extra weight per unit of an area's share while areas miss their least share.
MIN_BOOST = 10.0


class SlotRuns(NamedTuple):
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
      windows: :class:`SlotRuns`.
      passes: per pass its groups sorted by (pitch, roll); span: int64 [P, 2] its slots.
      roll_order: groups sorted by (pass, pitch, roll); roll_pos: each group's place there.
      los: per group the unit lines of sight at its slot boundaries ([n + 1, 3]), from its
        options (None where the satellite's model needs no lines of sight).
      pitched: bool [P], passes with groups of several pitches (a sample may be imaged
        at several slots of the pass); pass_windows: per pass its windows (ids).
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
        self.pitched = np.array([np.unique(cv.group_pitch[g]).size > 1 for g in self.passes])
        wp = cv.group_pass[self.windows.g]
        self.pass_windows = [np.flatnonzero(wp == p) for p in range(n)]
        self._gaps = {}
        self.bounds = {}  # need_bound by (option, group, before)
        self.ends = self.starts = None  # option ids by (group, end / start slot)
        nrow = cv.group_nslots
        group_of_row = np.repeat(np.arange(cv.n_groups), nrow)
        within = np.arange(cv.n_rows) - np.repeat(cv.group_row0, nrow)
        #: flat index ``sat * (n_slots + 2) + slot + 1`` of every row (busy masks)
        self.row_key = cv.group_sat[group_of_row] * (cv.n_slots + 2) + (
            cv.group_slot0[group_of_row] + within + 1
        )
        self.row_pass = cv.group_pass[group_of_row]

    def gaps(self, p: int, sub=None) -> np.ndarray:
        """Slots between two strips of pass p's groups ``passes[p][sub]`` (int [K, K],
        >= 1; every pair computed once, on first use).

        Args:
          p: pass; sub: int [K], positions in ``passes[p]`` (default: all of them).
        """
        groups = self.passes[p]
        sub = np.arange(groups.size) if sub is None else np.asarray(sub, np.int64)
        full = self._gaps.get(p)
        if full is None:
            full = self._gaps[p] = np.full((groups.size, groups.size), -1, np.int64)
        block = full[np.ix_(sub, sub)]
        ii, jj = np.nonzero(block < 0)
        if ii.size:
            found = pass_gaps(self, groups[sub[ii]], groups[sub[jj]])
            full[sub[ii], sub[jj]] = found
            block[ii, jj] = found
        return block


def area_index(pb) -> AreaIndex:
    """The problem's :class:`AreaIndex`, built on first use and kept on the problem."""
    if pb.area_index is None:
        pb.area_index = AreaIndex(pb)
    return pb.area_index


def _windows(cv) -> SlotRuns:
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
    return SlotRuns(arr[:, 0], arr[:, 1], arr[:, 2], r[:, 0], r[:, 1])


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


def _widest(u: np.ndarray, los: np.ndarray) -> float:
    """The largest angle [rad] between the unit vector u [3] and the rows of los [n, 3]
    (from the smallest dot product, rounded up by :data:`ANGLE_GUARD`)."""
    return math.acos(min(max(float((los @ u).min()), -1.0), 1.0)) + ANGLE_GUARD


def need_bound(ix: AreaIndex, c: int, g: int, before: bool) -> float:
    """An upper bound of the transition time between option c and any strip of group g.

    Args:
      ix: AreaIndex; c: option id; g: group; before: c comes before the strip.
    Returns:
      float [s]: the satellite's slew table at the largest angle between c's line of
      sight and the group's boundary ones (0 when the model needs no lines of sight:
      the exact check decides).
    """
    key = (c, g, before)
    got = ix.bounds.get(key)
    if got is None:
        pb = ix.pb
        k = int(ix.cv.group_sat[g])
        table, los = pb.tables[k], ix.los[g]
        if table is None or los is None:
            got = 0.0
        else:
            u = np.asarray(pb.option_end_los[c] if before else pb.option_start_los[c])
            got = float(table.scalar(_widest(u, los)))
        ix.bounds[key] = got
    return got


def pass_gaps(ix: AreaIndex, gi, gj) -> np.ndarray:
    """Slots needed between a strip of group ``gi[p]`` and a later one of group ``gj[p]``
    (groups of one pass): the slew table at the largest angle between their boundary lines
    of sight (>= 1); for a model that needs no lines of sight, the fewest slots after which
    the problem's own transition (:meth:`Problem.need`) from an option of ``gi[p]`` ending
    mid-pass to one of ``gj[p]`` fits (:func:`_exact_gaps`).

    Args:
      ix: AreaIndex; gi, gj: int [P], group ids.
    Returns:
      int [P].
    """
    pb, cv = ix.pb, ix.cv
    gi, gj = np.asarray(gi, np.int64), np.asarray(gj, np.int64)
    table = pb.tables[int(cv.group_sat[gi[0]])] if gi.size else None
    if table is None or any(ix.los[g] is None for g in np.unique(np.concatenate([gi, gj]))):
        return _exact_gaps(ix, gi, gj)
    out = np.empty(gi.size, np.int64)
    for g in np.unique(gi).tolist():  # one group against all its partners at once
        sel = np.flatnonzero(gi == g)
        b = max(ix.los[int(h)].shape[0] for h in gj[sel])
        los = np.stack([np.pad(ix.los[int(h)], ((0, b - ix.los[int(h)].shape[0]), (0, 0)),
                               mode="edge") for h in gj[sel]])  # fmt: skip
        dots = np.einsum("bc,jdc->jbd", ix.los[g], los).reshape(sel.size, -1).min(axis=-1)
        need = table(np.arccos(np.clip(dots, -1.0, 1.0)))
        out[sel] = np.maximum(np.ceil(np.asarray(need) / cv.slot_s - 1e-9).astype(np.int64), 1)
    return out


def _exact_gaps(ix: AreaIndex, gi, gj, most: int = 8) -> np.ndarray:
    """The gaps of :func:`pass_gaps` from exact transitions: per pair of groups, an option
    of the first ending at a boundary shared by both and options of the second starting 1,
    2, ... slots later (at most ``most``; never feasible: ``most``)."""
    pb, cv = ix.pb, ix.cv
    if ix.ends is None:
        ix.ends, ix.starts = {}, {}
        for c in np.flatnonzero(cv.option_group >= 0).tolist():
            g = int(cv.option_group[c])
            ix.ends.setdefault((g, int(cv.option_b[c])), c)
            ix.starts.setdefault((g, int(cv.option_a[c])), c)
    lo_i = cv.group_slot0[gi]
    hi_i = lo_i + cv.group_nslots[gi]
    t = np.maximum(lo_i + 1, np.minimum(hi_i, cv.group_slot0[gj] + 1))  # the end tested at
    src, dst, pair, step = [], [], [], []
    for p, (a, b, s) in enumerate(zip(gi.tolist(), gj.tolist(), t.tolist(), strict=True)):
        c = ix.ends.get((a, s))
        if c is None:
            continue
        for k in range(1, most):
            d = ix.starts.get((b, s + k))
            if d is not None:
                src.append(c)
                dst.append(d)
                pair.append(p)
                step.append(k)
    out = np.full(gi.size, most, np.int64)
    if src:
        step = np.asarray(step)
        sat = int(cv.group_sat[gi[0]])
        ok = step * cv.slot_s >= pb.closed_needs(src, dst, sat)
        k = np.where(ok, step, most)
        np.minimum.at(out, np.asarray(pair), k)
    return out


# ---------------------------------------------------------------- fitting one strip
def area_strips(tl: Timeline, k: int) -> list:
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


def _shorter(tl: Timeline, cv, g: int, a: int, b: int):
    """``(a', b', option)`` of the strip of most gain inside ``[a, b)`` that is shorter and
    passes :meth:`Timeline.check`, the longest such first; None when none gains."""
    need = int(cv.min_slots[cv.group_sat[g]])
    for length in range(b - a - 1, need - 1, -1):
        best, best_gain = None, MIN_GAIN
        for s in range(a, b - length + 1):
            c = cv.option_of(g, s, s + length)
            if c < 0 or tl.check(c) is None:
                continue
            gain = tl.cover.gain(g, s, s + length)
            if gain > best_gain:
                best, best_gain = (s, s + length, c), gain
        if best is not None:
            return best
    return None


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


def fill(tl: Timeline, ix: AreaIndex, deadline: float, banned=None, fails=None, only=None) -> int:
    """Add area strips by largest exact marginal gain until none gains or the cap is reached.

    Args:
      tl: Timeline, modified in place (not committed).
      ix: AreaIndex.
      deadline: ``time.monotonic()`` instant to stop at.
      banned: optional set of groups not to use.
      fails: optional dict window -> satellite's area observations at which it did not
        fit (shared across calls: a window is skipped while that timeline is unchanged).
      only: optional int array, the windows to choose from (default: all).
    Returns:
      number of strips added.
    """
    pb, cv, win = tl.pb, ix.cv, ix.windows
    busy = _busy(tl, cv)
    boost = _boost(tl, ix)
    cum = _open_cum(tl, ix, busy, boost)
    ub = cum[win.r1] - cum[win.r0]
    cand = np.nonzero(ub > MIN_GAIN)[0]
    if only is not None:
        cand = np.intersect1d(cand, only)
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
        if c < 0 or tl.check(c) is None:  # the duty, cap or battery: a shorter strip may do
            got = _shorter(tl, cv, g, a, b)
            if got is None:
                continue
            a, b, c = got
        tl.insert(c)
        _mark(busy, cv, k, a * cv.slot_s, b * cv.slot_s)
        if boost is not None:
            boost = _boost(tl, ix)
        cum = _open_cum(tl, ix, busy, boost)
        added += 1
    return added


# ---------------------------------------------------------------- pass re-plans
