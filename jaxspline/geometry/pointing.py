"""Pointing geometry: ground aim point -> body attitude (roll, pitch, yaw) in the orbital frame.

Orbital frame (OSK) at time t, from the ECI satellite position r and velocity v:
``z_o = -r/|r|`` (nadir), ``y_o = -(r x v)/|r x v|`` (minus the orbit normal),
``x_o = y_o x z_o`` (along-track, forward). Body axes: the camera boresight is
``z_b``, the push-broom detector line is ``y_b``, the image moves along ``x_b``.

Attitude angles (seeds/retarget-scan-pattern-optimization, eq. 7: pitch, then
roll, then yaw, each about the already-rotated axis): ``C = Ry(pitch) Rx(roll)
Rz(yaw)`` maps body to orbital coordinates, so the boresight in the orbital frame
is ``b = (cos roll sin pitch, -sin roll, cos roll cos pitch)``. For a unit line of
sight ``n`` to the aim point: ``pitch = atan2(n_x, n_z)``,
``roll = atan2(-n_y, hypot(n_x, n_z))``.

Yaw aligns the image motion with ``x_b`` (detector line across it): a scan
direction ``s`` (orbital frame) is expressed in the pitched-and-rolled frame,
``s' = (Ry Rx)^T s``, and ``yaw = atan2(s'_y, s'_x)``. For a strip, ``s`` is the
ground tangent of the strip at the aim point (the scene slides along the strip
as the boresight sweeps it). For a point target (tracked: no image motion at the
boresight) ``s`` is minus the target's motion in the orbital frame, i.e. the
direction the image would move for an orbit-fixed camera; at nadir without Earth
rotation this is ``x_o`` and yaw = 0, with Earth rotation it is the classic
yaw-steering angle (~3.8 deg at the equator for a 98 deg orbit).

Channel order everywhere: ``[roll, pitch, yaw]`` (C = 3). Rates and accelerations
are the time derivatives of these angles (the per-channel model of SPEC section 1),
computed by forward-mode autodiff (``jax.jvp``), never by finite differences.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import OMEGA_EARTH, R_EARTH
from jaxspline.geometry.frames import earth_rotation_angle, rot_z
from jaxspline.geometry.orbit import orbit_state
from jaxspline.kernels.batch import batched, padded_size
from jaxspline.kernels.validate import check_finite, is_concrete, to_device

__all__ = [
    "Scene",
    "aim_params",
    "aim_angles",
    "aim_state",
    "aim_geometry",
    "pointing_angles",
    "pointing_state",
    "off_nadir",
    "off_nadir_flat",
    "boresight",
    "roll_frame",
    "roll_look_direction",
    "roll_pointing",
    "roll_params",
    "ROLL_LAW",
]

#: Largest roll of roll-only pointing (exclusive) [deg].
RIGHT_ANGLE_DEG = 90.0
#: Kind code (last entry of an aim law) of a roll held fixed in the track frame.
ROLL_LAW = 2.0
_ROLL_SWITCH = 1.5  # kind codes above this are roll laws


class Scene(NamedTuple):
    """The pointing geometry of one scenario (a pytree).

    Attributes:
      orbit: a ``CircularOrbit`` or ``HermiteOrbit`` (jaxspline.geometry.orbit); a
        multi-satellite HermiteOrbit ([S, M, 3] tables) needs the ``sat`` argument of
        the kernels.
      gmst0: Earth rotation angle at t = 0 [rad] (``frames.gmst`` of the epoch).
    """

    orbit: object
    gmst0: jnp.ndarray


def aim_params(target_ecef, direction_ecef=None, speed=0.0):
    """Pack an aim law into the [8] parameter vector used by the kernels.

    ``[x0, y0, z0, dx, dy, dz, speed, kind]``: start point (ECEF, m), unit ground
    direction at the start (ECEF), ground speed of the aim point [m/s], and the law's
    kind: 1.0 for a strip (yaw from the strip tangent), 0.0 for a point target (yaw
    from the relative motion). The third kind, a roll held fixed in the track frame
    (:data:`ROLL_LAW`), is packed by :func:`roll_params`.

    Args:
      target_ecef: float [..., 3], start point, Earth-fixed [m].
      direction_ecef: float [..., 3], unit ground direction, Earth-fixed; None is a
        point target.
      speed: float [...], ground speed of the aim point [m/s] (0 for a point target).
    Returns:
      float [..., 8], the aim law p.
    """
    g0 = to_device(target_ecef)
    if direction_ecef is None:
        d = jnp.zeros_like(g0).at[..., 2].set(1.0)
        strip = jnp.zeros(g0.shape[:-1], g0.dtype)
        speed = jnp.zeros(g0.shape[:-1], g0.dtype)
    else:
        d = jnp.asarray(direction_ecef, g0.dtype)
        strip = jnp.ones(g0.shape[:-1], g0.dtype)
        speed = jnp.broadcast_to(jnp.asarray(speed, g0.dtype), g0.shape[:-1])
    return jnp.concatenate([g0, d, speed[..., None], strip[..., None]], -1)


def roll_params(roll, pitch=0.0):
    """Pack a roll law: the boresight held at (``roll``, ``pitch``) in the track frame (one
    candidate or broadcasting).

    The law of an area strip (and of every observation of a roll-only satellite, whose
    pitch is 0): at each instant the look direction is :func:`roll_look_direction` in the
    local frame of the Earth-fixed track (:func:`roll_frame`), the push-broom detector
    across the track, so the ground under the strip slides along the track. The packed
    vector is ``[roll, pitch, 0, 0, 0, 0, 0, ROLL_LAW]``; every aim-law kernel
    (:func:`aim_angles`, :func:`aim_state`, :func:`aim_geometry`) evaluates it, whatever
    the start ``t0``.

    Args:
      roll: float [...], roll [rad], positive towards ``across`` (|roll| < 90 deg).
      pitch: float [...], pitch [rad], positive forward (|pitch| < 90 deg).
    Returns:
      float [..., 8], the aim law p.
    """
    r, q = jnp.broadcast_arrays(jnp.asarray(roll), jnp.asarray(pitch))
    dt = jnp.result_type(r, q, float)
    r, q = r.astype(dt), q.astype(dt)
    z = jnp.zeros(r.shape + (5,), dt)
    kind = jnp.full(r.shape + (1,), ROLL_LAW, dt)
    return jnp.concatenate([r[..., None], q[..., None], z, kind], -1)


def _roll_los(scene: Scene, p, t, sat=None):
    """Unit look direction (ECI), the unit along-track direction (ECI) and the ground
    point's elevation sine of roll law p at time t (:func:`roll_params`).

    The satellite's Earth-fixed state is ``Rz(theta) r`` and ``Rz(theta) v - w_E z x
    pos`` (velocity relative to the rotating Earth, as the track frame asks); the ray
    meets the sphere of the WGS84 equatorial radius (-1 where it misses).
    """
    r, v = orbit_state(scene.orbit, t, sat)
    theta = earth_rotation_angle(scene.gmst0, t)
    pos = rot_z(theta, r)
    vel = rot_z(theta, v) - OMEGA_EARTH * jnp.stack([-pos[1], pos[0], jnp.zeros_like(pos[0])])
    nadir, along, across = roll_frame(pos, vel)
    d = jnp.cos(p[1]) * nadir + jnp.sin(p[1]) * along + jnp.tan(p[0]) * across
    d = rot_z(-theta, d / jnp.sqrt(jnp.sum(d * d)))
    rd = jnp.dot(r, d)
    disc = rd * rd - (jnp.dot(r, r) - R_EARTH * R_EARTH)
    hit = disc >= 0.0
    g = r + (-rd - jnp.sqrt(jnp.where(hit, disc, 0.0))) * d
    gn = jnp.sqrt(jnp.sum(g * g))
    elev = jnp.where(hit, jnp.dot(-d, g) / jnp.where(gn > 0, gn, 1.0), -1.0)
    return d, rot_z(-theta, along), elev


def aim_point(p, delta):
    """Aim point and unit ground tangent (ECEF) after an arc delta [rad] along the great circle.

    g(delta) = |g0| (u cos delta + d sin delta), u = g0/|g0|, d the start direction
    (made orthogonal to u): the great circle on the sphere through the start point.
    """
    g0, d = p[:3], p[3:6]
    rad = jnp.linalg.norm(g0)
    u = g0 / rad
    d = d - jnp.dot(d, u) * u
    dn2 = jnp.dot(d, d)
    # a point target's dummy direction (+z) is parallel to u at a pole: any unit d works
    d = jnp.where(dn2 > 0, d, jnp.array([1.0, 0.0, 0.0], d.dtype))
    d = d / jnp.sqrt(jnp.where(dn2 > 0, dn2, 1.0))
    c, s = jnp.cos(delta), jnp.sin(delta)
    return rad * (u * c + d * s), d * c - u * s


def _frame_los(scene: Scene, p, t0, t, sat=None):
    """LOS L [3] [m], its rate L' [3] [m/s] and the strip tangent [3], all in the orbital frame.

    L = B (g - r); L' = B (g' - v) - W x L, with B the orbital-frame basis (rows),
    g' = w_E z x g + (ground speed) * tangent (ECI), and W = (0, -|r x v| / |r|^2, 0)
    the orbital frame's angular velocity in its own axes (exact for Keplerian motion).
    """
    r, v = orbit_state(scene.orbit, t, sat)
    rn = jnp.linalg.norm(r)
    z = -r / rn
    h = jnp.cross(r, v)
    hn = jnp.linalg.norm(h)
    y = -h / hn
    x = jnp.cross(y, z)
    basis = jnp.stack([x, y, z])
    theta = earth_rotation_angle(scene.gmst0, t)
    rad_g = jnp.linalg.norm(p[:3])
    delta = p[6] * (t - t0) / rad_g
    g, tan = aim_point(p, delta)
    g_eci = rot_z(-theta, g)
    tan_eci = rot_z(-theta, tan)
    g_dot = OMEGA_EARTH * jnp.stack([-g_eci[1], g_eci[0], jnp.zeros_like(g_eci[0])])
    g_dot = g_dot + tan_eci * p[6]
    los = basis @ (g_eci - r)
    w = hn / rn**2
    w_x_los = jnp.stack([-w * los[2], jnp.zeros_like(w), w * los[0]])  # (0, -w, 0) x L
    los_dot = basis @ (g_dot - v) - w_x_los
    sees = jnp.dot(r - g_eci, g_eci)  # > 0 iff the satellite is above the aim point's horizon
    # a roll law (branchless): the held look direction, its image sliding along the track
    d_roll, along, elev = _roll_los(scene, p, t, sat)
    roll = p[7] > _ROLL_SWITCH
    los = jnp.where(roll, basis @ d_roll, los)
    los_dot = jnp.where(roll, jnp.zeros_like(los_dot), los_dot)
    tan_o = jnp.where(roll, basis @ along, basis @ tan_eci)
    sees = jnp.where(roll, elev, sees)
    return los, los_dot, tan_o, sees


def _angles_from(n, s):
    """Roll, pitch, yaw [3] from a unit LOS n and a scan direction s (orbital frame)."""
    pitch = jnp.arctan2(n[0], n[2])
    roll = jnp.arctan2(-n[1], jnp.hypot(n[0], n[2]))
    cp, sp, cr, sr = jnp.cos(pitch), jnp.sin(pitch), jnp.cos(roll), jnp.sin(roll)
    # s' = Rx(roll)^T Ry(pitch)^T s
    a = cp * s[0] - sp * s[2]  # after undoing the pitch
    b = s[1]
    c = sp * s[0] + cp * s[2]
    sx = a
    sy = cr * b + sr * c
    small = (jnp.abs(sx) + jnp.abs(sy)) < 1e-30
    yaw = jnp.arctan2(jnp.where(small, 0.0, sy), jnp.where(small, 1.0, sx))
    return jnp.stack([roll, pitch, yaw])


def aim_angles(scene: Scene, p, t0, t, sat=None):
    """Kernel: [roll, pitch, yaw, off_nadir] at time t for aim law p started at t0.

    off_nadir is pi when the aim point is below its horizon (seen through the Earth).
    The aim point moves along its great circle at ground speed p[6] from t0. Branchless
    in the point/strip switch; differentiable in t and t0. The aim point covers
    p[6] * (t - t0) metres of arc on the sphere of radius |g0| through the start point
    (within ~0.2 km of the ellipsoid for a 100 km strip).

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      p: float [8], aim law from :func:`aim_params`.
      t0: scalar, start of the aim law [s from the epoch].
      t: scalar, time [s from the epoch].
      sat: int, satellite index of a multi-satellite orbit table (None for one orbit).
    Returns:
      float [4], [roll, pitch, yaw, off_nadir] [rad].
    """

    los, los_dot, tan_o, sees = _frame_los(scene, p, t0, t, sat)
    n = los / jnp.linalg.norm(los)
    s = jnp.where(p[7] > 0.5, tan_o, -los_dot)
    ang = _angles_from(n, s)
    offn = jnp.arctan2(jnp.hypot(n[0], n[1]), n[2])
    offn = jnp.where(sees > 0, offn, jnp.pi)  # behind the Earth: not visible
    return jnp.concatenate([ang, offn[None]])


def aim_state(scene: Scene, p, t0, t, sat=None):
    """Kernel: (angle, rate, accel) of (roll, pitch, yaw), plus off-nadir, at time t.

    rate = d(angle)/dt and accel = d^2(angle)/dt^2 with t0 fixed, by nested
    ``jax.jvp`` of :func:`aim_angles`.

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      p: float [8], aim law from :func:`aim_params`.
      t0: scalar, start of the aim law [s from the epoch].
      t: scalar, time [s from the epoch].
      sat: int, satellite index of a multi-satellite orbit table (None for one orbit).
    Returns:
      (angle float [3] [rad], rate float [3] [rad/s], accel float [3] [rad/s^2],
      off_nadir scalar [rad]).
    """

    def f(tt):
        return aim_angles(scene, p, t0, tt, sat)

    def f1(tt):
        return jax.jvp(f, (tt,), (jnp.ones_like(tt),))

    (a, r), (_, acc) = jax.jvp(f1, (t,), (jnp.ones_like(t),))
    return a[:3], r[:3], acc[:3], a[3]


def aim_geometry(scene: Scene, p, t0, t, sat=None):
    """Kernel: imaging geometry of aim law p at time t, without attitude angles.

    The off-nadir angle is ``atan2(|d x n|, d . n)`` between the line of sight
    ``d = g - r`` and nadir ``n = -r``; the elevation sine is
    ``(r - g) . g / (|r - g| |g|)`` (> 0 iff the satellite is above the aim point's
    horizon, aeossp RULES.md rule 5). This is what rest-to-rest eigen-axis slews need
    (the angle between two lines of sight); one candidate, no autodiff, cheap.

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      p: float [8], aim law from :func:`aim_params`.
      t0: scalar, start of the aim law [s from the epoch].
      t: scalar, time [s from the epoch].
      sat: int, satellite index of a multi-satellite orbit table (None for one orbit).
    Returns:
      (off_nadir scalar [rad], elevation_sine scalar, los float [3], nadir float [3]):
      the unit line of sight and unit nadir in ECI (TEME).
    """
    r, _ = orbit_state(scene.orbit, t, sat)
    theta = earth_rotation_angle(scene.gmst0, t)
    g, _ = aim_point(p, p[6] * (t - t0) / jnp.linalg.norm(p[:3]))
    g_eci = rot_z(-theta, g)
    d = g_eci - r
    dn = jnp.linalg.norm(d)
    rn = jnp.linalg.norm(r)
    cr = jnp.cross(d, -r)
    offn = jnp.arctan2(jnp.linalg.norm(cr), jnp.dot(d, -r))
    elev = jnp.dot(-d, g_eci) / (dn * jnp.linalg.norm(g_eci))
    roll = p[7] > _ROLL_SWITCH  # a roll law (branchless)
    d_roll, _, elev_roll = _roll_los(scene, p, t, sat)
    offn_roll = jnp.arctan2(jnp.linalg.norm(jnp.cross(d_roll, -r)), jnp.dot(d_roll, -r))
    offn = jnp.where(roll, offn_roll, offn)
    elev = jnp.where(roll, elev_roll, elev)
    return offn, elev, jnp.where(roll, d_roll, d / dn), -r / rn


def _as_t(t, like):
    t = jnp.asarray(t)
    dt = jnp.result_type(t, like) if jnp.issubdtype(jnp.result_type(like), jnp.floating) else None
    if dt is None or not jnp.issubdtype(dt, jnp.floating):
        dt = jnp.result_type(float)
    return t.astype(dt)


def _point_kernel(scene, target, t):
    p = aim_params(target)
    return aim_angles(scene, p, jnp.zeros_like(t), t)


def _point_state_kernel(scene, target, t):
    p = aim_params(target)
    a, r, acc, _ = aim_state(scene, p, jnp.zeros_like(t), t)
    return jnp.stack([a, r, acc])


def _offn_kernel(scene, target, t):
    r, _ = orbit_state(scene.orbit, t)
    g = rot_z(-earth_rotation_angle(scene.gmst0, t), target)
    d = g - r
    nadir = -r
    cr = jnp.cross(d, nadir)
    offn = jnp.arctan2(jnp.sqrt(jnp.sum(cr * cr)), jnp.dot(d, nadir))
    return jnp.where(jnp.dot(-d, g) > 0, offn, jnp.pi)  # behind the Earth: pi


_offn_batched = batched(_offn_kernel, "(3),()->()", excluded={0})
_point_angles_batched = batched(_point_kernel, "(3),()->(4)", excluded={0})
_point_state_batched = batched(_point_state_kernel, "(3),()->(3,3)", excluded={0})


def _check_target(target_ecef, t):
    target = jnp.asarray(target_ecef)
    if target.shape[-1:] != (3,):
        raise ValueError(f"target_ecef must have shape [..., 3], got {target.shape}")
    check_finite("target_ecef", target)
    check_finite("t", t)
    t = _as_t(t, target)
    return target.astype(t.dtype), t


def pointing_angles(scene: Scene, target_ecef, t):
    """[roll, pitch, yaw] tracking a fixed ground point at times t.

    See the module docstring for the frames and the yaw law (point target: yaw from
    relative motion).

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      target_ecef: float [..., 3], ground point, Earth-fixed [m]; broadcasts with t.
      t: float [...], seconds from the epoch.
    Returns:
      float [..., 3], [roll, pitch, yaw] [rad].
    """
    target, t = _check_target(target_ecef, t)
    return _point_angles_batched(scene, target, t)[..., :3]


def off_nadir(scene: Scene, target_ecef, t):
    """Off-nadir angle of the line of sight to a ground point: atan2(|n x z_o|, n . z_o).

    A point below its horizon (satellite behind the Earth: (r - g) . g <= 0) gets pi.

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      target_ecef: float [..., 3], ground point, Earth-fixed [m]; broadcasts with t.
      t: float [...], seconds from the epoch.
    Returns:
      float [...], off-nadir angle [rad].
    """
    target, t = _check_target(target_ecef, t)
    return _offn_batched(scene, target, t)


def pointing_state(scene: Scene, target_ecef, t):
    """(angle, rate, accel) of [roll, pitch, yaw] tracking a ground point.

    Rates and accelerations are exact derivatives by ``jax.jvp``.

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      target_ecef: float [..., 3], ground point, Earth-fixed [m]; broadcasts with t.
      t: float [...], seconds from the epoch.
    Returns:
      (angle [rad], rate [rad/s], accel [rad/s^2]), float [..., 3] each.
    """
    target, t = _check_target(target_ecef, t)
    out = _point_state_batched(scene, target, t)
    return out[..., 0, :], out[..., 1, :], out[..., 2, :]


def off_nadir_flat(scene: Scene, targets_ecef, t):
    """Off-nadir angles of K (target, time) pairs (numpy in/out, float64 if enabled).

    Pads K to a power of two (>= 1024) so repeated calls reuse one compiled kernel.

    Args:
      scene: Scene, the orbit(s) and the Earth rotation angle at t = 0.
      targets_ecef: float [K, 3], ground points, Earth-fixed [m].
      t: float [K], seconds from the epoch.
    Returns:
      numpy float [K], off-nadir angles [rad].
    """
    targets = np.asarray(targets_ecef, np.float64).reshape(-1, 3)
    t = np.broadcast_to(np.asarray(t, np.float64), targets.shape[:1])
    k = targets.shape[0]
    m = padded_size(k)
    tg = np.concatenate([targets, np.repeat(targets[:1], m - k, 0)]) if k else np.ones((m, 3))
    tt = np.concatenate([t, np.full(m - k, t[0] if k else 0.0)])
    dt = jnp.result_type(float)
    return np.asarray(_offn_batched(scene, jnp.asarray(tg, dt), jnp.asarray(tt, dt)))[:k]


def boresight(roll, pitch):
    """Unit boresight in the orbital frame: (cos r sin p, -sin r, cos r cos p).

    Args:
      roll: float [...], roll angle r [rad].
      pitch: float [...], pitch angle p [rad].
    Returns:
      float [..., 3], unit vector.
    """
    roll, pitch = jnp.asarray(roll), jnp.asarray(pitch)
    return jnp.stack(
        [jnp.cos(roll) * jnp.sin(pitch), -jnp.sin(roll), jnp.cos(roll) * jnp.cos(pitch)], -1
    )


# ----------------------------------------------------------------------------
# roll-only pointing (regional_coverage RULES.md geometry)
# ----------------------------------------------------------------------------


def roll_frame(pos, vel):
    """The local frame of roll pointing: the track frame of area strips and roll-only satellites.

    ``nadir = -p/|p|``, ``along = v - (v.nadir) nadir`` normalized, ``across = along x
    nadir``, from the Earth-fixed position p and the velocity v relative to the rotating
    Earth (the regional_coverage benchmark's "Geometry" rule). Generic (numpy or JAX),
    broadcasting over leading axes.

    Args:
      pos: float [..., 3], Earth-fixed position p [m].
      vel: float [..., 3], Earth-fixed velocity v relative to the rotating Earth [m/s].
    Returns:
      (nadir [..., 3], along [..., 3], across [..., 3]), unit vectors.
    """
    xp = np if isinstance(pos, np.ndarray) and isinstance(vel, np.ndarray) else jnp
    r = xp.sqrt(xp.sum(pos * pos, axis=-1, keepdims=True))
    nadir = -pos / r
    along = vel - xp.sum(vel * nadir, axis=-1, keepdims=True) * nadir
    along = along / xp.sqrt(xp.sum(along * along, axis=-1, keepdims=True))
    return nadir, along, xp.cross(along, nadir)


def roll_look_direction(pos, vel, look_deg, pitch_deg=0.0):
    """Look direction ``down + tan(a) across`` of a held pointing offset (one candidate).

    ``down = cos(p) nadir + sin(p) along`` is nadir pitched by ``p`` towards the track;
    with ``p = 0`` it is nadir and the law is a roll-only satellite's (``nadir + tan(a)
    across``, the regional_coverage benchmark's). The body stays in the local frame of
    :func:`roll_frame`; during a strip the offset (a, p) is held fixed, so the look
    direction at each sample is this vector at that sample's state: the rays of one
    instant sweep the plane through ``down`` and ``across``. Not normalized: its length
    is ``sec a`` (the ray ``p + t d`` meets the ground where the caller solves for t).

    Args:
      pos: float [3], Earth-fixed position [m].
      vel: float [3], Earth-fixed velocity relative to the rotating Earth [m/s].
      look_deg: float [], look (roll) angle a [deg], positive towards ``across``.
      pitch_deg: float [], pitch p [deg], positive towards ``along`` (forward).
    Returns:
      float [3], the direction (length ``sec a``).
    """
    nadir, along, across = roll_frame(pos, vel)
    p = jnp.radians(pitch_deg)
    down = jnp.cos(p) * nadir + jnp.sin(p) * along
    return down + jnp.tan(jnp.radians(look_deg)) * across


def _roll_unit_kernel(pos, vel, roll_deg):
    d = roll_look_direction(pos, vel, roll_deg)
    return d / jnp.sqrt(jnp.sum(d * d))


_roll_unit_batched = batched(_roll_unit_kernel, "(3),(3),()->(3)")


def roll_pointing(pos, vel, roll_deg):
    """Unit look directions of a roll held fixed over a strip's samples (broadcasting).

    ``normalize(nadir + tan(r) across)`` at every sample (:func:`roll_look_direction`):
    the Earth-fixed boresight turns with the local frame while the roll r stays put.

    Args:
      pos: float [..., 3], Earth-fixed positions [m].
      vel: float [..., 3], Earth-fixed velocities relative to the rotating Earth [m/s].
      roll_deg: float [...], roll [deg], |roll| < 90; broadcasts with the samples.
    Returns:
      float [..., 3], unit look directions (Earth-fixed).
    Raises:
      ValueError: naming ``pos`` / ``vel`` (shape [..., 3], finite) or ``roll_deg``.
    """
    pos, vel = jnp.asarray(pos), jnp.asarray(vel)
    for name, x in (("pos", pos), ("vel", vel)):
        if x.shape[-1:] != (3,):
            raise ValueError(f"{name} must have shape [..., 3], got {x.shape}")
        check_finite(name, x)
    check_finite("roll_deg", roll_deg)
    if is_concrete(roll_deg) and np.any(np.abs(np.asarray(roll_deg)) >= RIGHT_ANGLE_DEG):
        raise ValueError(f"roll_deg must lie in (-90, 90), got {roll_deg!r}")
    dt = jnp.result_type(pos, vel, float)
    return _roll_unit_batched(pos.astype(dt), vel.astype(dt), jnp.asarray(roll_deg, dt))
