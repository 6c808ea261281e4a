"""Tests of jaxspline.kernels.reach: hand-computed values, numerical integration, brute force.

The Ruckig oracle tests live in tests/kernels/test_reach_ruckig.py.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads

from jaxspline import kernels
from jaxspline.kernels import reach
from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.reach import (
    angle_interval,
    envelopes,
    is_reachable,
    rate_interval,
    reach_margin,
    transfer,
)
from jaxspline.kernels.reach_durations import (
    feasible_durations,
    min_peak_accel,
    min_transfer_time,
)

LIM = AxisLimits(1.0, 1.0)


def _f(x):
    return np.asarray(x, dtype=float)


def _random_cases(n, seed, feasible_t=True):
    """Random boundary data (a1, b1, b2, T, b, d) with |b_i| <= b and |b1 - b2| <= dT."""
    rng = np.random.default_rng(seed)
    b = np.exp(rng.uniform(np.log(0.05), np.log(3.0), n))
    d = np.exp(rng.uniform(np.log(0.05), np.log(3.0), n))
    b1 = rng.uniform(-1, 1, n) * b
    b2 = rng.uniform(-1, 1, n) * b
    edge = rng.uniform(size=n)
    b1 = np.where(edge < 0.1, b, np.where(edge < 0.2, -b, b1))
    b2 = np.where((edge > 0.3) & (edge < 0.4), b, np.where(edge > 0.9, -b, b2))
    t0 = np.abs(b1 - b2) / d
    T = t0 + rng.uniform(0, 1, n) * rng.choice([0.5, 3.0, 20.0], n) * b / d
    if feasible_t:
        T = np.where((edge > 0.5) & (edge < 0.55), t0, T)
    a1 = rng.uniform(-2, 2, n)
    return a1, b1, b2, T, b, d


# ----------------------------------------------------------------------------- hand tables

# (a1, b1, b2, T, b, d) -> (lo, hi), computed by hand from the envelope areas
ANGLE_TABLE = [
    ((0.0, 0.0, 0.0, 2.0, 1.0, 1.0), (-1.0, 1.0)),  # two triangles, apex exactly at +-b
    ((0.0, 0.0, 0.0, 4.0, 1.0, 1.0), (-3.0, 3.0)),  # trapezoids: 4 - 1
    ((0.0, 1.0, 1.0, 2.0, 1.0, 1.0), (1.0, 2.0)),  # coast at b; dip to 0 and back
    ((0.5, 0.0, 1.0, 1.0, 1.0, 1.0), (1.0, 1.0)),  # T = |b1 - b2|/d: single parabola
    ((0.0, 0.0, 0.0, 0.0, 1.0, 1.0), (0.0, 0.0)),  # T = 0
    ((0.0, 0.5, -0.5, 0.5, 1.0, 1.0), (math.inf, -math.inf)),  # |b1-b2| > dT
    ((0.0, 1.5, 0.0, 5.0, 1.0, 1.0), (math.inf, -math.inf)),  # |b1| > b
]


@pytest.mark.parametrize(("args", "expected"), ANGLE_TABLE)
def test_angle_interval_table(args, expected):
    a1, b1, b2, T, b, d = args
    lo, hi = angle_interval(a1, b1, b2, T, AxisLimits(b, d))
    np.testing.assert_allclose([float(lo), float(hi)], expected, rtol=1e-14, atol=1e-14)


def test_rate_interval_table():
    # a1 = 0, b1 = 0, T = 2, b = d = 1, a2 = 0: 2 - (2 - b2)^2/4 >= 0 <=> b2 >= 2 - 2 sqrt 2
    lo, hi = rate_interval(0.0, 0.0, 0.0, 2.0, LIM)
    np.testing.assert_allclose([lo, hi], [2 - 2 * math.sqrt(2), 2 * math.sqrt(2) - 2], rtol=1e-14)
    # a2 at the top corner hi(U): only b2 = b1 + dT
    lo, hi = rate_interval(0.0, 0.0, 0.5, 1.0, LIM)
    np.testing.assert_allclose([lo, hi], [1.0, 1.0], atol=1e-7)
    lo, hi = rate_interval(0.0, 0.0, 0.6, 1.0, LIM)
    assert float(lo) == math.inf and float(hi) == -math.inf


def test_durations_table():
    # SPEC example b1 = b2 = b, D > 0: [D/b, 2(b - sqrt(b^2 - dD))/d] U [2(b + sqrt(...))/d, inf)
    b, d, D = 1.0, 1.0, 0.75
    out = feasible_durations(0.0, b, D, b, AxisLimits(b, d))
    np.testing.assert_allclose(out, [0.75, 1.0, 3.0], rtol=1e-14)
    # rest to rest: bang-bang 2 sqrt(D/d) if D <= b^2/d, else D/b + b/d; no blocked interval
    for D, expect in [(0.25, 1.0), (1.0, 2.0), (4.0, 5.0)]:
        tm, lo, hi = feasible_durations(0.0, 0.0, D, 0.0, LIM)
        np.testing.assert_allclose(float(tm), expect, rtol=1e-14)
        assert float(lo) == float(hi) == float(tm)
    assert float(min_transfer_time(0.0, 2.0, 1.0, 0.0, LIM)) == math.inf
    # decelerating to rest takes exactly T0 = 1 and any longer T also works (H' >= 0)
    np.testing.assert_allclose(feasible_durations(0.0, -1.0, -0.5, 0.0, LIM), [1.0] * 3)
    # the isolated point T0 = |b1 - b2|/d = 0.5 with b1 = -1, b2 = -0.5, D = E0 = -0.375:
    # H(T) = -0.75 T - 0.0625 + T^2/4 dips below D on (0.5, 2.5)
    np.testing.assert_allclose(
        feasible_durations(0.0, -1.0, -0.375, -0.5, LIM), [0.5, 0.5, 2.5], rtol=1e-14
    )


def test_min_peak_accel_table():
    # rest to rest D = 1, T = 2: bang-bang d = 4D/T^2 = 1 (peak rate 1 <= b = 1)
    np.testing.assert_allclose(min_peak_accel(0.0, 0.0, 1.0, 0.0, 2.0, 1.0), 1.0, rtol=1e-14)
    # b = 0.8: trapezoid D = bT - b^2/d -> d = b^2/(bT - D)
    np.testing.assert_allclose(min_peak_accel(0.0, 0.0, 1.0, 0.0, 2.0, 0.8), 0.64 / 0.6, rtol=1e-14)
    # rate change only: d = |b1 - b2|/T, D on the parabola
    np.testing.assert_allclose(min_peak_accel(0.0, 0.0, 0.5, 1.0, 1.0, 1.0), 1.0, rtol=1e-12)
    assert float(min_peak_accel(0.0, 0.0, 3.0, 0.0, 2.0, 1.0)) == math.inf  # D > bT
    assert float(min_peak_accel(0.0, 0.0, 0.0, 0.0, 0.0, 1.0)) == 0.0
    assert float(min_peak_accel(0.0, 0.0, 1.0, 0.0, 0.0, 1.0)) == math.inf


# ----------------------------------------------------------------------------- integration


def _integrated_envelopes(a1, b1, b2, T, b, d, n=100_001):
    """Cumulative-trapezoid integrals of F_hi, F_lo on n points (independent of reach)."""
    t = np.linspace(0.0, T, n)
    f_hi = np.minimum(np.minimum(b1 + d * t, b2 + d * (T - t)), b)
    f_lo = np.maximum(np.maximum(b1 - d * t, b2 - d * (T - t)), -b)
    dt = np.diff(t)
    up = a1 + np.concatenate([[0.0], np.cumsum(0.5 * (f_hi[1:] + f_hi[:-1]) * dt)])
    dn = a1 + np.concatenate([[0.0], np.cumsum(0.5 * (f_lo[1:] + f_lo[:-1]) * dt)])
    return t, dn, up


def test_angle_interval_and_envelopes_vs_integration():
    a1, b1, b2, T, b, d = _random_cases(60, seed=1)
    lo, hi = angle_interval(a1, b1, b2, T, AxisLimits(b, d))
    dev_end = dev_curve = 0.0
    for i in range(len(a1)):
        t, dn, up = _integrated_envelopes(a1[i], b1[i], b2[i], T[i], b[i], d[i])
        scale = abs(a1[i]) + b[i] * T[i] + 1e-300
        dev_end = max(dev_end, abs(up[-1] - hi[i]) / scale, abs(dn[-1] - lo[i]) / scale)
        e_lo, e_hi = envelopes(a1[i], b1[i], b2[i], T[i], AxisLimits(b[i], d[i]), t[::97])
        dev_curve = max(
            dev_curve,
            np.max(np.abs(_f(e_hi) - up[::97])) / scale,
            np.max(np.abs(_f(e_lo) - dn[::97])) / scale,
        )
    print(
        f"\n[reach] integration vs angle_interval: max rel dev {dev_end:.2e}, "
        f"envelope curves {dev_curve:.2e} (60 cases, 1e5 points)"
    )
    assert dev_end < 1e-9
    assert dev_curve < 1e-9


# ----------------------------------------------------------------------------- brute force


def test_rate_interval_vs_brute_force():
    rng = np.random.default_rng(2)
    n_cases, n_grid = 300, 4001
    b, d = np.exp(rng.uniform(np.log(0.1), np.log(2.0), (2, n_cases)))
    b1 = np.select(
        [rng.uniform(size=n_cases) < 0.1, rng.uniform(size=n_cases) < 0.1],
        [b, -b],
        rng.uniform(-1, 1, n_cases) * b,
    )
    T = rng.uniform(0.01, 4.0, n_cases) * b / d
    lim = AxisLimits(b, d)
    low = _f(angle_interval(0.0, b1, np.maximum(-b, b1 - d * T), T, lim)[0])
    top = _f(angle_interval(0.0, b1, np.minimum(b, b1 + d * T), T, lim)[1])
    a2 = low + rng.uniform(-0.1, 1.1, n_cases) * (top - low)
    grid = np.linspace(-1, 1, n_grid)[None, :] * b[:, None]
    lo_g, hi_g = angle_interval(0.0, b1[:, None], grid, T[:, None], lim_b(b, d))
    member = (_f(lo_g) <= a2[:, None]) & (a2[:, None] <= _f(hi_g))
    r_lo, r_hi = (_f(x) for x in rate_interval(0.0, b1, a2, T, lim))
    h = grid[:, 1] - grid[:, 0]
    any_member = member.any(axis=1)
    # empty on the grid: the exact interval is empty or thinner than one cell
    empty_ok = (r_lo > r_hi) | (r_hi - r_lo < h)
    first = grid[np.arange(n_cases), np.argmax(member, axis=1)]
    last = grid[np.arange(n_cases), n_grid - 1 - np.argmax(member[:, ::-1], axis=1)]
    # grid members lie inside [r_lo, r_hi]; the true ends within one cell of them
    dev = np.where(any_member, np.maximum(np.abs(first - r_lo), np.abs(last - r_hi)) / h, 0.0)
    agree = np.where(any_member, dev <= 1.0 + 1e-6, empty_ok)
    print(
        f"\n[reach] rate_interval vs brute force: {agree.sum()}/{n_cases} agree "
        f"({(~any_member).sum()} empty), max end deviation {dev.max():.3f} grid cells"
    )
    assert agree.all()
    assert (~any_member).sum() > 10 and any_member.sum() > 200


def test_rate_interval_ends_are_boundary_points():
    """At the returned ends a2 hits hi or lo or the end rate hits [L, U] (closed-form check)."""
    a1, b1, b2, T, b, d = _random_cases(500, seed=3)
    lim = AxisLimits(b, d)
    lo, hi = angle_interval(a1, b1, b2, T, lim)
    lam = np.random.default_rng(4).uniform(0, 1, len(a1))
    a2 = _f(lo) + lam * (_f(hi) - _f(lo))
    r_lo, r_hi = rate_interval(a1, b1, a2, T, lim)
    assert np.all(_f(r_lo) <= b2 + 1e-9) and np.all(b2 <= _f(r_hi) + 1e-9)
    for end in (r_lo, r_hi):
        assert np.all(_f(is_reachable(a1, b1, a2, end, T, lim)))
    eps = 1e-6 * b
    out_lo = _f(r_lo) - eps
    out_hi = _f(r_hi) + eps
    # just outside: the margin (no tolerance) is negative; near a cusp corner of P the
    # set is thinner than the tolerance of is_reachable, hence the margin here
    assert np.all(_f(reach_margin(a1, b1, a2, out_lo, T, lim)) < 0)
    assert np.all(_f(reach_margin(a1, b1, a2, out_hi, T, lim)) < 0)


# ----------------------------------------------------------------------------- transfer


def test_transfer_respects_bounds_and_boundary_values():
    a1, b1, b2, T, b, d = _random_cases(300, seed=5)
    lim = AxisLimits(b, d)
    lo, hi = angle_interval(a1, b1, b2, T, lim)
    lam = np.random.default_rng(6).choice([0.0, 1.0, 0.5, 0.123, 0.9], len(a1))
    a2 = _f(lo) + lam * (_f(hi) - _f(lo))
    n = 4001
    t = np.linspace(0, 1, n)[None, :] * T[:, None]
    ang, rate, acc = transfer(*(x[:, None] for x in (a1, b1, a2, b2, T)), lim_b(b, d), t)
    ang, rate, acc = _f(ang), _f(rate), _f(acc)
    assert np.all(np.isfinite(ang))
    scale = np.abs(a1) + b * T + 1e-300
    np.testing.assert_allclose(ang[:, 0], a1, atol=1e-12)
    assert np.max(np.abs(ang[:, -1] - a2) / scale) < 1e-12
    np.testing.assert_allclose(rate[:, 0], b1, atol=1e-12)
    np.testing.assert_allclose(rate[:, -1], b2, atol=1e-12)
    assert np.all(np.abs(rate) <= b[:, None] * (1 + 1e-12))
    assert np.all(np.abs(acc) <= d[:, None] * (1 + 1e-12))
    # angle is the integral of rate, rate the integral of accel (trapezoid, independent)
    dt = np.diff(t, axis=1)
    ang_int = a1[:, None] + np.cumsum(0.5 * (rate[:, 1:] + rate[:, :-1]) * dt, axis=1)
    assert np.max(np.abs(ang_int - ang[:, 1:]) / scale[:, None]) < 1e-6
    rate_int = b1[:, None] + np.cumsum(acc[:, :-1] * dt, axis=1)
    # left rectangles on a piecewise-constant accel: <= 4 switches, each off by <= d dt
    assert np.max(np.abs(rate_int - rate[:, 1:]) / (d[:, None] * dt)) < 4.01


def lim_b(b, d):
    return AxisLimits(b[:, None], d[:, None])


def test_transfer_hi_equals_lo_and_unreachable():
    # T = |b1 - b2|/d: only one trajectory
    ang, rate, acc = transfer(0.0, 0.0, 0.5, 1.0, 1.0, LIM, jnp.array([0.0, 0.5, 1.0]))
    np.testing.assert_allclose(ang, [0.0, 0.125, 0.5], atol=1e-14)
    np.testing.assert_allclose(rate, [0.0, 0.5, 1.0], atol=1e-14)
    np.testing.assert_allclose(acc[:2], [1.0, 1.0])
    ang, rate, acc = transfer(0.0, 0.0, 5.0, 0.0, 1.0, LIM, 0.5)
    assert float(ang) == float(rate) == float(acc) == math.inf


# ----------------------------------------------------------------------------- min peak accel


def test_min_peak_accel_consistent_with_is_reachable_and_bisection():
    rng = np.random.default_rng(7)
    n = 2000
    b = rng.uniform(0.1, 2.0, n)
    b1 = rng.uniform(-1, 1, n) * b
    b2 = rng.uniform(-1, 1, n) * b
    b1 = np.where(rng.uniform(size=n) < 0.1, b, b1)
    a1 = rng.uniform(-1, 1, n)
    T = rng.uniform(0.01, 10.0, n)
    a2 = a1 + rng.uniform(-1, 1, n) * b * T * 1.05
    ds = _f(min_peak_accel(a1, b1, a2, b2, T, b))
    fin = np.isfinite(ds) & (ds > 0)
    up = _f(is_reachable(a1, b1, a2, b2, T, AxisLimits(b, np.where(fin, ds, 1.0) * (1 + 1e-9))))
    dn = _f(is_reachable(a1, b1, a2, b2, T, AxisLimits(b, np.where(fin, ds, 1.0) * (1 - 1e-6))))
    assert np.all(up[fin]) and not np.any(dn[fin])
    inf = ~np.isfinite(ds)
    assert inf.sum() > 50
    assert not np.any(_f(is_reachable(a1, b1, a2, b2, T, AxisLimits(b, 1e8)))[inf])
    # brute-force bisection on d with the membership test (monotone in d)
    idx = np.flatnonzero(fin)[:200]
    lo_d = np.full(idx.size, 1e-8)
    hi_d = np.full(idx.size, 1e4)
    args = tuple(x[idx] for x in (a1, b1, a2, b2, T))
    for _ in range(80):
        mid = np.sqrt(lo_d * hi_d)
        ok = _f(reach.is_reachable(*args, AxisLimits(b[idx], mid)))
        hi_d = np.where(ok, mid, hi_d)
        lo_d = np.where(ok, lo_d, mid)
    dev = np.max(np.abs(hi_d - ds[idx]) / ds[idx])
    print(f"\n[reach] min_peak_accel vs bisection: max rel dev {dev:.2e} ({idx.size} cases)")
    assert dev < 1e-9


# ----------------------------------------------------------------------------- consistency


def test_margin_sign_matches_membership():
    a1, b1, b2, T, b, d = _random_cases(3000, seed=8, feasible_t=False)
    rng = np.random.default_rng(9)
    b1 = b1 * rng.choice([1.0, 1.0, 1.0, 1.2], len(b1))
    a2 = a1 + rng.uniform(-1.2, 1.2, len(a1)) * b * T
    lim = AxisLimits(b, d)
    m = _f(reach_margin(a1, b1, a2, b2, T, lim))
    r = np.asarray(is_reachable(a1, b1, a2, b2, T, lim), bool)
    clear = np.abs(m) > 1e-9
    assert np.all((m[clear] >= 0) == r[clear])
    assert r.sum() > 200 and (~r).sum() > 200


def test_durations_consistent_with_is_reachable():
    a1, b1, b2, T, b, d = _random_cases(400, seed=10)
    rng = np.random.default_rng(11)
    a2 = a1 + rng.uniform(-1, 1, len(a1)) * b * b / d * rng.choice([0.3, 3.0], len(a1))
    lim = AxisLimits(b, d)
    tm, blo, bhi = (_f(x) for x in feasible_durations(a1, b1, a2, b2, lim))
    assert np.sum(bhi > blo) > 10
    tt = tm[:, None] * np.linspace(0.0, 3.0, 301)[None, :] + (bhi - blo)[:, None] * 0.0
    tt = np.concatenate([tt, blo[:, None] + (bhi - blo)[:, None] * np.linspace(-0.1, 1.1, 61)], 1)
    tt = np.maximum(tt, 0.0)
    pred = (tt >= tm[:, None]) & ~((tt > blo[:, None]) & (tt < bhi[:, None]))
    got = _f(is_reachable(*(x[:, None] for x in (a1, b1, a2, b2)), tt, lim_b(b, d)))
    # exclude points within 1e-9 (relative) of an interval end
    ends = np.stack([tm, blo, bhi], 1)
    near = np.min(np.abs(tt[:, :, None] - ends[:, None, :]), axis=2) <= 1e-9 * (1 + tt)
    assert np.all((pred == got) | near)


def test_monotone_and_shape_properties():
    """hi(b2) non-decreasing & concave, lo(b2) non-decreasing & convex (Theorem 6)."""
    rng = np.random.default_rng(12)
    for _ in range(50):
        b, d = rng.uniform(0.1, 2, 2)
        b1 = rng.uniform(-b, b)
        T = rng.uniform(0.05, 5) * b / d
        lower, upper = max(-b, b1 - d * T), min(b, b1 + d * T)
        g = np.linspace(lower, upper, 501)
        lo, hi = (_f(x) for x in angle_interval(0.0, b1, g, T, AxisLimits(b, d)))
        sc = b * T * 1e-12
        assert np.all(np.diff(hi) >= -sc) and np.all(np.diff(lo) >= -sc)
        assert np.all(np.diff(hi, 2) <= sc) and np.all(np.diff(lo, 2) >= -sc)


# ----------------------------------------------------------------------------- jit / vmap / dtypes

KERNEL_ARGS = {
    "angle_interval_kernel": lambda c: (c[0], c[1], c[3], c[4], c[5], c[6]),
    "rate_interval_kernel": lambda c: (c[0], c[1], c[2], c[4], c[5], c[6]),
    "is_reachable_kernel": lambda c: c[:7],
    "reach_margin_kernel": lambda c: c[:7],
    "min_transfer_time_kernel": lambda c: (c[0], c[1], c[2], c[3], c[5], c[6]),
    "feasible_durations_kernel": lambda c: (c[0], c[1], c[2], c[3], c[5], c[6]),
    "min_peak_accel_kernel": lambda c: c[:6],
    "transfer_kernel": lambda c: (*c[:7], c[4] * 0.37),
    "envelopes_kernel": lambda c: (c[0], c[1], c[3], c[4], c[5], c[6], c[4] * 0.37),
}


def _cases_matrix(n=64, seed=13):
    a1, b1, b2, T, b, d = _random_cases(n, seed=seed)
    lo, hi = angle_interval(a1, b1, b2, T, AxisLimits(b, d))
    a2 = _f(lo) + np.random.default_rng(seed).uniform(-0.2, 1.2, n) * (_f(hi) - _f(lo))
    return [a1, b1, a2, b2, T, b, d]


_JIT_VMAP = {name: jax.jit(jax.vmap(getattr(kernels, name))) for name in KERNEL_ARGS}
# min_transfer_time_kernel is feasible_durations_kernel[0]; skip it in the costly tests
HEAVY = sorted(set(KERNEL_ARGS) - {"min_transfer_time_kernel"})


@pytest.mark.parametrize("name", sorted(KERNEL_ARGS))
def test_scalar_jit_vmap_agree(name):
    kern = getattr(kernels, name)
    cols = KERNEL_ARGS[name](_cases_matrix())
    batched = _JIT_VMAP[name](*(jnp.asarray(c) for c in cols))
    batched = batched if isinstance(batched, tuple) else (batched,)
    jitted = jax.jit(kern)
    for i in (0, 17, 42):
        s = kern(*(float(c[i]) for c in cols))
        j = jitted(*(float(c[i]) for c in cols))
        s = s if isinstance(s, tuple) else (s,)
        j = j if isinstance(j, tuple) else (j,)
        for sv, jv, bv in zip(s, j, batched, strict=True):
            np.testing.assert_allclose(_f(sv), _f(jv), rtol=1e-13)
            np.testing.assert_allclose(_f(sv), _f(bv[i]), rtol=1e-13)
            assert np.isfinite(_f(sv)) or _f(sv) in (np.inf, -np.inf) or _f(sv).dtype == bool


@pytest.mark.parametrize("name", HEAVY)
def test_float32_follows_dtype_and_matches_float64(name):
    cols = KERNEL_ARGS[name](_cases_matrix())
    out64 = _JIT_VMAP[name](*(jnp.asarray(c, jnp.float64) for c in cols))
    out32 = _JIT_VMAP[name](*(jnp.asarray(c, jnp.float32) for c in cols))
    out64 = out64 if isinstance(out64, tuple) else (out64,)
    out32 = out32 if isinstance(out32, tuple) else (out32,)
    for x64, x32 in zip(out64, out32, strict=True):
        if x64.dtype == bool:
            assert x32.dtype == bool
            assert np.mean(_f(x64) == _f(x32)) > 0.97  # boundary cases may flip
            continue
        assert x32.dtype == jnp.float32
        x64, x32 = _f(x64), _f(x32)
        both = np.isfinite(x64) & np.isfinite(x32)
        assert np.mean(both | (x64 == x32)) > 0.97
        if name.startswith(("transfer", "envelopes", "angle", "reach_margin")):
            scale = np.abs(cols[0]) + cols[5] * cols[4] + 1.0  # |a1| + bT
        elif name.startswith("rate"):
            scale = cols[5]
        else:
            scale = np.abs(x64) + 1e-3
        err = np.abs(x64[both] - x32[both]) / np.broadcast_to(scale, x64.shape)[both]
        assert np.quantile(err, 0.95) < 1e-4


def test_public_api_follows_float32():
    lo, hi = angle_interval(
        jnp.float32(0.0),
        jnp.float32(0.1),
        jnp.float32(0.0),
        jnp.float32(2.0),
        AxisLimits(jnp.float32(1.0), jnp.float32(1.0)),
    )
    assert lo.dtype == hi.dtype == jnp.float32


def test_broadcasting_shapes():
    lo, hi = angle_interval(jnp.zeros((3, 1)), 0.0, jnp.linspace(-0.5, 0.5, 4), 2.0, LIM)
    assert lo.shape == hi.shape == (3, 4)
    r = is_reachable(0.0, 0.0, jnp.linspace(-2, 2, 5), 0.0, 2.0, AxisLimits(jnp.ones(5), 1.0))
    np.testing.assert_array_equal(r, [False, True, True, True, False])


# ----------------------------------------------------------------------------- gradients

BOUNDARY_CASES = [
    # (a1, b1, a2, b2, T, b, d) exactly at regime switches
    (0.0, 0.0, 0.3, 0.0, 2.0, 1.0, 1.0),  # yA = b and yC = -b
    (0.0, 1.0, 1.5, 1.0, 2.0, 1.0, 1.0),  # |b1| = |b2| = b
    (0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0),  # |b1 - b2| = dT, hi == lo, a2 = hi
    (0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0),  # T = 0
    (0.0, 0.0, 1.0, 0.0, 2.0, 1.0, 1.0),  # a2 = hi exactly
    (0.0, -1.0, -0.375, -0.5, 0.5, 1.0, 1.0),  # D = E0 (isolated T0)
    (0.0, 1.0, 0.75, 1.0, 1.0, 1.0, 1.0),  # blocked-interval end
    (0.0, 0.0, 0.0, 0.0, 2.0, 1.0, 1.0),  # zero-displacement, zero-rate
]


@pytest.mark.parametrize("name", HEAVY)
def test_gradients_finite_at_boundaries(name):
    if name == "is_reachable_kernel":
        return
    kern = getattr(kernels, name)
    # the boundary table plus random cases (a2 partly outside [lo, hi])
    table = np.concatenate([np.array(BOUNDARY_CASES).T, np.array(_cases_matrix())], axis=1)
    cols = KERNEL_ARGS[name](list(table))

    def total(*a):
        out = kern(*a)
        out = out if isinstance(out, tuple) else (out,)
        return sum(jnp.where(jnp.isfinite(o), o, 0.0) for o in out)

    grad = jax.vmap(jax.grad(total, argnums=tuple(range(len(cols)))))
    grads = grad(*(jnp.asarray(c) for c in cols))
    for g in grads:
        assert np.all(np.isfinite(_f(g))), (name, g)


SMOOTH_POINTS = {
    "angle_interval_kernel": (0.1, 0.2, -0.1, 3.0, 1.0, 0.7),
    "rate_interval_kernel": (0.1, 0.2, 0.6, 3.0, 1.0, 0.7),
    "reach_margin_kernel": (0.1, 0.2, 0.5, -0.1, 3.0, 1.0, 0.7),
    "min_peak_accel_kernel": (0.1, 0.2, 1.9, -0.1, 3.0, 1.0),
    "feasible_durations_kernel": (0.1, 0.2, 1.9, -0.1, 1.0, 0.7),
    "transfer_kernel": (0.1, 0.2, 0.5, -0.1, 3.0, 1.0, 0.7, 1.3),
    "envelopes_kernel": (0.1, 0.2, -0.1, 3.0, 1.0, 0.7, 1.3),
}


@pytest.mark.parametrize("name", sorted(SMOOTH_POINTS))
def test_check_grads_away_from_kinks(name):
    kern = getattr(kernels, name)
    args = tuple(jnp.float64(x) for x in SMOOTH_POINTS[name])
    check_grads(kern, args, order=1, modes=["rev"], eps=1e-6, atol=1e-5, rtol=1e-5)


def test_margin_gradient_points_inward():
    """A gradient step on the margin moves an unreachable a2 toward the set."""
    g = jax.grad(reach.reach_margin_kernel, argnums=2)(0.0, 0.0, 1.5, 0.0, 2.0, 1.0, 1.0)
    assert float(g) == -1.0
    g = jax.grad(reach.reach_margin_kernel, argnums=4)(0.0, 0.0, 1.5, 0.0, 2.0, 1.0, 1.0)
    assert float(g) > 0  # longer T helps


# ----------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: angle_interval(0.0, 0.0, 0.0, 1.0, AxisLimits(-1.0, 1.0)), "limits.rate"),
        (lambda: angle_interval(0.0, 0.0, 0.0, 1.0, AxisLimits(1.0, 0.0)), "limits.accel"),
        (lambda: angle_interval(0.0, 0.0, 0.0, -1.0, LIM), "T"),
        (lambda: is_reachable(math.nan, 0.0, 0.0, 0.0, 1.0, LIM), "a1"),
        (lambda: is_reachable(0.0, 0.0, 0.0, math.nan, 1.0, LIM), "b2"),
        (lambda: rate_interval(0.0, 0.0, np.zeros(3), np.ones(4), LIM), "broadcast"),
        (lambda: reach_margin(0.0, 0.0, 0.0, 0.0, math.nan, LIM), "T"),
        (lambda: min_peak_accel(0.0, 0.0, 0.0, 0.0, 1.0, 0.0), "rate"),
        (lambda: feasible_durations(0.0, 0.0, 1.0, 0.0, "fast"), "limits"),
        (lambda: transfer(0.0, 0.0, 0.0, 0.0, 1.0, LIM, math.nan), "t"),
        (lambda: envelopes(0.0, 0.0, 0.0, 1.0, LIM, [0.0, math.inf]), "t"),
        (lambda: min_transfer_time(0.0, "x", 0.0, 0.0, LIM), "b1"),
    ],
)
def test_value_errors(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_t_zero_allowed():
    assert bool(is_reachable(0.3, 0.1, 0.3, 0.1, 0.0, LIM))
    assert not bool(is_reachable(0.3, 0.1, 0.3, 0.2, 0.0, LIM))


@pytest.mark.slow
def test_reach_figures(tmp_path):
    import importlib.util
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "scripts" / "reach_figures.py"
    spec = importlib.util.spec_from_file_location("reach_figures", script)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    paths = mod.make_reach_figures(tmp_path)
    assert len(paths) == 8 and all(p.stat().st_size > 10_000 for p in paths)
