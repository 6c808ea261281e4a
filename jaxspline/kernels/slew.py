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

import functools
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.batch import batched
from jaxspline.kernels.safe import pos_or_one, safe_sqrt
from jaxspline.kernels.validate import (
    cast_broadcast,
    check_finite,
    check_nonnegative,
    check_positive,
    is_concrete,
)

__all__ = [
    "KIND_CODES",
    "SlewProfile",
    "profile_state",
    "profile_state_kernel",
    "slew_profile",
    "slew_profile_kernel",
    "slew_profile_time",
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
    return jnp.where(phi > 0, 2.0 * jnp.sqrt(pos_or_one(phi) / accel), jnp.zeros_like(phi))


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
    t_tri = jnp.where(tri > 0, 2.0 * jnp.sqrt(pos_or_one(tri)), jnp.zeros_like(tri))
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
    t_small = jnp.where(q > 0, 4.0 * jnp.cbrt(pos_or_one(q)), jnp.zeros_like(q))
    t_large = 2.0 * (v_large / accel + accel / jerk)
    t_nocruise = jnp.where(small, t_small, t_large)
    # cruise duration
    v_c = jnp.where(cruise, rate, jnp.ones_like(rate))
    t_cruise = _scurve_acc_time(v_c, accel, jerk) + phi / v_c
    return jnp.where(cruise, t_cruise, t_nocruise)


_bang_bang_batched = batched(bang_bang_time_kernel)
_bang_coast_bang_batched = batched(bang_coast_bang_time_kernel)
_scurve_batched = batched(scurve_time_kernel)


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
    return _bang_bang_batched(*cast_broadcast(angle=angle, accel=accel))


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
    return _bang_coast_bang_batched(*cast_broadcast(angle=angle, rate=rate, accel=accel))


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
    return _scurve_batched(*cast_broadcast(angle=angle, rate=rate, accel=accel, jerk=jerk))


# ----------------------------------------------------------------------------
# eigen-axis profiles A, B, C, D (Belenkii, Semenov, Savelev)
# ----------------------------------------------------------------------------

#: integer codes of the profile kinds (``SlewProfile.kind``)
KIND_CODES = {"A": 0, "B": 1, "C": 2, "D": 3}
_KINDS = ("auto", "A", "B", "C", "D")


class SlewProfile(NamedTuple):
    """Parameters of a rest-to-rest eigen-axis slew profile (SPEC section 2 notation).

    The acceleration is, with eps the acceleration bound::

        [0, tau)               ramp 0 -> eps
        [.., + T)              hold eps
        [.., + tau)            ramp eps -> 0
        [.., + T1)             coast at the rate bound omega (profile D only)
        [.., + tau)            ramp 0 -> -eps
        [.., + T0)             linear return -eps -> 0
        duration = 3 tau + T + T0 + T1

    (``tau = 0`` turns the ramps into steps: profile B.)

    Attributes:
      kind: int code (``KIND_CODES``: A=0, B=1, C=2, D=3).
      tau: jerk-ramp time [s].
      T: constant-acceleration time [s].
      T0: braking return time [s].
      T1: coast time at omega [s].
      duration: total slew time T_d [s]; ``+inf`` if the forced kind does not
        exist for this angle (C outside [7/6, 2] omega^2/eps, D below its threshold).

    A NamedTuple, hence a pytree: fields may be arrays (one entry per candidate).
    """

    kind: jnp.ndarray
    tau: jnp.ndarray
    T: jnp.ndarray
    T0: jnp.ndarray
    T1: jnp.ndarray
    duration: jnp.ndarray


def slew_profile_kernel(angle, rate, accel, tau, kind: str = "auto"):
    """Profile A/B/C/D parameters for one rest-to-rest eigen-axis slew (one candidate).

    With ``a = phi/eps`` [s^2] and ``b = omega/eps`` [s]:

    * A (no const-accel phase, below omega): ``tau = sqrt(a/2), T = 0, T0 = tau``,
      ``T_d = sqrt(8a)`` (paper eq. 3 with the OCR error "sqrt(1/5)" corrected).
      Peak rate ``eps sqrt(a/2)`` reaches omega at ``a = 2 b^2``; forced "A"
      beyond that adds a coast ``T1 = a/b - 2b`` (= D with ``tau = b``).
    * B (reference, acceleration steps): ``tau = 0, T = sqrt(6a/7), T0 = 2T``,
      ``T_d = sqrt(54a/7)``; valid to ``a = 7/6 b^2``, forced "B" beyond adds a
      coast ``T1 = a/b - 7b/6`` (= D with ``tau = 0``).
    * C (``7/6 b^2 <= a <= 2 b^2``): ``tau = (6a/b - 7b)/5, T = b - tau,
      T0 = 2b - tau`` (eq. 2), ``T_d = 3 tau + T + T0 = 3b + tau``.
    * D (``a >= 5/6 tau b + 7/6 b^2``, tau in [0, b] given): ``T = b - tau,
      T0 = 2b - tau, T1 = a/b - 5 tau/6 - 7b/6`` (eq. 5),
      ``T_d = a/b + 11b/6 + tau/6``.

    ``kind="auto"`` (paper, Figs. 4 and 7): A for ``a <= 7/6 b^2``; otherwise D
    as soon as it exists (``a >= 5/6 tau b + 7/6 b^2``, the paper: "switch to D
    from the moment it exists"), else C. For the default ``tau = b`` the D
    threshold is exactly ``2 b^2`` (C up to 2 omega^2/eps, D beyond). For
    ``tau < b`` the regions of C and D overlap on ``[5/6 tau b + 7/6 b^2, 2 b^2]``
    (there is no gap: the D threshold is <= 2 b^2 whenever tau <= b); D is
    chosen there: its duration equals C's at the threshold and is shorter beyond
    (``T_d^D - T_d^C = 7b/30 + tau/6 - a/(5b)``). ``tau`` is clipped to [0, b].
    Note: the paper's auto rule has a 2 % jump of T_d at ``a = 7/6 b^2``
    (A: sqrt(28/3) b, C = B: 3b).

    Args:
      angle: slew angle phi [rad] (magnitude used).
      rate: rate bound omega [rad/s], > 0.
      accel: acceleration bound eps [rad/s^2], > 0.
      tau: ramp time of profile D [s] (used by kinds "D" and "auto").
      kind: static, one of "auto", "A", "B", "C", "D".
    Returns:
      ``(kind_code, tau, T, T0, T1, duration)`` (see :class:`SlewProfile`); a
      forced kind that does not exist has ``duration = +inf``.
    Reference: seeds/optimal-slew-profile-flexible-spacecraft, eqs. 1-5; SPEC section 2.
    """
    phi = jnp.abs(angle)
    a = phi / accel
    b = rate / accel
    z = jnp.zeros_like(a)
    inf = jnp.full_like(a, jnp.inf)
    thr_b = 7.0 / 6.0 * b * b
    # A (+ coast beyond 2 b^2)
    tau_a = jnp.minimum(safe_sqrt(0.5 * a), b)
    p_a = (tau_a, z, tau_a, jnp.maximum(a / b - 2.0 * b, 0.0), True)
    # B (+ coast beyond 7/6 b^2)
    t_b = jnp.minimum(safe_sqrt(6.0 / 7.0 * a), b)
    p_b = (z, t_b, 2.0 * t_b, jnp.maximum(a / b - 7.0 / 6.0 * b, 0.0), True)
    # C
    tau_c_raw = (6.0 * a / b - 7.0 * b) / 5.0
    tau_c = jnp.clip(tau_c_raw, 0.0, b)
    slack = 64.0 * jnp.finfo(a.dtype).eps * (b + a / b)  # rounding at the range ends
    ok_c = (tau_c_raw >= -slack) & (tau_c_raw <= b + slack)
    p_c = (tau_c, b - tau_c, 2.0 * b - tau_c, z, ok_c)
    # D
    tau_d = jnp.clip(tau, 0.0, b)
    t1_raw = a / b - 5.0 / 6.0 * tau_d - 7.0 / 6.0 * b
    p_d = (tau_d, b - tau_d, 2.0 * b - tau_d, jnp.maximum(t1_raw, 0.0), t1_raw >= -slack)

    def pack(code, p):
        t, tt, t0, t1, ok = p
        dur = jnp.where(ok, 3.0 * t + tt + t0 + t1, inf)
        return (jnp.full(jnp.shape(a), code, jnp.int32), t, tt, t0, t1, dur)

    if kind != "auto":
        code = KIND_CODES[kind]
        return pack(code, (p_a, p_b, p_c, p_d)[code])
    use_a = a <= thr_b
    use_d = (~use_a) & (t1_raw >= 0.0)
    # the auto choice always exists (up to rounding): no +inf from the range checks
    out_a, out_c, out_d = pack(0, p_a), pack(2, p_c[:4] + (True,)), pack(3, p_d[:4] + (True,))
    return tuple(
        jnp.where(use_a, xa, jnp.where(use_d, xd, xc))
        for xa, xc, xd in zip(out_a, out_c, out_d, strict=True)
    )


_profile_batched = {k: batched(functools.partial(slew_profile_kernel, kind=k)) for k in _KINDS}


def slew_profile(angle, rate, accel, tau=None, kind: str = "auto") -> SlewProfile:
    """Eigen-axis rest-to-rest slew profile A/B/C/D (broadcasting public wrapper).

    Args:
      angle: slew angle(s) phi [rad], >= 0.
      rate: rate bound(s) omega [rad/s], > 0.
      accel: acceleration bound(s) eps [rad/s^2], > 0.
      tau: ramp time of profile D [s], 0 <= tau <= omega/eps; default omega/eps
        (then C covers [7/6, 2] omega^2/eps and D begins at 2 omega^2/eps).
      kind: "auto" (paper's choice A / C / D, see :func:`slew_profile_kernel`)
        or a forced "A", "B", "C", "D" (static).
    Returns:
      :class:`SlewProfile` with broadcast array fields.
    Raises:
      ValueError: naming ``kind``, ``angle``, ``rate``, ``accel`` or ``tau``.
    Reference: SPEC section 2; paper eqs. 2, 3, 5.
    """
    if kind not in _KINDS:
        raise ValueError(f"kind must be one of {_KINDS}, got {kind!r}")
    _check_angle(angle)
    check_positive("rate", rate)
    check_positive("accel", accel)
    if tau is None:
        tau = jnp.asarray(rate) / jnp.asarray(accel)
    else:
        check_nonnegative("tau", tau)
        if is_concrete(tau) and is_concrete(rate) and is_concrete(accel):
            over = np.asarray(tau) > np.asarray(rate) / np.asarray(accel) * (1 + 1e-12)
            if over.any():
                raise ValueError(
                    f"tau must be <= rate/accel (T = omega/eps - tau >= 0), got tau={tau!r}"
                )
    out = _profile_batched[kind](*cast_broadcast(angle=angle, rate=rate, accel=accel, tau=tau))
    return SlewProfile(*out)


def slew_profile_time(angle, rate, accel, tau=None, kind: str = "auto"):
    """Duration T_d of :func:`slew_profile` (same arguments).

    Args:
      angle: slew angle(s) phi [rad], >= 0.
      rate: rate bound(s) omega [rad/s], > 0.
      accel: acceleration bound(s) eps [rad/s^2], > 0.
      tau: ramp time of profile D [s]; default omega/eps.
      kind: "auto", "A", "B", "C" or "D" (static).
    Returns:
      float [...] (broadcast shape), T_d [s].
    Raises:
      ValueError: as :func:`slew_profile`.
    """
    return slew_profile(angle, rate, accel, tau, kind).duration


# ----------------------------------------------------------------------------
# time history of a profile
# ----------------------------------------------------------------------------


def _ramp_integrals(t, t0, t1):
    """Unit ramp 0 -> 1 on [t0, t1] (a step if t1 == t0) and its 1st/2nd integrals."""
    d = t1 - t0
    d_s = pos_or_one(d)
    u = jnp.clip(t - t0, 0.0, jnp.maximum(d, 0.0))  # time spent inside the ramp
    w = jnp.maximum(t - t1, 0.0)  # time after the ramp
    after = t >= t1
    r0 = jnp.where(after, jnp.ones_like(u), u / d_s)
    r1 = jnp.where(after, 0.5 * d + w, u * u / (2.0 * d_s))
    r2 = jnp.where(after, d * d / 6.0 + 0.5 * d * w + 0.5 * w * w, u * u * u / (6.0 * d_s))
    return r0, r1, r2


def profile_state_kernel(tau, T, T0, T1, accel, t):
    """Acceleration, rate and angle of a profile at time t (one candidate, one time).

    The acceleration is a sum of four unit ramps (see :class:`SlewProfile`)::

        eps(t) = eps [r(t; 0, tau) - r(t; tau+T, 2tau+T)
                      - r(t; 2tau+T+T1, 3tau+T+T1) + r(t; 3tau+T+T1, 3tau+T+T1+T0)]

    and rate / angle use the closed-form first / second integrals of each ramp
    (exact, no cancellation for tiny tau). Before 0 everything is 0; after the
    end the state holds (accel 0, rate 0 for A-D, angle phi).

    Args:
      tau: jerk-ramp time of the profile [s].
      T: constant-acceleration time [s].
      T0: braking return time [s].
      T1: coast time at the rate bound [s].
      accel: acceleration bound eps [rad/s^2].
      t: time since the slew start [s].
    Returns:
      ``(accel_t [rad/s^2], rate_t [rad/s], angle_t [rad])``.
    Reference: paper Figs. 1, 3; SPEC section 2.
    """
    s1 = tau + T
    s2 = s1 + tau + T1
    s3 = s2 + tau
    ramps = [(0.0 * tau, tau, 1.0), (s1, s1 + tau, -1.0), (s2, s3, -1.0), (s3, s3 + T0, 1.0)]
    acc = rate = ang = jnp.zeros(jnp.broadcast_shapes(jnp.shape(t), jnp.shape(tau)), t.dtype)
    for t0, t1, sgn in ramps:
        r0, r1, r2 = _ramp_integrals(t, t0, t1)
        acc, rate, ang = acc + sgn * r0, rate + sgn * r1, ang + sgn * r2
    return accel * acc, accel * rate, accel * ang


_state_batched = batched(profile_state_kernel)


def profile_state(profile: SlewProfile, accel, t):
    """Acceleration, rate and angle of a slew profile at times t (broadcasting).

    Args:
      profile: :class:`SlewProfile` (e.g. from :func:`slew_profile`).
      accel: acceleration bound eps [rad/s^2] used to build the profile.
      t: time(s) since the slew start [s]; broadcast against the profile fields.
    Returns:
      ``(accel_t [rad/s^2], rate_t [rad/s], angle_t [rad])``.
    Raises:
      ValueError: naming ``accel`` or ``t``.
    See :func:`profile_state_kernel`.
    """
    check_positive("accel", accel)
    check_finite("t", t)
    args = cast_broadcast(
        tau=profile.tau, T=profile.T, T0=profile.T0, T1=profile.T1, accel=accel, t=t
    )
    return _state_batched(*args)
