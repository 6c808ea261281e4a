"""Stereo targets in scenario files: values as written, defaults, named errors, the example.

References: the numbers written in the files (degrees converted by hand here), the
stereo_imaging benchmark's thresholds and quality model (the ``[stereo]`` defaults), the
request type's own defaults. The shipped example is loaded whole and planned on a cut
(six cities, 12 h) through :func:`jaxspline.plan`: its report's products must be made of
the plan's looks.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

import jaxspline
from jaxspline.readers.mission import POINT, STEREO
from jaxspline.readers.satellites import tle_epoch
from jaxspline.readers.scenario import load_scenario, parse_scenario
from jaxspline.readers.stereo_files import STEREO_KEYS, TARGET_STEREO_KEYS, stereo_template
from jaxspline.readers.stereo_request import Stereo
from jaxspline.readers.targets import load_targets_csv

EXAMPLE = Path(jaxspline.__file__).parent / "data" / "stereo_example.toml"
TLE = [
    "1 40118U 14049A   26114.32389339  .00000172  00000+0  29228-4 0  9992",
    "2 40118  98.0137 178.5746 0008520  54.0613 306.1389 14.80833995631264",
]
HEAD = f"""[scenario]
epoch = "2026-04-24T00:00:00Z"
duration_h = 6.0

[[satellites]]
name = "gf2"
tle = ["{TLE[0]}",
       "{TLE[1]}"]
