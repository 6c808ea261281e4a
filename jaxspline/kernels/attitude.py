"""Attitude representations and kinematics: quaternions, MRPs, rotation matrices.

Conventions (used everywhere in jaxspline):

* A quaternion is a length-4 array ``[w, x, y, z]`` (scalar FIRST), multiplied
  with the Hamilton product ``p ∘ q``. (scipy's ``Rotation`` is scalar LAST.)
* An attitude quaternion Λ maps body-frame vectors to the reference (inertial
  or orbital) frame: ``v_ref = Λ ∘ v_body ∘ Λ̃``; ``quat_to_dcm(Λ)`` is the
  matrix of the same map, so its columns are the body axes in the reference
  frame. Composition: ``Λ = Λ_a ∘ Λ_b`` applies Λ_b first (a body-fixed
  rotation on top of Λ_a).
* ω is the angular velocity of the body, in BODY axes; the quaternion
  kinematics is Λ' = ½ Λ ∘ ω (seed vector-spline-guidance-laws, eq. 1).
* Modified Rodrigues parameters σ = e tan(Φ/4) = λ / (1 + λ0) (e Euler axis,
  Φ rotation angle); |σ| <= 1 is the canonical set (Φ <= 180°), its shadow
  σˢ = -σ/|σ|² describes the same attitude. MRP kinematics (seed eq. 2):
  σ' = ¼[(1 - σ·σ)ω + 2σ×ω + 2σ(σ·ω)] = ¼ B(σ) ω (checked against the
  quaternion equation in tests/kernels/test_attitude.py).

All functions are kernels on one attitude (small fixed arrays), batched with
``jnp.vectorize`` over leading axes; they follow the input dtype and are
branchless with finite values and gradients everywhere (safe norms, double-where).
Units: radians, seconds.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxspline.kernels.batch import batched
from jaxspline.kernels.safe import safe_norm
from jaxspline.kernels.validate import common_float, finite_vector

__all__ = [
    "quat_multiply",
    "quat_conjugate",
    "quat_normalize",
    "quat_rotate",
    "quat_to_dcm",
    "dcm_to_quat",
    "quat_to_mrp",
    "mrp_to_quat",
    "mrp_to_dcm",
    "dcm_to_mrp",
    "mrp_shadow",
    "attitude_angle",
    "quat_rate",
    "mrp_rate",
    "omega_from_mrp_rate",
    "angular_accel_from_mrp",
    "mrp_derivs_from_omega",
    "omega_from_mrp_derivs",
]


# ----------------------------------------------------------------------------- helpers
def _cross(a, b):
    # last-axis cross product (broadcasts over leading sample axes)
    return jnp.stack(
        [
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ],
        axis=-1,
    )


def _dot(a, b):
    # last-axis dot product, keeping the axis for broadcasting against vectors
    return jnp.sum(a * b, axis=-1, keepdims=True)


# ----------------------------------------------------------------------------- kernels
def _qmul(p, q):
    # Hamilton product on the last axis (leading axes broadcast)
    pw, pv = p[..., :1], p[..., 1:]
    qw, qv = q[..., :1], q[..., 1:]
    w = pw * qw - _dot(pv, qv)
    v = pw * qv + qw * pv + _cross(pv, qv)
    return jnp.concatenate([w, v], axis=-1)


def _qconj(q):
    return q * jnp.array([1.0, -1.0, -1.0, -1.0], dtype=q.dtype)


def _qnormalize(q):
    n = safe_norm(q)[..., None]
    # the zero quaternion has no attitude: return identity instead of NaN
    ident = jnp.zeros_like(q).at[..., 0].set(1.0)
    return jnp.where(n > 0, q / jnp.where(n > 0, n, 1.0), ident)


def _qrotate(q, v):
    # v' = q v q~ = v + 2 w (u x v) + 2 u x (u x v), for unit q = [w, u]
    w, u = q[..., :1], q[..., 1:]
    t = 2.0 * _cross(u, v)
    return v + w * t + _cross(u, t)


def quat_to_dcm_kernel(q):
    """DCM [3, 3] of one unit quaternion ``q`` = (w, x, y, z) (no normalization)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.stack(
        [
            jnp.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)]),
            jnp.stack([2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)]),
            jnp.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z]),
        ]
    )


