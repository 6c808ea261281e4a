"""Area targets: schema and named errors, cutting, and the coverage report against references.

References are independent of :mod:`jaxspline.readers.areas`: the ground track's azimuth from
finite differences of the sub-satellite point (spherical bearing formula); coverage of
the cut strips by Monte Carlo points tested against every strip on the sphere; and the
covered fraction of a plan rebuilt with shapely from the *observations' geometry* (the
satellite position and the flown line of sight of each planned strip, intersected with
the ground, buffered by half the swath in an azimuthal equidistant projection).
"""

import json
import math

import jax
import numpy as np
import pytest
import shapely
from shapely.geometry import LineString, Polygon

from jaxspline.cli import main
from jaxspline.geometry.frames import (
    earth_rotation_angle,
    ecef_to_geodetic,
    geodetic_to_ecef,
    rot_z,
)
from jaxspline.geometry.orbit import orbit_position
from jaxspline.geometry.pointing import aim_geometry, aim_params
from jaxspline.geometry.routes import strip_direction
from jaxspline.planner.pipeline import orbit_scene, plan
from jaxspline.readers.area_files import read_geojson
from jaxspline.readers.areas import area_coverage, coverage_line
from jaxspline.readers.scenario import load_scenario

HEAD = """
[scenario]
name = "areas"
epoch = "2026-04-14T09:00:00Z"
duration_s = 1800.0

[[satellites]]
name = "eigen"
over = { lat_deg = 45.8, lon_deg = 14.0, t_s = 900.0, descending = true }
model = "eigen_axis"
rate_deg_s = 1.8
accel_deg_s2 = 0.4
settle_s = 2.0
off_nadir_max_deg = 30.0
swath_km = 10.0

[planner]
time_step_s = 5.0
geometry_step_s = 5.0
scan_speeds_km_s = [7.0]
time_limit_s = 10.0
"""
# a pentagon ~75 x 60 km over the Karst: one pass cannot take all its strips
RING = [[13.5, 45.5], [14.5, 45.55], [14.45, 46.1], [13.9, 46.0], [13.55, 46.05]]
AREA = (  # the cut-strip mode (the coverage mode: tests/readers/test_area_coverage.py)
    f'[[areas]]\nname = "karst"\nlonlat_deg = {json.dumps(RING)}\npriority = 20.0\n'
    'objective = "strips"\n'
)
R_TEST = 6371e3  # sphere of the reference projection [m]
COVERAGE_TOL = 0.01  # target: covered fraction to 1 %


def _write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _aeqd(lon_deg, lat_deg, lon0, lat0):
    """Spherical azimuthal equidistant projection about (lon0, lat0) [deg] -> metres."""
    la, lo = np.radians(lat_deg), np.radians(lon_deg)
    la0, lo0 = math.radians(lat0), math.radians(lon0)
    cos_c = np.sin(la0) * np.sin(la) + np.cos(la0) * np.cos(la) * np.cos(lo - lo0)
    c = np.arccos(np.clip(cos_c, -1.0, 1.0))
    k = np.where(c > 1e-12, c / np.sin(np.maximum(c, 1e-12)), 1.0)
    x = k * np.cos(la) * np.sin(lo - lo0)
    y = k * (np.cos(la0) * np.sin(la) - np.sin(la0) * np.cos(la) * np.cos(lo - lo0))
    return R_TEST * x, R_TEST * y


def _bearing(la1, lo1, la2, lo2):
    """Initial great-circle bearing from point 1 to point 2 [rad], clockwise from north."""
    dlo = lo2 - lo1
    y = np.sin(dlo) * np.cos(la2)
    x = np.cos(la1) * np.sin(la2) - np.sin(la1) * np.cos(la2) * np.cos(dlo)
    return np.arctan2(y, x)


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    d = tmp_path_factory.mktemp("areas")
    return load_scenario(_write(d, HEAD + AREA))


@pytest.fixture(scope="module")
def planned(scenario):
    # an iteration cap, not only a clock: the search would otherwise run its whole limit
    return plan(scenario, time_limit=10.0, seed=0, progress=False, max_iters=300)


