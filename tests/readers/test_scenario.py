"""Scenario files: the default, the example, units, aliases, CSV targets, named errors."""

import collections
import math
from pathlib import Path

import numpy as np
import pytest

from jaxspline.base.elements import CircularOrbit, sso_inclination
from jaxspline.base.land import is_land
from jaxspline.geometry.orbit import tabulate_orbits
from jaxspline.readers.mission import POINT, STRIP
from jaxspline.readers.scenario import (
    DEFAULT_SCENARIO_PATH,
    default_scenario,
    load_scenario,
    parse_scenario,
)
from jaxspline.readers.targets import load_targets_csv

EXAMPLE = Path(__file__).resolve().parents[2] / "scripts" / "example_scenario.toml"
TLE = [
    "1 40013U 14033D   26103.93736737  .00001307  00000+0  12918-3 0  9990",
    "2 40013  97.5922 340.6596 0001765 111.5119 248.6289 14.93547723628139",
]
HEAD = '[scenario]\nepoch = "2026-04-14T00:00:00Z"\nduration_s = 600.0\n'
SAT = "[[satellites]]\naltitude_km = 600.0\n"
POINT_TARGET = "[[targets]]\nlat_deg = 46.0\nlon_deg = 15.0\n"


@pytest.fixture(scope="module")
def default():
    return default_scenario()


def _write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_default_scenario_satellites(default):
    assert DEFAULT_SCENARIO_PATH.is_file()
    assert default.duration == 21600.0
    assert default.epoch.isoformat() == "2026-04-14T00:00:00+00:00"
    sats = default.satellites
    assert len(sats) == 6 and len({s.name for s in sats}) == 6
    models = collections.Counter(s.model for s in sats)
    assert models == {"per_channel": 2, "eigen_axis": 2, "flexible": 2}
    assert [s.sensor for s in sats].count("infrared") == 1
    assert len({s.orbit for s in sats}) == 6  # six distinct TLEs
    for s in sats:
        assert isinstance(s.orbit, tuple) and len(s.orbit) == 2
        assert (s.flex is not None) == (s.model == "flexible")
        assert (s.power is not None) == (s.model == "eigen_axis")
        assert np.shape(s.limits.rate) == ((3,) if s.model == "per_channel" else ())
    pc = next(s for s in sats if s.model == "per_channel")
    np.testing.assert_allclose(np.degrees(pc.limits.rate), [3.0, 3.0, 2.0])
    np.testing.assert_allclose(np.degrees(pc.limits.accel), [1.5, 1.5, 1.0])
    fl = next(s for s in sats if s.model == "flexible")
    assert fl.flex.freq == pytest.approx(2 * math.pi * 0.5)
    assert fl.flex.tolerance == pytest.approx(math.radians(0.006))
    assert np.degrees(fl.off_nadir_max) == pytest.approx(25.0)
    pl = default.planner
    assert (pl.time_step, pl.geometry_step, pl.scan_speeds) == (10.0, 10.0, (7000.0,))
    assert pl.default_time_limit == 90.0 and pl.margins.battery_wh == 10.0


def test_default_scenario_orbits_propagate(default):
    sources = [s.orbit for s in default.satellites]
    table = tabulate_orbits(sources, default.epoch_jd, 3600.0, 60.0)
    assert bool(np.all(table.ok))
    norms = np.linalg.norm(np.asarray(table.orbit.r), axis=-1)
    assert norms.shape == (6, table.orbit.t.shape[0])
    assert 6.6e6 < norms.min() and norms.max() < 7.5e6


def test_default_scenario_targets(default):
    tg = default.targets
    kinds = collections.Counter(tg.kind.tolist())
    assert kinds[POINT] >= 1000 and kinds[STRIP] == 200
    pts = tg.kind == POINT
    assert len(set(tg.name[pts])) == kinds[POINT]  # deduplicated by name
    assert set(np.unique(tg.value[pts])) <= set(range(1, 11))
    dur = tg.duration[pts]
    assert dur.min() >= 10.0 and dur.max() <= 30.0 and np.all(dur % 5.0 == 0.0)
    infrared = np.mean(tg.sensor[pts] == "infrared")
    assert 0.01 < infrared < 0.1
    strips = tg.length[~pts]
    assert strips.min() >= 20e3 and strips.max() <= 60e3
    assert np.all(np.abs(tg.lat) <= np.pi / 2) and np.all(np.abs(tg.lon) <= np.pi)


