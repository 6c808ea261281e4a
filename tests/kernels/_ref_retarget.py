"""Reference for the tests: direct piecewise-constant minimum-peak retargeting.

Moved out of :mod:`jaxspline.kernels.retarget` (only the tests use it): an
independent optimizer the channel-wise solution is compared with.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.retarget import (
    ARCSEC,
    AttitudeModel,
    _check_inputs,
    _rk4_segment,
)
from jaxspline.kernels.validate import check_positive, float_dtype_of


class DirectResult(NamedTuple):
    """Result of :func:`min_peak_direct`.

    Attributes:
      peak: smallest bound s [units of u] found feasible (|u_i| <= s on the grid).
      u: (n_intervals, 3) piecewise-constant body control (x, y, z) [units of u].
      angle_residual [rad], rate_residual [rad/s]: end-state errors of ``u``.
      feasible: a control meeting ``tol`` was found at ``peak``.
    """

    peak: float
    u: np.ndarray
    angle_residual: float
    rate_residual: float
    feasible: bool


def _simulate_pc(model, sigma_a, omega_a, accel, T, steps):
    n = accel.shape[0]
    h = T / n

    def seg(x, k):
        return _rk4_segment(model, x, accel[k], k * h, (k + 1) * h, steps), None

    x, _ = jax.lax.scan(seg, (sigma_a, omega_a), jnp.arange(n))
    return x


def min_peak_direct(
    model: AttitudeModel,
    sigma_a,
    omega_a,
    sigma_b,
    omega_b,
    T,
    *,
    peak_hi,
    n_intervals=48,
    steps=2,
    bisections=14,
    lbfgs_iters=150,
    tol=ARCSEC,
):
    """Direct numerical minimum-peak control (independent reference for :func:`min_peak_retarget`).

    The control is piecewise constant on ``n_intervals`` equal intervals, parameterised as
    ``u = s·sin(v)`` so that |u_k| <= s exactly (ν = ∞). For a trial bound s the end-state
    least squares ``|σ(T) − σ_b|² + (T/4)²|ω̃(T) − ω̃_b|²`` (in arc-seconds) is minimised
    over v by optax L-BFGS (warm-started, RK4 with ``steps`` steps per interval); s is
    bisected on [0, peak_hi] for the smallest s whose residuals are <= tol [rad] and
    tol [rad/s]. A failed inner solve counts as infeasible, so ``peak`` errs high.
    Slow (seconds per case): a checking tool, not a kernel. Single case only.

    Args: as :func:`min_peak_retarget` (unbatched (3,) states, scalar T [s]); peak_hi [units of u]
      a feasible upper bound (e.g. 2× the linear peak). Returns :class:`DirectResult`.
    """
    import optax

    states = dict(sigma_a=sigma_a, omega_a=omega_a, sigma_b=sigma_b, omega_b=omega_b)
    _check_inputs(model, **states)
    for name, x in states.items():
        if jnp.ndim(x) != 1:
            raise ValueError(f"{name} must have shape (3,), got {jnp.shape(x)}")
    check_positive("T", T)
    check_positive("peak_hi", peak_hi)
    dt = float_dtype_of(sigma_a, omega_a, sigma_b, omega_b, T)
    sa, wa, sb, wb = (jnp.asarray(x, dt) for x in (sigma_a, omega_a, sigma_b, omega_b))
    T = jnp.asarray(T, dt)
    gain = jnp.asarray(model.gain, dt)
    scale = jnp.asarray(1.0 / ARCSEC, dt)

    def ends(u):
        return _simulate_pc(model, sa, wa, gain * u, T, steps)

    def loss(v, s):
        sT, wT = ends(s * jnp.sin(v))
        r = jnp.concatenate([(sT - sb) * scale, (wT - wb) * (0.25 * T) * scale])
        return 0.5 * jnp.sum(r * r)

    opt = optax.lbfgs()

    @jax.jit
    def solve(v0, s):
        f = lambda v: loss(v, s)  # noqa: E731
        vg = optax.value_and_grad_from_state(f)

        def body(c):
            v, st, _ = c
            val, g = vg(v, state=st)
            upd, st = opt.update(g, st, v, value=val, grad=g, value_fn=f)
            return optax.apply_updates(v, upd), st, val

        stop = jnp.asarray(0.5 * (0.1 * tol / ARCSEC) ** 2, dt)

        def cond(c):
            return (c[3] < lbfgs_iters) & (c[2] > stop)

        def body2(c):
            v, st, val = body(c[:3])
            return v, st, val, c[3] + 1

        inf = jnp.asarray(jnp.inf, dt)
        v, _, _, _ = jax.lax.while_loop(cond, body2, (v0, opt.init(v0), inf, 0))
        sT, wT = ends(s * jnp.sin(v))
        return v, jnp.max(jnp.abs(sT - sb)), jnp.max(jnp.abs(wT - wb))

    def rescale(v, s_old, s_new):
        return jnp.arcsin(jnp.clip(s_old / s_new * jnp.sin(v), -1.0, 1.0))

    lo, hi = 0.0, float(peak_hi)
    v_hi, ea, er = solve(jnp.zeros((n_intervals, 3), dt), jnp.asarray(hi, dt))
    best = (v_hi, float(ea), float(er))
    feasible = best[1] <= tol and best[2] <= tol
    if feasible:
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            v, ea, er = solve(rescale(best[0], hi, mid), jnp.asarray(mid, dt))
            if float(ea) <= tol and float(er) <= tol:
                hi, best = mid, (v, float(ea), float(er))
            else:
                lo = mid
    u = np.asarray(hi * jnp.sin(best[0]))
    return DirectResult(hi, u, best[1], best[2], feasible)
