"""Rest-to-rest (SlewTable) maneuver model on the fused screening engine.

References: ``sat.maneuver.pair_requirements`` (numpy table lookup)
and an independent table rebuilt here from ``kernels.slew.bang_coast_bang_time`` +
settle + gap margin on the same fine angle grid, read in numpy.
"""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest
from test_screen import synthetic_options

from jaxspline.base.elements import circular_orbit_over
from jaxspline.geometry.frames import angle_between
from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.slew import bang_coast_bang_time
from jaxspline.readers.mission import FlexMode, Satellite
from jaxspline.screen import fused as screen_fused
from jaxspline.screen import pairs as screen
from jaxspline.screen import slew_table, transitions

SETTLE, GAP_MARGIN, SIZE = 2.0, 0.5, 4096
_COLS = ("src", "dst", "T", "feasible", "margin", "effort", "t_min")


def _sat(model="eigen_axis"):
    orb = circular_orbit_over(math.radians(46.0), math.radians(15.0), 300.0, 0.0, altitude=550e3)
    flex = FlexMode(freq=2 * np.pi * 0.5, damping=0.01, tolerance=1e-6)
    return Satellite(
        "ea",
        orb,
        model=model,
        limits=AxisLimits(np.radians(2.0), np.radians(0.5 if model == "eigen_axis" else 0.05)),
        settle=SETTLE,
        flex=flex if model == "flexible" else None,
    )


def _unit(x):
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def _los_options(seed, n_routes=30, per_route=4, horizon=600.0):
    """Synthetic options with lines of sight spread over ~70 deg (some anti-parallel)."""
    rng = np.random.default_rng(seed)
    opt = synthetic_options(rng, n_routes=n_routes, per_route=per_route, horizon=horizon)
    n = len(opt.route)
    base = _unit(rng.normal(size=(n_routes, 3)) * [0.6, 0.6, 1.0] + [0, 0, 1.5])[opt.route]
    start = _unit(base + 0.02 * rng.normal(size=(n, 3)))
    end = _unit(base + 0.02 * rng.normal(size=(n, 3)))
    end[1:3] = -start[-3:-1]  # slews of pi from the first route to the last one
    end[0] = start[-1]  # and theta = 0 exactly
    scan_ok = rng.uniform(size=n) > 0.05
    scan_ok[:3] = scan_ok[-3:] = True
    return opt._replace(scan_ok=scan_ok, start_los=start, end_los=end)


def _independent_table(sat):
    """Upper bound of slew + settle + margin on the cells (theta_{k-1}, theta_k] (numpy).

    Node time at ``theta_k (1 + 1e-9) + 1e-14`` (rounding of the lookup and the angle),
    plus 1e-9 s; the flexible profile drops at its A -> C switch
    ``theta_s = 7/6 omega^2/eps`` from profile A's ``sqrt(8 theta_s/eps)`` (SPEC
    section 2): the cells around theta_s keep that value.
    """
    theta = math.pi * (np.arange(SIZE + 1) / SIZE) ** 2
    up = np.minimum(theta * (1.0 + 1e-9) + 1e-14, math.pi)
    rate, accel = float(sat.limits.rate), float(sat.limits.accel)
    if sat.model == "eigen_axis":
        t = np.asarray(bang_coast_bang_time(up, rate, accel))
    else:
        t = np.asarray(sat.maneuver.slew_time(sat, up)) - sat.settle
        th_s = 7.0 / 6.0 * rate * rate / accel
        k = np.ceil(SIZE * np.sqrt(th_s * (1.0 + np.array([-1e-9, 1e-9])) / math.pi) - 1e-12)
        k0, k1 = k.astype(int)
        t[k0 : k1 + 1] = np.maximum(t[k0 : k1 + 1], math.sqrt(8.0 * th_s * (1.0 + 1e-9) / accel))
    return t + sat.settle + GAP_MARGIN + 1e-9


def _ref_t_req(opt, src, dst, time):
    theta = np.clip(np.asarray(angle_between(opt.end_los[src], opt.start_los[dst])), 0, math.pi)
    k = np.minimum(np.ceil(SIZE * np.sqrt(theta / math.pi) - 1e-12), SIZE).astype(np.int64)
    return time[k], theta


