"""The sampled check of a degree-7 attitude join against rate, acceleration and jerk.

``maneuver_check`` plans the maneuver of :func:`jaxspline.kernels.joins.maneuver_plan`
and checks |ω| <= ω_max, |ε| <= ε_max, |ε'| <= jerk_max on equally spaced samples;
``maneuver_check_kernel`` is its one-candidate kernel (SPEC §3, seed
vector-spline-guidance-laws). Split from :mod:`jaxspline.kernels.joins` (the join and its
evaluation) along the seam the two share: the constant Hermite map
(:data:`jaxspline.kernels.joins.HERMITE_MAP`) and the checked boundary states.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.batch import batched, map_chunked
from jaxspline.kernels.joins import HERMITE_MAP
from jaxspline.kernels.limits import AxisLimits, validate_limits
from jaxspline.kernels.safe import safe_sqrt
from jaxspline.kernels.validate import (
    as_float_array,
    boundary_states,
    common_float,
    positive_duration,
)

__all__ = ["maneuver_check", "maneuver_check_kernel"]


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


_CHUNK = 16384  # candidates per call of the public check (~0.5 kB of temporaries each)


@functools.lru_cache(maxsize=16)
def _check_batched(n_samples):
    f = functools.partial(_check, n_samples=n_samples)
    return batched(f, "(4),(3),(3),(3),(4),(3),(3),(3),(),(),(),()->(),(),(),()")


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
      ManeuverCheck, a NamedTuple: ``peak_rate`` [rad/s], ``peak_accel`` [rad/s²],
      ``peak_jerk`` [rad/s³] float [...] and ``feasible`` bool [...].
    Raises:
      ValueError: n_samples < 2, invalid limits, or an argument as in ``maneuver_plan``.
    """
    if not isinstance(n_samples, int) or n_samples < 2:
        raise ValueError(f"n_samples must be an int >= 2, got {n_samples!r}")
    limits = validate_limits(limits)
    st = boundary_states(q0, w0, e0, j0, q1, w1, e1, j1)
    args = common_float(*st, positive_duration(T))
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
