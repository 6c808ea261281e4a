"""Sequencers: build an imaging plan from screened transitions (SPEC section 4).

A plan is a chain of route options o_1, ..., o_K in time order such that every
consecutive transition o_k -> o_{k+1} is feasible at its exact duration
(``Transitions.feasible`` from :func:`jaxspline.screen.pairs.screen_transitions`) and
every route occurs at most once; it maximizes the summed option value. Each
option fixes its route's start time, so the time windows are implied by the
option table. Feasible transitions always go forward in time (T > 0), so the
options form a DAG ordered by ``t_start``.

Every solver reads the transitions once, either as one ``Transitions`` or as a
*stream*: an iterable of ``Transitions`` chunks (a generator is fine) whose rows
are grouped by source option, sources in increasing ``(t_start, option index)``
order, a source's rows possibly spread over consecutive chunks, destinations in
any order (:mod:`jaxspline.sequences.stream`). A single ``Transitions``
is sorted into that order first, so any row order works. Memory is one chunk
plus O(options x width) states; the candidate table is never held.

* :func:`greedy_chain` — one chronological pass, each time taking the unvisited
  feasible successor of best value density value / (time it ends - now); it
  looks only at the rows of the option it stands on. It is the search's greedy
  strategy (:func:`jaxspline.search.construct.greedy_pass`, also the one of
  :func:`jaxspline.search.greedy`) with one decision per position of the chain.
* :func:`beam_search` — the dynamic programme below with at most ``width``
  partial plans kept per option.
* :func:`exact_plan` — dynamic programming over states (last option, set of
  visited routes) in time order; a state keeps the best value reaching it. It is
  exact because the future of a partial plan depends only on its last option
  and its visited routes. Exponential in the number of routes; meant for small
  instances (checked against brute force in the tests).
* :func:`path_bound` — the longest path over the feasible transitions without
  the each-route-once rule: an upper bound of every plan.

The two DP solvers push: the states of an option are final when its first row
as a source arrives (all its predecessors start earlier, so their rows came
before); they are extended into a candidate pool of every feasible destination,
which is pruned to the best distinct visited-route sets whenever a block of
candidates is merged and again when the destination becomes final. Visited-route
sets are packed bit rows (numpy ``uint64`` words) and live only while their
option can still be a source; afterwards a state keeps its parent pointer.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxspline.kernels.batch import ragged_positions
from jaxspline.screen.options import RouteOptions
from jaxspline.search.construct import greedy_pass
from jaxspline.sequences.stream import (
    OptionOrder,
    admissible_rows,
    batch_segments,
    option_order,
)

__all__ = ["Plan", "greedy_chain", "beam_search", "exact_plan", "path_bound", "plan_value"]

_BLOCK_BYTES = 1 << 25  # [bytes] candidate states expanded at once: 32 MiB
_STATE_WORDS = 12  # 8-byte words a candidate state takes besides its visited-route bits
_MIN_BLOCK = 1024  # least candidate states expanded at once
_MIN_DUR = 1e-9  # [s] floor of the greedy's time from now to the end of a candidate


class Plan(NamedTuple):
    """An imaging plan.

    Attributes:
      chosen: int64 [K], indices of the chosen options (rows of the RouteOptions) in
        time order.
      value: total value (sum of ``options.value`` over the plan).
    """

    chosen: np.ndarray
    value: float


def plan_value(options: RouteOptions, idx) -> float:
    """Sum of ``options.value`` over option indices ``idx``.

    Args:
      options: RouteOptions.
      idx: int [K], option indices.
    Returns:
      float.
    """
    idx = np.asarray(idx, np.int64)
    return float(np.asarray(options.value, np.float64)[idx].sum()) if idx.size else 0.0


# ----------------------------------------------------------------------------
# hashing of visited-route sets and tie keys
# ----------------------------------------------------------------------------


def _mix(x: np.ndarray) -> np.ndarray:
    """splitmix64 finalizer of a uint64 array (wrapping arithmetic)."""
    x = x ^ (x >> np.uint64(30))
    x = x * np.uint64(0xBF58476D1CE4E5B9)
    x = x ^ (x >> np.uint64(27))
    x = x * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def _u64(x) -> np.ndarray:
    return np.atleast_1d(np.asarray(x, np.int64)).astype(np.uint64)


class _States(NamedTuple):
    """Partial plans ending at option positions ``dpos`` (one row each)."""

    dpos: np.ndarray  # int64, position of the last option in the time order
    v: np.ndarray  # float64, plan value
    h: np.ndarray  # uint64, hash of the visited-route set
    m: np.ndarray  # uint64 [S, words], visited-route bits
    pnode: np.ndarray  # int64, previous option, -1 for a plan of one option
    pslot: np.ndarray  # int64, rank of the previous option's state, -1 for none
    k1: np.ndarray  # uint64, first tie key
    k2: np.ndarray  # int64, second tie key


def _cat(parts) -> _States:
    return _States(*(np.concatenate(f) for f in zip(*parts, strict=True)))


def _take(s: _States, idx) -> _States:
    return _States(*(f[idx] for f in s))


def _best_first(dpos, v, gid, keys, width):
    """Indices of the kept states, sorted by (dpos, -v, *keys).

    Per position, the best state of every group ``gid`` (int64: a visited set),
    then the ``width`` best groups (all with width None).
    """
    o = np.lexsort((*keys[::-1], -v, dpos))
    if width is None:  # gid: dense set ids
        pair = dpos[o] * (int(gid.max()) + 1) + gid[o]
    else:  # gid: set hashes
        pair = _mix(gid[o].astype(np.uint64) ^ _mix(dpos[o].astype(np.uint64)))
    first = np.unique(pair, return_index=True)[1]  # first occurrence: the best one
    o = o[np.sort(first)]
    if width is not None and o.size:
        d = dpos[o]
        start = np.flatnonzero(np.r_[True, d[1:] != d[:-1]])
        o = o[ragged_positions(np.diff(np.r_[start, d.size]))[1] < width]
    return o


class _Search:
    """Push DP over a transition stream; width None keeps every visited set (exact)."""

    def __init__(self, options: RouteOptions, order: OptionOrder, width, seed, max_states):
        self.order, self.width, self.max_states = order, width, max_states
        self.value = np.asarray(options.value, np.float64)
        uniq, dense = np.unique(np.asarray(options.route, np.int64), return_inverse=True)
        dense = dense.reshape(-1)
        self.nw = max((uniq.size + 63) // 64, 1)
        self.word = dense >> 6
        self.bit = np.left_shift(np.uint64(1), (dense & 63).astype(np.uint64))
        rng = np.random.default_rng(seed)
        self.salt = rng.integers(0, 2**63 - 1, size=self.nw, dtype=np.int64).astype(np.uint64)
        self.h0 = _mix(self.salt).sum(dtype=np.uint64)
        self.tie = _mix(_u64(seed if seed is not None else 0))[0]
        v = order.nodes.size
        self.store = self._empty()
        self.best = np.full(v, -np.inf)  # best value of a plan ending at each position
        self.floor = np.full(v, -np.inf)  # least value that can still enter a full pool
        self.goff = np.zeros(v, np.int64)  # first state of each position in the parents
        self.parents: list[tuple[np.ndarray, np.ndarray]] = []
        self.total = 0  # final states so far
        self.done = 0  # positions final so far
        self.table = None  # (lo, _States of positions lo.., off) of the current batch

    def _empty(self) -> _States:
        z = np.zeros(0, np.int64)
        return _States(
            z, z.astype(float), z.astype(np.uint64), np.zeros((0, self.nw), np.uint64), z, z,
            z.astype(np.uint64), z,
        )  # fmt: skip

    def _keys(self, dst, pnode, pslot):
        """Tie keys: exact, (position of the predecessor, its slot), start first;
        beam, a hash of (seed, dst, predecessor, slot)."""
        if self.width is None:
            pp = np.where(pnode >= 0, self.order.pos[np.maximum(pnode, 0)], -1)
            return _u64(pp + 1), pslot + 1
        k = _mix(self.tie ^ _u64(dst))
        k = _mix(k ^ _u64(pnode + 1))
        return _mix(k ^ _u64(pslot + 1)), np.zeros(dst.size, np.int64)

    def _prune(self, s: _States) -> _States:
        if s.v.size == 0:
            return s
        if self.width is None:
            gid = np.unique(s.m, axis=0, return_inverse=True)[1].reshape(-1)
        else:
            gid = s.h
        keys = (s.k1,) if self.width is not None else (s.k1, s.k2)
        return _take(s, _best_first(s.dpos, s.v, gid, keys, self.width))

    def _check_states(self):
        if self.max_states is not None and self.total + self.store.v.size > self.max_states:
            raise ValueError(
                f"exact_plan: more than max_states={self.max_states} DP states; the instance "
                "is too large for the exact solver (use beam_search)"
            )

    def finalize(self, hi: int):
        """Make positions done..hi-1 final: their pools plus the one-option plans."""
        lo = self.done
        if hi <= lo:
            return
        k = int(np.searchsorted(self.store.dpos, hi))
        head, self.store = _take(self.store, slice(0, k)), _take(self.store, slice(k, None))
        q = np.arange(lo, hi)
        j = self.order.nodes[q]
        w, bit = self.word[j], self.bit[j]
        m = np.zeros((q.size, self.nw), np.uint64)
        m[np.arange(q.size), w] = bit
        h = self.h0 - _mix(self.salt[w]) + _mix(bit ^ self.salt[w])
        none = np.full(q.size, -1, np.int64)
        k1, k2 = self._keys(j, none, none)
        fin = self._prune(_cat([head, _States(q, self.value[j], h, m, none, none, k1, k2)]))
        off = np.searchsorted(fin.dpos, np.arange(lo, hi + 1))
        self.best[lo:hi] = fin.v[off[:-1]]
        self.goff[lo:hi] = self.total + off[:-1]
        self.parents.append((fin.pnode, fin.pslot))
        self.total += fin.v.size
        self.done = hi
        self.table = (lo, fin, off)
        self._check_states()

    def push(self, src: np.ndarray, dst: np.ndarray):
        """Extend the final states of the sources (current batch) along rows src -> dst."""
        lo, tab, off = self.table
        p = self.order.pos[src] - lo
        first, cnt = off[p], off[p + 1] - off[p]
        cs = np.cumsum(cnt)
        cap = max(_BLOCK_BYTES // (8 * (self.nw + _STATE_WORDS)), _MIN_BLOCK)
        a = 0
        while a < src.size:
            base = cs[a - 1] if a else 0
            b = max(int(np.searchsorted(cs, base + cap, side="right")), a + 1)
            self._push_block(tab, src[a:b], dst[a:b], first[a:b], cnt[a:b])
            a = b

    def _push_block(self, tab: _States, src, dst, first, cnt):
        rep, slot = ragged_positions(cnt)
        st = first[rep] + slot
        d = dst[rep]
        v = tab.v[st] + self.value[d]
        dpos = self.order.pos[d]
        w, bit = self.word[d], self.bit[d]
        old = tab.m[st, w]
        good = ((old & bit) == 0) & (v >= self.floor[dpos])  # route unvisited, may enter
        rep, slot, st, d, v, dpos, w, bit, old = (
            x[good] for x in (rep, slot, st, d, v, dpos, w, bit, old)
        )
        pn = src[rep]
        h = tab.h[st] - _mix(old ^ self.salt[w]) + _mix((old | bit) ^ self.salt[w])
        k1, k2 = self._keys(d, pn, slot)
        if self.width is not None:  # drop the hopeless before building their bit rows
            o = _best_first(dpos, v, h, (k1,), self.width)
            st, d, w, bit, pn, slot, v, h, k1, k2, dpos = (
                x[o] for x in (st, d, w, bit, pn, slot, v, h, k1, k2, dpos)
            )
        m = tab.m[st]
        m[np.arange(st.size), w] |= bit
        new = _States(dpos, v, h, m, pn, slot, k1, k2)
        self.store = s = self._prune(_cat([self.store, new]))
        if self.width is not None and s.v.size >= self.width:
            # a pool of `width` distinct sets keeps them: worse candidates cannot enter
            gs = np.flatnonzero(np.r_[True, s.dpos[1:] != s.dpos[:-1]])
            gs = gs[np.diff(np.r_[gs, s.v.size]) >= self.width]
            self.floor[s.dpos[gs]] = s.v[gs + self.width - 1]
        self._check_states()

    def run(self, rows) -> Plan:
        """Read the admissible rows (a stream of ``(src, dst)``), return the best plan."""
        batch = -1
        for src, dst in rows:
            for b, s, d in batch_segments(self.order, src, dst):
                if b != batch:
                    self.finalize(int(self.order.batch_end[b]))
                    batch = b
                self.push(s, d)
        self.finalize(self.order.nodes.size)
        self.table = None
        if self.order.nodes.size == 0:
            return Plan(np.zeros(0, np.int64), 0.0)
        pnode = np.concatenate([p[0] for p in self.parents])
        pslot = np.concatenate([p[1] for p in self.parents])
        path = []
        node, slot = int(self.order.nodes[np.argmax(self.best)]), 0
        while node >= 0:
            path.append(node)
            g = self.goff[self.order.pos[node]] + slot
            node, slot = int(pnode[g]), int(pslot[g])
        return Plan(np.asarray(path[::-1], np.int64), float(self.best.max()))


def _dp(options, transitions, width, seed, max_states) -> Plan:
    order = option_order(options)
    rows = admissible_rows(options, order, transitions)
    plan = _Search(options, order, width, seed, max_states).run(rows)
    return Plan(plan.chosen, plan_value(options, plan.chosen))


def exact_plan(options: RouteOptions, transitions, *, max_states: int = 2_000_000) -> Plan:
    """Optimal plan by DP over (last option, visited-route set) on the time-ordered DAG.

    V(j, S) = value[j] + max(0-length start, max over feasible i -> j with
    route[j] not in S' of V(i, S')), S = S' + {route[j]}; the answer is the best
    V over all states. Exact (each state's future depends only on (j, S)).
    Ties are broken deterministically: among plans of equal value ending at an
    option, the one-option plan first, then the predecessor earlier in
    ``(t_start, index)`` order, then that predecessor's better-ranked state;
    between options, the earlier one in that order.

    Args:
      options: RouteOptions (N options).
      transitions: screened transitions, a Transitions or a stream of Transitions
        chunks (module docstring); only ``feasible`` rows are used.
      max_states: ValueError when the DP would hold more states than this.

    Returns:
      Plan (option indices in time order, total value).

    Raises:
      ValueError: invalid ``options`` or ``transitions`` (wrong type, indices out
        of range, sources out of order), or more than ``max_states`` states.
    """
    return _dp(options, transitions, None, None, int(max_states))


def beam_search(options: RouteOptions, transitions, width: int = 16, seed: int = 0) -> Plan:
    """Beam-limited version of :func:`exact_plan`: at most ``width`` states per option.

    Options are processed in time order; the partial plans ending at an option
    (extensions of kept predecessor states that do not revisit a route, plus the
    plan starting there) are deduplicated by visited-route set (a 64-bit hash,
    salted by ``seed``) and the ``width`` best by value are kept. Ties are broken
    by a 64-bit hash of (``seed``, option, predecessor, predecessor's state
    rank), so the plan is a function of the options, the feasible transitions
    and the seed only, whatever the row order or chunking of the stream. Pools
    are pruned every time a block of candidates is merged, so the result is the
    same as pruning once. Work is O(sum over options of out-degree x width).
    Equals ``exact_plan`` in value when ``width`` is at least the largest number
    of distinct states at an option.

    Args:
      options: RouteOptions.
      transitions: a Transitions or a stream of Transitions chunks screened on
        ``options`` (module docstring).
      width: int >= 1, states kept per option.
      seed: int, salt of the set hash and of the tie keys.
    Returns:
      Plan.
    Raises:
      ValueError: ``width < 1``, or invalid ``options`` / ``transitions``.
    """
    if int(width) < 1:
        raise ValueError(f"width must be >= 1, got {width!r}")
    return _dp(options, transitions, int(width), int(seed), None)


class _Chain:
    """The problem of :func:`greedy_chain` for :func:`~jaxspline.search.construct.greedy_pass`:
    one chain over the options, extended at its end.

    A decision is ``(candidates, now)``: the rows read for the last option (every
    ``scan_ok`` option at the start) and the time the chain stands at; its admissible
    candidates are those of an unvisited route, in ``(t_start, index)`` order, each of
    cost minus value / (t_end - now).
    """

    def __init__(self, options: RouteOptions, order: OptionOrder):
        self.order = order
        self.value = np.asarray(options.value, np.float64)
        self.ts = np.asarray(options.t_start, np.float64)
        self.te = np.asarray(options.t_end, np.float64)
        self.route = np.asarray(options.route, np.int64)
        self.path: list[int] = []
        self.visited: set[int] = set()

    def choices(self, decision):
        """The admissible candidates of ``decision`` and their costs (class docstring)."""
        cand, t_now = decision
        if cand.size:
            cand = cand[[self.route[c] not in self.visited for c in cand.tolist()]]
        cand = cand[np.argsort(self.order.rank[cand])]  # ties: earlier (t_start, index)
        return cand, -(self.value[cand] / np.maximum(self.te[cand] - t_now, _MIN_DUR))

    def commit(self, j):
        """Append option j to the chain."""
        self.path.append(int(j))
        self.visited.add(int(self.route[j]))

    def _last(self, n: int):
        """The chain's last option if the decision taken at length ``n`` appended one."""
        return self.path[-1] if len(self.path) > n else None

    def decisions(self, rows):
        """The chain's decisions, read off the admissible rows as the chain grows.

        Every option first; then, after each append, the rows of the option appended
        (they may span chunks). The decisions end when one appends nothing; the rows
        are read to their end all the same (the stream's checks run on every chunk).
        """
        order, nodes = self.order, self.order.nodes
        cur = None
        if nodes.size:
            yield nodes, self.ts[nodes].min()
            cur = self._last(0)
        succ: list[np.ndarray] = []  # rows of cur read so far
        for src, dst in rows:
            r = order.rank[src]
            a = 0
            while cur is not None:
                a = a + int(np.searchsorted(r[a:], order.rank[cur], side="left"))
                b = a + int(np.searchsorted(r[a:], order.rank[cur], side="right"))
                succ.append(dst[a:b])
                if b == r.size:
                    break  # cur's rows may go on in the next chunk
                n = len(self.path)
                yield np.concatenate(succ), self.te[cur]
                cur, succ, a = self._last(n), [], b
        while cur is not None:  # the stream has ended: no more rows for later options
            n = len(self.path)
            yield (np.concatenate(succ) if succ else np.zeros(0, np.int64)), self.te[cur]
            cur, succ = self._last(n), []


def greedy_chain(options: RouteOptions, transitions) -> Plan:
    """Chronological greedy plan (a fast baseline).

    Starting before the earliest option, repeatedly append the admissible
    option j (a feasible successor of the last one whose route is unvisited;
    any option at the start) maximizing value[j] / (t_end[j] - t_now), with
    t_now the end time of the last option (the earliest t_start at the
    start); ties go to the earlier t_start, then the lower index. On a stream,
    only the rows of the option last appended are looked at. This is the greedy
    strategy of the search (:func:`jaxspline.search.construct.greedy_pass`) with
    one decision per position of the chain.

    Args:
      options: RouteOptions.
      transitions: a Transitions or a stream of Transitions chunks screened on
        ``options`` (module docstring).
    Returns:
      Plan.
    Raises:
      ValueError: invalid ``options`` or ``transitions``.
    """
    order = option_order(options)
    rows = admissible_rows(options, order, transitions)
    chain = _Chain(options, order)
    greedy_pass(chain.decisions(rows), chain.choices, chain.commit)
    idx = np.asarray(chain.path, np.int64)
    return Plan(idx, plan_value(options, idx))


def path_bound(options: RouteOptions, transitions) -> float:
    """Longest path value over the feasible transitions, routes may repeat.

    B = max over chains o_1 -> ... -> o_K of admissible feasible transitions
    (both options ``scan_ok``, different routes, T > 0) of the summed value,
    without the each-route-once rule (one push pass, O(options) memory). Every
    plan built from the same transitions is such a chain, so B bounds every
    :func:`greedy_chain`, :func:`beam_search` and :func:`exact_plan` value from above
    (and equals the optimum when no route has two options). It bounds the plans
    over the transitions given only: transitions screened with ``top_k`` (or
    ``max_gap``) are a subset of all feasible ones, so B is then no bound of
    plans using the dropped transitions.

    Args:
      options: RouteOptions.
      transitions: a Transitions or a stream of Transitions chunks screened on
        ``options`` (module docstring).
    Returns:
      float, B (0.0 when no option is ``scan_ok``).
    Raises:
      ValueError: invalid ``options`` or ``transitions``.
    """
    order = option_order(options)
    rows = admissible_rows(options, order, transitions)
    value = np.asarray(options.value, np.float64)
    inc = np.zeros(value.size)  # best chain value into each option, 0 = start there
    for src, dst in rows:
        for _, s, d in batch_segments(order, src, dst):
            np.maximum.at(inc, d, value[s] + inc[s])
    nodes = order.nodes
    return float((value[nodes] + inc[nodes]).max()) if nodes.size else 0.0
