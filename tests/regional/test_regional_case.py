"""The regional_coverage case reader: the training cases load, every bad file is named."""

from __future__ import annotations

import json
import math
import shutil
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest
import yaml

from jaxspline.cli.case_commands import write_solution
from jaxspline.regional import case as rc
from jaxspline.regional.case import format_time, load_case, load_solution, parse_time
from jaxspline.regional.case_fields import tle_checksum

DATA = Path("/work/shared/data/regional_coverage/train")
if not DATA.is_dir():  # the CI copy of shared/ lies beside the clone
    DATA = Path(__file__).resolve().parents[3] / "shared/data/regional_coverage/train"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")
SMALL = "case_0003"


@pytest.fixture
def case_dir(tmp_path) -> Path:
    dst = tmp_path / SMALL
    shutil.copytree(DATA / SMALL, dst)
    return dst


def _edit_json(path: Path, fn) -> None:
    data = json.loads(path.read_text())
    fn(data)
    path.write_text(json.dumps(data))


def _edit_yaml(path: Path, fn) -> None:
    data = yaml.safe_load(path.read_text())
    fn(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))


def test_training_cases_load():
    for d in sorted(DATA.iterdir()):
        case = load_case(d)
        g = case.grid
        assert case.horizon_s == 72 * 3600
        assert case.time_step_s == 10 and case.sample_step_s == 5 and case.max_actions == 64
        assert 6 <= len(case.satellites) <= 12 and 2 <= len(case.regions) <= 4
        # flattened grid: one block per region, in region order, sums = totals
        assert np.all(np.diff(g.region) >= 0)
        sums = np.bincount(g.region, weights=g.weight_m2)
        np.testing.assert_allclose(sums, g.region_total_m2, rtol=1e-9)
        assert len(g.sample_id) == g.size == len(set(g.sample_id))
        for s in case.satellites:
            # ICEYE-like LEO: 14.9-15.6 rev/day
            assert 5500 < s.orbit_period_s < 5800
            assert s.sensor.min_edge_deg < s.sensor.max_edge_deg


def test_time_helpers(case_dir):
    case = load_case(case_dir)
    t = case.time_at(3600.5)
    assert case.seconds(t) == 3600.5
    assert format_time(case.time_at(10)) == "2025-07-18T00:00:10Z"
    assert format_time(datetime(2025, 1, 1, 0, 0, 0, 250000, tzinfo=UTC)).endswith(".250000Z")
    assert parse_time("2025-07-18T02:00:10+02:00") == case.time_at(10)
    with pytest.raises(ValueError, match="start: not an ISO 8601 time"):
        parse_time("yesterday", where="start")


def test_tle_checksum_and_period():
    l1 = "1 48918U 21059AR  25198.20029252  .00022303  00000-0  43262-3 0  9994"
    assert tle_checksum(l1) == 4
    l2 = "2 48918  97.6589   3.5479 0010524 127.8955 232.3247 15.47631360225573"
    sat = rc.Satellite("x", l1, l2, None, None, None)
    assert sat.mean_motion_rev_day == 15.4763136
    assert math.isclose(sat.orbit_period_s, 86400 / 15.4763136)


# (file, editor, expected message fragment)
def _sat0(fn):
    return rc.SATELLITES, lambda d: fn(d[0])


def _set0(section, key, value):
    return _sat0(lambda s: s[section].update({key: value}))


def _prop(i, key, value):
    return rc.REGIONS, lambda d: d["features"][i]["properties"].update({key: value})


def _bump_checksum(s):
    line = s["tle_line1"]
    s["tle_line1"] = line[:68] + str((int(line[68]) + 1) % 10)


def _two_points(d):
    ring = [[10.0, 10.0], [11.0, 10.0], [10.0, 10.0], [11.0, 10.0]]
    d["features"][1]["geometry"]["coordinates"] = [ring]


def _lon_out(d):
    d["features"][0]["geometry"]["coordinates"][0][1][0] = 200.0


def _dup_sample(d):
    d["regions"][1]["samples"].append(d["regions"][0]["samples"][0])


