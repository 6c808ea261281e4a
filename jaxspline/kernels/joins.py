"""Degree-7 polynomial joins, the vector spline, and spatial attitude maneuvers.

* ``join7_coeffs``: the unique degree-7 polynomial with prescribed angle, rate,
  acceleration and jerk at both ends of [0, T]. It is the minimum of ∫ w² dt
  for the chain θ' = ω, ω' = u, u' = v, v' = w (seed
  retarget-scan-pattern-optimization, "optimal conjugation", eqs. 23–27): the
  Euler–Lagrange equation is θ⁽⁸⁾ = 0, so w = θ⁽⁴⁾ is cubic (SPEC §3).
* ``spline7_coeffs``: the vector spline of seed vector-spline-guidance-laws —
  σ, σ', σ'' at both ends plus σ(T/3), σ(2T/3) fix the 8 coefficients.
* ``maneuver_plan`` / ``maneuver_eval``: a spatial rotation maneuver between two
  attitude states (Λ, ω, ε, ε') in time T, built as a degree-7 join of modified
  Rodrigues parameters in one MRP chart. Its batched check of |ω| <= ω_max,
  |ε| <= ε_max, |ε'| <= jerk_max on samples is :mod:`jaxspline.kernels.join_check`.

Polynomials are stored with NORMALIZED coefficients: p(t) = Σ_k c_k τ^k with
τ = t / T, coefficient axis last (shape [..., 8]); this keeps the linear
systems constant (their exact inverses are precomputed from rationals) and well
conditioned for any T. d^n p/dt^n = T^-n d^n p/dτ^n.

MRP chart of a maneuver: σ(t) parametrizes the attitude relative to a
reference Λ_ref = normalize(Λ0 + Λ1) (Λ1 sign-aligned with Λ0: the eigen-axis
midpoint), Λ(t) = Λ_ref ∘ Λ(σ(t)). Body ω and ε do not change under this
left-multiplication, and both ends satisfy |σ| <= tan(Φ/8) <= tan(22.5°), far
from the MRP singularity at Φ = 360° and away from the shadow switch at 180°.
"""

from __future__ import annotations

import functools
from fractions import Fraction
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.kernels import attitude as _att
from jaxspline.kernels.batch import batched
from jaxspline.kernels.validate import (
    as_float_array,
    boundary_states,
    check_finite,
    common_float,
    finite_vector,
    positive_duration,
)

__all__ = [
    "join7_coeffs",
    "spline7_coeffs",
    "poly_eval",
    "Maneuver",
    "maneuver_plan",
    "attitude_spline",
    "maneuver_eval",
]


# ----------------------------------------------------------------------------- constants
def _exact_inverse(rows):
    """Inverse of a small rational matrix by Gauss-Jordan on Fractions -> float64 numpy."""
    n = len(rows)
    a = [
        [Fraction(x) for x in r] + [Fraction(int(i == j)) for j in range(n)]
        for i, r in enumerate(rows)
    ]
    for c in range(n):
        p = next(r for r in range(c, n) if a[r][c] != 0)
        a[c], a[p] = a[p], a[c]
        piv = a[c][c]
        a[c] = [x / piv for x in a[c]]
        for r in range(n):
            if r != c and a[r][c] != 0:
                f = a[r][c]
                a[r] = [x - f * y for x, y in zip(a[r], a[c], strict=True)]
    return np.array([[float(x) for x in r[n:]] for r in a])


def _dmono(k, d, tau):
    """d-th derivative of τ^k at τ (Fraction)."""
    if d > k:
        return Fraction(0)
    f = Fraction(1)
    for i in range(d):
        f *= k - i
    return f * Fraction(tau) ** (k - d)


# join: unknown c4..c7 from p, p', p'', p''' at τ = 1
_JOIN_INV = _exact_inverse([[_dmono(k, d, 1) for k in range(4, 8)] for d in range(4)])
# spline: unknown c3..c7 from p(1/3), p(2/3), p(1), p'(1), p''(1)
_SPL_ROWS = [(0, Fraction(1, 3)), (0, Fraction(2, 3)), (0, 1), (1, 1), (2, 1)]
_SPL_INV = _exact_inverse([[_dmono(k, d, t) for k in range(3, 8)] for d, t in _SPL_ROWS])

# the whole join as one constant map: c = HERMITE_MAP @ (p0, p0_τ, p0_ττ, p0_τττ, p1, ..., p1_τττ)
HERMITE_MAP = _exact_inverse(
    [[_dmono(k, d, e) for k in range(8)] for e in (0, 1) for d in range(4)]
)
"""The degree-7 join as one exact 8x8 map from the end derivatives (value and three
derivatives at tau = 0 and 1) to the monomial coefficients."""


