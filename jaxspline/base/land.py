"""Offline land data: the GLOBE 30 arc-second land mask, streamed, never held whole.

The ``global_land_mask`` package ships the mask (21,600 x 43,200 cells of 1/120 deg,
``True`` = ocean) as one compressed ``.npy`` inside an ``.npz``; importing the package
decompresses all of it (0.9 GB resident). Here the mask is read from the package's
file row block by row block (a few MB of memory, one pass of decompression), and
what the planner asks of it most ships with jaxspline as a coastline grid
(:data:`COAST_FILE`, written by ``scripts/make_coast_grid.py``): per 0.25 deg cell,
how many mask cells are ocean, and the mask bits of every cell that is neither all
land nor all ocean. So a land test reads no mask at all.

* :func:`is_land`: land test of points, with the package's cell indexing (from the
  shipped grid: a cell's count, or its bit where the coast crosses it);
* :func:`ocean_cells`: per coarse grid cell, how many mask cells are ocean (streamed);
* :func:`coast_bits`: the mask bits of the mixed cells of such a grid (streamed);
* :func:`land_fraction`: land share on a coarse grid (coastline contours), cached; the
  default grid is the shipped one.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import zipfile
from pathlib import Path
from typing import NamedTuple

import numpy as np

__all__ = [
    "COAST_BLOCK",
    "COAST_FILE",
    "coast_bits",
    "is_land",
    "land_fraction",
    "mask_axes",
    "ocean_cells",
]

COAST_BLOCK = 30  # mask cells (1/120 deg) per coastline grid cell: 0.25 deg
#: the shipped grid of ``COAST_BLOCK``: arrays lat, lon, ocean_cells (:func:`ocean_cells`),
#: bits (:func:`coast_bits`), mask_lat and mask_lon (the mask's axes: first, second, min,
#: max value [deg])
COAST_FILE = Path(__file__).resolve().parents[1] / "data" / f"coast_cells_{COAST_BLOCK}.npz"
_MASK_FILE = "globe_combined_mask_compressed.npz"
_READ_ROWS = 240  # mask rows decompressed per read (10 MB)


@contextlib.contextmanager
def _mask_stream():
    """Yield (lat [R] deg, lon [C] deg, (R, C), file positioned at the first mask row)."""
    spec = importlib.util.find_spec("global_land_mask")
    if spec is None or not spec.submodule_search_locations:
        raise ValueError(
            "land data needs the global_land_mask package (pip install global-land-mask)"
        )
    path = Path(next(iter(spec.submodule_search_locations))) / _MASK_FILE
    with zipfile.ZipFile(path) as z:
        with z.open("lat.npy") as f:
            lat = np.load(f)
        with z.open("lon.npy") as f:
            lon = np.load(f)
        with z.open("mask.npy") as f:
            version = np.lib.format.read_magic(f)
            shape, fortran, dtype = (
                np.lib.format.read_array_header_1_0(f)
                if version == (1, 0)
                else np.lib.format.read_array_header_2_0(f)
            )
            if fortran or dtype != np.bool_ or len(shape) != 2:
                raise ValueError(f"{path}: unexpected land mask {shape} {dtype}")
            yield lat, lon, shape, f


def _axis_ends(axis) -> np.ndarray:
    """What :func:`_index` reads of a mask axis: first, second, min and max value [deg]."""
    return np.array([axis[0], axis[1], axis.min(), axis.max()], np.float64)


def _index(x, ends):
    """Cell index of coordinates x [deg] on a regular axis (:func:`_axis_ends`; clipped)."""
    x = np.clip(np.asarray(x, np.float64), ends[2], ends[3])
    return ((x - ends[0]) / (ends[1] - ends[0])).astype(np.int64)


class _Coast(NamedTuple):
    """The shipped grid, ready for lookups (:func:`_coast`)."""

    count: np.ndarray  # [N, M] ocean mask cells per grid cell
    rank: np.ndarray  # [N, M] position of a mixed cell among the mixed cells (row-major)
    bits: np.ndarray  # packed mask bits of the mixed cells, block x block each (uint8)
    mask_lat: np.ndarray  # _axis_ends of the mask's latitude axis
    mask_lon: np.ndarray


@functools.cache
def _coast() -> _Coast:
    with np.load(COAST_FILE) as z:
        count, bits = z["ocean_cells"], z["bits"]
        mask_lat, mask_lon = z["mask_lat"], z["mask_lon"]
    mixed = (count > 0) & (count < COAST_BLOCK**2)
    rank = (np.cumsum(mixed.ravel()) - 1).reshape(mixed.shape).astype(np.int32)
    return _Coast(count, rank, bits, mask_lat, mask_lon)


def is_land(lat, lon) -> np.ndarray:
    """Whether points are on land (GLOBE mask cell containing them; lakes count as land).

    Answered from the shipped coastline grid (module docstring): exactly the mask's cell.

    Args:
      lat: float [...] geodetic latitudes [deg] in [-90, 90].
      lon: float [...] longitudes [deg] in [-180, 180].
    Returns:
      bool [...].
    Raises:
      ValueError: a coordinate is outside its range or not finite.
    """
    lat, lon = np.broadcast_arrays(np.asarray(lat, np.float64), np.asarray(lon, np.float64))
    if not (np.all(np.abs(lat) <= 90.0) and np.all(np.abs(lon) <= 180.0)):
        raise ValueError("is_land: lat must lie in [-90, 90] and lon in [-180, 180] deg")
    c = _coast()
    row, col = _index(lat.ravel(), c.mask_lat), _index(lon.ravel(), c.mask_lon)
    i, j = row // COAST_BLOCK, col // COAST_BLOCK
    count = c.count[i, j]
    ocean = count == COAST_BLOCK**2
    mixed = np.flatnonzero((count > 0) & ~ocean)
    cell = c.rank[i[mixed], j[mixed]].astype(np.int64) * COAST_BLOCK**2
    pos = cell + (row[mixed] % COAST_BLOCK) * COAST_BLOCK + col[mixed] % COAST_BLOCK
    ocean[mixed] = (c.bits[pos >> 3] >> (7 - (pos & 7))) & 1  # np.packbits' bit order
    return ~ocean.reshape(lat.shape)


def mask_axes():
    """What the land test reads of the mask's axes (first, second, min, max value [deg]).

    Returns:
      (float [4] latitude, float [4] longitude), from the package's file.
    """
    with _mask_stream() as (lat, lon, _, _):
        return _axis_ends(lat), _axis_ends(lon)


def coast_bits(count: np.ndarray, block: int = COAST_BLOCK) -> np.ndarray:
    """The mask bits of the mixed cells of a coarse grid (one streamed pass).

    Args:
      count: [N, M] ocean cell counts of the grid (:func:`ocean_cells` of ``block``).
      block: mask cells per grid cell along each axis.
    Returns:
      uint8 [ceil(K block^2 / 8)]: for the K cells with ``0 < count < block^2`` in
      row-major order, each cell's ``block x block`` mask (``True`` = ocean, rows
      north to south as the mask), concatenated and packed by ``np.packbits``.
    """
    mixed = (count > 0) & (count < block * block)
    parts = []
    with _mask_stream() as (_, _, (nr, nc), f):
        if count.shape != (nr // block, nc // block):
            raise ValueError(f"count: shape {count.shape} is not the mask's grid of {block}")
        for i in range(count.shape[0]):
            rows = np.frombuffer(f.read(block * nc), np.bool_).reshape(block, nc // block, block)
            js = np.flatnonzero(mixed[i])
            if js.size:
                parts.append(rows[:, js, :].transpose(1, 0, 2).reshape(-1))
    return np.packbits(np.concatenate(parts)) if parts else np.zeros(0, np.uint8)


def ocean_cells(block: int = COAST_BLOCK):
    """Ocean cell counts of the mask on a coarse global grid (one streamed pass).

    Args:
      block: mask cells (1/120 deg each) per grid cell along each axis; must divide
        21600 and 43200 (30 gives 0.25 deg).
    Returns:
      ``(lat [N] deg, descending, lon [M] deg, ascending, count [N, M] uint16)``: the
      cell centres and how many of a cell's ``block**2`` mask cells are ocean.
    Raises:
      ValueError: ``block`` does not divide the mask's shape.
    """
    with _mask_stream() as (lat, lon, (nr, nc), f):
        if nr % block or nc % block:
            raise ValueError(f"block={block!r}: mask ({nr}, {nc}) is not divisible by it")
        n, m = nr // block, nc // block
        count = np.empty((n, m), np.uint16 if block * block < 2**16 else np.uint32)
        per_read = max(1, _READ_ROWS // block)
        for i in range(0, n, per_read):
            k = min(per_read, n - i)
            buf = np.frombuffer(f.read(k * block * nc), np.uint8).reshape(k, block, nc)
            rows_sum = buf.sum(axis=1, dtype=np.uint16).reshape(k, m, block)
            count[i : i + k] = rows_sum.sum(axis=2, dtype=np.uint32)
    lat_c = lat[: n * block].reshape(n, block).mean(axis=1)
    lon_c = lon[: m * block].reshape(m, block).mean(axis=1)
    return lat_c, lon_c, count


@functools.cache
def land_fraction(block: int = COAST_BLOCK):
    """Land fraction on a coarse global grid.

    The default ``block`` reads the shipped grid (:data:`COAST_FILE`); another block
    streams the mask (:func:`ocean_cells`).

    Args:
      block: mask cells (1/120 deg each) averaged per grid cell along each axis; must
        divide 21600 and 43200 (30 gives 0.25 deg).
    Returns:
      ``(lat [N] deg, descending, lon [M] deg, ascending, land [N, M] in [0, 1])``,
      cell centres. Cached per process.
    """
    if block == COAST_BLOCK and COAST_FILE.is_file():
        with np.load(COAST_FILE) as z:
            lat, lon, count = z["lat"], z["lon"], z["ocean_cells"]
    else:
        lat, lon, count = ocean_cells(block)
    return lat, lon, 1.0 - count / (block * block)