MAN, GRID = rc.MANIFEST, rc.GRID
BAD = {
    "manifest_missing_key": (
        MAN, lambda d: d.pop("horizon_start"), "manifest.json.horizon_start: missing field"),
    "manifest_end_before_start": (
        MAN, lambda d: d.update(horizon_end="2025-07-17T00:00:00Z"),
        "horizon_end: must be after horizon_start"),
    "manifest_bad_time": (
        MAN, lambda d: d.update(horizon_start="noon"),
        "manifest.json: horizon_start: not an ISO 8601 time"),
    "manifest_step_zero": (
        MAN, lambda d: d.update(time_step_s=0), "manifest.json.time_step_s: must be > 0, got 0"),
    "manifest_cap_float": (
        MAN, lambda d: d["scoring"].update(max_actions_total=6.5),
        "scoring.max_actions_total: expected an integer"),
    "rate_negative": (
        *_set0("agility", "max_roll_rate_deg_per_s", -1),
        "satellites.yaml: [0].agility.max_roll_rate_deg_per_s: must be > 0, got -1"),
    "fov_not_number": (
        *_set0("sensor", "cross_track_fov_deg", "wide"),
        "[0].sensor.cross_track_fov_deg: expected a number, got 'wide'"),
    "bool_is_not_number": (
        *_set0("power", "idle_power_w", True),
        "[0].power.idle_power_w: expected a number, got True"),
    "nan": (
        *_set0("power", "imaging_power_w", float("nan")),
        "[0].power.imaging_power_w: must be finite"),
    "inf": (
        *_set0("power", "slew_power_w", float("inf")), "[0].power.slew_power_w: must be finite"),
    "negative_idle": (
        *_set0("power", "idle_power_w", -5), "[0].power.idle_power_w: must be >= 0, got -5"),
    "negative_duration": (
        *_set0("sensor", "min_strip_duration_s", -10),
        "[0].sensor.min_strip_duration_s: must be > 0, got -10"),
    "negative_settling": (
        *_set0("agility", "settling_time_s", -1), "[0].agility.settling_time_s: must be >= 0"),
    "edge_min_gt_max": (
        *_set0("sensor", "min_edge_off_nadir_deg", 41),
        "[0].sensor.min_edge_off_nadir_deg: 41 > max_edge_off_nadir_deg"),
    "duration_min_gt_max": (
        *_set0("sensor", "min_strip_duration_s", 500),
        "[0].sensor.min_strip_duration_s: 500 > max_strip_duration_s"),
    "initial_gt_capacity": (
        *_set0("power", "initial_battery_wh", 1e6), "[0].power.initial_battery_wh"),
    "duty_negative": (
        *_set0("power", "imaging_duty_limit_s_per_orbit", -1),
        "[0].power.imaging_duty_limit_s_per_orbit: must be >= 0"),
    "missing_agility": (
        *_sat0(lambda s: s.pop("agility")), "satellites.yaml: [0].agility: missing field"),
    "tle_checksum": (*_sat0(_bump_checksum), "[0].tle_line1: bad checksum"),
    "tle_short": (
        *_sat0(lambda s: s.update(tle_line2=s["tle_line2"][:60])),
        "[0].tle_line2: not a 69-column TLE line 2"),
    "tle_swapped": (
        *_sat0(lambda s: s.update(tle_line1=s["tle_line2"], tle_line2=s["tle_line1"])),
        "[0].tle_line1: not a 69-column TLE line 1"),
    "duplicate_satellite": (
        rc.SATELLITES, lambda d: d.append(dict(d[0])), "satellite_id: duplicate 'sat_"),
    "empty_satellites": (
        rc.SATELLITES, lambda d: d.clear(), "expected a non-empty list of satellites"),
    "region_missing_id": (
        rc.REGIONS, lambda d: d["features"][0]["properties"].pop("region_id"),
        "regions.geojson: features[0].properties.region_id: missing field"),
    "region_two_points": (
        rc.REGIONS, _two_points,
        "features[1].geometry.coordinates[0]: a polygon needs >= 3 distinct points, got 2"),
    "region_weight_negative": (
        *_prop(0, "weight", -1), "features[0].properties.weight: must be >= 0"),
    "region_min_over_one": (
        *_prop(0, "min_required_coverage_ratio", 1.5), "min_required_coverage_ratio: must be <= 1"),
    "region_lon_out": (rc.REGIONS, _lon_out, "features[0].geometry.coordinates[0][1]: outside"),
    "region_not_polygon": (
        rc.REGIONS, lambda d: d["features"][0]["geometry"].update(type="Point"),
        "features[0].geometry.type: expected 'Polygon'"),
    "grid_no_samples": (
        GRID, lambda d: d["regions"][0].update(samples=[]),
        "coverage_grid.json: regions[0].samples: region 'gulf_of_mexico' has no samples"),
    "grid_missing_weight": (
        GRID, lambda d: d["regions"][1]["samples"][7].pop("weight_m2"),
        "regions[1].samples[7].weight_m2: missing field"),
    "grid_lat_out": (
        GRID, lambda d: d["regions"][1]["samples"][3].update(latitude_deg=91.0),
        "regions[1].samples[3].latitude_deg: must be <= 90"),
    "grid_unknown_region": (
        GRID, lambda d: d["regions"][0].update(region_id="atlantis"),
        "region_id 'atlantis' is not in regions.geojson"),
    "grid_missing_region": (
        GRID, lambda d: d["regions"].pop(0), "no samples for region 'gulf_of_mexico'"),
    "grid_total_zero": (
        GRID, lambda d: d["regions"][0].update(total_weight_m2=0),
        "regions[0].total_weight_m2: must be > 0"),
    "grid_duplicate_sample": (GRID, _dup_sample, "sample_id 'gulf_of_mexico_s000001' repeated"),
}  # fmt: skip


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_case_names_file_and_field(case_dir, name):
    fname, edit, message = BAD[name]
    path = case_dir / fname
    (_edit_yaml if fname.endswith(".yaml") else _edit_json)(path, edit)
    with pytest.raises(ValueError) as err:
        load_case(case_dir)
    assert message in str(err.value)


