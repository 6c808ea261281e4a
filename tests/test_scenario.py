"""Scenario loading: the default, the example file, a TLE satellite, and named errors."""

from pathlib import Path

import numpy as np
import pytest

from jaxspline.orbit import CircularOrbit, HermiteOrbit, orbit_position, sso_inclination
from jaxspline.routes import POINT, STRIP
from jaxspline.scenario import DEFAULT_SCENARIO, default_scenario, load_scenario, parse_scenario

EXAMPLE = Path(__file__).resolve().parents[1] / "scripts" / "example_scenario.toml"
ISS = [
    "1 25544U 98067A   08264.51782528 -.00002182  00000-0 -11606-4 0  2927",
    "2 25544  51.6416 247.4627 0006703 130.5360 325.0288 15.72125391563537",
]


def test_default_scenario():
    sc = default_scenario()
    assert sc.routes.kind.size == 300
    assert 0.1 < np.mean(sc.routes.kind == STRIP) < 0.3
    assert isinstance(sc.orbit, CircularOrbit)
    assert float(sc.orbit.inclination) == pytest.approx(sso_inclination(600e3))
    np.testing.assert_allclose(np.degrees(sc.limits.rate), 2.0)
    np.testing.assert_allclose(np.degrees(sc.limits.accel), 1.0)
    assert np.degrees(sc.max_off_nadir) == pytest.approx(45.0)
    lat = np.degrees(sc.routes.lat)
    assert lat.min() >= 38.0 and lat.max() <= 54.0
    assert default_scenario(count=10, seed=3).routes.kind.size == 10


def test_example_file_loads():
    sc = load_scenario(EXAMPLE)
    assert sc.name == "example"
    assert sc.routes.kind.size == 3 + 40
    assert list(sc.routes.kind[:3]) == [POINT, POINT, STRIP]
    assert sc.routes.length[2] == pytest.approx(40e3)
    assert (sc.routes.t0_lo[1], sc.routes.t0_hi[1]) == (250.0, 400.0)
    assert sc.planner.scan_speeds == (4000.0, 7000.0)
    assert sc.planner.t0_grid == 5


def test_tle_satellite_and_elements(tmp_path):
    data = {
        "scenario": {"epoch": "2008-09-20T12:00:00Z", "duration_s": 300.0},
        "satellite": {"tle": ISS},
        "routes": [{"kind": "point", "lat_deg": 10.0, "lon_deg": 20.0, "duration_s": 5.0}],
    }
    sc = parse_scenario(data)
    assert isinstance(sc.orbit, HermiteOrbit)
    r = np.linalg.norm(np.asarray(orbit_position(sc.orbit, 150.0)))
    assert 6.6e6 < r < 6.8e6  # ISS
    data["satellite"] = {"altitude_km": 700.0, "inclination_deg": 60.0, "raan_deg": 10.0}
    sc = parse_scenario(data)
    assert np.degrees(float(sc.orbit.inclination)) == pytest.approx(60.0)


BAD = [
    ("[satellite]\nrate_deg_s = [1, 2]\n[random_targets]\n", "satellite.rate_deg_s", 2),
    ("[satellite]\nrate_deg_s = -1\n[random_targets]\n", "satellite.rate_deg_s", 2),
    ("[satellite]\naltitude_km = 'high'\n[random_targets]\n", "satellite.altitude_km", 2),
    ("[satellite]\nfoo = 1\n[random_targets]\n", "satellite.foo", 2),
    ("[sattelite]\n", "sattelite", None),
    ("[random_targets]\n", "satellite", None),
    ("[satellite]\n", "routes", None),
    (
        "[satellite]\n[[routes]]\nkind='point'\nlat_deg=1\nlon_deg=2\nduration_s=3\n"
        "[[routes]]\nkind='point'\nlat_deg=95\nlon_deg=2\nduration_s=3\n",
        "routes[1].lat_deg",
        9,
    ),
    ("[satellite]\n[[routes]]\nkind='blob'\nlat_deg=1\nlon_deg=2\n", "routes[0].kind", 3),
    ("[satellite]\n[[routes]]\nkind='strip'\nlat_deg=1\nlon_deg=2\n", "routes[0].length_km", 2),
    (
        "[satellite]\n[[routes]]\nkind='point'\nlat_deg=1\nlon_deg=2\nduration_s=3\n"
        "window_s=[5, 1]\n",
        "routes[0].window_s",
        7,
    ),
    ("[scenario]\nepoch = 'yesterday'\n[satellite]\n[random_targets]\n", "scenario.epoch", 2),
    ("[satellite]\n[random_targets]\ncount = 0\n", "random_targets.count", 3),
    ("[satellite]\n[random_targets]\n[planner]\nbeam_width = 1.5\n", "planner.beam_width", 4),
    ("[satellite]\ntle = ['1 x', '2 y']\n[random_targets]\n", "satellite.tle", 2),
    ("[satellite]\nover = { lat_deg = 99.0 }\n[random_targets]\n", "satellite.over.lat_deg", 2),
]


@pytest.mark.parametrize(("text", "field", "line"), BAD)
def test_bad_files_name_the_field_and_line(tmp_path, text, field, line):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ValueError) as err:
        load_scenario(path)
    msg = str(err.value)
    assert field in msg
    if line is not None:
        assert f"(line {line})" in msg


def test_invalid_toml_and_missing_file(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[satellite\nx = 1\n")
    with pytest.raises(ValueError, match="invalid TOML.*line 1"):
        load_scenario(path)
    with pytest.raises(FileNotFoundError, match="nothere"):
        load_scenario(tmp_path / "nothere.toml")


def test_default_dict_is_not_mutated():
    default_scenario(count=5)
    assert DEFAULT_SCENARIO["random_targets"]["count"] == 300
