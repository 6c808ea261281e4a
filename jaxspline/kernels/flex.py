"""One flexible structural mode excited by a slew profile (SPEC section 2).

Two parts:

* the paper's design rule for the jerk-ramp time tau of profile D: residual
  amplitude ``A(0) = eps/(tau nu^3)`` (eq. 6), decayed by
  ``exp(-zeta nu (2 omega/eps - tau)/(2 pi))`` (eq. 7), solved for tau;
* an exact (closed-form) response of a rigid body with one elastic mode to a
  profile's acceleration, for the paper's settling comparison of profiles A and B.

Model of the simulator (two-body / hybrid-coordinate model, axis of the slew):
a rigid body (hub) of inertia J_b carries an elastic appendage whose modal
inertia is J_m = r J_b (r = ``inertia_ratio``, the paper's "effective inertia of
the elastic mode relative to the spacecraft inertia", 0.1). The attitude
control applies the feed-forward torque ``u(t) = (J_b + J_m) eps(t)`` that would
give the whole (rigid) spacecraft the profile acceleration eps(t). With the
hub angle theta (what the gyros measure: "body rate" = theta') and the elastic
angle e of the appendage relative to the hub (stiffness J_m nu_c^2, damping
2 zeta_c nu_c J_m, i.e. nu_c, zeta_c of the appendage clamped to the hub)::

    J_b theta''         = u + J_m (2 zeta_c nu_c e' + nu_c^2 e)     (hub)
    J_m (theta'' + e'') =   - J_m (2 zeta_c nu_c e' + nu_c^2 e)     (appendage)

Eliminating the hub, ``y = -J_m e/(J_b + J_m)`` (the elastic part of the hub
angle) obeys the single oscillator

    y'' + 2 zeta nu y' + nu^2 y = k eps(t),     theta'(t) = omega_ref(t) + y'(t)

with nu, zeta the circular frequency and damping of the coupled (free-free)
mode, k = J_m/J_b = r (``ratio_of="body"``, default) or, if r is read as
J_m/(J_b + J_m), k = r/(1 - r) (``ratio_of="total"``). If the given frequency
and damping are those of the appendage clamped to the hub
(``freq_convention="constrained"``), ``nu = nu_c sqrt(1 + k)`` and
``zeta = zeta_c sqrt(1 + k)``. omega_ref(t) is the profile's rate (the rigid
rate). Because eps(t) is a sum of linear ramps
(:func:`jaxspline.kernels.slew.profile_state_kernel`), y'(t) is a closed-form sum of
step responses: no time stepping.

Units: radians, seconds; frequencies are circular [rad/s] (2 Hz = 4 pi rad/s).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.batch import batched
from jaxspline.kernels.safe import pos_or_one
from jaxspline.kernels.slew import SlewProfile, profile_state_kernel
from jaxspline.kernels.validate import (
    cast_broadcast,
    check_finite,
    check_nonnegative,
    check_positive,
    is_concrete,
)

__all__ = [
    "initial_amplitude",
    "residual_amplitude",
    "min_mode_frequency",
    "mode_suppressible",
    "tau_for_tolerance",
    "tau_for_tolerance_kernel",
    "mode_rate_kernel",
    "flexible_body_rate",
    "settling_time",
]


# ----------------------------------------------------------------------------
# the paper's tau design rule (eqs. 6, 7)
# ----------------------------------------------------------------------------


def _residual_kernel(tau, freq, damping, rate, accel):
    b = rate / accel
    a0 = accel / (pos_or_one(tau) * freq**3)
    a0 = jnp.where(tau > 0, a0, jnp.full_like(a0, jnp.inf))
    return a0 * jnp.exp(-damping * freq * (2.0 * b - tau) / (2.0 * jnp.pi))


def initial_amplitude(tau, freq, accel):
    """Residual modal amplitude after a jerk ramp, ``A(0) = eps/(tau nu^3)`` [rad].

    Args:
      tau: ramp time 0 -> eps [s], > 0.
      freq: circular frequency nu of the mode [rad/s], > 0.
      accel: acceleration eps reached by the ramp [rad/s^2], > 0.
    Reference: paper eq. 6; SPEC section 2.
    """
    check_positive("tau", tau)
    check_positive("freq", freq)
    check_positive("accel", accel)
    tau, freq, accel = cast_broadcast(tau=tau, freq=freq, accel=accel)
    return accel / (tau * freq**3)


def residual_amplitude(tau, freq, damping, rate, accel):
    """Amplitude at the end of the slew, eq. 7 [rad]:

    ``A(t_k) = eps/(tau nu^3) exp(-zeta nu (2 omega/eps - tau)/(2 pi))``.

    The paper's decay exponent has the factor 1/(2 pi) (decay per cycle time
    2 omega/eps - tau counted in Hz); a physical envelope would be
    ``exp(-zeta nu t)``. Kept as printed (SPEC section 2).

    Args:
      tau: ramp time [s], > 0 (``+inf`` amplitude at 0).
      freq: circular frequency nu [rad/s], > 0.
      damping: damping ratio zeta, >= 0.
      rate: rate bound omega [rad/s], > 0.
      accel: acceleration bound eps [rad/s^2], > 0.
    Reference: paper eq. 7.
    """
    check_nonnegative("tau", tau)
    check_positive("freq", freq)
    check_nonnegative("damping", damping)
    check_positive("rate", rate)
    check_positive("accel", accel)
    args = cast_broadcast(tau=tau, freq=freq, damping=damping, rate=rate, accel=accel)
    return _residual_batched(*args)


_residual_batched = batched(_residual_kernel)


def min_mode_frequency(tolerance, rate, accel):
    """Sufficient mode frequency for eq. 7 to have a root tau <= omega/eps [rad/s]:

    ``nu > (eps^2 / (omega A(t_k)))^(1/3)`` (the paper's condition
    ``f1(omega/eps) > f2(omega/eps)`` with the damping factor bounded by 1).

    Args:
      tolerance: admissible amplitude A(t_k) [rad], > 0.
      rate: rate bound omega [rad/s], > 0.
      accel: acceleration bound eps [rad/s^2], > 0.
    Reference: paper, text after eq. 7 (example: 15.2 rad/s for 1e-7, 0.035, 0.0035).
    """
    check_positive("tolerance", tolerance)
    check_positive("rate", rate)
    check_positive("accel", accel)
    tolerance, rate, accel = cast_broadcast(tolerance=tolerance, rate=rate, accel=accel)
    return jnp.cbrt(accel**2 / (rate * tolerance))


def tau_for_tolerance_kernel(tolerance, freq, damping, rate, accel, iters: int = 80):
    """Smallest ramp time tau in (0, omega/eps] with ``A(t_k; tau) <= tolerance`` (eq. 7).

    Eq. 7 in logs: ``h(tau) = ln tau - c tau - K = 0`` with ``c = zeta nu/(2 pi)``
    and ``K = ln(eps/(A nu^3)) - 2 c omega/eps``. h increases on (0, 1/c), so the
    smallest root (the fastest admissible profile D, whose duration grows with
    tau) is found by bisection in log tau on (0, min(omega/eps, 1/c)], followed
    by one Newton step that carries the exact implicit-function gradient. (For
    strong damping the root can be astronomically small, ~exp(K): any ramp meets
    the tolerance.)
    For zeta = 0: ``tau* = eps/(A nu^3)``.

    Args:
      tolerance: admissible residual amplitude A(t_k) [rad], > 0.
      freq: circular mode frequency nu [rad/s], > 0.
      damping: damping ratio zeta, >= 0.
      rate: rate bound omega [rad/s], > 0.
      accel: acceleration bound eps [rad/s^2], > 0.
      iters: bisection steps (static).
    Returns:
      tau* [s], or ``+inf`` if no tau <= omega/eps meets the tolerance.
    Reference: paper eqs. 6-7, Fig. 8; SPEC section 2.
    """
    b = rate / accel
    c = damping * freq / (2.0 * jnp.pi)
    k = jnp.log(accel / (tolerance * freq**3)) - 2.0 * c * b
    hi = jnp.where(c * b > 1.0, 1.0 / pos_or_one(c), b)

    def h(tau):
        return jnp.log(tau) - c * tau - k

    exists = h(hi) >= 0.0
    hi_log = jnp.log(hi)
    lo_log = jnp.minimum(k, hi_log) - 5.0  # h(exp(k - 5)) < 0: a bracket

    def body(_, lh):
        lo, up = lh
        mid = 0.5 * (lo + up)
        pos = h(jnp.exp(mid)) >= 0.0
        return jnp.where(pos, lo, mid), jnp.where(pos, mid, up)

    lo, up = jax.lax.fori_loop(0, iters, body, (lo_log, hi_log))
    tau0 = jax.lax.stop_gradient(jnp.maximum(jnp.exp(up), jnp.finfo(up.dtype).tiny))
    # one Newton step: value ~unchanged (h concave: never past 0), exact implicit gradient
    tau1 = jnp.maximum(tau0 - h(tau0) / (1.0 / tau0 - c), 0.5 * tau0)
    return jnp.where(exists, tau1, jnp.full_like(tau1, jnp.inf))


_tau_batched = batched(tau_for_tolerance_kernel)


def mode_suppressible(
    tolerance: float, freq: float, damping: float, rate: float, accel: float
) -> bool:
    """Whether some ramp time tau <= omega/eps holds the mode to its tolerance (eq. 7).

    The existence test of :func:`tau_for_tolerance_kernel` (``h`` at the top of the
    bracket is >= 0) for one satellite, in plain floats: no JAX program, so a scenario
    reader can refuse an unsuppressible mode at once, before any planning. Where it is
    false, :func:`tau_for_tolerance` returns ``+inf``.

    Args:
      tolerance: admissible residual amplitude A(t_k) [rad], > 0.
      freq: circular mode frequency nu [rad/s], > 0.
      damping: damping ratio zeta, >= 0.
      rate: rate bound omega [rad/s], > 0.
      accel: acceleration bound eps [rad/s^2], > 0.
    Returns:
      bool.
    """
    b = rate / accel
    c = damping * freq / (2.0 * math.pi)
    k = math.log(accel / (tolerance * freq**3)) - 2.0 * c * b
    hi = 1.0 / c if c * b > 1.0 else b
    return math.log(hi) - c * hi - k >= 0.0


def tau_for_tolerance(tolerance, freq, damping, rate, accel):
    """Ramp time tau of profile D from one flexible mode (eq. 7), broadcasting.

    See :func:`tau_for_tolerance_kernel`. Returns ``+inf`` where no
    tau <= omega/eps exists (sufficient condition for existence:
    ``freq > min_mode_frequency(tolerance, rate, accel)``).

    Raises:
      ValueError: naming the offending argument.
    """
    check_positive("tolerance", tolerance)
    check_positive("freq", freq)
    check_nonnegative("damping", damping)
    check_positive("rate", rate)
    check_positive("accel", accel)
    args = cast_broadcast(tolerance=tolerance, freq=freq, damping=damping, rate=rate, accel=accel)
    return _tau_batched(*args)


# ----------------------------------------------------------------------------
# closed-form response of one elastic mode
# ----------------------------------------------------------------------------


def _step_response(t, freq, damping):
    """Unit-step response y_s and its derivative (impulse response) of
    ``y'' + 2 zeta nu y' + nu^2 y = H(t)``, zero for t <= 0 (0 <= zeta < 1)."""
    nd = freq * jnp.sqrt(1.0 - damping * damping)
    tp = jnp.maximum(t, 0.0)
    env = jnp.exp(-damping * freq * tp)
    cs, sn = jnp.cos(nd * tp), jnp.sin(nd * tp)
    ys = (1.0 - env * (cs + damping * freq / nd * sn)) / freq**2
    yd = env * sn / nd
    on = t > 0
    return jnp.where(on, ys, 0.0 * ys), jnp.where(on, yd, 0.0 * yd)


