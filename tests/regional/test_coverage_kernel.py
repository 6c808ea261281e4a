"""Strip-coverage engine, its kernels and the planner's Earth-fixed tracks against
independent references.

References (:mod:`_ref_coverage`, numpy + scipy + shapely + sgp4, apart from the
package): shapely's point-in-polygon on quads of edge points computed by explicit
rotations of nadir and the textbook ray-ellipsoid root; sgp4's own propagation and
``gstime`` for the tracks; direct per-candidate sweeps (no runs, pieces or tiles) for the
sub-strip equivalence; the regional checker (:mod:`jaxspline.regional.check`, its own
SGP4 frames and geometry) for the covered sets of real actions.
"""

from __future__ import annotations

import functools
from pathlib import Path

import _ref_coverage as ref
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxspline.screen.coverage import Candidates, coverage_slices, covered_samples, strip_quads
from jaxspline.screen.coverage_kernels import edge_points, look_point, quad_range

CASE = Path("/work/shared/data/regional_coverage/train/case_0004")
needs_case = pytest.mark.skipif(not CASE.is_dir(), reason="benchmark data not present")


@functools.lru_cache(maxsize=1)
def _case_and_tracks():
    """The case, its Scenario and the planner's Earth-fixed tracks (pos, vel, t)."""
    from jaxspline.geometry.windows import orbit_scene
    from jaxspline.planner.area_options import earth_fixed_tracks
    from jaxspline.regional.adapter import case_scenario
    from jaxspline.regional.case import load_case

    case = load_case(CASE)
    sc = case_scenario(case)
    table, scene = orbit_scene(sc)
    return case, sc, scene, earth_fixed_tracks(sc, table, scene)


def _fov(case):
    return np.array([s.sensor.fov_deg for s in case.satellites])


def _near_samples(case, pos, max_deg=6.0):
    """(sat, k) where the sub-satellite point is within max_deg of a region's centre."""
    g = case.grid
    cen = []
    for r in range(len(case.regions)):
        la, lo = np.radians(g.lat_deg[g.region == r]), np.radians(g.lon_deg[g.region == r])
        v = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1).mean(0)
        cen.append(v / np.linalg.norm(v))
    u = pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    return np.argwhere((u @ np.array(cen).T).max(-1) > np.cos(np.radians(max_deg)))


