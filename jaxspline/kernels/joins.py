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

from jaxspline.kernels import attitude as _att
from jaxspline.kernels._batch import batched, map_chunked
from jaxspline.kernels._safe import safe_sqrt
from jaxspline.kernels._validate import (
    as_float_array,
    check_finite,
    check_positive,
    common_float,
    finite_vector,
)
from jaxspline.kernels.limits import AxisLimits, validate_limits

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


# ---- fast sampled check: per-component scalars, one sample per scan step
# The check never materializes a sample grid: a scan over the n sample times carries the
# three running maxima, so under vmap every step is a few fused loops over the batch
# (memory per candidate and compile time do not grow with n).
def _cdot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _ccross(a, b):
    return (
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    )


def _cmrp_derivs(s, w, e, j):
    """(σ', σ'', σ''') from (σ, ω, ε, ε') as 3-tuples (formula of attitude._mrp_derivs).

    σ' = ¼[(1 - a0)ω + 2σ×ω + 2σ b0], a0 = σ·σ, b0 = σ·ω, differentiated twice
    (a1 = 2σ·σ', a2 = 2σ'·σ' + 2σ·σ'', b1 = σ'·ω + σ·ε, b2 = σ''·ω + 2σ'·ε + σ·ε').
    """
    a0, b0 = _cdot(s, s), _cdot(s, w)
    x = _ccross(s, w)
    d1 = tuple(0.25 * ((1.0 - a0) * w[i] + 2.0 * x[i] + 2.0 * s[i] * b0) for i in range(3))
    a1, b1 = 2.0 * _cdot(s, d1), _cdot(d1, w) + _cdot(s, e)
    x1, x2 = _ccross(d1, w), _ccross(s, e)
    d2 = tuple(
        0.25
        * ((1.0 - a0) * e[i] - a1 * w[i] + 2.0 * (x1[i] + x2[i]) + 2.0 * (d1[i] * b0 + s[i] * b1))
        for i in range(3)
    )
    a2 = 2.0 * (_cdot(d1, d1) + _cdot(s, d2))
    b2 = _cdot(d2, w) + 2.0 * _cdot(d1, e) + _cdot(s, j)
    y1, y2, y3 = _ccross(d2, w), _ccross(d1, e), _ccross(s, j)
    d3 = tuple(
        0.25
        * (
            (1.0 - a0) * j[i]
            - 2.0 * a1 * e[i]
            - a2 * w[i]
            + 2.0 * (y1[i] + 2.0 * y2[i] + y3[i])
            + 2.0 * (d2[i] * b0 + 2.0 * d1[i] * b1 + s[i] * b2)
        )
        for i in range(3)
    )
    return d1, d2, d3


def _cqmul_conj(a, b):
    """ã∘b for quaternions given as 4-tuples (w, x, y, z)."""
    av, bv = a[1:], b[1:]
    x = _ccross(av, bv)
    return (a[0] * b[0] + _cdot(av, bv), *(a[0] * bv[i] - b[0] * av[i] - x[i] for i in range(3)))


def _cnormalize(q):
    n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]
    pos = n2 > 0
    inv = jnp.where(pos, jax.lax.rsqrt(jnp.where(pos, n2, 1.0)), 0.0)
    # the zero quaternion has no attitude: identity instead of NaN (as attitude._qnormalize)
    return (jnp.where(pos, q[0] * inv, 1.0), *(q[i] * inv for i in range(1, 4)))


def _cchart(q0, q1):
    """The midpoint chart of ``_chart`` on 4-tuples: (σ0, σ1) as 3-tuples."""
    q0, q1 = _cnormalize(q0), _cnormalize(q1)
    sgn = jnp.where(sum(q0[i] * q1[i] for i in range(4)) < 0, -1.0, 1.0)
    q1 = tuple(sgn * x for x in q1)
    qr = _cnormalize(tuple(a + b for a, b in zip(q0, q1, strict=True)))

    def mrp(q):
        d = _cqmul_conj(qr, q)  # unit up to rounding; d_w = qr·q >= 1/sqrt(2)
        f = jnp.where(d[0] < 0, -1.0, 1.0) / (1.0 + jnp.abs(d[0]))
        return tuple(f * x for x in d[1:])

    return mrp(q0), mrp(q1)


