"""Peak rate, acceleration and jerk of a degree-7 join written channel by channel.

The join of SPEC section 3 between two states (angle, rate, acceleration, jerk at
both ends of [0, T]) is, in each channel, the unique degree-7 polynomial
``p(τ) = Σ_k c_k τ^k`` (τ = t / T) with ``c = H b``, ``b`` the boundary derivatives
with respect to τ (``p, T p', T² p'', T³ p'''`` at τ = 0, then at τ = 1) and ``H``
the exact inverse of the Hermite conditions (:mod:`jaxspline.kernels.joins`).
Its derivatives are polynomials again, so their peaks over [0, T] are read on a
uniform grid of τ (``n_samples`` points including both ends).

The engine screens candidate transitions with it (:mod:`jaxspline.planner.join_screen`):
the spatial join the plan finally flies is the same polynomial in the MRP chart of
the attitude, and in the per-channel angles its peaks are close to these (the
flown join is checked exactly afterwards).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.joins import HERMITE_MAP
from jaxspline.kernels.safe import safe_norm

__all__ = ["channel_join_peaks", "DEFAULT_JOIN_SAMPLES"]

DEFAULT_JOIN_SAMPLES = 33  # grid of τ for the peaks (the polynomials have degree <= 6)


class ChannelJoinPeaks(NamedTuple):
    """Peaks of one channel-wise degree-7 join over [0, T].

    Attributes:
      rate, accel, jerk: float [C], max over the grid of |p'|, |p''|, |p'''| per
        channel [unit/s, unit/s², unit/s³].
      rate_norm, accel_norm, jerk_norm: float scalars, max over the grid of the
        Euclidean norm over channels of p', p'', p'''.
    """

    rate: jnp.ndarray
    accel: jnp.ndarray
    jerk: jnp.ndarray
    rate_norm: jnp.ndarray
    accel_norm: jnp.ndarray
    jerk_norm: jnp.ndarray


def _derivative_grid(n_samples: int) -> np.ndarray:
    """[3, 8, n] values of d^m/dτ^m τ^k (m = 1, 2, 3) on the uniform grid of [0, 1]."""
    tau = np.linspace(0.0, 1.0, n_samples)
    k = np.arange(8)[:, None]
    out = np.zeros((3, 8, n_samples))
    for m in (1, 2, 3):
        fall = np.ones((8, 1))
        for i in range(m):
            fall = fall * (k - i)
        out[m - 1] = np.where(k >= m, fall * tau[None, :] ** np.maximum(k - m, 0), 0.0)
    return out


def channel_join_peaks(p0, v0, a0, j0, p1, v1, a1, j1, T, n_samples=DEFAULT_JOIN_SAMPLES):
    """Kernel: peaks of the channel-wise degree-7 join of one transition.

    ``c = H [p0, T v0, T² a0, T³ j0, p1, T v1, T² a1, T³ j1]`` per channel
    (SPEC section 3, eqs. of the "optimal conjugation": θ⁽⁸⁾ = 0 on [0, T]);
    ``p^(m)(t) = T^-m Σ_k c_k d^m τ^k / dτ^m``, read on ``n_samples`` uniform τ.
    A duration ``T <= 0`` is no join: every peak is +inf (never NaN).

    Args:
      p0: float [C], angle per channel at t = 0 [rad].
      v0: float [C], rate at t = 0 [rad/s].
      a0: float [C], acceleration at t = 0 [rad/s²].
      j0: float [C], jerk at t = 0 [rad/s³].
      p1: float [C], angle at t = T [rad].
      v1: float [C], rate at t = T [rad/s].
      a1: float [C], acceleration at t = T [rad/s²].
      j1: float [C], jerk at t = T [rad/s³].
      T: float scalar, duration [s].
      n_samples: static int >= 2, grid points of τ in [0, 1].
    Returns:
      ChannelJoinPeaks, a NamedTuple: ``rate``, ``accel``, ``jerk`` float [C], the
      peaks of |p'|, |p''|, |p'''| per channel, and ``rate_norm``, ``accel_norm``,
      ``jerk_norm``, the peaks of their Euclidean norms over channels.
    """
    good = T > 0
    Ts = jnp.where(good, T, jnp.ones_like(T))
    b = jnp.stack(
        [p0, Ts * v0, Ts**2 * a0, Ts**3 * j0, p1, Ts * v1, Ts**2 * a1, Ts**3 * j1], axis=-1
    )
    c = b @ jnp.asarray(HERMITE_MAP.T, dtype=b.dtype)  # [C, 8] monomial coefficients
    grid = jnp.asarray(_derivative_grid(n_samples), dtype=b.dtype)
    inf = jnp.asarray(jnp.inf, dtype=b.dtype)
    peaks, norms = [], []
    for m in range(3):
        d = (c @ grid[m]) / Ts ** (m + 1)  # [C, n] physical m+1-th derivative
        peaks.append(jnp.where(good, jnp.max(jnp.abs(d), axis=-1), inf))
        norms.append(jnp.where(good, jnp.max(safe_norm(d.T)), inf))
    return ChannelJoinPeaks(*peaks, *norms)