def _random_candidates(case, pos, c, seed, pitch=False):
    rng = np.random.default_rng(seed)
    near = _near_samples(case, pos)
    pick = near[rng.integers(0, len(near), c)]
    n = rng.integers(2, 19, c) * 2 + 1
    k0 = np.clip((pick[:, 1] - rng.integers(0, 30, c)) // 2 * 2, 0, pos.shape[1] - n - 1)
    sat = pick[:, 0]
    lo = np.array([s.sensor.min_edge_deg + s.sensor.fov_deg / 2 for s in case.satellites])[sat]
    hi = np.array([s.sensor.max_edge_deg - s.sensor.fov_deg / 2 for s in case.satellites])[sat]
    roll = np.round(rng.uniform(lo, hi) * 4) / 4 * rng.choice([-1.0, 1.0], c)
    p = np.round(rng.uniform(-25.0, 25.0, c), 2) if pitch else None
    return Candidates(sat.astype(np.int32), k0.astype(np.int32), n.astype(np.int32), roll, p)


def _engine(case, pos, vel, cands):
    g = case.grid
    return coverage_slices(pos, vel, _fov(case), cands, g.lon_deg, g.lat_deg, g.region)


def _row(cov, c):
    return np.sort(cov.pool[cov.lo[c] : cov.hi[c]].astype(np.int64))


# ------------------------------------------------------------------ engine vs shapely
@needs_case
@pytest.mark.parametrize("pitched", [False, True])
def test_engine_equals_shapely_on_random_candidates(pitched):
    """Covered sets of 150 random strips (rolls in the band, pitches within 25 deg when
    pitched) == shapely on the reference's own edge points; invalid where a ray misses."""
    case, _, _, (pos, vel, _) = _case_and_tracks()
    cands = _random_candidates(case, pos, 150, seed=1 + pitched, pitch=pitched)
    cov = _engine(case, pos, vel, cands)
    g, fov = case.grid, _fov(case)
    nonempty = 0
    for c in range(cands.sat.size):
        s, k0, n, r = cands.sat[c], cands.k0[c], cands.n[c], cands.roll_deg[c]
        p = 0.0 if cands.pitch_deg is None else float(cands.pitch_deg[c])
        inner, outer, hit = ref.edges(pos[s, k0 : k0 + n], vel[s, k0 : k0 + n], r, fov[s], p)
        assert cov.valid[c] == hit.all()
        want = ref.covered(inner, outer, g.lon_deg, g.lat_deg)
        np.testing.assert_array_equal(_row(cov, c), want, err_msg=f"candidate {c}")
        nonempty += want.size > 0
    assert nonempty >= 15  # the comparison is not vacuous
    tab = cov.csr(10, 60)
    np.testing.assert_array_equal(tab.valid, cov.valid[10:60])
    for i, c in enumerate(range(10, 60)):
        np.testing.assert_array_equal(
            np.sort(tab.indices[tab.indptr[i] : tab.indptr[i + 1]]), _row(cov, c)
        )


@needs_case
def test_sub_strips_of_one_sweep_equal_direct_sweeps():
    """Every (k0, n) of one (satellite, roll, pitch): engine == direct sweeps of the strip."""
    case, _, _, (pos, vel, _) = _case_and_tracks()
    g, fov = case.grid, _fov(case)
    probe = _random_candidates(case, pos, 300, seed=2)
    cov = _engine(case, pos, vel, probe)
    best = int(np.argmax(cov.counts()))
    s, roll = int(probe.sat[best]), float(probe.roll_deg[best])
    base = int(probe.k0[best]) - 20
    k0, n = np.meshgrid(np.arange(base, base + 40, 6), np.arange(2, 38, 7), indexing="ij")
    k0, n = k0.ravel(), n.ravel()
    for pitch in (0.0, 12.5):
        cands = Candidates(
            np.full(k0.size, s, np.int32),
            k0.astype(np.int32),
            n.astype(np.int32),
            np.full(k0.size, roll),
            np.full(k0.size, pitch),
        )
        cov = _engine(case, pos, vel, cands)
        sl = slice(base, base + 80)
        inner, outer, _ = strip_quads(pos[s, sl], vel[s, sl], roll, fov[s], pitch)
        sizes = []
        for c in range(k0.size):
            a = k0[c] - base
            direct = covered_samples(inner[a : a + n[c]], outer[a : a + n[c]], g.lon_deg, g.lat_deg)
            np.testing.assert_array_equal(_row(cov, c), direct, err_msg=f"k0={k0[c]} n={n[c]}")
            sizes.append(direct.size)
        assert max(sizes) > 100 and min(sizes) < max(sizes)
        assert cov.stats["groups"] == 1


@needs_case
def test_gains_equal_weight_sums():
    case, _, _, (pos, vel, _) = _case_and_tracks()
    cands = _random_candidates(case, pos, 200, seed=3)
    cov = _engine(case, pos, vel, cands)
    w = np.random.default_rng(0).uniform(0, 1, case.grid.size)
    want = np.array([w[cov.pool[cov.lo[c] : cov.hi[c]]].sum() for c in range(200)])
    np.testing.assert_allclose(cov.gains(w), want, rtol=1e-12, atol=1e-9)


# ------------------------------------------------------------------ pitch geometry
def _states(seed, n=6):
    """Random LEO states (Earth-fixed position [m], velocity [m/s])."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    pos = u * rng.uniform(6.8e6, 7.2e6, (n, 1))
    t = np.cross(u, rng.normal(size=(n, 3)))
    vel = t / np.linalg.norm(t, axis=-1, keepdims=True) * 7.3e3 + rng.normal(0, 30, (n, 3))
    return pos, vel


def test_pitch_zero_is_the_roll_only_law_bit_for_bit():
    """At pitch 0 the look direction is exactly ``nadir + tan(a) across`` (roll_frame's
    vectors), and the edge points equal those of the call without a pitch, bit for bit."""
    from jaxspline.geometry.pointing import roll_frame, roll_look_direction

    pos, vel = _states(7)
    edges = jax.jit(jax.vmap(edge_points, (0, 0, None, None, None)))
    plain = jax.jit(jax.vmap(edge_points, (0, 0, None, None)))
    for roll in (-33.0, -4.0, 0.0, 12.5, 29.75):
        for a, b in zip(edges(pos, vel, roll, 4.8, 0.0), plain(pos, vel, roll, 4.8), strict=True):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
        for k in range(pos.shape[0]):
            p, v = jnp.asarray(pos[k]), jnp.asarray(vel[k])
            nadir, _, across = roll_frame(p, v)
            want = nadir + jnp.tan(jnp.radians(roll)) * across
            np.testing.assert_array_equal(np.asarray(roll_look_direction(p, v, roll, 0.0)), want)


@pytest.mark.parametrize("pitch", [-28.0, -7.5, 3.0, 21.0])
def test_pitched_rays_are_rotations_of_nadir(pitch):
    """Look directions and ground points at (roll, pitch) == nadir turned by the pitch
    towards the track and then by the roll towards ``across`` (explicit rotations),
    intersected with the ellipsoid by the textbook root."""
    from jaxspline.geometry.pointing import roll_look_direction

    pos, vel = _states(8)
    look = jax.jit(jax.vmap(look_point, (0, 0, None, None)))
    for roll in (-30.0, -2.5, 0.0, 17.0):
        d_ref = ref.look_directions(pos, vel, roll, pitch)
        for k in range(pos.shape[0]):
            d = np.asarray(
                roll_look_direction(jnp.asarray(pos[k]), jnp.asarray(vel[k]), roll, pitch)
            )
            np.testing.assert_allclose(d / np.linalg.norm(d), d_ref[k], atol=1e-14)
        lon, lat, hit = look(pos, vel, roll, pitch)
        lon_r, lat_r, hit_r = ref.ground(pos, d_ref)
        np.testing.assert_array_equal(np.asarray(hit), hit_r)
        assert hit_r.all()
        np.testing.assert_allclose(np.asarray(lon), lon_r, atol=1e-9)
        np.testing.assert_allclose(np.asarray(lat), lat_r, atol=1e-9)


@needs_case
def test_roll_law_line_of_sight_is_the_imaging_ray():
    """The aim law of an area strip (roll_params) points, at every instant, along the
    reference ray of its roll and pitch (what the maneuvers turn to is what is imaged)."""
    from jaxspline.geometry.frames import earth_rotation_angle, rot_z
    from jaxspline.geometry.pointing import aim_geometry, roll_params

    case, sc, scene, (pos, vel, t) = _case_and_tracks()
    geo = jax.jit(aim_geometry, static_argnums=4)
    for k, i, roll, pitch in ((0, 4000, 20.0, 0.0), (1, 9000, -31.5, 14.0), (2, 30001, 5.0, -22.0)):
        p = roll_params(np.radians(roll), np.radians(pitch))
        offn, elev, los, _ = geo(scene, p, 0.0, float(t[i]), k)
        theta = earth_rotation_angle(float(scene.gmst0), float(t[i]))
        got = np.asarray(rot_z(theta, los))
        want = ref.look_directions(pos[k, i], vel[k, i], roll, pitch)[0]
        np.testing.assert_allclose(got, want, atol=1e-9)
        assert float(offn) == pytest.approx(
            np.arccos(np.cos(np.radians(roll)) * np.cos(np.radians(pitch))), abs=1e-9
        )


# ------------------------------------------------------------------ hand-made cases
def _square_strip():
    # two unit quads stacked in latitude: [0, 1] x [0, 1] and [0, 1] x [1, 2]
    inner = np.array([[0.0, 0.0], [0.0, 1.0], [0.0, 2.0]])
    outer = np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]])
    return inner, outer


def test_border_points_are_covered_like_shapely():
    inner, outer = _square_strip()
    pts = np.array(
        [
            [0.5, 0.0],
            [1.0, 0.5],
            [0.0, 0.0],
            [0.5, 0.5],
            [0.5, 1.0],
            [1.0, 2.0],
            [1.0 + 2**-30, 0.5],
            [0.5, -(2**-30)],
            [0.5, 2.0 + 2**-30],
            [-0.25, 1.0],
        ]
    )
    want = ref.covered(inner, outer, pts[:, 0], pts[:, 1])
    got = covered_samples(inner, outer, pts[:, 0], pts[:, 1])
    np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(got, [0, 1, 2, 3, 4, 5])
    first, last, count = jax.jit(jax.vmap(quad_range, (None, None, None, None, 0)))(
        jnp.asarray(inner), jnp.asarray(outer), 2, 0.0, jnp.asarray(pts)
    )
    assert (int(first[4]), int(last[4]), int(count[4])) == (0, 1, 2)  # on the shared edge
    assert (int(first[6]), int(last[6]), int(count[6])) == (2, -1, 0)  # outside


def test_reversed_orientation_and_antimeridian_quads():
    inner, outer = _square_strip()
    pts = np.array([[0.5, 0.5], [0.5, 1.5], [1.5, 0.5]])
    for a, b in ((outer, inner), (inner[::-1], outer[::-1])):  # clockwise quads too
        np.testing.assert_array_equal(covered_samples(a, b, pts[:, 0], pts[:, 1]), [0, 1])
    shift = np.array([179.5, 0.0])  # the strip straddles lon 180
    wrap = lambda x: (x + shift + [180.0, 0.0]) % [360.0, 1e9] - [180.0, 0.0]  # noqa: E731
    i2, o2, p2 = wrap(inner), wrap(outer), wrap(pts)
    assert i2[0, 0] > 0 and o2[0, 0] < 0
    np.testing.assert_array_equal(covered_samples(i2, o2, p2[:, 0], p2[:, 1]), [0, 1])
    np.testing.assert_array_equal(ref.covered(i2, o2, p2[:, 0], p2[:, 1]), [0, 1])


def _equatorial_states(lon0_deg, n, step_s=5.0, alt=520e3, eastward=True):
    """Synthetic Earth-fixed states over the equator (a straight track along it)."""
    r = ref.A + alt
    rate = 7300.0 / r * (1 if eastward else -1)  # rad/s ground-relative
    lam = np.radians(lon0_deg) + rate * step_s * np.arange(n)
    pos = r * np.stack([np.cos(lam), np.sin(lam), np.zeros(n)], -1)
    vel = 7300.0 * np.sign(rate) * np.stack([-np.sin(lam), np.cos(lam), np.zeros(n)], -1)
    return pos, vel


@pytest.mark.parametrize("pitch", [0.0, 18.0])
def test_engine_across_the_antimeridian_and_negative_roll(pitch):
    pos, vel = _equatorial_states(178.0 - pitch / 12.0, 200)  # pitched: imaged ~1.5 deg ahead
    lon1 = np.concatenate([np.linspace(179.0, 180.0, 40), np.linspace(-180.0, -179.0, 40)])
    lon, lat = (a.ravel() for a in np.meshgrid(lon1, np.linspace(-4.0, 4.0, 33)))
    region = np.zeros(lon.size, np.int32)
    cands = Candidates(
        np.zeros(4, np.int32),
        np.array([0, 0, 2, 2], np.int32),
        np.array([120, 120, 30, 30], np.int32),
        np.array([25.0, -25.0, 25.0, -25.0]),
        np.full(4, pitch),
    )
    cov = coverage_slices(pos[None], vel[None], np.array([4.8]), cands, lon, lat, region)
    for c in range(4):
        k0, n, r = cands.k0[c], cands.n[c], cands.roll_deg[c]
        inner, outer, hit = ref.edges(pos[k0 : k0 + n], vel[k0 : k0 + n], r, 4.8, pitch)
        want = ref.covered(inner, outer, lon, lat)
        assert hit.all() and want.size > 0 and np.ptp(lon[want]) > 300  # both sides
        np.testing.assert_array_equal(_row(cov, c), want)
        # eastward motion: across = along x nadir points north, so roll > 0 looks north
        assert np.all(np.sign(lat[want]) == np.sign(r))


def test_pitch_moves_the_strip_along_the_track():
    """An eastward track over the equator: pitch p > 0 images ahead (east) by about
    ``h tan(p)`` (h = 520 km), and the strip's covered samples are the reference's."""
    pos, vel = _equatorial_states(10.0, 8)  # 35 s: ~2.3 deg of track
    lon, lat = (a.ravel() for a in np.meshgrid(np.linspace(7.0, 15.0, 200), np.linspace(1, 3, 25)))
    region = np.zeros(lon.size, np.int32)
    mean_lon = []
    for pitch in (-15.0, 0.0, 15.0):
        cands = Candidates(
            np.zeros(1, np.int32),
            np.zeros(1, np.int32),
            np.array([8], np.int32),
            np.array([20.0]),
            np.array([pitch]),
        )
        cov = coverage_slices(pos[None], vel[None], np.array([4.8]), cands, lon, lat, region)
        inner, outer, _ = ref.edges(pos, vel, 20.0, 4.8, pitch)
        want = ref.covered(inner, outer, lon, lat)
        assert want.size > 50
        np.testing.assert_array_equal(_row(cov, 0), want)
        mean_lon.append(lon[want].mean())
    shift = np.degrees(520e3 * np.tan(np.radians(15.0)) / ref.A)  # ~1.25 deg
    assert mean_lon[2] - mean_lon[1] == pytest.approx(shift, rel=0.1)
    assert mean_lon[1] - mean_lon[0] == pytest.approx(shift, rel=0.1)


# ------------------------------------------------------------------ kernel properties
def test_miss_is_a_value_and_values_are_finite():
    pos = jnp.array([7.0e6, 0.0, 0.0])
    vel = jnp.array([0.0, 7.5e3, 0.0])
    lon, lat, hit = jax.jit(look_point)(pos, vel, 80.0)  # beyond the limb
    assert not bool(hit) and np.isfinite(float(lon)) and np.isfinite(float(lat))
    for pitch in (0.0, 60.0):
        inner, outer, hit = jax.jit(edge_points)(pos, vel, 75.0, 10.0, pitch)
        assert not bool(hit)
        assert np.all(np.isfinite(np.asarray(inner))) and np.all(np.isfinite(np.asarray(outer)))


def test_jit_vmap_agree_with_single_item_calls():
    rng = np.random.default_rng(5)
    pos, vel = _equatorial_states(-60.0, 4)
    pos = pos + rng.normal(0, 5e4, pos.shape)
    rolls = rng.uniform(-35, 35, 4)
    pitches = rng.uniform(-20, 20, 4)
    batched = jax.jit(jax.vmap(edge_points, (0, 0, 0, None, 0)))(pos, vel, rolls, 4.8, pitches)
    for k in range(4):
        single = jax.jit(edge_points)(
            jnp.asarray(pos[k]), jnp.asarray(vel[k]), rolls[k], 4.8, pitches[k]
        )
        for a, b in zip(single, batched, strict=True):
            np.testing.assert_allclose(np.asarray(a), np.asarray(b)[k], rtol=1e-13, atol=1e-13)
    inner, outer = rng.normal(size=(9, 2)), rng.normal(size=(9, 2)) + 0.5
    pts = rng.normal(size=(64, 2))
    got = jax.jit(jax.vmap(quad_range, (None, None, None, None, 0)))(inner, outer, 7, 0.0, pts)
    assert int(np.sum(np.asarray(got[2]) > 0)) >= 3  # some points inside
    for p in range(0, 64, 5):
        one = jax.jit(quad_range)(
            jnp.asarray(inner), jnp.asarray(outer), 7, 0.0, jnp.asarray(pts[p])
        )
        assert tuple(int(x) for x in one) == tuple(int(np.asarray(x)[p]) for x in got)


def test_bad_candidates_raise_named_errors():
    pos, vel = _equatorial_states(0.0, 10)
    grid = (np.zeros(1), np.zeros(1), np.zeros(1, np.int32))
    bad = Candidates(
        np.zeros(1, np.int32), np.array([5], np.int32), np.array([9], np.int32), np.zeros(1)
    )
    with pytest.raises(ValueError, match="candidates.k0"):
        coverage_slices(pos[None], vel[None], np.array([4.8]), bad, *grid)
    bad = bad._replace(k0=np.array([0], np.int32), n=np.array([1], np.int32))
    with pytest.raises(ValueError, match="candidates.n"):
        coverage_slices(pos[None], vel[None], np.array([4.8]), bad, *grid)
    with pytest.raises(ValueError, match="fov_deg"):
        coverage_slices(pos[None], vel[None], np.array([4.8, 1.0]), bad, *grid)


def test_folded_strip_takes_the_direct_sweep():
    """A strip that doubles back (samples in non-adjacent quads) falls back, still exact."""
    pos, vel = _equatorial_states(10.0, 21)
    back = np.r_[np.arange(11), np.arange(9, -1, -1)]  # east for 10 samples, then west
    pos, vel = pos[back], vel[np.zeros(21, int)]
    lon, lat = (a.ravel() for a in np.meshgrid(np.linspace(9.5, 14.0, 60), np.linspace(1, 3, 21)))
    region = np.zeros(lon.size, np.int32)
    cands = Candidates(
        np.zeros(3, np.int32),
        np.array([0, 0, 12], np.int32),
        np.array([21, 8, 8], np.int32),
        np.array([25.0, 25.0, 25.0]),
    )
    cov = coverage_slices(pos[None], vel[None], np.array([4.8]), cands, lon, lat, region)
    assert cov.stats["irregular_runs"] >= 1 and cov.stats["fallback_candidates"] >= 1
    for c in range(3):
        k0, n = cands.k0[c], cands.n[c]
        inner, outer, _ = ref.edges(pos[k0 : k0 + n], vel[k0 : k0 + n], 25.0, 4.8)
        want = ref.covered(inner, outer, lon, lat)
        assert want.size > 0
        np.testing.assert_array_equal(_row(cov, c), want)


# ------------------------------------------------------------------ tracks
@needs_case
def test_earth_fixed_tracks_equal_sgp4_and_gstime():
    """The planner's SGP4 orbit table rotated to the Earth == sgp4 at the same instants:
    to a centimetre at the start (time rounding of the Julian-date split, a microsecond),
    within centimetres over the three days (the test below)."""
    case, sc, _, (pos, vel, t) = _case_and_tracks()
    assert pos.shape == (len(case.satellites), 51841, 3) and t[0] == 0.0 and t[-1] == sc.duration
    for s in (0, len(case.satellites) - 1):
        sat = case.satellites[s]
        ks = np.array([0, 1, 12345, 51840])
        p, v = ref.sgp4_tracks(sat.tle1, sat.tle2, case.start, t[ks])
        np.testing.assert_allclose(pos[s, ks[:2]], p[:2], rtol=0, atol=1e-2)
        np.testing.assert_allclose(vel[s, ks[:2]], v[:2], rtol=0, atol=2e-5)
        drift = 8e-12 * t[ks] * ref.A + 1e-2  # [m] 7.1e-12 rad/s of rotation angle
        assert np.all(np.linalg.norm(pos[s, ks] - p, axis=-1) <= drift)
        np.testing.assert_allclose(pos[s, ks, 2], p[:, 2], rtol=0, atol=1e-2)  # a turn about z


@needs_case
def test_earth_fixed_tracks_to_a_centimetre_over_the_horizon():
    from sgp4.api import jday
    from sgp4.propagation import gstime

    from jaxspline.geometry.frames import earth_rotation_angle

    case, sc, scene, (pos, _, t) = _case_and_tracks()
    st = case.start
    jd, fr = jday(st.year, st.month, st.day, st.hour, st.minute, st.second)
    for k in (12345, 51840):
        th = gstime(jd + fr + t[k] / 86400.0)
        got = float(earth_rotation_angle(float(scene.gmst0), float(t[k])))
        # gstime takes one float Julian date (a 40 us resolution near 2.46e6): 3e-9 rad
        assert abs((got - th + np.pi) % (2 * np.pi) - np.pi) < 5e-9, k
    sat = case.satellites[0]
    p, _ = ref.sgp4_tracks(sat.tle1, sat.tle2, st, t[[12345, 51840]])
    np.testing.assert_allclose(pos[0, [12345, 51840]], p, rtol=0, atol=1e-2)


@needs_case
def test_per_action_coverage_equals_the_independent_checker():
    """The engine's covered sets == those of the regional checker (its own SGP4, frames
    and geometry), for actions on the case's grid."""
    from jaxspline.regional.case import format_time
    from jaxspline.regional.check import check_solution

    case, _, _, (pos, vel, _) = _case_and_tracks()
    cands = _random_candidates(case, pos, 300, seed=6)
    cands = cands._replace(n=(cands.n // 2 * 2 + 1).astype(np.int32))  # 10 s multiples
    ok = np.array(
        [
            case.satellites[s].sensor.min_duration_s
            <= (n - 1) * case.sample_step_s
            <= case.satellites[s].sensor.max_duration_s
            for s, n in zip(cands.sat, cands.n, strict=True)
        ]
    )
    cov = _engine(case, pos, vel, cands)
    pick = np.flatnonzero(ok & (cov.counts() > 0))[:12]
    assert pick.size >= 6
    actions = [
        {
            "type": "strip_observation",
            "satellite_id": case.satellites[cands.sat[c]].id,
            "start_time": format_time(case.time_at(cands.k0[c] * case.sample_step_s)),
            "duration_s": int((cands.n[c] - 1) * case.sample_step_s),
            "roll_deg": float(cands.roll_deg[c]),
        }
        for c in pick
    ]
    rep = check_solution(case, {"actions": actions})
    assert not [v for v in rep.violations if v.rule in ("band", "ray", "geometry", "grid")]
    w = case.grid.weight_m2
    np.testing.assert_allclose(rep.action_covered_m2, cov.gains(w)[pick], rtol=1e-12)
    union = np.zeros(case.grid.size, bool)
    for c in pick:
        union[cov.pool[cov.lo[c] : cov.hi[c]]] = True
    np.testing.assert_array_equal(rep.covered, union)
