"""The planner end to end on areas: a small scenario planned, its coverage recounted.

One agile satellite (a real TLE) passes over two small areas and a point target near
Trieste; its strips may pitch. References, none reading the planner's coverage: every
planned area strip's ground is rebuilt from sgp4 (positions at the geometry knots of its
imaging time, :mod:`_ref_coverage`: look directions as explicit rotations of nadir by the
strip's pitch and roll, the ray-ellipsoid root), its covered samples found by shapely,
their weights from the area's sample grid; the strip rules recounted from the scenario;
a regional_coverage training case planned through the adapter is checked by the
benchmark's independent checker (:mod:`jaxspline.regional.check`).
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path

import _ref_coverage as ref
import numpy as np
import pytest
import shapely

from jaxspline.cli import main
from jaxspline.geometry.area_grid import area_grid
from jaxspline.geometry.routes import AREA
from jaxspline.planner.pipeline import plan
from jaxspline.products.outputs import write_plan_outputs
from jaxspline.readers.scenario import load_scenario

TLE = (
    "1 43259U 18031A   26104.11950488  .00000002  00000+0  76800-5 0  9992",
    "2 43259  98.0579 166.8090 0002685 187.3457 172.7713 14.76430187433244",
)
SCENARIO = f"""
[scenario]
name = "area-plan"
epoch = "2026-04-16T09:04:00Z"
duration_s = 480.0

[[satellites]]
name = "eigen-1"
tle = {json.dumps(list(TLE))}
model = "eigen_axis"
rate_deg_s = 1.8
accel_deg_s2 = 0.4
settle_s = 2.0
off_nadir_max_deg = 30.0
swath_km = 15.0
fov_deg = 0.6
strip_duration_s = [10.0, 30.0]

[[areas]]
name = "karst"
lonlat_deg = [[13.55, 45.60], [13.95, 45.58], [13.98, 45.78], [13.62, 45.82]]
priority = 10.0
grid_km = 3.0

[[areas]]
name = "coast"
lonlat_deg = [[13.40, 45.45], [13.62, 45.45], [13.62, 45.58], [13.40, 45.58]]
priority = 5.0
grid_km = 3.0

[[targets]]
name = "Trieste"
lat_deg = 45.65
lon_deg = 13.78
priority = 8.0