def test_example_file_loads():
    sc = load_scenario(EXAMPLE)
    assert sc.name == "example" and sc.duration == 3600.0
    assert [s.model for s in sc.satellites] == ["eigen_axis", "per_channel"]
    assert isinstance(sc.satellites[1].orbit, CircularOrbit)
    assert len(sc.targets) == 4 + 30
    assert list(sc.targets.name[:4]) == ["Ljubljana", "Trieste", "Graz", "Drava valley"]
    assert list(sc.targets.kind[:4]) == [POINT, POINT, POINT, STRIP]
    assert sc.targets.alt[0] == 295.0
    assert sc.planner.scan_speeds == (4000.0, 7000.0)


def test_units_are_converted(tmp_path):
    text = (
        '[scenario]\nepoch = "2026-04-14T00:00:00Z"\nduration_h = 1.5\n'
        "[[satellites]]\nmodel = 'eigen_axis'\naltitude_km = 700.0\ninclination_deg = 60.0\n"
        "raan_deg = 30.0\narg_lat_deg = 90.0\nrate_deg_s = 1.8\naccel_deg_s2 = 0.4\n"
        "off_nadir_max_deg = 30.0\nsettle_s = 2.0\n"
        "power = { capacity_wh = 100.0, idle_w = 5.0 }\n"
        "[[targets]]\nkind = 'strip'\nlat_deg = -30.0\nlon_deg = 120.0\nazimuth_deg = 90.0\n"
        "length_km = 40.0\npriority = 3.0\n"
        "[planner]\nscan_speeds_km_s = [4.0, 7.0]\nsun_elevation_min_deg = 10.0\n"
        "off_nadir_margin_deg = 0.5\ngap_margin_s = 0.1\nshadow_guard_steps = 2\n"
    )
    sc = load_scenario(_write(tmp_path, text))
    assert sc.duration == 5400.0
    sat = sc.satellites[0]
    assert sat.name == "sat1"
    assert float(sat.orbit.inclination) == pytest.approx(math.radians(60.0))
    assert float(sat.orbit.raan) == pytest.approx(math.radians(30.0))
    assert float(sat.orbit.arg_lat) == pytest.approx(math.pi / 2)
    assert float(sat.limits.rate) == pytest.approx(math.radians(1.8))
    assert float(sat.limits.accel) == pytest.approx(math.radians(0.4))
    assert sat.off_nadir_max == pytest.approx(math.radians(30.0))
    assert sat.power.initial_wh == 100.0 and sat.power.idle_w == 5.0
    tg = sc.targets
    assert (tg.lat[0], tg.lon[0]) == pytest.approx((-math.pi / 6, 2 * math.pi / 3))
    assert tg.azimuth[0] == pytest.approx(math.pi / 2)
    assert (tg.length[0], tg.value[0], tg.duration[0]) == (40e3, 3.0, 0.0)
    pl = sc.planner
    assert pl.scan_speeds == (4000.0, 7000.0)
    assert pl.sun_elevation_min == pytest.approx(math.radians(10.0))
    assert pl.margins.off_nadir == pytest.approx(math.radians(0.5))
    assert (pl.margins.gap, pl.margins.shadow_guard) == (0.1, 2)


def test_window_and_point_defaults():
    data = {
        "scenario": {"epoch": "2026-04-14T00:00:00Z", "duration_s": 600.0},
        "satellites": [{"tle": TLE}],
        "targets": [
            {"lat_deg": 1.0, "lon_deg": 2.0, "window_s": [100.0, 400.0], "duration_s": 20.0},
            {"lat_deg": 3.0, "lon_deg": 4.0, "sensor": "infrared", "name": "b"},
        ],
    }
    sc = parse_scenario(data)
    assert sc.satellites[0].orbit == tuple(TLE)
    tg = sc.targets
    assert (tg.t_lo[0], tg.t_hi[0]) == (100.0, 400.0)
    assert (tg.t_lo[1], tg.t_hi[1]) == (-np.inf, np.inf)
    assert list(tg.duration) == [20.0, 10.0]  # default point duration 10 s
    assert list(tg.name) == ["target_1", "b"] and list(tg.sensor) == ["", "infrared"]
    assert list(tg.value) == [1.0, 1.0]


