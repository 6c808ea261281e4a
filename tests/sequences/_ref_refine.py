"""Reference for the tests: a toy differentiable RouteModel (moved out of engine.refine)."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.screen.options import RouteOptions


class LinearRouteModel(NamedTuple):
    """Toy differentiable RouteModel (R routes, C channels) for tests and examples.

    Route r started at t0 images for ``duration[r]`` seconds; its channel angle
    at the start is ``angle0[r] + lead[r] * (t0 - t_ref[r])`` [rad] (``lead`` in
    rad/s mimics the pitch lead that changes with the start time) and the scan
    runs at the constant channel rate ``scan_rate[r]`` [rad/s], so the end angle
    is the start angle + scan_rate * duration. Windows are
    ``[t0_min[r], t0_max[r]]`` [s]. All fields are arrays: angle0, lead,
    scan_rate [R, C]; t_ref, duration, t0_min, t0_max, value [R].
    """

    angle0: jnp.ndarray
    lead: jnp.ndarray
    scan_rate: jnp.ndarray
    t_ref: jnp.ndarray
    duration: jnp.ndarray
    t0_min: jnp.ndarray
    t0_max: jnp.ndarray
    value: jnp.ndarray

    def states(self, route, t0):
        """(t_end [K], start_angle [K, C], start_rate, end_angle, end_rate) at t0 [K] [s]."""
        t0 = jnp.asarray(t0)
        dur = jnp.asarray(self.duration)[route]
        sa = (
            jnp.asarray(self.angle0)[route]
            + jnp.asarray(self.lead)[route] * (t0 - jnp.asarray(self.t_ref)[route])[:, None]
        )
        w = jnp.asarray(self.scan_rate)[route]
        return t0 + dur, sa, w, sa + w * dur[:, None], w

    def window(self, route):
        """(t0_min [K], t0_max [K]) [s]."""
        return jnp.asarray(self.t0_min)[route], jnp.asarray(self.t0_max)[route]

    def value_of(self, route):
        """Value [K] of the routes."""
        return jnp.asarray(self.value)[route]

    def grid_options(self, per_route: int) -> RouteOptions:
        """RouteOptions with ``per_route`` start times evenly spaced over each window."""
        r_count = np.shape(self.value)[0]
        frac = np.linspace(0.0, 1.0, per_route) if per_route > 1 else np.array([0.5])
        route = np.repeat(np.arange(r_count), frac.size)
        lo, hi = (np.asarray(x) for x in self.window(route))
        t0 = lo + (hi - lo) * np.tile(frac, r_count)
        te, sa, sr, ea, er = (np.asarray(x) for x in self.states(route, t0))
        return RouteOptions(
            route=route,
            t_start=t0,
            t_end=te,
            start_angle=sa,
            start_rate=sr,
            end_angle=ea,
            end_rate=er,
            value=np.asarray(self.value_of(route)),
            scan_ok=np.ones(route.size, bool),
        )