[planner]
time_step_s = 5.0
geometry_step_s = 5.0
scan_speeds_km_s = [7.0]
max_actions = 5
"""
FOV_DEG = 0.6
POINT_ONLY = SCENARIO[SCENARIO.index("[[targets]]") :].replace("max_actions = 5\n", "")
REGIONAL = Path("/work/shared/data/regional_coverage/train")


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    d = tmp_path_factory.mktemp("area_plan")
    (d / "s.toml").write_text(SCENARIO)
    sc = load_scenario(d / "s.toml")
    # an iteration cap, not only a clock: the same plan on a loaded machine
    result = plan(sc, time_limit=120.0, seed=0, progress=False, max_iters=60)
    out = d / "out"
    out.mkdir()
    write_plan_outputs(result, out, plots=False, aem=False, html=True)
    return sc, result, out


def _area_strips(result):
    return np.flatnonzero(np.isfinite(result.observations.roll))


def _strip_ground(sc, result, i):
    """Reference edge points of planned strip i at its geometry knots."""
    o = result.observations
    t = np.arange(o.start[i], o.end[i] + 1e-6, sc.planner.geometry_step)
    pos, vel = ref.sgp4_tracks(*TLE, sc.epoch, t)
    roll, pitch = math.degrees(o.roll[i]), math.degrees(o.pitch[i])
    return ref.edges(pos, vel, roll, FOV_DEG, pitch)


def test_plan_is_valid_and_keeps_the_strip_rules(planned):
    sc, result, _ = planned
    o = result.observations
    assert result.report["valid"] and result.report["violations"] == []
    strips = _area_strips(result)
    assert strips.size >= 2 and len(o) <= sc.planner.max_actions
    assert np.all(sc.targets.kind[o.target[strips]] == AREA)
    assert np.all(np.isnan(o.roll[~np.isin(np.arange(len(o)), strips)]))
    sat = sc.satellites[0]
    off = sat.off_nadir_max
    for i in strips:
        dur = o.end[i] - o.start[i]
        assert 10.0 - 1e-9 <= dur <= 30.0 + 1e-9
        assert o.start[i] / 5.0 == pytest.approx(round(o.start[i] / 5.0), abs=1e-9)  # grid
        r, p = abs(o.roll[i]), abs(o.pitch[i])
        assert r + math.radians(FOV_DEG) / 2 <= off + 1e-9  # the outer edge in the limit
        assert math.acos(math.cos(r) * math.cos(p)) <= off + 1e-9  # the boresight
    assert np.any(np.abs(o.pitch[strips]) > 0.01)  # an agile satellite pitches
    assert np.all(o.slack >= -1e-9)


def test_covered_share_equals_an_independent_recount(planned):
    """Per area: the samples under some planned strip's reference quads == the plan's
    covered flags; covered share, value and the plan's value follow."""
    sc, result, _ = planned
    o = result.observations
    rep = {a["area"]: a for a in result.report["areas"]}
    quads = [_strip_ground(sc, result, i) for i in _area_strips(result)]
    total = 0.0
    for a, smp in zip(sc.areas, result.areas, strict=True):
        grid = area_grid(shapely.geometry.shape(a.geometry), a.spacing)
        np.testing.assert_array_equal(smp["lon_deg"], grid.lon_deg)
        hit = np.zeros(len(grid), bool)
        for inner, outer, ok in quads:
            assert ok.all()
            hit[ref.covered(inner, outer, grid.lon_deg, grid.lat_deg)] = True
        np.testing.assert_array_equal(np.asarray(smp["covered"], bool), hit, err_msg=a.name)
        share = float(grid.weight[hit].sum())
        r = rep[a.name]
        assert r["samples"] == len(grid) and r["samples_covered"] == int(hit.sum())
        assert r["covered_share"] == pytest.approx(share, abs=1e-12)
        prio = float(sc.targets.value[a.target])
        assert r["priority"] == prio and r["value"] == pytest.approx(prio * share, abs=1e-12)
        total += prio * share
    assert 0.0 < rep["karst"]["covered_share"] < 1.0  # partial: the check is not vacuous
    points = {int(t) for t in o.target if sc.targets.kind[t] != AREA}
    total += sum(float(sc.targets.value[t]) for t in points)
    assert result.value == pytest.approx(total, abs=1e-9)
    assert float(o.value.sum()) == pytest.approx(result.value, abs=1e-9)
    assert result.bound >= result.value - 1e-9


def test_footprints_are_the_strips_edges(planned):
    sc, result, _ = planned
    strips = set(_area_strips(result).tolist())
    assert len(result.footprints) == len(result.observations)
    for i, fp in enumerate(result.footprints):
        if i not in strips:
            assert fp is None
            continue
        inner, outer, _ = _strip_ground(sc, result, i)
        ring = np.concatenate([inner, outer[::-1], inner[:1]])
        np.testing.assert_allclose(np.stack(fp, -1), ring, atol=1e-7)


