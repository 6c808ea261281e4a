"""Area targets in scenario files: the schema, the target rows, the sample grid, named errors.

References: the values written in the files (rings, CSV rows, keys and their units),
shapely for the polygon geometry (union, centroid), and for the sample grid's weights
the exact area of a spherical cap over the polygon's area in an equal-area projection
written here (Lambert azimuthal, measured by shapely).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Polygon

from jaxspline.geometry.area_grid import area_grid
from jaxspline.geometry.routes import AREA
from jaxspline.readers.area_files import read_geojson, read_samples
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
fov_deg = 1.2
edge_off_nadir_deg = [5.0, 28.0]
strip_duration_s = [10.0, 60.0]
duty_s_per_orbit = 300.0

[[satellites]]
name = "pc"
over = { lat_deg = 45.8, lon_deg = 14.5, t_s = 1200.0 }
model = "per_channel"
off_nadir_max_deg = 40.0
sensor = "radar"
swath_km = 30.0

[planner]
time_step_s = 5.0
geometry_step_s = 5.0
max_actions = 12
area_roll_step_deg = 0.25
area_pitch_step_deg = 2.0
duty_margin_s = 1.5
"""
POINT = '[[targets]]\nname = "p"\nlat_deg = 45.9\nlon_deg = 14.1\npriority = 3.0\n'
RING = [[13.5, 45.5], [14.5, 45.55], [14.45, 46.1], [13.9, 46.0], [13.55, 46.05]]
TRI = "lonlat_deg = [[13, 45], [14, 45], [14, 46]]\n"


def _write(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _geodetic(lat_deg, lon_deg):
    """Unit vector of the WGS84 surface point at geodetic (lat, lon) [deg]."""
    f = 1.0 / 298.257223563
    e2 = f * (2.0 - f)
    la, lo = np.radians(lat_deg), np.radians(lon_deg)
    n = 1.0 / np.sqrt(1.0 - e2 * np.sin(la) ** 2)
    p = np.stack(
        [n * np.cos(la) * np.cos(lo), n * np.cos(la) * np.sin(lo), n * (1 - e2) * np.sin(la)], -1
    )
    return p / np.linalg.norm(p, axis=-1, keepdims=True)


# ----------------------------------------------------------------- what is read
def test_satellite_and_planner_area_keys(tmp_path):
    sc = load_scenario(_write(tmp_path, HEAD + POINT))
    eig, pc = sc.satellites
    assert eig.fov == pytest.approx(math.radians(1.2))
    assert eig.edge_band == pytest.approx((math.radians(5.0), math.radians(28.0)))
    assert tuple(eig.strip_duration) == (10.0, 60.0) and eig.duty == 300.0
    assert pc.fov is None and pc.edge_band is None and pc.duty is None  # not given: none
    pl = sc.planner
    assert pl.max_actions == 12 and pl.margins.duty == 1.5
    assert pl.area_roll_step == pytest.approx(math.radians(0.25))
    assert pl.area_pitch_step == pytest.approx(math.radians(2.0))
    sc2 = load_scenario(_write(tmp_path, HEAD.replace("area_pitch_step_deg = 2.0\n", "") + POINT))
    assert sc2.planner.area_pitch_step is None  # automatic


def test_areas_from_a_ring_a_geojson_file_and_a_sample_file(tmp_path):
    sq = [[13.6, 45.6], [13.8, 45.6], [13.8, 45.8], [13.6, 45.8], [13.6, 45.6]]
    sq2 = [[x + 0.5, y] for x, y in sq]
    fc = {
        "type": "FeatureCollection",
        "features": [
            {
                "type": "Feature",
                "properties": {},
                "geometry": {"type": "Polygon", "coordinates": [s]},
            }
            for s in (sq, sq2)
        ],
    }
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "two.geojson").write_text(json.dumps(fc))
    rows = [(14.0, 45.9, 0.25), (14.05, 45.9, 0.5), (14.1, 45.95, 0.125)]
    (tmp_path / "sub" / "s.csv").write_text(
        "lon_deg,lat_deg,weight\n" + "".join(f"{a},{b},{c}\n" for a, b, c in rows)
    )
    text = (
        HEAD
        + POINT
        + f'[[areas]]\nname = "ring"\nlonlat_deg = {json.dumps(RING)}\npriority = 20.0\n'
        + 'grid_km = 2.5\nwindow_s = [100.0, 900.0]\nmin_coverage = 0.4\nsensor = "radar"\n'
        + '[[areas]]\ngeojson = "sub/two.geojson"\n'
        + '[[areas]]\nname = "given"\nsamples_csv = "sub/s.csv"\npriority = 4.0\n'
    )
    sc = load_scenario(_write(tmp_path, text))
    tg = sc.targets
    assert len(tg) == 4 and [a.name for a in sc.areas] == ["ring", "area_2", "given"]
    ring, two, given = sc.areas
    assert [a.target for a in sc.areas] == [1, 2, 3]  # after the point target
    assert list(tg.kind) == [0, AREA, AREA, AREA] and AREA == 2
    assert list(tg.name[1:]) == ["ring", "area_2", "given"]
    np.testing.assert_array_equal(tg.value[1:], [20.0, 1.0, 4.0])  # priority (default 1)
    assert (tg.t_lo[1], tg.t_hi[1]) == (100.0, 900.0) and tg.sensor[1] == "radar"
    # the ring, closed; its spacing as given, its least share
    assert ring.geometry["type"] == "Polygon" and ring.geometry["coordinates"][0][:5] == RING
    assert ring.spacing == 2500.0 and ring.min_share == 0.4 and ring.samples.shape == (0, 3)
    # the GeoJSON file: relative to the scenario, its features united; the default grid is
    # a third of the narrowest swath of the satellites whose sensor the area accepts
    geom = shapely.geometry.shape(two.geometry)
    assert geom.geom_type == "MultiPolygon" and geom.area == pytest.approx(0.08)
    assert two.spacing == pytest.approx(10e3 / 3) and math.isnan(two.min_share)
    assert read_geojson(tmp_path / "sub" / "two.geojson").equals(geom)
    # the sample file: its rows as given, no polygon, no grid; its centre the samples'
    np.testing.assert_array_equal(given.samples, np.array(rows))
    assert given.geometry is None and given.spacing == 0.0
    w = np.array([r[2] for r in rows])
    assert math.degrees(tg.lon[3]) == pytest.approx(np.average([r[0] for r in rows], weights=w))
    assert math.degrees(tg.lat[3]) == pytest.approx(np.average([r[1] for r in rows], weights=w))
    # a radar-only area takes the radar satellite's swath: 30 km / 3
    only = text.replace("grid_km = 2.5\n", "")
    assert load_scenario(_write(tmp_path, only)).areas[0].spacing == pytest.approx(10e3)
    with pytest.raises(FileNotFoundError):
        read_geojson(tmp_path / "missing.geojson")


