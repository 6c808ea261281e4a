"""The data contract between geometry (routes) and the engine (screen/sequence/refine).

Route *options* are plain struct-of-arrays tables: no Python objects per
candidate, so millions fit in memory and every field can go through ``jit``.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import jax.numpy as jnp
import numpy as np

__all__ = ["RouteOptions", "RouteModel", "take_options"]


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
    model (:mod:`jaxspline.engine.models`). For the per-channel model every channel goes from
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
    """The options at positions ``idx`` (numpy fancy index or mask); None fields stay None."""
    return type(options)(*(None if x is None else np.asarray(x)[idx] for x in options))


class RouteModel(Protocol):
    """A differentiable map from route start times to boundary states (for refinement).

    ``states(route, t0)`` takes int route indices [K] and start times t0 [K] [s]
    and returns ``(t_end [K], start_angle [K, C], start_rate [K, C],
    end_angle [K, C], end_rate [K, C])``. It must be jit-able and differentiable
    in ``t0``. ``window(route)`` returns ``(t0_min [K], t0_max [K])`` and
    ``value(route)`` the value [K].
    """

    def states(self, route, t0): ...

    def window(self, route): ...

    def value(self, route): ...
