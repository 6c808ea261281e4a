"""Offline land data: the GLOBE 30 arc-second land mask, streamed, never held whole.

The ``global_land_mask`` package ships the mask (21,600 x 43,200 cells of 1/120 deg,
``True`` = ocean) as one compressed ``.npy`` inside an ``.npz``; importing the package
decompresses all of it (0.9 GB resident). Here the mask is read from the package's
file row block by row block, so a land test or a coarse land-fraction grid costs a
few MB of memory and one pass of decompression (about 3-4 s).

* :func:`is_land`: land test of points, with the package's cell indexing;
* :func:`ocean_cells`: per coarse grid cell, how many mask cells are ocean (streamed);
* :func:`land_fraction`: land share on a coarse grid (coastline contours), cached. The
  default grid (0.25 deg) ships with the package (:data:`COAST_FILE`, written by
  ``scripts/make_coast_grid.py`` from :func:`ocean_cells`), so the plan page and the
  ground-track figure do not decompress the whole mask in every run.
"""

from __future__ import annotations

import contextlib
import functools
import importlib.util
import zipfile
from pathlib import Path

import numpy as np

__all__ = ["COAST_BLOCK", "COAST_FILE", "is_land", "land_fraction", "ocean_cells"]

COAST_BLOCK = 30  # mask cells (1/120 deg) per coastline grid cell: 0.25 deg
#: the shipped :func:`ocean_cells` grid of ``COAST_BLOCK`` (arrays lat, lon, ocean_cells)
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


def _index(x, axis):
    """Cell index of coordinates x [deg] on a regular axis (clipped to its range)."""
    x = np.clip(np.asarray(x, np.float64), axis.min(), axis.max())
    return ((x - axis[0]) / (axis[1] - axis[0])).astype(np.int64)


def is_land(lat, lon) -> np.ndarray:
    """Whether points are on land (GLOBE mask cell containing them; lakes count as land).

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
    out = np.zeros(lat.shape, bool)
    flat_lat, flat_lon = lat.ravel(), lon.ravel()
    with _mask_stream() as (ax_lat, ax_lon, (n_rows, n_cols), f):
        row = _index(flat_lat, ax_lat)
        col = _index(flat_lon, ax_lon)
        order = np.argsort(row, kind="stable")
        bounds = np.searchsorted(row[order], np.arange(0, n_rows + _READ_ROWS, _READ_ROWS))
        ocean = np.zeros(row.size, bool)
        for k, r0 in enumerate(range(0, n_rows, _READ_ROWS)):
            q = order[bounds[k] : bounds[k + 1]]
            n = min(_READ_ROWS, n_rows - r0)
            block = f.read(n * n_cols)  # decompressed either way; kept only with queries
            if q.size:
                rows = np.frombuffer(block, np.bool_).reshape(n, n_cols)
                ocean[q] = rows[row[q] - r0, col[q]]
            if bounds[k + 1] == row.size:
                break
    out.ravel()[:] = ~ocean
    return out


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
