"""The data contract between geometry (routes) and the engine (screen/sequence/refine).

Route *options* are plain struct-of-arrays tables: no Python objects per
candidate, so millions fit in memory and every field can go through ``jit``.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import jax.numpy as jnp

__all__ = ["RouteOptions", "RouteModel"]


class RouteOptions(NamedTuple):
    """N start options of routes, C attitude channels (roll, pitch, yaw, ...).

    Attributes:
      route: int [N], index of the route this option images (0..R-1).
      t_start: [N] start time of imaging [s from the scenario epoch].
      t_end: [N] end time of imaging [s].
      start_angle, start_rate: [N, C] channel angle [rad] and rate [rad/s] at t_start.
      end_angle, end_rate: [N, C] channel angle [rad] and rate [rad/s] at t_end.
      value: [N] value (priority) collected if this option is imaged.
      scan_ok: bool [N], the scan itself is feasible (visible, within rate/accel
        limits); options with ``scan_ok == False`` are dropped before screening.

    A transition option i -> option j takes T = t_start[j] - t_end[i] seconds
    and must bring every channel from (end_angle[i], end_rate[i]) to
    (start_angle[j], start_rate[j]) in exactly T.
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
