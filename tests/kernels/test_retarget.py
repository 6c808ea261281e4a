"""Tests for jaxspline.kernels.retarget against independent references.

References: hand-computed cases; bisection over d with a feasibility check by dense
numerical quadrature of the envelope curves; dense integration of the produced
controls; reach_durations.min_peak_accel; scipy DOP853 integration of the rigid-body model written
with a direction-cosine matrix, absolute body rate and Euler's equations (no Euler-angle
kinematics), with attitudes converted by scipy's Rotation; optax direct optimisation
(slow).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from _ref_retarget import min_peak_direct
from jax.test_util import check_grads
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from jaxspline import kernels as R  # retarget and retarget_channel
from jaxspline.kernels import reach_durations

DEG = np.pi / 180.0
AS = R.ARCSEC
INF = float("inf")


# ------------------------------------------------------------------ linear channel


HAND = [
    # a1, b1, a2, b2, T, rate, d*, sign, t1, t2
    (0.0, 0.0, 1.0, 0.0, 10.0, INF, 0.04, 1.0, 5.0, 5.0),  # rest to rest: 4D/T²
    (0.0, 0.0, -1.0, 0.0, 10.0, INF, 0.04, -1.0, 5.0, 5.0),
    (0.0, 0.0, 1.0, 0.2, 10.0, INF, 0.02, 1.0, 10.0, 10.0),  # D = 0: pure rate change |Δ|/T
    (1.0, 0.1, 2.0, 0.1, 10.0, INF, 0.0, 0.0, 5.0, 5.0),  # coasting: no control
    (0.0, 0.0, 1.0, 0.0, 10.0, 0.125, 0.0625, 1.0, 2.0, 8.0),  # bang-coast-bang b²/(bT−D)
    (0.0, 0.0, 1.0, 0.0, 10.0, 0.2, 0.04, 1.0, 5.0, 5.0),  # rate bound inactive
    (0.0, 0.0, 3.0, 0.0, 10.0, 0.25, INF, 0.0, 5.0, 5.0),  # bT <= D: impossible
]


@pytest.mark.parametrize("case", HAND)
def test_channel_hand_cases(case):
    a1, b1, a2, b2, T, rate, d, s, t1, t2 = case
    c = R.min_peak_channel(a1, b1, a2, b2, T, rate)
    np.testing.assert_allclose(float(c.peak), d, rtol=1e-12, atol=1e-15)
    if d > 0:
        assert float(c.sign) == s
    np.testing.assert_allclose([float(c.t1), float(c.t2)], [t1, t2], rtol=1e-12, atol=1e-12)


def _random_cases(n, seed, bounded):
    rng = np.random.default_rng(seed)
    T = rng.uniform(5.0, 60.0, n)
    rate = rng.uniform(0.02, 0.06, n) if bounded else np.full(n, INF)
    vmax = np.where(np.isfinite(rate), rate, 0.05)
    b1 = rng.uniform(-0.9, 0.9, n) * vmax
    b2 = rng.uniform(-0.9, 0.9, n) * vmax
    a1 = rng.uniform(-0.5, 0.5, n)
    a2 = a1 + rng.uniform(-0.9, 0.9, n) * vmax * T
    return a1, b1, a2, b2, T, rate


def _feasible_dense(a1, b1, a2, b2, T, rate, d, n=20001):
    """Feasible iff |b1−b2| <= dT and ∫F_lo <= a2 − a1 <= ∫F_hi (dense trapezoid)."""
    if abs(b1 - b2) > d * T:
        return False
    t = np.linspace(0.0, T, n)
    fhi = np.minimum(np.minimum(b1 + d * t, b2 + d * (T - t)), rate)
    flo = np.maximum(np.maximum(b1 - d * t, b2 - d * (T - t)), -rate)
    return np.trapezoid(flo, t) <= a2 - a1 <= np.trapezoid(fhi, t)


def _bisect_peak(a1, b1, a2, b2, T, rate):
    hi = 1.0
    while not _feasible_dense(a1, b1, a2, b2, T, rate, hi):
        hi *= 2.0
        if hi > 1e3:
            return INF
    lo = 0.0
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _feasible_dense(a1, b1, a2, b2, T, rate, mid) else (mid, hi)
    return hi


@pytest.mark.parametrize("bounded", [False, True])
def test_channel_vs_bisection(bounded):
    args = _random_cases(25, 1 if bounded else 2, bounded)
    c = R.min_peak_channel(*args)
    for i in range(25):
        ref = _bisect_peak(*(float(x[i]) for x in args))
        got = float(c.peak[i])
        if np.isinf(ref):
            assert np.isinf(got)
        else:  # quadrature error of the dense check ~ d·T²/n²
            np.testing.assert_allclose(got, ref, rtol=2e-6, atol=1e-12)


@pytest.mark.parametrize("bounded", [False, True])
def test_channel_control_is_admissible(bounded):
    """Dense integration of the produced control hits (a2, b2), respects |f'| <= rate."""
    a1, b1, a2, b2, T, rate = _random_cases(25, 3, bounded)
    c = R.min_peak_channel(a1, b1, a2, b2, T, rate)
    for i in range(25):
        if not np.isfinite(float(c.peak[i])):
            continue
        t = np.linspace(0.0, T[i], 200001)
        ci = R.ChannelControl(*(float(x[i]) for x in c))
        u = np.asarray(R.channel_control_eval(ci, jnp.asarray(t)))
        assert np.max(np.abs(u)) <= ci.peak * (1 + 1e-12)
        rate_t = b1[i] + np.concatenate([[0.0], np.cumsum(0.5 * (u[1:] + u[:-1]) * np.diff(t))])
        ang_t = a1[i] + np.concatenate(
            [[0.0], np.cumsum(0.5 * (rate_t[1:] + rate_t[:-1]) * np.diff(t))]
        )
        tol = ci.peak * (t[1] - t[0]) * 2
        assert abs(rate_t[-1] - b2[i]) <= tol + 1e-12
        assert abs(ang_t[-1] - a2[i]) <= tol * T[i] + 1e-12
        assert np.max(np.abs(rate_t)) <= rate[i] + tol + 1e-12
        # closed-form state agrees with the quadrature along the way
        ang_c, rate_c = R.channel_state(ci, a1[i], b1[i], jnp.asarray(t[::1000]))
        np.testing.assert_allclose(np.asarray(rate_c), rate_t[::1000], atol=tol + 1e-12)
        np.testing.assert_allclose(np.asarray(ang_c), ang_t[::1000], atol=tol * T[i] + 1e-12)


