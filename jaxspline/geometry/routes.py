"""Imaging routes (point targets and strips), their start-time windows and start options.

A *route* is either
- a point target: the boresight tracks one ground point for ``duration`` seconds;
- a strip: the aim point runs along a great circle from a start point at
  ``azimuth`` for ``length`` metres at a ground ``scan speed`` (so the duration is
  length / speed); push-broom yaw aligns the detector line across the strip.

Each route has a window of allowed start times ``[t0_min, t0_max]`` (visibility
under the off-nadir limit intersected with any user window) and a value
(priority). Following the retarget-scan pattern (SPEC section 3, seeds/retarget-
scan-pattern-optimization, Steps 1-3) every route gets a grid of start times
``t0`` in its window and, for strips, a small set of scan speeds; each option's
scan is checked (visible, rates/accelerations within limits, Sun elevation) into
``scan_ok``, and the boundary states (angle, rate per channel at start and end)
go into a :class:`jaxspline.screen.options.RouteOptions` table.

:class:`RouteSet` implements :class:`jaxspline.screen.options.RouteModel`: a
differentiable ``states(route, t0)`` for refinement.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import geodetic_to_ecef
from jaxspline.geometry.frames import earth_rotation_angle, ecef_to_geodetic
from jaxspline.geometry.orbit import orbit_state
from jaxspline.geometry.pointing import Scene, aim_state, off_nadir_flat
from jaxspline.kernels.batch import map_chunked
from jaxspline.kernels.validate import check_finite, check_positive
from jaxspline.readers.mission import AREA, KIND_NAMES, POINT, STEREO, STRIP  # noqa: F401 (the kinds, read here too)

__all__ = [
    "RouteSet",
    "make_route_spec",
    "make_route_set",
    "strip_direction",
    "sample_aim_states",
]


class RouteSpec(NamedTuple):
    """User-level description of R routes (numpy arrays [R]; angles rad, lengths m, times s).

    Attributes:
      kind: POINT (0) or STRIP (1).
      lat, lon: geodetic start point (the target for a point route).
      azimuth: strip direction at the start, clockwise from north (0 for points).
      length: strip length [m] (0 for points).
      duration: imaging time of a point target [s] (0 for strips).
      value: priority collected if the route is imaged (> 0).
      t0_lo, t0_hi: user window of start times [s] (-inf/+inf when free).
    """

    kind: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    azimuth: np.ndarray
    length: np.ndarray
    duration: np.ndarray
    value: np.ndarray
    t0_lo: np.ndarray
    t0_hi: np.ndarray


def make_route_spec(
    kind, lat, lon, azimuth=0.0, length=0.0, duration=0.0, value=1.0, t0_lo=-np.inf, t0_hi=np.inf
) -> RouteSpec:
    """Validate and broadcast route fields into a RouteSpec.

    All fields broadcast together (scalars allowed).

    Args:
      kind: int [R], POINT (0) or STRIP (1).
      lat: float [R], geodetic latitude of the start point [rad], in [-pi/2, pi/2].
      lon: float [R], longitude of the start point [rad].
      azimuth: float [R], strip direction, clockwise from north [rad].
      length: float [R], strip length [m], > 0 for strips.
      duration: float [R], imaging time of a point target [s], > 0 for points.
      value: float [R], priority, > 0.
      t0_lo: float [R], earliest start [s from the epoch] (-inf: free).
      t0_hi: float [R], latest start [s from the epoch] (+inf: free).
    Returns:
      RouteSpec, a NamedTuple of the arguments broadcast to numpy [R] arrays.
    Raises:
      ValueError: naming the field (kind, not finite, lat range, value, length,
        duration, t0_lo > t0_hi, shapes).
    """
    kind = np.atleast_1d(np.asarray(kind, dtype=np.int64))
    if not np.isin(kind, (POINT, STRIP)).all():
        raise ValueError(f"kind must be 0 (point) or 1 (strip), got {kind.tolist()}")
    arrs = {
        "lat": lat,
        "lon": lon,
        "azimuth": azimuth,
        "length": length,
        "duration": duration,
        "value": value,
        "t0_lo": t0_lo,
        "t0_hi": t0_hi,
    }
    try:
        out = dict(
            zip(
                arrs,
                np.broadcast_arrays(*(np.asarray(v, np.float64) for v in arrs.values()), kind),
                strict=False,
            )
        )
    except ValueError as exc:
        raise ValueError(f"route fields are not broadcastable: {exc}") from exc
    kind = np.broadcast_to(kind, out["lat"].shape)
    for name in ("lat", "lon", "azimuth", "length", "duration", "value"):
        check_finite(name, out[name])
    if (np.abs(out["lat"]) > np.pi / 2).any():
        raise ValueError(f"lat must be within [-pi/2, pi/2] rad, got {out['lat'].tolist()}")
    check_positive("value", out["value"])
    if (out["length"][kind == STRIP] <= 0).any():
        raise ValueError("length must be > 0 for strips")
    if (out["duration"][kind == POINT] <= 0).any():
        raise ValueError("duration must be > 0 for point targets")
    if (out["t0_lo"] > out["t0_hi"]).any():
        raise ValueError("t0_lo must be <= t0_hi (route window)")
    return RouteSpec(kind=np.array(kind), **{k: np.array(v) for k, v in out.items()})


def strip_direction(lat, lon, azimuth):
    """Unit ECEF ground direction at (lat, lon) for an azimuth (from north, clockwise).

    Args:
      lat: float [...], geodetic latitude [rad].
      lon: float [...], longitude [rad].
      azimuth: float [...], direction clockwise from north [rad].
    Returns:
      float [..., 3], unit direction, Earth-fixed.
    """
    lat, lon, az = (np.asarray(x, np.float64) for x in (lat, lon, azimuth))
    north = np.stack([-np.sin(lat) * np.cos(lon), -np.sin(lat) * np.sin(lon), np.cos(lat)], -1)
    east = np.stack([-np.sin(lon), np.cos(lon), np.zeros_like(lon)], -1)
    return np.cos(az)[..., None] * north + np.sin(az)[..., None] * east


def _sample_kernel(scene, p, t0, t):
    a, r, acc, offn = aim_state(scene, p, t0, t)
    return a, r, acc, offn


_sample_batched = jax.jit(jax.vmap(_sample_kernel, in_axes=(None, 0, 0, 0)))


@jax.jit
def _states_jit(scene, params, duration, route, t0):
    p = params[route].astype(t0.dtype)
    t1 = t0 + duration[route].astype(t0.dtype)
    # one batched evaluation of both ends (one kernel copy in the compiled graph)
    a, r, _, _ = jax.vmap(_sample_kernel, in_axes=(None, 0, 0, 0))(
        scene, jnp.concatenate([p, p]), jnp.concatenate([t0, t0]), jnp.concatenate([t0, t1])
    )
    k = t0.shape[0]
    return t1, a[:k], r[:k], a[k:], r[k:]


def sample_aim_states(scene, p, t0, t, chunk=8192, desc=None):
    """``aim_state`` at M (p, t0, t) triples in padded chunks (one compiled shape).

    Args:
      scene: Scene.
      p: float [M, 8], aim laws.
      t0: float [M], aim-law start times [s from the epoch].
      t: float [M], sample times [s from the epoch].
      chunk: int, rows per compiled call.
      desc: label of a progress bar (None: none).
    Returns:
      numpy (angle [rad], rate [rad/s], accel [rad/s^2]), float [M, 3] each, and
      off_nadir float [M] [rad].
    """
    if t.size == 0:
        z = np.zeros((0, 3))
        return z, z, z, np.zeros(0)
    dtype = jnp.result_type(float)

    def run(*args):
        return _sample_batched(scene, *(jnp.asarray(a, dtype) for a in args))

    return tuple(map_chunked(run, (p, t0, t), chunk, desc=desc))


class RouteSet(NamedTuple):
    """R routes ready for pointing: a :class:`jaxspline.screen.options.RouteModel` implementation.

    Attributes:
      scene: the :class:`jaxspline.geometry.pointing.Scene`.
      params: [R, 8] aim laws (:func:`jaxspline.geometry.pointing.aim_params`; strips at the
        current scan speed, see :meth:`with_speeds`).
      kind: int [R]; length: [R] m; duration: [R] s (points; strips: length / speed).
      t0_min, t0_max: [R] start-time window [s] (+inf/-inf when never visible).
      value: [R] value (priority) of each route.
      lat, lon, azimuth: [R] the (possibly direction-flipped) start points [rad].
    """

    scene: Scene
    params: jnp.ndarray
    kind: jnp.ndarray
    length: jnp.ndarray
    duration: jnp.ndarray
    t0_min: jnp.ndarray
    t0_max: jnp.ndarray
    value: jnp.ndarray
    lat: jnp.ndarray
    lon: jnp.ndarray
    azimuth: jnp.ndarray

    def states(self, route, t0):
        """Exact pointing-law states at t0 and t_end = t0 + duration.

        Jit-able and differentiable in t0 (RouteModel protocol).

        Args:
          route: int [K], route indices.
          t0: float [K], start times [s from the epoch].
        Returns:
          (t_end float [K] [s], start_angle [rad], start_rate [rad/s], end_angle [rad],
          end_rate [rad/s], float [K, C] each).
        """
        t0 = jnp.asarray(t0)
        if not jnp.issubdtype(t0.dtype, jnp.floating):
            t0 = t0.astype(jnp.result_type(float))
        return _states_jit(self.scene, self.params, self.duration, jnp.asarray(route), t0)

    def window(self, route):
        """Start-time windows of the given routes.

        Args:
          route: int [K], route indices.
        Returns:
          (t0_min, t0_max), float [K] each [s].
        """
        return self.t0_min[route], self.t0_max[route]

    def value_of(self, route):
        """Values of the given routes.

        Args:
          route: int [K], route indices.
        Returns:
          float [K].
        """
        return self.value[route]

    def with_speeds(self, route, speed) -> RouteSet:
        """A copy with some strips scanned at new ground speeds.

        Use before refinement so ``states`` reproduces the chosen options' scan speeds
        (points ignore the speed).

        Args:
          route: int [K], route indices.
          speed: float [K], ground speeds [m/s].
        Returns:
          RouteSet.
        """
        route = np.asarray(route, dtype=np.int64)
        speed = np.broadcast_to(np.asarray(speed, np.float64), route.shape)
        kind = np.asarray(self.kind)
        params = np.array(self.params)
        dur = np.array(self.duration)
        strip = kind[route] == STRIP
        r_s = route[strip]
        params[r_s, 6] = speed[strip]
        dur[r_s] = np.asarray(self.length)[r_s] / speed[strip]
        return self._replace(params=jnp.asarray(params), duration=jnp.asarray(dur))


def make_route_set(
    scene: Scene,
    spec: RouteSpec,
    t_begin: float,
    t_end: float,
    max_off_nadir: float,
    nominal_speed: float = 7000.0,
    step: float = 10.0,
) -> RouteSet:
    """Place routes under the pass: direction of strips, start-time windows, aim laws.

    - A strip whose direction opposes the satellite's ground motion (negative dot
      product of its ECI tangent with the satellite velocity at the start point's
      closest approach) is scanned from its other end (push-broom images forward).
    - Window: the start point must be within ``max_off_nadir``; t0 ranges over
      the longest visibility interval of the start point in [t_begin, t_end],
      intersected with the user window, with t0_max reduced by the route's duration
      at ``nominal_speed`` (strips). Invisible routes get (+inf, -inf).

    The ``scan_ok`` check of :func:`build_route_options` covers the rest of the scan.

    Args:
      scene: Scene.
      spec: RouteSpec of R routes.
      t_begin: float, start of the planning horizon [s from the epoch].
      t_end: float, end of the planning horizon [s from the epoch].
      max_off_nadir: float, off-nadir limit [rad].
      nominal_speed: float, strip ground speed used for the windows [m/s].
      step: float, visibility sampling step [s].
    Returns:
      RouteSet of R routes.
    """
    from jaxspline.geometry.pointing import aim_params
    from jaxspline.geometry.windows import visibility_windows

    check_positive("max_off_nadir", max_off_nadir)
    check_positive("nominal_speed", nominal_speed)
    strip = spec.kind == STRIP
    grid = np.linspace(t_begin, t_end, max(int((t_end - t_begin) / step), 1) + 1)
    lat, lon, az = _scan_forward(scene, spec, strip, grid)
    r_e = np.asarray(geodetic_to_ecef(lat, lon, 0.0))
    wins = visibility_windows(scene, r_e, t_begin, t_end, max_off_nadir, step=step)
    dur = np.where(strip, spec.length / nominal_speed, spec.duration)
    t0_min, t0_max = _start_windows(wins, dur, spec)
    d = strip_direction(lat, lon, az)
    params = np.array(aim_params(jnp.asarray(r_e), jnp.asarray(d), nominal_speed))
    params[:, 6] = np.where(strip, nominal_speed, 0.0)
    params[:, 7] = strip.astype(np.float64)
    return RouteSet(
        scene=scene,
        params=jnp.asarray(params),
        kind=jnp.asarray(spec.kind),
        length=jnp.asarray(spec.length),
        duration=jnp.asarray(dur),
        t0_min=jnp.asarray(t0_min),
        t0_max=jnp.asarray(t0_max),
        value=jnp.asarray(spec.value),
        lat=jnp.asarray(lat),
        lon=jnp.asarray(lon),
        azimuth=jnp.asarray(az),
    )


def _scan_forward(scene: Scene, spec: RouteSpec, strip, grid):
    """Start points and azimuths [rad] of the routes, every strip scanned along the flight.

    A strip whose ECI tangent at its start point opposes the satellite velocity at the
    start point's closest approach (least off-nadir angle on ``grid``) starts from its
    other end instead (push-broom images forward). Returns copies (lat, lon, azimuth).
    """
    lat, lon, az = spec.lat.copy(), spec.lon.copy(), spec.azimuth.copy()
    if not strip.any():
        return lat, lon, az
    rs_ = np.asarray(geodetic_to_ecef(lat, lon, 0.0))[strip]
    offn = off_nadir_flat(scene, np.repeat(rs_, grid.size, 0), np.tile(grid, rs_.shape[0]))
    offn = offn.reshape(rs_.shape[0], grid.size)
    t_ca = grid[np.argmin(offn, axis=1)]
    _, v = orbit_state(scene.orbit, jnp.asarray(t_ca))
    theta = earth_rotation_angle(np.asarray(scene.gmst0), t_ca)
    d = strip_direction(lat[strip], lon[strip], az[strip])
    # ECEF -> ECI rotation of the tangent (the Earth-rotation term does not matter for a sign)
    c, s = np.cos(theta), np.sin(theta)
    d_eci = np.stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1], d[:, 2]], -1)
    back = np.sum(d_eci * np.asarray(v), -1) < 0
    if back.any():
        idx = np.nonzero(strip)[0][back]
        la, lo, azb = _great_circle_end(lat[idx], lon[idx], az[idx], spec.length[idx])
        lat[idx], lon[idx], az[idx] = la, lo, azb
    return lat, lon, az


def _start_windows(wins, dur, spec: RouteSpec):
    """(t0_min, t0_max) [s] per route: the longest visibility interval of its start point
    cut to the user window, its end reduced by the route's duration; (+inf, -inf) when
    empty."""
    t0_min = np.full(dur.shape, np.inf)
    t0_max = np.full(dur.shape, -np.inf)
    for i, w in enumerate(wins):
        if w.shape[0] == 0:
            continue
        k = int(np.argmax(w[:, 1] - w[:, 0]))
        lo_, hi_ = max(w[k, 0], spec.t0_lo[i]), min(w[k, 1] - dur[i], spec.t0_hi[i])
        if lo_ <= hi_:
            t0_min[i], t0_max[i] = lo_, hi_
    return t0_min, t0_max


def _great_circle_end(lat, lon, az, length):
    """End point (geodetic lat, lon [rad]) and reversed azimuth [rad] of a strip of ``length`` [m].

    Same arc as the aim law of :func:`jaxspline.geometry.pointing.aim_angles`: the great circle
    on the sphere through the start point's ECEF position g0, direction = the ground
    direction made orthogonal to g0; numpy, for geometry and plots.
    """
    g0 = np.asarray(geodetic_to_ecef(lat, lon, 0.0))
    rad = np.linalg.norm(g0, axis=-1, keepdims=True)
    u = g0 / rad
    d = strip_direction(lat, lon, az)
    d = d - np.sum(d * u, -1, keepdims=True) * u
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    delta = np.asarray(length, np.float64)[..., None] / rad
    e = rad * (u * np.cos(delta) + d * np.sin(delta))
    tan = d * np.cos(delta) - u * np.sin(delta)
    lat2, lon2, _ = (np.asarray(x) for x in ecef_to_geodetic(e))
    north = np.stack([-np.sin(lat2) * np.cos(lon2), -np.sin(lat2) * np.sin(lon2), np.cos(lat2)], -1)
    east = np.stack([-np.sin(lon2), np.cos(lon2), np.zeros_like(lon2)], -1)
    az2 = np.arctan2(np.sum(-tan * east, -1), np.sum(-tan * north, -1))
    return lat2, lon2, az2