def dcm_to_quat_kernel(R):
    """Unit quaternion (w, x, y, z) of one DCM ``R`` [3, 3] (Shepperd, branchless)."""
    # Shepperd's method, branchless: the candidate with the largest 4*c^2 >= 1 is
    # selected; the other candidates get a clamped (safe) square-root argument.
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    args = jnp.stack(
        [1.0 + tr, 1.0 + 2 * R[0, 0] - tr, 1.0 + 2 * R[1, 1] - tr, 1.0 + 2 * R[2, 2] - tr]
    )
    k = jnp.argmax(args)
    r = jnp.sqrt(jnp.maximum(args, 1.0))  # = 2|c| for the selected candidate
    d32, d13, d21 = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    s32, s13, s21 = R[2, 1] + R[1, 2], R[0, 2] + R[2, 0], R[1, 0] + R[0, 1]
    c0 = jnp.stack([r[0] * r[0], d32, d13, d21]) / (2 * r[0])
    c1 = jnp.stack([d32, r[1] * r[1], s21, s13]) / (2 * r[1])
    c2 = jnp.stack([d13, s21, r[2] * r[2], s32]) / (2 * r[2])
    c3 = jnp.stack([d21, s13, s32, r[3] * r[3]]) / (2 * r[3])
    q = jnp.where(k == 0, c0, jnp.where(k == 1, c1, jnp.where(k == 2, c2, c3)))
    q = jnp.where(q[0] < 0, -q, q)
    return _qnormalize(q)


def _q2mrp(q):
    q = _qnormalize(q)
    w = q[..., :1]
    s = jnp.where(w < 0, -1.0, 1.0).astype(q.dtype)  # shadow switch: keep |σ| <= 1
    return s * q[..., 1:] / (1.0 + jnp.abs(w))


def _mrp2q(sig):
    # σ [..., 3] -> q [..., 4] (broadcasts over leading sample axes)
    s2 = _dot(sig, sig)
    d = 1.0 + s2
    return jnp.concatenate([(1.0 - s2) / d, 2.0 * sig / d], axis=-1)


def _mrp_shadow(sig):
    s2 = _dot(sig, sig)
    pos = s2 > 0
    # the shadow of σ = 0 is at infinity; we return 0 (the same attitude) instead
    return jnp.where(pos, -sig / jnp.where(pos, s2, 1.0), sig)


def _angle(q1, q2):
    dq = _qmul(_qconj(_qnormalize(q1)), _qnormalize(q2))
    return 2.0 * jnp.arctan2(safe_norm(dq[..., 1:]), jnp.abs(dq[..., 0]))


def _qrate(q, w):
    return 0.5 * _qmul(q, jnp.concatenate([jnp.zeros_like(w[..., :1]), w], axis=-1))


def _mrp_rate(sig, w):
    # σ, ω [..., 3] (leading axes broadcast: used on sample grids inside kernels)
    s2 = _dot(sig, sig)
    return 0.25 * ((1.0 - s2) * w + 2.0 * _cross(sig, w) + 2.0 * sig * _dot(sig, w))


def _omega_from_rate(sig, dsig):
    # B(σ)^-1 = B(σ)^T / (1 + σ·σ)^2
    s2 = _dot(sig, sig)
    bt = (1.0 - s2) * dsig - 2.0 * _cross(sig, dsig) + 2.0 * sig * _dot(sig, dsig)
    return 4.0 * bt / (1.0 + s2) ** 2


def _eps_from_mrp(sig, d1, d2):
    return _omega_derivs(sig, d1, d2, jnp.zeros_like(d2))[1]