def test_channel_consistent_with_reach():
    """Bounded: same d* as reach_durations.min_peak_accel; unbounded: reach at huge rate."""
    args = _random_cases(200, 4, True)
    c = R.min_peak_channel(*args)
    ref = reach_durations.min_peak_accel(*args)
    np.testing.assert_allclose(np.asarray(c.peak), np.asarray(ref), rtol=1e-12)
    a1, b1, a2, b2, T, _ = _random_cases(200, 5, False)
    c = R.min_peak_channel(a1, b1, a2, b2, T)
    ref = reach_durations.min_peak_accel(a1, b1, a2, b2, T, 1e4)
    np.testing.assert_allclose(np.asarray(c.peak), np.asarray(ref), rtol=1e-10)


def test_channel_scalar_jit_vmap_float32():
    args = [np.asarray(x) for x in _random_cases(16, 6, True)]
    batched = R.min_peak_channel(*args)
    k = jax.jit(R.min_peak_channel_kernel)
    vm = jax.jit(jax.vmap(R.min_peak_channel_kernel))(*(jnp.asarray(x) for x in args))
    for i in range(16):
        one = R.min_peak_channel(*(x[i] for x in args))
        j = k(*(jnp.asarray(x[i]) for x in args))
        for f in range(4):
            np.testing.assert_allclose(float(one[f]), float(batched[f][i]), rtol=1e-14)
            np.testing.assert_allclose(float(j[f]), float(batched[f][i]), rtol=1e-14)
            np.testing.assert_allclose(float(vm[f][i]), float(batched[f][i]), rtol=1e-14)
    c32 = R.min_peak_channel(*(x.astype(np.float32) for x in args))
    assert c32.peak.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(c32.peak), np.asarray(batched.peak), rtol=2e-5)