# --- cutting ---


def test_area_becomes_strip_targets(scenario):
    (area,) = scenario.areas
    tg = scenario.targets
    assert len(tg) == area.targets.size > 1  # only the area's strips
    assert np.all(tg.kind[area.targets] == 1)
    assert area.passes.tolist() == [1] and area.azimuth.shape == (1,)
    np.testing.assert_allclose(area.share.sum(), 1.0, rtol=1e-12)
    np.testing.assert_allclose(tg.value[area.targets].sum(), 20.0, rtol=1e-12)
    assert area.swath == 10e3 and area.name == "karst"
    assert all(str(n).startswith("karst/d0/s") for n in tg.name)
    # every strip runs along the cutting direction (mod 180 deg: either way)
    diff = np.mod(tg.azimuth[area.targets] - area.azimuth[0] + np.pi / 2, np.pi) - np.pi / 2
    assert np.abs(np.degrees(diff)).max() < 1.0


def test_cutting_follows_the_ground_track(scenario):
    """Cutting azimuth vs the track's bearing from finite differences of the sub-satellite point."""
    table, scene = orbit_scene(scenario)
    t = np.array([895.0, 905.0])  # around the pass over the area (t_s = 900)
    r = np.asarray(orbit_position(table.orbit, t, sat=0))
    r_e = rot_z(earth_rotation_angle(float(scene.gmst0), t), r)
    lat = np.arctan2(r_e[:, 2], np.hypot(r_e[:, 0], r_e[:, 1]))  # geocentric is fine here
    lon = np.arctan2(r_e[:, 1], r_e[:, 0])
    track = _bearing(lat[0], lon[0], lat[1], lon[1])
    diff = np.mod(track - scenario.areas[0].azimuth[0] + np.pi / 2, np.pi) - np.pi / 2
    assert abs(math.degrees(diff)) < 0.1


def test_cut_strips_cover_the_polygon(scenario):
    """Monte Carlo: every point of the polygon lies within swath/2 of a strip, between its ends."""
    area = scenario.areas[0]
    tg = scenario.targets
    rng = np.random.default_rng(0)
    poly = Polygon(RING)
    lo0, la0, lo1, la1 = poly.bounds
    pts = np.column_stack([rng.uniform(lo0, lo1, 40000), rng.uniform(la0, la1, 40000)])
    pts = pts[shapely.contains_xy(poly, pts[:, 0], pts[:, 1])]
    p = geodetic_to_ecef(np.radians(pts[:, 1]), np.radians(pts[:, 0]))
    p = p / np.linalg.norm(p, axis=-1, keepdims=True)
    covered = np.zeros(len(p), bool)
    for r in area.targets:
        a = geodetic_to_ecef(tg.lat[r], tg.lon[r])
        a = a / np.linalg.norm(a)
        d = strip_direction(tg.lat[r], tg.lon[r], tg.azimuth[r])
        d = d - (d @ a) * a
        d = d / np.linalg.norm(d)
        pole = np.cross(a, d)  # the strip's great circle: points with p . pole = 0
        rad = np.linalg.norm(geodetic_to_ecef(tg.lat[r], tg.lon[r]))  # the strip's sphere
        cross = np.arcsin(np.clip(p @ pole, -1.0, 1.0)) * rad
        along = np.arctan2(p @ d, p @ a) * rad
        covered |= (np.abs(cross) <= area.swath / 2) & (along >= 0.0) & (along <= tg.length[r])
    assert len(p) > 30000 and covered.all(), covered.mean()


# --- coverage of a plan ---


