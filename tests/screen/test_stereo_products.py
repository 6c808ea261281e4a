"""Stereo products: the lattice overlap against exact areas, the quality formula, selection."""

from __future__ import annotations

import math

import numpy as np
import pytest
from shapely.geometry import LineString, Point

from jaxspline.readers.stereo_request import Stereo
from jaxspline.screen.stereo_products import (
    OVERLAP_POINTS,
    disk_points,
    pair_quality,
    pass_probability,
    select_products,
    strip_masks,
)

#: Largest error of the lattice overlap against the exact area share.
LATTICE_TOL = 0.015
#: Buffer segments per quarter circle of the exact capsules (area error < 1e-5).
QUAD_SEGS = 256


def _capsule(track: np.ndarray, h: float):
    pts = np.unique(track, axis=0)
    geom = Point(pts[0]) if len(pts) == 1 else LineString(track)
    return geom.buffer(h, quad_segs=QUAD_SEGS)


def _random_strip(rng, radius: float):
    """A strip crossing near the disk: a polyline of 2-9 vertices (some repeated) along a
    random direction, offset across it, a half-width between 0.4 and 1.4 radii."""
    k = int(rng.integers(2, 10))
    theta = rng.uniform(0, math.pi)
    u = np.array([math.cos(theta), math.sin(theta)])
    v = np.array([-u[1], u[0]])
    s = np.sort(rng.uniform(-1.6, 1.6, k)) * radius
    s[-1] = s[-2] if rng.random() < 0.3 else s[-1]  # a repeated end point, as the tracks pad
    bend = rng.normal(0, 0.02, k) * radius
    track = s[:, None] * u + (bend + rng.uniform(-0.4, 0.4) * radius)[:, None] * v
    return track, rng.uniform(0.4, 1.4) * radius


def _padded(*tracks) -> np.ndarray:
    """Polylines [n, K, 2], each padded by repeating its last point (as look tracks are)."""
    k = max(len(t) for t in tracks)
    return np.stack([np.concatenate([t, np.repeat(t[-1:], k - len(t), 0)]) for t in tracks])


def test_lattice_overlap_matches_exact_areas():
    rng = np.random.default_rng(3)
    radius = 5000.0
    pts = disk_points(radius)
    disk = Point(0, 0).buffer(radius, quad_segs=QUAD_SEGS)
    errors = []
    for _ in range(60):
        (ta, ha), (tb, hb) = _random_strip(rng, radius), _random_strip(rng, radius)
        m = strip_masks(_padded(ta, tb), np.array([ha, hb]), pts)
        lattice = float(np.mean(m[0] & m[1]))
        exact = disk.intersection(_capsule(ta, ha)).intersection(_capsule(tb, hb)).area
        errors.append(lattice - exact / disk.area)
    errors = np.abs(errors)
    assert errors.max() < LATTICE_TOL, errors.max()
    assert errors.mean() < LATTICE_TOL / 3


def test_strip_masks_match_point_distances():
    rng = np.random.default_rng(4)
    pts = rng.uniform(-6000, 6000, (300, 2))
    track, h = _random_strip(rng, 5000.0)
    m = strip_masks(track[None], np.array([h]), pts)[0]
    line = LineString(track)
    ref = np.array([line.distance(Point(p)) <= h for p in pts])
    np.testing.assert_array_equal(m, ref)


def test_disk_points_fill_the_disk_evenly():
    pts = disk_points(1000.0)
    assert pts.shape == (OVERLAP_POINTS, 2)
    r = np.hypot(pts[:, 0], pts[:, 1])
    assert r.max() < 1000.0
    # equal areas: the share of points within radius rho is (rho / R)^2
    for rho in (250.0, 500.0, 750.0):
        assert abs(np.mean(r <= rho) - (rho / 1000.0) ** 2) <= 1.5 / OVERLAP_POINTS
    # quadrants hold a quarter each
    q = np.mean((pts[:, 0] > 0) & (pts[:, 1] > 0))
    assert abs(q - 0.25) < 0.01


REQ = Stereo("t", 0, 5000.0, band=(math.radians(8.0), math.radians(18.0)))


@pytest.mark.parametrize(
    "conv_deg, overlap, ratio, expected",
    [
        (12.0, 0.95, 1.0, 1.0),  # in band, full overlap term, equal scales
        (8.0, 1.0, 1.0, 1.0),  # band edge included
        (20.0, 0.95, 1.0, 0.5 * 0.8 + 0.35 + 0.15),  # 2 deg past the band
        (40.0, 0.95, 1.0, 0.35 + 0.15),  # 22 deg past: Qg = 0
        (12.0, 0.76, 1.0, 0.5 + 0.35 * 0.8 + 0.15),  # Qo = 0.76 / 0.95
        (12.0, 0.95, 1.25, 0.5 + 0.35 + 0.15 * 0.5),  # Qr = 1 - 0.25 / 0.5
        (3.0, 0.95, 1.6, 0.5 * 0.5 + 0.35),  # 5 deg below; Qr = 0
    ],
)
def test_pair_quality_table(conv_deg, overlap, ratio, expected):
    q = pair_quality(math.radians(conv_deg), overlap, ratio, REQ)
    assert q == pytest.approx(expected, abs=1e-12)


def test_select_products_caps_groups_and_breaks_ties_by_time():
    quality = np.array([1.0, 1.0, 1.0, 0.9, 0.8, 1.0])
    when = np.array([50.0, 10.0, 30.0, 5.0, 1.0, 20.0])
    group = np.array([0, 0, 0, 1, 2, 0])
    # group 0 in order of time: 1 (10), 5 (20), 2 (30), 0 (50); cap 2 keeps 1, 5 first
    got = select_products(quality, when, group, keep=6, per_group=2)
    np.testing.assert_array_equal(got, [1, 5, 3, 4, 2, 0])
    np.testing.assert_array_equal(
        select_products(quality, when, group, keep=3, per_group=2), [1, 5, 3]
    )
    np.testing.assert_array_equal(
        select_products(quality, when, group, keep=6, per_group=10), [1, 5, 2, 0, 3, 4]
    )


@pytest.mark.parametrize(
    "share, n, fail",  # docs/stereo.md "Overlap margin": P(fail) of the 0.8 test
    [(0.80, 100, 0.44), (0.85, 100, 0.066), (0.88, 100, 0.0073), (0.85, 80, 0.084)],
)
def test_pass_probability_matches_the_binomial_table(share, n, fail):
    assert 1.0 - pass_probability(share, n, 0.8) == pytest.approx(fail, abs=0.006)


def test_pass_probability_against_exact_sums():
    for share in (0.0, 0.3, 0.79, 0.8, 0.9, 1.0):
        exact = sum(math.comb(100, j) * share**j * (1 - share) ** (100 - j) for j in range(80, 101))
        assert pass_probability(share, 100, 0.8) == pytest.approx(exact, abs=1e-12)
    np.testing.assert_allclose(pass_probability(np.array([0.0, 1.0]), 80, 0.8), [0.0, 1.0])
