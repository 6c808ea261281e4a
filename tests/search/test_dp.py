"""The bound's per-satellite DP and its back-tracking against independent references.

References: every subset of each satellite's options taken in start order (brute force:
the best sequence's value, transitions by the rules of :mod:`jaxspline.search.dp`), and
a one-satellite-at-a-time walk written here from :func:`backtrack`'s rule (first near
predecessor by id that provides the value, else the first far one), which both walks
of :func:`backtrack` (a few pairs a step without pair costs, all satellites at once with
them) must reproduce exactly: same paths, values and near pairs.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from test_timeline_battery import _problem

from jaxspline.search.dp import NeedPrice, backtrack, dp_forward, dp_prepare

TOL = 1e-9  # the back-tracking's tolerance (dp._PATH_TOL)


def _transition(pb, w, arc, merge, i, j):
    """Best value added by moving i -> j (-inf: not allowed) and the near pair it takes."""
    out, pos = -np.inf, -1
    if pb.option_end[i] + pb.far[pb.option_sat[i]] <= pb.option_start[j]:
        out = 0.0  # far: always feasible, free
    row = pb.pairs.row(j)
    for q in range(row.start, row.stop):
        if pb.pairs.src[q] == i:
            v = -(float(arc[q]) if arc is not None else 0.0)
            if merge and pb.option_target[i] == pb.option_target[j]:
                v -= w[j]
            if v > out:
                out, pos = v, q
    return out, pos


def _brute_force(pb, w, arc, merge, k):
    """Best value of a sequence of satellite k's options (0: the empty one)."""
    ids = range(pb.sat_lo[k], pb.sat_hi[k])
    best = 0.0
    for n in range(1, len(ids) + 1):
        for seq in itertools.combinations(ids, n):
            if pb.option_first[seq[0]] > pb.option_start[seq[0]]:
                continue
            v = sum(w[j] for j in seq)
            for i, j in itertools.pairwise(seq):
                v += _transition(pb, w, arc, merge, i, j)[0]
            best = max(best, v)
    return best


def _reference_walk(pb, d, w, best, arc, merge):
    """One satellite at a time, one step a loop turn: (paths, values, used)."""
    ptr, src = pb.pairs.ptr, pb.pairs.src
    paths, values, used = [], [], []
    for k in range(pb.n_sats):
        lo, hi = pb.sat_lo[k], pb.sat_hi[k]
        if hi <= lo or not best[lo:hi].max() > 0.0:
            paths.append([])
            values.append(0.0)
            continue
        j = lo + int(np.argmax(best[lo:hi]))
        values.append(float(best[j]))
        path = [j]
        while True:
            rest = best[j] - w[j]
            if d.first_ok[j] and rest <= TOL:
                break
            r = pb.pairs.row_of[j]
            nxt = -1
            for q in range(int(ptr[r]), int(ptr[r + 1])):
                cv = best[src[q]] - (arc[q] if arc is not None else 0.0)
                if merge and pb.option_target[src[q]] == pb.option_target[j]:
                    cv -= w[j]
                if cv >= rest - TOL:
                    used.append(q)
                    nxt = int(src[q])
                    break
            if nxt < 0:
                far = [
                    i for i in range(lo, j) if d.ready[i] <= d.start[j] and best[i] >= rest - TOL
                ]
                if not far:
                    break
                nxt = far[0]
            j = nxt
            path.append(j)
        paths.append(path[::-1])
    return paths, values, used


@pytest.mark.parametrize("seed", range(12))
def test_backtrack_matches_brute_force_and_reference_walk(seed):
    rng = np.random.default_rng(500 + seed)
    # long horizon: far transitions; short: rows of several near pairs; both: repeats
    steps, far = (rng.integers(40, 120), 25.0) if seed % 2 else (rng.integers(30, 60), 80.0)
    pb, _ = _problem(rng, int(steps), n_sats=3, n_targets=12, far=far, repeats=0.5)
    d = dp_prepare(pb)
    ties = seed % 4 < 2  # integer values: many exact ties between predecessors
    w = rng.integers(-2, 6, pb.n_options).astype(float) if ties else rng.normal(2, 2, pb.n_options)
    arc = rng.uniform(0.0, 1.0, len(pb.pairs)).astype(np.float32) if seed % 3 == 0 else None
    for merge in (False, True):
        best = dp_forward(pb, d, w, arc, merge)
        used = []
        paths, values = backtrack(pb, d, w, best, arc, used, merge)
        assert (paths, values, used) == _reference_walk(pb, d, w, best, arc, merge)
        for k, (path, value) in enumerate(zip(paths, values, strict=True)):
            assert value == pytest.approx(_brute_force(pb, w, arc, merge, k), abs=1e-9)
            if path:  # a feasible sequence worth the optimum
                assert pb.option_first[path[0]] <= pb.option_start[path[0]]
                got = sum(w[j] for j in path)
                for i, j in itertools.pairwise(path):
                    got += _transition(pb, w, arc, merge, i, j)[0]
                assert got == pytest.approx(value, abs=1e-9)
        on_paths = {j for p in paths for j in p}
        assert all(pb.pairs.src[q] in on_paths for q in used)


@pytest.mark.parametrize("seed", range(6))
def test_need_priced_pairs_match_brute_force(seed):
    """Pair costs derived block by block (``NeedPrice``: rate of the destination times
    the required time less a tolerance) give the brute-force optimum of the same costs
    written out pair by pair here, and a path worth it."""
    rng = np.random.default_rng(900 + seed)
    steps, far = (rng.integers(40, 120), 25.0) if seed % 2 else (rng.integers(30, 60), 80.0)
    pb, _ = _problem(rng, int(steps), n_sats=3, n_targets=12, far=far, repeats=0.5)
    d = dp_prepare(pb)
    w = rng.normal(2, 2, pb.n_options)
    rate = rng.uniform(0.0, 0.2, pb.n_options)
    rate[rng.random(pb.n_options) < 0.3] = 0.0
    tol = 0.1
    dst = np.repeat(pb.pairs.rows, np.diff(pb.pairs.ptr))
    need = pb.pairs.need.astype(np.float64)
    written = rate[dst] * np.maximum(need - tol, 0.0)
    priced = NeedPrice(rate, pb.pairs.need, tol)
    for merge in (False, True):
        best = dp_forward(pb, d, w, priced, merge)
        used = []
        paths, values = backtrack(pb, d, w, best, priced, used, merge)
        for k, (path, value) in enumerate(zip(paths, values, strict=True)):
            assert value == pytest.approx(_brute_force(pb, w, written, merge, k), abs=1e-9)
            if path:
                got = sum(w[j] for j in path)
                for i, j in itertools.pairwise(path):
                    got += _transition(pb, w, written, merge, i, j)[0]
                assert got == pytest.approx(value, abs=1e-9)
