"""The sample grid of an area: weighted ground points whose covered weight is the area's coverage.

An area target (a polygon of the scenario, or a benchmark region given with its own
samples) is planned as a set of weighted samples: the plan's value of the area is its
priority times the summed weight of the samples some planned strip covers
(:mod:`jaxspline.screen.coverage`). When the scenario gives no samples, the planner lays
them out here (:func:`area_grid`): points ``spacing`` apart on a square grid of the
gnomonic plane about the area's centre, kept where they fall inside the polygon, each
weighted by the sphere's area element there, ``(1 + rho^2)^(-3/2)`` (``rho`` the plane
distance over the radius), normalised to sum 1, so that a sum of weights is a share of
the area. A polygon thinner than the spacing still gets one sample (its representative
point).

GeoJSON edges are straight in longitude / latitude (RFC 7946 section 3.1.1): the polygon
is densified every :data:`DENSIFY_DEG` before it is projected.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from jaxspline.base.elements import geodetic_to_ecef, unit_vectors
from jaxspline.geometry.frames import ecef_to_geodetic
from jaxspline.geometry.ground import gnomonic, gnomonic_inverse, surface_point
from jaxspline.readers.area_files import polygon_center

__all__ = ["DENSIFY_DEG", "AreaGrid", "area_grid"]

#: Longest polygon edge [deg] before projection (edges are straight in lon / lat).
DENSIFY_DEG = 0.05


@dataclass(frozen=True)
class AreaGrid:
    """The coverage samples of one area.

    Attributes:
      lon_deg, lat_deg: float [N], geodetic longitude / latitude of each sample [deg].
      weight: float [N], share of the area each sample stands for (sums to 1).
      spacing: grid spacing [m] (0 for samples given by the scenario).
    """

    lon_deg: np.ndarray
    lat_deg: np.ndarray
    weight: np.ndarray
    spacing: float

    def __len__(self) -> int:
        return int(self.weight.shape[0])


def area_grid(polygon, spacing: float) -> AreaGrid:
    """The sample grid of a polygon (module docstring).

    Args:
      polygon: shapely Polygon / MultiPolygon, (lon, lat) [deg].
      spacing: grid spacing [m] (> 0).
    Returns:
      AreaGrid (at least one sample).
    Raises:
      ValueError: ``spacing`` is not a positive number.
    """
    if not (isinstance(spacing, int | float) and np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"spacing must be a number of metres > 0, got {spacing!r}")
    center = polygon_center(polygon)
    radius = float(np.linalg.norm(surface_point(center)))

    def to_plane(xy):
        u = unit_vectors(geodetic_to_ecef(np.radians(xy[:, 1]), np.radians(xy[:, 0]), 0.0))
        return radius * gnomonic(u, center)

    plane = shapely.transform(shapely.segmentize(polygon, DENSIFY_DEG), to_plane)
    x0, y0, x1, y1 = plane.bounds
    nx, ny = int((x1 - x0) // spacing) + 1, int((y1 - y0) // spacing) + 1
    xs = 0.5 * (x0 + x1) + (np.arange(nx) - 0.5 * (nx - 1)) * spacing
    ys = 0.5 * (y0 + y1) + (np.arange(ny) - 0.5 * (ny - 1)) * spacing
    gx, gy = (g.ravel() for g in np.meshgrid(xs, ys))
    inside = shapely.contains_xy(plane, gx, gy)
    pts = np.stack([gx[inside], gy[inside]], -1)
    if pts.shape[0] == 0:
        p = plane.representative_point()
        pts = np.array([[p.x, p.y]])
    unit = gnomonic_inverse(pts / radius, center)
    w = (1.0 + np.sum((pts / radius) ** 2, axis=1)) ** -1.5
    lat, lon, _ = ecef_to_geodetic(surface_point(unit))
    return AreaGrid(
        np.degrees(np.asarray(lon)), np.degrees(np.asarray(lat)), w / w.sum(), float(spacing)
    )
