"""Peaks of the channel-wise degree-7 join against a numpy brute force.

Reference: the 8 x 8 Hermite system solved in physical time by numpy.linalg.solve and
its derivatives evaluated on 20,001 points (no normalized time, no precomputed inverse).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxspline.kernels.channel_join import channel_join_peaks

DENSE = 20001


def _brute(b0, b1, T):
    """Peaks |p'|, |p''|, |p'''| per channel and of the norms, dense grid."""
    t = np.linspace(0.0, T, DENSE)
    rows = []
    for at in (0.0, T):
        for d in range(4):
            row = np.zeros(8)
            for k in range(d, 8):
                row[k] = np.prod(np.arange(k - d + 1, k + 1)) * at ** (k - d)
            rows.append(row)
    A = np.array(rows)
    out = []
    for c in range(3):
        coef = np.linalg.solve(A, np.r_[b0[:, c], b1[:, c]])
        poly = np.polynomial.Polynomial(coef)
        out.append([poly.deriv(m)(t) for m in (1, 2, 3)])
    d = np.array(out)  # [channel, m, t]
    per = np.abs(d).max(-1).T  # [m, channel]
    norm = np.linalg.norm(d, axis=0).max(-1)  # [m]
    return per, norm


@pytest.mark.parametrize("seed", range(6))
def test_peaks_match_dense_brute_force(seed):
    rng = np.random.default_rng(seed)
    T = float(rng.uniform(5.0, 200.0))
    scale = np.array([0.5, 0.01, 1e-3, 1e-4])[:, None]  # angle, rate, accel, jerk
    b0, b1 = rng.normal(size=(4, 3)) * scale, rng.normal(size=(4, 3)) * scale
    with jax.enable_x64(True):
        pk = channel_join_peaks(*jnp.asarray(b0), *jnp.asarray(b1), jnp.float64(T), n_samples=4001)
    per, norm = _brute(b0, b1, T)
    got_per = np.stack([np.asarray(x) for x in pk[:3]])
    got_norm = np.array([float(x) for x in pk[3:]])
    # 4001 samples against 20,001: the sampled max is below by O((T/n)^2) relatively
    np.testing.assert_allclose(got_per, per, rtol=1e-5)
    np.testing.assert_allclose(got_norm, norm, rtol=1e-5)
    assert np.all(got_per <= per * (1 + 1e-12)) and np.all(got_norm <= norm * (1 + 1e-12))


def test_default_grid_close_and_vmap_agrees():
    rng = np.random.default_rng(7)
    n = 64
    b = rng.normal(size=(n, 8, 3)) * np.array([0.5, 0.01, 1e-3, 1e-4] * 2)[None, :, None]
    T = rng.uniform(5.0, 200.0, n)
    with jax.enable_x64(True):
        batched = jax.jit(jax.vmap(channel_join_peaks))(*jnp.moveaxis(jnp.asarray(b), 1, 0), T)
        for i in range(0, n, 16):
            one = channel_join_peaks(*jnp.asarray(b[i]), jnp.float64(T[i]))
            for x, y in zip(batched, one, strict=True):
                np.testing.assert_allclose(np.asarray(x)[i], np.asarray(y), rtol=1e-12)
    for i in range(0, n, 8):
        per, _ = _brute(b[i, :4], b[i, 4:], T[i])
        got = np.stack([np.asarray(x)[i] for x in batched[:3]])
        assert np.all(got <= per * (1 + 1e-12)) and np.all(got >= 0.97 * per)


def test_nonpositive_duration_is_infinite_not_nan():
    z = jnp.zeros(3)
    for T in (0.0, -1.0):
        pk = channel_join_peaks(z, z, z, z, z + 0.1, z, z, z, jnp.asarray(T))
        assert all(np.all(np.isinf(np.asarray(x))) for x in pk)
    g = jax.grad(lambda T: channel_join_peaks(z, z, z, z, z + 0.1, z, z, z, T).accel_norm)(20.0)
    assert np.isfinite(g) and g < 0  # a longer join needs less acceleration