def _mrp_derivs(sig, w, e, j):
    """σ', σ'', σ''' from (σ, ω, ε, ε') [..., 3]: Leibniz rule on σ' = ¼B(σ)ω.

    With a = σ·σ, b = σ·ω: σ' = ¼[(1 - a)ω + 2σ×ω + 2σb]; the k-th time
    derivative of each product is Σ_i C(k, i) (i-th factor)(k-i-th factor).
    """
    s = [sig]
    om = [w, e, j]
    binom = ((1,), (1, 1), (1, 2, 1))
    for k in range(3):
        c = binom[k]
        a = [sum(c2 * _dot(s[i], s[m - i]) for i, c2 in enumerate(binom[m])) for m in range(k + 1)]
        b = [sum(c2 * _dot(s[i], om[m - i]) for i, c2 in enumerate(binom[m])) for m in range(k + 1)]
        t1 = om[k] - sum(c[i] * a[i] * om[k - i] for i in range(k + 1))
        t2 = 2.0 * sum(c[i] * _cross(s[i], om[k - i]) for i in range(k + 1))
        t3 = 2.0 * sum(c[i] * s[i] * b[k - i] for i in range(k + 1))
        s.append(0.25 * (t1 + t2 + t3))
    return s[1], s[2], s[3]


def _omega_derivs(sig, d1, d2, d3):
    """ω, ε, ε' from σ and its first three time derivatives [..., 3], closed form.

    With p = Λ(σ) = [2g - 1, 2gσ], g = 1/(1 + σ·σ): ω = 2 vec(p̃∘p'),
    ε = 2 vec(p̃∘p'') (p̃'∘p' = |p'|² is scalar), ε' = 2 vec(p̃'∘p'' + p̃∘p''').
    A small graph (cheap to compile inside sampled kernels).
    """
    u1 = 2.0 * _dot(sig, d1)
    u2 = 2.0 * (_dot(d1, d1) + _dot(sig, d2))
    u3 = 2.0 * (3.0 * _dot(d1, d2) + _dot(sig, d3))
    g0 = 1.0 / (1.0 + _dot(sig, sig))
    g1 = -u1 * g0**2
    g2 = -u2 * g0**2 + 2.0 * u1**2 * g0**3
    g3 = -u3 * g0**2 + 6.0 * u1 * u2 * g0**3 - 6.0 * u1**3 * g0**4
    p0 = jnp.concatenate([2.0 * g0 - 1.0, 2.0 * g0 * sig], axis=-1)
    p1 = 2.0 * jnp.concatenate([g1, g1 * sig + g0 * d1], axis=-1)
    p2 = 2.0 * jnp.concatenate([g2, g2 * sig + 2.0 * g1 * d1 + g0 * d2], axis=-1)
    p3 = 2.0 * jnp.concatenate([g3, g3 * sig + 3.0 * g2 * d1 + 3.0 * g1 * d2 + g0 * d3], axis=-1)
    c0, c1 = _qconj(p0), _qconj(p1)
    w = 2.0 * _qmul(c0, p1)[..., 1:]
    e = 2.0 * _qmul(c0, p2)[..., 1:]
    j = 2.0 * (_qmul(c1, p2) + _qmul(c0, p3))[..., 1:]
    return w, e, j


