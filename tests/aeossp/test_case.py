"""Tests for the aeossp_standard case loader and solution I/O."""

from __future__ import annotations

import functools
import json
import shutil
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
import yaml

from jaxspline.aeossp.case import (
    Case,
    format_time,
    load_case,
    load_solution,
    parse_time,
)
from jaxspline.cli.case_commands import write_solution

DATA = Path("/work/shared/data/aeossp_standard")
CASE1 = DATA / "train" / "case_0001"
pytestmark = pytest.mark.skipif(not CASE1.is_dir(), reason="benchmark data not present")


def _load(path):
    with open(path, encoding="utf-8") as fh:
        return yaml.load(fh, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


@pytest.fixture(scope="module")
def case() -> Case:
    return load_case(CASE1)


def test_fields_match_raw_yaml(case):
    raw_m = _load(CASE1 / "mission.yaml")["mission"]
    raw_s = _load(CASE1 / "satellites.yaml")["satellites"]
    raw_t = _load(CASE1 / "tasks.yaml")["tasks"]
    assert case.case_id == raw_m["case_id"] == "case_0001"
    assert case.horizon_start == datetime(2026, 4, 14, 4, tzinfo=UTC)
    assert case.duration_s == 12 * 3600
    assert (case.action_step_s, case.geometry_step_s, case.resource_step_s) == (5, 5, 10)
    assert len(case.satellites) == len(raw_s) and len(case.tasks) == len(raw_t)
    s, r = case.satellites[0], raw_s[0]
    assert s.satellite_id == r["satellite_id"] and s.norad_id == r["norad_catalog_id"]
    assert s.tle_line1 == r["tle_line1"] and s.tle_line2 == r["tle_line2"]
    assert s.sensor_type == r["sensor"]["sensor_type"]
    assert s.max_slew_rate_deg_s == r["attitude_model"]["max_slew_velocity_deg_per_s"]
    assert s.max_slew_accel_deg_s2 == r["attitude_model"]["max_slew_acceleration_deg_per_s2"]
    assert s.settling_time_s == r["attitude_model"]["settling_time_s"]
    assert s.max_off_nadir_deg == r["attitude_model"]["max_off_nadir_deg"]
    for key in ("battery_capacity_wh", "initial_battery_wh", "idle_power_w"):
        assert getattr(s, key) == r["resource_model"][key]
    assert s.sunlit_charge_power_w == r["resource_model"]["sunlit_charge_power_w"]
    t, r = case.tasks[-1], raw_t[-1]
    assert t.task_id == r["task_id"] and t.name == r["name"]
    assert (t.latitude_deg, t.longitude_deg, t.altitude_m) == (
        r["latitude_deg"],
        r["longitude_deg"],
        r["altitude_m"],
    )
    assert t.release_time == parse_time(r["release_time"])
    assert t.required_duration_s == r["required_duration_s"] and t.weight == r["weight"]
    table = case.task_table()
    assert table["release_s"][-1] == (t.release_time - case.horizon_start).total_seconds()
    assert table["infrared"].sum() == sum(x["required_sensor_type"] == "infrared" for x in raw_t)


def test_time_helpers():
    t = parse_time("2026-04-14T04:00:05Z")
    assert t == datetime(2026, 4, 14, 4, 0, 5, tzinfo=UTC)
    assert format_time(t) == "2026-04-14T04:00:05Z"
    assert parse_time("2026-04-14T06:00:05+02:00") == t
    assert format_time(t + timedelta(microseconds=250000)) == "2026-04-14T04:00:05.250000Z"
    with pytest.raises(ValueError, match="start_time"):
        parse_time("yesterday", where="start_time")
    with pytest.raises(ValueError):
        parse_time(12.0)


@functools.lru_cache(maxsize=1)
def _six_tasks_yaml() -> str:
    text = (CASE1 / "tasks.yaml").read_text(encoding="utf-8")
    cut = [i for i in range(len(text)) if text.startswith("\n- task_id:", i)][6]
    return text[: cut + 1]


def _broken_copy(tmp_path, fname, edit):
    """A copy of case_0001 cut to 6 tasks (fast to load), with ``fname`` edited."""
    dst = tmp_path / "case"
    dst.mkdir()
    shutil.copy(CASE1 / "mission.yaml", dst)
    shutil.copy(CASE1 / "satellites.yaml", dst)
    (dst / "tasks.yaml").write_text(_six_tasks_yaml())
    doc = _load(dst / fname)
    edit(doc)
    (dst / fname).write_text(yaml.safe_dump(doc))
    return dst


@pytest.mark.parametrize(
    "fname, edit, match",
    [
        ("mission.yaml", lambda d: d["mission"].pop("horizon_end"), "mission.yaml.*horizon_end"),
        (
            "mission.yaml",
            lambda d: d["mission"].__setitem__("action_time_step_s", -5),
            "action_time_step_s",
        ),
        (
            "satellites.yaml",
            lambda d: d["satellites"][1]["attitude_model"].pop("settling_time_s"),
            "satellites.yaml.*sat_002.*settling_time_s",
        ),
        (
            "satellites.yaml",
            lambda d: d["satellites"][0]["sensor"].__setitem__("sensor_type", "radar"),
            "sensor_type",
        ),
        (
            "satellites.yaml",
            lambda d: d["satellites"][1].__setitem__("satellite_id", "sat_001"),
            "duplicate satellite_id",
        ),
        (
            "tasks.yaml",
            lambda d: d["tasks"][3].__setitem__("release_time", "soon"),
            "tasks.yaml.*task_0004.*release_time",
        ),
        ("tasks.yaml", lambda d: d["tasks"][0].pop("weight"), "tasks.yaml.*weight"),
        (  # a damaged TLE (SGP4 alone takes it): the checksum names the line
            "satellites.yaml",
            lambda d: d["satellites"][0].update(
                tle_line1=d["satellites"][0]["tle_line1"][:-1] + "4"
            ),
            "satellites.yaml.*sat_001.*tle_line1: line 1 checksum",
        ),
        (
            "tasks.yaml",
            lambda d: d["tasks"][2].__setitem__("latitude_deg", "north"),
            "latitude_deg",
        ),
    ],
)
def test_invalid_fields_name_file_and_field(tmp_path, fname, edit, match):
    with pytest.raises(ValueError, match=match):
        load_case(_broken_copy(tmp_path, fname, edit))


def test_missing_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        load_case(tmp_path / "nope")
    with pytest.raises(FileNotFoundError, match="mission.yaml"):
        load_case(tmp_path)


def test_solution_io(tmp_path):
    actions = [
        {
            "type": "observation",
            "satellite_id": "sat_001",
            "task_id": "task_0001",
            "start_time": "2026-04-14T05:00:00Z",
            "end_time": "2026-04-14T05:00:45Z",
        }
    ]
    path = tmp_path / "sub" / "sol.json"
    write_solution(path, {"actions": actions})
    assert load_solution(path) == {"actions": actions}
    assert [p.name for p in path.parent.iterdir()] == ["sol.json"]  # no temp file left
    with pytest.raises(FileExistsError):
        write_solution(path, {"actions": []})
    write_solution(path, {"actions": []}, force=True)
    assert json.loads(path.read_text()) == {"actions": []}
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ValueError, match="bad.json"):
        load_solution(bad)
    bad.write_text('{"acts": []}')
    with pytest.raises(ValueError, match="actions"):
        load_solution(bad)
    assert load_solution(DATA / "example_solution.json") == {"actions": []}
