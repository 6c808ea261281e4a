"""The planner's near pairs through the fused screen equal the host-built reference.

``_near_pairs_host`` is the planner's former implementation (pairs built on the host
with ``ragged_positions``, screened with the model's ``pair_requirements``), kept here as
the reference for the same inputs as :func:`jaxspline.planner.pipeline.build_problem`.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_planner import _scenario

from jaxspline.kernels.batch import ragged_positions
from jaxspline.planner import build as planner
from jaxspline.search.store import NearPairs, start_order

_PAIR_BLOCK = 1 << 20


def _near_pairs_host(sc, opp, tables, far, slack):
    o = opp.options
    src_all, dst_all, need_all = [], [], []
    for k, sat in enumerate(sc.satellites):
        ids = np.flatnonzero(o.sat == k)
        if ids.size == 0:
            continue
        s, e = o.t_start[ids], o.t_end[ids]
        eo = ids[np.argsort(e, kind="stable")]
        es = o.t_end[eo]
        a = np.searchsorted(es, s - far[k] - slack, side="right")
        b = np.searchsorted(es, s, side="left")
        cnt = np.maximum(b - a, 0)
        rows = max(1, ids.size * _PAIR_BLOCK // max(int(cnt.sum()), 1))
        for c0 in range(0, ids.size, rows):
            sl = slice(c0, c0 + rows)
            owner, off = ragged_positions(cnt[sl])
            jj = ids[sl][owner]
            ii = eo[a[sl][owner] + off]
            need = sat.maneuver.pair_requirements(sat, o, ii, jj, tables[k])
            ok = np.isfinite(need)
            src_all.append(ii[ok])
            dst_all.append(jj[ok])
            need_all.append(need[ok])
    if not src_all:
        z = np.zeros(0, np.int64)
        return z, z, np.zeros(0)
    return np.concatenate(src_all), np.concatenate(dst_all), np.concatenate(need_all)


@pytest.mark.parametrize("far_scale", [1.0, 0.25])
def test_near_pairs_equal_the_host_reference(monkeypatch, far_scale):
    """Per-channel, eigen-axis and flexible satellites: same pairs, same order, same needs."""
    calls = []
    new = planner._near_pairs

    def spy(sc, opp, tables, far, slack, join_filter=None, **kw):
        far = np.asarray(far) * far_scale  # a shorter window cuts through feasible pairs
        calls.append((sc, opp, tables, far, slack))
        return new(sc, opp, tables, far, slack, join_filter, **kw)

    monkeypatch.setattr(planner, "_near_pairs", spy)
    sc = _scenario(0, 20, 2, 14.0, 0)
    planner.build_problem(sc)
    ((sc, opp, tables, far, slack),) = calls
    with planner.jax.enable_x64(True):
        table, removed = new(sc, opp, tables, far, slack)
        ref = _near_pairs_host(sc, opp, tables, far, slack)
    assert removed == 0
    o = opp.options
    # the store keeps pairs by destination row (start order), sources ascending
    want = NearPairs.from_arrays(len(opp), *ref, rows=start_order(o.t_start, o.sat))
    got = (table.src.astype(np.int64), table.dst(), table.need.astype(np.float64))
    models = {sc.satellites[k].model for k in np.unique(o.sat[got[0]])}
    assert models == ({"per_channel", "eigen_axis", "flexible"} if far_scale == 1 else models)
    assert got[0].size > (200 if far_scale == 1 else 20)
    np.testing.assert_array_equal(table.ptr, want.ptr)
    np.testing.assert_array_equal(table.src, want.src)
    # needs are stored in float32, rounded up: never below the float64 screen value
    ref_need = np.asarray(ref[2])[np.lexsort((ref[0], want.row_of[ref[1]]))]
    assert np.all(got[2] >= ref_need)
    np.testing.assert_allclose(got[2], ref_need, rtol=2.5e-7, atol=0)
    # gaps inside the planner's window, same-target pairs included
    gap = o.t_start[got[1]] - o.t_end[got[0]]
    assert np.all(gap > 0) and np.all(gap < far[o.sat[got[0]]] + slack)
    assert np.any(o.route[got[0]] == o.route[got[1]])
