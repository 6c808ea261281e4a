"""The streamed land test against the global_land_mask package's own (reference)."""

from __future__ import annotations

import numpy as np
import pytest

from jaxspline.readers.land import is_land


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


@pytest.mark.parametrize(("lat", "lon"), [(91.0, 0.0), (0.0, -181.0), (np.nan, 0.0)])
def test_is_land_rejects_bad_coordinates(lat, lon):
    with pytest.raises(ValueError, match="lat must lie"):
        is_land(lat, lon)