# ----------------------------------------------------------------------------- kernels
def _join7(p0, v0, a0, j0, p1, v1, a1, j1, T):
    c0, c1, c2, c3 = p0, T * v0, T * T * a0 / 2.0, T**3 * j0 / 6.0
    rhs = jnp.stack(
        [
            p1 - (c0 + c1 + c2 + c3),
            T * v1 - (c1 + 2.0 * c2 + 3.0 * c3),
            T * T * a1 - (2.0 * c2 + 6.0 * c3),
            T**3 * j1 - 6.0 * c3,
        ],
        axis=-1,
    )
    hi = rhs @ jnp.asarray(_JOIN_INV.T, dtype=rhs.dtype)
    return jnp.concatenate([jnp.stack([c0, c1, c2, c3], axis=-1), hi], axis=-1)


def _spline7(p0, v0, a0, pa, pb, p1, v1, a1, T):
    c0, c1, c2 = p0, T * v0, T * T * a0 / 2.0

    def low(tau):
        return c0 + c1 * tau + c2 * tau * tau

    rhs = jnp.stack(
        [
            pa - low(1.0 / 3.0),
            pb - low(2.0 / 3.0),
            p1 - low(1.0),
            T * v1 - (c1 + 2.0 * c2),
            T * T * a1 - 2.0 * c2,
        ],
        axis=-1,
    )
    hi = rhs @ jnp.asarray(_SPL_INV.T, dtype=rhs.dtype)
    return jnp.concatenate([jnp.stack([c0, c1, c2], axis=-1), hi], axis=-1)


def _poly(c, T, t, deriv):
    """d^deriv/dt^deriv of Σ c_k (t/T)^k; c [..., K]; t broadcasts with c[..., 0]."""
    K = c.shape[-1]
    tau = t / T
    acc = jnp.zeros(jnp.broadcast_shapes(c.shape[:-1], jnp.shape(tau)), dtype=c.dtype)
    for k in range(K - 1, deriv - 1, -1):
        f = float(np.prod(np.arange(k - deriv + 1, k + 1))) if deriv else 1.0
        acc = acc * tau + f * c[..., k]
    return acc / T**deriv


def _chart(q0, q1):
    q0 = _att._qnormalize(q0)
    q1 = _att._qnormalize(q1)
    q1 = jnp.where(jnp.dot(q0, q1) < 0, -q1, q1)
    qr = _att._qnormalize(q0 + q1)  # |q0 + q1| >= sqrt(2) after alignment
    s0 = _att._q2mrp(_att._qmul(_att._qconj(qr), q0))
    s1 = _att._q2mrp(_att._qmul(_att._qconj(qr), q1))
    return qr, s0, s1


def _plan(q0, w0, e0, j0, q1, w1, e1, j1, T):
    qr, s0, s1 = _chart(q0, q1)
    d0 = _att._mrp_derivs(s0, w0, e0, j0)
    d1 = _att._mrp_derivs(s1, w1, e1, j1)
    coeffs = _join7(s0, *d0, s1, *d1, T)  # per component: [3, 8]
    return qr, coeffs


def _aspline(q0, w0, e0, qa, qb, q1, w1, e1, T):
    qr, s0, s1 = _chart(q0, q1)
    qrc = _att._qconj(qr)
    # interior samples: same chart (|σ| <= 1 branch of the relative attitude)
    sa = _att._q2mrp(_att._qmul(qrc, qa))
    sb = _att._q2mrp(_att._qmul(qrc, qb))
    z = jnp.zeros_like(w0)
    d0 = _att._mrp_derivs(s0, w0, e0, z)[:2]
    d1 = _att._mrp_derivs(s1, w1, e1, z)[:2]
    coeffs = _spline7(s0, *d0, sa, sb, s1, *d1, T)  # per component: [3, 8]
    return qr, coeffs


def _eval(qr, coeffs, T, t):
    """Attitude state at times t [...]: (q [...,4], ω, ε, ε' [...,3])."""
    tt = jnp.asarray(t, coeffs.dtype)[..., None]
    s, d1, d2, d3 = (_poly(coeffs, T, tt, n) for n in range(4))
    w, e, j = _att._omega_derivs(s, d1, d2, d3)
    q = _att._qmul(qr, _att._mrp2q(s))
    return q, w, e, j


_join_batched = batched(_join7, "(),(),(),(),(),(),(),(),()->(8)")
_spline_batched = batched(_spline7, "(),(),(),(),(),(),(),(),()->(8)")
_plan_batched = batched(_plan, "(4),(3),(3),(3),(4),(3),(3),(3),()->(4),(3,8)")
_aspline_batched = batched(_aspline, "(4),(3),(3),(4),(4),(4),(3),(3),()->(4),(3,8)")


@functools.lru_cache(maxsize=16)
def _poly_batched(deriv):
    return batched(functools.partial(_poly, deriv=deriv), "(k),(),()->()")