def test_single_satellite_alias_and_routes_alias(tmp_path):
    text = HEAD + "[satellite]\nname = 'solo'\nrate_deg_s = 3.0\n"
    text += "[[routes]]\nlat_deg = 46.0\nlon_deg = 15.0\n"
    sc = load_scenario(_write(tmp_path, text))
    assert [s.name for s in sc.satellites] == ["solo"]
    np.testing.assert_allclose(sc.satellites[0].limits.rate, np.radians([3.0, 3.0, 3.0]))
    orbit = sc.satellites[0].orbit
    assert float(orbit.inclination) == pytest.approx(sso_inclination(600e3))
    assert len(sc.targets) == 1


def test_over_places_the_pass():
    data = {
        "scenario": {"epoch": "2026-04-14T00:00:00Z", "duration_s": 600.0},
        "satellites": [{"over": {"lat_deg": 46.0, "lon_deg": 15.0, "t_s": 300.0}}],
        "random_targets": {"count": 5, "lat_deg": [40.0, 50.0], "lon_deg": [10.0, 20.0]},
    }
    sc = parse_scenario(data)
    orb = sc.satellites[0].orbit
    u = float(orb.arg_lat + orb.mean_motion * 300.0)
    lat = math.asin(math.sin(float(orb.inclination)) * math.sin(u))
    assert math.degrees(lat) == pytest.approx(46.0, abs=1e-6)
    assert math.cos(u) < 0  # descending by default
    lat_t = np.degrees(sc.targets.lat)
    assert len(sc.targets) == 5 and lat_t.min() >= 40.0 and lat_t.max() <= 50.0


def test_targets_csv_relative_to_the_toml(tmp_path, monkeypatch):
    folder = tmp_path / "job"
    folder.mkdir()
    (folder / "t.csv").write_text(
        "name,lat_deg,lon_deg,priority,kind,length_km,window_lo_s,window_hi_s\n"
        "a,10.0,20.0,2,,,,\n"
        "b,-10.0,30.0,,strip,25,,\n"
        "c,0.5,0.5,7,point,,60,120\n",
        encoding="utf-8",
    )
    _write(folder, 'targets_csv = "t.csv"\n' + HEAD + SAT)
    monkeypatch.chdir(tmp_path)  # elsewhere: the path must start from the TOML's folder
    sc = load_scenario(folder / "s.toml")
    tg = sc.targets
    assert list(tg.name) == ["a", "b", "c"]
    assert list(tg.kind) == [POINT, STRIP, POINT]
    assert list(tg.value) == [2.0, 1.0, 7.0]
    assert (tg.duration[0], tg.length[1]) == (10.0, 25e3)
    assert (tg.t_lo[2], tg.t_hi[2]) == (60.0, 120.0)
    assert tg.lat[1] == pytest.approx(math.radians(-10.0))
    text = HEAD + SAT + '[targets_file]\npath = "t.csv"\n' + POINT_TARGET
    sc = load_scenario(_write(folder, text, "u.toml"))
    assert list(sc.targets.name) == ["target_1", "a", "b", "c"]


def test_imaging_time_fields_and_swath(tmp_path):
    text = (
        HEAD + SAT + "swath_km = 12.5\n" + POINT_TARGET + "desired_s = 300.0\ntolerance_s = 20.0\n"
    )
    text += "[[targets]]\nkind = 'strip'\nlat_deg = 1.0\nlon_deg = 2.0\nlength_km = 30.0\n"
    text += "min_duration_s = 6.0\n"
    text += POINT_TARGET + "min_duration_s = 15.0\n"
    sc = load_scenario(_write(tmp_path, text))
    assert sc.satellites[0].swath == 12.5e3
    tg = sc.targets
    assert (tg.mid_lo[0], tg.mid_hi[0]) == (280.0, 320.0)
    assert (tg.mid_lo[1], tg.mid_hi[1]) == (-np.inf, np.inf)
    assert list(tg.min_duration) == [0.0, 6.0, 15.0]
    assert tg.duration[2] == 15.0  # a point's duration defaults to max(10, min_duration_s)
    (tmp_path / "t.csv").write_text(
        "name,lat_deg,lon_deg,priority,desired_s,tolerance_s,min_duration_s,duration_s\n"
        "a,10,20,1,500,0,,\nb,10,20,1,,,12,\nc,10,20,1,,,,\n",
        encoding="utf-8",
    )
    tg = load_targets_csv(tmp_path / "t.csv")
    assert (tg.mid_lo[0], tg.mid_hi[0]) == (500.0, 500.0)
    assert list(tg.duration) == [10.0, 12.0, 10.0] and list(tg.min_duration) == [0.0, 12.0, 0.0]
    assert tg.mid_lo[2] == -np.inf and tg.mid_hi[2] == np.inf


