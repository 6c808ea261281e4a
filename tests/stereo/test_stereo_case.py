"""The stereo_imaging case reader and solution files: every training case loads, every
malformed field is a ValueError naming the file and the field, solutions round-trip and
are written atomically."""

from __future__ import annotations

import json
import re
import shutil

import pytest
import yaml
from _ref_stereo import DATA, EXAMPLE

from jaxspline.cli.case_commands import write_solution
from jaxspline.stereo.case import (
    SCENE_TYPES,
    load_case,
    load_solution,
    parse_solution,
    solution_document,
)

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")


@pytest.fixture(scope="module")
def case1():
    return load_case(DATA / "case_0001")


@pytest.mark.parametrize("n", range(1, 6))
def test_every_training_case_loads(n):
    case = load_case(DATA / f"case_000{n}")
    assert case.case_id == f"case_000{n}"
    assert case.horizon_s == 172800.0
    assert len(case.satellites) == 10 and 120 <= len(case.targets) <= 144
    m = case.mission
    assert m.allow_cross_satellite and m.max_pair_separation_s == 3600.0
    assert (m.thresholds.min_overlap, m.thresholds.anchor_max_off_nadir_deg) == (0.8, 10.0)
    assert m.quality.geometry + m.quality.overlap + m.quality.resolution == pytest.approx(1.0)
    assert set(m.quality.tri_bonus) == set(SCENE_TYPES)
    assert {t.scene_type for t in case.targets} <= set(SCENE_TYPES)
    assert all(
        s.fov_deg == s.pixels * s.ifov_deg and s.access_step_s == 1.0 for s in case.satellites
    )


def _copy(tmp_path):
    dst = tmp_path / "case"
    shutil.copytree(DATA / "case_0001", dst)
    return dst


def _edit(path, change):
    data = yaml.safe_load(path.read_text())
    change(data)
    path.write_text(yaml.safe_dump(data, sort_keys=False))


def _set(keys, value):
    def change(data):
        node = data
        for k in keys[:-1]:
            node = node[k]
        if value is KeyError:
            del node[keys[-1]]
        else:
            node[keys[-1]] = value

    return change


@pytest.mark.parametrize(
    "file, keys, value, message",
    [
        (
            "mission.yaml",
            ["mission", "horizon_end"],
            KeyError,
            "mission.yaml: mission.horizon_end: missing field",
        ),
        (
            "mission.yaml",
            ["mission", "horizon_start"],
            "2026-04-20T05:00:00",
            "horizon_start: needs Z or an explicit offset",
        ),
        (
            "mission.yaml",
            ["mission", "horizon_end"],
            "2026-04-20T01:00:00Z",
            "horizon_end: must be after horizon_start",
        ),
        (
            "mission.yaml",
            ["mission", "validity_thresholds", "min_overlap_fraction"],
            "0.8",
            "min_overlap_fraction: expected a number, got '0.8'",
        ),
        (
            "mission.yaml",
            ["mission", "validity_thresholds", "max_convergence_deg"],
            2.0,
            "min_convergence_deg: 5 > max_convergence_deg 2",
        ),
        (
            "mission.yaml",
            ["mission", "quality_model", "tri_stereo_bonus_by_scene", "open"],
            KeyError,
            "tri_stereo_bonus_by_scene.open: missing field",
        ),
        (
            "mission.yaml",
            ["mission", "allow_cross_satellite_stereo"],
            "yes",
            "allow_cross_satellite_stereo: expected true or false",
        ),
        (
            "satellites.yaml",
            [0, "max_off_nadir_deg"],
            -1,
            "satellites.yaml: [0].max_off_nadir_deg: must be > 0, got -1",
        ),
        (
            "satellites.yaml",
            [2, "cross_track_pixels"],
            1.5,
            "[2].cross_track_pixels: expected an integer >= 1, got 1.5",
        ),
        (
            "satellites.yaml",
            [1, "id"],
            "sat_gaofen_2",
            "satellites.yaml: [1].id: duplicate 'sat_gaofen_2' (also [0])",
        ),
        (
            "satellites.yaml",
            [0, "min_obs_duration_s"],
            90.0,
            "[0].min_obs_duration_s: 90 > max_obs_duration_s 60",
        ),
        (
            "targets.yaml",
            [4, "scene_type"],
            "desert",
            "targets.yaml: [4].scene_type: 'desert' is not one of",
        ),
        (
            "targets.yaml",
            [0, "latitude_deg"],
            91.0,
            "targets.yaml: [0].latitude_deg: must be <= 90, got 91",
        ),
        (
            "targets.yaml",
            [3, "aoi_radius_m"],
            KeyError,
            "targets.yaml: [3].aoi_radius_m: missing field",
        ),
        (
            "targets.yaml",
            [1, "id"],
            None,
            "targets.yaml: [1].id: expected a non-empty string, got None",
        ),
    ],
)
def test_a_bad_field_names_its_file_and_field(tmp_path, file, keys, value, message):
    case = _copy(tmp_path)
    _edit(case / file, _set(keys, value))
    with pytest.raises(ValueError, match=re.escape(message)):
        load_case(case)


