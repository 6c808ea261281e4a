"""The compact near-pair table against a plain dict of pairs (brute-force reference)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jaxspline.search import store
from jaxspline.search.store import NearPairs, PairsBuilder, start_order


def _random_pairs(rng, n_sats=3, per_sat=60, density=0.3, ids_by_start=True):
    sat = np.repeat(np.arange(n_sats), per_sat)
    starts = [rng.uniform(0, 1e4, per_sat) for _ in range(n_sats)]
    start = np.concatenate([np.sort(s) for s in starts] if ids_by_start else starts)
    ref = {}
    for k in range(n_sats):
        ids = np.flatnonzero(sat == k)
        for i in ids:
            for j in ids:
                if i != j and rng.random() < density:
                    ref[(int(i), int(j))] = float(rng.uniform(0.0, 300.0))
    return sat, start, ref


@pytest.mark.parametrize(
    "seed, piece, stream, background",
    [(0, None, "shuffled", False), (1, None, "shuffled", False), (2, 7, "shuffled", False),
     (3, 1, "shuffled", False), (4, None, "by source", False), (5, 7, "by source", False),
     (6, None, "by source, ids not by start", False), (7, 7, "by source", True),
     (8, 7, "shuffled", True)],
)  # fmt: skip
def test_streamed_table_answers_like_a_dict(seed, piece, stream, background, monkeypatch):
    # "by source": the planner's stream (sources ascending, each one's destinations
    # ascending, ids by start within a satellite), which the builder sorts by
    # destination alone; the other two take its general (row, source) sort;
    # "background": each satellite sorted in a thread while the next one is added
    if piece is not None:  # pieces smaller than a row: rows split over several pieces
        monkeypatch.setattr(store, "PIECE_PAIRS", piece)
    rng = np.random.default_rng(seed)
    sat, start, ref = _random_pairs(rng, ids_by_start=stream != "by source, ids not by start")
    n = sat.size
    rows = start_order(start, sat)
    b = PairsBuilder(n, rows, background=background)
    for k in range(3):  # one satellite at a time, its pairs in chunks
        mine = [(i, j, w) for (i, j), w in ref.items() if sat[j] == k]
        if stream == "shuffled":
            rng.shuffle(mine)
        else:
            mine.sort()
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


def test_a_background_sort_error_reaches_the_caller(monkeypatch):
    def fail(self, chunks):
        raise MemoryError("sort")

    monkeypatch.setattr(PairsBuilder, "_close", fail)
    b = PairsBuilder(4, np.arange(4), background=True)
    b.add(np.array([0]), np.array([1]), np.array([2.0]))
    b.close()  # submitted: the error waits for the next close or build
    with pytest.raises(MemoryError, match="sort"):
        b.build()


def test_needs_round_up_to_the_next_float32():
    # against numpy's nextafter: every value the cast rounds down moves up one step
    rng = np.random.default_rng(0)
    need = np.concatenate([
        rng.uniform(-300.0, 300.0, 20000), rng.uniform(-1e-40, 1e-40, 2000),
        [0.0, -0.0, np.inf, -np.inf, 1e-300, -1e-300, 3.0, -3.0, 0.1, -0.1],
    ])  # fmt: skip
    got = store._round_up32(need)
    want = need.astype(np.float32)
    low = want.astype(np.float64) < need
    want[low] = np.nextafter(want[low], np.float32(np.inf))
    np.testing.assert_array_equal(got.view(np.int32), want.view(np.int32))
    assert np.all(got.astype(np.float64) >= need) and low.sum() > 10000


def test_rejects_inconsistent_arrays():
    with pytest.raises(ValueError, match="NearPairs"):
        NearPairs(np.array([0, 2]), np.zeros(1, np.int32), np.zeros(1, np.float32), [0])
