"""Sequencers: build an imaging plan from screened transitions (SPEC section 4).

A plan is a chain of route options o_1, ..., o_K in time order such that every
consecutive transition o_k -> o_{k+1} is feasible at its exact duration
(``Transitions.feasible`` from :func:`jaxspline.engine.screen.screen_transitions`) and
every route occurs at most once; it maximizes the summed option value. Each
option fixes its route's start time, so the time windows are implied by the
option table. Feasible transitions always go forward in time (T > 0), so the
options form a DAG ordered by ``t_start``.

Three solvers share that model:

* :func:`greedy` — one chronological pass, each time taking the unvisited
  feasible successor of best value density value / (time it ends - now).
* :func:`beam_search` — the exact dynamic programme below with at most
  ``width`` partial plans kept per option (best values, ties broken by a seeded
  random key).
* :func:`exact_plan` — dynamic programming over states (last option, set of
  visited routes) in time order; a state keeps the best value reaching it. It is
  exact because the future of a partial plan depends only on its last option
  and its visited routes. Exponential in the number of routes; meant for small
  instances (checked against brute force in the tests).

Visited-route sets are packed bit rows (numpy ``uint8``), so the per-option
work is vectorized over predecessors and kept states.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxspline.engine.options import RouteOptions, validate_options
from jaxspline.engine.screen import Transitions

__all__ = ["Plan", "greedy", "beam_search", "exact_plan", "plan_value"]


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


def _graph(options: RouteOptions, transitions: Transitions):
    """Feasible, admissible edges as CSR by destination; node order by t_start."""
    validate_options(options)
    if not isinstance(transitions, Transitions):
        raise ValueError(f"transitions must be a Transitions, got {type(transitions).__name__}")
    n = np.shape(options.t_start)[0]
    src = np.asarray(transitions.src, np.int64)
    dst = np.asarray(transitions.dst, np.int64)
    if src.size and (min(src.min(), dst.min()) < 0 or max(src.max(), dst.max()) >= n):
        raise ValueError(f"transitions.src/dst must index the {n} options")
    route = np.asarray(options.route, np.int64)
    ok = np.asarray(options.scan_ok, bool)
    ts = np.asarray(options.t_start, np.float64)
    te = np.asarray(options.t_end, np.float64)
    keep = (
        np.asarray(transitions.feasible, bool)
        & ok[src]
        & ok[dst]
        & (route[src] != route[dst])
        & (ts[dst] > te[src])
    )
    src, dst = src[keep], dst[keep]
    o = np.lexsort((src, dst))
    src, dst = src[o], dst[o]
    indptr = np.searchsorted(dst, np.arange(n + 1))
    nodes = np.flatnonzero(ok)
    nodes = nodes[np.argsort(ts[nodes], kind="stable")]
    return nodes, src, dst, indptr


def _routes_index(options: RouteOptions):
    route = np.asarray(options.route, np.int64)
    uniq, dense = np.unique(route, return_inverse=True)
    return dense.reshape(-1), uniq.size


def _dp(options: RouteOptions, transitions: Transitions, width, seed, max_states):
    """Per-option DP / beam; width=None keeps every distinct visited set (exact)."""
    nodes, src, _, indptr = _graph(options, transitions)
    value = np.asarray(options.value, np.float64)
    rdense, n_routes = _routes_index(options)
    nb = max((n_routes + 7) // 8, 1)
    rng = np.random.default_rng(seed)
    n = value.size
    vals = [None] * n  # per node: float [s]
    masks = [None] * n  # per node: uint8 [s, nb]
    parent = [None] * n  # per node: int64 [s, 2] (pred node, pred slot), -1 for a start
    total_states = 0
    best = (-np.inf, -1, -1)
    # random 64-bit weights: a row hash of the visited set for fast deduplication in
    # beam mode (collision probability ~ states^2 / 2^64); the exact mode compares rows
    weights = rng.integers(1, 2**63 - 1, size=nb, dtype=np.uint64)
    for j in nodes:
        r = rdense[j]
        byte, bit = r >> 3, np.uint8(1 << (r & 7))
        preds = src[indptr[j] : indptr[j + 1]]
        preds = [i for i in preds.tolist() if vals[i] is not None]
        start_mask = np.zeros((1, nb), np.uint8)
        start_mask[0, byte] |= bit
        if preds:
            pv = np.concatenate([vals[i] for i in preds])
            pm = np.concatenate([masks[i] for i in preds])
            pnode = np.repeat(preds, [vals[i].size for i in preds])
            pslot = np.concatenate([np.arange(vals[i].size) for i in preds])
            free = (pm[:, byte] & bit) == 0
            pm = pm[free]
            pm[:, byte] |= bit
            v = np.concatenate([[value[j]], pv[free] + value[j]])
            m = np.concatenate([start_mask, pm])
            p = np.concatenate([[[-1, -1]], np.stack([pnode[free], pslot[free]], axis=1)]).astype(
                np.int64
            )
        else:
            v, m, p = np.array([value[j]]), start_mask, np.array([[-1, -1]], np.int64)
        key = rng.random(v.size)
        # best first: value descending, then the seeded random key
        o = np.lexsort((key, -v))
        v, m, p = v[o], m[o], p[o]
        # dedupe identical visited sets, keeping the first (best) occurrence
        if v.size > 1:
            if width is None:
                _, first = np.unique(m, axis=0, return_index=True)
            else:
                h = (m.astype(np.uint64) * weights[None, :]).sum(axis=1, dtype=np.uint64)
                _, first = np.unique(h, return_index=True)
            first = np.sort(first)
            if width is not None:
                first = first[:width]
            v, m, p = v[first], m[first], p[first]
        vals[j], masks[j], parent[j] = v, m, p
        total_states += v.size
        if max_states is not None and total_states > max_states:
            raise ValueError(
                f"exact_plan: more than max_states={max_states} DP states; the instance is "
                "too large for the exact solver (use beam_search)"
            )
        if v[0] > best[0]:
            best = (v[0], j, 0)
    if best[1] < 0:
        return Plan(np.zeros(0, np.int64), 0.0)
    path = []
    node, slot = best[1], best[2]
    while node >= 0:
        path.append(node)
        node, slot = parent[node][slot]
    idx = np.asarray(path[::-1], np.int64)
    return Plan(idx, plan_value(options, idx))


def exact_plan(
    options: RouteOptions, transitions: Transitions, *, max_states: int = 2_000_000
) -> Plan:
    """Optimal plan by DP over (last option, visited-route set) on the time-ordered DAG.

    V(j, S) = value[j] + max(0-length start, max over feasible i -> j with
    route[j] not in S' of V(i, S')), S = S' + {route[j]}; the answer is the best
    V over all states. Exact (each state's future depends only on (j, S)).

    Args:
      options: RouteOptions (N options).
      transitions: screened transitions (only ``feasible`` ones are used).
      max_states: ValueError when the DP would hold more states than this.

    Returns:
      Plan (option indices in time order, total value). Ties between equal
      values are broken deterministically.
    """
    return _dp(options, transitions, None, 0, int(max_states))


def beam_search(
    options: RouteOptions, transitions: Transitions, width: int = 16, seed: int = 0
) -> Plan:
    """Beam-limited version of :func:`exact_plan`: at most ``width`` states per option.

    Options are processed in time order; at each option the partial plans ending
    there (extensions of kept predecessor states that do not revisit a route,
    plus the plan starting there) are deduplicated by visited-route set and the
    ``width`` best by value are kept (ties broken by a random key drawn from
    ``numpy.random.default_rng(seed)``; deterministic for a given seed). Work is
    O(sum over options of in-degree x width). Equals ``exact_plan`` when
    ``width`` is at least the largest number of distinct states at an option.

    Args:
      options: RouteOptions.
      transitions: Transitions screened on ``options``.
      width: int, states kept per option.
      seed: int, tie-breaking seed.
    Returns:
      Plan.
    """
    if int(width) < 1:
        raise ValueError(f"width must be >= 1, got {width!r}")
    return _dp(options, transitions, int(width), int(seed), None)


def greedy(options: RouteOptions, transitions: Transitions) -> Plan:
    """Chronological greedy plan (a fast baseline).

    Starting before the earliest option, repeatedly append the admissible
    option j (a feasible successor of the last one whose route is unvisited;
    any option at the start) maximizing value[j] / (t_end[j] - t_now), with
    t_now the end time of the last option (the earliest t_start at the
    start); ties go to the earlier t_start, then the lower index.

    Args:
      options: RouteOptions.
      transitions: Transitions screened on ``options``.
    Returns:
      Plan.
    """
    nodes, src, dst, _ = _graph(options, transitions)
    value = np.asarray(options.value, np.float64)
    ts = np.asarray(options.t_start, np.float64)
    te = np.asarray(options.t_end, np.float64)
    route = np.asarray(options.route, np.int64)
    if nodes.size == 0:
        return Plan(np.zeros(0, np.int64), 0.0)
    o = np.lexsort((dst, src))
    s_sorted, d_sorted = src[o], dst[o]
    out_ptr = np.searchsorted(s_sorted, np.arange(value.size + 1))
    visited: set[int] = set()
    path: list[int] = []
    cand = nodes
    t_now = ts[nodes].min()
    while True:
        cand = cand[[route[c] not in visited for c in cand]] if cand.size else cand
        if cand.size == 0:
            break
        dur = np.maximum(te[cand] - t_now, 1e-9)
        score = value[cand] / dur
        k = np.lexsort((cand, ts[cand], -score))[0]
        j = int(cand[k])
        path.append(j)
        visited.add(int(route[j]))
        t_now = te[j]
        cand = d_sorted[out_ptr[j] : out_ptr[j + 1]]
    idx = np.asarray(path, np.int64)
    return Plan(idx, plan_value(options, idx))