def mode_rate_kernel(tau, T, T0, T1, accel, t, freq, damping, gain):
    """Elastic rate y'(t) of ``y'' + 2 zeta nu y' + nu^2 y = k eps(t)`` (one candidate, one time).

    eps(t) is the profile's acceleration, a signed sum of unit ramps
    ``(R(t - t0) - R(t - t1))/(t1 - t0)`` (R the unit ramp function), so
    ``y'(t) = k eps sum_i s_i (y_s(t - t0_i) - y_s(t - t1_i))/(t1_i - t0_i)``
    with y_s the unit-step response; a ramp shorter than 1e-5/nu (profile B's
    steps) uses the impulse response at the ramp midpoint instead (no
    cancellation). Zero initial conditions (body at rest, mode at rest).

    Args:
      tau: jerk-ramp time of the profile [s] (:class:`jaxspline.kernels.slew.SlewProfile`).
      T: constant-acceleration time [s].
      T0: braking return time [s].
      T1: coast time at the rate bound [s].
      accel: acceleration bound eps [rad/s^2].
      t: time since the slew start [s].
      freq: coupled (free-free) circular frequency nu [rad/s], > 0.
      damping: coupled damping ratio zeta, 0 <= zeta < 1.
      gain: k = J_mode / J_body (see module docstring).
    Returns:
      y'(t) [rad/s]; the body (hub) rate is ``omega_ref(t) + y'(t)``.
    Reference: module docstring; paper Figs. 5-6 (settling comparison).
    """
    s1 = tau + T
    s2 = s1 + tau + T1
    s3 = s2 + tau
    ramps = [(0.0 * tau, tau, 1.0), (s1, s1 + tau, -1.0), (s2, s3, -1.0), (s3, s3 + T0, 1.0)]
    out = jnp.zeros(jnp.broadcast_shapes(jnp.shape(t), jnp.shape(tau)), jnp.result_type(t, tau))
    for t0, t1, sgn in ramps:
        d = t1 - t0
        wide = d * freq > 1e-5
        y0, _ = _step_response(t - t0, freq, damping)
        y1, _ = _step_response(t - t1, freq, damping)
        _, hm = _step_response(t - t0 - 0.5 * d, freq, damping)
        d_s = jnp.where(wide, d, jnp.ones_like(d))
        out = out + sgn * jnp.where(wide, (y0 - y1) / d_s, hm)
    return gain * accel * out