CSV_BAD = [
    ("name,lat_deg,lon_deg,priority\nx,1,2,1\ny,95.2,2,1\n", 3, "lat_deg", "[-90, 90]", "'95.2'"),
    ("name,lat_deg,lon_deg,priority\nx,1,abc,1\n", 2, "lon_deg", "a number", "'abc'"),
    ("name,lat_deg,lon_deg,priority\nx,1,2,0\n", 2, "priority", "within [1e-06, 1e+06]", "'0'"),
    ("name,lat_deg,lon_deg,priority,kind\nx,1,2,1,blob\n", 2, "kind", "'point' or 'strip'", ""),
    ("name,lat_deg,lon_deg,priority,kind\nx,1,2,1,strip\n", 2, "length_km", "missing", ""),
    ("name,lat_deg,lon_deg,priority,colour\nx,1,2,1,red\n", 1, "colour", "unknown column", ""),
    ("name,lat_deg,lon_deg\nx,1,2\n", 1, "priority", "missing", ""),
    (
        "name,lat_deg,lon_deg,priority,window_lo_s,window_hi_s\nx,1,2,1,100,105\n",
        2,
        "window_hi_s",
        "shorter than the imaging time",
        "",
    ),
    ("name,lat_deg,lon_deg,priority,desired_s\nx,1,2,1,100\n", 2, "tolerance_s", "missing", ""),
    ("name,lat_deg,lon_deg,priority,tolerance_s\nx,1,2,1,5\n", 2, "tolerance_s", "only with", ""),
    (
        "name,lat_deg,lon_deg,priority,desired_s,tolerance_s\nx,1,2,1,9,-1\n",
        2,
        "tolerance_s",
        "within [0, ",
        "",
    ),
    (
        "name,lat_deg,lon_deg,priority,duration_s,min_duration_s\nx,1,2,1,5,8\n",
        2,
        "duration_s",
        "min_duration_s",
        "",
    ),
    (
        "name,lat_deg,lon_deg,priority,window_lo_s,window_hi_s,desired_s,tolerance_s\n"
        "x,1,2,1,100,200,400,10\n",
        2,
        "desired_s",
        "misses the window",
        "",
    ),
]


@pytest.mark.parametrize(("text", "row", "column", "why", "value"), CSV_BAD)
def test_bad_csv_names_file_row_and_column(tmp_path, text, row, column, why, value):
    path = tmp_path / "cities.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(ValueError) as err:
        load_targets_csv(path)
    msg = str(err.value)
    assert msg.startswith(f"cities.csv row {row}, column {column!r}: ")
    assert why in msg and value in msg


def test_land_only_random_targets_are_on_land():
    # is_land is checked against the global_land_mask package in test_land.py; each land
    # test streams the whole mask (3-4 s), so this test makes two: the draw and the check
    data = {
        "scenario": {"epoch": "2026-04-14T00:00:00Z", "duration_s": 600.0},
        "satellites": [{}],
        "random_targets": {"seed": 3, "count": 150, "land_only": True, "strip_fraction": 0.5},
    }
    tg = parse_scenario(data).targets
    # the same region without the mask puts most points at sea
    data["random_targets"]["land_only"] = False
    sea = parse_scenario(data).targets
    land = is_land(np.degrees(np.r_[tg.lat, sea.lat]), np.degrees(np.r_[tg.lon, sea.lon]))
    assert len(tg) == 150 and np.all(land[:150])
    assert np.mean(land[150:]) < 0.6
    assert 0.3 < np.mean(tg.kind == STRIP) < 0.7
    # deterministic in the seed (the land draw filters the same seeded generator's draws)
    np.testing.assert_array_equal(parse_scenario(data).targets.lat, sea.lat)