@jax.jit
@jax.grad
def _grad_sum(x):
    c = R.min_peak_channel_kernel(*x)
    return c.peak + c.t1 + c.t2


@pytest.mark.parametrize(
    "point",
    [
        (0.0, 0.0, 0.0, 0.0, 10.0, INF),  # d* = 0 (D = Δ = 0)
        (0.0, 0.0, 1.0, 0.2, 10.0, INF),  # D = 0 kink
        (0.0, 0.1, 1.0, 0.1, 10.0, INF),  # Δ = 0
        (0.0, 0.0, 1.0, 0.0, 10.0, 0.2),  # rate bound, apex exactly at the bound
        (0.0, 0.0, 1.0, 0.0, 10.0, 0.125),  # three-link
    ],
)
def test_channel_gradients_finite(point):
    g = _grad_sum(jnp.asarray(point))
    assert np.all(np.isfinite(np.asarray(g)[:5]))


def test_channel_check_grads_smooth():
    def f(a2, b2, T):
        return R.min_peak_channel_kernel(0.1, 0.01, a2, b2, T, INF).peak

    check_grads(jax.jit(f), (0.7, -0.02, 20.0), order=1, modes=["fwd", "rev"])


def test_min_peak_linear_vector():
    a1, b1, a2, b2, T, _ = _random_cases(12, 7, False)
    sh = (4, 3)
    gain = np.array([0.5, 1.0, 2.0])
    peak, ctrl = R.min_peak_linear(
        a1.reshape(sh), b1.reshape(sh), a2.reshape(sh), b2.reshape(sh), T[:4], gain=gain
    )
    assert peak.shape == (4,) and ctrl.peak.shape == sh
    for i in range(4):
        ref = max(
            _bisect_peak(a1[3 * i + k], b1[3 * i + k], a2[3 * i + k], b2[3 * i + k], T[i], INF)
            / gain[k]
            for k in range(3)
        )
        np.testing.assert_allclose(float(peak[i]), ref, rtol=2e-6)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(T=0.0), "T"),
        (dict(T=-1.0), "T"),
        (dict(rate=0.0), "rate"),
        (dict(a1=np.nan), "a1"),
        (dict(b2=np.inf), "b2"),
    ],
)
def test_channel_value_errors(kw, match):
    args = dict(a1=0.0, b1=0.0, a2=1.0, b2=0.0, T=10.0, rate=INF)
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        R.min_peak_channel(**args)


def test_linear_gain_error():
    with pytest.raises(ValueError, match="gain"):
        R.min_peak_linear(np.zeros(3), np.zeros(3), np.ones(3), np.zeros(3), 10.0, gain=[1, 0, 1])


# ----------------------------------------------------------------------- nonlinear

MODEL = R.AttitudeModel(
    inertia=np.array([3000.0, 4000.0, 3500.0]),
    gain=np.array([1.0, 0.8, 1.2]),
    omega0=-0.00113,
    gravity_gradient=1.0,
)


def _dcm(sigma):
    """Orbital -> body DCM for pitch(z), roll(x), yaw(y), via scipy (intrinsic ZXY)."""
    return Rotation.from_euler("ZXY", sigma).as_matrix().T


def _angles(C):
    return Rotation.from_matrix(C.T).as_euler("ZXY")


