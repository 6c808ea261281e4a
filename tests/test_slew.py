"""Tests for jaxspline.slew: rigid models vs Ruckig, profiles A-D vs the paper and
numerical integration."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from ruckig import InputParameter, Result, Ruckig, Trajectory

from jaxspline import slew

INF = float("inf")


# ----------------------------------------------------------------------------
# Ruckig reference
# ----------------------------------------------------------------------------


def ruckig_duration(angle, rate, accel, jerk):
    """Rest-to-rest 1-DoF time-optimal duration from Ruckig (jerk = inf: 2nd order)."""
    inp = InputParameter(1)
    inp.current_position = [0.0]
    inp.target_position = [float(angle)]
    inp.max_velocity = [float(rate)]
    inp.max_acceleration = [float(accel)]
    inp.max_jerk = [float(jerk)]
    traj = Trajectory(1)
    res = Ruckig(1).calculate(inp, traj)
    assert res == Result.Working, res
    return traj.duration


def _random_cases(n, seed, with_jerk):
    rng = np.random.default_rng(seed)
    rate = 10 ** rng.uniform(-2.5, 0, n)
    accel = 10 ** rng.uniform(-3, 0, n)
    jerk = 10 ** rng.uniform(-3, 1, n) if with_jerk else np.full(n, INF)
    # angle scaled around the regime switches so that every sub-case occurs
    scale = rate * rate / accel
    angle = scale * 10 ** rng.uniform(-3, 1.5, n)
    return angle, rate, accel, jerk


def _scurve_case(angle, rate, accel, jerk):
    """Sub-case label computed with numpy (for coverage counts)."""
    a2j = accel**2 / jerk
    phi1 = 2 * accel**3 / jerk**2
    v_unb = np.where(
        angle <= phi1,
        np.cbrt(angle**2 * jerk / 4),
        0.5 * (-a2j + np.sqrt(a2j**2 + 4 * accel * angle)),
    )
    cruise = v_unb > rate
    const_acc = np.where(cruise, rate > a2j, angle > phi1)
    return cruise.astype(int) * 2 + const_acc.astype(int)


def test_bang_coast_bang_matches_ruckig_second_order():
    angle, rate, accel, jerk = _random_cases(1200, 1, with_jerk=False)
    ref = np.array([ruckig_duration(*c) for c in zip(angle, rate, accel, jerk, strict=True)])
    got = np.asarray(slew.bang_coast_bang_time(angle, rate, accel))
    coast = angle > rate**2 / accel
    assert coast.sum() > 100 and (~coast).sum() > 100
    rel = np.abs(got - ref) / ref
    print(f"bang-coast-bang vs ruckig: n={len(ref)} max rel dev={rel.max():.3e}")
    assert rel.max() < 1e-9


def test_scurve_matches_ruckig_third_order():
    angle, rate, accel, jerk = _random_cases(1500, 2, with_jerk=True)
    ref = np.array([ruckig_duration(*c) for c in zip(angle, rate, accel, jerk, strict=True)])
    got = np.asarray(slew.scurve_time(angle, rate, accel, jerk))
    case = _scurve_case(angle, rate, accel, jerk)
    counts = np.bincount(case, minlength=4)
    assert (counts > 50).all(), counts  # all four sub-cases covered
    rel = np.abs(got - ref) / ref
    print(f"S-curve vs ruckig: n={len(ref)} cases={counts.tolist()} max rel dev={rel.max():.3e}")
    assert rel.max() < 1e-8


def test_scurve_jerk_inf_is_bang_coast_bang_and_rate_inf():
    angle, rate, accel, _ = _random_cases(200, 3, with_jerk=False)
    a = slew.scurve_time(angle, rate, accel, INF)
    b = slew.bang_coast_bang_time(angle, rate, accel)
    np.testing.assert_allclose(a, b, rtol=1e-13)
    np.testing.assert_allclose(
        slew.bang_coast_bang_time(angle, INF, accel), 2 * np.sqrt(angle / accel), rtol=1e-13
    )
    np.testing.assert_allclose(
        slew.bang_bang_time(angle, accel), 2 * np.sqrt(angle / accel), rtol=1e-13
    )


def test_rigid_hand_cases():
    # bang-coast-bang, paper's omega/eps: omega^2/eps = 0.35 rad
    assert float(slew.bang_coast_bang_time(0.35, 0.035, 0.0035)) == pytest.approx(20.0)
    assert float(slew.bang_coast_bang_time(0.7, 0.035, 0.0035)) == pytest.approx(30.0)
    assert float(slew.bang_coast_bang_time(0.0875, 0.035, 0.0035)) == pytest.approx(10.0)
    # S-curve: jerk-only phase: 4 segments of t1, phi = 2 J t1^3; phi=2, J=1 -> t1=1, t=4
    assert float(slew.scurve_time(2.0, 10.0, 10.0, 1.0)) == pytest.approx(4.0)
    # S-curve with cruise and const accel: V=1, A=1, J=1 -> t_a = 2, t = 2 + phi
    assert float(slew.scurve_time(5.0, 1.0, 1.0, 1.0)) == pytest.approx(7.0)
    for f, args in [
        (slew.bang_bang_time, (0.0, 1.0)),
        (slew.bang_coast_bang_time, (0.0, 1.0, 1.0)),
        (slew.scurve_time, (0.0, 1.0, 1.0, 1.0)),
    ]:
        assert float(f(*args)) == 0.0


KERNELS = [
    (slew.bang_bang_time_kernel, slew.bang_bang_time, 2),
    (slew.bang_coast_bang_time_kernel, slew.bang_coast_bang_time, 3),
    (slew.scurve_time_kernel, slew.scurve_time, 4),
]


@pytest.mark.parametrize("kernel,public,nargs", KERNELS)
def test_rigid_scalar_jit_vmap_agree(kernel, public, nargs):
    angle, rate, accel, jerk = _random_cases(64, 4, with_jerk=True)
    cols = [angle, rate, accel, jerk]
    args = [angle, accel] if nargs == 2 else cols[:nargs]
    batched = np.asarray(public(*args))
    scalar = np.array([float(kernel(*[a[i] for a in args])) for i in range(8)])
    jitted = np.array([float(jax.jit(kernel)(*[a[i] for a in args])) for i in range(8)])
    vm = np.asarray(jax.jit(jax.vmap(kernel))(*[jnp.asarray(a) for a in args]))
    np.testing.assert_allclose(scalar, batched[:8], rtol=1e-13)
    np.testing.assert_allclose(jitted, batched[:8], rtol=1e-13)
    np.testing.assert_allclose(vm, batched, rtol=1e-13)


@pytest.mark.parametrize("kernel,public,nargs", KERNELS)
def test_rigid_float32(kernel, public, nargs):
    angle, rate, accel, jerk = _random_cases(64, 5, with_jerk=True)
    cols = [angle, rate, accel, jerk]
    args = [angle, accel] if nargs == 2 else cols[:nargs]
    out32 = public(*[np.float32(a) for a in args])
    assert out32.dtype == jnp.float32
    np.testing.assert_allclose(out32, public(*args), rtol=2e-5)


def test_rigid_gradients_finite_at_boundaries():
    w, e, j = 0.035, 0.0035, 0.001
    a2j = e * e / j
    points = [
        (0.0, w, e, j),
        (0.0, w, e, INF),
        (0.0, INF, e, INF),
        (w * w / e, w, e, INF),  # bang-coast-bang switch
        (2 * e**3 / j**2, 10.0, e, j),  # S-curve: const-accel phase appears
        (w * (2 * math.sqrt(w / j)), w, e, 1.0),  # S-curve: cruise appears
        (1.0, a2j, e, j),  # rate exactly A^2/J
    ]
    g = jax.grad(slew.scurve_time_kernel, argnums=(0, 1, 2, 3))
    for p in points:
        for x in g(*p):
            assert np.isfinite(x), (p, g(*p))
    gb = jax.grad(slew.bang_coast_bang_time_kernel, argnums=(0, 1, 2))
    for p in points:
        assert all(np.isfinite(x) for x in gb(*p[:3])), p
    assert np.isfinite(jax.grad(slew.bang_bang_time_kernel)(0.0, e))


def test_rigid_check_grads_away_from_kinks():
    from jax.test_util import check_grads

    for p in [(0.3, 0.035, 0.0035, 0.01), (2.0, 0.035, 0.0035, 0.01), (0.01, 0.035, 0.0035, 1e-3)]:
        check_grads(slew.scurve_time_kernel, p, order=1, modes=["rev"], eps=1e-7, rtol=1e-5)
        check_grads(
            slew.bang_coast_bang_time_kernel, p[:3], order=1, modes=["rev"], eps=1e-7, rtol=1e-5
        )


@pytest.mark.parametrize(
    "call,name",
    [
        (lambda: slew.bang_bang_time(-1.0, 1.0), "angle"),
        (lambda: slew.bang_bang_time(1.0, 0.0), "accel"),
        (lambda: slew.bang_coast_bang_time(1.0, -1.0, 1.0), "rate"),
        (lambda: slew.bang_coast_bang_time(float("nan"), 1.0, 1.0), "angle"),
        (lambda: slew.scurve_time(1.0, 1.0, 1.0, 0.0), "jerk"),
        (lambda: slew.scurve_time(1.0, 1.0, INF, 1.0), "accel"),
        (lambda: slew.scurve_time(np.ones(3), np.ones(2), 1.0, 1.0), "angle"),
    ],
)
def test_rigid_value_errors(call, name):
    with pytest.raises(ValueError, match=name):
        call()
