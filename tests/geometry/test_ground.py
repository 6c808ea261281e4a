"""Ground geometry: projections, strips between points, footprints, ground tracks.

References: the planner's own strip kernel (``aim_params`` + ``aim_point``, JAX) for
the strip inversion; collinearity of great-circle points (gnomonic); the area of a
spherical cap ``2 pi (1 - cos a)`` and of a lune (equal-area); great-circle distances
by the haversine formula (footprint widths); finite differences of the orbit
(ground-track rate).
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np
import pytest

from jaxspline.base.elements import circular_orbit, geodetic_to_ecef, unit_vectors
from jaxspline.geometry.frames import earth_rotation_angle, teme_to_ecef
from jaxspline.geometry.ground import (
    equal_area,
    gnomonic,
    gnomonic_inverse,
    ground_track,
    local_axes,
    strip_between,
    strip_centerline,
    strip_footprint,
    surface_point,
)
from jaxspline.geometry.orbit import orbit_state
from jaxspline.geometry.pointing import aim_params, aim_point
from jaxspline.geometry.routes import strip_direction

RNG = np.random.default_rng(11)


def _random_units(n, spread=0.03):
    a = unit_vectors(RNG.normal(size=(n, 3)))
    return a, unit_vectors(a + spread * RNG.normal(size=(n, 3)))


def _haversine(u, v):
    return 2.0 * np.arcsin(np.linalg.norm(u - v, axis=-1) / 2.0)


def test_strip_between_inverts_the_planner_strip():
    u_a, u_b = _random_units(50)
    lat, lon, az, length = strip_between(u_a, u_b)
    g0 = geodetic_to_ecef(lat, lon, 0.0)
    np.testing.assert_allclose(unit_vectors(g0), u_a, atol=1e-14)
    np.testing.assert_allclose(
        np.linalg.norm(surface_point(u_a), axis=-1), np.linalg.norm(g0, axis=-1), rtol=1e-14
    )
    p = aim_params(jnp.asarray(g0), jnp.asarray(strip_direction(lat, lon, az)), 7000.0)
    for i in range(len(u_a)):
        g, _ = aim_point(p[i], length[i] / np.linalg.norm(g0[i]))
        np.testing.assert_allclose(unit_vectors(np.asarray(g)), u_b[i], atol=1e-13)
    assert np.all((az >= 0) & (az < 2 * np.pi))
    np.testing.assert_allclose(
        length, np.linalg.norm(g0, axis=-1) * _haversine(u_a, u_b), rtol=1e-10
    )


def test_strip_centerline_matches_the_planner_kernel():
    lat, lon = np.radians([45.0, -30.0, 80.0]), np.radians([14.0, 120.0, -60.0])
    az, length = np.radians([10.0, 200.0, 95.0]), np.array([40e3, 5e3, 120e3])
    u, tan, rad = strip_centerline(lat, lon, az, length, 7, alt=[0.0, 300.0, 0.0])
    g0 = geodetic_to_ecef(lat, lon, np.array([0.0, 300.0, 0.0]))
    p = aim_params(jnp.asarray(g0), jnp.asarray(strip_direction(lat, lon, az)), 7000.0)
    for i in range(3):
        for j, f in enumerate(np.linspace(0, 1, 7)):
            g, t = aim_point(p[i], f * length[i] / rad[i])
            np.testing.assert_allclose(u[i, j], unit_vectors(np.asarray(g)), atol=1e-14)
            np.testing.assert_allclose(tan[i, j], np.asarray(t), atol=1e-14)
    with pytest.raises(ValueError, match="samples"):
        strip_centerline(0.0, 0.0, 0.0, 1.0, 1)


def test_gnomonic_maps_great_circles_to_lines_and_inverts():
    c = unit_vectors(np.array([0.3, 0.5, 0.8]))
    a, b = _random_units(1, 0.1)
    t = np.linspace(-0.2, 1.2, 15)[:, None]
    w = unit_vectors(b[0] - (a[0] @ b[0]) * a[0])
    arc = np.arctan2(np.linalg.norm(np.cross(a[0], b[0])), a[0] @ b[0])
    pts = np.cos(t * arc) * a[0] + np.sin(t * arc) * w  # on the great circle through a, b
    c = unit_vectors(a[0] + 0.05 * w + 0.03 * np.cross(a[0], w))
    xy = gnomonic(pts, c)
    d = xy - xy[0]
    cross = d[:, 0] * d[-1, 1] - d[:, 1] * d[-1, 0]
    assert np.abs(cross).max() < 1e-14
    np.testing.assert_allclose(gnomonic_inverse(xy, c), pts, atol=1e-14)
    np.testing.assert_allclose(gnomonic(c, c), [0.0, 0.0], atol=1e-15)
    e, n = local_axes(c)
    np.testing.assert_allclose([e @ c, n @ c, e @ n, np.linalg.norm(e)], [0, 0, 0, 1], atol=1e-15)
    assert n[2] > 0  # north points up
    np.testing.assert_allclose(local_axes(np.array([0.0, 0.0, 1.0]))[0], [1.0, 0.0, 0.0])


@pytest.mark.parametrize("cap_deg", [0.5, 10.0, 60.0])
def test_equal_area_keeps_the_area_of_a_cap(cap_deg):
    c = unit_vectors(np.array([0.2, -0.7, 0.5]))
    e, n = local_axes(c)
    a = math.radians(cap_deg)
    phi = np.linspace(0.0, 2 * np.pi, 20001)[:-1]
    ring = np.cos(a) * c + np.sin(a) * (np.cos(phi)[:, None] * e + np.sin(phi)[:, None] * n)
    x, y = equal_area(ring, c).T
    shoelace = 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    np.testing.assert_allclose(shoelace, 2 * np.pi * (1 - np.cos(a)), rtol=1e-7)


def test_equal_area_keeps_the_area_of_a_lune_quadrilateral():
    """Latitude-longitude box [lat0, lat1] x [0, dlon]: area dlon (sin lat1 - sin lat0)."""
    lat0, lat1, dlon = np.radians([40.0, 41.0, 1.5])
    la = np.linspace(lat0, lat1, 2001)
    lo = np.linspace(0.0, dlon, 2001)
    ring = np.concatenate(
        [
            np.column_stack([np.full_like(lo, lat0), lo]),
            np.column_stack([la, np.full_like(la, dlon)]),
            np.column_stack([np.full_like(lo, lat1), lo[::-1]]),
            np.column_stack([la[::-1], np.zeros_like(la)]),
        ]
    )
    u = np.stack(
        [
            np.cos(ring[:, 0]) * np.cos(ring[:, 1]),
            np.cos(ring[:, 0]) * np.sin(ring[:, 1]),
            np.sin(ring[:, 0]),
        ],
        -1,
    )
    x, y = equal_area(u, unit_vectors(u.mean(0))).T
    shoelace = 0.5 * abs(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))
    np.testing.assert_allclose(shoelace, dlon * (np.sin(lat1) - np.sin(lat0)), rtol=1e-6)


def test_strip_footprint_width_and_shape():
    lat, lon, az, length, swath = np.radians(45.0), np.radians(14.0), np.radians(30.0), 50e3, 12e3
    ring = strip_footprint(lat, lon, az, length, swath, 11)
    u, _, rad = strip_centerline(lat, lon, az, length, 11)
    assert ring.shape == (22, 3)
    left, right = ring[:11], ring[11:][::-1]
    np.testing.assert_allclose(_haversine(left, right) * rad, swath, rtol=1e-12)
    np.testing.assert_allclose(_haversine(left, u) * rad, swath / 2, rtol=1e-12)
    # left is to the left of the direction of travel (north-east heading: left is north-west)
    e, n = local_axes(u[0])
    side = left[0] - u[0]
    assert side @ n > 0 and side @ e < 0


def test_ground_track_rate_matches_finite_differences():
    orb = circular_orbit(600e3, None, 0.4, 1.0)
    t = np.array([100.0, 100.0 + 1e-3, 100.0 - 1e-3])
    r, v = (np.asarray(x) for x in orbit_state(orb, jnp.asarray(t)))
    theta = earth_rotation_angle(0.7, t)
    r_e, v_e = teme_to_ecef(r, theta, v)
    u, u_dot = ground_track(r_e, v_e)
    fd = (u[1] - u[2]) / 2e-3
    np.testing.assert_allclose(u_dot[0], fd, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(u_dot[0] @ u[0], 0.0, atol=1e-15)