def test_plan_csv_has_the_area_columns(planned, tmp_path):
    sc, result, out = planned
    rows = list(csv.DictReader((out / "plan.csv").open()))
    rep = {a["area"]: a for a in result.report["areas"]}
    o = result.observations
    assert len(rows) == len(o)
    for i, row in enumerate(rows):
        if row["kind"] == "area":
            assert float(row["roll_deg"]) == pytest.approx(math.degrees(o.roll[i]), abs=1e-6)
            assert float(row["pitch_deg"]) == pytest.approx(math.degrees(o.pitch[i]), abs=1e-6)
            share = rep[row["target"]]["covered_share"]
            assert float(row["area_covered_share"]) == pytest.approx(share, abs=1e-6)
        else:
            assert row["roll_deg"] == row["pitch_deg"] == row["area_covered_share"] == ""
    # a plan without areas has none of these columns: its point observation alone, in the
    # scenario without the areas (Trieste stays target 0)
    (tmp_path / "p.toml").write_text(SCENARIO[: SCENARIO.index("[[areas]]")] + POINT_ONLY)
    sc2 = load_scenario(tmp_path / "p.toml")
    j = [i for i in range(len(o)) if not np.isfinite(o.roll[i])]
    obs = type(o)(*(np.asarray(x)[j] for x in o))
    points = dataclasses.replace(result, scenario=sc2, observations=obs, areas=[], footprints=[])
    points.to_csv(tmp_path / "p.csv")
    head = next(csv.reader((tmp_path / "p.csv").open()))
    assert not {"roll_deg", "pitch_deg", "area_covered_share"} & set(head)


def test_plan_json_view_and_the_page_rebuilt_by_view(planned, tmp_path):
    """plan.json's view holds each area's polygon and samples (covered as planned) and the
    area strips' footprints; ``jaxspline view`` rebuilds plan.html from the file alone."""
    sc, result, out = planned
    doc = json.loads((out / "plan.json").read_text())
    view = doc["view"]
    assert [a["name"] for a in view["areas"]] == [a.name for a in sc.areas]
    for a, v, smp in zip(sc.areas, view["areas"], result.areas, strict=True):
        assert shapely.geometry.shape(v["geometry"]).equals(shapely.geometry.shape(a.geometry))
        assert v["samples"]["covered"] == [int(x) for x in smp["covered"]]
        np.testing.assert_allclose(v["samples"]["lon_deg"], smp["lon_deg"], atol=1e-4)
    feet = view["observations"]["footprint"]
    strips = set(_area_strips(result).tolist())
    for i, fp in enumerate(feet):
        if i in strips:
            np.testing.assert_allclose(fp["lon_deg"], result.footprints[i][0], atol=1e-4)
            np.testing.assert_allclose(fp["lat_deg"], result.footprints[i][1], atol=1e-4)
    assert doc["report"]["areas"] == json.loads(json.dumps(result.report["areas"]))
    page = tmp_path / "again.html"
    assert main(["view", str(out / "plan.json"), "-o", str(page)]) == 0
    html = page.read_text()
    assert "karst" in html and "coast" in html
    assert page.stat().st_size > 0.5 * (out / "plan.html").stat().st_size


@pytest.mark.skipif(not REGIONAL.is_dir(), reason="regional training cases not available")
def test_a_regional_case_planned_through_the_adapter_is_valid():
    """case_0004 through solve_case (a short search): the benchmark's checker finds the
    solution valid; its coverage_ratio is the plan's value up to border samples."""
    from jaxspline.regional.adapter import solve_case
    from jaxspline.regional.case import load_case
    from jaxspline.regional.check import check_solution

    case = load_case(REGIONAL / "case_0004")
    sol, result = solve_case(case, time_limit=60.0, progress=False, max_iters=20)
    rep = check_solution(case, sol)
    assert rep.valid, rep.violations[:5]
    assert 0 < len(sol["actions"]) <= case.max_actions
    assert result.report["valid"]
    assert result.value == pytest.approx(rep.coverage_ratio, abs=1e-3)
    g = case.grid
    mine = np.zeros(g.size, bool)
    for i, smp in enumerate(result.areas):
        mine[np.flatnonzero(g.region == i)] = np.asarray(smp["covered"], bool)
    # only samples within metres of a strip's edge may differ (the rotation angle's drift,
    # tests/regional/test_coverage_kernel.py)
    assert np.sum(mine != rep.covered) <= max(2, 1e-3 * rep.covered.sum())
