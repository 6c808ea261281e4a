"""The stereo checker's geometry against independent references: finite differences and
a second SGP4 path for the states, brute-force ray marching for ground points, the
steering identities, the NOAA solar position, exact polygon areas (shapely) for the
overlap quadrature, and RULES.md's slew examples."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from _ref_stereo import DATA, brute_force_hit, noaa_solar_elevation_deg

from jaxspline.aeossp.check_frames import Ephemeris, angle_deg, bang_coast_bang_time
from jaxspline.stereo.case import load_case
from jaxspline.stereo.check_geometry import (
    Track,
    boresight,
    combined_off_nadir_deg,
    disk_lattice,
    enu_basis,
    foot_point,
    ground_point,
    inside_strip,
    ray_ellipsoid,
    solar_elevation_deg,
    steering_angles,
    target_ecef,
    window_samples,
)

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")


@pytest.fixture(scope="module")
def case1():
    return load_case(DATA / "case_0001")


@pytest.fixture(scope="module")
def track(case1):
    return Track(case1.satellites[0], case1.start)


def test_velocity_is_the_derivative_of_the_earth_fixed_position(track):
    """The Earth-fixed velocity adds nothing to SGP4's own velocity-vs-position mismatch
    (~0.02 m/s in TEME): the rotation term is exact."""
    t = np.array([1000.0, 50000.0, 120000.0])
    h = 1.0

    def mismatch(states):
        (p1, _), (p0, _), (_, v) = states(t + h), states(t - h), states(t)
        return np.linalg.norm((p1 - p0) / (2 * h) - v, axis=-1)

    teme, ecef = mismatch(track.teme), mismatch(track.ecef)
    assert np.all(teme < 0.05)
    assert np.allclose(ecef, teme, atol=2e-3)  # m/s


def test_states_match_a_second_sgp4_path(case1):
    """The aeossp checker's ephemeris (its own rotation matrices), WGS72, zero UT1 - UTC."""
    sat = case1.satellites[3]

    class Tle:  # the two fields Ephemeris reads
        satellite_id, tle_line1, tle_line2 = sat.id, sat.tle1, sat.tle2

    t = np.linspace(0.0, case1.horizon_s, 7)
    ref = Ephemeris(Tle, case1.start, gravity="wgs72").ecef(t)
    mine, _ = Track(sat, case1.start, ut1_minus_utc_s=0.0).ecef(t)
    assert np.max(np.linalg.norm(mine - ref, axis=-1)) < 1e-3
    shifted, _ = Track(sat, case1.start).ecef(t)  # UT1 - UTC turns the Earth a little
    assert 1.0 < np.max(np.linalg.norm(shifted - ref, axis=-1)) < 50.0


def test_ground_points_match_brute_force_ray_marching(track):
    rng = np.random.default_rng(5)
    pos, vel = track.ecef(rng.uniform(0, 170000, 6))
    for p, v in zip(pos, vel, strict=True):
        al, ac = rng.uniform(-30, 30, 2)
        d = boresight(p, v, al, ac)
        assert ray_ellipsoid(p, d) == pytest.approx(brute_force_hit(p, d), abs=1e-3)
        assert float(angle_deg(d, -p)) == pytest.approx(
            float(combined_off_nadir_deg(al, ac)), abs=1e-9
        )
    far = pos[0] / np.linalg.norm(pos[0])  # pointing away from the Earth misses
    assert math.isnan(float(ray_ellipsoid(pos[0], far)))


def test_steering_angles_invert_the_boresight(case1, track):
    tgt = case1.targets[7]
    aim = foot_point(target_ecef(tgt))
    assert aim[:2] @ aim[:2] / 6378137.0**2 + aim[2] ** 2 / 6356752.314245179**2 == pytest.approx(
        1.0
    )
    east_north_up = enu_basis(target_ecef(tgt)) @ (aim - target_ecef(tgt))
    assert np.allclose(east_north_up[:2], 0.0, atol=1e-6)
    assert east_north_up[2] == pytest.approx(-tgt.elevation_m, abs=1.0)
    pos, vel = track.ecef(np.array([4321.0, 9876.0]))
    for al, ac in ((12.0, -7.0), (-25.0, 3.5), (0.0, 0.0)):
        g = ground_point(pos, vel, al, ac)
        back = steering_angles(pos, vel, g)
        assert np.allclose(back[0], al, atol=1e-9) and np.allclose(back[1], ac, atol=1e-9)


