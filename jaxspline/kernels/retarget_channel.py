"""Minimum-peak control of one channel and of decoupled channels (the linear case).

The double integrator ``f'' = a`` from (a1, b1) to (a2, b2) in exactly T with the
smallest peak |a| (bang-coast-bang), and its vector form. Formulas, references
and errata: :mod:`jaxspline.kernels.retarget` (retarget-scan paper eqs. 5-7, 21;
SPEC §3); the nonlinear 3-D problem built on it lives there.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.batch import batched
from jaxspline.kernels.reach_durations import min_peak_accel_kernel
from jaxspline.kernels.safe import safe_sqrt
from jaxspline.kernels.validate import (
    as_float_array,
    broadcast_named,
    check_finite,
    check_positive,
    float_dtype_of,
    is_concrete,
)

__all__ = [
    "ARCSEC",
    "ChannelControl",
    "min_peak_channel_kernel",
    "min_peak_channel",
    "channel_control_eval",
    "channel_state",
    "min_peak_linear",
]

ARCSEC = math.pi / 648000.0
"""One arc-second in radians."""

CHANNEL_AXIS = (2, 0, 1)
"""Body axis of channel k of sigma = (pitch, roll, yaw)."""
AXIS_CHANNEL = (1, 2, 0)
"""Channel of body axis i (the inverse of ``CHANNEL_AXIS``)."""


class ChannelControl(NamedTuple):
    """Bang–coast–bang control of one channel: ``a(t) = s·d`` on [0, t1), 0 on [t1, t2),
    ``−s·d`` on [t2, T].

    Attributes:
      peak: d = peak |a| [rad/s²] (``inf`` if the transfer is impossible, 0 if no
        control is needed).
      sign: s ∈ {−1, 0, +1} (0 when peak is 0 or inf).
      t1, t2: switch times [s], 0 <= t1 <= t2 <= T.
    """

    peak: jnp.ndarray
    sign: jnp.ndarray
    t1: jnp.ndarray
    t2: jnp.ndarray


# ----------------------------------------------------------------------------- linear


def unbounded_peak(a1, b1, a2, b2, T):
    """d* = (2|D| + sqrt(4D² + T²Δ²))/T² (no rate bound), finite gradients at D = Δ = 0."""
    D = a2 - a1 - 0.5 * T * (b1 + b2)
    dv = b2 - b1
    q = 4.0 * D * D + (T * dv) ** 2
    return (2.0 * jnp.abs(D) + safe_sqrt(q)) / (T * T)


def _hi_lo(a1, b1, b2, T, d, rate):
    """Envelope end angles hi(d), lo(d) of SPEC §1 (d > 0, rate may be inf)."""
    fin = jnp.isfinite(rate)
    b = jnp.where(fin, rate, 0.0)
    yA = 0.5 * (b1 + b2 + d * T)
    yC = 0.5 * (b1 + b2 - d * T)
    base = a1 + 0.5 * T * (b1 + b2)
    hi2 = base - (b1 - b2) ** 2 / (4.0 * d) + d * T * T / 4.0
    lo2 = base + (b1 - b2) ** 2 / (4.0 * d) - d * T * T / 4.0
    hi3 = a1 - ((b - b1) ** 2 + (b - b2) ** 2) / (2.0 * d) + b * T
    lo3 = a1 + ((b + b1) ** 2 + (b + b2) ** 2) / (2.0 * d) - b * T
    hi = jnp.where(fin & (yA > b), hi3, hi2)
    lo = jnp.where(fin & (yC < -b), lo3, lo2)
    return hi, lo


def min_peak_channel_kernel(a1, b1, a2, b2, T, rate):
    """Minimum-peak control of one double-integrator channel in exactly T (kernel).

    Minimises ``max_t |f''(t)|`` over f with f(0) = a1, f'(0) = b1, f(T) = a2,
    f'(T) = b2 and ``|f'| <= rate`` (``rate = inf``: no bound). Without a rate bound
    ``d* = (2|D| + sqrt(4D² + T²Δ²))/T²`` with D = a2 − a1 − T(b1 + b2)/2, Δ = b2 − b1
    (paper eqs. 13, 21 for one channel); with a finite rate, d* = reach_durations.min_peak_accel.
    The optimal control runs along the upper (s = +1) or lower (s = −1) envelope of
    SPEC §1 for d = d*: apex tA = (T + s Δ/d)/2, t1 = min((rate − s b1)/d, tA),
    t2 = max(T − (rate − s b2)/d, tA).

    Args:
      a1: start angle [rad] (broadcast with a2).
      a2: end angle [rad].
      b1: start rate [rad/s].
      b2: end rate [rad/s].
      T: duration [s], > 0.
      rate: rate bound [rad/s], > 0 or inf.
    Returns:
      :class:`ChannelControl` (peak [rad/s²], sign, t1 [s], t2 [s]); peak = inf
      (sign 0) if no admissible transfer exists.
    """
    a1, b1, a2, b2, T, rate = jnp.broadcast_arrays(a1, b1, a2, b2, T, rate)
    fin = jnp.isfinite(rate)
    d_unb = unbounded_peak(a1, b1, a2, b2, T)
    rate_safe = jnp.where(fin, rate, 1.0)
    d = jnp.where(fin, min_peak_accel_kernel(a1, b1, a2, b2, T, rate_safe), d_unb)
    return control_from_peak(a1, b1, a2, b2, T, rate, d)


def control_from_peak(a1, b1, a2, b2, T, rate, d):
    """Envelope choice s and switch times t1, t2 for the optimal peak d (see kernel)."""
    fin = jnp.isfinite(rate)
    ok = jnp.isfinite(d) & (d > 0)
    ds = jnp.where(ok, d, 1.0)
    hi, lo = _hi_lo(a1, b1, b2, T, ds, rate)
    s = jnp.where(hi - a2 <= a2 - lo, 1.0, -1.0)
    s = jnp.where(ok, s, 0.0).astype(ds.dtype)
    half = 0.5 * T
    tA = jnp.clip(0.5 * (T + s * (b2 - b1) / ds), 0.0, T)
    b = jnp.where(fin, rate, 0.0)
    t1 = jnp.where(fin, jnp.minimum((b - s * b1) / ds, tA), tA)
    t2 = jnp.where(fin, jnp.maximum(T - (b - s * b2) / ds, tA), tA)
    t1 = jnp.where(ok, jnp.clip(t1, 0.0, T), half)
    t2 = jnp.where(ok, jnp.clip(t2, 0.0, T), half)
    return ChannelControl(d, s, t1, t2)


_channel_batched = batched(min_peak_channel_kernel)


def _prep(**named):
    """Validate concrete inputs (finite, no NaN) and broadcast to a common float dtype."""
    for k, v in named.items():
        check_finite(k, v, allow_inf=(k == "rate"))
    dt = float_dtype_of(*named.values())
    arrs = {k: as_float_array(k, v, dt) for k, v in named.items()}
    return broadcast_named(**arrs)


def min_peak_channel(a1, b1, a2, b2, T, rate=float("inf")):
    """Minimum peak |f''| for one channel, batched (see :func:`min_peak_channel_kernel`).

    Args:
      a1: float [...], start angle [rad].
      a2: float [...], end angle [rad].
      b1: float [...], start rate [rad/s].
      b2: float [...], end rate [rad/s].
      T: float [...], duration [s], > 0.
      rate: float [...], rate bound [rad/s], > 0 or inf (no bound).
    Returns:
      :class:`ChannelControl` with float [...] fields (the broadcast shape).
    Raises:
      ValueError: naming the argument for NaN/inf boundary values, T <= 0, rate <= 0.
    """
    check_positive("T", T)
    check_positive("rate", rate, allow_inf=True)
    args = _prep(a1=a1, b1=b1, a2=a2, b2=b2, T=T, rate=rate)
    return ChannelControl(*_channel_batched(*args))


def channel_control_eval(ctrl: ChannelControl, t):
    """Control value a(t) = s d [t < t1] − s d [t >= t2] of a ChannelControl at t.

    Args:
      ctrl: ChannelControl (fields scalar or broadcast against t).
      t: float [...], times [s].
    Returns:
      float [...], a(t) [rad/s²].
    """
    d = jnp.where(jnp.isfinite(ctrl.peak), ctrl.peak, 0.0)
    sd = ctrl.sign * d
    return jnp.where(t < ctrl.t1, sd, 0.0) - jnp.where(t >= ctrl.t2, sd, 0.0)


def channel_state(ctrl: ChannelControl, a1, b1, t):
    """Closed-form (angle, rate) at t of f'' = a(t), f(0) = a1, f'(0) = b1.

    rate = b1 + s d (min(t, t1) − max(t − t2, 0));
    angle = a1 + b1 t + s d (∫₀ᵗ min(τ, t1) dτ − max(t − t2, 0)²/2).

    Args:
      ctrl: ChannelControl (fields scalar or broadcast against t).
      a1: float [...], start angle [rad].
      b1: float [...], start rate [rad/s].
      t: float [...], times [s].
    Returns:
      (angle [rad], rate [rad/s]), float [...] each.
    """
    d = jnp.where(jnp.isfinite(ctrl.peak), ctrl.peak, 0.0)
    sd = ctrl.sign * d
    m = jnp.minimum(t, ctrl.t1)
    e = jnp.maximum(t - ctrl.t2, 0.0)
    rate = b1 + sd * (m - e)
    ang = a1 + b1 * t + sd * (0.5 * m * m + ctrl.t1 * jnp.maximum(t - ctrl.t1, 0.0) - 0.5 * e * e)
    return ang, rate


def min_peak_linear(angle_a, rate_a, angle_b, rate_b, T, rate=float("inf"), gain=1.0):
    """Vector minimum-peak control of decoupled double integrators (ν = ∞, paper eq. 21).

    Channel k: ``f_k'' = gain_k u_k``; the minimum of ``max_t max_k |u_k(t)|`` is
    ``max_k d*_k / |gain_k|`` and the per-channel minimum-peak controls realise it.

    Args:
      angle_a: float [..., K], start angle per channel [rad].
      angle_b: float [..., K], end angle per channel [rad].
      rate_a: float [..., K], start rate per channel [rad/s].
      rate_b: float [..., K], end rate per channel [rad/s].
      T: float [...], duration [s], broadcast over the leading axes.
      rate: float [K] or scalar, rate bound per channel [rad/s] (inf: none).
      gain: float [K] or scalar, [rad/s² per unit u], nonzero.
    Returns:
      (peak float [...] [units of u], ChannelControl with float [..., K] fields in rad/s²).
    Raises:
      ValueError: gain is zero or not finite, or as :func:`min_peak_channel`.
    """
    check_finite("gain", gain)
    if is_concrete(gain) and (np.asarray(gain) == 0).any():
        raise ValueError(f"gain must be nonzero, got {np.asarray(gain).tolist()!r}")
    T = jnp.asarray(T)
    ctrl = min_peak_channel(angle_a, rate_a, angle_b, rate_b, T[..., None], rate)
    peak = jnp.max(ctrl.peak / jnp.abs(jnp.asarray(gain, ctrl.peak.dtype)), axis=-1)
    return peak, ctrl