_eval_batched = batched(_eval, "(4),(3,8),(),()->(4),(3),(3),(3)")


# ----------------------------------------------------------------------------- public API
class Maneuver(NamedTuple):
    """A polynomial attitude law on [0, duration] (pytree).

    Attributes:
      q_ref: [..., 4] chart reference quaternion (scalar-first, Hamilton).
      coeffs: [..., 3, 8] normalized MRP coefficients: σ(t) = Σ_k c_k (t/T)^k.
      duration: [...] T [s].
    Attitude at t: Λ(t) = q_ref ∘ Λ(σ(t)).
    """

    q_ref: jnp.ndarray
    coeffs: jnp.ndarray
    duration: jnp.ndarray


def join7_coeffs(p0, v0, a0, j0, p1, v1, a1, j1, T):
    """Normalized coefficients of the degree-7 join on [0, T].

    p(t) = Σ_{k=0..7} c_k (t/T)^k with p, p', p'', p''' equal to (p0, v0, a0, j0)
    at t = 0 and (p1, v1, a1, j1) at t = T; elementwise over broadcast inputs (a
    vector join = per component). c0..c3 = p0, T v0, T²a0/2, T³j0/6; c4..c7 from a
    constant 4×4 system (exact inverse). This is the unique minimizer of ∫₀ᵀ (p⁗)² dt
    under these conditions (seed retarget-scan-pattern-optimization, optimal
    conjugation, eq. 27; SPEC §3).

    Args:
      p0: float [...], angle at 0 [rad].
      p1: float [...], angle at T [rad].
      v0: float [...], rate at 0 [rad/s].
      v1: float [...], rate at T [rad/s].
      a0: float [...], acceleration at 0 [rad/s²].
      a1: float [...], acceleration at T [rad/s²].
      j0: float [...], jerk at 0 [rad/s³].
      j1: float [...], jerk at T [rad/s³].
      T: float [...], duration [s], > 0.
    Returns:
      float [..., 8], normalized coefficients c_k [rad].
    Raises:
      ValueError: T is not positive or an argument is not finite (named).
    """
    names = ("p0", "v0", "a0", "j0", "p1", "v1", "a1", "j1")
    args = [
        as_float_array(n, x) for n, x in zip(names, (p0, v0, a0, j0, p1, v1, a1, j1), strict=True)
    ]
    for n, a in zip(names, args, strict=True):
        check_finite(n, a)
    return _join_batched(*common_float(*args, positive_duration(T)))


def spline7_coeffs(p0, v0, a0, p_third, p_two_thirds, p1, v1, a1, T):
    """Normalized coefficients of the vector-spline segment on [0, T].

    p(t) = Σ c_k (t/T)^k with p, p', p'' = (p0, v0, a0) at 0 and (p1, v1, a1) at
    T, p(T/3) = p_third, p(2T/3) = p_two_thirds (seed vector-spline-guidance-laws,
    "Синтез закона наведения при сканирующей съёмке": 8 vector coefficients
    from (i)–(iii)). Elementwise over broadcast inputs (per component).

    Args:
      p0: float [...], angle at 0 [rad].
      p1: float [...], angle at T [rad].
      v0: float [...], rate at 0 [rad/s].
      v1: float [...], rate at T [rad/s].
      a0: float [...], acceleration at 0 [rad/s²].
      a1: float [...], acceleration at T [rad/s²].
      p_third: float [...], angle at T/3 [rad].
      p_two_thirds: float [...], angle at 2T/3 [rad].
      T: float [...], duration [s], > 0.
    Returns:
      float [..., 8], normalized coefficients c_k [rad].
    Raises:
      ValueError: T is not positive or an argument is not finite (named).
    """
    names = ("p0", "v0", "a0", "p_third", "p_two_thirds", "p1", "v1", "a1")
    vals = (p0, v0, a0, p_third, p_two_thirds, p1, v1, a1)
    args = [as_float_array(n, x) for n, x in zip(names, vals, strict=True)]
    for n, a in zip(names, args, strict=True):
        check_finite(n, a)
    return _spline_batched(*common_float(*args, positive_duration(T)))


def poly_eval(coeffs, T, t, deriv: int = 0):
    """d^deriv p / dt^deriv at times t of p(t) = Σ c_k (t/T)^k.

    Args:
      coeffs: float [..., K], normalized coefficients (as returned by ``join7_coeffs``) [rad].
      T: float [...], duration [s], > 0.
      t: float [...], times [s], broadcast against coeffs[..., 0].
      deriv: static int >= 0, order of the derivative.
    Returns:
      float [...], the derivative [rad / s^deriv] for angle coefficients in [rad].
    Raises:
      ValueError: deriv is not a non-negative int, coeffs has no coefficient axis, or
        an argument is not finite / T not positive (named).
    """
    if not isinstance(deriv, int) or deriv < 0:
        raise ValueError(f"deriv must be a non-negative int, got {deriv!r}")
    c = as_float_array("coeffs", coeffs)
    if c.ndim == 0:
        raise ValueError(f"coeffs must have a coefficient axis, got shape {c.shape}")
    check_finite("coeffs", c)
    t = as_float_array("t", t)
    check_finite("t", t)
    return _poly_batched(deriv)(*common_float(c, positive_duration(T), t))