def test_a_file_of_areas_alone_needs_no_other_target(tmp_path):
    sc = load_scenario(_write(tmp_path, HEAD + "[[areas]]\n" + TRI))
    assert len(sc.targets) == 1 and sc.targets.kind[0] == AREA and sc.areas[0].target == 0


def test_a_polygon_area_target_is_at_its_centroid(tmp_path):
    sc = load_scenario(_write(tmp_path, HEAD + f"[[areas]]\nlonlat_deg = {json.dumps(RING)}\n"))
    c = Polygon(RING).centroid
    assert math.degrees(sc.targets.lon[0]) == pytest.approx(c.x, abs=1e-9)
    assert math.degrees(sc.targets.lat[0]) == pytest.approx(c.y, abs=1e-9)


def test_read_samples_rows_and_errors(tmp_path):
    p = tmp_path / "s.csv"
    p.write_text("weight,lat_deg,lon_deg,note\n0.5,45.0,13.0,a\n0.25,-10.5,-179.5,b\n")
    np.testing.assert_array_equal(read_samples(p), [[13.0, 45.0, 0.5], [-179.5, -10.5, 0.25]])
    for text, why in [
        ("lon_deg,lat_deg\n13,45\n", "missing column 'weight'"),
        ("lon_deg,lat_deg,weight\n13,45,0.5\n13,x,0.1\n", "s.csv row 3: lat_deg must be a number"),
        ("lon_deg,lat_deg,weight\n13,45,nan\n", "s.csv row 2: weight"),
        ("lon_deg,lat_deg,weight\n190,45,0.5\n", "row 2: lon_deg must be within [-180, 180]"),
        ("lon_deg,lat_deg,weight\n13,45,-0.5\n", "row 2: weight must be within [0, 1]"),
        ("lon_deg,lat_deg,weight\n13,45,0.7\n14,45,0.7\n", "the weights sum to 1.4, more than 1"),
        ("lon_deg,lat_deg,weight\n", "no samples"),
    ]:
        p.write_text(text)
        with pytest.raises(ValueError, match=None) as exc:
            read_samples(p)
        assert why in str(exc.value), (text, str(exc.value))
    with pytest.raises(OSError):
        read_samples(tmp_path / "none.csv")


