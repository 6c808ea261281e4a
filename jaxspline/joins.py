"""Degree-7 polynomial joins, the vector spline, and spatial attitude maneuvers.

* ``join7_coeffs``: the unique degree-7 polynomial with prescribed angle, rate,
  acceleration and jerk at both ends of [0, T]. It is the minimum of ∫ w² dt
  for the chain θ' = ω, ω' = u, u' = v, v' = w (seed
  retarget-scan-pattern-optimization, "optimal conjugation", eqs. 23–27): the
  Euler–Lagrange equation is θ⁽⁸⁾ = 0, so w = θ⁽⁴⁾ is cubic (SPEC §3).
* ``spline7_coeffs``: the vector spline of seed vector-spline-guidance-laws —
  σ, σ', σ'' at both ends plus σ(T/3), σ(2T/3) fix the 8 coefficients.
* ``maneuver_plan`` / ``maneuver_eval`` / ``maneuver_check``: a spatial
  rotation maneuver between two attitude states (Λ, ω, ε, ε') in time T, built
  as a degree-7 join of modified Rodrigues parameters in one MRP chart, and the
  batched check of |ω| <= ω_max, |ε| <= ε_max, |ε'| <= jerk_max on samples.

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

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline import attitude as _att
from jaxspline._validate import as_float_array, check_finite, check_positive
from jaxspline.limits import AxisLimits, validate_limits

__all__ = [
    "join7_coeffs",
    "spline7_coeffs",
    "poly_eval",
    "Maneuver",
    "ManeuverCheck",
    "maneuver_plan",
    "attitude_spline",
    "maneuver_eval",
    "maneuver_check",
    "maneuver_check_kernel",
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


def _check(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk, n_samples):
    good = T > 0  # a non-positive duration is infeasible (+inf peaks), never NaN
    Ts = jnp.where(good, T, 1.0)
    qr, coeffs = _plan(q0, w0, e0, j0, q1, w1, e1, j1, Ts)
    t = jnp.linspace(0.0, 1.0, n_samples, dtype=coeffs.dtype) * Ts
    _, w, e, j = _eval(qr, coeffs, Ts, t)
    inf = jnp.asarray(jnp.inf, coeffs.dtype)
    pw, pe, pj = (jnp.where(good, jnp.max(_att._safe_norm(x)), inf) for x in (w, e, j))
    ok = good & (pw <= rate) & (pe <= accel) & (pj <= jerk) & jnp.isfinite(pw + pe + pj)
    return pw, pe, pj, ok


def maneuver_check_kernel(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk, n_samples=129):
    """One-candidate kernel of ``maneuver_check`` (no validation; ``n_samples`` static).

    Arguments as in ``maneuver_check`` with the limits unpacked (rate [rad/s],
    accel [rad/s²], jerk [rad/s³], 0-d). Returns (peak |ω|, peak |ε|, peak
    |ε'|, feasible); T <= 0 gives +inf peaks and False. For the engine: ``jax.jit(jax.vmap(partial(
    maneuver_check_kernel, n_samples=N)))``.
    """
    return _check(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk, n_samples)


_v_join = jax.jit(jnp.vectorize(_join7, signature="(),(),(),(),(),(),(),(),()->(8)"))
_v_spline = jax.jit(jnp.vectorize(_spline7, signature="(),(),(),(),(),(),(),(),()->(8)"))
_v_plan = jax.jit(jnp.vectorize(_plan, signature="(4),(3),(3),(3),(4),(3),(3),(3),()->(4),(3,8)"))
_v_aspline = jax.jit(
    jnp.vectorize(_aspline, signature="(4),(3),(3),(4),(4),(4),(3),(3),()->(4),(3,8)")
)


@functools.lru_cache(maxsize=16)
def _v_poly(deriv):
    return jax.jit(jnp.vectorize(functools.partial(_poly, deriv=deriv), signature="(k),(),()->()"))


_v_eval = jax.jit(jnp.vectorize(_eval, signature="(4),(3,8),(),()->(4),(3),(3),(3)"))


@functools.lru_cache(maxsize=16)
def _v_check(n_samples):
    f = functools.partial(_check, n_samples=n_samples)
    sig = "(4),(3),(3),(3),(4),(3),(3),(3),(),(),(),()->(),(),(),()"
    return jax.jit(jnp.vectorize(f, signature=sig))


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


class ManeuverCheck(NamedTuple):
    """Result of ``maneuver_check``: sampled peaks and the feasibility flag.

    Attributes: peak_rate [rad/s], peak_accel [rad/s²], peak_jerk [rad/s³]
    (max over samples of |ω|, |ε|, |ε'|), feasible (bool: all within limits).
    """

    peak_rate: jnp.ndarray
    peak_accel: jnp.ndarray
    peak_jerk: jnp.ndarray
    feasible: jnp.ndarray


def _vec(name, x, n):
    arr = as_float_array(name, x)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ValueError(f"{name} must have last axis of length {n}, got shape {arr.shape}")
    check_finite(name, arr)
    return arr


def _dur(T):
    T = as_float_array("T", T)
    check_positive("T", T)
    return T


def _same(*arrs):
    dt = jnp.result_type(*arrs)
    return tuple(jnp.asarray(a, dt) for a in arrs)


def join7_coeffs(p0, v0, a0, j0, p1, v1, a1, j1, T):
    """Normalized coefficients [..., 8] of the degree-7 join on [0, T].

    p(t) = Σ_{k=0..7} c_k (t/T)^k with p, p', p'', p''' equal to (p0, v0, a0, j0)
    at t = 0 and (p1, v1, a1, j1) at t = T. Units: angle [rad], rate [rad/s],
    acceleration [rad/s²], jerk [rad/s³], T [s] > 0; elementwise over
    broadcast inputs (a vector join = per component). c0..c3 = p0, T v0,
    T²a0/2, T³j0/6; c4..c7 from a constant 4×4 system (exact inverse). This is
    the unique minimizer of ∫₀ᵀ (p⁗)² dt under these conditions (seed
    retarget-scan-pattern-optimization, optimal conjugation, eq. 27; SPEC §3).
    """
    names = ("p0", "v0", "a0", "j0", "p1", "v1", "a1", "j1")
    args = [
        as_float_array(n, x) for n, x in zip(names, (p0, v0, a0, j0, p1, v1, a1, j1), strict=True)
    ]
    for n, a in zip(names, args, strict=True):
        check_finite(n, a)
    return _v_join(*_same(*args, _dur(T)))


def spline7_coeffs(p0, v0, a0, p_third, p_two_thirds, p1, v1, a1, T):
    """Normalized coefficients [..., 8] of the vector-spline segment on [0, T].

    p(t) = Σ c_k (t/T)^k with p, p', p'' = (p0, v0, a0) at 0 and (p1, v1, a1) at
    T, p(T/3) = p_third, p(2T/3) = p_two_thirds (seed vector-spline-guidance-laws,
    "Синтез закона наведения при сканирующей съёмке": 8 vector coefficients
    from (i)–(iii)). Units as in ``join7_coeffs``; elementwise (per component).
    """
    names = ("p0", "v0", "a0", "p_third", "p_two_thirds", "p1", "v1", "a1")
    vals = (p0, v0, a0, p_third, p_two_thirds, p1, v1, a1)
    args = [as_float_array(n, x) for n, x in zip(names, vals, strict=True)]
    for n, a in zip(names, args, strict=True):
        check_finite(n, a)
    return _v_spline(*_same(*args, _dur(T)))


def poly_eval(coeffs, T, t, deriv: int = 0):
    """d^deriv p / dt^deriv at times t [s] of p(t) = Σ c_k (t/T)^k.

    coeffs [..., K] normalized coefficients (as returned by ``join7_coeffs``),
    T [s] > 0, t [s] (broadcast against coeffs[..., 0]); deriv a static int
    >= 0. Result in [rad / s^deriv] for angle coefficients in [rad].
    """
    if not isinstance(deriv, int) or deriv < 0:
        raise ValueError(f"deriv must be a non-negative int, got {deriv!r}")
    c = as_float_array("coeffs", coeffs)
    if c.ndim == 0:
        raise ValueError(f"coeffs must have a coefficient axis, got shape {c.shape}")
    check_finite("coeffs", c)
    t = as_float_array("t", t)
    check_finite("t", t)
    return _v_poly(deriv)(*_same(c, _dur(T), t))


def _states(q0, w0, e0, j0, q1, w1, e1, j1):
    q0, q1 = _vec("q0", q0, 4), _vec("q1", q1, 4)
    w0, e0, w1, e1 = (_vec(n, x, 3) for n, x in (("w0", w0), ("e0", e0), ("w1", w1), ("e1", e1)))
    j0 = jnp.zeros_like(e0) if j0 is None else _vec("j0", j0, 3)
    j1 = jnp.zeros_like(e1) if j1 is None else _vec("j1", j1, 3)
    return q0, w0, e0, j0, q1, w1, e1, j1


def maneuver_plan(q0, w0, e0, q1, w1, e1, T, j0=None, j1=None) -> Maneuver:
    """Spatial maneuver between two attitude states as a degree-7 MRP join.

    Boundary states at t = 0 and t = T [s]: attitude quaternions q0, q1 [..., 4]
    (scalar-first, body -> reference), body angular velocity w [rad/s],
    acceleration e = dω/dt [rad/s²] and its derivative j [rad/s³] (default 0),
    all [..., 3]. (Λ, ω, ε, ε') -> (σ, σ', σ'', σ''') in the midpoint chart
    (module docstring), then ``join7_coeffs`` per MRP component. Every boundary
    condition (seed vector-spline-guidance-laws eq. 3, plus ε') holds exactly.
    Returns a ``Maneuver``.
    """
    st = _states(q0, w0, e0, j0, q1, w1, e1, j1)
    args = _same(*st, _dur(T))
    qr, c = _v_plan(*args)
    return Maneuver(qr, c, args[-1])


def attitude_spline(q0, w0, e0, q_third, q_two_thirds, q1, w1, e1, T) -> Maneuver:
    """Vector-spline approximation of an attitude law on [0, T] (degree-7 MRP).

    Inputs: the law's attitude at 0, T/3, 2T/3, T (quaternions [..., 4]), body
    ω [rad/s] and ε [rad/s²] at both ends [..., 3], T [s]. σ, σ', σ'' at the ends
    and σ at T/3, 2T/3 (midpoint chart) fix the 8 vector coefficients (seed
    vector-spline-guidance-laws). Returns a ``Maneuver`` (evaluate with
    ``maneuver_eval``).
    """
    q0, qa, qb, q1 = (
        _vec(n, x, 4)
        for n, x in (("q0", q0), ("q_third", q_third), ("q_two_thirds", q_two_thirds), ("q1", q1))
    )
    w0, e0, w1, e1 = (_vec(n, x, 3) for n, x in (("w0", w0), ("e0", e0), ("w1", w1), ("e1", e1)))
    args = _same(q0, w0, e0, qa, qb, q1, w1, e1, _dur(T))
    qr, c = _v_aspline(*args)
    return Maneuver(qr, c, args[-1])


def maneuver_eval(maneuver: Maneuver, t):
    """Attitude state of a ``Maneuver`` at times t [s].

    Returns (q [..., 4], ω [..., 3] rad/s, ε = dω/dt [..., 3] rad/s², ε' [..., 3]
    rad/s³), body-frame components; ω, ε, ε' are recovered exactly from σ and its
    derivatives (``attitude.omega_from_mrp_derivs``). t broadcasts against the
    maneuver's batch shape.
    """
    if not isinstance(maneuver, Maneuver):
        raise ValueError(f"maneuver must be a Maneuver, got {type(maneuver).__name__}")
    t = as_float_array("t", t)
    check_finite("t", t)
    qr, c, T = maneuver
    return _v_eval(*_same(qr, c, T, t))


def maneuver_check(
    q0, w0, e0, q1, w1, e1, T, limits: AxisLimits, j0=None, j1=None, n_samples: int = 129
) -> ManeuverCheck:
    """Plan the degree-7 MRP maneuver and check |ω|, |ε|, |ε'| against limits.

    Inputs as in ``maneuver_plan``; ``limits`` = AxisLimits(rate [rad/s], accel
    [rad/s²], jerk [rad/s³]) on the Euclidean norms of body ω, ε and ε';
    ``n_samples`` (static, >= 2) equally spaced samples on [0, T] including both
    ends. Peaks are sampled maxima (they can miss an interior peak by
    O((T/n)²) relatively). Reference: SPEC §3 (seed vector-spline-guidance-laws,
    constraints |ω| <= ω_max, |ε| <= ε_max, |ε'| <= jerk_max).
    """
    if not isinstance(n_samples, int) or n_samples < 2:
        raise ValueError(f"n_samples must be an int >= 2, got {n_samples!r}")
    limits = validate_limits(limits)
    st = _states(q0, w0, e0, j0, q1, w1, e1, j1)
    args = _same(*st, _dur(T))
    dt = args[0].dtype  # the limits follow the candidate's dtype
    lim = [
        as_float_array(f"limits.{n}", x, dt) for n, x in zip(limits._fields, limits, strict=True)
    ]
    args = (*args, *lim)
    return ManeuverCheck(*_v_check(n_samples)(*args))