def _reference_end(model, sa, wa, ctrl, T):
    """Independent model: DCM + absolute rate + Euler's equations, scipy DOP853."""
    J = np.diag(np.asarray(model.inertia, float))
    Jinv = np.linalg.inv(J)
    gain = np.asarray(model.gain, float)
    w0 = float(model.omega0)
    ez, ey = np.array([0.0, 0.0, 1.0]), np.array([0.0, 1.0, 0.0])
    C0 = _dcm(sa)
    y0 = np.concatenate([C0.ravel(), np.asarray(wa) + w0 * C0 @ ez])
    peak, sign, t1, t2 = (np.asarray(x, float) for x in ctrl)
    # channel (pitch, roll, yaw) acts on body axis (z, x, y)
    body_of_channel = [2, 0, 1]

    def accel(t):
        a_ch = sign * peak * ((t < t1).astype(float) - (t >= t2).astype(float))
        a = np.zeros(3)
        a[body_of_channel] = a_ch
        return a  # = B u

    def rhs(t, y, a):
        C = y[:9].reshape(3, 3)
        w = y[9:]
        wrel = w - w0 * C @ ez
        Cdot = -np.cross(wrel[:, None], C, axis=0)
        r = C @ ey
        mgg = float(model.gravity_gradient) * 3 * w0**2 * np.cross(r, J @ r)
        wdot = a + Jinv @ (mgg - np.cross(w, J @ w))
        return np.concatenate([Cdot.ravel(), wdot])

    pts = np.unique(np.clip(np.concatenate([[0.0], t1, t2, [T]]), 0.0, T))
    y = y0
    for lo, hi in zip(pts[:-1], pts[1:], strict=True):
        if hi - lo <= 0:
            continue
        a = accel(0.5 * (lo + hi))
        assert np.all(np.abs(a / gain) <= peak.max() / np.abs(gain).min() + 1e-15)
        sol = solve_ivp(rhs, (lo, hi), y, args=(a,), method="DOP853", rtol=1e-12, atol=1e-14)
        y = sol.y[:, -1]
    C = y[:9].reshape(3, 3)
    U, _, Vt = np.linalg.svd(C)
    C = U @ Vt
    return _angles(C), y[9:] - w0 * C @ ez


def test_euler_rates_matrix_matches_dcm():
    """eq. 7 vs dC/dt = −[ω̃×]C by central differences of the scipy DCM."""
    rng = np.random.default_rng(8)
    for _ in range(10):
        s = rng.uniform([-0.8, -1.2, -1.0], [0.8, 1.2, 1.0])
        w = rng.normal(size=3) * 0.05
        sd = np.asarray(R.euler_rates_matrix(jnp.asarray(s))) @ w
        h = 1e-6
        Cdot = (_dcm(s + h * sd) - _dcm(s - h * sd)) / (2 * h)
        C = _dcm(s)
        np.testing.assert_allclose(Cdot, -np.cross(w[:, None], C, axis=0), atol=1e-9)
        np.testing.assert_allclose(np.asarray(R.orbital_to_body(jnp.asarray(s))), C, atol=1e-14)


def _nl_cases(n, seed):
    rng = np.random.default_rng(seed)
    sa = rng.uniform([-30, -40, -10], [30, 40, 10], (n, 3)) * DEG
    sb = rng.uniform([-30, -40, -10], [30, 40, 10], (n, 3)) * DEG
    wa = rng.uniform(-0.3, 0.3, (n, 3)) * DEG
    wb = rng.uniform(-0.3, 0.3, (n, 3)) * DEG
    T = rng.uniform(30.0, 60.0, n)
    return sa, wa, sb, wb, T


def test_simulate_matches_reference():
    sa, wa, sb, wb, T = _nl_cases(3, 9)
    for i in range(3):
        peak, ctrl = R.min_peak_linear(sa[i], np.zeros(3), sb[i], np.zeros(3), T[i])
        s_ref, w_ref = _reference_end(MODEL, sa[i], wa[i], ctrl, T[i])
        # RK4 aligned with the switches: 4th order (measured 0.016″ at 16 steps, 6e-5″ at 64)
        for steps, tol in ((16, 0.05 * AS), (64, 3e-4 * AS)):
            s, w = R.simulate(MODEL, sa[i], wa[i], ctrl, T[i], steps=steps)
            np.testing.assert_allclose(np.asarray(s), s_ref, atol=tol)
            np.testing.assert_allclose(np.asarray(w), w_ref, atol=tol)


@pytest.fixture(scope="module")
def six():
    cases = _nl_cases(6, 10)
    return cases, R.min_peak_retarget(MODEL, *cases)