# ----------------------------------------------------------------- the sample grid
def _laea_area(geom, lat0, lon0):
    """Area [m^2] of a (lon, lat) polygon on the sphere of radius R_M, by the Lambert
    azimuthal equal-area projection about (lat0, lon0) [deg] and shapely."""
    la0, lo0 = math.radians(lat0), math.radians(lon0)

    def proj(xy):
        lo, la = np.radians(xy[:, 0]), np.radians(xy[:, 1])
        c = np.sin(la0) * np.sin(la) + np.cos(la0) * np.cos(la) * np.cos(lo - lo0)
        k = np.sqrt(2.0 / (1.0 + c))
        x = k * np.cos(la) * np.sin(lo - lo0)
        y = k * (np.cos(la0) * np.sin(la) - np.sin(la0) * np.cos(la) * np.cos(lo - lo0))
        return R_M * np.stack([x, y], -1)

    return shapely.transform(shapely.segmentize(geom, 0.01), proj).area


R_M = 6371e3


def test_grid_weights_are_shares_of_the_sphere():
    """A 14 x 14 deg box: the summed weight of the samples within 4 deg of the centre
    equals the spherical cap's share of the box's area (0.1 %), where plain counting is
    off by the gnomonic plane's stretch (0.8 %)."""
    box = Polygon([(3.0, 38.0), (17.0, 38.0), (17.0, 52.0), (3.0, 52.0)])
    grid = area_grid(box, 6000.0)
    assert grid.weight.sum() == pytest.approx(1.0, abs=1e-12) and grid.spacing == 6000.0
    assert shapely.contains_xy(box, grid.lon_deg, grid.lat_deg).all()
    c = box.centroid
    u = _geodetic(grid.lat_deg, grid.lon_deg)
    u0 = _geodetic(c.y, c.x)
    # the cap about the direction of the grid's centre (the centroid's geodetic normal)
    ang = np.degrees(np.arccos(np.clip(u @ u0, -1.0, 1.0)))
    inside = ang < 4.0
    share = 2.0 * math.pi * R_M**2 * (1.0 - math.cos(math.radians(4.0)))
    # the box on the sphere: geodetic latitudes to geocentric directions first
    f = 1.0 / 298.257223563
    geo = shapely.transform(
        shapely.segmentize(box, 0.01),
        lambda xy: np.stack(
            [xy[:, 0], np.degrees(np.arctan((1 - f) ** 2 * np.tan(np.radians(xy[:, 1]))))], -1
        ),
    )
    lat0 = math.degrees(math.asin(u0[2]))
    want = share / _laea_area(geo, lat0, c.x)
    got = grid.weight[inside].sum()
    assert got == pytest.approx(want, rel=1e-3)
    assert abs(inside.mean() - want) > 4 * abs(got - want)  # plain counting is farther off
    n_cells = _laea_area(geo, lat0, c.x) / 6000.0**2
    assert grid.weight.size == pytest.approx(n_cells, rel=0.05)  # about one per cell


def test_a_sliver_gets_one_sample():
    thin = Polygon([(14.0, 45.0), (14.001, 45.0), (14.0, 45.001)])  # ~100 m
    grid = area_grid(thin, 5000.0)
    assert len(grid) == 1 and grid.weight[0] == 1.0
    assert shapely.contains_xy(thin.buffer(1e-6), grid.lon_deg, grid.lat_deg).all()
    with pytest.raises(ValueError, match="spacing"):
        area_grid(thin, 0.0)