@pytest.mark.parametrize("model", ["eigen_axis", "flexible"])
def test_slew_table_screen_matches_numpy_references(model):
    sat = _sat(model)
    table = slew_table.slew_table(sat, GAP_MARGIN, size=SIZE)
    opt = _los_options(41)
    tr = screen.screen_transitions(opt, table, progress=False, chunk_size=512)
    assert tr.src.size > 3000 and 0.1 < tr.feasible.mean() < 0.9
    # numpy reference of the planner: t_req where feasible, inf elsewhere
    need = sat.maneuver.pair_requirements(sat, opt, tr.src, tr.dst, table)
    np.testing.assert_array_equal(tr.feasible, np.isfinite(need))
    np.testing.assert_allclose(tr.t_min[tr.feasible], need[tr.feasible], rtol=1e-12, atol=0)
    # independent table from the slew kernel + settle + margin
    time = _independent_table(sat)
    np.testing.assert_allclose(table.time, time, rtol=1e-12, atol=0)
    t_req, theta = _ref_t_req(opt, tr.src, tr.dst, time)
    np.testing.assert_allclose(tr.t_min, t_req, rtol=1e-12, atol=0)
    T = opt.t_start[tr.dst] - opt.t_end[tr.src]
    np.testing.assert_array_equal(tr.feasible, (T > 0) & (T >= t_req))
    np.testing.assert_allclose(tr.margin, T - t_req, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tr.effort, t_req / T, rtol=1e-12)
    assert np.all((tr.effort <= 1) == tr.feasible)
    # the table never under-estimates the exact time; it over-estimates by the rise over
    # one cell, except in the cell of the flexible model's A -> C switch (the whole drop)
    exact = np.asarray(sat.maneuver.slew_time(sat, theta, GAP_MARGIN))
    assert np.all(tr.t_min >= exact)
    rate, accel = float(sat.limits.rate), float(sat.limits.accel)
    k_sw = math.ceil(SIZE * math.sqrt(7.0 / 6.0 * rate * rate / accel / math.pi) - 1e-12)
    k = np.ceil(SIZE * np.sqrt(theta / math.pi) - 1e-12)
    away = (k != k_sw) | (model == "eigen_axis")
    assert away.mean() > 0.99 and np.all((tr.t_min - exact)[away] < 0.05)
    assert theta.min() == 0.0 and theta.max() > 3.0
    # feasible_only and top_k select from the same screen
    only = screen.screen_transitions(opt, table, progress=False, feasible_only=True)
    for k in _COLS:
        np.testing.assert_array_equal(getattr(only, k), getattr(tr, k)[tr.feasible], err_msg=k)
    for k in (1, 3):
        best = screen.screen_transitions(opt, table, progress=False, top_k=k, chunk_size=16)
        ref = transitions.best_per_source(_rank(opt)[only.src], only.margin, k)
        for c in _COLS:
            np.testing.assert_array_equal(getattr(best, c), getattr(only, c)[ref], err_msg=c)
    # the pairs entry point and the host path agree exactly with the fused path
    pairs = screen.screen_pairs(opt, table, tr.src, tr.dst)
    host = screen._screen_transitions_host(opt, table, None, 1024, False, False, 0, 1)
    for k in _COLS:
        np.testing.assert_array_equal(getattr(pairs, k), getattr(tr, k), err_msg=k)
        np.testing.assert_array_equal(getattr(host, k), getattr(tr, k), err_msg=k)


def _rank(opt):
    valid = np.flatnonzero(opt.scan_ok)
    order = valid[np.argsort(opt.t_start[valid], kind="stable")]
    rank = np.empty(len(opt.t_start), np.int64)
    rank[order] = np.arange(order.size)
    return rank


