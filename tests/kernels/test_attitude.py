"""Tests of jaxspline.kernels.attitude against scipy Rotation and numerical integration."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from jaxspline.kernels import attitude as A

RNG = np.random.default_rng(20261121)


def _rots(n=64, seed=0):
    r = Rotation.random(n, random_state=seed)
    # include exact half-turns about each axis and near-identity rotations (Shepperd branches)
    extra = Rotation.from_rotvec(
        np.array([[np.pi, 0, 0], [0, np.pi, 0], [0, 0, np.pi], [1e-9, 0, 0], [0, 0, 0]])
    )
    return Rotation.concatenate([r, extra])


def _q(r):  # scipy scalar-last -> our scalar-first
    return np.roll(r.as_quat(), 1, axis=-1)


def _same_attitude(q1, q2):
    return np.minimum(np.abs(q1 - q2).max(-1), np.abs(q1 + q2).max(-1))


# ----------------------------------------------------------------------------- conversions
def test_dcm_matches_scipy():
    r = _rots()
    np.testing.assert_allclose(A.quat_to_dcm(_q(r)), r.as_matrix(), atol=1e-14)
    v = RNG.normal(size=(len(r), 3))
    np.testing.assert_allclose(A.quat_rotate(_q(r), v), r.apply(v), atol=1e-14)


def test_dcm_to_quat_matches_scipy():
    r = _rots()
    q = np.asarray(A.dcm_to_quat(r.as_matrix()))
    assert (q[:, 0] >= 0).all()
    assert _same_attitude(q, _q(r)).max() < 1e-14


def test_mrp_matches_scipy_and_shadow():
    r = _rots()
    s = np.asarray(A.quat_to_mrp(_q(r)))
    assert (np.linalg.norm(s, axis=-1) <= 1 + 1e-15).all()
    # scipy's as_mrp also returns the |σ| <= 1 set; half-turns are ambiguous (±e)
    m = np.linalg.norm(s, axis=-1) < 1 - 1e-9
    np.testing.assert_allclose(s[m], r.as_mrp()[m], atol=1e-14)
    np.testing.assert_allclose(A.mrp_to_dcm(s), r.as_matrix(), atol=1e-14)
    np.testing.assert_allclose(A.dcm_to_mrp(r.as_matrix())[m], s[m], atol=1e-14)
    # the negated quaternion is the same attitude: same canonical MRP
    np.testing.assert_allclose(A.quat_to_mrp(-_q(r))[m], s[m], atol=1e-14)
    sh = np.array(A.mrp_shadow(s[:-1]))  # skip σ = 0
    np.testing.assert_allclose(Rotation.from_mrp(sh).as_matrix(), r.as_matrix()[:-1], atol=1e-12)
    assert _same_attitude(np.asarray(A.mrp_to_quat(s)), _q(r)).max() < 1e-14


def test_quat_multiply_is_composition():
    r1, r2 = _rots(20, 1), _rots(20, 2)
    q = np.asarray(A.quat_multiply(_q(r1), _q(r2)))
    assert _same_attitude(q, _q(r1 * r2)).max() < 1e-14
    np.testing.assert_allclose(
        A.quat_multiply(_q(r1), A.quat_conjugate(_q(r1)))[..., 0], 1.0, atol=1e-15
    )


def test_normalize_zero_is_identity():
    np.testing.assert_array_equal(A.quat_normalize(np.zeros(4)), [1.0, 0, 0, 0])
    np.testing.assert_allclose(A.quat_normalize([2.0, 0, 0, 0]), [1.0, 0, 0, 0])


# ----------------------------------------------------------------------------- angle
def test_attitude_angle_scipy_and_tiny():
    r1, r2 = _rots(30, 3), _rots(30, 4)
    ref = (r1.inv() * r2).magnitude()
    np.testing.assert_allclose(A.attitude_angle(_q(r1), _q(r2)), ref, atol=1e-14)
    for ang in [1e-12, 1e-9, 1e-6, 1e-3]:
        axis = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
        rr = r1[0] * Rotation.from_rotvec(ang * axis)
        got = float(A.attitude_angle(_q(r1[0]), -_q(rr)))
        assert abs(got - ang) <= 1e-15 + 1e-10 * ang, (ang, got)
    # arccos-free: angle of a 1e-12 rad rotation is resolved (arccos would give 0 or 1e-8)


def test_attitude_angle_gradient_finite_at_zero():
    q = jnp.asarray(_q(_rots(1, 5))[0])
    grad = jax.jit(jax.grad(A._angle, argnums=1))
    assert np.isfinite(grad(q, q)).all()
    assert np.isfinite(grad(q, -q)).all()


def test_gradients_finite_at_branch_points():
    # shadow switch at w = 0, Shepperd selection at ties, identity
    # one compiled function for all three Jacobians (compile time dominates this test)
    @jax.jit
    def jacs(q, s):
        return (
            jax.jacobian(A._q2mrp)(q),
            jax.jacobian(A.dcm_to_quat_kernel)(A.quat_to_dcm_kernel(q)),
            jax.jacobian(A._mrp_shadow)(s),
        )

    for q in [jnp.array([0.0, 1.0, 0.0, 0.0]), jnp.array([0.5, 0.5, 0.5, 0.5]), jnp.eye(4)[0]]:
        jq, jr, js = jacs(q, jnp.zeros(3))
        assert np.isfinite(jq).all()
        assert np.isfinite(jr).all()
        assert np.isfinite(js).all()


# ----------------------------------------------------------------------------- kinematics
def _omega_t(t):
    return np.array([0.05 * np.sin(0.3 * t), -0.03 + 0.01 * t, 0.04 * np.cos(0.2 * t)])


def _quat_ode(t, q):
    # independent numpy Hamilton product: q' = 1/2 q ∘ [0, ω]
    w = _omega_t(t)
    qw, qv = q[0], q[1:]
    return 0.5 * np.concatenate([[-qv @ w], qw * w + np.cross(qv, w)])


def test_quat_rate_constant_omega_matches_scipy_body_rotation():
    # ω constant in body axes: Λ(t) = Λ0 ∘ exp(ω t), i.e. scipy R0 * from_rotvec(ω t)
    r0 = _rots(1, 6)[0]
    w = np.array([0.2, -0.1, 0.3])
    sol = solve_ivp(
        lambda t, q: np.asarray(A.quat_rate(q, w)), (0, 10), _q(r0), rtol=1e-12, atol=1e-13
    )
    ref = _q(r0 * Rotation.from_rotvec(w * 10.0))
    assert _same_attitude(sol.y[:, -1], ref) < 1e-9


def test_mrp_kinematics_vs_quaternion_integration():
    r0 = Rotation.from_rotvec([0.4, -1.1, 0.7])
    tq = solve_ivp(_quat_ode, (0, 40), _q(r0), rtol=1e-12, atol=1e-13, dense_output=True)
    s0 = np.asarray(A.quat_to_mrp(_q(r0)))
    ts = solve_ivp(
        lambda t, s: np.asarray(A.mrp_rate(s, _omega_t(t))),
        (0, 40),
        s0,
        rtol=1e-12,
        atol=1e-13,
        dense_output=True,
    )
    for t in np.linspace(0, 40, 9):
        qs = np.asarray(A.mrp_to_quat(ts.sol(t)))
        ang = float(A.attitude_angle(qs, tq.sol(t)))
        assert ang < 1e-9, (t, ang)
    # the flipped sign of the cross term must fail (the check can fail)
    s2 = solve_ivp(
        lambda t, s: (
            0.25
            * ((1 - s @ s) * _omega_t(t) - 2 * np.cross(s, _omega_t(t)) + 2 * s * (s @ _omega_t(t)))
        ),
        (0, 40),
        s0,
        rtol=1e-10,
        atol=1e-12,
    )
    assert float(A.attitude_angle(A.mrp_to_quat(s2.y[:, -1]), tq.sol(40.0))) > 1e-3


def test_omega_from_mrp_rate_inverts():
    s = RNG.normal(size=(50, 3)) * 0.6
    w = RNG.normal(size=(50, 3))
    np.testing.assert_allclose(A.omega_from_mrp_rate(s, A.mrp_rate(s, w)), w, atol=1e-13)


def _sigma_path(t):
    return jnp.stack(
        [0.1 + 0.03 * t - 0.002 * t**2, -0.2 + 0.05 * jnp.sin(t), 0.3 * jnp.cos(0.5 * t)]
    )


def test_accel_and_jerk_vs_finite_differences():
    # ω(t) from the exact σ(t) path, differentiated numerically (central differences)
    def omega_at(t):
        return A.omega_from_mrp_rate(_sigma_path(t), jax.jacfwd(_sigma_path)(t))

    t0, h = 1.3, 1e-3
    w = [np.asarray(omega_at(t0 + k * h)) for k in (-2, -1, 0, 1, 2)]
    eps_fd = (w[0] - 8 * w[1] + 8 * w[3] - w[4]) / (12 * h)
    jerk_fd = (-w[0] + 16 * w[1] - 30 * w[2] + 16 * w[3] - w[4]) / (12 * h * h)
    s, d1, d2, d3 = jax.jit(
        lambda t: (
            _sigma_path(t),
            jax.jacfwd(_sigma_path)(t),
            jax.jacfwd(jax.jacfwd(_sigma_path))(t),
            jax.jacfwd(jax.jacfwd(jax.jacfwd(_sigma_path)))(t),
        )
    )(t0)
    np.testing.assert_allclose(A.angular_accel_from_mrp(s, d1, d2), eps_fd, atol=1e-10)
    w_, e_, j_ = A.omega_from_mrp_derivs(s, d1, d2, d3)
    np.testing.assert_allclose(w_, w[2], atol=1e-14)
    np.testing.assert_allclose(e_, eps_fd, atol=1e-10)
    np.testing.assert_allclose(j_, jerk_fd, atol=1e-6)
    # and the inverse map returns the path derivatives
    r1, r2, r3 = A.mrp_derivs_from_omega(s, w_, e_, j_)
    np.testing.assert_allclose(r1, d1, atol=1e-14)
    np.testing.assert_allclose(r2, d2, atol=1e-14)
    np.testing.assert_allclose(r3, d3, atol=1e-13)


# ----------------------------------------------------------------------------- API properties
def test_scalar_jit_vmap_agree():
    s = RNG.normal(size=(8, 3)) * 0.5
    w = RNG.normal(size=(8, 3))
    batched = np.asarray(A.mrp_rate(s, w))
    single = np.stack([np.asarray(A.mrp_rate(s[i], w[i])) for i in range(8)])
    jv = np.asarray(jax.jit(jax.vmap(A._mrp_rate))(s, w))
    np.testing.assert_allclose(batched, single, atol=1e-15)
    np.testing.assert_allclose(jv, single, atol=1e-15)
    # broadcasting: one σ against many ω
    np.testing.assert_allclose(A.mrp_rate(s[0], w), [A.mrp_rate(s[0], x) for x in w], atol=1e-15)


def test_float32_follows_dtype():
    r = Rotation.random(10, random_state=7)
    q32 = _q(r).astype(np.float32)
    out = A.quat_to_mrp(q32)
    assert out.dtype == jnp.float32
    np.testing.assert_allclose(out, r.as_mrp(), atol=2e-6)
    assert A.quat_to_dcm(q32).dtype == jnp.float32
    assert A.attitude_angle(q32, q32).dtype == jnp.float32
    s = np.asarray(out)
    w = np.ones((10, 3), np.float32) * 0.1
    assert A.omega_from_mrp_derivs(s, s, s, s)[2].dtype == jnp.float32
    np.testing.assert_allclose(A.omega_from_mrp_rate(s, A.mrp_rate(s, w)), w, atol=1e-6)


def test_value_errors():
    with pytest.raises(ValueError, match="q"):
        A.quat_to_mrp([1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="omega"):
        A.mrp_rate([0.0, 0, 0], [np.nan, 0, 0])
    with pytest.raises(ValueError, match="R"):
        A.dcm_to_quat(np.eye(4)[:3])
    with pytest.raises(ValueError, match="sigma"):
        A.mrp_to_quat("abc")
