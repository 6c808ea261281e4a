"""Areas planned by unique coverage (``objective = "coverage"``, jaxspline.readers.coverage_strips).

* the lazy (CELF) greedy takes the same sets with the same gains as the plain greedy
  (brute force over every set at every step), on random instances;
* the grid's weights are the sphere's area shares: their sum times the polygon's area
  matches shapely's area of the polygon in an equal-area projection, and the samples lie
  inside the polygon;
* the chosen strips' values never count ground twice: on the ground (great-circle
  geometry, :func:`covered_samples`) the chosen strips cover at least the sum of their
  marginal gains, and :func:`covered_samples` agrees with shapely polygons of the
  strips' footprints (an independent point-in-polygon test);
* a plan of a coverage area is valid (the independent plan check), its report's covered
  fraction equals the covered weight recomputed with shapely footprints, plan.csv and
  plan.html carry it;
* the new keys' errors name the field.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import shapely
from jaxspline.readers.coverage_strips import area_grid, covered_samples, lazy_greedy
from shapely.geometry import Polygon
from test_areas import HEAD, RING, _write  # same folder

from jaxspline.geometry.ground import equal_area, strip_footprint, surface_point
from jaxspline.readers.area_files import polygon_center
from jaxspline.readers.scenario import load_scenario

COVER = (
    f'[[areas]]\nname = "karst"\nlonlat_deg = {json.dumps(RING)}\npriority = 20.0\ngrid_km = 3.0\n'
)


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    return load_scenario(_write(tmp_path_factory.mktemp("cover"), HEAD + COVER))


def _plain_greedy(members, weight, min_gain):
    covered = np.zeros(weight.size, bool)
    order, gains = [], []
    while True:
        g = [weight[m[~covered[m]]].sum() for m in members]
        i = int(np.argmax(g))
        if g[i] < min_gain:
            return order, gains
        covered[members[i]] = True
        order.append(i)
        gains.append(g[i])


@pytest.mark.parametrize("seed", range(5))
def test_lazy_greedy_equals_plain_greedy(seed):
    rng = np.random.default_rng(seed)
    n = 60
    w = rng.random(n)
    members = [rng.choice(n, rng.integers(1, 15), replace=False) for _ in range(25)]
    order, gains = lazy_greedy(members, w, 1e-9)
    want_o, want_g = _plain_greedy(members, w, 1e-9)
    assert order.tolist() == want_o
    np.testing.assert_allclose(gains, want_g, rtol=1e-12)
    assert np.all(np.diff(gains) <= 1e-12)


def _equal_area_poly(geom, center):
    radius = float(np.linalg.norm(surface_point(center)))
    from jaxspline.base.elements import geodetic_to_ecef, unit_vectors

    def f(xy):
        u = unit_vectors(geodetic_to_ecef(np.radians(xy[:, 1]), np.radians(xy[:, 0]), 0.0))
        return radius * equal_area(u, center)

    return shapely.transform(shapely.segmentize(geom, 0.01), f), f


def test_grid_weights_are_area_shares():
    poly = Polygon(RING)
    center = polygon_center(poly)
    grid = area_grid(poly, center, 2000.0)
    assert grid.weight.sum() == pytest.approx(1.0)
    assert shapely.contains_xy(poly, grid.lon_deg, grid.lat_deg).mean() > 0.99
    ea, _ = _equal_area_poly(poly, center)
    cell = 2000.0**2  # each sample stands for one plane cell; weight = its sphere share
    n_equiv = ea.area / cell
    assert abs(grid.weight.size - n_equiv) < 0.03 * n_equiv  # grid count ~ area / cell


def _shapely_cover(tg, idx, swaths, lon, lat, center):
    """Samples inside the union of the strips' footprint polygons (equal-area plane)."""
    _, f = _equal_area_poly(Polygon(RING), center)
    radius = float(np.linalg.norm(surface_point(center)))
    feet = []
    for r, sw in zip(idx, swaths, strict=True):
        ring = strip_footprint(tg.lat[r], tg.lon[r], tg.azimuth[r], tg.length[r], sw, 200)
        feet.append(Polygon(radius * equal_area(ring, center)))
    pts = f(np.column_stack([lon, lat]))
    return shapely.contains_xy(shapely.union_all(feet), pts[:, 0], pts[:, 1])


