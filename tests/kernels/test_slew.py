"""Tests for jaxspline.kernels.slew: rigid models vs Ruckig, profiles A-D vs the paper and
numerical integration."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from ruckig import InputParameter, Result, Ruckig, Trajectory

from jaxspline.kernels import slew

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
    scalar = np.array([float(kernel(*[a[i] for a in args])) for i in range(3)])
    kj = jax.jit(kernel)
    jitted = np.array([float(kj(*[a[i] for a in args])) for i in range(8)])
    vm = np.asarray(jax.jit(jax.vmap(kernel))(*[jnp.asarray(a) for a in args]))
    np.testing.assert_allclose(scalar, batched[:3], rtol=1e-13)
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
    g = jax.jit(jax.grad(slew.scurve_time_kernel, argnums=(0, 1, 2, 3)))
    for p in points:
        for x in g(*p):
            assert np.isfinite(x), (p, g(*p))
    gb = jax.jit(jax.grad(slew.bang_coast_bang_time_kernel, argnums=(0, 1, 2)))
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


# ----------------------------------------------------------------------------
# profiles A-D: the paper's numbers (SPEC section 2 table)
# ----------------------------------------------------------------------------

W, E = 0.035, 0.0035  # paper's omega [rad/s], eps [rad/s^2]: a = phi/E, b = W/E = 10 s


def _prof(phi, kind="auto", tau=None, w=W, e=E):
    return {k: float(v) for k, v in slew.slew_profile(phi, w, e, tau, kind)._asdict().items()}


def _r(x, nd):
    return round(x, nd)


def test_spec_ex1_phi_0p7():
    # tau = 10, T = 0, T0 = 10, T_d = 40 (phi = 2 omega^2/eps: C and D(tau=b) coincide)
    p = _prof(0.7)
    assert p["kind"] in (slew.KIND_CODES["C"], slew.KIND_CODES["D"])
    assert (p["tau"], p["T"], p["T0"], p["duration"]) == pytest.approx((10, 0, 10, 40), abs=1e-9)
    assert p["T1"] == pytest.approx(0.0, abs=1e-9)


def test_spec_ex2_phi_0p55():
    # paper uses a = 157 (phi = 0.5495): tau = 4.84, T = 5.16, T0 = 15.16, T_d = 34.84 (exact)
    p = _prof(157 * E)
    assert p["kind"] == slew.KIND_CODES["C"]
    assert (p["tau"], p["T"], p["T0"], p["duration"]) == pytest.approx(
        (4.84, 5.16, 15.16, 34.84), abs=1e-9
    )
    # with phi = 0.55 exactly (a = 157.14): 4.857, 5.143, 15.143, 34.857 (2 decimals: 4.86 ...)
    q = _prof(0.55)
    assert [_r(q[k], 2) for k in ("tau", "T", "T0", "duration")] == [4.86, 5.14, 15.14, 34.86]


def test_spec_ex3_phi_0p408():
    # paper a = 116.67 = 7/6 b^2 (C with tau = 0 = B): tau = 0, T = 10, T0 = 20, T_d = 30
    p = _prof(7 / 6 * W * W / E, kind="C")
    assert (p["tau"], p["T"], p["T0"], p["duration"]) == pytest.approx((0, 10, 20, 30), abs=1e-9)
    p = _prof(116.67 * E)  # just above the boundary: auto gives C
    assert p["kind"] == slew.KIND_CODES["C"]
    assert [_r(p[k], 2) for k in ("tau", "T", "T0", "duration")] == [0.0, 10.0, 20.0, 30.0]
    # phi = 0.408 exactly is 0.08 % below 7/6 omega^2/eps: auto gives A there (documented)
    assert _prof(0.408)["kind"] == slew.KIND_CODES["A"]


def test_spec_ex4_phi_0p07():
    a = _prof(0.07, "A")
    assert _r(a["tau"], 2) == 3.16 and _r(a["T0"], 2) == 3.16 and a["T"] == 0.0
    assert math.floor(a["duration"] * 10) / 10 == 12.6  # 12.649: paper truncates to 12.6
    assert _prof(0.07)["kind"] == slew.KIND_CODES["A"]
    b = _prof(0.07, "B")
    assert _r(b["T"], 1) == 4.1 and b["tau"] == 0.0
    # the paper computes T0 = 2 * 4.1 = 8.2 and T_d = 3 * 4.1 = 12.3 from the rounded T;
    # exact values are T0 = 8.281, T_d = sqrt(54 a / 7) = 12.421
    assert 2 * _r(b["T"], 1) == pytest.approx(8.2) and 3 * _r(b["T"], 1) == pytest.approx(12.3)
    assert b["duration"] == pytest.approx(math.sqrt(54 * 20 / 7), rel=1e-12)


def test_spec_ex5_phi_0p007():
    a = _prof(0.007, "A")
    assert (a["tau"], a["T"], a["T0"], a["duration"]) == pytest.approx((1, 0, 1, 4), abs=1e-9)
    b = _prof(0.007, "B")
    assert [_r(b[k], 2) for k in ("T", "T0", "duration")] == [1.31, 2.62, 3.93]
    assert a["duration"] / b["duration"] == pytest.approx(math.sqrt(28 / 27), rel=1e-12)


def test_spec_profile_d():
    # phi = 0.7, tau = 1: T = 9, T1 = 7.5, T0 = 19, T_d = 38.5
    p = _prof(0.7, "D", tau=1.0)
    assert (p["T"], p["T1"], p["T0"], p["duration"]) == pytest.approx((9, 7.5, 19, 38.5), abs=1e-9)
    assert _prof(0.7, tau=1.0) == p  # auto picks D
    # D exists from 5/6 tau omega + 7/6 omega^2/eps = 0.4375 rad = 25.07 deg ("more than 25 deg")
    thr = 5 / 6 * 1.0 * W + 7 / 6 * W * W / E
    assert math.degrees(thr) == pytest.approx(25.07, abs=0.01)
    assert _prof(thr * (1 + 1e-9), "D", tau=1.0)["duration"] < INF
    assert _prof(thr * (1 - 1e-6), "D", tau=1.0)["duration"] == INF
    assert _prof(thr * (1 - 1e-6), tau=1.0)["kind"] == slew.KIND_CODES["C"]
    # 4 % faster than Ex.1 and the last jerk discontinuity moves from 10 s to 19 s before the end
    assert 1 - 38.5 / 40 == pytest.approx(0.0375)


# ----------------------------------------------------------------------------
# profiles: independent checks by numerical integration
# ----------------------------------------------------------------------------


def _random_profiles(n, seed):
    rng = np.random.default_rng(seed)
    w = 10 ** rng.uniform(-2, -0.5, n)
    e = 10 ** rng.uniform(-3, -1, n)
    b = w / e
    phi = w * w / e * 10 ** rng.uniform(-2, 1, n)
    phi[: n // 4] = w[: n // 4] ** 2 / e[: n // 4] * rng.uniform(7 / 6, 2, n // 4)  # C range
    tau = b * rng.uniform(0, 1, n)
    return phi, w, e, tau


@pytest.mark.parametrize("kind", ["auto", "A", "B", "C", "D"])
def test_profile_integration(kind):
    from scipy.integrate import cumulative_trapezoid

    phi, w, e, tau = _random_profiles(16, 10 + len(kind) + ord(kind[0]))
    prof = slew.slew_profile(phi, w, e, tau, kind)
    dur = np.asarray(prof.duration)
    ok = np.isfinite(dur)
    if kind in ("auto", "A", "B"):
        assert ok.all()
    assert ok.sum() >= 5
    n = 20001
    for i in np.where(ok)[0]:
        p_i = slew.SlewProfile(*[np.asarray(f)[i] for f in prof])
        t = np.linspace(0, dur[i], n)
        acc, rate, ang = (np.asarray(x) for x in slew.profile_state(p_i, e[i], t))
        r_num = cumulative_trapezoid(acc, t, initial=0.0)
        a_num = cumulative_trapezoid(r_num, t, initial=0.0)
        sc_r, sc_a = w[i], phi[i]
        # trapezoid error: O(dt^2) on ramps, plus eps*dt at each acceleration step (B)
        step_err = 2 * e[i] * (t[1] - t[0]) if float(p_i.tau) == 0 else 0.0
        assert np.max(np.abs(r_num - rate)) < 1e-6 * sc_r + step_err
        assert np.max(np.abs(a_num - ang)) < 1e-6 * sc_a + step_err * dur[i]
        assert ang[-1] == pytest.approx(phi[i], rel=1e-10)  # final angle = phi
        assert abs(rate[-1]) < 1e-10 * sc_r  # final rate = 0
        assert np.all(np.abs(rate) <= w[i] * (1 + 1e-10))
        assert np.all(np.abs(acc) <= e[i] * (1 + 1e-10))
        assert np.all(rate >= -1e-10 * sc_r)  # no reversal
        jump = np.max(np.abs(np.diff(acc)))
        if kind != "B":  # continuous acceleration: jumps ~ eps dt / tau only
            assert jump < 1e-2 * e[i] or float(p_i.tau) < 1e-3 * dur[i], (kind, float(p_i.tau))
        # after the end: holds
        a2, r2, g2 = (float(x) for x in slew.profile_state(p_i, e[i], dur[i] + 5.0))
        assert a2 == 0.0 and abs(r2) < 1e-10 * sc_r and g2 == pytest.approx(phi[i], rel=1e-10)


def test_auto_kind_regions_and_durations():
    b = W / E
    a = np.linspace(0.0, 4 * b * b, 2001)
    for tau in (b, 1.0, 0.0):
        prof = slew.slew_profile(a * E, W, E, tau)
        kind = np.asarray(prof.kind)
        thr_d = 5 / 6 * tau * b + 7 / 6 * b * b
        exp = np.where(a <= 7 / 6 * b * b, 0, np.where(a >= thr_d, 3, 2))
        inner = (np.abs(a - 7 / 6 * b * b) > 1e-6) & (np.abs(a - thr_d) > 1e-6)
        assert (kind[inner] == exp[inner]).all()
        # auto is the fastest of the existing C / D above 7/6 b^2
        dc = np.asarray(slew.slew_profile_time(a * E, W, E, tau, "C"))
        dd = np.asarray(slew.slew_profile_time(a * E, W, E, tau, "D"))
        d = np.asarray(prof.duration)
        above = a > 7 / 6 * b * b
        assert np.all(d[above] <= np.minimum(dc, dd)[above] * (1 + 1e-12))
        assert np.isfinite(d).all()
        # durations continuous at 2 b^2 and at the D threshold; the paper's rule jumps
        # by (sqrt(28/3) - 3) b (2 %) at 7/6 b^2 (A -> C = B)
        for x, jump in [(2 * b * b, 0.0), (thr_d, 0.0), (7 / 6 * b * b, (28 / 3) ** 0.5 - 3)]:
            lo, hi = (
                float(slew.slew_profile_time(x * E * f, W, E, tau)) for f in (1 - 1e-9, 1 + 1e-9)
            )
            if x == thr_d and tau == 0.0:
                jump = (28 / 3) ** 0.5 - 3  # D(tau=0) starts at 7/6 b^2 as well
            assert lo - hi == pytest.approx(jump * b, abs=1e-6), (x, tau)
    # A and B extend by a coast at omega beyond their ranges
    assert _prof(1.0, "A")["duration"] == pytest.approx(_prof(1.0, "D", tau=W / E)["duration"])
    assert _prof(1.0, "B")["duration"] == pytest.approx(_prof(1.0, "D", tau=0.0)["duration"])
    # paper's formulas T_d^A = sqrt(8a), T_d^B = sqrt(54 a / 7)
    assert _prof(0.2, "A")["duration"] == pytest.approx(math.sqrt(8 * 0.2 / E), rel=1e-13)
    assert _prof(0.2, "B")["duration"] == pytest.approx(math.sqrt(54 * 0.2 / E / 7), rel=1e-13)


def test_profile_scalar_jit_vmap_and_float32():
    phi, w, e, tau = _random_profiles(32, 7)
    ref = slew.slew_profile(phi, w, e, tau)
    k = slew.slew_profile_kernel
    vm = jax.jit(jax.vmap(k))(*(jnp.asarray(x) for x in (phi, w, e, tau)))
    for f_ref, f_vm in zip(ref, vm, strict=True):
        np.testing.assert_allclose(f_vm, f_ref, rtol=1e-13)
    kj = jax.jit(k)
    for i in range(2):
        sc = k(phi[i], w[i], e[i], tau[i])
        jt = kj(phi[i], w[i], e[i], tau[i])
        for f_ref, f_s, f_j in zip(ref, sc, jt, strict=True):
            assert float(f_s) == pytest.approx(float(f_ref[i]), rel=1e-13)
            assert float(f_j) == pytest.approx(float(f_ref[i]), rel=1e-13)
    p32 = slew.slew_profile(*(np.float32(x) for x in (phi, w, e, tau)))
    assert p32.duration.dtype == jnp.float32 and p32.kind.dtype == jnp.int32
    np.testing.assert_allclose(p32.duration, ref.duration, rtol=2e-5)
    t = np.linspace(0, 1, 5, dtype=np.float32) * p32.duration[0]
    s32 = slew.profile_state(slew.SlewProfile(*(f[0] for f in p32)), np.float32(e[0]), t)
    assert all(x.dtype == jnp.float32 for x in s32)


def test_profile_gradients_finite_at_boundaries():
    b = W / E

    def dur(phi, w, e, tau):
        return slew.slew_profile_kernel(phi, w, e, tau)[-1]

    def ang_at(phi, w, e, tau, t):
        p = slew.slew_profile_kernel(phi, w, e, tau)
        return slew.profile_state_kernel(*p[1:5], e, t)[2]

    g = jax.jit(jax.vmap(jax.grad(dur, argnums=(0, 1, 2, 3))))
    ga = jax.jit(jax.vmap(jax.grad(ang_at, argnums=(0, 1, 2, 3, 4))))
    pts = []
    for tau in (b, 1.0, 0.0):
        for phi in (0.0, 7 / 6 * b * b * E, 2 * b * b * E, (5 / 6 * tau * b + 7 / 6 * b * b) * E):
            for t in (0.0, 1.0, tau, 30.0):
                pts.append((phi, W, E, tau, t))
    cols = [jnp.asarray(c) for c in zip(*pts, strict=True)]
    for x in g(*cols[:4]) + ga(*cols):
        assert np.isfinite(np.asarray(x)).all()
    # d T_d / d phi of profile A = sqrt(8/eps) / (2 sqrt(phi)) (check_grads away from kinks)
    from jax.test_util import check_grads

    dur = jax.jit(dur)
    check_grads(dur, (0.1, W, E, 1.0), order=1, modes=["rev"], eps=1e-7, rtol=1e-5)
    check_grads(dur, (0.5, W, E, 1.0), order=1, modes=["rev"], eps=1e-7, rtol=1e-5)
    check_grads(dur, (0.9, W, E, 1.0), order=1, modes=["rev"], eps=1e-7, rtol=1e-5)


@pytest.mark.parametrize(
    "call,name",
    [
        (lambda: slew.slew_profile(0.1, W, E, kind="E"), "kind"),
        (lambda: slew.slew_profile(-0.1, W, E), "angle"),
        (lambda: slew.slew_profile(0.1, 0.0, E), "rate"),
        (lambda: slew.slew_profile(0.1, W, -E), "accel"),
        (lambda: slew.slew_profile(0.1, W, E, tau=-1.0), "tau"),
        (lambda: slew.slew_profile(0.1, W, E, tau=11.0), "tau"),
        (lambda: slew.profile_state(slew.slew_profile(0.1, W, E), E, np.nan), "t"),
    ],
)
def test_profile_value_errors(call, name):
    with pytest.raises(ValueError, match=name):
        call()


@pytest.mark.slow
def test_make_slew_figures(tmp_path):
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "scripts" / "slew_figures.py"
    spec = importlib.util.spec_from_file_location("slew_figures", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = mod.make_slew_figures(tmp_path)
    assert len(out) == 3 and all(p.exists() and p.stat().st_size > 10_000 for p in out)