@pytest.mark.parametrize("fname", [rc.MANIFEST, rc.SATELLITES, rc.REGIONS, rc.GRID])
def test_missing_file(case_dir, fname):
    (case_dir / fname).unlink()
    with pytest.raises(ValueError, match=f"{fname}: file not found"):
        load_case(case_dir)


def test_missing_directory(tmp_path):
    with pytest.raises(ValueError, match="case directory not found"):
        load_case(tmp_path / "nope")


@pytest.mark.parametrize(
    ("fname", "text", "message"),
    [
        (rc.MANIFEST, "{not json", "manifest.json: not valid JSON"),
        (rc.MANIFEST, '{"time_step_s": NaN}', "manifest.json: not valid JSON: NaN"),
        (rc.MANIFEST, '{"a": 1, "a": 2}', "manifest.json: not valid JSON: duplicate key 'a'"),
        (rc.SATELLITES, "- [unclosed", "satellites.yaml: not valid YAML"),
        (rc.SATELLITES, "- a: 1\n  a: 2\n", "satellites.yaml: not valid YAML"),
        (rc.GRID, b"\xff\xfe{}", "coverage_grid.json: not UTF-8"),
        pytest.param(
            rc.MANIFEST,
            "[" * 50000 + "]" * 50000,
            "manifest.json: not valid JSON here",
            id="deep-json",
        ),  # fmt: skip
    ],
)
def test_unparsable_files(case_dir, fname, text, message):
    path = case_dir / fname
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with pytest.raises(ValueError, match=message):
        load_case(case_dir)


def test_optional_fields(case_dir):
    def edit(d):
        d["features"][0]["properties"]["min_required_coverage_ratio"] = 0.25

    _edit_json(case_dir / rc.REGIONS, edit)
    _edit_yaml(case_dir / rc.SATELLITES,
               lambda d: d[0]["power"].update(imaging_duty_limit_s_per_orbit=None))  # fmt: skip
    case = load_case(case_dir)
    assert case.regions[0].min_coverage == 0.25 and case.regions[1].min_coverage is None
    assert case.satellites[0].power.duty_limit_s is None


def test_solution_io(tmp_path):
    actions = [
        {"type": "strip_observation", "satellite_id": "s", "start_time": "2025-07-17T00:00:10Z",
         "duration_s": 20, "roll_deg": -20.5},
    ]  # fmt: skip
    path = tmp_path / "out" / "sol.json"
    write_solution(path, {"actions": actions})
    assert load_solution(path) == {"actions": actions}
    with pytest.raises(FileExistsError):
        write_solution(path, {"actions": []})
    write_solution(path, {"actions": []}, force=True)
    assert load_solution(path) == {"actions": []}
    assert sorted(p.name for p in path.parent.iterdir()) == ["sol.json"]  # no temp file left
    with pytest.raises(ValueError, match="a list of actions"):
        write_solution(tmp_path / "x.json", {"actions": 3})
    with pytest.raises(ValueError, match="a list of actions"):
        write_solution(tmp_path / "x.json", [])
    assert not (tmp_path / "x.json").exists()
    for text, message in [
        ("[1, 2]", "expected an object with an 'actions' list"),
        ('{"actions": 1}', "expected an object with an 'actions' list"),
        ("{", "not valid JSON"),
    ]:
        (tmp_path / "bad.json").write_text(text)
        with pytest.raises(ValueError, match=message):
            load_solution(tmp_path / "bad.json")
    with pytest.raises(ValueError, match="file not found"):
        load_solution(tmp_path / "none.json")