def _body_rate_kernel(tau, T, T0, T1, accel, t, freq, damping, gain):
    _, w_ref, _ = profile_state_kernel(tau, T, T0, T1, accel, t)
    return w_ref + mode_rate_kernel(tau, T, T0, T1, accel, t, freq, damping, gain)


_body_rate_batched = batched(_body_rate_kernel)


def flexible_body_rate(
    profile: SlewProfile,
    accel,
    t,
    freq,
    damping,
    inertia_ratio,
    *,
    freq_convention: str = "free",
    ratio_of: str = "body",
):
    """Body (hub) rate of a spacecraft with one elastic mode slewing by a profile.

    ``theta'(t) = omega_ref(t) + y'(t)`` with ``y'' + 2 zeta nu y' + nu^2 y = k eps(t)``
    (exact closed form, see the module docstring for the model and conventions).

    Args:
      profile: :class:`jaxspline.kernels.slew.SlewProfile` (rest-to-rest).
      accel: the profile's acceleration bound eps [rad/s^2].
      t: sample times [s] (broadcast against the profile fields).
      freq: circular frequency of the mode [rad/s] (2 Hz = 4 pi).
      damping: damping ratio, 0 <= zeta < 1.
      inertia_ratio: modal inertia ratio r, >= 0.
      freq_convention: "free" (freq, damping are the coupled free-free mode's,
        default) or "constrained" (appendage clamped to the hub).
      ratio_of: "body" (r = J_mode/J_body, default: k = r) or "total"
        (r = J_mode/(J_body + J_mode): k = r/(1 - r)).
    Returns:
      body rate [rad/s] at t.
    Raises:
      ValueError: naming the offending argument.
    """
    if freq_convention not in ("free", "constrained"):
        raise ValueError(
            f"freq_convention must be 'free' or 'constrained', got {freq_convention!r}"
        )
    if ratio_of not in ("body", "total"):
        raise ValueError(f"ratio_of must be 'body' or 'total', got {ratio_of!r}")
    check_positive("accel", accel)
    check_finite("t", t)
    check_positive("freq", freq)
    check_nonnegative("damping", damping)
    check_nonnegative("inertia_ratio", inertia_ratio)
    if is_concrete(damping) and (np.asarray(damping) >= 1).any():
        raise ValueError(f"damping must be < 1 (underdamped mode), got {damping!r}")
    if ratio_of == "total" and is_concrete(inertia_ratio):
        if (np.asarray(inertia_ratio) >= 1).any():
            raise ValueError(
                f"inertia_ratio must be < 1 for ratio_of='total', got {inertia_ratio!r}"
            )
    r = inertia_ratio
    k = r if ratio_of == "body" else r / (1.0 - r)
    nu, zeta = freq, damping
    if freq_convention == "constrained":
        nu, zeta = nu * (1.0 + k) ** 0.5, zeta * (1.0 + k) ** 0.5
        if is_concrete(zeta) and (np.asarray(zeta) >= 1).any():
            raise ValueError(f"damping is >= 1 after the constrained->free conversion: {damping!r}")
    args = cast_broadcast(
        tau=profile.tau,
        T=profile.T,
        T0=profile.T0,
        T1=profile.T1,
        accel=accel,
        t=t,
        freq=nu,
        damping=zeta,
        gain=k,
    )
    return _body_rate_batched(*args)


