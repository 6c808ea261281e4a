"""Geometry: time scales and frames, orbits, pointing laws, routes, visibility windows.

``frames`` (time scales, Earth rotation, WGS84, Sun) -> ``orbit`` (circular,
SGP4/TLE, tables for many satellites) -> ``pointing`` (aim laws, pointing
states) -> ``routes`` (targets and strips, route models) and ``windows`` (every
visibility window), ``ground`` (local projections, strips between points, footprints,
ground tracks).

Layer 1: imports the kernels at most.
"""

from jaxspline.geometry import frames, ground, orbit, pointing, routes, windows
from jaxspline.geometry.frames import *  # noqa: F403
from jaxspline.geometry.ground import *  # noqa: F403
from jaxspline.geometry.orbit import *  # noqa: F403
from jaxspline.geometry.pointing import *  # noqa: F403
from jaxspline.geometry.routes import *  # noqa: F403
from jaxspline.geometry.windows import *  # noqa: F403

_MODULES = (frames, orbit, pointing, routes, windows, ground)
__all__ = [name for m in _MODULES for name in m.__all__]
