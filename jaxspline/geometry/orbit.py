"""Orbit models: circular (J2-drifting) orbits, TLE propagation (SGP4), tabulated orbits.

Positions are in ECI = TEME (the frame of SGP4; see :mod:`jaxspline.geometry.frames` for the
Earth-fixed rotation, WGS84 and the Sun). Two models serve the pointing kernels:

* :class:`CircularOrbit` - analytic circular orbit with secular J2 nodal regression;
* :class:`HermiteOrbit` - a table of (r, v, a) at equally spaced knots, interpolated by
  quintic Hermite pieces (C2 in t). It is exact at the knots, so a table whose knots
  lie on a scenario's geometry grid reproduces SGP4 there to the last bit. A table
  may hold several satellites (``r`` of shape [S, M, 3]); kernels then take the
  satellite index ``sat`` (:func:`orbit_state`).

:func:`tabulate_orbits` builds one table for a whole constellation (TLEs through the
``sgp4`` package's vectorized ``SatrecArray``, circular orbits analytically).

Units: metres, seconds, radians. Times ``t`` are seconds from a scenario epoch,
whose Julian date (UTC) is carried separately.

References: vector-spline paper (seeds/vector-spline-guidance-laws, example data:
600 km Sun-synchronous orbit); Vallado, *Fundamentals of Astrodynamics* (J2 nodal
regression, SSO inclination).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.base.elements import (
    J2_EARTH,
    MU_EARTH,
    R_EARTH,
    SECONDS_PER_DAY,
    CircularOrbit,
    jd_split,
    parse_tle,
)
from jaxspline.kernels.validate import check_positive, to_device

__all__ = [
    "HermiteOrbit",
    "padded_orbit",
    "orbit_position",
    "orbit_state",
    "propagate_tle",
    "tle_orbit",
    "OrbitTable",
    "orbit_period",
    "tabulate_orbits",
]

_KM = 1e3


class HermiteOrbit(NamedTuple):
    """A tabulated orbit, interpolated by quintic Hermite pieces (C2 in t).

    Attributes:
      t: knot times [M] [s], equally spaced.
      r, v, a: position [M, 3] [m], velocity [M, 3] [m/s], acceleration [M, 3] [m/s^2]
        at the knots (from SGP4; accelerations from the two-body + J2 model).
      n: knots in use (int scalar; the tables beyond are padding, never read), or None
        for all M (:func:`padded_orbit`).

    Between knots the position is the unique quintic matching r, v, a at both ends,
    so the interpolant and its first two derivatives are continuous. Outside the
    knot range the end pieces are extrapolated (keep the scenario inside the table).
    """

    t: jnp.ndarray
    r: jnp.ndarray
    v: jnp.ndarray
    a: jnp.ndarray
    n: jnp.ndarray | None = None


def padded_orbit(orb: HermiteOrbit, min_knots: int = 64) -> HermiteOrbit:
    """A multi-satellite table ([S, M, 3]) padded to power-of-two S and M (M at least
    ``min_knots``), with ``n`` = M: the same interpolation, one compiled shape for
    every table of the same sizes (programs take the orbit as an argument).

    Args:
      orb: HermiteOrbit with [S, M, 3] tables and ``n`` None.
      min_knots: fewest knots of the padded table.
    Returns:
      HermiteOrbit (JAX arrays).
    """
    s, m = np.shape(orb.r)[:2]
    s2 = 1 << (s - 1).bit_length()
    m2 = max(min_knots, 1 << (m - 1).bit_length())
    tab = [np.pad(np.asarray(x), [(0, s2 - s), (0, m2 - m), (0, 0)]) for x in orb[1:4]]
    t = np.pad(np.asarray(orb.t), (0, m2 - m), mode="edge")
    return HermiteOrbit(*(to_device(x) for x in (t, *tab, np.int32(m))))


def _circular_position(orb: CircularOrbit, t):
    u = orb.arg_lat + orb.mean_motion * t
    w = orb.raan + orb.raan_rate * t
    cu, su, cw, sw = jnp.cos(u), jnp.sin(u), jnp.cos(w), jnp.sin(w)
    ci, si = jnp.cos(orb.inclination), jnp.sin(orb.inclination)
    return orb.radius * jnp.stack([cw * cu - sw * ci * su, sw * cu + cw * ci * su, si * su], -1)


def _circular_velocity(orb: CircularOrbit, t):
    u = orb.arg_lat + orb.mean_motion * t
    w = orb.raan + orb.raan_rate * t
    cu, su, cw, sw = jnp.cos(u), jnp.sin(u), jnp.cos(w), jnp.sin(w)
    ci, si = jnp.cos(orb.inclination), jnp.sin(orb.inclination)
    du = jnp.stack([-cw * su - sw * ci * cu, -sw * su + cw * ci * cu, si * cu], -1)
    dw = jnp.stack([-sw * cu - cw * ci * su, cw * cu - sw * ci * su, jnp.zeros_like(su)], -1)
    return orb.radius * (orb.mean_motion * du + orb.raan_rate * dw)


def _hermite_basis(orb: HermiteOrbit, t, deriv: bool, sat=None):
    t = jnp.asarray(t)
    h = orb.t[1] - orb.t[0]
    last = orb.t.shape[0] - 2 if orb.n is None else orb.n - 2
    k = jnp.clip(jnp.floor((t - orb.t[0]) / h).astype(jnp.int32), 0, last)
    s = ((t - orb.t[k]) / h)[..., None]
    s2, s3, s4 = s**2, s**3, s**4
    if deriv:  # d/ds of the quintic Hermite basis, then d/dt = (1/h) d/ds
        b = (
            (-30 * s2 + 60 * s3 - 30 * s4) / h,
            1 - 18 * s2 + 32 * s3 - 15 * s4,
            (s - 4.5 * s2 + 6 * s3 - 2.5 * s4) * h,
            (30 * s2 - 60 * s3 + 30 * s4) / h,
            -12 * s2 + 28 * s3 - 15 * s4,
            (1.5 * s2 - 4 * s3 + 2.5 * s4) * h,
        )
    else:
        s5 = s**5
        b = (
            1 - 10 * s3 + 15 * s4 - 6 * s5,
            (s - 6 * s3 + 8 * s4 - 3 * s5) * h,
            (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * h**2,
            10 * s3 - 15 * s4 + 6 * s5,
            (-4 * s3 + 7 * s4 - 3 * s5) * h,
            (0.5 * s3 - s4 + 0.5 * s5) * h**2,
        )
    if sat is None:
        r0, v0, a0, r1, v1, a1 = (
            orb.r[k],
            orb.v[k],
            orb.a[k],
            orb.r[k + 1],
            orb.v[k + 1],
            orb.a[k + 1],
        )
    else:
        r0, v0, a0 = orb.r[sat, k], orb.v[sat, k], orb.a[sat, k]
        r1, v1, a1 = orb.r[sat, k + 1], orb.v[sat, k + 1], orb.a[sat, k + 1]
    return b[0] * r0 + b[1] * v0 + b[2] * a0 + b[3] * r1 + b[4] * v1 + b[5] * a1


def orbit_position(orbit, t, sat=None):
    """Satellite position in ECI (TEME) at times t; differentiable in t.

    Args:
      orbit: CircularOrbit or HermiteOrbit.
      t: float [...], seconds from the epoch.
      sat: int [...] broadcastable with t, selects the satellite of a multi-satellite
        :class:`HermiteOrbit`; None for a single orbit.
    Returns:
      float [..., 3], position [m].
    Raises:
      ValueError: orbit is neither a CircularOrbit nor a HermiteOrbit.
    """
    if isinstance(orbit, HermiteOrbit):
        return _hermite_basis(orbit, t, False, sat)
    if isinstance(orbit, CircularOrbit):
        return _circular_position(orbit, t)
    raise ValueError(f"orbit must be a CircularOrbit or HermiteOrbit, got {type(orbit).__name__}")


def orbit_state(orbit, t, sat=None):
    """Position and velocity in ECI at times t.

    The velocity is the analytic time derivative of :func:`orbit_position` (so that
    pointing kernels need no nested autodiff for it); differentiable in t.

    Args:
      orbit: CircularOrbit or HermiteOrbit.
      t: float [...], seconds from the epoch.
      sat: as in :func:`orbit_position`.
    Returns:
      (position float [..., 3] [m], velocity float [..., 3] [m/s]).
    Raises:
      ValueError: orbit is neither a CircularOrbit nor a HermiteOrbit.
    """
    if isinstance(orbit, HermiteOrbit):
        return _hermite_basis(orbit, t, False, sat), _hermite_basis(orbit, t, True, sat)
    if isinstance(orbit, CircularOrbit):
        return _circular_position(orbit, t), _circular_velocity(orbit, t)
    raise ValueError(f"orbit must be a CircularOrbit or HermiteOrbit, got {type(orbit).__name__}")


def propagate_tle(line1: str, line2: str, jd, fr=0.0, gravity: str = "wgs84"):
    """Propagate one TLE with SGP4 (vectorized ``SatrecArray.sgp4``) on numpy arrays.

    Args:
      line1: first TLE line.
      line2: second TLE line.
      jd: integer-ish part of the Julian date (array, UTC).
      fr: fractional part of the Julian date (array).
      gravity: geopotential constants, "wgs84" (default) or "wgs72".
    Returns:
      (r [..., 3] [m], v [..., 3] [m/s], error [...] int) in TEME; error != 0 marks
      SGP4 failures (decayed orbit, etc.), as in the ``sgp4`` package.
    """
    from sgp4.api import SatrecArray

    sat = parse_tle(line1, line2, gravity=gravity)
    jd = np.atleast_1d(np.asarray(jd, dtype=np.float64))
    fr = np.broadcast_to(np.asarray(fr, dtype=np.float64), jd.shape)
    shape = jd.shape
    e, r, v = SatrecArray([sat]).sgp4(jd.ravel(), np.ascontiguousarray(fr.ravel()))
    return r[0].reshape(*shape, 3) * _KM, v[0].reshape(*shape, 3) * _KM, e[0].reshape(shape)


def _gravity_j2(r):
    rn = np.linalg.norm(r, axis=-1, keepdims=True)
    z2 = (r[..., 2:3] / rn) ** 2
    k = 1.5 * J2_EARTH * (R_EARTH / rn) ** 2
    fac = np.concatenate([1 + k * (1 - 5 * z2), 1 + k * (1 - 5 * z2), 1 + k * (3 - 5 * z2)], -1)
    return -MU_EARTH * r / rn**3 * fac


def tle_orbit(line1: str, line2: str, epoch_jd: float, t_end: float, step: float = 20.0):
    """Tabulate one TLE with SGP4 on [-step, t_end + step] s from ``epoch_jd``.

    Knots every ``step`` seconds; knot accelerations from the two-body + J2 field,
    so the interpolant is a differentiable JAX function of t. Interpolation error
    against SGP4 is below 1 m for step <= 30 s at LEO.

    Args:
      line1: TLE line 1.
      line2: TLE line 2.
      epoch_jd: float, Julian date of t = 0 [days].
      t_end: float, end of the span [s from the epoch].
      step: float, knot spacing [s].
    Returns:
      HermiteOrbit (one satellite).
    Raises:
      ValueError: the lines cannot be parsed or SGP4 reports an error in the span.
    """
    check_positive("t_end", t_end)
    check_positive("step", step)
    m = int(np.ceil(t_end / step)) + 3
    t = -step + step * np.arange(m)
    jd, fr = jd_split(epoch_jd, t)
    r, v, err = propagate_tle(line1, line2, jd, fr)
    if np.any(err != 0):
        raise ValueError(f"tle: SGP4 error code {int(err[err != 0][0])} within the scenario span")
    return HermiteOrbit(*(to_device(x) for x in (t, r, v, _gravity_j2(r))))


@jax.jit
def _circular_knots(orb: CircularOrbit, t):
    r = _circular_position(orb, t)
    v, a = jax.jvp(lambda x: _circular_velocity(orb, x), (t,), (jnp.ones_like(t),))
    return r, v, a


def _circular_table(orb: CircularOrbit, t):
    """(r, v, a) [M, 3] of a circular orbit at knots t [M]; a = dv/dt by forward autodiff.

    One compiled program per knot count (run op by op, the same arithmetic compiled
    some seventy programs of one operation each, per knot count).
    """
    r, v, a = _circular_knots(orb, jnp.asarray(t, jnp.float64))
    return np.asarray(r), np.asarray(v), np.asarray(a)


class OrbitTable(NamedTuple):
    """A constellation tabulated on common knots (the output of :func:`tabulate_orbits`).

    Attributes:
      orbit: :class:`HermiteOrbit` with r, v, a of shape [S, M, 3] (knot times t [M]).
      ok: bool [S, M], SGP4 returned without error at the knot (always True for
        circular orbits); positions at failed knots are copied from the nearest good
        knot so that the table stays finite, and callers must not use times whose
        bracketing knots are not both ok (see :meth:`usable`).
    """

    orbit: HermiteOrbit
    ok: np.ndarray

    def usable(self, sat, t):
        """True where time t of satellite ``sat`` lies between two good knots (numpy).

        Args:
          sat: int [...], satellite indices.
          t: float [...], seconds from the epoch.
        Returns:
          bool [...].
        """
        tk = np.asarray(self.orbit.t)
        h = tk[1] - tk[0]
        k = np.clip(
            np.floor((np.asarray(t, np.float64) - tk[0]) / h).astype(np.int64), 0, tk.size - 2
        )
        return self.ok[sat, k] & self.ok[sat, k + 1]


def orbit_period(source) -> float:
    """The orbital period of a satellite [s]: ``86400 / n`` from a TLE's mean motion ``n``
    [rev/day] (line 2, columns 53-63), or ``2 pi / n`` of a circular orbit.

    Args:
      source: :class:`CircularOrbit` or the two TLE lines ``(line1, line2)``.
    Returns:
      float [s].
    """
    if isinstance(source, CircularOrbit):
        return float(2.0 * math.pi / float(source.mean_motion))
    return SECONDS_PER_DAY / float(source[1][52:63])


def tabulate_orbits(sources, epoch_jd: float, t_end: float, step: float) -> OrbitTable:
    """One :class:`HermiteOrbit` table for S satellites, knots ``t_k = k step`` for k = -1..n+1.

    Args:
      sources: list of S orbit sources, each a :class:`CircularOrbit` or a pair of TLE
        lines ``(line1, line2)`` (propagated with SGP4, WGS84 constants, all TLEs in one
        vectorized ``SatrecArray`` call).
      epoch_jd: Julian date (UTC) of t = 0.
      t_end: last time [s] the table must cover.
      step: knot spacing [s]; put it on the scenario's geometry grid so that every grid
        instant is a knot (then positions there are SGP4's own values).
    Returns:
      :class:`OrbitTable`. Raises ValueError naming the satellite for a malformed TLE.
    """
    check_positive("t_end", t_end)
    check_positive("step", step)
    n = int(math.ceil(t_end / step - 1e-9)) + 1
    t = step * np.arange(-1, n + 1, dtype=np.float64)
    m, s_count = t.size, len(sources)
    r = np.zeros((s_count, m, 3))
    v = np.zeros((s_count, m, 3))
    ok = np.ones((s_count, m), bool)
    tle_idx = [i for i, src in enumerate(sources) if not isinstance(src, CircularOrbit)]
    circ = {
        i: _circular_table(src, t)
        for i, src in enumerate(sources)
        if isinstance(src, CircularOrbit)
    }
    for i, (ri, vi, _) in circ.items():
        r[i], v[i] = ri, vi
    if tle_idx:
        from sgp4.api import SatrecArray

        sats = [parse_tle(*sources[i], who=f"satellite {i}: tle") for i in tle_idx]
        jd, fr = jd_split(epoch_jd, t)
        err, rr, vv = SatrecArray(sats).sgp4(jd, fr)
        good = (err == 0) & np.all(np.isfinite(rr), axis=-1)
        for row, i in enumerate(tle_idx):
            g = good[row]
            if not g.any():
                raise ValueError(f"satellite {i}: SGP4 fails over the whole horizon (decayed?)")
            near = _nearest_good(g)
            r[i], v[i], ok[i] = rr[row][near] * _KM, vv[row][near] * _KM, g
    a = _gravity_j2(r)
    for i, (_, _, ai) in circ.items():
        a[i] = ai
    return OrbitTable(HermiteOrbit(*(to_device(x) for x in (t, r, v, a))), ok)


def _nearest_good(good: np.ndarray) -> np.ndarray:
    """Index of the nearest True entry of ``good`` for every position."""
    idx = np.flatnonzero(good)
    pos = np.clip(np.searchsorted(idx, np.arange(good.size)), 0, idx.size - 1)
    left = idx[np.maximum(pos - 1, 0)]
    right = idx[pos]
    here = np.arange(good.size)
    return np.where(np.abs(here - left) <= np.abs(right - here), left, right)