_qmul_batched = batched(_qmul, "(4),(4)->(4)")
_qconj_batched = batched(_qconj, "(4)->(4)")
_qnorm_batched = batched(_qnormalize, "(4)->(4)")
_qrot_batched = batched(_qrotate, "(4),(3)->(3)")
_q2dcm_batched = batched(lambda q: quat_to_dcm_kernel(_qnormalize(q)), "(4)->(3,3)")
_dcm2q_batched = batched(dcm_to_quat_kernel, "(3,3)->(4)")
_q2mrp_batched = batched(_q2mrp, "(4)->(3)")
_mrp2q_batched = batched(_mrp2q, "(3)->(4)")
_mrp2dcm_batched = batched(lambda s: quat_to_dcm_kernel(_mrp2q(s)), "(3)->(3,3)")
_dcm2mrp_batched = batched(lambda R: _q2mrp(dcm_to_quat_kernel(R)), "(3,3)->(3)")
_shadow_batched = batched(_mrp_shadow, "(3)->(3)")
_angle_batched = batched(_angle, "(4),(4)->()")
_qrate_batched = batched(_qrate, "(4),(3)->(4)")
_mrp_rate_batched = batched(_mrp_rate, "(3),(3)->(3)")
_omega_batched = batched(_omega_from_rate, "(3),(3)->(3)")
_eps_batched = batched(_eps_from_mrp, "(3),(3),(3)->(3)")
_mrp_derivs_batched = batched(_mrp_derivs, "(3),(3),(3),(3)->(3),(3),(3)")
_omega_derivs_batched = batched(_omega_derivs, "(3),(3),(3),(3)->(3),(3),(3)")


# ----------------------------------------------------------------------------- public API
def quat_multiply(p, q):
    """Hamilton product p ∘ q of scalar-first quaternions [w, x, y, z].

    (p∘q)_w = p_w q_w - p_v·q_v, (p∘q)_v = p_w q_v + q_w p_v + p_v × q_v.
    Reference: seed vector-spline-guidance-laws, eq. 1.

    Args:
      p: float [..., 4], left quaternion (scalar first), broadcast against q.
      q: float [..., 4], right quaternion (scalar first).
    Returns:
      float [..., 4], the product p ∘ q.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    p, q = common_float(finite_vector("p", p, 4), finite_vector("q", q, 4))
    return _qmul_batched(p, q)


def quat_conjugate(q):
    """Conjugate [w, -x, -y, -z] of quaternions (the inverse for unit q).

    Args:
      q: float [..., 4], quaternions (scalar first).
    Returns:
      float [..., 4], the conjugates.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _qconj_batched(finite_vector("q", q, 4))


def quat_normalize(q):
    """q / |q|; the zero quaternion maps to identity [1, 0, 0, 0].

    Args:
      q: float [..., 4], quaternions (scalar first).
    Returns:
      float [..., 4], unit quaternions.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _qnorm_batched(finite_vector("q", q, 4))


def quat_rotate(q, v):
    """Rotate body vectors to the reference frame: Λ ∘ v ∘ Λ̃.

    Args:
      q: float [..., 4], unit attitude quaternions (body -> reference), broadcast against v.
      v: float [..., 3], vectors in body axes (any unit).
    Returns:
      float [..., 3], the vectors in the reference frame (unit of v).
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    q, v = common_float(finite_vector("q", q, 4), finite_vector("v", v, 3))
    return _qrot_batched(q, v)


def quat_to_dcm(q):
    """Rotation matrix of attitude quaternions (normalized first).

    R = (w² - |u|²) I + 2 u uᵀ + 2 w [u×]; columns are body axes in the reference
    frame, so ``R @ v_body == quat_rotate(q, v_body)``.

    Args:
      q: float [..., 4], attitude quaternions (scalar first).
    Returns:
      float [..., 3, 3], rotation matrices body -> reference.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _q2dcm_batched(finite_vector("q", q, 4))


def dcm_to_quat(R):
    """Unit quaternion (w >= 0) of rotation matrices.

    Shepperd's method (largest of 4w², 4x², 4y², 4z² selected branchlessly).

    Args:
      R: float [..., 3, 3], rotation matrices body -> reference.
    Returns:
      float [..., 4], unit quaternions (scalar first, w >= 0).
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    R = finite_vector("R", R, 3)
    if R.ndim < 2 or R.shape[-2] != 3:
        raise ValueError(f"R must have shape [..., 3, 3], got {R.shape}")
    return _dcm2q_batched(R)


