"""Eigen-axis rest-to-rest slew models (SPEC section 2).

Two families live here:

* classic rigid-body time-optimal models: bang-bang, bang-coast-bang
  (rate + acceleration limited) and the jerk-limited S-curve;
* the continuous-acceleration profiles A, B, C, D of Belenkii, Semenov,
  Savelev, "Selection of the optimal profile of a spacecraft slew towards an
  imaging target" (seeds/optimal-slew-profile-flexible-spacecraft.ru.txt),
  designed so that the acceleration has no steps and the last jerk
  discontinuity is as early as possible (a flexible structure then rings less).

Units: radians, seconds (rad/s, rad/s^2, rad/s^3). Every ``*_kernel`` is a pure,
branchless function of one candidate; the public wrappers validate concrete
inputs (ValueError naming the argument) and broadcast.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxspline._validate import (
    as_float_array,
    broadcast_named,
    check_nonnegative,
    check_positive,
    float_dtype_of,
)

__all__ = [
    "bang_bang_time",
    "bang_bang_time_kernel",
    "bang_coast_bang_time",
    "bang_coast_bang_time_kernel",
    "scurve_time",
    "scurve_time_kernel",
]


# ----------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------


def _pos(x):
    """Double-where guard: ``x`` where it is > 0, else 1 (safe for sqrt / division)."""
    return jnp.where(x > 0, x, jnp.ones_like(x))


def _prep(**named):
    """Cast named inputs to one common float dtype and broadcast them."""
    dt = float_dtype_of(*named.values())
    arrs = {k: as_float_array(k, v, dt) for k, v in named.items()}
    return broadcast_named(**arrs)


# ----------------------------------------------------------------------------
# rigid-body time-optimal models
# ----------------------------------------------------------------------------


def bang_bang_time_kernel(angle, accel):
    """Rest-to-rest bang-bang slew time ``t = 2 sqrt(|phi| / eps)`` (one candidate).

    Args:
      angle: slew angle phi [rad] (its magnitude is used).
      accel: acceleration bound eps [rad/s^2], > 0.
    Returns:
      duration [s]; 0 at phi = 0 with a finite (zero) gradient there.
    Reference: SPEC section 2 (rigid-body models).
    """
    phi = jnp.abs(angle)
    return jnp.where(phi > 0, 2.0 * jnp.sqrt(_pos(phi) / accel), jnp.zeros_like(phi))


def bang_coast_bang_time_kernel(angle, rate, accel):
    """Rest-to-rest bang-coast-bang slew time (rate + acceleration limited, one candidate).

    ``t = 2 sqrt(phi/eps)`` if ``phi <= omega^2/eps`` (triangular rate profile),
    else ``t = phi/omega + omega/eps`` (trapezoid with a coast at omega).

    Args:
      angle: slew angle phi [rad] (its magnitude is used).
      rate: rate bound omega [rad/s], > 0 (``inf`` gives bang-bang).
      accel: acceleration bound eps [rad/s^2], > 0.
    Returns:
      duration [s]; finite value and gradient everywhere, incl. phi = 0 and the
      switch ``phi = omega^2/eps``.
    Reference: SPEC section 2 (classic rigid-body models).
    """
    phi = jnp.abs(angle)
    coast = phi > rate * rate / accel
    tri = bang_bang_time_kernel(jnp.where(coast, jnp.zeros_like(phi), phi), accel)
    w = jnp.where(coast, rate, jnp.ones_like(rate))
    trap = phi / w + w / accel
    return jnp.where(coast, trap, tri)


def _scurve_acc_time(v, accel, jerk):
    """Time to go from rest to rate v (> 0) under accel/jerk bounds, time-optimally."""
    full = v >= accel * accel / jerk
    v_tri = jnp.where(full, jnp.ones_like(v), v)
    v_full = jnp.where(full, v, jnp.ones_like(v))
    tri = v_tri / jerk
    t_tri = jnp.where(tri > 0, 2.0 * jnp.sqrt(_pos(tri)), jnp.zeros_like(tri))
    return jnp.where(full, v_full / accel + accel / jerk, t_tri)


def scurve_time_kernel(angle, rate, accel, jerk):
    """Rest-to-rest time-optimal jerk-limited (S-curve, 7-segment) slew time, one candidate.

    With V = rate, A = accel, J = jerk and t_a(v) the optimal time from rest to
    rate v (``t_a = v/A + A/J`` if ``v >= A^2/J`` else ``2 sqrt(v/J)``), the
    distance covered by accelerating to v and back to rest is ``v t_a(v)``
    (increasing in v). Sub-cases:

    * jerk phases only (no constant-acceleration, no cruise), when
      ``phi <= 2 A^3/J^2`` and the peak rate ``(phi^2 J / 4)^(1/3) <= V``:
      ``t = 4 (phi/(2J))^(1/3)``;
    * with a constant-acceleration phase, no cruise: peak rate
      ``v = (-A^2/J + sqrt(A^4/J^2 + 4 A phi))/2 <= V``, ``t = 2 (v/A + A/J)``;
    * with a cruise at V (``phi > V t_a(V)``): ``t = t_a(V) + phi/V``
      (covers both "with" and "without" constant-acceleration phase via t_a).

    ``jerk = inf`` reduces to bang-coast-bang, ``rate = inf`` to the
    unbounded-rate S-curve.

    Args:
      angle: slew angle phi [rad] (its magnitude is used).
      rate: rate bound V [rad/s], > 0 (inf allowed).
      accel: acceleration bound A [rad/s^2], > 0.
      jerk: jerk bound J [rad/s^3], > 0 (inf allowed).
    Returns:
      duration [s]; finite value and gradient everywhere (zero gradient at phi = 0).
    Reference: SPEC section 2 (rigid-body family); standard third-order
    time-optimal rest-to-rest profile (agrees with Ruckig, see tests).
    """
    phi = jnp.abs(angle)
    a2j = accel * accel / jerk  # rate gained by a pure jerk-up/jerk-down pulse
    phi1 = 2.0 * accel * a2j / jerk  # 2 A^3 / J^2: largest angle without const-accel phase
    # unbounded-rate peak velocity
    small = phi <= phi1
    phi_s = jnp.where(small, phi, jnp.zeros_like(phi))
    phi_l = jnp.where(small, jnp.zeros_like(phi), phi)
    v_small = jnp.cbrt(0.25 * phi_s * phi_s * jerk)
    disc = jnp.where(small, jnp.ones_like(phi), a2j * a2j + 4.0 * accel * phi_l)
    v_large = 0.5 * (-a2j + jnp.sqrt(disc))
    v_unb = jnp.where(small, v_small, v_large)
    cruise = v_unb > rate
    # no-cruise durations
    q = 0.5 * phi_s / jerk
    t_small = jnp.where(q > 0, 4.0 * jnp.cbrt(_pos(q)), jnp.zeros_like(q))
    t_large = 2.0 * (v_large / accel + accel / jerk)
    t_nocruise = jnp.where(small, t_small, t_large)
    # cruise duration
    v_c = jnp.where(cruise, rate, jnp.ones_like(rate))
    t_cruise = _scurve_acc_time(v_c, accel, jerk) + phi / v_c
    return jnp.where(cruise, t_cruise, t_nocruise)


_bang_bang_batched = jax.jit(jnp.vectorize(bang_bang_time_kernel))
_bang_coast_bang_batched = jax.jit(jnp.vectorize(bang_coast_bang_time_kernel))
_scurve_batched = jax.jit(jnp.vectorize(scurve_time_kernel))


def _check_angle(angle):
    check_nonnegative("angle", angle)


def bang_bang_time(angle, accel):
    """Rest-to-rest bang-bang slew time ``t = 2 sqrt(phi/eps)`` [s], broadcasting.

    Args:
      angle: slew angle(s) phi [rad], >= 0.
      accel: acceleration bound(s) eps [rad/s^2], > 0.
    Raises:
      ValueError: naming ``angle`` or ``accel`` for negative / non-finite values.
    See :func:`bang_bang_time_kernel`.
    """
    _check_angle(angle)
    check_positive("accel", accel)
    return _bang_bang_batched(*_prep(angle=angle, accel=accel))


def bang_coast_bang_time(angle, rate, accel):
    """Rest-to-rest bang-coast-bang slew time [s], broadcasting.

    ``t = 2 sqrt(phi/eps)`` if ``phi <= omega^2/eps`` else ``phi/omega + omega/eps``.

    Args:
      angle: slew angle(s) phi [rad], >= 0.
      rate: rate bound(s) omega [rad/s], > 0 (inf allowed).
      accel: acceleration bound(s) eps [rad/s^2], > 0.
    Raises:
      ValueError: naming the offending argument.
    See :func:`bang_coast_bang_time_kernel`.
    """
    _check_angle(angle)
    check_positive("rate", rate, allow_inf=True)
    check_positive("accel", accel)
    return _bang_coast_bang_batched(*_prep(angle=angle, rate=rate, accel=accel))


def scurve_time(angle, rate, accel, jerk):
    """Rest-to-rest time-optimal jerk-limited (S-curve) slew time [s], broadcasting.

    Args:
      angle: slew angle(s) phi [rad], >= 0.
      rate: rate bound(s) [rad/s], > 0 (inf allowed).
      accel: acceleration bound(s) [rad/s^2], > 0.
      jerk: jerk bound(s) [rad/s^3], > 0 (inf allowed: bang-coast-bang).
    Raises:
      ValueError: naming the offending argument.
    See :func:`scurve_time_kernel` for the formula and sub-cases.
    """
    _check_angle(angle)
    check_positive("rate", rate, allow_inf=True)
    check_positive("accel", accel)
    check_positive("jerk", jerk, allow_inf=True)
    return _scurve_batched(*_prep(angle=angle, rate=rate, accel=accel, jerk=jerk))
