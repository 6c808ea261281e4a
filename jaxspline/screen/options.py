"""The option table: the data contract between geometry and the engine.

Route *options* are plain struct-of-arrays tables: no Python objects per
candidate, so millions fit in memory and every field can go through ``jit``.
This module holds the table's types (:class:`RouteOptions`, the
:class:`RouteModel` protocol), its eager checks (:func:`validate_options`) and
the builder from a :class:`jaxspline.geometry.routes.RouteSet`
(:func:`build_route_options`; the planner's builder is
:mod:`jaxspline.planner.opportunities`).
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import SECONDS_PER_DAY, gmst
from jaxspline.geometry.frames import sun_direction
from jaxspline.geometry.routes import STRIP, RouteSet, sample_aim_states
from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.validate import check_positive

__all__ = [
    "RouteModel",
    "RouteOptions",
    "build_route_options",
    "options_dtype",
    "take_options",
    "validate_options",
]


class RouteOptions(NamedTuple):
    """N imaging options (a target, a satellite, a start time), C attitude channels.

    Attributes:
      route: int [N], index of the route (target) this option images (0..R-1).
      t_start: [N] start time of imaging [s from the scenario epoch].
      t_end: [N] end time of imaging [s].
      start_angle, start_rate: [N, C] channel angle [rad] and rate [rad/s] at t_start.
      end_angle, end_rate: [N, C] channel angle [rad] and rate [rad/s] at t_end.
      value: [N] value (priority) collected if this option is imaged.
      scan_ok: bool [N], the scan itself is feasible (visible, within rate/accel
        limits); options with ``scan_ok == False`` are dropped before screening.
      sat: int [N], satellite of the option (None: one satellite, index 0).
      start_los, end_los: [N, 3] unit lines of sight (ECI) at t_start / t_end, for
        rest-to-rest eigen-axis slews (None when no model needs them).
      start_nadir: [N, 3] unit nadir (ECI) at t_start: the attitude a satellite
        starts the plan in, seen at this option's start (None as above).

    A transition option i -> option j (same satellite) takes T = t_start[j] -
    t_end[i] seconds; what it must achieve in T depends on the satellite's maneuver
    model (:mod:`jaxspline.screen.models`). For the per-channel model every channel goes from
    (end_angle[i], end_rate[i]) to (start_angle[j], start_rate[j]) in exactly T.
    """

    route: jnp.ndarray
    t_start: jnp.ndarray
    t_end: jnp.ndarray
    start_angle: jnp.ndarray
    start_rate: jnp.ndarray
    end_angle: jnp.ndarray
    end_rate: jnp.ndarray
    value: jnp.ndarray
    scan_ok: jnp.ndarray
    sat: jnp.ndarray | None = None
    start_los: jnp.ndarray | None = None
    end_los: jnp.ndarray | None = None
    start_nadir: jnp.ndarray | None = None


def take_options(options: RouteOptions, idx) -> RouteOptions:
    """The options at positions ``idx``; None fields stay None.

    Args:
      options: RouteOptions of N options.
      idx: numpy fancy index (int [M]) or mask (bool [N]).
    Returns:
      RouteOptions with numpy fields of M rows.
    """
    return type(options)(*(None if x is None else np.asarray(x)[idx] for x in options))


class RouteModel(Protocol):
    """A differentiable map from route start times to boundary states (for refinement).

    Implemented by :class:`jaxspline.geometry.routes.RouteSet`.
    """

    def states(self, route, t0):
        """Boundary states of routes started at t0; jit-able, differentiable in ``t0``.

        Args:
          route: int [K], route indices.
          t0: float [K], start times [s from the epoch].
        Returns:
          (t_end float [K] [s], start_angle [rad], start_rate [rad/s], end_angle [rad],
          end_rate [rad/s], float [K, C] each).
        """
        ...

    def window(self, route):
        """Start-time windows of routes.

        Args:
          route: int [K], route indices.
        Returns:
          (t0_min, t0_max), float [K] each [s from the epoch].
        """
        ...

    def value_of(self, route):
        """Values (priorities) of routes.

        Args:
          route: int [K], route indices.
        Returns:
          float [K].
        """
        ...


def options_dtype(options: RouteOptions):
    """Floating dtype the engine computes in: that of ``options.start_angle``.

    Args:
      options: RouteOptions.
    Returns:
      a JAX floating dtype (JAX's default float when ``start_angle`` is not floating;
      float64 becomes float32 when x64 is off).
    """
    dt = jnp.result_type(options.start_angle)
    if not jnp.issubdtype(dt, jnp.floating):
        return jnp.result_type(float)
    return jax.dtypes.canonicalize_dtype(dt)  # float64 -> float32 when x64 is off


def validate_options(options: RouteOptions, name: str = "options") -> int:
    """Eagerly check shapes and values of a RouteOptions table.

    Args:
      options: RouteOptions of N options and C channels.
      name: argument name used in the error messages.
    Returns:
      int, the number of channels C.
    Raises:
      ValueError: naming the field when shapes disagree (N options, C channels),
        times are not finite, ``t_end < t_start`` or a boundary state is NaN.
    """
    if not isinstance(options, RouteOptions):
        raise ValueError(f"{name} must be a RouteOptions, got {type(options).__name__}")
    n = np.shape(options.t_start)
    if len(n) != 1:
        raise ValueError(f"{name}.t_start must be 1-D [N], got shape {n}")
    (nn,) = n
    for f in ("route", "t_end", "value", "scan_ok"):
        if np.shape(getattr(options, f)) != (nn,):
            got = np.shape(getattr(options, f))
            raise ValueError(f"{name}.{f} must have shape ({nn},), got {got}")
    sa = np.shape(options.start_angle)
    if len(sa) != 2 or sa[0] != nn:
        raise ValueError(f"{name}.start_angle must have shape ({nn}, C), got {sa}")
    for f in ("start_rate", "end_angle", "end_rate"):
        if np.shape(getattr(options, f)) != sa:
            got = np.shape(getattr(options, f))
            raise ValueError(f"{name}.{f} must have shape {sa}, got {got}")
    ts, te = np.asarray(options.t_start, float), np.asarray(options.t_end, float)
    if not (np.isfinite(ts).all() and np.isfinite(te).all()):
        raise ValueError(f"{name}.t_start/t_end must be finite")
    bad = np.flatnonzero(te < ts)
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"{name}.t_end must be >= t_start, got t_end[{k}]={te[k]!r} < {ts[k]!r}")
    for f in ("start_angle", "start_rate", "end_angle", "end_rate", "value"):
        if np.isnan(np.asarray(getattr(options, f), float)).any():
            raise ValueError(f"{name}.{f} must not contain NaN")
    return sa[1]


class OptionInfo(NamedTuple):
    """Per-option side data of :func:`build_route_options` (numpy arrays).

    Attributes:
      speed: float [N], ground scan speed [m/s] (0 for points).
      t0: float [N], scan start time [s from the epoch].
      peak_rate: float [N, C], max |rate| during the scan [rad/s].
      peak_accel: float [N, C], max |accel| during the scan [rad/s^2].
      max_off_nadir: float [N], largest off-nadir angle during the scan [rad].
      sun_elevation: float [N], Sun elevation at the start point and t0 [rad].
    """

    speed: np.ndarray
    t0: np.ndarray
    peak_rate: np.ndarray
    peak_accel: np.ndarray
    max_off_nadir: np.ndarray
    sun_elevation: np.ndarray


def build_route_options(
    routes: RouteSet,
    limits: AxisLimits,
    max_off_nadir: float,
    *,
    n_t0: int = 8,
    scan_speeds=(7000.0,),
    samples: int = 9,
    epoch_jd: float | None = None,
    sun_elevation_min: float | None = None,
    chunk: int = 8192,
    progress: bool = False,
):
    """Start options of every route: t0 grid x scan speeds, boundary states, ``scan_ok``.

    For route r with a non-empty window, t0 takes ``n_t0`` equally spaced values in
    [t0_min, t0_max] (one value if the window is a point); strips take every speed in
    ``scan_speeds`` [m/s] (duration = length / speed), points one option per t0.
    Each option's scan is sampled at ``samples`` equally spaced times in
    [t0, t_end]; ``scan_ok`` requires at every sample |rate_c| <= limits.rate[c],
    |accel_c| <= limits.accel[c], off-nadir <= ``max_off_nadir`` [rad], and (if
    ``sun_elevation_min`` [rad] and ``epoch_jd`` are given) a Sun elevation at the
    start point >= the minimum at t0. States come from the exact pointing law with
    autodiff rates (SPEC section 3, retarget-scan pattern, Steps 1-3). Jerk limits
    are not checked on the scan.

    Returns:
      (RouteOptions with N options, OptionInfo). The options keep ``scan_ok == False``
      rows; the caller drops them before screening. OptionInfo, a NamedTuple per
      option: ``speed`` [m/s], ``t0`` [s], ``peak_rate`` [N, C] [rad/s], ``peak_accel``
      [N, C] [rad/s^2], ``max_off_nadir`` [rad] and ``sun_elevation`` [rad].
    """
    if n_t0 < 1 or samples < 2:
        raise ValueError(f"n_t0 must be >= 1 and samples >= 2, got n_t0={n_t0}, samples={samples}")
    speeds = np.atleast_1d(np.asarray(scan_speeds, np.float64))
    check_positive("scan_speeds", speeds)
    grid = _option_grid(routes, n_t0, speeds)
    if grid is None:
        return _no_options()
    route, t0, speed = grid
    scan = _sample_scans(routes, route, t0, speed, samples, chunk, progress)
    rate_lim = np.broadcast_to(np.asarray(limits.rate, np.float64), (3,))
    acc_lim = np.broadcast_to(np.asarray(limits.accel, np.float64), (3,))
    peak_rate = np.abs(scan.rate).max(1)
    peak_acc = np.abs(scan.accel).max(1)
    max_off = scan.off_nadir.max(1)
    ok = (
        (peak_rate <= rate_lim).all(-1)
        & (peak_acc <= acc_lim).all(-1)
        & (max_off <= max_off_nadir + 1e-9)
        & np.isfinite(scan.angle).all((1, 2))
    )
    sun_el = np.full(route.size, np.nan)
    if epoch_jd is not None:
        sun_el = _sun_elevation(routes, route, t0, epoch_jd)
        if sun_elevation_min is not None:
            ok &= sun_el >= sun_elevation_min
    dtype = jnp.result_type(float)
    opts = RouteOptions(
        route=jnp.asarray(route),
        t_start=jnp.asarray(t0, dtype),
        t_end=jnp.asarray(t0 + scan.duration, dtype),
        start_angle=jnp.asarray(scan.angle[:, 0], dtype),
        start_rate=jnp.asarray(scan.rate[:, 0], dtype),
        end_angle=jnp.asarray(scan.angle[:, -1], dtype),
        end_rate=jnp.asarray(scan.rate[:, -1], dtype),
        value=jnp.asarray(np.asarray(routes.value)[route], dtype),
        scan_ok=jnp.asarray(ok),
    )
    info = OptionInfo(speed, t0, peak_rate, peak_acc, max_off, sun_el)
    return opts, info


def _option_grid(routes: RouteSet, n_t0: int, speeds):
    """(route, t0, speed) [N] of every option: ``n_t0`` starts spread over each non-empty
    window (one when the window is a point) times every speed for strips (0 for points);
    None when no route has a window."""
    kind = np.asarray(routes.kind)
    t0_min, t0_max = np.asarray(routes.t0_min), np.asarray(routes.t0_max)
    rows_r, rows_t0, rows_v = [], [], []
    for r in np.nonzero(t0_min <= t0_max)[0]:
        t0s = (
            np.linspace(t0_min[r], t0_max[r], n_t0) if t0_max[r] > t0_min[r] else t0_min[r : r + 1]
        )
        vs = speeds if kind[r] == STRIP else np.zeros(1)
        rr, tt, vv = np.meshgrid([r], t0s, vs, indexing="ij")
        rows_r.append(rr.ravel())
        rows_t0.append(tt.ravel())
        rows_v.append(vv.ravel())
    if not rows_r:
        return None
    return np.concatenate(rows_r), np.concatenate(rows_t0), np.concatenate(rows_v)


def _no_options():
    """The empty option table and side data (no route has a window)."""
    empty = np.zeros((0, 3))
    z = np.zeros(0)
    opts = RouteOptions(
        *(jnp.asarray(x) for x in (z.astype(np.int64), z, z, empty, empty, empty, empty, z)),
        scan_ok=jnp.zeros(0, bool),
    )
    return opts, OptionInfo(z, z, empty, empty, z, z)


class _Scans(NamedTuple):
    """The sampled scans of N options (numpy): duration [N] [s]; angle, rate, accel
    [N, samples, 3] [rad, rad/s, rad/s^2]; off_nadir [N, samples] [rad]."""

    duration: np.ndarray
    angle: np.ndarray
    rate: np.ndarray
    accel: np.ndarray
    off_nadir: np.ndarray


def _sample_scans(routes: RouteSet, route, t0, speed, samples, chunk, progress) -> _Scans:
    """The exact pointing law of every option at ``samples`` instants of its scan."""
    kind = np.asarray(routes.kind)
    length, duration = np.asarray(routes.length), np.asarray(routes.duration)
    n, c = route.size, 3
    p = np.asarray(routes.params)[route].copy()
    p[:, 6] = speed
    dur = np.where(
        kind[route] == STRIP, length[route] / np.where(speed > 0, speed, 1.0), duration[route]
    )
    frac = np.linspace(0.0, 1.0, samples)
    ts = t0[:, None] + dur[:, None] * frac[None, :]
    ang, rate, acc, offn = sample_aim_states(
        routes.scene,
        np.repeat(p, samples, axis=0),
        np.repeat(t0, samples),
        ts.ravel(),
        chunk,
        "route options" if progress else None,
    )
    return _Scans(
        dur,
        ang.reshape(n, samples, c),
        rate.reshape(n, samples, c),
        acc.reshape(n, samples, c),
        offn.reshape(n, samples),
    )


def _sun_elevation(routes: RouteSet, route, t0, epoch_jd: float):
    """Sun elevation [rad] at each option's start point at its start time t0 [s]."""
    jd = epoch_jd + t0 / SECONDS_PER_DAY
    sun = sun_direction(jd)
    th = gmst(jd)
    sun_e = np.stack(
        [
            np.cos(th) * sun[:, 0] + np.sin(th) * sun[:, 1],
            -np.sin(th) * sun[:, 0] + np.cos(th) * sun[:, 1],
            sun[:, 2],
        ],
        -1,
    )
    la, lo = np.asarray(routes.lat)[route], np.asarray(routes.lon)[route]
    up = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1)
    return np.arcsin(np.clip(np.sum(up * sun_e, -1), -1.0, 1.0))