BAD = [
    (HEAD + SAT + "foo = 1\n" + POINT_TARGET, "satellites[0].foo", 6, "unknown key"),
    (HEAD + SAT + SAT + "accel_deg_s3 = 1\n" + POINT_TARGET, "satellites[1].accel_deg_s3", 8, ""),
    ("[sattelite]\n" + HEAD + SAT + POINT_TARGET, "sattelite", 1, "unknown"),
    (HEAD + "colour = 'red'\n" + SAT + POINT_TARGET, "scenario.colour", 4, "unknown key"),
    (HEAD + SAT + "rate_deg_s = [1, 2]\n" + POINT_TARGET, "satellites[0].rate_deg_s", 6, ""),
    (
        HEAD + SAT + "rate_deg_s = -1\n" + POINT_TARGET,
        "satellites[0].rate_deg_s",
        6,
        "within [0.01, 90]",
    ),
    (
        HEAD + "[[satellites]]\naltitude_km = 'high'\n" + POINT_TARGET,
        "satellites[0].altitude_km",
        5,
        "a number",
    ),
    (  # the value as written, in km, and the way out
        HEAD + "[[satellites]]\naltitude_km = 30000\n" + POINT_TARGET,
        "satellites[0].altitude_km",
        5,
        "30000 km admits no Sun-synchronous orbit (the orbit of a satellite without "
        "inclination_deg): give inclination_deg",
    ),
    (HEAD + SAT + "model = 'flexible'\n" + POINT_TARGET, "satellites[0].model", 6, "flex ="),
    (
        HEAD + SAT + "model = 'eigen_axis'\nrate_deg_s = [1, 1, 1]\n" + POINT_TARGET,
        "satellites[0].rate_deg_s",
        7,
        "one number for model 'eigen_axis'",
    ),
    (
        HEAD + SAT + "flex = { freq_hz = 1.0 }\n" + POINT_TARGET,
        "satellites[0].flex",
        6,
        "only used by model 'flexible'",
    ),
    (  # valid ranges, but no ramp time holds this mode: refused when read, not when planning
        HEAD + SAT + "model = 'flexible'\nrate_deg_s = 2.0\naccel_deg_s2 = 1.0\n"
        "flex = { freq_hz = 0.5, tolerance_deg = 1e-4 }\n" + POINT_TARGET,
        "satellites[0].flex",
        9,
        "no slew profile holds a 0.5 Hz mode",
    ),
    (
        HEAD + SAT + "model = 'flexible'\nflex = { damping = 0.1 }\n" + POINT_TARGET,
        "satellites[0].flex.freq_hz",
        7,
        "missing",
    ),
    (
        HEAD + SAT + "power = { capacity_wh = 10.0, initial_wh = 20.0 }\n" + POINT_TARGET,
        "satellites[0].power.initial_wh",
        6,
        "must be <= capacity_wh = 10, got 20",
    ),
    (HEAD + "[[satellites]]\ntle = ['1 x', '2 y']\n" + POINT_TARGET, "satellites[0].tle", 5, ""),
    (
        HEAD + "[[satellites]]\ntle = []\naltitude_km = 500\n" + POINT_TARGET,
        "satellites[0].altitude_km",
        6,
        "cannot be combined with tle",
    ),
    (
        HEAD + SAT + "over = { lat_deg = 99.0 }\n" + POINT_TARGET,
        "satellites[0].over.lat_deg",
        6,
        "",
    ),
    (
        HEAD + SAT + "[[satellites]]\nname = 'sat1'\n" + POINT_TARGET,
        "satellites[1].name",
        7,
        "duplicate",
    ),
    (HEAD + SAT, "targets", None, "no targets"),
    (HEAD + POINT_TARGET, "satellites", None, "at least one"),
    (
        HEAD + SAT + POINT_TARGET + POINT_TARGET.replace("46.0", "95"),
        "targets[1].lat_deg",
        10,
        "[-90, 90]",
    ),
    (HEAD + SAT + POINT_TARGET + "window_s = [500, 100]\n", "targets[0].window_s", 9, "lo <= hi"),
    (HEAD + SAT + POINT_TARGET + "kind = 'blob'\n", "targets[0].kind", 9, "'point' or 'strip'"),
    (
        HEAD + SAT + "[[targets]]\nkind = 'strip'\nlat_deg = 1\nlon_deg = 2\n",
        "targets[0].length_km",
        6,
        "missing",
    ),
    (HEAD + SAT + POINT_TARGET + "length_km = 5\n", "targets[0].length_km", 9, "a point has no"),
    ('targets_csv = "nothere.csv"\n' + HEAD + SAT, "targets_csv", 1, "not found"),
    (
        "[scenario]\nepoch = 'yesterday'\nduration_s = 1\n" + SAT + POINT_TARGET,
        "scenario.epoch",
        2,
        "ISO-8601",
    ),
    # an epoch without a time zone: refused, whatever zone it was meant in
    *[
        (
            f"[scenario]\nepoch = {epoch}\nduration_s = 600.0\n" + SAT + POINT_TARGET,
            "scenario.epoch",
            2,
            f"{shown} has no time zone: add Z (UTC) or an offset",
        )
        for epoch, shown in [
            ('"2026-04-14"', "2026-04-14"),
            ('"2026-04-14T12:30:00"', "2026-04-14T12:30:00"),
            ("2026-04-14T12:30:00", "2026-04-14T12:30:00"),  # a TOML local date-time
            ("2026-04-14", "2026-04-14"),  # a TOML local date
        ]
    ],
    # a blank name is refused for a target as for a satellite
    *[
        (HEAD + SAT + POINT_TARGET + f"name = {name}\n", field, 9, "must be a non-empty string")
        for name, field in [('""', "targets[0].name"), ('"   "', "targets[0].name")]
    ],
    (HEAD + "[[satellites]]\nname = '  '\n" + POINT_TARGET, "satellites[0].name", 5, "non-empty"),
    (
        '[scenario]\nepoch = "2026-04-14T00:00:00Z"\n' + SAT + POINT_TARGET,
        "scenario.duration_s",
        1,
        "exactly one",
    ),
    (
        HEAD + SAT + "[random_targets]\ncount = 0\n",
        "random_targets.count",
        7,
        "within [1, 1000000]",
    ),
    (
        HEAD + SAT + "[random_targets]\ncount = 5\nland_only = true\nlat_deg = [-5, -4]\n"
        "lon_deg = [-30, -29]\n",
        "random_targets.land_only",
        8,
        "land points",
    ),
    (
        HEAD + SAT + POINT_TARGET + "[planner]\ntime_step_s = 5.0\ngeometry_step_s = 2.0\n",
        "planner.time_step_s",
        10,
        "multiple",
    ),
    (
        HEAD + SAT + "swath_km = 0\n" + POINT_TARGET,
        "satellites[0].swath_km",
        6,
        "within [0.01, 5000]",
    ),
    (HEAD + SAT + POINT_TARGET + "desired_s = 100\n", "targets[0].tolerance_s", 6, "missing"),
    (
        HEAD + SAT + POINT_TARGET + "window_s = [0, 50]\ndesired_s = 100\ntolerance_s = 5\n",
        "targets[0].desired_s",
        10,
        "misses the window",
    ),
    (
        HEAD + SAT + POINT_TARGET + "[planner]\nbeam_width = 16\n",
        "planner.beam_width",
        10,
        "unknown key",
    ),
]