def test_a_bad_tle_checksum_is_named(tmp_path):
    case = _copy(tmp_path)

    def change(data):
        line = data[0]["tle_line1"]
        data[0]["tle_line1"] = line[:-1] + str((int(line[-1]) + 1) % 10)

    _edit(case / "satellites.yaml", change)
    with pytest.raises(ValueError, match=r"satellites.yaml: \[0\].tle_line1: bad checksum"):
        load_case(case)


def test_missing_files_and_folders(tmp_path):
    with pytest.raises(ValueError, match="case directory not found"):
        load_case(tmp_path / "none")
    case = _copy(tmp_path)
    (case / "targets.yaml").unlink()
    with pytest.raises(ValueError, match="targets.yaml: file not found"):
        load_case(case)


def test_the_example_solution_reads(case1):
    sol = load_solution(EXAMPLE, case1, strict=True)
    assert [o.index for o in sol.observations] == [0, 1, 2]
    o = sol.observations[1]
    assert (o.satellite_id, o.along_deg, o.across_deg) == ("sat_cartosat_2e", -7.8102, 25.7345)
    assert (o.end - o.start).total_seconds() == 4.0


def _action(**over):
    a = json.loads(EXAMPLE.read_text())["actions"][0]
    a.update(over)
    return a


@pytest.mark.parametrize(
    "data, message",
    [
        ([], "solution: expected an object with an 'actions' list"),
        ({"actions": {}}, "solution: actions: expected a list, got dict"),
        ({"actions": [3]}, r"solution: actions\[0\]: expected an object, got 3"),
        (
            {"actions": [_action(start_time="2026-04-21T03:52:18")]},
            r"actions\[0\].start_time: needs Z",
        ),
        ({"actions": [_action(end_time="soon")]}, r"actions\[0\].end_time: not an ISO 8601 time"),
        (
            {"actions": [_action(off_nadir_along_deg=None)]},
            r"actions\[0\].off_nadir_along_deg: expected a number",
        ),
        ({"actions": [{"type": "observation"}]}, r"actions\[0\].satellite_id: missing field"),
    ],
)
def test_a_malformed_solution_is_refused(data, message):
    with pytest.raises(ValueError, match=message):
        parse_solution(data)


@pytest.mark.parametrize(
    "over, message",
    [
        (dict(satellite_id="sat_x"), r"actions\[0\].satellite_id: unknown satellite 'sat_x'"),
        (dict(target_id="nowhere"), r"actions\[0\].target_id: unknown target 'nowhere'"),
        (
            dict(end_time="2026-04-21T03:52:18Z"),
            r"actions\[0\].end_time: .* is not after start_time",
        ),
        (
            dict(start_time="2026-04-20T04:59:59Z"),
            r"actions\[0\].start_time: .* is before horizon_start",
        ),
        (dict(end_time="2026-04-22T05:00:01Z"), r"actions\[0\].end_time: .* is after horizon_end"),
    ],
)
def test_strict_reading_refuses_what_the_checker_reports(case1, over, message):
    data = {"actions": [_action(**over)]}
    parse_solution(data, case1)  # the checker judges these
    with pytest.raises(ValueError, match=message):
        parse_solution(data, case1, strict=True)


def test_other_action_types_are_skipped(case1):
    sol = parse_solution({"actions": [{"type": "downlink"}, _action(), "x" and {"type": None}]})
    assert sol.skipped == (0, 2) and [o.index for o in sol.observations] == [1]


def test_write_solution_round_trips_atomically(tmp_path, case1):
    sol = load_solution(EXAMPLE, case1)
    out = write_solution(tmp_path / "sub" / "s.json", solution_document(sol))
    again = load_solution(out, case1, strict=True)
    assert again.observations == sol.observations
    assert [p.name for p in out.parent.iterdir()] == ["s.json"]  # no temp file left
    with pytest.raises(FileExistsError, match="exists"):
        write_solution(out, solution_document(sol))
    write_solution(out, solution_document(list(sol.observations[:1])), force=True)
    assert len(load_solution(out).observations) == 1
    with pytest.raises(ValueError, match=r"actions\[0\]"):
        write_solution(tmp_path / "bad.json", solution_document([{"type": "observation"}]))
    assert not (tmp_path / "bad.json").exists()