def _footprints_from_observations(sc, res, area):
    """Shapely footprints rebuilt from the satellite and its line of sight (independent)."""
    tg = sc.targets
    table, scene = orbit_scene(sc)
    poly_ll = Polygon(RING)
    lon0, lat0 = poly_ll.centroid.x, poly_ll.centroid.y
    dense = shapely.segmentize(poly_ll, 0.01)
    xy = np.asarray(dense.exterior.coords)
    poly = Polygon(np.column_stack(_aeqd(xy[:, 0], xy[:, 1], lon0, lat0)))
    obs = res.observations
    feet = []
    for i in np.flatnonzero(np.isin(obs.target, area.targets)):
        r, k = int(obs.target[i]), int(obs.sat[i])
        g0 = geodetic_to_ecef(tg.lat[r], tg.lon[r], tg.alt[r])
        p = np.asarray(
            aim_params(g0, strip_direction(tg.lat[r], tg.lon[r], tg.azimuth[r]), obs.speed[i])
        )
        ts = np.linspace(obs.start[i], obs.end[i], 41)
        los = jax.vmap(aim_geometry, in_axes=(None, None, None, 0, None))(
            scene, p, obs.start[i], ts, k
        )[2]
        los = np.asarray(los)
        sat = np.asarray(orbit_position(table.orbit, ts, sat=k))
        rd = np.sum(sat * los, -1)  # ray sat + s los meets the sphere |g| = |g0| (near side)
        s = -rd - np.sqrt(rd * rd - (np.sum(sat * sat, -1) - g0 @ g0))
        g_eci = sat + s[:, None] * los
        ground = rot_z(earth_rotation_angle(float(scene.gmst0), ts), g_eci)
        lat, lon, _ = ecef_to_geodetic(np.asarray(ground))
        line = LineString(np.column_stack(_aeqd(np.degrees(lon), np.degrees(lat), lon0, lat0)))
        feet.append(line.buffer(sc.satellites[k].swath / 2, cap_style="flat"))
    return poly, feet


def test_coverage_matches_shapely_on_observed_footprints(scenario, planned):
    (area,) = scenario.areas
    (rep,) = area_coverage(planned)
    assert planned.report["valid"]
    n = int(np.isin(planned.observations.target, area.targets).sum())
    assert rep["strips_planned"] == n and rep["strips"] == area.targets.size
    assert 0 < n < area.targets.size  # a partial cover: the test means something
    poly, feet = _footprints_from_observations(scenario, planned, area)
    ref = shapely.union_all(feet).intersection(poly).area / poly.area
    assert abs(rep["covered_fraction"] - ref) < COVERAGE_TOL, (rep["covered_fraction"], ref)
    assert abs(rep["area_km2"] - poly.area / 1e6) < 0.01 * rep["area_km2"]
    np.testing.assert_allclose(
        rep["value_planned"], planned.value, rtol=1e-12
    )  # only area strips here
    assert "karst" in coverage_line([rep]) and "strips" in coverage_line([rep])


def test_plan_command_reports_coverage_and_czml(tmp_path, capsys):
    scen = _write(tmp_path, HEAD + AREA)
    out = tmp_path / "out"
    quick = ["--time-limit", "60", "--max-iters", "50"]  # the join kernels compile here
    code = main(["plan", str(scen), "-o", str(out), "--no-plots", "--no-aem", "--quiet", *quick])
    assert code == 0
    doc = json.loads((out / "plan.json").read_text())
    (rep,) = doc["report"]["areas"]
    assert rep["area"] == "karst" and 0.0 <= rep["covered_fraction"] <= 1.0
    assert [a["name"] for a in doc["view"]["areas"]] == ["karst"]  # drawn by plan.html
    assert (out / "plan.html").stat().st_size > 0
    assert "areas         1 area covered: karst" in capsys.readouterr().out
    czml = json.loads((out / "plan.czml").read_text())
    ids = {p["id"] for p in czml}
    assert "area-0-0" in ids
    n_obs = len(doc["observations"])
    assert {f"footprint-{i}" for i in range(n_obs)} <= ids
    taken = [p for p in czml if p["id"].startswith("taken-")]
    assert len(taken) == n_obs  # every observation is an area strip here
    area_pkt = next(p for p in czml if p["id"] == "area-0-0")
    ring = np.reshape(area_pkt["polygon"]["positions"]["cartographicDegrees"], (-1, 3))
    np.testing.assert_allclose(ring[: len(RING), :2], RING)
    fp = next(p for p in czml if p["id"] == "footprint-0")["polygon"]["positions"]
    assert len(fp) == 8 and all("interval" in f for f in fp)  # grows while imaged