def test_an_epoch_with_a_zone_is_converted_to_utc_and_a_nameless_target_named(tmp_path):
    text = HEAD.replace('"2026-04-14T00:00:00Z"', "2026-04-14T02:30:00+02:00") + SAT
    sc = load_scenario(_write(tmp_path, text + POINT_TARGET + POINT_TARGET.replace("15.0", "16")))
    assert sc.epoch.isoformat() == "2026-04-14T00:30:00+00:00"
    assert sc.targets.name.tolist() == ["target_1", "target_2"]  # no name key: the default


def test_a_case_time_without_a_zone_is_refused():
    import datetime as dt

    from jaxspline.readers.case_files import parse_time

    with pytest.raises(ValueError, match=r"horizon_start: '2026-04-14T04:00:05' has no time "):
        parse_time("2026-04-14T04:00:05", where="horizon_start")
    with pytest.raises(ValueError, match="add Z"):
        parse_time("2026-04-14", where="x")
    # a YAML timestamp is a datetime; without a zone YAML's rules make it UTC
    naive = dt.datetime(2026, 4, 14, 4, 0, 5)
    assert parse_time(naive, allow_datetime=True) == parse_time("2026-04-14T04:00:05Z")


def test_tle_angles_are_checked(tmp_path):
    """SGP4 propagates an inclination of 200 deg without a word: the reader refuses it."""
    from jaxspline.readers.satellites import tle_checksum

    line2 = TLE[1][:8] + "200.0448" + TLE[1][16:68]
    line2 += str(tle_checksum(line2))
    text = (
        '[scenario]\nepoch = "2026-04-14T12:00:00Z"\nduration_s = 600.0\n[[satellites]]\n'
        f"tle = [{TLE[0]!r}, {line2!r}]\n" + POINT_TARGET
    )
    with pytest.raises(ValueError, match=r"satellites\[0\].tle .*inclination .* got 200"):
        load_scenario(_write(tmp_path, text))


