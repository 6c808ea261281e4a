"""Feasible durations, minimum transfer time and minimum peak acceleration of one channel.

The duration-side questions of SPEC section 1 for the channel model of
:mod:`jaxspline.kernels.reach` (|f'| <= b, |f''| <= d, boundary angles and rates):
for which T the transfer exists (not an interval in general), the shortest such T, and
the least acceleration bound that makes a given T feasible (the dual problem). The
paper does not state them; they are derived here from its closed-form bounds and
tested against Ruckig, brute force and numerical integration. Same two API layers and
tolerances as :mod:`jaxspline.kernels.reach`.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxspline.kernels.batch import batched
from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.reach import prepare_inputs, rtol_of
from jaxspline.kernels.safe import safe_div, safe_sqrt
from jaxspline.kernels.validate import common_float

__all__ = [
    "feasible_durations",
    "feasible_durations_kernel",
    "min_peak_accel",
    "min_peak_accel_kernel",
    "min_transfer_time",
    "min_transfer_time_kernel",
]


# ----------------------------------------------------------------------------- kernels


def _h_region(b1, b2, D, b, d):
    """{T >= T0: H(T) < D} as (start, end, nonempty), H(T) = hi(T) - a1 (convex in T).

    H'(T) = min(p + dT/2, b); minimum at max(T0, -2p/d) with value -S/d if max(b1,b2) < 0
    else E0 = H(T0). Roots: two-link dT^2/4 + pT - q^2/d = D gives
    T = 2(-p +- sqrt(S + dD))/d (S = (b1^2 + b2^2)/2), three-link bT - K/(2d) = D.
    """
    p = 0.5 * (b1 + b2)
    q = 0.5 * (b1 - b2)
    s2 = p * p + q * q
    t0_min = jnp.abs(b1 - b2) / d
    e0 = (b1 + b2) * jnp.abs(b1 - b2) / (2.0 * d)
    h_min = jnp.where(jnp.maximum(b1, b2) < 0, -s2 / d, e0)
    nonempty = h_min < D
    s = safe_sqrt(s2 + d * D)
    num = q * q + d * D  # = s^2 - p^2
    # larger root, cancellation-free for p > 0
    plus = jnp.where(p > 0, 2.0 * safe_div(num, d * (s + p)), 2.0 * (s - p) / d)
    # smaller root, cancellation-free for p < 0
    minus = jnp.where(p < 0, -2.0 * safe_div(num, d * (s - p)), -2.0 * (s + p) / d)
    k = (b - b1) ** 2 + (b - b2) ** 2
    lin = (D + k / (2.0 * d)) / b
    h_b = (b * b - s2) / d  # H at the two-/three-link switch T = 2(b - p)/d
    end = jnp.where(D <= h_b, plus, lin)
    start = jnp.maximum(t0_min, minus)
    return start, end, nonempty


def feasible_durations_kernel(a1, b1, a2, b2, rate, accel):
    """Feasible transfer durations: [t_min, inf) minus the open interval (blocked_lo, blocked_hi).

    Derivation (SPEC section 1 "durations are not monotone"): with D = a2 - a1, the
    transfer takes exactly T iff T >= T0 = |b1 - b2|/d and L(T) <= D <= H(T), H = hi - a1,
    L = lo - a1. dH/dT = min(p + dT/2, b) is non-decreasing (H convex), L is concave, and
    H(T0) = L(T0) = E0 = (b1 + b2)|b1 - b2|/(2d). So {H < D} and {L > D} are intervals,
    disjoint; the one that contains T0 (D > E0 or D < E0) ends at t_min, the other (it can
    start after T0 only if b1, b2 share a sign) is the blocked interval. Roots are the
    closed forms of ``_h_region``; |D - E0| <= tol (module tolerance with b^2/d) counts
    as D = E0 (T0 itself feasible).

    Args:
      a1: scalar, start angle [rad].
      a2: scalar, end angle [rad].
      b1: scalar, start rate [rad/s].
      b2: scalar, end rate [rad/s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
    Returns:
      (t_min, blocked_lo, blocked_hi) [s]; no block gives blocked_lo == blocked_hi
      == t_min; impossible (|b_i| > b) gives all +inf.
    """
    a1, b1, a2, b2, b, d = common_float(a1, b1, a2, b2, rate, accel)
    r = rtol_of(a1)
    ok = (jnp.abs(b1) <= b * (1.0 + r)) & (jnp.abs(b2) <= b * (1.0 + r))
    b1 = jnp.clip(b1, -b, b)
    b2 = jnp.clip(b2, -b, b)
    t0 = jnp.abs(b1 - b2) / d
    e0 = (b1 + b2) * jnp.abs(b1 - b2) / (2.0 * d)
    D = a2 - a1
    tol = r * (jnp.abs(a1) + jnp.abs(a2) + b * b / d)
    D = jnp.where(jnp.abs(D - e0) <= tol, e0, D)
    h0, h1, hnon = _h_region(b1, b2, D, b, d)
    l0, l1, lnon = _h_region(-b1, -b2, -D, b, d)
    t_min = jnp.where(D > e0, h1, jnp.where(D < e0, l1, t0))
    use_h = hnon & ~(D > e0)
    use_l = lnon & ~(D < e0)
    blo = jnp.where(use_h, h0, jnp.where(use_l, l0, t_min))
    bhi = jnp.where(use_h, h1, jnp.where(use_l, l1, t_min))
    blo = jnp.where(D == e0, t0, jnp.maximum(blo, t_min))  # isolated T0: block starts there
    none = bhi <= blo
    blo = jnp.where(none, t_min, blo)
    bhi = jnp.where(none, t_min, bhi)
    inf = jnp.inf
    return jnp.where(ok, t_min, inf), jnp.where(ok, blo, inf), jnp.where(ok, bhi, inf)


def min_transfer_time_kernel(a1, b1, a2, b2, rate, accel):
    """Shortest feasible duration T_min (first element of ``feasible_durations_kernel``).

    Note that T > T_min need not be feasible (blocked interval).

    Args:
      a1: scalar, start angle [rad].
      b1: scalar, start rate [rad/s].
      a2: scalar, end angle [rad].
      b2: scalar, end rate [rad/s].
      rate: scalar, rate bound b [rad/s].
      accel: scalar, acceleration bound d [rad/s^2].
    Returns:
      T_min [s]; +inf when |b1| or |b2| > b.
    """
    return feasible_durations_kernel(a1, b1, a2, b2, rate, accel)[0]


def _d_hi(b1, b2, D, T, b):
    """Smallest d > 0 with hi_d - a1 >= D (hi_d is increasing in d for d > 0)."""
    p = 0.5 * (b1 + b2)
    q = 0.5 * (b1 - b2)
    # H at the switch d_b = 2(b - p)/T: pT + (b - p)T/2 - q^2 T/(2(b - p))
    h_b = p * T + 0.5 * (b - p) * T - 0.5 * T * safe_div(q * q, b - p)
    # two-link: (T^2/4) d^2 + (pT - D) d - q^2 = 0, non-negative root
    B = p * T - D
    sq = safe_sqrt(B * B + T * T * q * q)
    d2 = jnp.where(B > 0, safe_div(2.0 * q * q, B + sq), 2.0 * safe_div(sq - B, T * T))
    # three-link: bT - K/(2d) = D
    k = (b - b1) ** 2 + (b - b2) ** 2
    den = 2.0 * (b * T - D)
    d3 = jnp.where(den > 0, safe_div(k, den), jnp.inf)
    return jnp.where(D <= h_b, d2, d3)


def min_peak_accel_kernel(a1, b1, a2, b2, T, rate):
    """Smallest acceleration bound d* making the exact-T transfer possible.

    Dual problem (seed retarget-scan, eq. 13, L-inf norm of the control). Because hi_d is
    increasing and lo_d decreasing in d, d* = max(|b1 - b2|/T, d_hi, d_lo) where d_hi solves
    hi_d = a2 on the active piece: two-link (T^2/4) d^2 + (pT - D) d - q^2 = 0, three-link
    d = ((b - b1)^2 + (b - b2)^2)/(2(bT - D)) (D = a2 - a1; +inf if bT <= D), and d_lo is
    its mirror image. d* <= d  <=>  is_reachable(..., d).

    Args:
      a1: scalar, start angle [rad].
      b1: scalar, start rate [rad/s].
      a2: scalar, end angle [rad].
      b2: scalar, end rate [rad/s].
      T: scalar, transfer duration [s].
      rate: scalar, rate bound b [rad/s].
    Returns:
      d* [rad/s^2]; +inf when |b_i| > b (1 + r) or no d works; for T = 0, 0 if the
      states coincide (within tolerance) else +inf.
    """
    a1, b1, a2, b2, T, b = common_float(a1, b1, a2, b2, T, rate)
    r = rtol_of(a1)
    ok = (jnp.abs(b1) <= b * (1.0 + r)) & (jnp.abs(b2) <= b * (1.0 + r))
    b1 = jnp.clip(b1, -b, b)
    b2 = jnp.clip(b2, -b, b)
    D = a2 - a1
    pos = T > 0
    Ts = jnp.where(pos, T, 1.0)
    d0 = jnp.abs(b1 - b2) / Ts
    dh = _d_hi(b1, b2, D, Ts, b)
    dl = _d_hi(-b1, -b2, -D, Ts, b)
    dstar = jnp.maximum(jnp.maximum(d0, dh), dl)
    same = (jnp.abs(b1 - b2) <= r * b) & (jnp.abs(D) <= r * (jnp.abs(a1) + jnp.abs(a2)))
    d_zero_t = jnp.where(same, 0.0 * b, jnp.inf)
    return jnp.where(ok, jnp.where(pos, dstar, d_zero_t), jnp.inf)


# ----------------------------------------------------------------------------- batched


_feasible_durations_batched = batched(feasible_durations_kernel)
_min_peak_accel_batched = batched(min_peak_accel_kernel)


def feasible_durations(a1, b1, a2, b2, limits: AxisLimits):
    """Feasible durations [t_min, inf) minus (blocked_lo, blocked_hi) (SPEC section 1).

    Example b1 = b2 = b, a2 - a1 = D > 0: t_min = D/b, blocked =
    (2(b - sqrt(b^2 - dD))/d, 2(b + sqrt(b^2 - dD))/d). See ``feasible_durations_kernel``.
    Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      b2: float [...], end rate [rad/s].
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
    Returns:
      (t_min, blocked_lo, blocked_hi), float [...] each [s]; no block gives
      blocked_lo == blocked_hi == t_min; impossible gives all +inf.
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    return _feasible_durations_batched(*prepare_inputs(limits, a1=a1, b1=b1, a2=a2, b2=b2))


def min_transfer_time(a1, b1, a2, b2, limits: AxisLimits):
    """Shortest feasible duration (+inf when impossible).

    Longer durations need not be feasible: see ``feasible_durations``. Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      b2: float [...], end rate [rad/s].
      limits: AxisLimits, rate bound b [rad/s] and acceleration bound d [rad/s^2] (jerk ignored).
    Returns:
      float [...], t_min [s].
    Raises:
      ValueError: an argument is not finite, T < 0 or a limit is not positive (named).
    """
    return feasible_durations(a1, b1, a2, b2, limits)[0]


def min_peak_accel(a1, b1, a2, b2, T, rate):
    """Smallest acceleration bound d* for the exact-T transfer under rate bound b.

    The differentiable "effort" of a transition (seed retarget-scan eq. 13); formula in
    ``min_peak_accel_kernel``. Arguments broadcast together.

    Args:
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      a2: float [...], end angle [rad].
      b2: float [...], end rate [rad/s].
      T: float [...], transfer duration [s], >= 0.
      rate: float [...], rate bound b [rad/s], > 0.
    Returns:
      float [...], d* [rad/s^2]; +inf if impossible for every d.
    Raises:
      ValueError: an argument is not finite, T < 0 or rate is not positive (named).
    """
    args = prepare_inputs(None, need_accel=False, a1=a1, b1=b1, a2=a2, b2=b2, T=T, rate=rate)
    return _min_peak_accel_batched(*args)
