"""The compact near-pair table against a plain dict of pairs (brute-force reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jaxspline.search import store
from jaxspline.search.store import NearPairs, PairsBuilder, start_order


def _random_pairs(rng, n_sats=3, per_sat=60, density=0.3):
    sat = np.repeat(np.arange(n_sats), per_sat)
    start = np.concatenate([np.sort(rng.uniform(0, 1e4, per_sat)) for _ in range(n_sats)])
    ref = {}
    for k in range(n_sats):
        ids = np.flatnonzero(sat == k)
        for i in ids:
            for j in ids:
                if i != j and rng.random() < density:
                    ref[(int(i), int(j))] = float(rng.uniform(0.0, 300.0))
    return sat, start, ref


@pytest.mark.parametrize("seed, piece", [(0, None), (1, None), (2, 7), (3, 1)])
def test_streamed_table_answers_like_a_dict(seed, piece, monkeypatch):
    if piece is not None:  # pieces smaller than a row: rows split over several pieces
        monkeypatch.setattr(store, "PIECE_PAIRS", piece)
    rng = np.random.default_rng(seed)
    sat, start, ref = _random_pairs(rng)
    n = sat.size
    rows = start_order(start, sat)
    b = PairsBuilder(n, rows)
    for k in range(3):  # one satellite at a time, its pairs in shuffled chunks
        mine = [(i, j, w) for (i, j), w in ref.items() if sat[j] == k]
        rng.shuffle(mine)
        for part in np.array_split(np.arange(len(mine)), 7):
            b.add(*(np.array([mine[p][c] for p in part]) for c in range(3)))
        b.close()
    table = b.build()
    assert len(table) == len(ref)
    assert table.nbytes == 8 * len(ref) + 24 * n + 8  # int32 + float32 a pair
    for i in range(n):
        for j in range(n):
            got = table.lookup(i, j)
            want = ref.get((i, j), math.inf)
            if math.isinf(want):
                assert math.isinf(got)
            else:  # float32, rounded up
                assert want <= got <= want * (1 + 2.0**-23) + 1e-30
    # rows in the given order, sources ascending, destinations recovered
    dst = table.dst()
    assert np.all(np.diff(table.row_of[dst]) >= 0)
    for r in range(n):
        assert np.all(np.diff(table.src[table.ptr[r] : table.ptr[r + 1]]) > 0)
    assert sorted(zip(table.src.tolist(), dst.tolist(), strict=True)) == sorted(ref)
    # the same table from plain arrays
    keys = list(ref)
    other = NearPairs.from_arrays(
        n, [k[0] for k in keys], [k[1] for k in keys], list(ref.values()), rows
    )
    np.testing.assert_array_equal(other.ptr, table.ptr)
    np.testing.assert_array_equal(other.src, table.src)
    np.testing.assert_array_equal(other.need, table.need)
    # gather: positions and destinations of some rows
    some = rng.choice(n, 10, replace=False)
    idx, d = table.gather(some)
    assert sorted(zip(table.src[idx].tolist(), d.tolist(), strict=True)) == sorted(
        (i, j) for (i, j) in ref if j in set(some.tolist())
    )


def test_rejects_inconsistent_arrays():
    with pytest.raises(ValueError, match="NearPairs"):
        NearPairs(np.array([0, 2]), np.zeros(1, np.int32), np.zeros(1, np.float32), [0])