@pytest.mark.parametrize(("text", "field", "line", "why"), BAD)
def test_bad_files_name_the_field_and_line(tmp_path, text, field, line, why):
    with pytest.raises(ValueError) as err:
        load_scenario(_write(tmp_path, text))
    msg = str(err.value)
    assert f": {field}" in msg and why in msg
    if line is not None:
        assert f"{field} (line {line}):" in msg


def test_invalid_toml_and_missing_files(tmp_path):
    with pytest.raises(ValueError, match="invalid TOML.*line 1"):
        load_scenario(_write(tmp_path, "[satellites\nx = 1\n"))
    with pytest.raises(FileNotFoundError, match="nothere"):
        load_scenario(tmp_path / "nothere.toml")
    with pytest.raises(FileNotFoundError, match="nothere"):
        load_targets_csv(tmp_path / "nothere.csv")


def test_a_scenario_file_over_its_size_limit_says_by_how_much(tmp_path):
    from jaxspline.readers.scenario import MAX_TOML_BYTES

    path = tmp_path / "big.toml"
    path.write_text("#" + "x" * MAX_TOML_BYTES + "\n", encoding="utf-8")  # 2 characters over
    with pytest.raises(ValueError) as exc:
        load_scenario(path)
    msg = str(exc.value)  # not "16 MiB, more than the 16 MiB"
    assert msg == (
        f"{path}: 16,777,218 characters, more than the 16,777,216 (16 MiB) a scenario file "
        "may have (put targets in a CSV file)"
    )


def test_the_reading_clock_ticks_every_read_tick_rows_of_a_csv_and_a_geojson(tmp_path):
    import json

    from jaxspline.readers.area_files import read_geojson
    from jaxspline.readers.fields import READ_CLOCK, READ_TICK_ROWS

    rows = "".join(f"t{i},{40 + i % 10},{10 + i % 7},1\n" for i in range(2 * READ_TICK_ROWS))
    (tmp_path / "t.csv").write_text("name,lat_deg,lon_deg,priority\n" + rows, encoding="utf-8")
    square = [[[15.0, 46.0], [15.001, 46.0], [15.001, 46.001], [15.0, 46.001], [15.0, 46.0]]]
    feature = {"type": "Feature", "geometry": {"type": "Polygon", "coordinates": square}}
    n_feats = READ_TICK_ROWS + 5
    doc = {"type": "FeatureCollection", "features": [feature] * n_feats}
    (tmp_path / "a.geojson").write_text(json.dumps(doc), encoding="utf-8")
    ticks = []
    token = READ_CLOCK.set(lambda label, share: ticks.append((label, round(share, 4))))
    try:
        load_targets_csv(tmp_path / "t.csv")
        read_geojson(tmp_path / "a.geojson")
    finally:
        READ_CLOCK.reset(token)
    lines = 2 * READ_TICK_ROWS + 2  # the header and the last newline
    csv = [s for label, s in ticks if label == "t.csv"]
    assert csv == [round(READ_TICK_ROWS / lines, 4), round(2 * READ_TICK_ROWS / lines, 4)]
    assert [s for label, s in ticks if label == "a.geojson"] == [round(READ_TICK_ROWS / n_feats, 4)]