@jax.jit
def _settling(t, rate, tol):
    viol = jnp.abs(rate) > tol
    n = t.shape[-1]
    idx = jnp.arange(n)
    last = jnp.max(jnp.where(viol, idx, -1), axis=-1)
    nxt = jnp.take_along_axis(t, jnp.clip(last + 1, 0, n - 1)[..., None], axis=-1)[..., 0]
    return jnp.where(last == n - 1, jnp.inf, jnp.where(last < 0, t[..., 0], nxt))


def settling_time(t, rate, tol):
    """Time after which ``|rate| <= tol`` for good on the sampled grid [s].

    The first sample after the last violation; ``t[0]`` if never violated,
    ``+inf`` if the last sample still violates (not settled within the horizon).

    Args:
      t: increasing sample times [s], shape (..., n).
      rate: sampled rate [rad/s], same shape.
      tol: tube half-width [rad/s], > 0 (paper: 0.001 deg/s).
    Reference: paper, settling criterion of Figs. 5-6.
    """
    check_positive("tol", tol)
    t = jnp.asarray(t)
    rate = jnp.asarray(rate)
    if t.shape != rate.shape or t.ndim < 1:
        raise ValueError(
            f"t and rate must have the same shape (..., n), got {t.shape}, {rate.shape}"
        )
    return _settling(t, rate, tol)
