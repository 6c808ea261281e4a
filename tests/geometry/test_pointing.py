"""Pointing law: geometry reconstructed in numpy, autodiff vs finite differences, visibility."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxspline.base.elements import (
    GMST_RATE,
    OMEGA_EARTH,
    circular_orbit,
    circular_orbit_over,
    geodetic_to_ecef,
    gmst,
    julian_date,
)
from jaxspline.geometry.orbit import orbit_position, orbit_state
from jaxspline.geometry.pointing import (
    Scene,
    aim_angles,
    aim_params,
    aim_state,
    boresight,
    off_nadir,
    pointing_angles,
    pointing_state,
)
from jaxspline.geometry.windows import visibility_windows

G0 = float(gmst(julian_date("2026-06-21T10:00:00Z")))
ORB = circular_orbit_over(np.radians(46.0), np.radians(15.0), 300.0, G0)
SCENE = Scene(ORB, jnp.asarray(G0))
TARGETS = np.asarray(
    geodetic_to_ecef(
        np.radians([46.3, 44.0, 50.0, 47.0]), np.radians([15.2, 18.5, 11.0, 13.0]), 0.0
    )
)
TIMES = np.array([180.0, 260.0, 300.0, 345.0, 420.0])


def _los_numpy(t, target):
    """Unit LOS in the orbital frame, rebuilt in numpy from position and velocity."""
    r, v = (np.asarray(x) for x in orbit_state(ORB, t))
    th = G0 + GMST_RATE * t
    c, s = np.cos(th), np.sin(th)
    g = np.array([c * target[0] - s * target[1], s * target[0] + c * target[1], target[2]])
    z = -r / np.linalg.norm(r)
    y = -np.cross(r, v)
    y /= np.linalg.norm(y)
    x = np.cross(y, z)
    d = g - r
    d /= np.linalg.norm(d)
    return np.array([d @ x, d @ y, d @ z])


@pytest.mark.parametrize("t", TIMES)
def test_boresight_from_angles_hits_the_target(t):
    ang = np.asarray(pointing_angles(SCENE, TARGETS, t))
    for k, tgt in enumerate(TARGETS):
        b = np.asarray(boresight(ang[k, 0], ang[k, 1]))
        n = _los_numpy(t, tgt)
        err = np.arctan2(np.linalg.norm(np.cross(b, n)), b @ n)
        assert err < 1e-12
        assert float(off_nadir(SCENE, tgt, t)) == pytest.approx(np.arccos(n[2]), abs=1e-9)


def test_nadir_target_has_zero_angles_and_zero_off_nadir():
    t = 300.0
    r = np.asarray(orbit_position(ORB, t))
    th = G0 + GMST_RATE * t
    c, s = np.cos(th), np.sin(th)
    re = np.array([c * r[0] + s * r[1], -s * r[0] + c * r[1], r[2]])
    tgt = re * (6.36e6 / np.linalg.norm(re))
    ang = np.asarray(pointing_angles(SCENE, tgt, t))
    assert abs(ang[0]) < 1e-12 and abs(ang[1]) < 1e-12
    assert float(off_nadir(SCENE, tgt, t)) < 1e-12


def test_yaw_at_equator_matches_classic_yaw_steering():
    # Nadir at the ascending node, no nodal drift: tan(psi) = k sin i / (1 - k cos i), k = w_E / n
    orb = circular_orbit(600e3, j2_drift=False)
    scene = Scene(orb, jnp.asarray(0.0))
    r = np.asarray(orbit_position(orb, 0.0))
    tgt = r * (6.378e6 / np.linalg.norm(r))  # equator, lon 0 (gmst0 = 0, raan = 0)
    yaw = float(pointing_angles(scene, tgt, 0.0)[2])
    k = OMEGA_EARTH / float(orb.mean_motion)
    i = float(orb.inclination)
    ref = np.arctan(k * np.sin(i) / (1 - k * np.cos(i)))
    assert np.degrees(ref) == pytest.approx(3.78, abs=0.01)
    assert abs(yaw) == pytest.approx(ref, abs=1e-9)


def _fd(f, t, h, order):
    """8th-order central finite differences (test-only reference)."""
    c1 = np.array([1 / 280, -4 / 105, 1 / 5, -4 / 5, 0, 4 / 5, -1 / 5, 4 / 105, -1 / 280])
    c2 = np.array([-1 / 560, 8 / 315, -1 / 5, 8 / 5, -205 / 72, 8 / 5, -1 / 5, 8 / 315, -1 / 560])
    vals = np.stack([np.asarray(f(t + k * h)) for k in range(-4, 5)])
    c = c1 if order == 1 else c2
    return np.tensordot(c, vals, axes=(0, 0)) / h**order


_ANGLES = jax.jit(lambda p, t0, t: aim_angles(SCENE, p, t0, t)[:3])
_STATE = jax.jit(lambda p, t0, t: aim_state(SCENE, p, t0, t)[:3])


@pytest.mark.parametrize("kind", ["point", "strip"])
def test_autodiff_rates_match_finite_differences(kind):
    tgt = jnp.asarray(TARGETS[0])
    if kind == "point":
        p = aim_params(tgt)
    else:
        p = aim_params(tgt, jnp.asarray([0.1, -0.3, -0.9]), 4000.0)
    t0 = jnp.asarray(250.0)

    def f(t):
        return _ANGLES(p, t0, jnp.asarray(t))

    for t in (255.0, 290.0, 310.0):
        _, rate, acc = (np.asarray(x) for x in _STATE(p, t0, jnp.asarray(t)))
        np.testing.assert_allclose(rate, _fd(f, t, 0.5, 1), rtol=1e-7, atol=1e-11)
        np.testing.assert_allclose(acc, _fd(f, t, 1.0, 2), rtol=1e-5, atol=1e-10)
    if kind == "point":  # the public wrapper gives the same derivatives
        _, r2, a2 = pointing_state(SCENE, TARGETS[0], 290.0)
        np.testing.assert_allclose(r2, _STATE(p, t0, jnp.asarray(290.0))[1], rtol=1e-12)


def test_scalar_jit_vmap_agree():
    ang_batch = np.asarray(pointing_angles(SCENE, TARGETS[:, None, :], TIMES[None, :]))
    for k in range(TARGETS.shape[0]):
        for j, t in enumerate(TIMES):
            np.testing.assert_allclose(
                pointing_angles(SCENE, TARGETS[k], t), ang_batch[k, j], rtol=1e-13, atol=1e-15
            )
    p = aim_params(jnp.asarray(TARGETS))
    vm = jax.jit(jax.vmap(lambda pp, t: aim_angles(SCENE, pp, 0.0, t)[:3], in_axes=(0, None)))
    np.testing.assert_allclose(vm(p, 300.0), ang_batch[:, 2], rtol=1e-13, atol=1e-15)


def test_float32_follows_dtype():
    scene32 = jax.tree.map(lambda x: jnp.asarray(x, jnp.float32), SCENE)
    a32 = pointing_angles(scene32, jnp.asarray(TARGETS, jnp.float32), jnp.float32(300.0))
    assert a32.dtype == jnp.float32
    a64 = pointing_angles(SCENE, TARGETS, 300.0)
    np.testing.assert_allclose(a32, a64, atol=2e-5)


def test_visibility_windows_match_dense_sampling():
    lim = np.radians(30.0)
    wins = visibility_windows(SCENE, TARGETS, 0.0, 600.0, lim, step=10.0)
    dense = np.arange(0.0, 600.0, 0.25)
    offn = np.asarray(off_nadir(SCENE, TARGETS[:, None, :], dense[None, :]))
    for k, w in enumerate(wins):
        inside = offn[k] <= lim
        if not inside.any():
            assert w.shape[0] == 0
            continue
        assert w.shape[0] == 1
        assert w[0, 0] == pytest.approx(dense[inside][0], abs=0.25)
        assert w[0, 1] == pytest.approx(dense[inside][-1], abs=0.25)
        for t in w[0]:
            assert float(off_nadir(SCENE, TARGETS[k], t)) == pytest.approx(lim, abs=1e-9)


def test_target_behind_the_earth_is_never_visible():
    # nearly antipodal to the sub-satellite point: the LOS passes through the Earth near nadir
    far = np.asarray(geodetic_to_ecef(np.radians(-46.0), np.radians(15.0 - 180.0), 0.0))
    assert float(off_nadir(SCENE, far, 300.0)) == pytest.approx(np.pi)
    assert visibility_windows(SCENE, far[None], 0.0, 600.0, np.radians(45.0))[0].shape == (0, 2)
    p = aim_params(jnp.asarray(far))
    assert float(aim_angles(SCENE, p, 0.0, 300.0)[3]) == pytest.approx(np.pi)


def test_value_errors():
    with pytest.raises(ValueError, match="target_ecef"):
        pointing_angles(SCENE, np.zeros(2), 0.0)
    with pytest.raises(ValueError, match="t must be finite"):
        pointing_angles(SCENE, TARGETS[0], np.nan)
    with pytest.raises(ValueError, match="max_off_nadir"):
        visibility_windows(SCENE, TARGETS, 0.0, 10.0, -1.0)
    with pytest.raises(ValueError, match="t_end"):
        visibility_windows(SCENE, TARGETS, 10.0, 0.0, 0.5)