def quat_to_mrp(q):
    """Modified Rodrigues parameters σ of quaternions, |σ| <= 1.

    σ = λ / (1 + λ0) if λ0 >= 0, else the shadow -λ / (1 - λ0) (same attitude,
    q and -q are the same attitude). σ = e tan(Φ/4) with Φ in [0, π].
    Reference: SPEC §3; seed vector-spline-guidance-laws (σ = λ/(1 + λ0)).

    Args:
      q: float [..., 4], attitude quaternions (scalar first).
    Returns:
      float [..., 3], MRPs σ (dimensionless), |σ| <= 1.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _q2mrp_batched(finite_vector("q", q, 4))


def mrp_to_quat(sigma):
    """Unit quaternion of MRPs: λ0 = (1 - σ²)/(1 + σ²), λ = 2σ/(1 + σ²).

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
    Returns:
      float [..., 4], unit quaternions (scalar first).
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _mrp2q_batched(finite_vector("sigma", sigma, 3))


def mrp_to_dcm(sigma):
    """Rotation matrix (body -> reference) of MRPs.

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
    Returns:
      float [..., 3, 3], rotation matrices body -> reference.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _mrp2dcm_batched(finite_vector("sigma", sigma, 3))


def dcm_to_mrp(R):
    """MRPs (|σ| <= 1) of rotation matrices.

    Args:
      R: float [..., 3, 3], rotation matrices body -> reference.
    Returns:
      float [..., 3], MRPs σ (dimensionless), |σ| <= 1.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    R = finite_vector("R", R, 3)
    if R.ndim < 2 or R.shape[-2] != 3:
        raise ValueError(f"R must have shape [..., 3, 3], got {R.shape}")
    return _dcm2mrp_batched(R)


def mrp_shadow(sigma):
    """Shadow MRP set σˢ = -σ / |σ|² (same attitude); σ = 0 maps to 0.

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
    Returns:
      float [..., 3], the shadow set σˢ.
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    return _shadow_batched(finite_vector("sigma", sigma, 3))


def attitude_angle(q1, q2):
    """Eigen-axis angle between two attitudes.

    δ = q̃1 ∘ q2, angle = 2 atan2(|δ_v|, |δ_w|): exact for tiny angles (no
    arccos), sign-invariant (q ≡ -q), gradient finite (zero) at angle 0.

    Args:
      q1: float [..., 4], attitude quaternions (scalar first), broadcast against q2.
      q2: float [..., 4], attitude quaternions (scalar first).
    Returns:
      float [...], angle [rad] in [0, π].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    q1, q2 = common_float(finite_vector("q1", q1, 4), finite_vector("q2", q2, 4))
    return _angle_batched(q1, q2)