# --- files and errors ---


def test_geojson_files_relative_and_united(tmp_path):
    sq = [[13.6, 45.6], [13.8, 45.6], [13.8, 45.8], [13.6, 45.8], [13.6, 45.6]]
    sq2 = [[p[0] + 0.5, p[1]] for p in sq]
    fc = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "properties": {},
                "geometry": {"type": "Polygon", "coordinates": [sq]},
            },
            {
                "type": "Feature",
                "properties": {},
                "geometry": {"type": "Polygon", "coordinates": [sq2]},
            },
        ],
    }
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "two.geojson").write_text(json.dumps(fc))
    geom = read_geojson(tmp_path / "sub" / "two.geojson")
    assert geom.geom_type == "MultiPolygon" and geom.area == pytest.approx(0.08)
    sc = load_scenario(_write(tmp_path, HEAD + '[[areas]]\ngeojson = "sub/two.geojson"\n'))
    (area,) = sc.areas
    assert area.name == "area_1" and area.geometry["type"] == "MultiPolygon"
    assert area.swath == 10e3  # the satellite's swath_km
    np.testing.assert_allclose(area.share.sum(), 1.0)
    with pytest.raises(FileNotFoundError):
        read_geojson(tmp_path / "missing.geojson")


BAD = [
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\nfoo = 1\n",
        "areas[0].foo",
        "unknown key",
    ),
    ("[[areas]]\npriority = 2.0\n", "areas[0].geojson", "exactly one of"),
    (
        '[[areas]]\ngeojson = "a.geojson"\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\n',
        "areas[0].geojson",
        "exactly one of",
    ),
    ('[[areas]]\ngeojson = "nope.geojson"\n', "areas[0].geojson", "not found"),
    ("[[areas]]\nlonlat_deg = [[13, 45], [14, 45]]\n", "areas[0].lonlat_deg", ">= 3"),
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 46], [14, 45], [13, 46]]\n",
        "areas[0].lonlat_deg",
        "Self-intersection",
    ),
    ("[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 95]]\n", "areas[0].lonlat_deg", "within"),
    ("[[areas]]\nlonlat_deg = [[0, 0], [30, 0], [30, 30]]\n", "areas[0].lonlat_deg", "too large"),
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\npriority = 0\n",
        "areas[0].priority",
        "must be within [1e-06, 1e+06], got 0",
    ),
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\nswath_km = -1\n",
        "areas[0].swath_km",
        "must be within [0.01, 5000], got -1",
    ),
    (
        '[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\nsensor = "radar"\n',
        "areas[0].swath_km",
        "no satellite has sensor",
    ),
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\nmax_length_km = 0\n",
        "areas[0].max_length_km",
        "must be within [1, 10000], got 0",
    ),
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\nwindow_s = [900, 100]\n",
        "areas[0].window_s",
        "lo <= hi",
    ),
    (
        '[[areas]]\nname = "a"\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\n'
        '[[areas]]\nname = "a"\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\n',
        "areas[1].name",
        "duplicate",
    ),
    (  # the grid from a tiny swath: the message says where the spacing came from
        '[[areas]]\nobjective = "coverage"\nswath_km = 0.01\n'
        "lonlat_deg = [[13, 45], [14, 45], [14, 46]]\n",
        "areas[0].grid_km",
        "0.00333333 km (0.333 x the 0.01 km swath: grid_km not given) is too fine",
    ),
]


@pytest.mark.parametrize(("text", "field", "why"), BAD)
def test_bad_areas_name_the_field(tmp_path, text, field, why):
    (tmp_path / "a.geojson").write_text('{"type": "Point", "coordinates": [13, 45]}')
    with pytest.raises(ValueError, match=r"\(line \d+\)") as exc:
        load_scenario(_write(tmp_path, HEAD + text))
    msg = str(exc.value)
    assert f": {field} (line" in msg and why in msg, msg