def maneuver_plan(q0, w0, e0, q1, w1, e1, T, j0=None, j1=None) -> Maneuver:
    """Spatial maneuver between two attitude states as a degree-7 MRP join.

    (Λ, ω, ε, ε') -> (σ, σ', σ'', σ''') in the midpoint chart (module docstring), then
    ``join7_coeffs`` per MRP component. Every boundary condition (seed
    vector-spline-guidance-laws eq. 3, plus ε') holds exactly.

    Args:
      q0: float [..., 4], attitude quaternion (scalar first, body -> reference) at t = 0.
      q1: float [..., 4], attitude quaternion at t = T.
      w0: float [..., 3], body angular velocity ω at 0 [rad/s].
      w1: float [..., 3], body angular velocity ω at T [rad/s].
      e0: float [..., 3], body angular acceleration ε = dω/dt at 0 [rad/s²].
      e1: float [..., 3], body angular acceleration ε at T [rad/s²].
      T: float [...], duration [s], > 0.
      j0: float [..., 3], ε' at 0 [rad/s³]; None means 0.
      j1: float [..., 3], ε' at T [rad/s³]; None means 0.
    Returns:
      Maneuver, the join (batch shape of the broadcast inputs).
    Raises:
      ValueError: an argument is not finite, has the wrong last axis, or T <= 0 (named).
    """
    st = boundary_states(q0, w0, e0, j0, q1, w1, e1, j1)
    args = common_float(*st, positive_duration(T))
    qr, c = _plan_batched(*args)
    return Maneuver(qr, c, args[-1])


def attitude_spline(q0, w0, e0, q_third, q_two_thirds, q1, w1, e1, T) -> Maneuver:
    """Vector-spline approximation of an attitude law on [0, T] (degree-7 MRP).

    σ, σ', σ'' at the ends and σ at T/3, 2T/3 (midpoint chart) fix the 8 vector
    coefficients (seed vector-spline-guidance-laws). Evaluate with ``maneuver_eval``.

    Args:
      q0: float [..., 4], attitude quaternion (scalar first, body -> reference) of the law
        at 0.
      q_third: float [..., 4], the same at T/3.
      q_two_thirds: float [..., 4], the same at 2T/3.
      q1: float [..., 4], the same at T.
      w0: float [..., 3], body angular velocity ω at 0 [rad/s].
      w1: float [..., 3], body angular velocity ω at T [rad/s].
      e0: float [..., 3], body angular acceleration ε at 0 [rad/s²].
      e1: float [..., 3], body angular acceleration ε at T [rad/s²].
      T: float [...], duration [s], > 0.
    Returns:
      Maneuver, the spline segment.
    Raises:
      ValueError: an argument is not finite, has the wrong last axis, or T <= 0 (named).
    """
    q0, qa, qb, q1 = (
        finite_vector(n, x, 4)
        for n, x in (("q0", q0), ("q_third", q_third), ("q_two_thirds", q_two_thirds), ("q1", q1))
    )
    w0, e0, w1, e1 = (
        finite_vector(n, x, 3) for n, x in (("w0", w0), ("e0", e0), ("w1", w1), ("e1", e1))
    )
    args = common_float(q0, w0, e0, qa, qb, q1, w1, e1, positive_duration(T))
    qr, c = _aspline_batched(*args)
    return Maneuver(qr, c, args[-1])


def maneuver_eval(maneuver: Maneuver, t):
    """Attitude state of a ``Maneuver`` at times t.

    ω, ε, ε' are recovered exactly from σ and its derivatives
    (``attitude.omega_from_mrp_derivs``); body-frame components.

    Args:
      maneuver: Maneuver, from ``maneuver_plan`` or ``attitude_spline``.
      t: float [...], times [s], broadcast against the maneuver's batch shape.
    Returns:
      (q float [..., 4], ω float [..., 3] [rad/s], ε = dω/dt float [..., 3] [rad/s²],
      ε' float [..., 3] [rad/s³]).
    Raises:
      ValueError: maneuver is not a Maneuver or t is not finite.
    """
    if not isinstance(maneuver, Maneuver):
        raise ValueError(f"maneuver must be a Maneuver, got {type(maneuver).__name__}")
    t = as_float_array("t", t)
    check_finite("t", t)
    qr, c, T = maneuver
    return _eval_batched(*common_float(qr, c, T, t))