# ----------------------------------------------------------------- named errors
BAD = [
    ("[[areas]]\n" + TRI + "swath_km = 3\n", "areas[0].swath_km", "is no longer read"),
    ("[[areas]]\n" + TRI + "max_length_km = 9\n", "areas[0].max_length_km", "is no longer read"),
    ("[[areas]]\n" + TRI + 'objective = "strips"\n', "areas[0].objective", "is no longer read"),
    ("[[areas]]\n" + TRI + "foo = 1\n", "areas[0].foo", "unknown key"),
    ("[[areas]]\npriority = 2.0\n", "areas[0].geojson", "exactly one of"),
    ('[[areas]]\ngeojson = "a.geojson"\n' + TRI, "areas[0].geojson", "exactly one of"),
    ('[[areas]]\ngeojson = "nope.geojson"\n', "areas[0].geojson", "not found"),
    ('[[areas]]\ngeojson = "a.geojson"\n', "areas[0].geojson", "is not an area"),
    ("[[areas]]\nlonlat_deg = [[13, 45], [14, 45]]\n", "areas[0].lonlat_deg", ">= 3"),
    (
        "[[areas]]\nlonlat_deg = [[13, 45], [14, 46], [14, 45], [13, 46]]\n",
        "areas[0].lonlat_deg",
        "Self-intersection",
    ),
    ("[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 95]]\n", "areas[0].lonlat_deg", "within"),
    ("[[areas]]\nlonlat_deg = [[0, 0], [30, 0], [30, 30]]\n", "areas[0].lonlat_deg", "too large"),
    ("[[areas]]\n" + TRI + "priority = 0\n", "areas[0].priority", "must be within [1e-06, 1e+06]"),
    ("[[areas]]\n" + TRI + 'sensor = "ir"\n', "areas[0].sensor", "no satellite has sensor 'ir'"),
    ("[[areas]]\n" + TRI + "window_s = [900, 100]\n", "areas[0].window_s", "lo <= hi"),
    ("[[areas]]\n" + TRI + "min_coverage = 1.5\n", "areas[0].min_coverage", "within [0, 1]"),
    ("[[areas]]\n" + TRI + "min_coverage = -0.1\n", "areas[0].min_coverage", "within [0, 1]"),
    ("[[areas]]\n" + TRI + "grid_km = 0\n", "areas[0].grid_km", "within [0.01, 1000]"),
    ("[[areas]]\n" + TRI + "grid_km = 0.05\n", "areas[0].grid_km", "0.05 km is too fine"),
    (
        '[[areas]]\nname = "a"\n' + TRI + '[[areas]]\nname = "a"\n' + TRI,
        "areas[1].name",
        "duplicate",
    ),
    ('[[areas]]\nsamples_csv = "bad.csv"\n', "areas[0].samples_csv", "bad.csv row 3: lat_deg"),
    ('[[areas]]\nsamples_csv = "no.csv"\n', "areas[0].samples_csv", "no.csv"),
]


@pytest.mark.parametrize(("text", "field", "why"), BAD)
def test_bad_areas_name_the_field_and_line(tmp_path, text, field, why):
    (tmp_path / "a.geojson").write_text('{"type": "Point", "coordinates": [13, 45]}')
    (tmp_path / "bad.csv").write_text("lon_deg,lat_deg,weight\n13,45,0.5\n13,x,0.1\n")
    with pytest.raises(ValueError, match=r"\(line \d+\)") as exc:
        load_scenario(_write(tmp_path, HEAD + text))
    msg = str(exc.value)
    assert f": {field} (line" in msg and why in msg, msg