def test_chosen_strips_cover_their_gains(scenario):
    (a,) = scenario.areas
    tg = scenario.targets
    assert a.objective == "coverage" and a.targets.size > 0 and a.candidates > a.targets.size
    lon, lat = a.sample_lonlat[:, 0], a.sample_lonlat[:, 1]
    from jaxspline.base.elements import geodetic_to_ecef, unit_vectors

    unit = unit_vectors(geodetic_to_ecef(np.radians(lat), np.radians(lon), 0.0))
    strips = np.stack([tg.lat, tg.lon, tg.azimuth, tg.length], -1)[a.targets]
    swaths = np.full(a.targets.size, a.swath)
    hit = covered_samples(unit, strips, swaths)
    assert a.sample_weight[hit].sum() >= a.share.sum() - 1e-9  # values never exceed coverage
    np.testing.assert_allclose(tg.value[a.targets], a.value * a.share, rtol=1e-12)
    ref = _shapely_cover(tg, a.targets, swaths, lon, lat, polygon_center(Polygon(RING)))
    assert np.mean(hit != ref) < 0.002, np.mean(hit != ref)  # only samples on an edge
    # subsets: the marginal values of ANY subset are at most its covered share
    rng = np.random.default_rng(0)
    for _ in range(5):
        m = rng.random(a.targets.size) < 0.5
        sub = covered_samples(unit, strips[m], swaths[m])
        assert a.share[m].sum() <= a.sample_weight[sub].sum() + 1e-9


@pytest.fixture(scope="module")
def plan_files(tmp_path_factory):
    from jaxspline.cli import main

    d = tmp_path_factory.mktemp("cover_plan")
    scen = _write(d, HEAD + COVER)
    out = d / "out"
    quick = ["--time-limit", "60", "--max-iters", "50", "--no-aem"]
    assert main(["plan", str(scen), "-o", str(out), "--no-plots", "--quiet", *quick]) == 0
    return load_scenario(scen), out


def test_plan_reports_covered_fraction(plan_files):
    sc, out = plan_files
    doc = json.loads((out / "plan.json").read_text())
    assert doc["report"]["valid"]
    (rep,) = doc["report"]["areas"]
    assert rep["objective"] == "coverage" and 0.0 < rep["covered_fraction"] <= rep["bound"]
    (a,) = sc.areas
    assert rep["samples"] == a.sample_weight.size and 0 < rep["samples_covered"]
    # independent: shapely footprints of the planned strips over the grid, satellite swath
    names = [o["target"] for o in doc["observations"]]
    idx = np.array([int(np.flatnonzero(sc.targets.name == n)[0]) for n in names])
    swaths = np.full(idx.size, sc.satellites[0].swath)
    lon, lat = a.sample_lonlat[:, 0], a.sample_lonlat[:, 1]
    ref = _shapely_cover(sc.targets, idx, swaths, lon, lat, polygon_center(Polygon(RING)))
    assert abs(rep["covered_fraction"] - a.sample_weight[ref].sum()) < 0.005
    rows = list(csv.DictReader((out / "plan.csv").open()))
    assert rows and {r["area"] for r in rows} == {"karst"}
    assert float(rows[0]["area_covered_fraction"]) == pytest.approx(rep["covered_fraction"], 1e-5)
    smp = doc["view"]["areas"][0]["samples"]
    assert sum(smp["covered"]) == rep["samples_covered"] and len(smp["lon_deg"]) == rep["samples"]
    assert b"area_samples_covered" in (out / "plan.html").read_bytes()


@pytest.mark.parametrize(
    ("text", "field", "why"),
    [
        ('objective = "tiles"\n', "areas[0].objective", "coverage, strips"),
        ("grid_km = 0\n", "areas[0].grid_km", ""),
        ("grid_km = 0.02\n", "areas[0].grid_km", "too fine"),
        ("objective = 3\n", "areas[0].objective", ""),
    ],
)
def test_bad_coverage_keys_name_the_field(tmp_path, text, field, why):
    ring = "[[areas]]\nlonlat_deg = [[13, 45], [14, 45], [14, 46]]\n"
    with pytest.raises(ValueError) as exc:
        load_scenario(_write(tmp_path, HEAD + ring + text))
    assert field in str(exc.value) and why in str(exc.value)