model = "roll_only"
rate_deg_s = 1.4
accel_deg_s2 = 0.65
off_nadir_max_deg = 30.0
ifov_deg = 6.5e-5
pixels = 12000
strip_duration_s = [2.0, 60.0]
"""
TABLE = """
[stereo]
product = "tri"
radius_m = 4000.0
min_overlap = 0.85
convergence_deg = [6.0, 40.0]
band_deg = [15.0, 25.0]
max_scale_ratio = 1.3
max_separation_s = 1800.0
cross_satellite = false
anchor_off_nadir_deg = 12.0
quality_weights = [0.6, 0.3, 0.1]
tri_bonus = 0.05
quality_weight = 0.25
"""
PARIS = """
[[targets]]
kind = "stereo"
name = "Paris"
lat_deg = 48.85
lon_deg = 2.35
alt_m = 35.0
priority = 4.0
window_s = [600.0, 20000.0]
sensor = "visible"
"""
OWN = 'product = "pair"\nradius_m = 7500.0\nband_deg = [10.0, 20.0]\ntri_bonus = 0.12\n'
POINT_TARGET = '\n[[targets]]\nname = "p"\nlat_deg = 45.0\nlon_deg = 14.0\n'


def _load(tmp_path, text, name="s.toml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return load_scenario(path)


def _rad(*deg):
    return tuple(math.radians(x) for x in deg)


def test_a_stereo_target_reads_as_written(tmp_path):
    sc = _load(tmp_path, HEAD + TABLE + PARIS + OWN + POINT_TARGET)
    tg = sc.targets
    assert tg.kind.tolist() == [STEREO, POINT] and len(sc.stereo) == 1
    assert (tg.lat[0], tg.lon[0], tg.alt[0]) == (math.radians(48.85), math.radians(2.35), 35.0)
    assert (tg.value[0], tg.t_lo[0], tg.t_hi[0], tg.sensor[0]) == (4.0, 600.0, 20000.0, "visible")
    assert (tg.duration[0], tg.length[0], tg.min_duration[0]) == (0.0, 0.0, 0.0)
    assert (tg.mid_lo[0], tg.mid_hi[0]) == (-np.inf, np.inf)
    assert sc.stereo[0] == Stereo(
        name="Paris", target=0, radius=7500.0, product="pair", min_overlap=0.85,
        convergence=_rad(6.0, 40.0), band=_rad(10.0, 20.0), max_scale_ratio=1.3,
        max_separation=1800.0, cross_satellite=False, anchor_off_nadir=math.radians(12.0),
        weights=(0.6, 0.3, 0.1), tri_bonus=0.12, quality_weight=0.25,
    )  # fmt: skip


def test_a_stereo_target_takes_the_tables_defaults(tmp_path):
    sc = _load(tmp_path, HEAD + TABLE + PARIS)
    s = sc.stereo[0]
    assert (s.product, s.radius, s.band, s.tri_bonus) == ("tri", 4000.0, _rad(15.0, 25.0), 0.05)
    assert s.value_share(0.6) == pytest.approx(0.75 + 0.25 * 0.6, rel=1e-15)


def test_without_a_table_the_benchmarks_thresholds():
    """No [stereo] table: the stereo_imaging benchmark's thresholds and quality model,
    its urban band, a 5 km disk and a 0.1 triple bonus (mission.yaml of the training
    cases: overlap 0.8, convergence 5-45 deg, scale ratio 1.5, 3600 s, anchor 10 deg,
    weights 0.5 / 0.35 / 0.15)."""
    sc = parse_scenario(tomllib.loads(HEAD + PARIS))
    s = sc.stereo[0]
    want = Stereo(
        name="Paris", target=0, radius=5000.0, product="pair", min_overlap=0.8,
        convergence=_rad(5.0, 45.0), band=_rad(8.0, 18.0), max_scale_ratio=1.5,
        max_separation=3600.0, cross_satellite=True, anchor_off_nadir=math.radians(10.0),
        weights=(0.5, 0.35, 0.15), tri_bonus=0.1, quality_weight=1.0,
    )  # fmt: skip
    assert s == want
    base = Stereo(name="", target=-1, radius=5000.0, tri_bonus=0.1)  # the type's defaults
    assert stereo_template() == base


def test_pixels_times_ifov_is_the_field_of_view(tmp_path):
    sat = _load(tmp_path, HEAD + PARIS).satellites[0]
    assert sat.ifov == math.radians(6.5e-5)
    assert sat.fov == pytest.approx(math.radians(12000 * 6.5e-5), rel=1e-15)
    both = HEAD.replace("pixels = 12000", "pixels = 12000\nfov_deg = 0.7805")  # 0.064 % off
    assert _load(tmp_path, both + PARIS).satellites[0].fov == math.radians(0.7805)
    alone = HEAD.replace("pixels = 12000", "fov_deg = 1.5")  # fov_deg and ifov_deg
    s = _load(tmp_path, alone + PARIS).satellites[0]
    assert (s.fov, s.ifov) == (math.radians(1.5), math.radians(6.5e-5))


def test_csv_stereo_rows(tmp_path):
    (tmp_path / "t.csv").write_text(
        "name,lat_deg,lon_deg,priority,kind,product,radius_m,band_lo_deg,band_hi_deg,tri_bonus\n"
        "Lima,-12.0464,-77.0428,3,stereo,tri,6000,10,20,0.1\n"
        "Quito,-0.1807,-78.4678,2,stereo,,,,,\n"
        "Cusco,-13.53,-71.97,1,point,,,,,\n",
        encoding="utf-8",
    )
    sc = _load(tmp_path, 'targets_csv = "t.csv"\n' + HEAD + TABLE)
    assert sc.targets.kind.tolist() == [STEREO, STEREO, POINT]
    lima, quito = sc.stereo
    assert (lima.name, lima.target, lima.product, lima.radius) == ("Lima", 0, "tri", 6000.0)
    assert (lima.band, lima.tri_bonus) == (_rad(10.0, 20.0), 0.1)
    want = (1, "tri", 4000.0, _rad(15.0, 25.0))  # the [stereo] table's
    assert (quito.target, quito.product, quito.radius, quito.band) == want
    assert load_targets_csv(tmp_path / "t.csv").kind.tolist() == [STEREO, STEREO, POINT]


def _line(text: str, field: str, key: str) -> int:
    """The 1-based line of ``text`` where ``key =`` is set in the section ``field`` names."""
    section = field.split(".")[0].split("[")[0]
    header = f"[{section}]" if section == "stereo" else f"[[{section}]]"
    lines = text.splitlines()
    start = lines.index(header)
    return next(i + 1 for i in range(start, len(lines)) if lines[i].startswith(f"{key} ="))


BAD = [  # (replaced, by, field named, key of the line, fragment of the message)
    ("min_overlap = 0.85", "min_overlap = 0.0", "stereo.min_overlap", "min_overlap",
     "must be within [0.01, 1], got 0.0"),
    ("convergence_deg = [6.0, 40.0]", "convergence_deg = [6.0, 95.0]",
     "stereo.convergence_deg", "convergence_deg", "must be within [0, 90], got 95.0"),
    ("band_deg = [15.0, 25.0]", "band_deg = [2.0, 25.0]", "stereo.band_deg", "band_deg",
     "must lie within convergence_deg [6, 40]"),
    ("quality_weights = [0.6, 0.3, 0.1]", "quality_weights = [0.6, 0.3]",
     "stereo.quality_weights", "quality_weights", "must be a list [geometry, overlap"),
    ("quality_weights = [0.6, 0.3, 0.1]", "quality_weights = [0.6, 0.3, 0.3]",
     "stereo.quality_weights", "quality_weights", "must sum to 1"),
    ('product = "tri"', 'product = "quad"', "stereo.product", "product", "'quad'"),
    ("cross_satellite = false", 'cross_satellite = "no"', "stereo.cross_satellite",
     "cross_satellite", "must be true or false"),
    ("tri_bonus = 0.05", "tri_bonus = 5.0", "stereo.tri_bonus", "tri_bonus",
     "must be within [0, 1], got 5.0"),
    ("quality_weight = 0.25", "quality_weight = 1.5", "stereo.quality_weight",
     "quality_weight", "got 1.5"),
    ("max_separation_s = 1800.0", "max_separation_s = -1.0", "stereo.max_separation_s",
     "max_separation_s", "got -1.0"),
    ("max_scale_ratio = 1.3", "max_scale_ratio = 0.9", "stereo.max_scale_ratio",
     "max_scale_ratio", "must be within [1, 100]"),
    ("anchor_off_nadir_deg = 12.0", "anchor_deg = 12.0", "stereo.anchor_deg", "anchor_deg",
     "unknown key"),
    ('sensor = "visible"', 'sensor = "visible"\nradius_m = 5.0', "targets[0].radius_m",
     "radius_m", "must be within [10, 100000], got 5.0"),
    ('sensor = "visible"', 'sensor = "visible"\nband_deg = [1.0, 20.0]', "targets[0].band_deg",
     "band_deg", "must lie within the [stereo] table's convergence_deg [6, 40]"),
    ('sensor = "visible"', 'sensor = "visible"\nband_deg = [20.0, 10.0]',
     "targets[0].band_deg", "band_deg", "lo <= hi"),
    ('sensor = "visible"', 'sensor = "visible"\nband_deg = 12.0', "targets[0].band_deg",
     "band_deg", "must be a list [lo, hi]"),
    ('sensor = "visible"', 'sensor = "visible"\nproduct = "triple"', "targets[0].product",
     "product", "must be 'pair' or 'tri'"),
    ('sensor = "visible"', 'sensor = "visible"\nduration_s = 10.0', "targets[0].duration_s",
     "duration_s", "a stereo target takes no duration_s"),
    ('sensor = "visible"', 'sensor = "visible"\ndesired_s = 900.0', "targets[0].desired_s",
     "desired_s", "use window_s"),
    ('sensor = "visible"', 'sensor = "visible"\nlength_km = 10.0', "targets[0].length_km",
     "length_km", "a stereo target takes no length_km"),
    ('kind = "stereo"', 'kind = "point"\nproduct = "tri"', "targets[0].product", "product",
     "only a stereo target (kind 'stereo') takes it, not a point"),
    ('kind = "stereo"', 'kind = "pair"', "targets[0].kind", "kind", "or 'stereo'"),
    ("pixels = 12000", "pixels = 12000.5", "satellites[0].pixels", "pixels",
     "must be an integer"),
    ("pixels = 12000", "pixels = 12000\nfov_deg = 0.9", "satellites[0].fov_deg", "fov_deg",
     "0.9 deg disagrees with pixels x ifov_deg = 12000 x 6.5e-05 = 0.78 deg"),
    ("ifov_deg = 6.5e-5", "ifov_deg = 2.0", "satellites[0].ifov_deg", "ifov_deg",
     "must be within [1e-07, 1], got 2.0"),
    ("ifov_deg = 6.5e-5\n", "", "satellites[0].pixels", "pixels", "needs ifov_deg"),
    ("pixels = 12000", "pixels = 1", "satellites[0].pixels", "pixels",
     "= 6.5e-05 deg, the field of view, must be within [0.001, 80]"),
    ("ifov_deg = 6.5e-5\npixels = 12000", "ifov_deg = 0.02\nfov_deg = 0.01",
     "satellites[0].ifov_deg", "ifov_deg", "must be <= the field of view"),
]  # fmt: skip


@pytest.mark.parametrize(("old", "new", "field", "key", "why"), BAD)
def test_bad_values_are_refused_by_name_and_line(tmp_path, old, new, field, key, why):
    good = HEAD + TABLE + PARIS
    assert good.count(old) == 1, old
    text = good.replace(old, new)
    with pytest.raises(ValueError) as exc:
        _load(tmp_path, text)
    msg = str(exc.value)
    where = f"{field} (line {_line(text, field, key)})"
    assert msg.startswith(f"{tmp_path / 's.toml'}: {where}: "), msg
    assert why in msg, msg


@pytest.mark.parametrize(
    ("cells", "column", "why"),
    [
        ("stereo,,,10,,", "band_hi_deg", "give both band_lo_deg and band_hi_deg"),
        ("stereo,,,,20,", "band_lo_deg", "give both"),
        ("stereo,,,30,50,", "band_lo_deg", "must lie within"),
        ("stereo,,5,,,", "radius_m", "must be within [10, 100000], got '5'"),
        ("stereo,quad,,,,", "product", "'quad'"),
        ("stereo,,,,,-0.1", "tri_bonus", "must be within [0, 1]"),
        ("point,,,,,0.1", "tri_bonus", "only a stereo target"),
        ("strip,pair,,,,", "product", "only a stereo target"),
    ],
)
def test_bad_csv_cells_are_refused_by_row_and_column(tmp_path, cells, column, why):
    path = tmp_path / "t.csv"
    path.write_text(
        "name,lat_deg,lon_deg,priority,kind,product,radius_m,band_lo_deg,band_hi_deg,tri_bonus\n"
        "ok,1,2,1,stereo,,,,,\n"
        f"bad,1,3,1,{cells}\n",
        encoding="utf-8",
    )
    with pytest.raises(ValueError) as exc:
        load_targets_csv(path)
    msg = str(exc.value)
    assert msg.startswith(f"t.csv row 3, column {column!r}: "), msg
    assert why in msg, msg


def test_the_schema_docstring_names_every_key():
    import jaxspline.readers.scenario as schema

    doc = schema.__doc__
    assert "\n    [stereo] " in doc and '"strip" or "stereo"' in doc
    for key in sorted(STEREO_KEYS | set(TARGET_STEREO_KEYS) | {"ifov_deg", "pixels"}):
        assert f"\n    {key} = " in doc, key


# --- the shipped example ---


@pytest.fixture(scope="module")
def example():
    return load_scenario(EXAMPLE)


def test_the_example_loads(example):
    sc = example
    assert sc.duration == 86400.0 and len(sc.satellites) == 4
    assert len(sc.targets) == len(sc.stereo) == 30
    assert set(sc.targets.kind.tolist()) == {STEREO}
    products = [s.product for s in sc.stereo]
    assert products.count("tri") >= 5 and products.count("pair") >= 5
    for s in sc.satellites:
        assert s.model == "roll_only" and s.ifov is not None
        assert s.strip_duration == (2.0, 60.0)
        # fresh TLEs: at most two days from the horizon's start
        assert abs((tle_epoch(s.orbit[0]) - sc.epoch).total_seconds()) < 2 * 86400
    wv3 = sc.satellites[0]
    assert wv3.fov == pytest.approx(math.radians(30000 * 3.5e-5), rel=1e-15)
    pl = sc.planner
    assert (pl.time_step, pl.geometry_step) == (1.0, 1.0)
    assert pl.sun_elevation_min == math.radians(10.0)
    assert _names(EXAMPLE) == list(sc.targets.name)


def _names(path) -> list[str]:
    """The target names as the file lists them."""
    return [t["name"] for t in tomllib.loads(path.read_text(encoding="utf-8"))["targets"]]


CUT = ("London", "Rome", "Cairo", "Bangkok", "Beijing", "Tokyo")


def test_a_cut_of_the_example_plans_its_products():
    """Six cities (three triples asked for) over 12 h: every product the report names is
    made of the plan's looks of its target, and the looks' values add up to the plan's."""
    data = tomllib.loads(EXAMPLE.read_text(encoding="utf-8"))
    data["targets"] = [t for t in data["targets"] if t["name"] in CUT]
    data["scenario"]["duration_h"] = 12.0
    sc = parse_scenario(data)
    r = jaxspline.plan(sc, time_limit=20, progress=False)
    assert r.report["valid"], r.report["violations"]
    rows = r.report["stereo"]
    assert [row["target"] for row in rows] == list(sc.targets.name)
    got = [row for row in rows if row["product"]]
    assert len(got) >= 4 and any(row["product"] == "tri" for row in got)
    o = r.observations
    size = {"pair": 2, "tri": 3}
    for row in rows:
        k = list(sc.targets.name).index(row["target"])
        mine = o.target == k
        if not row["product"]:
            assert o.value[mine].sum() == 0.0
            continue
        req = sc.stereo[k]
        assert mine.sum() >= size[row["product"]] == len(row["looks"])
        assert row["product"] == "pair" or req.product == "tri"
        assert o.value[mine].sum() == pytest.approx(row["value"], rel=1e-12)
        conv = math.radians(row["convergence_deg"])
        assert req.convergence[0] <= conv <= req.convergence[1]
        assert row["overlap"] >= req.min_overlap and row["scale_ratio"] <= req.max_scale_ratio
        # the looks see the city from different angles along the track, each held fixed
        assert np.ptp(o.pitch[mine]) > 0.0 and np.all(np.isfinite(o.roll[mine]))
        dur = o.end[mine] - o.start[mine]
        assert np.all((dur >= 2.0 - 1e-9) & (dur <= 60.0 + 1e-9))
    assert r.value == pytest.approx(sum(row["value"] for row in got), rel=1e-9)
    assert r.value <= r.bound * (1 + 1e-9)


def test_per_channel_satellites_plan_stereo_targets():
    """The same cut with per-channel satellites (no rest-to-rest slew law): a valid plan
    whose products are made of the plan's looks."""
    data = tomllib.loads(EXAMPLE.read_text(encoding="utf-8"))
    data["targets"] = [t for t in data["targets"] if t["name"] in CUT]
    data["scenario"]["duration_h"] = 12.0
    for s in data["satellites"]:
        s["model"] = "per_channel"
    sc = parse_scenario(data)
    r = jaxspline.plan(sc, time_limit=20, progress=False)
    assert r.report["valid"], r.report["violations"]
    got = [row for row in r.report["stereo"] if row["product"]]
    assert got
    for row in got:
        k = list(sc.targets.name).index(row["target"])
        assert int(np.sum(r.observations.target == k)) >= len(row["looks"])