def test_bad_geojson_content_is_named(tmp_path):
    (tmp_path / "p.geojson").write_text('{"type": "Point", "coordinates": [13, 45]}')
    (tmp_path / "bad.geojson").write_text("{not json")
    ring = "[[[13.6, 45.6], [14.0, 45.6], [14.0, 45.85], [13.6, 45.6]]]"
    # GeoJSON types are case-sensitive, and a Feature's geometry is not a Feature
    (tmp_path / "lower.geojson").write_text(f'{{"type": "polygon", "coordinates": {ring}}}')
    inner = f'{{"type": "Feature", "geometry": {{"type": "Polygon", "coordinates": {ring}}}}}'
    (tmp_path / "nested.geojson").write_text(f'{{"type": "Feature", "geometry": {inner}}}')
    for name, why in (
        ("p.geojson", "is not an area"),
        ("bad.geojson", "invalid JSON"),
        ("lower.geojson", "type 'polygon' is not an area"),
        ("nested.geojson", "type 'Feature' is not an area"),
    ):
        with pytest.raises(ValueError, match=why) as exc:
            load_scenario(_write(tmp_path, HEAD + f'[[areas]]\ngeojson = "{name}"\n'))
        assert "areas[0].geojson" in str(exc.value)


def test_area_without_pass_and_without_targets_is_an_error(tmp_path):
    far = "[[areas]]\nlonlat_deg = [[-100, -30], [-99, -30], [-99, -29]]\n"  # never overflown
    with pytest.raises(ValueError, match="no targets"):
        load_scenario(_write(tmp_path, HEAD + far))
    sc = load_scenario(_write(tmp_path, HEAD + far + AREA))
    assert [a.targets.size for a in sc.areas][0] == 0 and sc.areas[0].passes.size == 0


@pytest.mark.parametrize(
    ("axes_deg", "want"),
    [
        ([10.0, 12.0, 100.0], [(11.0, 2), (100.0, 1)]),
        ([179.0, 1.0, 2.0], [(0.667, 3)]),  # axes wrap at 180 deg
        ([190.0, 10.0], [(10.0, 2)]),  # a track and its reverse share a cutting
        ([], []),
    ],
)
def test_passes_group_into_cuttings(axes_deg, want):
    from jaxspline.readers.areas import _cuttings

    got = _cuttings(np.radians(axes_deg))
    assert [c for _, c in got] == [c for _, c in want]
    for (az, _), (az_want, _) in zip(got, want, strict=True):
        d = (math.degrees(az) - az_want + 90.0) % 180.0 - 90.0
        assert abs(d) < 1e-3 and 0.0 <= az < math.pi


def test_example_scenario_file():
    from jaxspline.readers.scenario import DEFAULT_SCENARIO_PATH

    sc = load_scenario(DEFAULT_SCENARIO_PATH.parent / "areas_example.toml")
    assert [a.name for a in sc.areas] == ["central-slovenia", "karst"]
    tg = sc.targets
    assert list(tg.name[:2]) == ["Ljubljana", "Trieste"]
    assert (tg.mid_lo[0], tg.mid_hi[0], tg.min_duration[1], tg.duration[1]) == (
        11300.0,
        11360.0,
        20.0,
        20.0,
    )
    for a in sc.areas:
        assert a.passes.tolist() == [1, 1] and a.swath == 12e3  # a descending, an ascending pass
        assert a.objective == "coverage" and set(a.cutting.tolist()) == {0, 1}
        # marginal gains: together worth what they cover, never more than the priority
        total = tg.value[a.targets].sum()
        np.testing.assert_allclose(total, a.value * a.share.sum(), rtol=1e-12)
        assert a.value * 0.99 <= total <= a.value * (1 + 1e-12) and a.union == pytest.approx(1.0)
        assert np.all(tg.length[a.targets] <= (20e3 if a.name == "karst" else np.inf) + 1e-6)