def test_slew_table_t_le_zero_chunks_and_float32():
    sat = _sat()
    table = slew_table.slew_table(sat, GAP_MARGIN, size=SIZE)
    opt = _los_options(42, n_routes=12)
    # T <= 0 pairs through screen_pairs: infeasible, margin -inf, effort +inf
    src, dst = np.arange(10), np.arange(10)
    bad = screen.screen_pairs(opt, table, src, dst)
    assert not bad.feasible.any() and np.all(bad.margin == -np.inf) and np.all(bad.effort == np.inf)
    whole = screen.screen_transitions(opt, table, progress=False, max_gap=150.0)
    chunks = list(
        screen.screen_chunks(
            opt, table, progress=False, feasible_only=False, max_gap=150.0, chunk_size=4
        )
    )
    assert len(chunks) > 1
    for k in _COLS:
        np.testing.assert_array_equal(np.concatenate([getattr(c, k) for c in chunks]),
                                      getattr(whole, k))  # fmt: skip
    with jax.enable_x64(False):
        f32 = opt._replace(**{f: np.asarray(getattr(opt, f), np.float32) for f in
                              ("t_start", "t_end", "start_angle", "start_rate", "end_angle",
                               "end_rate", "value", "start_los", "end_los")})  # fmt: skip
        t32 = screen.screen_transitions(f32, table, progress=False, max_gap=150.0)
    assert t32.t_min.dtype == np.float32
    np.testing.assert_array_equal(t32.src, whole.src)
    clear = np.abs(whole.margin) > 1e-2
    np.testing.assert_array_equal(t32.feasible[clear], whole.feasible[clear])


def test_slew_table_value_errors():
    sat = _sat()
    table = slew_table.slew_table(sat, 0.0, size=64)
    opt = _los_options(43, n_routes=4)
    with pytest.raises(ValueError, match="end_los"):
        screen.screen_transitions(opt._replace(end_los=None), table, progress=False)
    with pytest.raises(ValueError, match="start_los"):
        screen.screen_pairs(opt._replace(start_los=opt.start_los[:, :2]), table, [0], [1])
    with pytest.raises(ValueError, match="model.time"):
        screen.screen_transitions(opt, slew_table.SlewTable(table.time[:-1], 64), progress=False)
    with pytest.raises(ValueError, match="model must be an AxisLimits"):
        screen.screen_transitions(opt, table.time, progress=False)
    # the pair function keys the compile cache by value: one program for both tables
    other = slew_table.slew_table(sat, 1.0, size=64)
    screen.screen_transitions(opt, table, progress=False)
    n = screen_fused._fused_program.cache_info().currsize
    screen.screen_transitions(opt, other, progress=False)
    assert screen_fused._fused_program.cache_info().currsize == n


@pytest.mark.parametrize("model", ["eigen_axis", "flexible"])
def test_slew_table_screen_sequences_match_a_numpy_composition(model):
    """Whole sequences under a SlewTable: first failure = first of (scan_ok false, route
    repeated, T <= 0 or T below the numpy table lookup of ``pair_requirements``)."""
    from jaxspline.sequences.route_screen import screen_sequences

    sat = _sat(model)
    table = slew_table.slew_table(sat, GAP_MARGIN, SIZE)
    opt = _los_options(7)
    rng = np.random.default_rng(3)
    n, kk, ll = len(opt.route), 400, 6
    order = np.argsort(opt.t_start, kind="stable")
    seq = np.full((kk, ll), -1, np.int64)
    for r in range(kk):  # mostly increasing in time, sometimes random, random lengths
        m = rng.integers(1, ll + 1)
        pick = np.sort(rng.choice(n, m, replace=False)) if r % 3 else rng.choice(n, m)
        seq[r, :m] = order[pick] if r % 3 else pick
    with jax.enable_x64(True):
        feas, first, value = screen_sequences(opt, seq, table, chunk_size=64)
    scan_ok = np.asarray(opt.scan_ok, bool)
    want_first = np.full(kk, -1)
    for r in range(kk):
        row = seq[r][seq[r] >= 0]
        for p, j in enumerate(row):
            bad = not scan_ok[j] or opt.route[j] in opt.route[row[:p]]
            if p and not bad:
                need = sat.maneuver.pair_requirements(sat, opt, [row[p - 1]], [j], table)[0]
                bad = not np.isfinite(need)
            if bad:
                want_first[r] = p
                break
    np.testing.assert_array_equal(first, want_first)
    np.testing.assert_array_equal(feas, want_first < 0)
    assert 0.1 < feas.mean() < 0.9  # both outcomes occur
    want_value = [np.asarray(opt.value)[row[row >= 0]].sum() for row in seq]
    np.testing.assert_allclose(value, want_value, rtol=1e-14)
