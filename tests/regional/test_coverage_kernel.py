"""Strip-coverage engine and solver tracks against independent references.

References: shapely's point-in-polygon (``bench.coverage_baseline``, its own numpy edge
points), direct per-candidate sweeps (no runs, pieces or tiles) for the sub-strip
equivalence, sgp4's scalar ``Satrec.sgp4`` with sgp4's own ``gstime`` for the tracks,
the aeossp checker's independent Sun/shadow model for the sunlit flags.
"""

from __future__ import annotations

import functools
import math
from datetime import UTC, datetime
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from bench.coverage_baseline import covered_baseline, edges_np
from jaxspline.geometry.frames import OMEGA_EARTH, R_EARTH, angle_between, ecef_to_geodetic
from jaxspline.screen.coverage import (
    Candidates,
    coverage_slices,
    covered_samples,
    strip_quads,
)
from jaxspline.screen.coverage_kernels import WGS84_B, edge_points, look_point, quad_range

CASE = Path("/work/shared/data/regional_coverage/train/case_0004")
needs_case = pytest.mark.skipif(not CASE.is_dir(), reason="benchmark data not present")


@functools.lru_cache(maxsize=1)
def _case_and_tracks():
    from jaxspline.geometry.coverage_tracks import build_tracks
    from jaxspline.regional.case import load_case

    case = load_case(CASE)
    return case, build_tracks(case)


def _fov(case):
    return np.array([s.sensor.fov_deg for s in case.satellites])


def _near_samples(case, tr, max_deg=6.0):
    """(sat, k) where the sub-satellite point is within max_deg of a region's centre."""
    g = case.grid
    cen = []
    for r in range(len(case.regions)):
        la, lo = np.radians(g.lat_deg[g.region == r]), np.radians(g.lon_deg[g.region == r])
        v = np.stack([np.cos(la) * np.cos(lo), np.cos(la) * np.sin(lo), np.sin(la)], -1).mean(0)
        cen.append(v / np.linalg.norm(v))
    u = tr.pos / np.linalg.norm(tr.pos, axis=-1, keepdims=True)
    return np.argwhere((u @ np.array(cen).T).max(-1) > math.cos(math.radians(max_deg)))


