"""Areas planned by unique coverage: a sample grid, free candidate strips, a lazy greedy.

An area with ``objective = "coverage"`` (the default, :mod:`jaxspline.readers.area_files`)
is not tiled into fixed strips; its strip targets are chosen so that no ground counts
twice:

1. **Grid** (:func:`area_grid`). Points ``grid_km`` apart on a square grid of the
   gnomonic plane about the area's centre, kept where they lie inside the polygon; each
   is weighted by the sphere's area element there, ``(1 + rho^2)^(-3/2)`` (``rho`` the
   plane distance over the radius), normalised to sum 1, so a sum of weights is a share
   of the area.
2. **Candidates** (:func:`candidate_strips`). For every cutting direction (the ground
   track of the passes, :mod:`jaxspline.readers.areas`), centre lines on a cross-track
   grid of :data:`OFFSET_PER_SWATH` of the swath (free offsets, not a tiling); along each
   line the samples within half a swath form runs (split at gaps of more than
   :data:`RUN_GAP_CELLS` grid cells and into equal pieces that, half a cell longer at
   each end, are no longer than ``max_length_km``), and each run is a candidate strip
   from its first to its last sample, half a cell longer at each end. A candidate
   covers the samples of its run: gnomonic distances are never shorter than ground
   distances, so they lie within half a swath of the strip's great circle on the
   ground as well.
3. **Selection** (:func:`lazy_greedy`): CELF lazy greedy by marginal covered weight,
   strips with a gain below :data:`MIN_GAIN` of the area left out. Each chosen strip
   becomes a strip target whose value is the area's priority times its marginal gain
   in greedy order. Coverage is submodular, so for ANY subset the planner images, the
   sum of these values is at most the priority times the subset's covered share: the
   planner's objective never counts ground twice (cut strips of two directions do).
   The strips are then planned with the point targets by the ordinary search, on the
   satellites' own maneuver models, and checked like any strip.

:func:`covered_samples` is the report's test (a sample is covered by a planned strip
when it lies within half the imaging satellite's swath of the strip's great circle and
between its ends); :func:`jaxspline.readers.areas.area_coverage` sums the covered
samples' weights.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
import shapely

from jaxspline.geometry.frames import ecef_to_geodetic, geodetic_to_ecef
from jaxspline.geometry.ground import (
    gnomonic,
    gnomonic_inverse,
    strip_between,
    strip_centerline,
    surface_point,
    unit_vectors,
)
from jaxspline.readers.area_files import DENSIFY_DEG, MIN_STRIP_M

__all__ = [
    "MIN_GAIN",
    "OFFSET_PER_SWATH",
    "RUN_GAP_CELLS",
    "AreaGrid",
    "CoverageStrips",
    "area_grid",
    "candidate_strips",
    "covered_samples",
    "lazy_greedy",
    "select_strips",
]

#: Cross-track step of the candidate centre lines, as a share of the swath.
OFFSET_PER_SWATH = 1.0 / 3.0
#: A run of samples along a centre line breaks at a gap of more than this many cells.
RUN_GAP_CELLS = 2.0
#: Strips adding less than this share of the area are not offered to the planner.
MIN_GAIN = 1e-3
_EDGE_M = 1e-6  # samples on a band's edge count as inside [m]


@dataclass(frozen=True)
class AreaGrid:
    """The coverage samples of one area.

    Attributes:
      unit: float [N, 3], unit vectors of the samples (Earth-fixed).
      lon_deg, lat_deg: float [N], geodetic longitude / latitude [deg].
      plane: float [N, 2], gnomonic (east, north) coordinates about the centre [m].
      weight: float [N], share of the area each sample stands for (sums to 1).
      spacing: grid spacing [m].
    """

    unit: np.ndarray
    lon_deg: np.ndarray
    lat_deg: np.ndarray
    plane: np.ndarray
    weight: np.ndarray
    spacing: float


@dataclass(frozen=True)
class CoverageStrips:
    """The strips chosen for one area (rows in greedy order).

    Attributes:
      strips: float [K, 4], (lat [rad], lon [rad], azimuth [rad], length [m]) of each
        strip's start, as :func:`jaxspline.geometry.ground.strip_between` gives them.
      gain: float [K], marginal covered share of each strip in greedy order.
      cutting: int [K], the cutting (direction) of each strip.
      candidates: number of candidate strips screened.
      union: covered share of all candidates together (no plan of these strips covers
        more: an upper bound).
    """

    strips: np.ndarray
    gain: np.ndarray
    cutting: np.ndarray
    candidates: int
    union: float


def area_grid(polygon, center, spacing: float) -> AreaGrid:
    """The sample grid of an area (module docstring, step 1).

    Args:
      polygon: shapely Polygon / MultiPolygon, (lon, lat) [deg].
      center: float [3], unit vector of the area's centre.
      spacing: grid spacing [m] (> 0).
    Returns:
      AreaGrid (at least one sample: the polygon's representative point when the grid
      misses a polygon thinner than the spacing).
    """
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
        unit, np.degrees(np.asarray(lon)), np.degrees(np.asarray(lat)), pts, w / w.sum(), spacing
    )


def _runs(along: np.ndarray, gap: float, max_length: float) -> list[tuple[float, float]]:
    """(first, last) along-track coordinate of each run of sorted ``along`` values."""
    if along.size == 0:
        return []
    cut = np.flatnonzero(np.diff(along) > gap)
    out = []
    for a, b in zip(np.r_[0, cut + 1], np.r_[cut, along.size - 1], strict=True):
        lo, hi = float(along[a]), float(along[b])
        m = max(1, math.ceil((hi - lo) / max_length - 1e-9)) if math.isfinite(max_length) else 1
        edges = lo + (hi - lo) * np.arange(m + 1) / m
        out += list(zip(edges[:-1], edges[1:], strict=True))
    return out


def candidate_strips(grid: AreaGrid, azimuth: float, swath: float, max_length: float):
    """Candidate strips of one cutting and the samples each covers (module doc, step 2).

    Args:
      grid: AreaGrid.
      azimuth: strip direction at the centre, clockwise from north [rad].
      swath: strip width [m].
      max_length: longest strip [m] (inf: no limit).
    Returns:
      (ends, members): ends float [M, 3] = (along0, along1, cross) [m] in the cutting's
      plane; members list of M int arrays of covered sample indices.
    """
    e_ax, n_ax = math.sin(azimuth), math.cos(azimuth)
    x, y = grid.plane[:, 0], grid.plane[:, 1]
    along, cross = x * e_ax + y * n_ax, x * n_ax - y * e_ax
    step = swath * OFFSET_PER_SWATH
    c_lo, c_hi = float(cross.min()), float(cross.max())
    n = max(1, math.ceil((c_hi - c_lo) / step - 1e-9) + 1)
    ends, members = [], []
    for k in range(n):
        c = 0.5 * (c_lo + c_hi) + (k - 0.5 * (n - 1)) * step
        idx = np.flatnonzero(np.abs(cross - c) <= swath / 2 + _EDGE_M)
        idx = idx[np.argsort(along[idx], kind="stable")]
        piece = max_length - grid.spacing if max_length > 2.0 * grid.spacing else max_length
        for lo, hi in _runs(along[idx], RUN_GAP_CELLS * grid.spacing, piece):
            pad = max(0.0, min(0.5 * grid.spacing, 0.5 * (max_length - (hi - lo))))
            a0, a1 = lo - pad, hi + pad
            if a1 - a0 < MIN_STRIP_M:
                mid = 0.5 * (a0 + a1)
                a0, a1 = mid - MIN_STRIP_M / 2, mid + MIN_STRIP_M / 2
            sel = idx[(along[idx] >= lo - _EDGE_M) & (along[idx] <= hi + _EDGE_M)]
            ends.append((a0, a1, c))
            members.append(sel)
    return np.asarray(ends, np.float64).reshape(-1, 3), members


def lazy_greedy(members: list, weight: np.ndarray, min_gain: float = 0.0):
    """CELF lazy greedy maximum coverage: repeatedly the set of largest marginal weight.

    A set's marginal gain only falls as others are taken (submodularity), so a stale gain
    on the heap bounds the fresh one; the top is re-evaluated and taken when it still
    beats the next stale gain. Ties go to the lower index.

    Args:
      members: list of int arrays, the sample indices of each set.
      weight: float [N], sample weights (>= 0).
      min_gain: sets adding less than this are never taken.
    Returns:
      (order, gains): int [K] indices of the sets taken, in order; float [K] the marginal
      gain of each when taken (non-increasing).
    """
    covered = np.zeros(weight.shape[0], bool)
    heap = [(-float(weight[m].sum()), i) for i, m in enumerate(members)]
    heapq.heapify(heap)
    order, gains = [], []
    while heap:
        neg, i = heapq.heappop(heap)
        if -neg < min_gain:
            break
        m = members[i]
        gain = float(weight[m[~covered[m]]].sum())
        if heap and gain < -heap[0][0]:
            heapq.heappush(heap, (-gain, i))
            continue
        if gain < min_gain:
            continue
        covered[m] = True
        order.append(i)
        gains.append(gain)
    return np.asarray(order, np.int64), np.asarray(gains, np.float64)


def select_strips(grid: AreaGrid, center, azimuths, swath: float, max_length: float):
    """The strips of an area chosen by unique coverage (module docstring, steps 2 and 3).

    Args:
      grid: AreaGrid of the area.
      center: float [3], unit vector of the area's centre (the plane's origin).
      azimuths: float [C], cutting directions [rad].
      swath: strip width [m].
      max_length: longest strip [m] (inf: no limit).
    Returns:
      CoverageStrips.
    """
    radius = float(np.linalg.norm(surface_point(center)))
    ends, members, cutting = [], [], []
    for c, az in enumerate(azimuths):
        e, m = candidate_strips(grid, float(az), swath, max_length)
        ends.append(np.column_stack([e, np.full(len(e), az)]))
        members += m
        cutting += [c] * len(m)
    union = np.zeros(grid.weight.shape[0], bool)
    for m in members:
        union[m] = True
    order, gains = lazy_greedy(members, grid.weight, MIN_GAIN)
    rows = np.concatenate(ends, 0)[order] if ends else np.zeros((0, 4))
    s_ax, c_ax = np.sin(rows[:, 3]), np.cos(rows[:, 3])

    def plane_to_unit(along, cross):
        x = along * s_ax + cross * c_ax
        y = along * c_ax - cross * s_ax
        return gnomonic_inverse(np.stack([x, y], -1) / radius, center)

    if len(order):
        lat, lon, az, length = strip_between(
            plane_to_unit(rows[:, 0], rows[:, 2]), plane_to_unit(rows[:, 1], rows[:, 2])
        )
        strips = np.stack([lat, lon, az, length], -1)
    else:
        strips = np.zeros((0, 4))
    return CoverageStrips(
        strips,
        gains,
        np.asarray(cutting, np.int64)[order],
        len(members),
        float(grid.weight[union].sum()),
    )


def covered_samples(unit: np.ndarray, strips: np.ndarray, swaths: np.ndarray) -> np.ndarray:
    """Which samples the given strips cover on the ground (great-circle geometry).

    A sample ``p`` is covered by the strip starting at ``u0`` in the direction ``d`` (the
    planner's strip model, :func:`jaxspline.geometry.ground.strip_centerline`, radius
    ``R = |g0|`` at the start) when ``|asin(p . (u0 x d))| <= swath / (2 R)`` and its
    along-track angle ``atan2(p . d, p . u0)`` lies in ``[0, length / R]``: the footprint
    of :func:`jaxspline.geometry.ground.strip_footprint` (square ends).

    Args:
      unit: float [N, 3], sample unit vectors.
      strips: float [K, 4], (lat [rad], lon [rad], azimuth [rad], length [m]) per strip.
      swaths: float [K], imaged width of each strip [m].
    Returns:
      bool [N].
    """
    out = np.zeros(unit.shape[0], bool)
    for (lat, lon, az, length), sw in zip(strips, swaths, strict=True):
        u, tan, rad = strip_centerline(lat, lon, az, length, 2)
        u0, d = u[0], tan[0]
        cross = np.arcsin(np.clip(unit @ np.cross(u0, d), -1.0, 1.0))
        ang = np.arctan2(unit @ d, unit @ u0)
        tol = _EDGE_M / float(rad)
        out |= (
            (np.abs(cross) <= sw / (2.0 * rad) + tol) & (ang >= -tol) & (ang <= length / rad + tol)
        )
    return out
