"""The independent regional checker: coverage against an independent geometry, every rule
with a failing case and a near miss, the battery by hand, and the ``regional check`` CLI."""

from __future__ import annotations

import json
import math
import time
from dataclasses import replace
from datetime import timedelta
from pathlib import Path

import numpy as np
import pytest
import shapely
from _ref_regional import (
    RefTrack,
    heikkinen,
    ref_covered,
    ref_direction,
    ref_hit,
    spaced,
    useful_actions,
)

from jaxspline.aeossp.check_frames import bang_coast_bang_time
from jaxspline.regional.case import format_time, load_case
from jaxspline.regional.check import check_solution, duty_window_s, format_report
from jaxspline.regional.check_geometry import (
    Track,
    ecef_to_lonlat,
    points_in_quad,
    quad_area,
    ray_ellipsoid,
    strip_ground,
)

DATA = Path("/work/shared/data/regional_coverage/train")
if not DATA.is_dir():
    DATA = Path(__file__).resolve().parents[3] / "shared/data/regional_coverage/train"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")
HOURS = 6.0
BASE_START = 600.0  # s: a valid strip of satellite 0 in the mini case
BASE_ROLL = 25.0


@pytest.fixture(scope="module")
def case1():
    """case_0001 cut to its first 24 h (fast battery checks, several passes per region)."""
    full = load_case(DATA / "case_0001")
    return replace(full, end=full.start + timedelta(hours=24))


@pytest.fixture(scope="module")
def mini(case1):
    """case_0001 cut to its first satellite and 6 h (fast battery checks)."""
    return replace(case1, end=case1.start + timedelta(hours=HOURS), satellites=case1.satellites[:1])


@pytest.fixture(scope="module")
def valid12(case1):
    acts = spaced(case1, useful_actions(case1, 40, seed=3))[:12]
    assert len(acts) == 12
    return acts


def act(case, start=BASE_START, dur=60, roll=BASE_ROLL, sat=0, **extra):
    a = {
        "type": "strip_observation",
        "satellite_id": case.satellites[sat].id,
        "start_time": format_time(case.time_at(start)),
        "duration_s": dur,
        "roll_deg": roll,
    }
    a.update(extra)
    return a


def rules(report):
    return sorted({v.rule for v in report.violations})


# ----------------------------------------------------------------------------- geometry


def test_coverage_matches_independent_geometry(case1, valid12):
    report = check_solution(case1, {"actions": valid12})
    assert report.valid, format_report(report)
    ref, polys = ref_covered(case1, valid12)
    assert ref.sum() > 1000  # the actions do cover samples
    g = case1.grid
    ratios = np.bincount(g.region, weights=g.weight_m2 * ref) / g.region_total_m2
    # the checker's mask, rebuilt from its per-action covered weight
    assert math.isclose(report.covered_weight_m2, float(g.weight_m2[ref].sum()), rel_tol=1e-3)
    for r, x in zip(case1.regions, ratios, strict=True):
        assert abs(report.region_ratios[r.id] - x) < 1e-3
    assert abs(report.coverage_ratio - ratios.mean()) < 1e-3
    assert abs(report.weighted_coverage_ratio - ref @ g.weight_m2 / g.region_total_m2.sum()) < 1e-3


def test_covered_set_differs_only_at_borders(case1, valid12):
    """Sample by sample: a disagreement is only allowed within 1e-4 deg of a quad border."""
    report = check_solution(case1, valid12)
    ref, polys = ref_covered(case1, valid12)
    g = case1.grid
    diff = np.flatnonzero(report.covered != ref)
    border = shapely.union_all([p.boundary for p in polys])
    for i in diff:
        assert border.distance(shapely.Point(g.lon_deg[i], g.lat_deg[i])) < 1e-4
    assert len(diff) <= 3


def test_ground_points_match_reference(case1):
    """Ray ground points of the checker vs the reference chain (< 5 m everywhere)."""
    rng = np.random.default_rng(0)
    for sat in case1.satellites:
        tr, rt = Track(sat, case1.start), RefTrack(sat, case1.start)
        for t in rng.uniform(0, case1.horizon_s, 4):
            for a in (-38.0, -17.0, 22.0, 39.0):
                mine = strip_ground(tr, t, np.array([0.0]), [a])[0, 0]
                pos, vel = rt.state(t)
                ref = ref_hit(pos, ref_direction(pos, vel, a))
                assert np.linalg.norm(mine - ref) < 5.0
                lon, lat = ecef_to_lonlat(mine)
                rlon, rlat = heikkinen(mine)
                assert abs(lon - rlon) < 1e-9 and abs(lat - rlat) < 1e-9