def test_retarget_hits_targets_and_matches_loop(six):
    (sa, wa, sb, wb, T), res = six
    assert bool(np.all(res.converged))
    assert np.all(np.asarray(res.iterations) <= 20)
    for i in range(6):
        ctrl = R.ChannelControl(*(np.asarray(c[i]) for c in res.control))
        s_ref, w_ref = _reference_end(MODEL, sa[i], wa[i], ctrl, T[i])
        assert np.max(np.abs(s_ref - sb[i])) < AS
        assert np.max(np.abs(w_ref - wb[i])) < AS
        # peak = max |u| of the body control
        t = np.linspace(0, T[i], 4001)
        u = np.asarray(R.body_control(MODEL, ctrl, jnp.asarray(t)))
        np.testing.assert_allclose(np.max(np.abs(u)), float(res.peak[i]), rtol=1e-12)
    one = R.min_peak_retarget(MODEL, sa[2], wa[2], sb[2], wb[2], T[2])
    np.testing.assert_allclose(float(one.peak), float(res.peak[2]), rtol=1e-12)
    assert int(one.iterations) == int(res.iterations[2])


def test_retarget_linear_limit_and_broyden():
    """No orbit, no coupling (small angles, zero rates... ): iteration 0 is already exact;
    Broyden and Picard agree on a large maneuver."""
    model0 = R.AttitudeModel(inertia=np.ones(3), omega0=0.0, gravity_gradient=0.0)
    sa = np.array([0.0, 0.0, 0.0])
    sb = np.array([0.3, 0.0, 0.0])  # pure pitch: N' = I along the way, no coupling
    res = R.min_peak_retarget(model0, sa, np.zeros(3), sb, np.zeros(3), 20.0)
    assert int(res.iterations) == 0
    np.testing.assert_allclose(float(res.peak), 4 * 0.3 / 400, rtol=1e-12)
    sa, wa, sb, wb, T = _nl_cases(1, 11)
    p = R.min_peak_retarget(MODEL, sa[0], wa[0], sb[0], wb[0], T[0], method="picard")
    n = R.min_peak_retarget(MODEL, sa[0], wa[0], sb[0], wb[0], T[0], method="broyden")
    assert bool(p.converged) and bool(n.converged)
    assert int(n.iterations) <= int(p.iterations)
    np.testing.assert_allclose(float(n.peak), float(p.peak), rtol=1e-4)


def test_retarget_float32(six):
    cases, r64 = six
    f = [np.asarray(x, np.float32) for x in cases]
    r32 = R.min_peak_retarget(MODEL, *f, tol=2 * AS, rate_tol=2 * AS)
    assert bool(np.all(r32.converged))
    assert r32.peak.dtype == jnp.float32
    np.testing.assert_allclose(np.asarray(r32.peak), np.asarray(r64.peak), rtol=1e-3)


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(T=0.0), "T"),
        (dict(sigma_a=np.zeros(2)), "sigma_a"),
        (dict(omega_b=np.array([0.0, np.nan, 0.0])), "omega_b"),
        (dict(sigma_b=np.array([0.0, 1.6, 0.0])), "sigma_b"),
        (dict(method="bfgs"), "method"),
        (dict(model=MODEL._replace(gain=np.array([1.0, 0.0, 1.0]))), "gain"),
        (dict(model=MODEL._replace(inertia=np.array([1.0, -1.0, 1.0]))), "inertia"),
        (dict(model=(1, 2, 3)), "model"),
        (dict(tol=0.0), "tol"),
    ],
)
def test_retarget_value_errors(kw, match):
    args = dict(
        model=MODEL,
        sigma_a=np.zeros(3),
        omega_a=np.zeros(3),
        sigma_b=np.full(3, 0.1),
        omega_b=np.zeros(3),
        T=30.0,
    )
    args.update(kw)
    with pytest.raises(ValueError, match=match):
        R.min_peak_retarget(**args)


@pytest.mark.slow
def test_direct_optimisation_not_much_better():
    """optax direct min-peak (u = s·sin v, L-BFGS + bisection) vs successive approximations."""
    sa, wa, sb, wb, T = _nl_cases(1, 13)
    res = R.min_peak_retarget(MODEL, sa[0], wa[0], sb[0], wb[0], T[0])
    d = min_peak_direct(
        MODEL,
        sa[0],
        wa[0],
        sb[0],
        wb[0],
        T[0],
        peak_hi=2 * float(res.peak),
        n_intervals=40,
        bisections=10,
    )
    assert d.feasible
    assert d.angle_residual <= AS and d.rate_residual <= AS
    ratio = float(res.peak) / d.peak
    assert 0.97 <= ratio <= 1.25
