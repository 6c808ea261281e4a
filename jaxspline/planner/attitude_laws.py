"""Inertial attitude of the pointing laws: observation scans, nadir hold, per-channel view.

Frames and conventions (shared by :mod:`jaxspline.planner.flown_joins`,
:mod:`jaxspline.products.attitude_history` and :mod:`jaxspline.products.aem`):

* Reference frame: ECI = TEME, the frame of the orbit tables (:mod:`jaxspline.geometry.orbit`).
* Body frame (:mod:`jaxspline.geometry.pointing`): ``+Z_b`` is the boresight (line of sight),
  ``+X_b`` the image-motion direction, ``+Y_b`` the detector line.
  ``C = Ry(pitch) Rx(roll) Rz(yaw)`` maps body to orbital axes (``x_o`` along-track,
  ``y_o = -`` orbit normal, ``z_o`` nadir), so body -> TEME is ``R = B^T C`` with ``B``
  the orbital axes as rows (TEME components).
* Yaw: ``per_channel`` satellites fly the planner's yaw law
  (:func:`jaxspline.geometry.pointing.aim_angles`: strip tangent for strips, minus the target's
  relative motion for points; :data:`LAW_POINTING`); the rest-to-rest models plan on
  the line of sight only, so their body keeps zero yaw (``+X_b = Ry(pitch) x_o``, in
  the plane of ``x_o`` and ``z_o``; :data:`LAW_ZERO_YAW`); the nadir law has zero roll,
  pitch and yaw (body = orbital axes; the per-channel model's rest state).
* Attitude quaternion: scalar first ``[w, x, y, z]``, Hamilton product, body -> TEME
  (``v_teme = q ∘ v_body ∘ q̃``; :mod:`jaxspline.kernels.attitude`).
* Body rates: ω [rad/s], ε = dω/dt [rad/s²], ε' [rad/s³] of the body relative to TEME,
  in BODY axes.

A *law* is a vector [9]: an aim law [8] of :func:`jaxspline.geometry.pointing.aim_params` and
its yaw mode (law[8]). Kernels take one sample; numpy wrappers batch them with
:func:`jaxspline.planner.opportunities.evaluate` (fixed padded shapes, few compilations).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import R_EARTH
from jaxspline.geometry.orbit import orbit_state
from jaxspline.kernels.attitude import dcm_to_quat_kernel, quat_to_dcm_kernel
from jaxspline.planner.opportunities import evaluate, state_batched

__all__ = [
    "LAW_NADIR",
    "LAW_POINTING",
    "LAW_ZERO_YAW",
    "NADIR_LAW",
    "angles_from_dcm",
    "compose",
    "dcm_from_angles",
    "decompose",
    "frame_rates",
    "law_modes",
    "law_states",
    "orbital_basis",
    "state_angles",
]

LAW_POINTING, LAW_ZERO_YAW, LAW_NADIR = 1.0, 0.0, -1.0  # law[8]: yaw mode of a law
# the nadir law: a point law on the equator (finite anywhere) whose angles are zeroed
NADIR_LAW = np.array([R_EARTH, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, LAW_NADIR])
JERK_STEP_S = 1e-2  # [s] half step of the central difference of the exact eps giving eps'
_LAW_OF_MODEL = {"pointing": LAW_POINTING, "zero_yaw": LAW_ZERO_YAW}


def law_modes(sats) -> np.ndarray:
    """[S] yaw mode of each satellite's laws between observations (its model's law).

    Args:
      sats: the satellites; each model's ``attitude_law`` is ``"pointing"``
        (:data:`LAW_POINTING`) or ``"zero_yaw"`` (:data:`LAW_ZERO_YAW`).
    """
    return np.array([_LAW_OF_MODEL[s.maneuver.attitude_law] for s in sats])


def orbital_basis(scene, t, sat=None):
    """Orbital axes in TEME at time t (the frame of :mod:`jaxspline.geometry.pointing`).

    Args:
      scene: Scene of the scenario's satellites.
      t: scalar, seconds from the epoch.
      sat: int, satellite index (None for a one-satellite orbit).
    Returns:
      float [3, 3], rows x_o, y_o, z_o (unit vectors in TEME).
    """
    r, v = orbit_state(scene.orbit, t, sat)
    z = -r / jnp.linalg.norm(r)
    h = jnp.cross(r, v)
    y = -h / jnp.linalg.norm(h)
    return jnp.stack([jnp.cross(y, z), y, z])


def dcm_from_angles(ang):
    """``C = Ry(pitch) Rx(roll) Rz(yaw)`` (body -> orbital) of attitude angles.

    Args:
      ang: float [3], [roll, pitch, yaw] [rad].
    Returns:
      float [3, 3], C.
    """
    cr, cp, cy = jnp.cos(ang)
    sr, sp, sy = jnp.sin(ang)
    one, zero = jnp.ones_like(cr), jnp.zeros_like(cr)
    rx = jnp.array([[one, zero, zero], [zero, cr, -sr], [zero, sr, cr]])
    ry = jnp.array([[cp, zero, sp], [zero, one, zero], [-sp, zero, cp]])
    rz = jnp.array([[cy, -sy, zero], [sy, cy, zero], [zero, zero, one]])
    return ry @ rx @ rz


def angles_from_dcm(c):
    """Attitude angles of a body -> orbital matrix C = Ry(pitch) Rx(roll) Rz(yaw).

    Boresight ``b = C e_z = (cos r sin p, -sin r, cos r cos p)``: pitch = atan2(b_x, b_z),
    roll = atan2(-b_y, hypot(b_x, b_z)); row 1 of C is ``(cos r sin y, cos r cos y, -sin r)``,
    so yaw = atan2(C_10, C_11). No arcsin / arccos (exact near zero).

    Args:
      c: float [3, 3], C.
    Returns:
      float [3], [roll, pitch, yaw] [rad].
    """
    b = c[:, 2]
    pitch = jnp.arctan2(b[0], b[2])
    roll = jnp.arctan2(-b[1], jnp.hypot(b[0], b[2]))
    yaw = jnp.arctan2(c[1, 0], c[1, 1])
    return jnp.stack([roll, pitch, yaw])


def _rates_kernel(scene, sat, p, t0, t):
    """Orbital axes B [3, 3] (rows, TEME), their angular velocity w and dw/dt [3] (orbital axes).

    With B' and B'' by nested ``jax.jvp``: ``[w x] = B B'^T`` (skew: the axes turn as
    x_i' = Omega x x_i) and ``[w' x] = asym(B B''^T)`` (B' B'^T is symmetric).
    ``p`` and ``t0`` are unused (the batched signature of ``evaluate``).
    """

    def f0(tt):
        return orbital_basis(scene, tt, sat)

    def f1(tt):
        return jax.jvp(f0, (tt,), (jnp.ones_like(tt),))

    (b, b1), (_, b2) = jax.jvp(f1, (t,), (jnp.ones_like(t),))
    return b, _vee_asym(b @ b1.T), _vee_asym(b @ b2.T)


def _vee_asym(a):
    """Axial vector of the skew part of a [3, 3] matrix: ``vee((a - a^T) / 2)``."""
    return 0.5 * jnp.stack([a[2, 1] - a[1, 2], a[0, 2] - a[2, 0], a[1, 0] - a[0, 1]])


def _rz_t(yaw, v):
    """Rz(yaw)^T v."""
    c, s = jnp.cos(yaw), jnp.sin(yaw)
    return jnp.stack([c * v[0] + s * v[1], -s * v[0] + c * v[1], v[2]])


def _body_rate(ang, rate, w):
    """Body ω [3] (TEME-relative, body axes) from angles, their rates and the frame rate w.

    ω = C^T w + ω_rel, ω_rel = Rz(yaw)^T (roll', pitch' cos roll, yaw' - pitch' sin roll)
    for C = Ry(pitch) Rx(roll) Rz(yaw).
    """
    c = dcm_from_angles(ang)
    v = jnp.stack([rate[0], rate[1] * jnp.cos(ang[0]), rate[2] - rate[1] * jnp.sin(ang[0])])
    return c.T @ w + _rz_t(ang[2], v)


def _angle_rate(ang, omega, w):
    """Inverse of :func:`_body_rate`: (roll', pitch', yaw') [3] from ω [3] and w [3]."""
    c = dcm_from_angles(ang)
    rel = omega - c.T @ w
    cy, sy = jnp.cos(ang[2]), jnp.sin(ang[2])
    v = jnp.stack([cy * rel[0] - sy * rel[1], sy * rel[0] + cy * rel[1], rel[2]])  # Rz(yaw) rel
    pitch_rate = v[1] / jnp.cos(ang[0])  # |roll| < pi/2 inside the off-nadir cone
    return jnp.stack([v[0], pitch_rate, v[2] + pitch_rate * jnp.sin(ang[0])])


def compose(ang, rate, acc, b, w, wd):
    """Kernel: inertial state of a body at given attitude angles, rates and accelerations.

    R = B^T C(ang); ω by :func:`_body_rate`; ε = dω/dt by one ``jax.jvp`` of it
    along (rate, acc, wd).

    Args:
      ang: float [3], [roll, pitch, yaw] [rad].
      rate: float [3], their rates [rad/s].
      acc: float [3], their accelerations [rad/s^2].
      b: float [3, 3], orbital axes (rows) in TEME.
      w: float [3], angular velocity of the orbital axes [rad/s].
      wd: float [3], its derivative [rad/s^2] (:func:`_rates_kernel`).
    Returns:
      (q float [4], ω float [3] [rad/s], ε float [3] [rad/s^2]), body -> TEME.
    """
    omega, eps = jax.jvp(_body_rate, (ang, rate, w), (rate, acc, wd))
    return dcm_to_quat_kernel(b.T @ dcm_from_angles(ang)), omega, eps


def decompose(q, omega, eps, b, w, wd):
    """Kernel, inverse of :func:`compose`: attitude angles, rates and accelerations.

    C = B R(q); angles by :func:`angles_from_dcm`; rates by :func:`_angle_rate`; the
    accelerations by one ``jax.jvp`` of it along (rates, ε, wd).

    Args:
      q: float [4], attitude quaternion (scalar first, body -> TEME).
      omega: float [3], body angular velocity [rad/s].
      eps: float [3], body angular acceleration [rad/s^2].
      b: float [3, 3], orbital axes (rows) in TEME.
      w: float [3], angular velocity of the orbital axes [rad/s].
      wd: float [3], its derivative [rad/s^2].
    Returns:
      (angles [rad], rates [rad/s], accelerations [rad/s^2]), float [3] each.
    """
    ang = angles_from_dcm(b @ quat_to_dcm_kernel(q))
    rate, acc = jax.jvp(lambda a, o, ww: _angle_rate(a, o, ww), (ang, omega, w), (
        _angle_rate(ang, omega, w), eps, wd))  # fmt: skip
    return ang, rate, acc


def _compose_packed(scene, sat, x, t0, t):
    # evaluate()'s signature; x = [angle, rate, accel, w, w'] (15) + B (9)
    return compose(x[0:3], x[3:6], x[6:9], x[15:24].reshape(3, 3), x[9:12], x[12:15])


def _decompose_packed(scene, sat, x, t0, t):
    # x = [q (4), omega, eps, w, w'] (16) + B (9)
    return decompose(x[0:4], x[4:7], x[7:10], x[16:25].reshape(3, 3), x[10:13], x[13:16])


_rates_v = jax.jit(jax.vmap(_rates_kernel, in_axes=(None, 0, 0, 0, 0)))
_compose_v = jax.jit(jax.vmap(_compose_packed, in_axes=(None, 0, 0, 0, 0)))
_decompose_v = jax.jit(jax.vmap(_decompose_packed, in_axes=(None, 0, 0, 0, 0)))


def frame_rates(scene, sat, t):
    """Orbital axes and their angular velocity and acceleration (numpy).

    Args:
      scene: Scene of the scenario's satellites.
      sat: int [n], satellite indices.
      t: float [n], seconds from the epoch.
    Returns:
      (B float [n, 3, 3], w float [n, 3] [rad/s], dw/dt float [n, 3] [rad/s^2]).
    """
    t = np.asarray(t, np.float64)
    return evaluate(_rates_v, scene, sat, np.zeros((t.size, 8)), t, t)


def law_states(scene, sat, law, t0, t, jerk: bool = True):
    """Inertial states of attitude laws started at t0, at t (numpy).

    Angles, rates and accelerations of an aim law are the planner's own
    (:func:`jaxspline.geometry.pointing.aim_state`, through the compiled batch of
    :mod:`jaxspline.planner.opportunities`); yaw is zeroed for :data:`LAW_ZERO_YAW`, all three
    for :data:`LAW_NADIR`; :func:`compose` turns them into the inertial state. ε' is the
    central difference of the exact ε over +-:data:`JERK_STEP_S` (truncation ~1e-4 s^2
    times the fourth derivative of ω; zeros when ``jerk`` is False).

    Args:
      scene: Scene of the scenario's satellites.
      sat: int [n], satellite indices.
      law: float [n, 9], aim law [8] plus its yaw mode law[8] (``LAW_*``).
      t0: float [n], law start times [s from the epoch].
      t: float [n], evaluation times [s from the epoch].
      jerk: compute ε'.
    Returns:
      (q float [n, 4], ω [rad/s], ε [rad/s^2], ε' [rad/s^3] float [n, 3] each).
    """
    sat, law = np.asarray(sat), np.asarray(law, np.float64).reshape(-1, 9)
    t0, t = np.asarray(t0, np.float64), np.asarray(t, np.float64)
    if t.size == 0:
        z = np.zeros((0, 3))
        return np.zeros((0, 4)), z, z, z
    n = t.size
    if jerk:  # the three instants in one batch (every row is evaluated on its own)
        sat, law, t0 = np.tile(sat, 3), np.tile(law, (3, 1)), np.tile(t0, 3)
        t = np.concatenate([t, t + JERK_STEP_S, t - JERK_STEP_S])
    keep = np.stack([law[:, 8] != LAW_NADIR] * 2 + [law[:, 8] == LAW_POINTING], -1)
    state = evaluate(state_batched, scene, sat, law[:, :8], t0, t)
    ang, rate, acc = (np.where(keep, x, 0.0) for x in state)
    b, w, wd = frame_rates(scene, sat, t)
    x = np.concatenate([ang, rate, acc, w, wd, b.reshape(-1, 9)], -1)
    q, omega, eps = evaluate(_compose_v, scene, sat, x, t0, t)
    if not jerk:
        return q, omega, eps, np.zeros_like(eps)
    d = (eps[n : 2 * n] - eps[2 * n :]) / (2.0 * JERK_STEP_S)
    return q[:n], omega[:n], eps[:n], d


def state_angles(scene, sat, q, omega, eps, t):
    """Per-channel angles, rates and accelerations of inertial states (numpy).

    The inverse of :func:`law_states` (without yaw modes): what the per-channel model
    limits, for any attitude history (e.g. samples of a join).

    Args:
      scene: Scene of the scenario's satellites.
      sat: int [n], satellite indices.
      q: float [n, 4], attitude quaternions (scalar first, body -> TEME).
      omega: float [n, 3], body angular velocity [rad/s].
      eps: float [n, 3], body angular acceleration [rad/s^2].
      t: float [n], seconds from the epoch.
    Returns:
      (angles [rad], rates [rad/s], accelerations [rad/s^2]), float [n, 3] each.
    """
    b, w, wd = frame_rates(scene, sat, t)
    x = np.concatenate([q, omega, eps, w, wd, b.reshape(-1, 9)], -1)
    return evaluate(_decompose_v, scene, sat, x, t, t)