def _horner_derivs(c, tau):
    """(p, p_τ, p_ττ, p_τττ) at a scalar τ of Σ_k c[i][k] τ^k, each a 3-tuple over i."""
    out = []
    for d in range(4):
        comp = []
        for i in range(3):
            acc = None
            for k in range(7, d - 1, -1):
                term = c[i][k] * float(np.prod(np.arange(k - d + 1, k + 1))) if d else c[i][k]
                acc = term if acc is None else acc * tau + term
            comp.append(acc)
        out.append(tuple(comp))
    return out


def _rates_sq(s, d1, d2, d3):
    """|ω|², |ε|², |ε'|² from σ and its first three derivatives (3-tuples), closed form.

    Formula of attitude._omega_derivs: p = Λ(σ) = [2g - 1, 2gσ], g = 1/(1 + σ·σ),
    ω = 2 vec(p̃∘p'), ε = 2 vec(p̃∘p''), ε' = 2 vec(p̃'∘p'' + p̃∘p'''). With derivatives
    with respect to τ = t/T the results are T², T⁴, T⁶ times the physical ones.
    """
    u1 = 2.0 * _cdot(s, d1)
    u2 = 2.0 * (_cdot(d1, d1) + _cdot(s, d2))
    u3 = 2.0 * (3.0 * _cdot(d1, d2) + _cdot(s, d3))
    g0 = 1.0 / (1.0 + _cdot(s, s))
    g02 = g0 * g0
    g1 = -u1 * g02
    g2 = (2.0 * u1 * u1 * g0 - u2) * g02
    g3 = (-u3 + (6.0 * u1 * u2 - 6.0 * u1 * u1 * u1 * g0) * g0) * g02
    p0 = (2.0 * g0 - 1.0, *(2.0 * g0 * s[i] for i in range(3)))
    p1 = (2.0 * g1, *(2.0 * (g1 * s[i] + g0 * d1[i]) for i in range(3)))
    p2 = (2.0 * g2, *(2.0 * (g2 * s[i] + 2.0 * g1 * d1[i] + g0 * d2[i]) for i in range(3)))
    p3 = (
        2.0 * g3,
        *(2.0 * (g3 * s[i] + 3.0 * g2 * d1[i] + 3.0 * g1 * d2[i] + g0 * d3[i]) for i in range(3)),
    )
    w = _cqmul_conj(p0, p1)[1:]
    e = _cqmul_conj(p0, p2)[1:]
    ja, jb = _cqmul_conj(p1, p2)[1:], _cqmul_conj(p0, p3)[1:]
    j = tuple(a + b for a, b in zip(ja, jb, strict=True))
    return 4.0 * _cdot(w, w), 4.0 * _cdot(e, e), 4.0 * _cdot(j, j)


# the whole join as one constant map: c = HERMITE_MAP @ (p0, p0_τ, p0_ττ, p0_τττ, p1, ..., p1_τττ)
HERMITE_MAP = _exact_inverse(
    [[_dmono(k, d, e) for k in range(8)] for e in (0, 1) for d in range(4)]
)
"""The degree-7 join as one exact 8x8 map from the end derivatives (value and three
derivatives at tau = 0 and 1) to the monomial coefficients."""


def _check(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk, n_samples):
    dt = jnp.result_type(q0, T)
    good = T > 0  # a non-positive duration is infeasible (+inf peaks), never NaN
    Ts = jnp.where(good, T, 1.0)
    T2 = Ts * Ts
    qs = (q0, w0, e0, j0, q1, w1, e1, j1)
    cq = [tuple(x[..., i] for i in range(x.shape[-1])) for x in qs]
    s0, s1 = _cchart(cq[0], cq[4])
    da = _cmrp_derivs(s0, *cq[1:4])
    db = _cmrp_derivs(s1, *cq[5:8])
    # boundary derivatives with respect to τ = t/T, then the constant Hermite map
    sc = (Ts, T2, T2 * Ts)
    H = HERMITE_MAP.tolist()
    c = []
    for i in range(3):
        b = (s0[i], *(sc[k] * da[k][i] for k in range(3)))
        b = (*b, s1[i], *(sc[k] * db[k][i] for k in range(3)))
        c.append([sum(H[k][m] * b[m] for m in range(8) if H[k][m] != 0.0) for k in range(8)])
    tau = jnp.asarray(np.linspace(0.0, 1.0, n_samples), dt)
    z = jnp.zeros((), dt)

    def step(carry, t):
        sq = _rates_sq(*_horner_derivs(c, t))
        return tuple(jnp.maximum(m, x) for m, x in zip(carry, sq, strict=True)), None

    (mw, me, mj), _ = jax.lax.scan(step, (z, z, z), tau)
    iT = 1.0 / Ts
    inf = jnp.asarray(jnp.inf, dt)
    peaks = (safe_sqrt(mw) * iT, safe_sqrt(me) * (iT * iT), safe_sqrt(mj) * (iT * iT * iT))
    pw, pe, pj = (jnp.where(good, p, inf) for p in peaks)
    ok = good & (pw <= rate) & (pe <= accel) & (pj <= jerk) & jnp.isfinite(pw + pe + pj)
    return pw, pe, pj, ok