def _random_candidates(case, tr, c, seed):
    rng = np.random.default_rng(seed)
    near = _near_samples(case, tr)
    pick = near[rng.integers(0, len(near), c)]
    n = rng.integers(2, 19, c) * 2 + 1
    k0 = np.clip((pick[:, 1] - rng.integers(0, 30, c)) // 2 * 2, 0, tr.n_samples - n - 1)
    sat = pick[:, 0]
    lo = np.array([s.sensor.min_edge_deg + s.sensor.fov_deg / 2 for s in case.satellites])[sat]
    hi = np.array([s.sensor.max_edge_deg - s.sensor.fov_deg / 2 for s in case.satellites])[sat]
    roll = np.round(rng.uniform(lo, hi) * 4) / 4 * rng.choice([-1.0, 1.0], c)
    return Candidates(sat.astype(np.int32), k0.astype(np.int32), n.astype(np.int32), roll)


def _engine(case, tr, cands):
    g = case.grid
    return coverage_slices(tr.pos, tr.vel, _fov(case), cands, g.lon_deg, g.lat_deg, g.region)


def _row(cov, c):
    return np.sort(cov.pool[cov.lo[c] : cov.hi[c]].astype(np.int64))


# ------------------------------------------------------------------ engine vs shapely
@needs_case
def test_engine_equals_shapely_baseline_on_random_candidates():
    case, tr = _case_and_tracks()
    cands = _random_candidates(case, tr, 250, seed=1)
    cov = _engine(case, tr, cands)
    g, fov = case.grid, _fov(case)
    nonempty = 0
    for c in range(cands.sat.size):
        s, k0, n, r = cands.sat[c], cands.k0[c], cands.n[c], cands.roll_deg[c]
        inner, outer, hit = edges_np(tr.pos[s, k0 : k0 + n], tr.vel[s, k0 : k0 + n], r, fov[s])
        assert cov.valid[c] == hit.all()
        ref = covered_baseline(inner, outer, g.lon_deg, g.lat_deg)
        np.testing.assert_array_equal(_row(cov, c), ref, err_msg=f"candidate {c}")
        nonempty += ref.size > 0
    assert nonempty >= 25  # the comparison is not vacuous
    assert np.all(cov.counts() >= 0)
    tab = cov.csr(10, 60)
    np.testing.assert_array_equal(tab.valid, cov.valid[10:60])
    for i, c in enumerate(range(10, 60)):
        np.testing.assert_array_equal(
            np.sort(tab.indices[tab.indptr[i] : tab.indptr[i + 1]]), _row(cov, c)
        )


@needs_case
def test_sub_strips_of_one_sweep_equal_direct_sweeps():
    """Every (k0, n) of one (satellite, roll): engine slices == direct sweeps of the strip."""
    case, tr = _case_and_tracks()
    g, fov = case.grid, _fov(case)
    probe = _random_candidates(case, tr, 300, seed=2)
    cov = _engine(case, tr, probe)
    best = int(np.argmax(cov.counts()))
    s, roll = int(probe.sat[best]), float(probe.roll_deg[best])
    base = int(probe.k0[best]) - 20
    k0, n = np.meshgrid(np.arange(base, base + 40, 6), np.arange(2, 38, 7), indexing="ij")
    k0, n = k0.ravel(), n.ravel()
    cands = Candidates(
        np.full(k0.size, s, np.int32),
        k0.astype(np.int32),
        n.astype(np.int32),
        np.full(k0.size, roll),
    )
    cov = _engine(case, tr, cands)
    inner, outer, _ = strip_quads(
        tr.pos[s, base : base + 80], tr.vel[s, base : base + 80], roll, fov[s]
    )
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
    case, tr = _case_and_tracks()
    cands = _random_candidates(case, tr, 200, seed=3)
    cov = _engine(case, tr, cands)
    w = np.random.default_rng(0).uniform(0, 1, case.grid.size)
    want = np.array([w[cov.pool[cov.lo[c] : cov.hi[c]]].sum() for c in range(200)])
    np.testing.assert_allclose(cov.gains(w), want, rtol=1e-12, atol=1e-9)


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
    want = covered_baseline(inner, outer, pts[:, 0], pts[:, 1])
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
    np.testing.assert_array_equal(covered_baseline(i2, o2, p2[:, 0], p2[:, 1]), [0, 1])


def _equatorial_states(lon0_deg, n, step_s=5.0, alt=520e3, eastward=True):
    """Synthetic Earth-fixed states over the equator (a straight track along it)."""
    r = R_EARTH + alt
    rate = 7300.0 / r * (1 if eastward else -1)  # rad/s ground-relative
    lam = np.radians(lon0_deg) + rate * step_s * np.arange(n)
    pos = r * np.stack([np.cos(lam), np.sin(lam), np.zeros(n)], -1)
    vel = 7300.0 * np.sign(rate) * np.stack([-np.sin(lam), np.cos(lam), np.zeros(n)], -1)
    return pos, vel


def test_engine_across_the_antimeridian_and_negative_roll():
    pos, vel = _equatorial_states(178.0, 200)
    lon1 = np.concatenate([np.linspace(179.0, 180.0, 40), np.linspace(-180.0, -179.0, 40)])
    lon, lat = (a.ravel() for a in np.meshgrid(lon1, np.linspace(-4.0, 4.0, 33)))
    region = np.zeros(lon.size, np.int32)
    cands = Candidates(
        np.zeros(4, np.int32),
        np.array([0, 0, 2, 2], np.int32),
        np.array([120, 120, 30, 30], np.int32),
        np.array([25.0, -25.0, 25.0, -25.0]),
    )
    cov = coverage_slices(pos[None], vel[None], np.array([4.8]), cands, lon, lat, region)
    for c in range(4):
        k0, n, r = cands.k0[c], cands.n[c], cands.roll_deg[c]
        inner, outer, hit = edges_np(pos[k0 : k0 + n], vel[k0 : k0 + n], r, 4.8)
        ref = covered_baseline(inner, outer, lon, lat)
        assert ref.size > 0 and np.ptp(lon[ref]) > 300  # both sides of the antimeridian
        np.testing.assert_array_equal(_row(cov, c), ref)
        # eastward motion: across = along x nadir points north, so roll > 0 looks north
        assert np.all(np.sign(lat[ref]) == np.sign(r))


# ------------------------------------------------------------------ kernel properties
_look_batch = jax.jit(jax.vmap(look_point, (0, 0, None)))


def test_look_point_geometry():
    rng = np.random.default_rng(4)
    pos, vel = _equatorial_states(10.0, 3)
    pos = pos + rng.normal(0, 1e5, pos.shape)
    vel = vel + rng.normal(0, 50, vel.shape)
    for look in (-40.0, -17.5, 0.0, 3.0, 33.3):
        lon, lat, hit = _look_batch(jnp.asarray(pos), jnp.asarray(vel), look)
        assert bool(jnp.all(hit))
        la, lo = np.radians(np.asarray(lat)), np.radians(np.asarray(lon))
        nrm = R_EARTH / np.sqrt(1 - (1 - (WGS84_B / R_EARTH) ** 2) * np.sin(la) ** 2)
        g = np.stack(
            [
                nrm * np.cos(la) * np.cos(lo),
                nrm * np.cos(la) * np.sin(lo),
                nrm * (WGS84_B / R_EARTH) ** 2 * np.sin(la),
            ],
            -1,
        )
        ray = g - pos
        np.testing.assert_allclose(np.degrees(angle_between(-pos, ray)), abs(look), atol=1e-7)
        along = vel - np.sum(vel * pos, -1, keepdims=True) * pos / np.sum(
            pos * pos, -1, keepdims=True
        )
        np.testing.assert_allclose(
            np.sum(ray * along, -1) / np.linalg.norm(ray, axis=-1) / np.linalg.norm(along, axis=-1),
            0.0,
            atol=1e-9,
        )
        glat, glon, gh = ecef_to_geodetic(g)
        np.testing.assert_allclose(np.abs(gh), 0.0, atol=1e-6)


def test_miss_is_a_value_and_values_are_finite():
    pos = jnp.array([7.0e6, 0.0, 0.0])
    vel = jnp.array([0.0, 7.5e3, 0.0])
    lon, lat, hit = jax.jit(look_point)(pos, vel, 80.0)  # beyond the limb
    assert not bool(hit) and np.isfinite(float(lon)) and np.isfinite(float(lat))
    inner, outer, hit = jax.jit(edge_points)(pos, vel, 75.0, 10.0)
    assert (
        not bool(hit)
        and np.all(np.isfinite(np.asarray(inner)))
        and np.all(np.isfinite(np.asarray(outer)))
    )


def test_jit_vmap_agree_with_single_item_calls():
    rng = np.random.default_rng(5)
    pos, vel = _equatorial_states(-60.0, 4)
    pos = pos + rng.normal(0, 5e4, pos.shape)
    rolls = rng.uniform(-35, 35, 4)
    batched = jax.jit(jax.vmap(edge_points, (0, 0, 0, None)))(pos, vel, rolls, 4.8)
    for k in range(4):
        single = jax.jit(edge_points)(jnp.asarray(pos[k]), jnp.asarray(vel[k]), rolls[k], 4.8)
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


# ------------------------------------------------------------------ tracks
@needs_case
def test_tracks_equal_scalar_sgp4_and_gstime():
    from sgp4.api import WGS84, Satrec, jday
    from sgp4.propagation import gstime

    case, tr = _case_and_tracks()
    assert tr.pos.shape == (len(case.satellites), 51841, 3) and tr.ok.all()
    for s in (0, len(case.satellites) - 1):
        sat = case.satellites[s]
        rec = Satrec.twoline2rv(sat.tle1, sat.tle2, WGS84)
        for k in (0, 1, 12345, 51840):
            t = case.start.timestamp() + 5.0 * k
            when = datetime.fromtimestamp(t, UTC)
            jd, fr = jday(when.year, when.month, when.day, when.hour, when.minute, when.second)
            err, r, v = rec.sgp4(jd, fr)
            assert err == 0
            th = gstime(jd + fr)
            c, sn = math.cos(th), math.sin(th)
            rot = np.array([[c, sn, 0.0], [-sn, c, 0.0], [0.0, 0.0, 1.0]])
            p = rot @ (np.array(r) * 1e3)
            vv = rot @ (np.array(v) * 1e3) - np.cross([0.0, 0.0, OMEGA_EARTH], p)
            np.testing.assert_allclose(tr.pos[s, k], p, atol=1e-3)  # mm (jd split rounding)
            np.testing.assert_allclose(tr.vel[s, k], vv, atol=1e-5)


@needs_case
def test_sunlit_flags_agree_with_the_aeossp_shadow_model():
    """Against the checkers' Sun/GCRF/cylinder model: only single samples at transitions."""
    from jaxspline.aeossp import check_frames as cf
    from jaxspline.geometry.coverage_tracks import propagate_teme, sunlit_at

    case, tr = _case_and_tracks()
    tles = [(s.tle1, s.tle2) for s in case.satellites]
    np.testing.assert_array_equal(sunlit_at(tles, case.start, tr.t_s[::37]), tr.sunlit[:, ::37])
    t = tr.t_s
    r, _, _ = propagate_teme(tles[:1], case.start, t)
    unix = case.start.timestamp() + t
    r_gcrf = np.einsum("tij,tj->ti", cf.ecef_to_gcrf_matrix(unix), cf.teme_to_ecef(r[0], unix))
    ref = cf.sunlit(r_gcrf, unix)
    diff = np.flatnonzero(ref != tr.sunlit[0])
    assert diff.size < 1e-3 * t.size
    assert np.all(np.diff(diff) > 1)  # isolated samples
    assert np.all(ref[diff - 1] != ref[diff + 1])  # each one next to a transition
    assert 0.5 < tr.sunlit.mean() < 0.95


@needs_case
def test_per_action_coverage_equals_the_independent_checker():
    """The engine's covered sets == those of R1's checker (its own SGP4/frames/geometry)."""
    from jaxspline.regional.case import format_time
    from jaxspline.regional.check import check_solution

    case, tr = _case_and_tracks()
    cands = _random_candidates(case, tr, 300, seed=6)
    cands = cands._replace(n=(cands.n // 2 * 2 + 1).astype(np.int32))  # 10 s multiples
    ok = np.array(
        [
            case.satellites[s].sensor.min_duration_s
            <= (n - 1) * case.sample_step_s
            <= case.satellites[s].sensor.max_duration_s
            for s, n in zip(cands.sat, cands.n, strict=True)
        ]
    )
    cov = _engine(case, tr, cands)
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
        inner, outer, _ = edges_np(pos[k0 : k0 + n], vel[k0 : k0 + n], 25.0, 4.8)
        ref = covered_baseline(inner, outer, lon, lat)
        assert ref.size > 0
        np.testing.assert_array_equal(_row(cov, c), ref)
