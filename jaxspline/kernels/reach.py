"""Reachable sets of one attitude channel under rate and acceleration bounds (SPEC section 1).

One control channel is a function f on [0, T] with |f'| <= b, |f''| <= d (a.e.),
f(0) = a1, f'(0) = b1, f(T) = a2, f'(T) = b2 (the set M_T of the paper
"reachable sets of quadratic splines", seeds/reachable-sets-quadratic-splines).
Units: angles rad, rates rad/s, accelerations rad/s^2, times s.

Closed forms used throughout (p = (b1+b2)/2, q = (b1-b2)/2, yA = p + dT/2,
yC = p - dT/2; paper eqs. 2.5-2.10, 3.1-3.2):

    hi = a1 + pT - q^2/d + dT^2/4                       if yA <= b  (two-link)
       = a1 + bT - ((b-b1)^2 + (b-b2)^2)/(2d)           if yA >  b  (three-link)
    lo = a1 + pT + q^2/d - dT^2/4                       if yC >= -b
       = a1 - bT + ((b+b1)^2 + (b+b2)^2)/(2d)           if yC <  -b

Both pieces meet with equal value and slope (hi3 = hi2 - (yA-b)^2/d), so every
quantity below is continuous and a.e. differentiable. The lower quantities are
the mirror image of the upper ones: lo(a1, b1, b2) = -hi(-a1, -b1, -b2).

Two API layers:

* ``*_kernel`` functions take ONE candidate as plain scalars (limits split into
  ``rate``, ``accel``), are branchless, never raise and never return NaN
  (infeasible = +inf / False / empty interval (+inf, -inf)); callers batch them
  with ``jax.jit(jax.vmap(...))``.
* Public functions (``angle_interval``, ``is_reachable`` ...) validate concrete
  inputs eagerly (ValueError naming the argument), broadcast, and call the kernel
  batched once (``batch.batched``: ``jax.jit(jnp.vectorize(kernel))``).

Corrections to the paper (verified by the tests against integration, brute force and
Ruckig): its eq. (3.2) three-link lower bound reads (b - b1)^2, correctly (b + b1)^2; its
final algorithm's case 2 should read T <= (2b - |b1 + b2|)/d; its rate-interval root
selection (section 3, steps 3-7) is garbled and re-derived in ``rate_interval_kernel``;
feasible durations and the minimum peak acceleration are derived in
:mod:`jaxspline.kernels.reach_durations`.

Tolerance: boundary cases computed by floating-point formulas count as
reachable. With r = 64 * eps(dtype) (1.4e-14 in float64, 7.6e-6 in float32),
rates are accepted when |b_i| <= b (1 + r) and |b1 - b2| <= dT + 2 r b, angles
when lo - tol <= a2 <= hi + tol with tol = r (|a1| + |a2| + 2 b T).
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxspline.kernels.batch import batched
from jaxspline.kernels.limits import AxisLimits, validate_limits
from jaxspline.kernels.safe import safe_div, safe_sqrt
from jaxspline.kernels.validate import (
    as_float_array,
    broadcast_named,
    check_finite,
    check_nonnegative,
    check_positive,
    common_float,
    float_dtype_of,
)

__all__ = [
    "angle_interval",
    "angle_interval_kernel",
    "envelopes",
    "envelopes_kernel",
    "is_reachable",
    "is_reachable_kernel",
    "rate_interval",
    "rate_interval_kernel",
    "reach_margin",
    "reach_margin_kernel",
    "transfer",
    "transfer_kernel",
]

#: Relative tolerance of the feasibility tests, in units of the dtype's machine epsilon.
_RTOL_ULPS = 64.0


# ----------------------------------------------------------------------------- helpers


def rtol_of(x):
    """Relative tolerance of the reach tests in the dtype of ``x``: ``_RTOL_ULPS`` ulps."""
    return _RTOL_ULPS * jnp.finfo(jnp.result_type(x)).eps


def _hi(a1, b1, b2, T, b, d):
    """Upper end of the angle reachable set (formula only, no feasibility test)."""
    p = 0.5 * (b1 + b2)
    q = 0.5 * (b1 - b2)
    y_a = p + 0.5 * d * T
    hi2 = a1 + p * T - q * q / d + 0.25 * d * T * T
    hi3 = a1 + b * T - ((b - b1) ** 2 + (b - b2) ** 2) / (2.0 * d)
    return jnp.where(y_a <= b, hi2, hi3)


def _lo(a1, b1, b2, T, b, d):
    """Lower end of the angle reachable set (mirror of ``_hi``)."""
    return -_hi(-a1, -b1, -b2, T, b, d)


def _rates_ok(b1, b2, T, b, d):
    r = rtol_of(b1)
    return (
        (jnp.abs(b1) <= b * (1.0 + r))
        & (jnp.abs(b2) <= b * (1.0 + r))
        & (jnp.abs(b1 - b2) <= d * T + 2.0 * r * b)
    )


def _angle_tol(a1, a2, T, b):
    return rtol_of(a1) * (jnp.abs(a1) + jnp.abs(a2) + 2.0 * b * T)


# ----------------------------------------------------------------------------- kernels


def angle_interval_kernel(a1, b1, b2, T, rate, accel):
    """Reachable end angles [lo, hi] for one candidate (paper eqs. 2.5-2.10; SPEC section 1).

    Args:
      a1: scalar, start angle [rad].
      b1: scalar, start rate [rad/s].
      b2: scalar, end rate [rad/s].
      T: scalar, duration [s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
    Returns:
      (lo, hi) [rad], the integrals of the envelopes F_lo, F_hi (module docstring).
      Empty (+inf, -inf) unless |b1|, |b2| <= b and |b1 - b2| <= dT (within the module
      tolerance; rates are then clipped to [-b, b] and hi < lo from rounding collapses to
      the midpoint).
    """
    a1, b1, b2, T, b, d = common_float(a1, b1, b2, T, rate, accel)
    ok = _rates_ok(b1, b2, T, b, d)
    b1c = jnp.clip(b1, -b, b)
    b2c = jnp.clip(b2, -b, b)
    hi = _hi(a1, b1c, b2c, T, b, d)
    lo = _lo(a1, b1c, b2c, T, b, d)
    mid = 0.5 * (hi + lo)
    hi, lo = jnp.maximum(hi, mid), jnp.minimum(lo, mid)
    return jnp.where(ok, lo, jnp.inf), jnp.where(ok, hi, -jnp.inf)


def is_reachable_kernel(a1, b1, a2, b2, T, rate, accel):
    """True iff (a2, b2) is in the pair set P(a1, b1, T) (Theorem 6; SPEC section 1).

    Conditions |b1|, |b2| <= b (1 + r), |b1 - b2| <= dT + 2 r b and
    lo - tol <= a2 <= hi + tol with r = 64 eps(dtype), tol = r (|a1| + |a2| + 2 b T), so
    boundary cases evaluated in floating point count as reachable. ~40 flops, no
    transcendental functions.

    Args:
      a1: scalar, start angle [rad].
      a2: scalar, end angle [rad].
      b1: scalar, start rate [rad/s].
      b2: scalar, end rate [rad/s].
      T: scalar, duration [s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
    Returns:
      scalar bool.
    """
    a1, b1, a2, b2, T, b, d = common_float(a1, b1, a2, b2, T, rate, accel)
    ok = _rates_ok(b1, b2, T, b, d)
    tol = _angle_tol(a1, a2, T, b)
    b1c = jnp.clip(b1, -b, b)
    b2c = jnp.clip(b2, -b, b)
    hi = _hi(a1, b1c, b2c, T, b, d)
    lo = _lo(a1, b1c, b2c, T, b, d)
    return ok & (a2 >= lo - tol) & (a2 <= hi + tol)


def reach_margin_kernel(a1, b1, a2, b2, T, rate, accel):
    """Signed reachability margin [rad]; >= 0 iff (a2, b2) in P(a1, b1, T) (exact arithmetic).

    Definition (every term in radians):

        m = min(a2 - lo, hi - a2, (b - |b1|) b/d, (b - |b2|) b/d)

    with lo, hi the raw closed forms of the module docstring evaluated at the given
    (unclipped) rates. The duration condition |b1 - b2| <= dT is folded in continuously:
    hi - lo <= (d^2 T^2 - (b1 - b2)^2)/(2d), so it is negative exactly when that condition
    fails, and then m <= (hi - lo)/2 < 0. Rate-bound violations are converted to radians
    with the time scale b/d (time to reach full rate from rest). m is continuous in every
    argument and piecewise smooth (kinks where the min switches), so it is a usable cost for
    gradient refinement: maximise min over channels, or penalise relu(-m). Floating-point
    boundary cases may give m slightly below 0 (see ``is_reachable_kernel`` tolerance).

    Args:
      a1: scalar, start angle [rad].
      b1: scalar, start rate [rad/s].
      a2: scalar, end angle [rad].
      b2: scalar, end rate [rad/s].
      T: scalar, transfer duration [s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
    Returns:
      m [rad], a scalar.
    """
    a1, b1, a2, b2, T, b, d = common_float(a1, b1, a2, b2, T, rate, accel)
    hi = _hi(a1, b1, b2, T, b, d)
    lo = _lo(a1, b1, b2, T, b, d)
    scale = b / d
    m_rate = jnp.minimum(b - jnp.abs(b1), b - jnp.abs(b2)) * scale
    return jnp.minimum(jnp.minimum(a2 - lo, hi - a2), m_rate)


def _rate_lo(a1, b1, a2, T, b, d):
    """Smallest b2 in [L, U] with hi(b2) >= a2 (no emptiness test); rates already clipped."""
    lower = jnp.maximum(-b, b1 - d * T)
    upper = jnp.minimum(b, b1 + d * T)
    c = jnp.clip(2.0 * b - b1 - d * T, lower, upper)  # two-link for b2 <= c
    # two-link: hi = a1 + b1 T + dT^2/2 - x^2/(4d), x = b1 + dT - b2 (paper 3.6)
    root2 = b1 + d * T - 2.0 * safe_sqrt(d * (a1 + b1 * T + 0.5 * d * T * T - a2))
    # three-link: hi = a1 + bT - ((b-b1)^2 + (b-b2)^2)/(2d)
    root3 = b - safe_sqrt(2.0 * d * (a1 - a2 + b * T) - (b - b1) ** 2)
    r = jnp.where(a2 <= _hi(a1, b1, c, T, b, d), root2, root3)
    r = jnp.where(a2 <= _hi(a1, b1, lower, T, b, d), lower, r)
    return jnp.clip(r, lower, upper)


def rate_interval_kernel(a1, b1, a2, T, rate, accel):
    """Reachable end rates [lo, hi] for a given end angle a2 (Theorem 6, derived roots).

    On [L, U] = [max(-b, b1 - dT), min(b, b1 + dT)] the bound hi(b2) is concave
    non-decreasing and lo(b2) convex non-decreasing, so the set is
    [min{b2: hi(b2) >= a2}, max{b2: lo(b2) <= a2}]. Each end is a root of one piece:
    two-link upper b2 = b1 + dT - 2 sqrt(d (a1 + b1 T + dT^2/2 - a2)) for b2 <= 2b - b1 - dT,
    three-link upper b2 = b - sqrt(2d (a1 - a2 + bT) - (b - b1)^2) above it; the lower
    bound by mirror symmetry b2_hi(a1, b1, a2) = -b2_lo(-a1, -b1, -a2).
    (The paper's steps 3-7 of its second algorithm are garbled; this is re-derived.)

    Args:
      a1: scalar, start angle [rad].
      a2: scalar, end angle [rad].
      b1: scalar, start rate [rad/s].
      T: scalar, duration [s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
    Returns:
      (b2_lo, b2_hi) [rad/s]; empty (+inf, -inf) when |b1| > b or a2 is outside
      [lo(L), hi(U)] (module tolerance applies).
    """
    a1, b1, a2, T, b, d = common_float(a1, b1, a2, T, rate, accel)
    r = rtol_of(a1)
    tol = _angle_tol(a1, a2, T, b)
    b1c = jnp.clip(b1, -b, b)
    lower = jnp.maximum(-b, b1c - d * T)
    upper = jnp.minimum(b, b1c + d * T)
    ok = (jnp.abs(b1) <= b * (1.0 + r)) & (a2 <= _hi(a1, b1c, upper, T, b, d) + tol)
    ok = ok & (a2 >= _lo(a1, b1c, lower, T, b, d) - tol)
    lo = _rate_lo(a1, b1c, a2, T, b, d)
    hi = -_rate_lo(-a1, -b1c, -a2, T, b, d)
    mid = 0.5 * (lo + hi)
    lo, hi = jnp.minimum(lo, mid), jnp.maximum(hi, mid)
    return jnp.where(ok, lo, jnp.inf), jnp.where(ok, hi, -jnp.inf)


def _env_hi(a1, b1, b2, T, b, d, t):
    """Upper envelope f_hi at time t: (angle, rate, accel); f_hi' = min(b1+dt, b2+d(T-t), b)."""
    t_apex = (b2 - b1 + d * T) / (2.0 * d)
    tau1 = jnp.clip(jnp.minimum(t_apex, (b - b1) / d), 0.0, T)
    tau2 = jnp.clip(jnp.maximum(t_apex, T - (b - b2) / d), tau1, T)
    t = jnp.clip(t, 0.0, T)
    up = jnp.minimum(t, tau1)
    down = jnp.maximum(t - tau2, 0.0)
    rate = b1 + d * up - d * down
    flat = tau1 * jnp.maximum(t - tau1, 0.0)
    angle = a1 + b1 * t + d * (0.5 * up * up + flat) - 0.5 * d * down**2
    acc = jnp.where(t < tau1, d, jnp.where(t < tau2, 0.0 * d, -d))
    return angle, rate, acc


def _env_lo(a1, b1, b2, T, b, d, t):
    angle, rate, acc = _env_hi(-a1, -b1, -b2, T, b, d, t)
    return -angle, -rate, -acc


def envelopes_kernel(a1, b1, b2, T, rate, accel, t):
    """Envelope angle curves (f_lo(t), f_hi(t)) at one time (paper Theorems 2-5).

    f_hi(t) = a1 + int_0^t min(b1 + d s, b2 + d (T - s), b) ds and f_lo likewise with
    max(b1 - d s, b2 - d (T - s), -b); t is clipped to [0, T]. f_hi(T) = hi, f_lo(T) = lo.

    Args:
      a1: scalar, start angle [rad].
      b1: scalar, start rate [rad/s].
      b2: scalar, end rate [rad/s].
      T: scalar, transfer duration [s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
      t: scalar, evaluation time [s] (clipped to [0, T]).
    Returns:
      (f_lo, f_hi) [rad]; infeasible rates (see ``angle_interval_kernel``) give (+inf, -inf).
    """
    a1, b1, b2, T, b, d, t = common_float(a1, b1, b2, T, rate, accel, t)
    ok = _rates_ok(b1, b2, T, b, d)
    b1c = jnp.clip(b1, -b, b)
    b2c = jnp.clip(b2, -b, b)
    f_hi = _env_hi(a1, b1c, b2c, T, b, d, t)[0]
    f_lo = _env_lo(a1, b1c, b2c, T, b, d, t)[0]
    return jnp.where(ok, f_lo, jnp.inf), jnp.where(ok, f_hi, -jnp.inf)


def transfer_kernel(a1, b1, a2, b2, T, rate, accel, t):
    """Theorem-1 trajectory at one time t.

    f = ((hi - a2) f_lo + (a2 - lo) f_hi)/(hi - lo) (paper Theorem 1), i.e. the convex
    combination lam f_hi + (1 - lam) f_lo with lam = clip((a2 - lo)/(hi - lo), 0, 1) and
    lam = 1/2 when hi == lo. It is a quadratic spline (piecewise-constant f'', at most four
    switches) with |f'| <= b, |f''| <= d and the four boundary values. The acceleration is
    right-continuous (at t = T the last piece's value); t is clipped to [0, T].

    Args:
      a1: scalar, start angle [rad].
      b1: scalar, start rate [rad/s].
      a2: scalar, end angle [rad].
      b2: scalar, end rate [rad/s].
      T: scalar, transfer duration [s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
      t: scalar, evaluation time [s] (clipped to [0, T]).
    Returns:
      (angle [rad], rate [rad/s], accel [rad/s^2]); (+inf, +inf, +inf) when (a2, b2) is
      not reachable (``is_reachable_kernel``).
    """
    a1, b1, a2, b2, T, b, d, t = common_float(a1, b1, a2, b2, T, rate, accel, t)
    ok = is_reachable_kernel(a1, b1, a2, b2, T, b, d)
    b1c = jnp.clip(b1, -b, b)
    b2c = jnp.clip(b2, -b, b)
    hi = _hi(a1, b1c, b2c, T, b, d)
    lo = _lo(a1, b1c, b2c, T, b, d)
    lam = jnp.clip(safe_div(a2 - lo, hi - lo, 0.5), 0.0, 1.0)
    lam = jnp.where(hi > lo, lam, 0.5)
    up = _env_hi(a1, b1c, b2c, T, b, d, t)
    dn = _env_lo(a1, b1c, b2c, T, b, d, t)
    out = tuple(lam * u + (1.0 - lam) * v for u, v in zip(up, dn, strict=True))
    return tuple(jnp.where(ok, x, jnp.inf) for x in out)


# ----------------------------------------------------------------------------- batched


_angle_interval_batched = batched(angle_interval_kernel)
_rate_interval_batched = batched(rate_interval_kernel)
_is_reachable_batched = batched(is_reachable_kernel)
_reach_margin_batched = batched(reach_margin_kernel)
_envelopes_batched = batched(envelopes_kernel)
_transfer_batched = batched(transfer_kernel)


def prepare_inputs(limits, need_accel=True, **named):
    """Validate named inputs + limits and return them broadcast in one float dtype."""
    if need_accel:
        lim = validate_limits(limits)
        named = dict(named, rate=lim.rate, accel=lim.accel)
    arrs = {k: as_float_array(k, v) for k, v in named.items()}
    for name, x in arrs.items():
        if name == "T":
            check_nonnegative("T", x)
        elif name in ("rate", "accel"):
            check_positive(name if not need_accel else f"limits.{name}", x)
        else:
            check_finite(name, x)
    dt = float_dtype_of(*arrs.values())
    return broadcast_named(**{k: v.astype(dt) for k, v in arrs.items()})


def angle_interval(a1, b1, b2, T, limits: AxisLimits):
    """Reachable end angles (lo, hi) for exactly duration T (SPEC section 1, question 1).

    Formula: ``angle_interval_kernel``. Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      b2: float [...], end rate [rad/s].
      T: float [...], transfer duration [s], >= 0.
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
    Returns:
      (lo, hi), float [...] each [rad]; empty = (+inf, -inf).
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    return _angle_interval_batched(*prepare_inputs(limits, a1=a1, b1=b1, b2=b2, T=T))


def rate_interval(a1, b1, a2, T, limits: AxisLimits):
    """Reachable end rates (lo, hi) for end angle a2 and duration T (question 2).

    Formula and derivation: ``rate_interval_kernel``. Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      T: float [...], transfer duration [s], >= 0.
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
    Returns:
      (lo, hi), float [...] each [rad/s]; empty = (+inf, -inf).
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    return _rate_interval_batched(*prepare_inputs(limits, a1=a1, b1=b1, a2=a2, T=T))


def is_reachable(a1, b1, a2, b2, T, limits: AxisLimits):
    """Membership of (a2, b2) in the pair set P(a1, b1, T) (Theorem 6; question 3).

    Exact duration T (not "T or longer"). Tolerance: ``is_reachable_kernel``.
    Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      b2: float [...], end rate [rad/s].
      T: float [...], transfer duration [s], >= 0.
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
    Returns:
      bool [...].
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    return _is_reachable_batched(*prepare_inputs(limits, a1=a1, b1=b1, a2=a2, b2=b2, T=T))


def reach_margin(a1, b1, a2, b2, T, limits: AxisLimits):
    """Signed margin, >= 0 iff reachable: min(a2 - lo, hi - a2, (b - |b_i|) b/d).

    Continuous and a.e. differentiable; definition and rationale in ``reach_margin_kernel``.
    Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      b2: float [...], end rate [rad/s].
      T: float [...], transfer duration [s], >= 0.
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
    Returns:
      float [...], margin [rad].
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    return _reach_margin_batched(*prepare_inputs(limits, a1=a1, b1=b1, a2=a2, b2=b2, T=T))


def envelopes(a1, b1, b2, T, limits: AxisLimits, t):
    """Envelope angle curves (f_lo(t), f_hi(t)) at times t (paper Theorems 2-5).

    See ``envelopes_kernel``; t broadcasts with the other arguments.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      b2: float [...], end rate [rad/s].
      T: float [...], transfer duration [s], >= 0.
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
      t: float [...], evaluation times [s] (clipped to [0, T]).
    Returns:
      (f_lo, f_hi), float [...] each [rad].
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    a1, b1, b2, T, t, rate, accel = prepare_inputs(limits, a1=a1, b1=b1, b2=b2, T=T, t=t)
    return _envelopes_batched(a1, b1, b2, T, rate, accel, t)


def transfer(a1, b1, a2, b2, T, limits: AxisLimits, t):
    """Theorem-1 trajectory at times t.

    Convex combination of the envelopes; see ``transfer_kernel``. Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      b2: float [...], end rate [rad/s].
      T: float [...], transfer duration [s], >= 0.
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
      t: float [...], evaluation times [s] (clipped to [0, T]).
    Returns:
      (angle [rad], rate [rad/s], accel [rad/s^2]), float [...] each; +inf when
      unreachable.
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    a1, b1, a2, b2, T, t, rate, accel = prepare_inputs(limits, a1=a1, b1=b1, a2=a2, b2=b2, T=T, t=t)
    return _transfer_batched(a1, b1, a2, b2, T, rate, accel, t)