def quat_rate(q, omega):
    """Quaternion derivative Λ' = ½ Λ ∘ [0, ω].

    Reference: seed vector-spline-guidance-laws, eq. 1.

    Args:
      q: float [..., 4], attitude quaternions Λ (scalar first).
      omega: float [..., 3], body angular velocity ω [rad/s].
    Returns:
      float [..., 4], Λ' [1/s].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    q, omega = common_float(finite_vector("q", q, 4), finite_vector("omega", omega, 3))
    return _qrate_batched(q, omega)


def mrp_rate(sigma, omega):
    """MRP derivative σ' = ¼[(1 - σ·σ)ω + 2σ×ω + 2σ(σ·ω)].

    Reference: seed vector-spline-guidance-laws, eq. 2 (sign verified against
    Λ' = ½ Λ∘ω with the Hamilton product).

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
      omega: float [..., 3], body angular velocity ω [rad/s].
    Returns:
      float [..., 3], σ' [1/s].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    sigma, omega = common_float(finite_vector("sigma", sigma, 3), finite_vector("omega", omega, 3))
    return _mrp_rate_batched(sigma, omega)


def omega_from_mrp_rate(sigma, sigma_dot):
    """Body angular velocity from σ and σ': the inverse of ``mrp_rate``.

    ω = 4 [(1 - σ·σ)σ' - 2σ×σ' + 2σ(σ·σ')] / (1 + σ·σ)², using B⁻¹ = Bᵀ/(1 + σ²)².

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
      sigma_dot: float [..., 3], σ' [1/s].
    Returns:
      float [..., 3], body angular velocity ω [rad/s].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    sigma, sigma_dot = common_float(
        finite_vector("sigma", sigma, 3), finite_vector("sigma_dot", sigma_dot, 3)
    )
    return _omega_batched(sigma, sigma_dot)


def angular_accel_from_mrp(sigma, sigma_dot, sigma_ddot):
    """Body angular acceleration ε = dω/dt from σ, σ', σ''.

    ε = dω/dt along the trajectory, ω(σ, σ') of ``omega_from_mrp_rate``; closed
    form via the quaternion p = Λ(σ): ε = 2 vec(p̃∘p'') (see ``omega_from_mrp_derivs``).

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
      sigma_dot: float [..., 3], σ' [1/s].
      sigma_ddot: float [..., 3], σ'' [1/s²].
    Returns:
      float [..., 3], ε [rad/s²].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    a = common_float(
        finite_vector("sigma", sigma, 3),
        finite_vector("sigma_dot", sigma_dot, 3),
        finite_vector("sigma_ddot", sigma_ddot, 3),
    )
    return _eps_batched(*a)


def mrp_derivs_from_omega(sigma, omega, eps, eps_dot=None):
    """(σ', σ'', σ''') from σ, ω, ε and ε'.

    Total time derivatives of σ' = ¼B(σ)ω (seed eq. 2) by the Leibniz rule:
    σ'' = ¼(B ε + Ḃ ω), σ''' = ¼(B ε' + 2Ḃ ε + B̈ ω).

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
      omega: float [..., 3], body angular velocity ω [rad/s].
      eps: float [..., 3], body angular acceleration ε [rad/s²].
      eps_dot: float [..., 3], ε' [rad/s³]; None means 0.
    Returns:
      tuple (σ' [1/s], σ'' [1/s²], σ''' [1/s³]), each float [..., 3].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    sigma = finite_vector("sigma", sigma, 3)
    omega = finite_vector("omega", omega, 3)
    eps = finite_vector("eps", eps, 3)
    eps_dot = jnp.zeros_like(eps) if eps_dot is None else finite_vector("eps_dot", eps_dot, 3)
    return _mrp_derivs_batched(*common_float(sigma, omega, eps, eps_dot))


def omega_from_mrp_derivs(sigma, sigma_dot, sigma_ddot, sigma_dddot):
    """(ω, ε, ε') from σ and its first three time derivatives.

    The inverse of ``mrp_derivs_from_omega``. Closed form through p = Λ(σ) =
    [2g - 1, 2gσ], g = 1/(1 + σ·σ): ω = 2 vec(p̃∘p'), ε = 2 vec(p̃∘p''),
    ε' = 2 vec(p̃'∘p'' + p̃∘p''') (Λ' = ½Λ∘ω differentiated).

    Args:
      sigma: float [..., 3], MRPs σ (dimensionless).
      sigma_dot: float [..., 3], σ' [1/s].
      sigma_ddot: float [..., 3], σ'' [1/s²].
      sigma_dddot: float [..., 3], σ''' [1/s³].
    Returns:
      tuple (ω [rad/s], ε [rad/s²], ε' [rad/s³]), each float [..., 3].
    Raises:
      ValueError: an argument is not finite or its last axis has the wrong length.
    """
    a = common_float(
        finite_vector("sigma", sigma, 3),
        finite_vector("sigma_dot", sigma_dot, 3),
        finite_vector("sigma_ddot", sigma_ddot, 3),
        finite_vector("sigma_dddot", sigma_dddot, 3),
    )
    return _omega_derivs_batched(*a)
