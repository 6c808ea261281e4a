"""Minimum-peak-control retargeting (retarget–scan paper, eqs. 5–7, 13, 18–22; SPEC §3).

The channel (linear) part is in :mod:`jaxspline.kernels.retarget_channel`; this
module holds the nonlinear 3-D problem built on it.

Problem (paper eq. 13 with ν = ∞): over a FIXED interval [0, T] move the attitude
from (σ_a, ω̃_a) to (σ_b, ω̃_b) while minimising the peak control
``J(u) = max_t max_k |u_k(t)|``.

Linear decoupled case (the paper's reference problem, eq. 21): every channel is a
double integrator ``f'' = a`` with boundary values (a1, b1) -> (a2, b2). Without a
rate bound the optimum is bang–bang with one switch and (D = a2 - a1 - T(b1+b2)/2,
Δ = b2 - b1)

    d* = (2|D| + sqrt(4 D² + T² Δ²)) / T².

With a rate bound |f'| <= rate the optimum is bang–coast–bang on the envelope curve of
SPEC §1 that passes through a2 (d* from ``reach_durations.min_peak_accel``). Every optimal
channel control has the form ``a(t) = s d`` on [0, t1), ``0`` on [t1, t2),
``-s d`` on [t2, T] (:class:`ChannelControl`).

Nonlinear model (paper eqs. 4–7). σ = (ϑ pitch, γ roll, ψ yaw), the angles that turn
the orbital frame (ОСК: x along the velocity, y along the radius vector, z = x × y)
into the body frame by pitch about z, roll about x, yaw about y; ω̃ = body rate
relative to the orbital frame in body axes (x, y, z)::

    dσ/dt = N(σ) ω̃                                                      (6, 7)
    dω̃/dt = B u + f_ω,  f_ω = J⁻¹[M_gg − ω × J ω] + ω̃ × ω_o,  ω = ω̃ + ω_o   (4, 5)

with ω_o = omega0 · C(σ) e_z the orbital-frame rate in body axes (``ε_ОСК`` of eq. 3
equals −ω̃ × ω_o for a circular orbit) and M_gg = 3 omega0² r × J r the gravity-gradient
torque (r = C(σ) e_y, optional).

Successive approximations (paper eqs. 18–22). Channel k of σ is paired with the body
axis p(k) = (z, x, y) for (pitch, roll, yaw), because N(0) maps ω̃_z, ω̃_x, ω̃_y to
ϑ', γ', ψ' (with the body order x, y, z the paper's f_σ = [N − I] ω̃ would not vanish at
σ = 0 — an inconsistency of eq. 18 fixed here). Written per channel,

    σ_k'' = B_p(k) u_p(k) + h_k(t),   h = (N' − I) B u + Ṅ' ω̃ + N' f_ω,

where N' is N with its columns reordered. Freezing h from the previous iterate turns the
problem into the linear one with shifted targets; by superposition the shift equals the
end-state mismatch between the nonlinear model and the double integrator under the same
control, so iteration k re-solves the closed form with targets
``c_{k+1} = c_k − (x_true(T; u_k) − x_b)`` (``method="picard"``, the paper's one-step
iteration) or with a quasi-Newton step on the same 6-dimensional map
(``method="broyden"``: forward-difference Jacobian at u⁽⁰⁾ from 6 extra simulations, then
good-Broyden rank-one updates; far fewer iterations on large maneuvers). u⁽⁰⁾ is the
linear solution (eq. 21). (A Newton step with the Jacobian by forward-mode autodiff
through the integrator also converges in 2–3 iterations but takes minutes to compile on a
2-core CPU, so it is not offered.)
The iterate at convergence is the minimum-peak control of the linear problem with the
nonlinear terms frozen along its own trajectory; a direct optimisation
(``min_peak_direct`` in tests/kernels/_ref_retarget.py) can therefore find a slightly lower peak.

Left out: ν = 2 (Euclidean norm of u). Its reference problem couples the channels: the
optimal control is ``u = J* B⁻¹ g(t)/|g(t)|`` with g linear in t (Krasovskii's moment
problem), so there is no per-channel closed form and each iteration would need a
5-dimensional convex dual solve; not implemented. The rate bound is supported in the
linear case only (in the nonlinear iteration it would bound σ' + frozen terms, not ω̃).

Units: radians, seconds; ``a`` in rad/s²; u in the units of the control parameters
(``B u`` in rad/s²). Reference: Gorelov, Kurganskaya, Manturov, Sollogub, Yurin, "К
задаче оптимизации программ управления угловым движением КА ДЗЗ" (seeds/
retarget-scan-pattern-optimization.ru.txt), eqs. 3–7, 13, 18–22; SPEC §1, §3.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.batch import batched
from jaxspline.kernels.retarget_channel import (
    ARCSEC,
    AXIS_CHANNEL,
    CHANNEL_AXIS,
    ChannelControl,
    channel_control_eval,
    control_from_peak,
    unbounded_peak,
)
from jaxspline.kernels.validate import (
    check_finite,
    check_positive,
    float_dtype_of,
    is_concrete,
)

__all__ = [
    "AttitudeModel",
    "euler_rates_matrix",
    "orbital_to_body",
    "simulate",
    "min_peak_retarget",
    "body_control",
]

# -------------------------------------------------------------------------- nonlinear


class AttitudeModel(NamedTuple):
    """Rigid spacecraft in a circular orbit (paper eqs. 1–5).

    Attributes:
      inertia: J_C [kg m²], (3,) principal moments or (3, 3) matrix, body axes x, y, z.
      gain: B = diag(b_x, b_y, b_z) [rad/s² per unit u], (3,), nonzero.
      omega0: orbital-frame rate about the orbital z axis [rad/s]; for the ОСК with
        x along the velocity and y along the radius vector, z = x × y is opposite to the
        orbit normal and a circular orbit of mean motion n has omega0 = −n.
      gravity_gradient: multiplier of the torque 3 omega0² r × J r (1 = on, 0 = off).
    """

    inertia: jnp.ndarray
    gain: jnp.ndarray = (1.0, 1.0, 1.0)
    omega0: float = 0.0
    gravity_gradient: float = 1.0


def euler_rates_matrix(sigma):
    """N(σ) of paper eq. 7: (ϑ', γ', ψ') = N(σ) (ω̃_x, ω̃_y, ω̃_z).

    Rows: ϑ' = (−sinψ ω̃_x + cosψ ω̃_z)/cosγ; γ' = cosψ ω̃_x + sinψ ω̃_z;
    ψ' = ω̃_y + tanγ (sinψ ω̃_x − cosψ ω̃_z). Singular at cosγ = 0.

    Args:
      sigma: float [..., 3], angles σ = (pitch ϑ, roll γ, yaw ψ) [rad].
    Returns:
      float [..., 3, 3], N(σ) [dimensionless] mapping body rates [rad/s] to angle rates [rad/s].
    """
    sigma = jnp.asarray(sigma)
    g, p = sigma[..., 1], sigma[..., 2]
    cg, tg = jnp.cos(g), jnp.tan(g)
    sp, cp = jnp.sin(p), jnp.cos(p)
    z = jnp.zeros_like(g)
    o = jnp.ones_like(g)
    rows = [
        jnp.stack([-sp / cg, z, cp / cg], -1),
        jnp.stack([cp, z, sp], -1),
        jnp.stack([sp * tg, o, -cp * tg], -1),
    ]
    return jnp.stack(rows, -2)


def orbital_to_body(sigma):
    """Direction-cosine matrix C(σ) = R_y(ψ) R_x(γ) R_z(ϑ) (orbital -> body components).

    Passive elementary rotations (pitch about z, then roll about x, then yaw about y),
    consistent with eq. 7: dC/dt = −[ω̃×] C.

    Args:
      sigma: float [..., 3], angles σ = (pitch, roll, yaw) [rad].
    Returns:
      float [..., 3, 3], C(σ).
    """
    sigma = jnp.asarray(sigma)
    t, g, p = sigma[..., 0], sigma[..., 1], sigma[..., 2]
    ct, st, cg, sg, cp, sp = jnp.cos(t), jnp.sin(t), jnp.cos(g), jnp.sin(g), jnp.cos(p), jnp.sin(p)
    rows = [
        jnp.stack([cp * ct - sp * sg * st, cp * st + sp * sg * ct, -sp * cg], -1),
        jnp.stack([-cg * st, cg * ct, sg], -1),
        jnp.stack([sp * ct + cp * sg * st, sp * st - cp * sg * ct, cp * cg], -1),
    ]
    return jnp.stack(rows, -2)


def _inertia_matrix(inertia):
    J = jnp.asarray(inertia)
    return jnp.diag(J) if J.ndim == 1 else J


def _attitude_rhs(model: AttitudeModel, sigma, omega_rel, accel_body):
    """Right-hand side of eqs. 4–6 for one state: returns (dσ/dt, dω̃/dt).

    dσ/dt = N(σ) ω̃; dω̃/dt = a + J⁻¹[M_gg − ω × J ω] + ω̃ × ω_o with ω_o = omega0 C e_z,
    ω = ω̃ + ω_o, M_gg = gravity_gradient · 3 omega0² r × J r, r = C e_y.

    Args:
      model: AttitudeModel.
      sigma: float [3], pitch, roll, yaw [rad].
      omega_rel: float [3], ω̃ body x, y, z [rad/s].
      accel_body: float [3], B u [rad/s²].
    Returns:
      (dσ/dt [rad/s], dω̃/dt [rad/s²]), float [3] each.
    """
    J = _inertia_matrix(model.inertia).astype(omega_rel.dtype)
    C = orbital_to_body(sigma)
    w0 = jnp.asarray(model.omega0, omega_rel.dtype)
    wo = w0 * C[:, 2]
    r = C[:, 1]
    w = omega_rel + wo
    mgg = jnp.asarray(model.gravity_gradient, omega_rel.dtype) * 3.0 * w0 * w0 * jnp.cross(r, J @ r)
    fw = jnp.linalg.solve(J, mgg - jnp.cross(w, J @ w)) + jnp.cross(omega_rel, wo)
    return euler_rates_matrix(sigma) @ omega_rel, accel_body + fw


def _channel_accel(ctrl: ChannelControl, t):
    """Per-channel a(t) (pitch, roll, yaw) mapped to body axes (x, y, z)."""
    a = channel_control_eval(ctrl, t)
    return a[jnp.array(AXIS_CHANNEL)]


def _rk4_segment(model, x, a, t0, t1, steps):
    """``steps`` RK4 steps of eqs. 4–6 over [t0, t1] with constant body acceleration a."""
    h = (t1 - t0) / steps

    def f(x):
        return _attitude_rhs(model, x[0], x[1], a)

    def step(_, x):
        k1 = f(x)
        k2 = f((x[0] + 0.5 * h * k1[0], x[1] + 0.5 * h * k1[1]))
        k3 = f((x[0] + 0.5 * h * k2[0], x[1] + 0.5 * h * k2[1]))
        k4 = f((x[0] + h * k3[0], x[1] + h * k3[1]))
        return tuple(x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]) for i in (0, 1))

    return jax.lax.fori_loop(0, steps, step, x)


def _simulate_kernel(model, sigma_a, omega_a, ctrl, T, steps):
    """RK4 on a grid aligned with every switch time (steps per constant-control segment)."""
    sw = jnp.sort(jnp.concatenate([ctrl.t1, ctrl.t2]))
    pts = jnp.clip(jnp.concatenate([jnp.zeros((1,), T.dtype), sw, T[None]]), 0.0, T)

    def seg(x, k):
        t0, t1 = pts[k], pts[k + 1]
        a = _channel_accel(ctrl, 0.5 * (t0 + t1))
        return _rk4_segment(model, x, a, t0, t1, steps), None

    x, _ = jax.lax.scan(seg, (sigma_a, omega_a), jnp.arange(pts.shape[0] - 1))
    return x


def simulate(model: AttitudeModel, sigma_a, omega_a, ctrl: ChannelControl, T, steps=16):
    """Integrate the nonlinear model (eqs. 4–7) under a per-channel bang–coast–bang control.

    Channel k's acceleration a_k(t) (pitch, roll, yaw) is applied as B u on body axis
    (z, x, y)[k]. RK4 with ``steps`` steps between consecutive switch times (the control
    is constant there, so the scheme keeps its 4th order).

    Args:
      model: AttitudeModel.
      sigma_a: float [3], pitch, roll, yaw at t = 0 [rad].
      omega_a: float [3], ω̃ at t = 0 [rad/s].
      ctrl: ChannelControl with float [3] fields (pitch, roll, yaw).
      T: scalar, duration [s].
      steps: int, RK4 steps per constant-control segment.
    Returns:
      (σ(T) [rad], ω̃(T) [rad/s]), float [3] each.
    """
    sigma_a = jnp.asarray(sigma_a)
    dt = float_dtype_of(sigma_a, omega_a, T)
    return _simulate_jit(
        model,
        sigma_a.astype(dt),
        jnp.asarray(omega_a, dt),
        ChannelControl(*(jnp.asarray(c, dt) for c in ctrl)),
        jnp.asarray(T, dt),
        int(steps),
    )


_simulate_jit = jax.jit(_simulate_kernel, static_argnums=5)


class RetargetResult(NamedTuple):
    """Result of :func:`min_peak_retarget`.

    Attributes:
      peak: max_t max_k |u_k(t)| [units of u] of the returned control.
      control: ChannelControl with (..., 3) fields, channels (pitch, roll, yaw), in
        rad/s² of effective acceleration B u on body axes (z, x, y).
      iterations: number of corrections after the linear solution u⁽⁰⁾ (int32).
      angle_residual: max_k |σ_k(T) − σ_b,k| [rad] of the returned control.
      rate_residual: max_k |ω̃_k(T) − ω̃_b,k| [rad/s].
      converged: both residuals within tolerance.
    """

    peak: jnp.ndarray
    control: ChannelControl
    iterations: jnp.ndarray
    angle_residual: jnp.ndarray
    rate_residual: jnp.ndarray
    converged: jnp.ndarray


def _linear_control(sigma_a, ra, c, T):
    """The closed-form minimum-peak control (eq. 21) reaching c = (σ, σ') at T, no rate bound."""
    inf = jnp.asarray(jnp.inf, T.dtype)
    d = unbounded_peak(sigma_a, ra, c[:3], c[3:], T)
    return control_from_peak(sigma_a, ra, c[:3], c[3:], T, inf, d)


def _end_errors(s, w, sigma_b, omega_b):
    """(max_k |σ_k(T) − σ_b,k|, max_k |ω̃_k(T) − ω̃_b,k|), +inf where not finite."""
    inf = jnp.asarray(jnp.inf, s.dtype)
    ea = jnp.max(jnp.abs(s - sigma_b))
    er = jnp.max(jnp.abs(w - omega_b))
    ea = jnp.where(jnp.isfinite(ea), ea, inf)
    er = jnp.where(jnp.isfinite(er), er, inf)
    return ea, er


def _initial_jacobian(end_of, z0, e0, sc):
    """Forward-difference Jacobian of the scaled end-state map at u⁽⁰⁾ (6 simulations,
    vmapped); the identity where it is not finite."""
    h = jnp.sqrt(jnp.finfo(z0.dtype).eps)
    Es = jax.vmap(lambda zz: end_of(zz / sc)[0])(z0[None, :] + h * jnp.eye(6, dtype=z0.dtype))
    B1 = ((Es - e0[None, :]) * sc[None, :]).T / h
    return jnp.where(jnp.all(jnp.isfinite(B1)), B1, jnp.eye(6, dtype=z0.dtype))


def _broyden_update(Bm, dz, r, r1):
    """Good Broyden rank-one update of the Jacobian estimate after the step dz (r -> r1)."""
    den = jnp.dot(dz, dz)
    ok = den > 0
    return Bm + jnp.where(ok, jnp.outer(r1 - r - Bm @ dz, dz) / jnp.where(ok, den, 1.0), 0.0)


def _retarget_kernel(
    sigma_a,
    omega_a,
    sigma_b,
    omega_b,
    T,
    inertia,
    gain,
    omega0,
    gg,
    tol,
    rate_tol,
    *,
    max_iter,
    steps,
    method,
):
    model = AttitudeModel(inertia, gain, omega0, gg)
    ra = euler_rates_matrix(sigma_a) @ omega_a  # σ'(0)
    rb = euler_rates_matrix(sigma_b) @ omega_b  # σ'(T) target

    def end(c):  # the true end state (σ, σ') under the linear control for targets c
        s, w = _simulate_kernel(
            model, sigma_a, omega_a, _linear_control(sigma_a, ra, c, T), T, steps
        )
        return jnp.concatenate([s, euler_rates_matrix(s) @ w]), (s, w)

    target = jnp.concatenate([sigma_b, rb])
    e0, aux0 = end(target)
    sc = jnp.concatenate([jnp.ones(3, T.dtype), jnp.full((3,), T)])  # angle, rate·T

    def cond(st):
        return (st[3] < max_iter) & ~((st[4] <= tol) & (st[5] <= rate_tol))

    def body(st):
        z, r, Bm, it, _, _ = st  # scaled targets z = c·sc, scaled mismatch r
        if method == "broyden":
            dz = -jnp.linalg.solve(Bm, r)
            dz = jnp.where(jnp.all(jnp.isfinite(dz)), dz, -r)
        else:
            dz = -r
        z1 = z + dz
        e1, aux = end(z1 / sc)
        r1 = (e1 - target) * sc
        if method == "broyden":
            Bm = _broyden_update(Bm, dz, r, r1)
        return z1, r1, Bm, it + 1, *_end_errors(*aux, sigma_b, omega_b)

    z0 = target * sc
    B0 = jnp.eye(6, dtype=T.dtype)
    if method == "broyden":
        B0 = _initial_jacobian(end, z0, e0, sc)
    st0 = (z0, (e0 - target) * sc, B0, jnp.int32(0), *_end_errors(*aux0, sigma_b, omega_b))
    z, _, _, it, ea, er = jax.lax.while_loop(cond, body, st0)
    ctrl = _linear_control(sigma_a, ra, z / sc, T)
    conv = (ea <= tol) & (er <= rate_tol)
    peak = jnp.max(ctrl.peak / jnp.abs(gain[jnp.array(CHANNEL_AXIS)]))
    return (peak, *ctrl, it, ea, er, conv)


_SIG = "(3),(3),(3),(3),(),(3,3),(3),(),(),(),()->(),(3),(3),(3),(3),(),(),(),()"
_retarget_cache: dict = {}


def _retarget_fn(max_iter, steps, method):
    key = (max_iter, steps, method)
    if key not in _retarget_cache:

        def k(*a):
            return _retarget_kernel(*a, max_iter=max_iter, steps=steps, method=method)

        _retarget_cache[key] = batched(k, _SIG)
    return _retarget_cache[key]


def _check_state(name, x):
    check_finite(name, x)
    if jnp.shape(x)[-1:] != (3,):
        raise ValueError(f"{name} must have a trailing axis of length 3, got shape {jnp.shape(x)}")


def _check_inputs(model, **states):
    """Eager checks of a retargeting problem: the model and every named [..., 3] state."""
    _check_model(model)
    for name, x in states.items():
        _check_state(name, x)


def _check_model(model):
    if not isinstance(model, AttitudeModel):
        raise ValueError(f"model must be an AttitudeModel, got {type(model).__name__}")
    J = np.asarray(model.inertia, dtype=float)
    if J.shape not in ((3,), (3, 3)):
        raise ValueError(f"model.inertia must have shape (3,) or (3, 3), got {J.shape}")
    check_positive("model.inertia", J if J.ndim == 1 else np.linalg.eigvalsh(0.5 * (J + J.T)))
    g = np.asarray(model.gain, dtype=float)
    if g.shape != (3,):
        raise ValueError(f"model.gain must have shape (3,), got {g.shape}")
    check_finite("model.gain", g)
    if (g == 0).any():
        raise ValueError(f"model.gain must be nonzero, got {g.tolist()!r}")
    check_finite("model.omega0", model.omega0)
    check_finite("model.gravity_gradient", model.gravity_gradient)


def min_peak_retarget(
    model: AttitudeModel,
    sigma_a,
    omega_a,
    sigma_b,
    omega_b,
    T,
    *,
    tol=ARCSEC,
    rate_tol=ARCSEC,
    max_iter=20,
    steps=16,
    method="picard",
):
    """Minimum-peak retargeting of the nonlinear model by successive approximations.

    Paper eqs. 18–22 with ν = ∞ (see the module docstring): u⁽⁰⁾ solves the linear
    double-integrator problem per channel (eq. 21); iteration k re-solves it with the
    nonlinear terms frozen from u⁽ᵏ⁻¹⁾ (eq. 22), i.e. with targets shifted by the
    nonlinear end-state mismatch, until |σ(T) − σ_b| <= tol and |ω̃(T) − ω̃_b| <= rate_tol
    (end state by :func:`simulate`). ``lax.while_loop`` with at most ``max_iter``
    corrections.

    Args:
      model: :class:`AttitudeModel`.
      sigma_a: float [..., 3], pitch, roll, yaw at t = 0 [rad] (|roll| < π/2).
      sigma_b: float [..., 3], pitch, roll, yaw at t = T [rad] (|roll| < π/2).
      omega_a: float [..., 3], ω̃ body x, y, z at t = 0 [rad/s].
      omega_b: float [..., 3], ω̃ body x, y, z at t = T [rad/s].
      T: float [...], duration [s] > 0, broadcast over the leading axes.
      tol: convergence tolerance on σ(T) [rad] (default 1″).
      rate_tol: convergence tolerance on ω̃(T) [rad/s] (default 1″/s).
      max_iter: maximum number of corrections.
      steps: RK4 steps per constant-control segment.
      method: "picard" (the paper's simple iteration) or "broyden" (quasi-Newton).
    Returns:
      RetargetResult, a NamedTuple: ``peak``, ``control``, ``iterations``,
      ``angle_residual`` [rad], ``rate_residual`` [rad/s] and ``converged`` (check it).
    Raises:
      ValueError: naming the argument (shapes, NaN, T <= 0, |roll| >= π/2, model,
        method, max_iter).
    """
    if method not in ("picard", "broyden"):
        raise ValueError(f"method must be 'picard' or 'broyden', got {method!r}")
    if int(max_iter) < 0:
        raise ValueError(f"max_iter must be >= 0, got {max_iter!r}")
    if int(steps) < 1:
        raise ValueError(f"steps must be >= 1, got {steps!r}")
    _check_inputs(model, sigma_a=sigma_a, omega_a=omega_a, sigma_b=sigma_b, omega_b=omega_b)
    for name, x in (("sigma_a", sigma_a), ("sigma_b", sigma_b)):
        if is_concrete(x) and (np.abs(np.asarray(x)[..., 1]) >= 0.5 * np.pi).any():
            shown = np.asarray(x).tolist()
            raise ValueError(f"{name}: roll must satisfy |roll| < pi/2, got {shown!r}")
    check_positive("T", T)
    check_positive("tol", tol)
    check_positive("rate_tol", rate_tol)
    dt = float_dtype_of(sigma_a, omega_a, sigma_b, omega_b, T)
    J = jnp.asarray(model.inertia, dt)
    J = jnp.diag(J) if J.ndim == 1 else J
    args = [jnp.asarray(x, dt) for x in (sigma_a, omega_a, sigma_b, omega_b, T)]
    out = _retarget_fn(int(max_iter), int(steps), method)(
        *args,
        J,
        jnp.asarray(model.gain, dt),
        jnp.asarray(model.omega0, dt),
        jnp.asarray(model.gravity_gradient, dt),
        jnp.asarray(tol, dt),
        jnp.asarray(rate_tol, dt),
    )
    return RetargetResult(out[0], ChannelControl(*out[1:5]), *out[5:])


def body_control(model: AttitudeModel, ctrl: ChannelControl, t):
    """Body-axis control u(t) (x, y, z) of a per-channel control at t.

    u_p(k) = a_k(t) / B_p(k) with p = (z, x, y) for (pitch, roll, yaw).

    Args:
      model: AttitudeModel, its gain B [rad/s² per unit u] is used.
      ctrl: ChannelControl with fields float [3] (pitch, roll, yaw channels).
      t: scalar or float [n], times [s].
    Returns:
      float [3] or [n, 3], u [units of u].
    """
    t = jnp.asarray(t)
    if t.ndim:
        ctrl, t = ChannelControl(*(c[..., None, :] for c in ctrl)), t[..., None]
    a = channel_control_eval(ctrl, t)
    return a[..., jnp.array(AXIS_CHANNEL)] / jnp.asarray(model.gain, a.dtype)
