"""The roll-only maneuver model and the roll-only pointing law.

References, each independent of the model: hand-computed cases; the regional checker's
own slew formula (:func:`jaxspline.aeossp.check_frames.bang_coast_bang_time`, the test
oracle, which must not call the model); brute force (the shortest time whose largest
reachable rest-to-rest angle covers the change, by bisection); a scipy ODE integration of
the profile's acceleration; the checker's numpy look direction
(:func:`jaxspline.regional.check_geometry.look_direction`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.test_util import check_grads
from scipy.integrate import solve_ivp

from jaxspline.aeossp.check_frames import bang_coast_bang_time as checker_slew
from jaxspline.base import ManeuverModel, model_names
from jaxspline.geometry.pointing import roll_look_direction, roll_pointing
from jaxspline.regional.check_geometry import look_direction
from jaxspline.screen import (
    RollLimits,
    RollOnly,
    roll_min_gap,
    roll_need,
    roll_profile,
    roll_profile_kernel,
    roll_slew_time,
    roll_transition,
    roll_transition_kernel,
)


def brute_slew(d, w, a):
    """Shortest rest-to-rest time over angle d: bisection on the largest reachable angle."""

    def reach(t):  # accelerate to v = min(w, a t / 2), coast, brake
        v = min(w, a * t / 2.0)
        return v * (t - v / a)

    lo, hi = 0.0, 2.0 * (d / w + w / a) + 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if reach(mid) < d else (lo, mid)
    return hi


def random_cases(seed, n):
    rng = np.random.default_rng(seed)
    w = rng.uniform(0.2, 4.0, n)
    a = rng.uniform(0.05, 3.0, n)
    # angles on both sides of the switch w^2/a, down to tiny ones
    d = np.where(rng.uniform(size=n) < 0.5, rng.uniform(0, 1, n) * w * w / a, rng.uniform(0, 90, n))
    return d, w, a


@pytest.mark.parametrize(
    "d,w,a,t",
    [
        (0.0, 2.0, 1.0, 0.0),
        (1.0, 2.0, 1.0, 2.0),  # triangle: 2 sqrt(1/1)
        (4.0, 2.0, 1.0, 4.0),  # the switch: both formulas give 4
        (10.0, 2.0, 1.0, 7.0),  # trapezoid: 10/2 + 2/1
        (-10.0, 2.0, 1.0, 7.0),  # the magnitude counts
        (9.0, np.inf, 1.0, 6.0),  # no rate bound: bang-bang
    ],
)
def test_hand_computed(d, w, a, t):
    lim = RollLimits(w, a, 1.5)
    assert float(roll_slew_time(d, w, a)) == pytest.approx(t, rel=1e-14)
    assert float(roll_need(d, lim)) == pytest.approx(t + 1.5, rel=1e-14)
    tr = roll_transition(d, t + 1.5, lim)
    assert bool(tr.feasible) and float(tr.margin) == pytest.approx(0.0, abs=1e-12)
    assert not bool(roll_transition(d, t + 1.5 - 1e-6, lim).feasible)


def test_equals_checker_formula_and_brute_force():
    d, w, a = random_cases(0, 400)
    host = roll_slew_time(d, w, a)
    ref = [checker_slew(*x) for x in zip(d, w, a, strict=True)]
    np.testing.assert_allclose(host, ref, rtol=1e-12, atol=1e-12)
    brute = [brute_slew(*x) for x in zip(d[:100], w[:100], a[:100], strict=True)]
    np.testing.assert_allclose(host[:100], brute, rtol=1e-10, atol=1e-10)


def test_host_equals_kernel_bit_for_bit():
    d, w, a = random_cases(1, 300)
    d[:3] = [0.0, w[1] * w[1] / a[1], 1e-300]
    gap = np.random.default_rng(2).uniform(0, 200, d.size)
    lim = RollLimits(w, a, 2.25)
    tr = roll_transition(d, gap, lim)
    np.testing.assert_array_equal(np.asarray(tr.need), roll_need(d, lim))
    np.testing.assert_array_equal(np.asarray(tr.margin), gap - roll_need(d, lim))
    np.testing.assert_array_equal(np.asarray(tr.feasible), gap >= roll_need(d, lim))


def test_feasibility_as_value_against_brute_force():
    d, w, a = random_cases(3, 200)
    brute = np.array([brute_slew(*x) for x in zip(d, w, a, strict=True)]) + 1.0
    gap = brute + np.random.default_rng(4).choice([-1.0, 1.0], d.size) * 1e-6
    tr = roll_transition(d, gap, RollLimits(w, a, 1.0))
    np.testing.assert_array_equal(np.asarray(tr.feasible), gap > brute)
    bad = roll_transition_kernel(5.0, jnp.nan, 1.0, 1.0, 0.0)  # a NaN gap: a value
    assert not bool(bad.feasible)


def test_scalar_jit_vmap_agree():
    d, w, a = random_cases(5, 64)
    gap = np.linspace(0.0, 60.0, d.size)
    jit = jax.jit(roll_transition_kernel)
    vm = jax.jit(jax.vmap(roll_transition_kernel, (0, 0, 0, 0, None)))(d, gap, w, a, 0.5)
    for i in (0, 17, 63):
        one = roll_transition_kernel(d[i], gap[i], w[i], a[i], 0.5)
        assert float(jit(d[i], gap[i], w[i], a[i], 0.5).margin) == float(one.margin)
        assert float(vm.margin[i]) == float(one.margin)


def simulate_time_optimal(d, w, a, steps=20000):
    """Explicit simulation of the time-optimal feedback law: brake once the braking
    distance reaches what is left, else speed up to w (then coast); returns the time at
    rest, the angle reached and the step."""
    dt = 2.0 * (d / w + w / a) / steps
    x = v = t = 0.0
    while t < 1e6:
        u = -a if d - x <= v * v / (2.0 * a) else (a if v < w else 0.0)
        if u < 0 and v + u * dt <= 0.0:  # comes to rest inside this step
            return t + v / a, x + v * v / (2.0 * a), dt
        v_new = min(v + u * dt, w)
        x, v, t = x + 0.5 * (v + v_new) * dt, v_new, t + dt
    raise AssertionError("no arrival")


def test_time_against_explicit_simulation():
    for d, w, a in [(30.0, 1.8, 0.7), (2.0, 1.8, 0.7), (0.4, 0.5, 2.0)]:
        t, x, dt = simulate_time_optimal(d, w, a)
        assert x == pytest.approx(d, abs=1e-3 * d)
        assert float(roll_slew_time(d, w, a)) == pytest.approx(t, abs=5 * dt)


def test_profile_against_ode_integration():
    for d, w, a in [(30.0, 1.8, 0.7), (2.0, 1.8, 0.7), (-12.0, 2.5, 1.0)]:
        total = float(roll_slew_time(d, w, a))
        lim = RollLimits(w, a, 0.0)
        fine = np.linspace(0.0, total, 20001)
        acc_fine = np.asarray(roll_profile(d, lim, fine)[0])

        def rhs(t, y, fine=fine, acc_fine=acc_fine):  # piecewise constant acceleration
            k = min(np.searchsorted(fine, t, side="right") - 1, fine.size - 2)
            return [y[1], acc_fine[k]]

        t = np.linspace(0.0, total, 41)
        sol = solve_ivp(rhs, (0.0, total), [0.0, 0.0], t_eval=t, max_step=total / 1000)
        acc, rate, ang = (np.asarray(x) for x in roll_profile(d, lim, t))
        np.testing.assert_allclose(ang, sol.y[0], atol=2e-3 * abs(d))
        np.testing.assert_allclose(rate, sol.y[1], atol=2e-3 * w)
        assert np.all(np.abs(rate) <= w * (1 + 1e-12)) and np.all(np.abs(acc) <= a)
        end = roll_profile(d, lim, np.array([total, total + 5.0, -1.0]))
        np.testing.assert_allclose(np.asarray(end[2]), [d, d, 0.0], atol=1e-12)
        np.testing.assert_allclose(np.asarray(end[1]), 0.0, atol=1e-12)


def test_gradients_finite_at_kinks_and_correct_elsewhere():
    w, a = 2.0, 1.0

    def both(x, r, t):  # the transition margin and the profile angle at t
        return (
            roll_transition_kernel(x, 20.0, r, a, 1.0).margin + roll_profile_kernel(x, r, a, t)[2]
        )

    grad = jax.jit(jax.grad(both, argnums=(0, 1)))
    for d in [0.0, w * w / a]:  # the kinks
        assert np.all(np.isfinite(grad(d, w, 1.0)))
    fast = jax.jit(both)
    for d in [1.0, 9.0]:  # triangle and trapezoid
        check_grads(lambda x, r, d=d: fast(x, r, 0.3 * d), (d, w), 1, modes=["rev"])


def test_float32_follows_input():
    tr = roll_transition(jnp.float32(3.0), jnp.float32(9.0), RollLimits(np.float32(2.0), 1.0, 1.0))
    assert tr.margin.dtype == jnp.float32
    assert float(tr.need) == pytest.approx(2.0 * np.sqrt(3.0) + 1.0, rel=1e-6)


def test_min_gap_is_the_smallest_fixed_point():
    lim, drift = RollLimits(1.2, 0.4, 2.05), 0.08
    d = np.array([0.0, 0.3, 4.0, 12.0, 40.0])
    g = roll_min_gap(d, lim, drift, 8)
    assert np.all(g <= roll_need(d + drift * g, lim) + 1e-9)  # from below
    assert np.all(g + 0.01 >= roll_need(d + drift * (g + 0.01), lim))  # and a slack is safe
    np.testing.assert_array_equal(roll_min_gap(d, lim, 0.0, 3), roll_need(d, lim))


@pytest.mark.parametrize(
    "kw,field",
    [
        (dict(limits=RollLimits(0.0, 1.0, 0.0)), "limits.rate"),
        (dict(limits=RollLimits(1.0, -1.0, 0.0)), "limits.accel"),
        (dict(limits=RollLimits(1.0, 1.0, -2.0)), "limits.settle"),
        (dict(delta=np.nan), "delta"),
        (dict(gap=np.nan), "gap"),
    ],
)
def test_bad_inputs_name_the_field(kw, field):
    args = dict(delta=1.0, gap=5.0, limits=RollLimits(1.0, 1.0, 0.0)) | kw
    with pytest.raises(ValueError, match=field):
        roll_transition(**args)


def test_roll_only_model_protocol():
    class Sat:
        class limits:
            rate, accel = np.radians(1.8), np.radians(0.7)

        settle = 1.5

    m = RollOnly()
    assert isinstance(m, ManeuverModel) and m.name in model_names()
    assert m.los_frame == "earth_fixed" and not m.tracks_points and not m.first_from_nadir
    np.testing.assert_array_equal(m.first_requirements(Sat, None, np.arange(3), None), 0.0)
    theta = np.radians([0.0, 1.0, 30.0])
    np.testing.assert_array_equal(m.slew_time(Sat, theta), roll_need(theta, m.limits(Sat)) + 0.0)


def test_pointing_law_against_checker_geometry():
    rng = np.random.default_rng(6)
    pos = rng.normal(size=(50, 3))
    pos *= 6.9e6 / np.linalg.norm(pos, axis=1, keepdims=True)
    vel = np.cross(pos, rng.normal(size=(50, 3)))
    vel *= 7.5e3 / np.linalg.norm(vel, axis=1, keepdims=True)
    roll = rng.uniform(-45, 45, 50)
    unit = np.asarray(roll_pointing(pos, vel, roll))
    np.testing.assert_allclose(unit, look_direction(pos, vel, roll), atol=1e-14)
    d = np.asarray(jax.vmap(roll_look_direction)(pos, vel, roll))
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0 / np.cos(np.radians(roll)))
    # two rolls at one sample are |r2 - r1| apart: the roll is the only turn
    other = np.asarray(roll_pointing(pos, vel, roll[::-1]))
    ang = np.degrees(np.arccos(np.clip(np.sum(unit * other, axis=1), -1, 1)))
    np.testing.assert_allclose(ang, np.abs(roll - roll[::-1]), atol=1e-6)
    with pytest.raises(ValueError, match="roll_deg"):
        roll_pointing(pos, vel, 90.0)