def test_positive_across_looks_left_of_the_track(track):
    pos, vel = track.ecef(np.array([777.0]))
    left = np.cross(pos[0], vel[0])  # up x forward: to the left of the ground track
    g0 = ground_point(pos[0], vel[0], 0.0, 0.0)
    g1 = ground_point(pos[0], vel[0], 0.0, 10.0)
    assert (g1 - g0) @ left > 0
    gf = ground_point(pos[0], vel[0], 10.0, 0.0)
    assert (gf - g0) @ vel[0] > 0  # positive along looks ahead


def test_enu_basis_is_orthonormal_and_geocentric(case1):
    c = target_ecef(case1.targets[0])
    b = enu_basis(c)
    assert np.allclose(b @ b.T, np.eye(3), atol=1e-12)
    assert np.allclose(b[2], c / np.linalg.norm(c))
    assert b[1][2] > 0 and np.cross(b[0], b[1]) @ b[2] == pytest.approx(1.0)


def test_solar_elevation_matches_the_noaa_formulas(case1):
    for tgt in case1.targets[:6]:
        c = target_ecef(tgt)
        for s in np.linspace(0.0, case1.horizon_s, 9):
            unix = case1.start.timestamp() + s
            ref = noaa_solar_elevation_deg(tgt.lat_deg, tgt.lon_deg, unix)
            assert float(solar_elevation_deg(c, unix)) == pytest.approx(ref, abs=0.4)


def _exact_share(radius, polys, widths):
    disk = shapely.Point(0, 0).buffer(radius, quad_segs=256)
    area = disk
    for poly, w in zip(polys, widths, strict=True):
        area = area.intersection(shapely.LineString(poly).buffer(w, quad_segs=256))
    return area.area / disk.area


def test_the_lattice_overlap_matches_exact_areas():
    """The quadrature's error is far below the official 100-point estimate's spread."""
    rng = np.random.default_rng(11)
    errs = []
    for _ in range(40):
        radius = rng.uniform(2500, 7500)
        polys, widths = [], []
        for _ in range(rng.integers(2, 4)):
            heading = rng.uniform(0, np.pi)
            off = rng.uniform(-0.6, 0.6, 2) * radius
            u = np.array([np.cos(heading), np.sin(heading)])
            polys.append(off + np.outer(np.linspace(-1.5, 1.5, 3) * radius, u))
            widths.append(rng.uniform(0.4, 1.5) * radius)
        pts = disk_lattice(radius)
        share = np.mean(
            np.all([inside_strip(pts, p, w) for p, w in zip(polys, widths, strict=True)], 0)
        )
        errs.append(abs(share - _exact_share(radius, polys, widths)))
    assert max(errs) < 0.004


def test_lattice_points_are_uniform_over_the_disk():
    pts = disk_lattice(1.0, 4096)
    r = np.linalg.norm(pts, axis=-1)
    assert r.max() < 1.0
    for q in (0.25, 0.5, 0.75):
        assert np.mean(r <= math.sqrt(q)) == pytest.approx(q, abs=1e-3)
    assert abs(np.mean(pts[:, 0] > 0) - 0.5) < 2e-3


@pytest.mark.parametrize("deg, total", [(1, 3.2), (10, 7.7), (20, 11.9), (30, 16.2)])
def test_slew_times_of_rules_md(case1, deg, total):
    """RULES.md's SPOT examples (rate 2.35 deg/s, accel 1.15 deg/s², settling 1.35 s),
    given there to one decimal."""
    assert 1.35 + bang_coast_bang_time(deg, 2.35, 1.15) == pytest.approx(total, abs=0.06)


def test_window_samples():
    assert window_samples(10.0, 13.5, 1.0).tolist() == [10.0, 11.0, 12.0, 13.0, 13.5]
    assert window_samples(10.0, 12.0, 1.0).tolist() == [10.0, 11.0, 12.0]
    assert window_samples(5.0, 5.0, 1.0).tolist() == [5.0]
    assert window_samples(5.0, 4.0, 1.0).size == 0