def test_ray_ellipsoid_misses_and_hits():
    o = np.array([[7.0e6, 0.0, 0.0]] * 3)
    d = np.array([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    s = ray_ellipsoid(o, d)
    assert math.isclose(s[0], 7.0e6 - 6378137.0, rel_tol=1e-12)
    assert np.isnan(s[1]) and np.isnan(s[2])
    # grazing ray along z at x = b-ish: hits the polar cap at the far point of the ellipse
    s = ray_ellipsoid(np.array([0.0, 0.0, 7.0e6]), np.array([0.0, 0.0, -1.0]))
    assert math.isclose(s, 7.0e6 - 6356752.314245179, rel_tol=1e-12)


def test_points_in_quad_vs_shapely():
    """Random convex and concave quads on an integer lattice, points on a half lattice
    (so vertices and edge points are exact): the border counts, as ``covers``."""
    rng = np.random.default_rng(1)
    xs, ys = np.meshgrid(np.arange(-1, 11.5, 0.5), np.arange(-1, 11.5, 0.5))
    x, y = xs.ravel(), ys.ravel()
    pts = shapely.points(x, y)
    n = 0
    while n < 60:
        quad = rng.integers(0, 11, size=(4, 2)).astype(float)
        poly = shapely.Polygon(quad)
        if not poly.is_valid or poly.area == 0:
            continue
        n += 1
        np.testing.assert_array_equal(points_in_quad(quad, x, y), shapely.covers(poly, pts))
    assert quad_area(np.array([[[0, 0], [2, 0], [2, 1], [0, 1]]], dtype=float))[0] == 2.0
    assert quad_area(np.array([[[0, 0], [1, 1], [2, 2], [1, 1]]], dtype=float))[0] == 0.0


# ----------------------------------------------------------------------------- rules


def test_empty_and_base_solutions_valid(mini):
    empty = check_solution(mini, {"actions": []})
    assert empty.valid and empty.num_actions == 0 and empty.coverage_ratio == 0.0
    base = check_solution(mini, [act(mini)])
    assert base.valid, format_report(base)
    assert base.min_battery_wh < empty.min_battery_wh or base.min_battery_wh == empty.min_battery_wh


def test_action_cap(mini):
    two = [act(mini), act(mini, start=3000)]
    assert rules(check_solution(replace(mini, max_actions=1), two)) == ["action_cap"]
    assert check_solution(replace(mini, max_actions=2), two).valid


def test_a_solution_over_the_action_cap_fails_at_once_naming_it(mini):
    """100,000 actions against a cap of 64: refused by the cap alone, before the rules of
    every action and the coverage are worked out (a minute of work for nothing)."""
    many = [act(mini, start=BASE_START + 10 * (i % 500)) for i in range(100_000)]
    t0 = time.monotonic()
    report = check_solution(replace(mini, max_actions=64), {"actions": many})
    assert time.monotonic() - t0 < 2.0
    assert not report.valid and rules(report) == ["action_cap"]
    assert report.violations[0].message.startswith(
        "100000 actions > cap 64 (scoring.max_actions_total); the other rules and the coverage"
    )
    assert report.num_actions == 100_000 and report.coverage_ratio == 0.0
    json.loads(report.to_json())  # the scores are numbers (0), not NaN


@pytest.mark.parametrize(
    ("change", "rule"),
    [
        ({"type": "observation"}, "structure"),
        ({"satellite_id": 5}, "structure"),
        ({"satellite_id": "sat_nobody"}, "satellite"),
        ({"start_time": "2025-07-17T00:10:00"}, "structure"),  # no time zone
        ({"start_time": "soon"}, "structure"),
        ({"duration_s": "60"}, "structure"),
        ({"duration_s": True}, "structure"),
        ({"roll_deg": float("nan")}, "structure"),
        ({"roll_deg": None}, "structure"),
    ],
)
def test_structure(mini, change, rule):
    report = check_solution(mini, [act(mini, **change)])
    assert rules(report) == [rule]
    assert report.violations[0].action == 0


def test_structure_missing_field_and_non_object(mini):
    a = act(mini)
    del a["roll_deg"]
    assert rules(check_solution(mini, [a, 3])) == ["structure"]
    with pytest.raises(ValueError, match="actions: expected a list"):
        check_solution(mini, {"actions": {}})


@pytest.mark.parametrize(
    ("start", "dur", "rule"),
    [
        (-10, 60, "horizon"),
        (HOURS * 3600 - 50, 60, "horizon"),  # ends 10 s late (start not on the grid either)
        (HOURS * 3600 - 60, 60, None),  # ends exactly at the horizon end
        (0, 60, None),
        (605, 60, "time_grid"),
        (600.000001, 60, None),  # 1 µs off the grid: within the 1e-6 step tolerance
        (600, 25, "duration"),  # not a multiple of 10 s
        (600, 10, "duration"),  # below min 20 s
        (600, 190, "duration"),  # above max 180 s
        (600, 0, "duration"),
        (600, 20, None),
        (600, 180, None),
    ],
)
def test_timing(mini, start, dur, rule):
    report = check_solution(mini, [act(mini, start=start, dur=dur)])
    assert (rule in rules(report)) if rule else report.valid, format_report(report)


@pytest.mark.parametrize(
    ("roll", "ok"),
    [
        (18.4 - 2e-6, False),  # inner edge 2e-6 deg below 16
        (18.4 - 5e-7, True),  # within the 1e-6 deg tolerance
        (-(18.4 - 2e-6), False),
        (37.6 + 2e-6, False),  # outer edge 2e-6 deg above 40
        (37.6 + 5e-7, True),
        (-37.6, True),
    ],
)
def test_band(mini, roll, ok):
    report = check_solution(mini, [act(mini, roll=roll)])
    assert report.valid if ok else rules(report) == ["band"]


def test_rays_must_hit_the_earth(mini):
    sat = mini.satellites[0]
    wide = replace(sat, sensor=replace(sat.sensor, max_edge_deg=89.0))
    case = replace(mini, satellites=(wide,))
    assert rules(check_solution(case, [act(case, roll=80.0)])) == ["ray"]
    assert check_solution(case, [act(case, roll=55.0)]).valid


def _ref_boresight_angle(case, a_end, r1, b_start, r2):
    rt = RefTrack(case.satellites[0], case.start)
    p1, v1 = rt.state(a_end)
    p2, v2 = rt.state(b_start)
    b1, b2 = ref_direction(p1, v1, r1), ref_direction(p2, v2, r2)
    return math.degrees(math.atan2(np.linalg.norm(np.cross(b1, b2)), b1 @ b2))


def test_overlap_and_settling(mini):
    a = act(mini)
    assert rules(check_solution(mini, [a, act(mini, start=BASE_START + 50)])) == ["overlap"]
    # back to back with the same roll: the settling time is still needed
    assert rules(check_solution(mini, [a, act(mini, start=BASE_START + 60)])) == ["slew"]
    assert check_solution(mini, [a, act(mini, start=BASE_START + 70)]).valid


def test_slew_threshold(mini):
    """Gap 10 s: the largest slew is d* with slew(d*) + settling = 10 s; the next roll is
    chosen (by the reference geometry) so the boresight angle is d* -/+ 0.01 deg."""
    ag = mini.satellites[0].agility
    lo_d, hi_d = 0.0, 40.0
    for _ in range(100):
        mid = 0.5 * (lo_d + hi_d)
        need = bang_coast_bang_time(mid, ag.rate_deg_s, ag.accel_deg_s2) + ag.settling_s
        lo_d, hi_d = (mid, hi_d) if need < 10.0 else (lo_d, mid)
    d_star = lo_d
    end, nxt = BASE_START + 60, BASE_START + 70

    def roll_for(angle):
        lo, hi = BASE_ROLL, 37.6
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            ang = _ref_boresight_angle(mini, end, BASE_ROLL, nxt, mid)
            lo, hi = (mid, hi) if ang < angle else (lo, mid)
        return 0.5 * (lo + hi)

    ok = [act(mini), act(mini, start=nxt, roll=roll_for(d_star - 0.01))]
    bad = [act(mini), act(mini, start=nxt, roll=roll_for(d_star + 0.01))]
    assert check_solution(mini, ok).valid
    assert rules(check_solution(mini, bad)) == ["slew"]


def test_slew_counts_the_frame_rotation(mini):
    """Same roll 10 s apart: |Δr| = 0, but the boresight turns with the orbit (official)."""
    sat = mini.satellites[0]
    slow = replace(sat, agility=replace(sat.agility, accel_deg_s2=0.02))
    case = replace(mini, satellites=(slow,))
    ang = _ref_boresight_angle(case, BASE_START + 60, BASE_ROLL, BASE_START + 70, BASE_ROLL)
    assert 0.3 < ang < 1.0
    assert bang_coast_bang_time(ang, 1.8, 0.02) + sat.agility.settling_s > 10.0
    assert rules(check_solution(case, [act(case), act(case, start=BASE_START + 70)])) == ["slew"]


DUTY_CASES = [(100, 200, False), (120, 200, True), (100, 6000, True), (None, 200, True)]


@pytest.mark.parametrize(("limit", "gap", "ok"), DUTY_CASES)
def test_duty(mini, limit, gap, ok):
    sat = mini.satellites[0]
    case = replace(mini, satellites=(replace(sat, power=replace(sat.power, duty_limit_s=limit)),))
    report = check_solution(case, [act(case), act(case, start=BASE_START + 60 + gap)])
    assert report.valid if ok else rules(report) == ["duty"]


def test_duty_window_takes_the_longer_reading():
    from jaxspline.regional.case import Satellite

    l1 = "1 48918U 21059AR  25198.20029252  .00022303  00000-0  43262-3 0  9994"
    merged_big = "2 48918  97.6589   3.5479 0010524 127.8955 232.3247 15.47631360225573"
    merged_small = "2 48918  97.6589   3.5479 0010524 127.8955   5.3247 15.47631360225573"
    spaced_line = "2 48918  97.6589   3.5479 0010524 127.8955 232.3247 15.47631360 25573"
    true = 86400 / 15.4763136
    for line, want in [(merged_big, true), (merged_small, 86400 / 5.3247), (spaced_line, true)]:
        sat = Satellite("x", l1, line, None, None, None)
        assert math.isclose(duty_window_s(sat), want, rel_tol=1e-12)


def _power_case(mini, initial, charge=0.0):
    sat = mini.satellites[0]
    p = replace(sat.power, capacity_wh=1e5, initial_wh=initial, charge_w=charge)
    return replace(mini, satellites=(replace(sat, power=p),))


def test_battery_by_hand(mini):
    """No charging: the minimum is initial - idle·H - imaging·dur - slew·(slew + settle)."""
    p = mini.satellites[0].power
    ag = mini.satellites[0].agility
    a, b = act(mini), act(mini, start=BASE_START + 120, roll=30.0)
    ang = _ref_boresight_angle(mini, BASE_START + 60, BASE_ROLL, BASE_START + 120, 30.0)
    window = bang_coast_bang_time(ang, ag.rate_deg_s, ag.accel_deg_s2) + ag.settling_s
    used = (p.idle_w * HOURS * 3600 + p.imaging_w * 120 + p.slew_w * window) / 3600
    report = check_solution(_power_case(mini, used + 1e-3), [a, b])
    assert report.valid, format_report(report)
    assert abs(report.min_battery_wh - 1e-3) < 1e-6
    assert rules(check_solution(_power_case(mini, used - 1e-3), [a, b])) == ["battery"]


def _meeus_sun_dir(jd_tt):
    t = (jd_tt - 2451545.0) / 36525.0
    m = math.radians(357.52911 + 35999.05029 * t)
    c = (1.914602 - 0.004817 * t) * math.sin(m) + 0.019993 * math.sin(2 * m)
    lam = math.radians(280.46646 + 36000.76983 * t + c)
    eps = math.radians(23.439291 - 0.0130042 * t)
    return np.array([math.cos(lam), math.cos(eps) * math.sin(lam), math.sin(eps) * math.sin(lam)])


def test_battery_against_independent_sun(mini):
    """Charging on: a sequential simulation with Meeus's Sun and TEME positions (of date)
    gives the same lowest level within 1 Wh, and the level never passes the capacity."""
    from sgp4.api import WGS84, Satrec

    sat = mini.satellites[0]
    p = sat.power
    acts = [act(mini), act(mini, start=7000, dur=180, roll=-30.0)]
    report = check_solution(mini, acts)
    assert report.valid
    rec = Satrec.twoline2rv(sat.tle1, sat.tle2, WGS84)
    h = mini.horizon_s
    t = np.unique(np.concatenate([np.arange(0, h, 5.0), [h, 600, 660, 7000, 7180]]))
    e, low = p.initial_wh, p.initial_wh
    for t0, t1 in zip(t[:-1], t[1:], strict=True):
        mid = 0.5 * (t0 + t1)
        jd = (mini.start.timestamp() + mid) / 86400 + 2440587.5
        _, r, _ = rec.sgp4(math.floor(jd), jd - math.floor(jd))
        r = np.array(r) * 1e3
        s = _meeus_sun_dir(jd + 69.184 / 86400)
        lit = not (r @ s < 0 and np.linalg.norm(r - (r @ s) * s) < 6378136.3)
        load = p.idle_w + p.imaging_w * ((600 <= mid < 660) or (7000 <= mid < 7180))
        e = min(p.capacity_wh, e + ((p.charge_w if lit else 0.0) - load) * (t1 - t0) / 3600)
        low = min(low, e)
    assert abs(report.min_battery_wh - low) < 1.0


def test_region_minimum(case1, valid12):
    base = check_solution(case1, valid12)
    r0 = case1.regions[0]
    x = base.region_ratios[r0.id]
    for need, ok in [(x + 1e-6, False), (x, True), (x - 1e-6, True)]:
        case = replace(case1, regions=(replace(r0, min_coverage=need), *case1.regions[1:]))
        report = check_solution(case, valid12)
        assert report.valid if ok else rules(report) == ["region_min"]


def test_report_json(mini):
    report = check_solution(mini, [act(mini), act(mini, start=BASE_START + 10)])
    data = json.loads(report.to_json())
    assert data["valid"] is False and data["num_actions"] == 2
    assert data["violations"][0]["rule"] == "overlap" and data["violations"][0]["action"] == 1
    assert "violations: 1" in format_report(report)


# ----------------------------------------------------------------------------- CLI


def test_cli_exit_codes(tmp_path, case1, valid12, capsys):
    from jaxspline.cli import main

    good, bad = tmp_path / "good.json", tmp_path / "bad.json"
    good.write_text(json.dumps({"actions": valid12[:3]}))
    bad.write_text(json.dumps({"actions": [valid12[0], valid12[0]]}))
    case_dir = str(DATA / "case_0001")
    out = tmp_path / "report.json"
    assert main(["regional", "check", case_dir, str(good), "--json", str(out)]) == 0
    assert json.loads(out.read_text())["valid"] is True
    text = capsys.readouterr().out
    for key in ("coverage_ratio", "weighted_coverage_ratio", "num_actions: 3", "min_battery_wh"):
        assert key in text
    assert main(["regional", "check", case_dir, str(bad)]) == 1
    assert "overlap" in capsys.readouterr().out
    (tmp_path / "broken.json").write_text("{")
    assert main(["regional", "check", case_dir, str(tmp_path / "broken.json")]) == 2
    assert main(["regional", "check", str(tmp_path / "nocase"), str(good)]) == 2
    assert "not found" in capsys.readouterr().err


# ----------------------------------------------------------------------------- layout

CHECKER = ("check", "check_geometry")
ALLOWED = {
    "jaxspline.regional.case",
    "jaxspline.regional.check_geometry",
    "jaxspline.aeossp.check_frames",
}


@pytest.mark.parametrize("name", CHECKER)
def test_checker_is_independent(name):
    """The checker imports nothing of the package but the case reader, its own geometry
    and the other benchmark's independent frame models: no solver code."""
    import ast

    import jaxspline.regional as pkg

    path = Path(pkg.__file__).parent / f"{name}.py"
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("jaxspline"):
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("jaxspline"))
    assert found <= ALLOWED, found - ALLOWED


@pytest.mark.parametrize("name", ("case", "case_fields", "check", "check_geometry", "cli"))
def test_public_names_documented(name):
    import importlib
    import inspect

    mod = importlib.import_module(f"jaxspline.regional.{name}")
    assert mod.__doc__
    for attr, obj in vars(mod).items():
        if attr.startswith("_") or getattr(obj, "__module__", None) != mod.__name__:
            continue
        if inspect.isfunction(obj) or inspect.isclass(obj):
            assert obj.__doc__, f"{name}.{attr} has no docstring"