def maneuver_check_kernel(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk, n_samples=129):
    """One-candidate kernel of ``maneuver_check`` (no validation; ``n_samples`` static).

    For the engine: ``jax.jit(jax.vmap(partial(maneuver_check_kernel, n_samples=N)))``.

    Computation (per component, no sample grid is materialized): boundary states ->
    midpoint-chart MRPs σ0, σ1 and their τ-derivatives (τ = t/T) -> join coefficients
    by one constant exact 8×8 Hermite inverse (eq. 27 of the optimal-conjugation seed)
    -> a ``lax.scan`` over the n sample times τ_i = i/(n-1): Horner for σ, σ_τ, σ_ττ,
    σ_τττ, closed-form |ω_τ|², |ε_τ|², |ε'_τ|² (``attitude.omega_from_mrp_derivs``),
    running maxima -> peaks sqrt(max)·T⁻¹, T⁻², T⁻³. Temporaries are ~0.5 kB per
    candidate whatever n; batches of ~1e4 candidates per call keep each scan step in
    cache (``maneuver_check`` chunks larger batches itself).

    Args:
      q0: float [4], start attitude quaternion (scalar first).
      q1: float [4], end attitude quaternion (scalar first).
      w0: float [3], start body angular velocity [rad/s].
      w1: float [3], end body angular velocity [rad/s].
      e0: float [3], start body angular acceleration [rad/s²].
      e1: float [3], end body angular acceleration [rad/s²].
      j0: float [3], start angular jerk [rad/s³].
      j1: float [3], end angular jerk [rad/s³].
      T: scalar, duration [s].
      rate: scalar, bound on |ω| [rad/s].
      accel: scalar, bound on |ε| [rad/s²].
      jerk: scalar, bound on |ε'| [rad/s³].
      n_samples: static int >= 2, equally spaced samples on [0, T].
    Returns:
      (peak |ω| [rad/s], peak |ε| [rad/s²], peak |ε'| [rad/s³], feasible bool);
      T <= 0 gives +inf peaks and False.
    """
    return _check(q0, w0, e0, j0, q1, w1, e1, j1, T, rate, accel, jerk, n_samples)


_join_batched = batched(_join7, "(),(),(),(),(),(),(),(),()->(8)")
_spline_batched = batched(_spline7, "(),(),(),(),(),(),(),(),()->(8)")
_plan_batched = batched(_plan, "(4),(3),(3),(3),(4),(3),(3),(3),()->(4),(3,8)")
_aspline_batched = batched(_aspline, "(4),(3),(3),(4),(4),(4),(3),(3),()->(4),(3,8)")


@functools.lru_cache(maxsize=16)
def _poly_batched(deriv):
    return batched(functools.partial(_poly, deriv=deriv), "(k),(),()->()")


_eval_batched = batched(_eval, "(4),(3,8),(),()->(4),(3),(3),(3)")


_CHUNK = 16384  # candidates per call of the public check (~0.5 kB of temporaries each)