SAT_BAD = [
    ("fov_deg = 1.2", "fov_deg = 0", "satellites[0].fov_deg", "must be within [0.001, 80]"),
    ("fov_deg = 1.2", "fov_deg = 95", "satellites[0].fov_deg", "must be within [0.001, 80]"),
    ("edge_off_nadir_deg = [5.0, 28.0]", "edge_off_nadir_deg = [28.0, 5.0]",
     "satellites[0].edge_off_nadir_deg", "lo <= hi"),
    ("edge_off_nadir_deg = [5.0, 28.0]", "edge_off_nadir_deg = [5.0, 35.0]",
     "satellites[0].edge_off_nadir_deg", "must be <= off_nadir_max_deg = 30"),
    ("strip_duration_s = [10.0, 60.0]", "strip_duration_s = [60.0, 10.0]",
     "satellites[0].strip_duration_s", "lo <= hi"),
    ("strip_duration_s = [10.0, 60.0]", "strip_duration_s = 30",
     "satellites[0].strip_duration_s", ""),
    ("duty_s_per_orbit = 300.0", "duty_s_per_orbit = 0",
     "satellites[0].duty_s_per_orbit", "must be within [0.01, 86400]"),
    ("max_actions = 12", "max_actions = 0", "planner.max_actions", ""),
    ("max_actions = 12", "max_actions = 2.5", "planner.max_actions", ""),
    ("area_roll_step_deg = 0.25", "area_roll_step_deg = 0", "planner.area_roll_step_deg", ""),
    ("area_pitch_step_deg = 2.0", "area_pitch_step_deg = 90", "planner.area_pitch_step_deg", ""),
    ("duty_margin_s = 1.5", "duty_margin_s = -1", "planner.duty_margin_s", ""),
]  # fmt: skip


@pytest.mark.parametrize(("old", "new", "field", "why"), SAT_BAD)
def test_bad_satellite_and_planner_area_keys_name_the_field(tmp_path, old, new, field, why):
    assert old in HEAD
    with pytest.raises(ValueError, match=r"\(line \d+\)") as exc:
        load_scenario(_write(tmp_path, HEAD.replace(old, new) + POINT))
    msg = str(exc.value)
    assert f": {field} (line" in msg and why in msg, msg


def test_bad_geojson_content_is_named(tmp_path):
    (tmp_path / "bad.geojson").write_text("{not json")
    ring = "[[[13.6, 45.6], [14.0, 45.6], [14.0, 45.85], [13.6, 45.6]]]"
    # GeoJSON types are case-sensitive, and a Feature's geometry is not a Feature
    (tmp_path / "lower.geojson").write_text(f'{{"type": "polygon", "coordinates": {ring}}}')
    inner = f'{{"type": "Feature", "geometry": {{"type": "Polygon", "coordinates": {ring}}}}}'
    (tmp_path / "nested.geojson").write_text(f'{{"type": "Feature", "geometry": {inner}}}')
    for name, why in (
        ("bad.geojson", "invalid JSON"),
        ("lower.geojson", "type 'polygon' is not an area"),
        ("nested.geojson", "type 'Feature' is not an area"),
    ):
        with pytest.raises(ValueError, match=why) as exc:
            load_scenario(_write(tmp_path, HEAD + f'[[areas]]\ngeojson = "{name}"\n'))
        assert "areas[0].geojson" in str(exc.value) and name in str(exc.value)


def test_example_scenario_file():
    from jaxspline.readers.scenario import DEFAULT_SCENARIO_PATH

    sc = load_scenario(DEFAULT_SCENARIO_PATH.parent / "areas_example.toml")
    assert [a.name for a in sc.areas] == ["central-slovenia", "karst"]
    tg = sc.targets
    assert list(tg.name) == ["Ljubljana", "Trieste", "central-slovenia", "karst"]
    assert list(tg.kind) == [0, 0, AREA, AREA] and [a.target for a in sc.areas] == [2, 3]
    np.testing.assert_array_equal(tg.value[2:], [30.0, 10.0])
    assert (tg.mid_lo[0], tg.mid_hi[0], tg.min_duration[1], tg.duration[1]) == (
        11300.0,
        11360.0,
        20.0,
        20.0,
    )
    for a in sc.areas:  # the default grid: a third of the narrowest swath (12 km)
        assert a.spacing == pytest.approx(4000.0) and a.samples.shape == (0, 3)
    assert shapely.geometry.shape(sc.areas[0].geometry).is_valid


def test_plan_command_refuses_a_retired_key_in_one_line(tmp_path, capsys):
    """`jaxspline plan` on a file with a retired area key: exit 2, one line naming the
    field, its line and what replaced it, nothing written."""
    from jaxspline.cli import main

    scen = _write(tmp_path, HEAD + "[[areas]]\n" + TRI + 'objective = "coverage"\n')
    out = tmp_path / "out"
    capsys.readouterr()
    assert main(["plan", str(scen), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    line = 1 + (HEAD + "[[areas]]\n" + TRI).count("\n")
    assert f"areas[0].objective (line {line}): is no longer read" in err, err
    assert "unique coverage" in err and not out.exists()
