"""The streamed land test and the coastline grids against the global_land_mask package."""

from __future__ import annotations

import numpy as np
import pytest

from jaxspline.base.land import COAST_BLOCK, is_land, land_fraction, ocean_cells


def test_is_land_equals_the_package_on_random_points():
    from global_land_mask import globe  # decompresses the whole mask (the reference)

    rng = np.random.default_rng(0)
    lat = np.r_[rng.uniform(-90.0, 90.0, 20000), -90.0, 90.0, 0.0]
    lon = np.r_[rng.uniform(-180.0, 180.0, 20000), 180.0, -180.0, 0.0]
    got = is_land(lat, lon)
    np.testing.assert_array_equal(got, globe.is_land(lat, lon))
    assert 0.2 < got.mean() < 0.4  # Earth: ~29 % land
    # a 2-D input: the same answers (points north of 60 N: the stream stops a sixth in)
    north = np.flatnonzero(lat[:20000] > 60.0)[:3000]
    grid = is_land(lat[north].reshape(30, 100), lon[north].reshape(30, 100))
    np.testing.assert_array_equal(grid.ravel(), got[north])


def test_is_land_equals_the_package_along_whole_mask_rows():
    """Every cell of some mask rows (each cell the coast crosses, from the shipped bits)."""
    from global_land_mask import globe

    rng = np.random.default_rng(1)
    rows = rng.choice(np.flatnonzero(np.abs(globe._lat) < 75.0), 12, replace=False)
    lon = np.clip(globe._lon + rng.uniform(0.0, 1.0 / 120.0, globe._lon.size), -180.0, 180.0)
    lat = np.repeat(globe._lat[rows][:, None], lon.size, axis=1)
    got = is_land(lat, np.broadcast_to(lon, lat.shape))
    np.testing.assert_array_equal(got, globe.is_land(lat, np.broadcast_to(lon, lat.shape)))
    assert 0 < got.sum() < got.size


@pytest.mark.parametrize(("lat", "lon"), [(91.0, 0.0), (0.0, -181.0), (np.nan, 0.0)])
def test_is_land_rejects_bad_coordinates(lat, lon):
    with pytest.raises(ValueError, match="lat must lie"):
        is_land(lat, lon)


def _package_ocean_counts(block):
    """Ocean cells per block x block cell of the package's in-memory mask (the reference)."""
    from global_land_mask import globe

    mask, (n, m) = globe._mask, (s // block for s in globe._mask.shape)
    count = np.empty((n, m), np.int64)
    for i in range(n):  # a row of cells at a time: the mask is 0.9 GB
        rows = mask[i * block : (i + 1) * block]
        count[i] = rows.reshape(block, m, block).sum(axis=(0, 2))
    lat = globe._lat[: n * block].reshape(n, block).mean(axis=1)
    lon = globe._lon[: m * block].reshape(m, block).mean(axis=1)
    return lat, lon, count


def test_shipped_coast_grid_and_streamed_grids_equal_the_package_mask():
    """The shipped 0.25 deg grid (COAST_FILE) and a streamed 0.5 deg one: the package's
    mask summed per block, cell centres included."""
    lat, lon, land = land_fraction()
    ref_lat, ref_lon, ref = _package_ocean_counts(COAST_BLOCK)
    np.testing.assert_allclose(lat, ref_lat, rtol=0, atol=1e-9)
    np.testing.assert_allclose(lon, ref_lon, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(land, 1.0 - ref / COAST_BLOCK**2)
    assert 0.25 < land.mean() < 0.35  # Earth: ~29 % land
    lat2, lon2, count2 = ocean_cells(2 * COAST_BLOCK)  # streamed from the package's file
    ref_lat2, _, ref2 = _package_ocean_counts(2 * COAST_BLOCK)
    np.testing.assert_array_equal(count2, ref2)
    np.testing.assert_allclose(lat2, ref_lat2, rtol=0, atol=1e-9)
