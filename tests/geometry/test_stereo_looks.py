"""Stereo looks: the steering frame against RULES.md, rays, access intervals, looks."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from jaxspline.base.elements import OMEGA_EARTH
from jaxspline.geometry.frames import earth_rotation_angle, rot_z
from jaxspline.geometry.orbit import orbit_state
from jaxspline.geometry.pointing import aim_geometry, roll_params
from jaxspline.geometry.stereo_looks import (
    ellipsoid_distance,
    look_direction,
    roll_pitch,
    satellite_states,
    steering_to,
    stereo_access,
    stereo_looks,
)
from jaxspline.geometry.windows import orbit_scene
from jaxspline.readers.mission import POINT, Scenario, make_targets
from jaxspline.stereo.case import load_case
from jaxspline.stereo.check_geometry import Track, access_mask, target_ecef

sys.path[:0] = [str(Path(__file__).resolve().parents[1] / d) for d in ("planner", "stereo")]
from _ref_stereo import DATA, brute_force_hit  # noqa: E402
from test_stereo_options import case_scenario  # noqa: E402

#: Sub-horizon of these tests [s].
HOURS4 = 4 * 3600.0


@pytest.fixture(scope="module")
def case1():
    return load_case(DATA / "case_0001")


@pytest.fixture(scope="module")
def small(case1):
    sc = case_scenario(case1, HOURS4)
    table, scene = orbit_scene(sc)
    return sc, table, scene


def _benchmark_boresight(r_teme, v_teme, theta, al, ac):
    """RULES.md: Earth-fixed p, v (velocity relative to the rotating Earth); n = -p/|p|,
    a = v minus its n part, c = a x n; boresight n + tan(al) a + tan(ac) c (numpy)."""
    c, s = math.cos(theta), math.sin(theta)
    rz = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    p = rz @ r_teme
    v = rz @ v_teme - OMEGA_EARTH * np.array([-p[1], p[0], 0.0])
    n = -p / np.linalg.norm(p)
    a = v - (v @ n) * n
    a /= np.linalg.norm(a)
    cc = np.cross(a, n)
    d = n + math.tan(al) * a + math.tan(ac) * cc
    return d / np.linalg.norm(d)


def test_roll_law_is_the_benchmark_boresight(small):
    _, _, scene = small
    rng = np.random.default_rng(1)
    g0 = float(scene.gmst0)
    for k in range(12):
        sat, t = k % 3, float(rng.uniform(0.0, HOURS4))
        al, ac = np.radians(rng.uniform(-35, 35, 2))
        roll, pitch = roll_pitch(al, ac)
        _, _, los, _ = aim_geometry(scene, roll_params(roll, pitch), t, t, sat)
        theta = float(earth_rotation_angle(g0, t))  # the planner's Earth rotation
        got = np.asarray(rot_z(theta, np.asarray(los)))  # ECI -> Earth-fixed
        r, v = (np.asarray(x) for x in orbit_state(scene.orbit, t, sat))
        ref = _benchmark_boresight(r, v, theta, al, ac)
        np.testing.assert_allclose(got, ref, atol=1e-12)
        pos, vel = satellite_states(scene, [sat], [t])
        np.testing.assert_allclose(look_direction(pos[0], vel[0], al, ac), ref, atol=1e-12)


def test_steering_inverts_the_boresight(small):
    _, _, scene = small
    pos, vel = satellite_states(scene, [0, 1, 2], [100.0, 2000.0, 9000.0])
    rng = np.random.default_rng(2)
    al, ac = np.radians(rng.uniform(-30, 30, (2, 3)))
    d = look_direction(pos, vel, al, ac)
    g = pos + ellipsoid_distance(pos, d)[:, None] * d
    al2, ac2 = steering_to(pos, vel, g)
    np.testing.assert_allclose(al2, al, atol=1e-12)
    np.testing.assert_allclose(ac2, ac, atol=1e-12)
    for i in range(3):  # the ray's first crossing, by marching and bisection
        assert ellipsoid_distance(pos[i], d[i]) == pytest.approx(
            brute_force_hit(pos[i], d[i]), abs=1e-3
        )
    up = pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    assert np.all(np.isnan(ellipsoid_distance(pos, up)))  # pointing away misses


def test_access_intervals_hold_for_the_checker(case1, small):
    sc, table, scene = small
    acc = stereo_access(sc, table, scene)
    assert len(acc) > 20
    min_sun = case1.mission.thresholds.min_solar_elevation_deg
    tracks = {}
    for i in range(len(acc)):
        s, k = int(acc.sat[i]), int(acc.target[i])
        sat = case1.satellites[s]
        tr = tracks.setdefault(s, Track(sat, case1.start))
        t = np.arange(acc.lo[i], acc.hi[i] + 0.5, 1.0)
        ok = access_mask(tr, target_ecef(case1.targets[k]), sat.max_off_nadir_deg, min_sun, t)
        assert ok.all(), (sat.id, case1.targets[k].id, acc.lo[i], acc.hi[i])
        # the margins take little: a second past either end the checker soon fails
        wide = np.arange(acc.lo[i] - 20.0, acc.hi[i] + 20.5, 1.0)
        wide = wide[(wide >= 0) & (wide <= HOURS4)]
        mask = access_mask(tr, target_ecef(case1.targets[k]), sat.max_off_nadir_deg, min_sun, wide)
        assert mask.sum() <= ok.size + 40


def test_looks_aim_at_the_target(case1, small):
    sc, table, scene = small
    acc, lk = stereo_looks(sc, table, scene)
    assert len(lk) > 100
    assert np.all((lk.t_start >= acc.lo[lk.access]) & (lk.t_end <= acc.hi[lk.access]))
    np.testing.assert_array_equal(acc.sat[lk.access], lk.sat)
    dur = lk.t_end - lk.t_start
    assert np.all((dur >= 2.0) & (dur <= 60.0)) and np.all(dur == np.round(dur))
    assert np.all(lk.t_start == np.round(lk.t_start))
    assert np.all(np.degrees(lk.off_nadir) <= 35.0 - 0.05 + 1e-9)
    # the track's middle point lies at the target's foot (east/north offset ~0)
    for i in np.random.default_rng(3).choice(len(lk), 20, replace=False):
        tr = Track(case1.satellites[lk.sat[i]], case1.start, ut1_minus_utc_s=0.0)
        mid = (lk.t_start[i] + lk.t_end[i]) / 2.0
        pos, _ = tr.ecef(np.array([mid]))
        assert np.linalg.norm(pos[0] - lk.sat_mid[i]) < 500.0  # WGS72 vs WGS84 SGP4
        centre = target_ecef(case1.targets[lk.target[i]])
        up = centre / np.linalg.norm(centre)
        a, b = lk.track[i, 0], lk.track[i, -1]
        off = (a + b) / 2.0 - centre
        assert np.linalg.norm(off - (off @ up) * up) < 0.05 * np.linalg.norm(b - a) + 50.0
    slant = np.linalg.norm(lk.track[:, 0] - lk.sat_mid, axis=-1)
    assert np.all(np.abs(slant - lk.slant) < 0.2 * lk.slant)
    np.testing.assert_allclose(
        lk.scale, lk.slant * np.array([s.ifov for s in sc.satellites])[lk.sat]
    )


def test_bad_input_and_no_stereo(small):
    sc, table, scene = small
    with pytest.raises(ValueError, match="mid_step"):
        stereo_looks(sc, table, scene, mid_step=0.0)
    points = make_targets(np.array([POINT]), [0.2], [0.3], duration=5.0)
    bare = Scenario(sc.name, sc.epoch, sc.duration, sc.satellites, points, sc.planner)
    assert len(stereo_access(bare, table, scene)) == 0
    acc, lk = stereo_looks(bare, table, scene)
    assert len(acc) == 0 and len(lk) == 0