@functools.lru_cache(maxsize=16)
def _check_batched(n_samples):
    f = functools.partial(_check, n_samples=n_samples)
    return batched(f, "(4),(3),(3),(3),(4),(3),(3),(3),(),(),(),()->(),(),(),()")


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

    Attributes:
      peak_rate: float [...], max over samples of |ω| [rad/s].
      peak_accel: float [...], max over samples of |ε| [rad/s²].
      peak_jerk: float [...], max over samples of |ε'| [rad/s³].
      feasible: bool [...], all three peaks within the limits.
    """

    peak_rate: jnp.ndarray
    peak_accel: jnp.ndarray
    peak_jerk: jnp.ndarray
    feasible: jnp.ndarray


def _dur(T):
    T = as_float_array("T", T)
    check_positive("T", T)
    return T


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
    return _join_batched(*common_float(*args, _dur(T)))


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
    return _spline_batched(*common_float(*args, _dur(T)))


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
    return _poly_batched(deriv)(*common_float(c, _dur(T), t))


def _states(q0, w0, e0, j0, q1, w1, e1, j1):
    q0, q1 = finite_vector("q0", q0, 4), finite_vector("q1", q1, 4)
    w0, e0, w1, e1 = (
        finite_vector(n, x, 3) for n, x in (("w0", w0), ("e0", e0), ("w1", w1), ("e1", e1))
    )
    j0 = jnp.zeros_like(e0) if j0 is None else finite_vector("j0", j0, 3)
    j1 = jnp.zeros_like(e1) if j1 is None else finite_vector("j1", j1, 3)
    return q0, w0, e0, j0, q1, w1, e1, j1


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
    st = _states(q0, w0, e0, j0, q1, w1, e1, j1)
    args = common_float(*st, _dur(T))
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
    args = common_float(q0, w0, e0, qa, qb, q1, w1, e1, _dur(T))
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


def maneuver_check(
    q0, w0, e0, q1, w1, e1, T, limits: AxisLimits, j0=None, j1=None, n_samples: int = 129
) -> ManeuverCheck:
    """Plan the degree-7 MRP maneuver and check |ω|, |ε|, |ε'| against limits.

    Peaks are sampled maxima (they can miss an interior peak by O((T/n)²) relatively).
    Reference: SPEC §3 (seed vector-spline-guidance-laws, constraints |ω| <= ω_max,
    |ε| <= ε_max, |ε'| <= jerk_max). Batches larger than 16384 candidates are checked
    in chunks of that size (one compile, bounded memory).

    Args:
      q0: as in ``maneuver_plan``.
      w0: as in ``maneuver_plan``.
      e0: as in ``maneuver_plan``.
      q1: as in ``maneuver_plan``.
      w1: as in ``maneuver_plan``.
      e1: as in ``maneuver_plan``.
      T: as in ``maneuver_plan``.
      limits: AxisLimits, rate [rad/s], accel [rad/s²], jerk [rad/s³] bounds on the
        Euclidean norms of body ω, ε and ε'.
      j0: as in ``maneuver_plan``.
      j1: as in ``maneuver_plan``.
      n_samples: static int >= 2, equally spaced samples on [0, T] including both ends.
    Returns:
      ManeuverCheck, float [...] peaks and bool [...] feasible.
    Raises:
      ValueError: n_samples < 2, invalid limits, or an argument as in ``maneuver_plan``.
    """
    if not isinstance(n_samples, int) or n_samples < 2:
        raise ValueError(f"n_samples must be an int >= 2, got {n_samples!r}")
    limits = validate_limits(limits)
    st = _states(q0, w0, e0, j0, q1, w1, e1, j1)
    args = common_float(*st, _dur(T))
    dt = args[0].dtype  # the limits follow the candidate's dtype
    lim = [
        as_float_array(f"limits.{n}", x, dt) for n, x in zip(limits._fields, limits, strict=True)
    ]
    args = (*args, *lim)
    f = _check_batched(n_samples)
    cores = (4, 3, 3, 3, 4, 3, 3, 3, 0, 0, 0, 0)  # trailing core length (0 = scalar)
    lead = [a.shape[: a.ndim - (k > 0)] for a, k in zip(args, cores, strict=True)]
    batch = jnp.broadcast_shapes(*lead)
    size = int(np.prod(batch))
    if size <= _CHUNK:
        return ManeuverCheck(*f(*args))
    # large batches in fixed-size chunks (one compile): bounded memory, cache-sized steps
    flat = [
        jnp.broadcast_to(a, batch + a.shape[a.ndim - 1 :] if k else batch).reshape(
            (size, k) if k else (size,)
        )
        for a, k in zip(args, cores, strict=True)
    ]
    res = map_chunked(f, flat, _CHUNK, to_numpy=False)
    return ManeuverCheck(*(r.reshape(batch) for r in res))
