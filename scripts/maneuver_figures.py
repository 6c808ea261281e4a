"""Spatial maneuver example of seed vector-spline-guidance-laws and its figures.

Scenario (the paper's data, with a self-contained geometry stated here):

* Circular Sun-synchronous orbit, altitude 600 km (i from the J2 node rate),
  spherical ROTATING Earth (R = 6371 km, ω_E = 7.292115e-5 rad/s); the inertial
  and Earth-fixed frames coincide at t = 0, the time of the ascending node,
  whose longitude is 29.5°.
* Route 1 (track imaging, t = 580–600 s): attitude fixed in the orbital frame
  (x along track, z nadir, y = z × x) rolled by 10° about x, pitch 0, yaw 0.
* Route 2 (image-motion-aligned scan, t = 633–653 s): the boresight (body z)
  tracks a ground point that starts at L = 18.11°, B = 39.68° and moves along
  the great circle of azimuth 10° at the sub-satellite ground speed n·R
  (Earth-fixed); body x is the strip direction projected perpendicular to the
  line of sight (image motion along the TDI columns, no transverse drift).
* Maneuver: t = 600–633 s (T = 33 s), ω_max = 2°/s, ε_max = 1°/s², jerk 1°/s³,
  degree-7 MRP join (``jaxspline.kernels.maneuver_plan``) matching Λ, ω, ε, ε' of both
  routes.

The exact scan laws are closed-form attitude matrices; ω, ε, ε' are obtained by
automatic differentiation in time (ω = vee(Rᵀ Ṙ)). ``spline_accuracy`` fits the
vector spline (σ, σ', σ'' at the ends, σ at T/3, 2T/3) to a route's law and
measures the max angle and rate errors (the paper: 0.03″ and 0.04″/s, 40 s), for
both route laws and for a slowed route-2 scan (aim point at 0.25 n·R, larger rates).

Run: ``python scripts/maneuver_figures.py [outdir]`` (prints the numbers, writes PNGs).
"""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np

import jaxspline as js

DEG = np.pi / 180
ARCSEC = DEG / 3600
MU = 398600.4418  # km^3/s^2
RE = 6371.0  # km, spherical Earth
WE = 7.2921159e-5  # rad/s
J2, RE_J2 = 1.08262668e-3, 6378.137
ALT = 600.0
A_ORB = RE + ALT
N_ORB = np.sqrt(MU / A_ORB**3)
# Sun-synchronous: dΩ/dt = -3/2 J2 (R/a)^2 n cos i = 360°/365.2422 d
_NODE_RATE = 2 * np.pi / (365.2422 * 86400)
INC = np.arccos(-_NODE_RATE / (1.5 * J2 * (RE_J2 / A_ORB) ** 2 * N_ORB))
NODE_LON = 29.5 * DEG

ROUTE1 = dict(t0=580.0, T=20.0, roll=10 * DEG)
ROUTE2 = dict(t0=633.0, T=20.0, lon=18.11 * DEG, lat=39.68 * DEG, azimuth=10 * DEG)
MANEUVER = dict(t0=600.0, T=33.0)
LIMITS = js.AxisLimits(2 * DEG, 1 * DEG, 1 * DEG)


def _rz(a):
    c, s = jnp.cos(a), jnp.sin(a)
    z, o = jnp.zeros_like(a), jnp.ones_like(a)
    return jnp.stack([jnp.stack([c, -s, z]), jnp.stack([s, c, z]), jnp.stack([z, z, o])])


def sat_position(t):
    """Inertial satellite position [km] at t [s] after the ascending node."""
    u = N_ORB * t
    co, so, ci, si = np.cos(NODE_LON), np.sin(NODE_LON), np.cos(INC), np.sin(INC)
    cu, su = jnp.cos(u), jnp.sin(u)
    return A_ORB * jnp.stack([cu * co - su * ci * so, cu * so + su * ci * co, su * si])


def _unit(v):
    return v / jnp.linalg.norm(v)


def route1_dcm(t):
    """Route 1 law: orbital frame rotated by the roll angle about its x axis."""
    r = sat_position(t)
    v = jax.jacfwd(sat_position)(t)
    z = -_unit(r)
    y = _unit(jnp.cross(z, v))  # = -orbit normal
    x = jnp.cross(y, z)
    ro = jnp.stack([x, y, z], axis=1)
    c, s = np.cos(ROUTE1["roll"]), np.sin(ROUTE1["roll"])
    rx = jnp.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])
    return ro @ rx


def ground_point(t, speed=1.0):
    """Route 2 aim point [km, inertial]: great circle from (L, B), azimuth A, speed n·R."""
    lon, lat, az = ROUTE2["lon"], ROUTE2["lat"], ROUTE2["azimuth"]
    p0 = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    north = np.cross(p0, east)
    d0 = np.cos(az) * north + np.sin(az) * east
    ang = speed * N_ORB * (t - ROUTE2["t0"])  # arc length / R
    pe = RE * (jnp.cos(ang) * p0 + jnp.sin(ang) * d0)
    return _rz(WE * t) @ pe


def _strip_dir(t, speed=1.0):
    # strip direction (Earth-fixed tangent) in inertial axes
    ang = speed * N_ORB * (t - ROUTE2["t0"])
    lon, lat, az = ROUTE2["lon"], ROUTE2["lat"], ROUTE2["azimuth"]
    p0 = np.array([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)])
    east = np.array([-np.sin(lon), np.cos(lon), 0.0])
    d0 = np.cos(az) * np.cross(p0, east) + np.sin(az) * east
    return _rz(WE * t) @ (-jnp.sin(ang) * p0 + jnp.cos(ang) * d0)


def route2_dcm(t, speed=1.0):
    """Route 2 law: body z on the line of sight, body x along the strip's image motion."""
    z = _unit(ground_point(t, speed) - sat_position(t))
    s = _strip_dir(t, speed)
    x = _unit(s - jnp.dot(s, z) * z)
    y = jnp.cross(z, x)
    return jnp.stack([x, y, z], axis=1)


# a slowed scan (aim point at a quarter of the ground-track speed: larger body rates)
route2_slow = functools.partial(route2_dcm, speed=0.25)


def law_state(dcm_fn, t):
    """(q, ω, ε, ε') of an attitude law R(t) at scalar t, by autodiff (ω = vee(Rᵀ Ṙ))."""

    def omega(tt):
        R = dcm_fn(tt)
        W = R.T @ jax.jacfwd(dcm_fn)(tt)
        return 0.5 * jnp.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])

    eps = jax.jacfwd(omega)
    q = js.kernels.attitude.dcm_to_quat_kernel(dcm_fn(t))
    return q, omega(t), eps(t), jax.jacfwd(eps)(t)


_STATE_FNS = {}


def _states(dcm_fn, ts):
    # one compiled batch function per law; inputs padded to a few fixed sizes
    if dcm_fn not in _STATE_FNS:
        _STATE_FNS[dcm_fn] = jax.jit(jax.vmap(lambda t: law_state(dcm_fn, t)))
    ts = np.atleast_1d(np.asarray(ts, dtype=np.float64))
    size = next(s for s in (8, 256, 2048, 1 << 30) if s >= len(ts))
    pad = np.concatenate([ts, np.full(size - len(ts), ts[-1])])
    return tuple(x[: len(ts)] for x in _STATE_FNS[dcm_fn](jnp.asarray(pad)))


def maneuver_example():
    """Plan and check the paper's maneuver; returns a dict of results (SI units)."""
    t_a = MANEUVER["t0"]
    t_b = t_a + MANEUVER["T"]
    qa, wa, ea, ja = (x[0] for x in _states(route1_dcm, [t_a]))
    qb, wb, eb, jb = (x[0] for x in _states(route2_dcm, [t_b]))
    T = MANEUVER["T"]
    m = js.kernels.maneuver_plan(qa, wa, ea, qb, wb, eb, T, j0=ja, j1=jb)
    chk = js.kernels.maneuver_check(qa, wa, ea, qb, wb, eb, T, LIMITS, j0=ja, j1=jb, n_samples=2001)
    r = sat_position(t_b)
    los = ground_point(t_b) - r
    off_nadir = float(jnp.arctan2(jnp.linalg.norm(jnp.cross(los, -r)), jnp.dot(los, -r)))
    return dict(
        maneuver=m,
        check=chk,
        angle=float(js.kernels.attitude_angle(qa, qb)),
        off_nadir_route2=off_nadir,
        boundary=((qa, wa, ea, ja), (qb, wb, eb, jb)),
        inclination=INC,
    )


def spline_accuracy(dcm_fn, t0, T, pieces=1, n=801):
    """Max |angle error| [rad] and |ω error| [rad/s] of the vector spline vs the exact law.

    The law on [t0, t0 + T] is split into ``pieces`` equal segments, each fitted by
    ``jaxspline.kernels.attitude_spline`` (σ, σ', σ'' at the ends, σ at 1/3 and 2/3);
    neighbouring segments share their knot state (joined smoothly up to ε).
    """
    h = T / pieces
    knots = t0 + h * np.arange(pieces + 1)
    thirds = np.concatenate([knots[:-1] + h / 3, knots[:-1] + 2 * h / 3])
    qk, wk, ek, _ = _states(dcm_fn, knots)
    qt = _states(dcm_fn, thirds)[0]
    m = js.kernels.attitude_spline(
        qk[:-1], wk[:-1], ek[:-1], qt[:pieces], qt[pieces:], qk[1:], wk[1:], ek[1:], h
    )
    ts = np.linspace(0, h, n)
    qs, ws, _, _ = js.kernels.maneuver_eval(m, ts[:, None])  # [n, pieces, ...]
    qe, we, _, _ = _states(dcm_fn, (knots[:-1][None, :] + ts[:, None]).ravel())
    qe = qe.reshape(n, pieces, 4)
    we = we.reshape(n, pieces, 3)
    ang = float(jnp.max(js.kernels.attitude_angle(qs, qe)))
    rate = float(jnp.max(jnp.linalg.norm(ws - we, axis=-1)))
    return ang, rate


def make_maneuver_figures(outdir) -> list[Path]:
    """Write the maneuver figures (norms vs limits, per-axis components) to ``outdir``."""
    jax.config.update("jax_enable_x64", True)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    ex = maneuver_example()
    m = ex["maneuver"]
    t_a, T = MANEUVER["t0"], MANEUVER["T"]
    tm = np.linspace(0, T, 661)
    _, wm, em, jm = (np.asarray(x) for x in js.kernels.maneuver_eval(m, tm))
    t1 = np.linspace(ROUTE1["t0"], t_a, 201)
    t2 = np.linspace(t_a + T, ROUTE2["t0"] + ROUTE2["T"], 201)
    s1 = [np.asarray(x) for x in _states(route1_dcm, t1)[1:]]
    s2 = [np.asarray(x) for x in _states(route2_dcm, t2)[1:]]
    segs = [(t1, s1, "route 1"), (t_a + tm, [wm, em, jm], "maneuver"), (t2, s2, "route 2")]
    names = [
        ("|ω| [°/s]", LIMITS.rate),
        ("|ε| [°/s²]", LIMITS.accel),
        ("|dε/dt| [°/s³]", LIMITS.jerk),
    ]
    colors = {"route 1": "tab:blue", "maneuver": "tab:red", "route 2": "tab:green"}
    paths = []

    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for k, (ax, (label, lim)) in enumerate(zip(axes, names, strict=True)):
        for t, s, seg in segs:
            ax.plot(t, np.linalg.norm(s[k], axis=-1) / DEG, color=colors[seg], label=seg)
        ax.axhline(lim / DEG, color="k", ls="--", lw=1, label="limit")
        ax.set_ylabel(label)
        ax.set_ylim(0, 1.1 * lim / DEG)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("time from ascending node [s]")
    c = ex["check"]
    fig.suptitle(
        f"Spatial maneuver, T = {T:.0f} s, {ex['angle'] / DEG:.1f}° eigen-axis: peaks "
        f"{float(c.peak_rate) / DEG:.3f}°/s, {float(c.peak_accel) / DEG:.3f}°/s², "
        f"{float(c.peak_jerk) / DEG:.3f}°/s³"
    )
    fig.tight_layout()
    p = outdir / "maneuver_norms.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)

    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for k, (ax, (label, _)) in enumerate(zip(axes, names, strict=True)):
        for t, s, seg in segs:
            for i, ls in enumerate(("-", "--", ":")):
                ax.plot(
                    t,
                    s[k][:, i] / DEG,
                    color=colors[seg],
                    ls=ls,
                    label=f"{'xyz'[i]}" if seg == "maneuver" else None,
                )
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_ylabel(label.replace("|", ""))
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper right", fontsize=8, title="body axis")
    axes[-1].set_xlabel("time from ascending node [s]")
    fig.suptitle(
        "Body-axis components (route 1 blue, maneuver red, route 2 green; limits on the norms)"
    )
    fig.tight_layout()
    p = outdir / "maneuver_components.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths


def report():
    """Print the example's peaks and the spline accuracy figures."""
    jax.config.update("jax_enable_x64", True)
    ex = maneuver_example()
    c = ex["check"]
    inc, off = ex["inclination"] / DEG, ex["off_nadir_route2"] / DEG
    print(f"inclination {inc:.3f}°, route-2 off-nadir {off:.2f}°")
    print(f"maneuver eigen-axis angle {ex['angle'] / DEG:.3f}° in {MANEUVER['T']} s")
    pw, pe, pj = (float(x) / DEG for x in c[:3])
    print(f"peaks: |ω| {pw:.4f}°/s (lim 2), |ε| {pe:.4f}°/s² (lim 1), ", end="")
    print(f"|ε'| {pj:.4f}°/s³ (lim 1), feasible {bool(c.feasible)}")
    for name, fn, t0 in (
        ("route-1 law", route1_dcm, ROUTE1["t0"]),
        ("route-2 law", route2_dcm, ROUTE2["t0"]),
        ("route-2 law, scan at 0.25 n·R", route2_slow, ROUTE2["t0"]),
    ):
        wmax = float(jnp.max(jnp.linalg.norm(_states(fn, t0 + np.linspace(0, 80, 8))[1], axis=-1)))
        print(f"{name}: |ω| up to {wmax / DEG:.3f}°/s")
        for T, pieces in ((20.0, 1), (40.0, 1), (80.0, 2), (80.0, 1)):
            a, r = spline_accuracy(fn, t0, T, pieces)
            a, r = a / ARCSEC, r / ARCSEC
            print(f"{name} spline T={T:.0f}s x{pieces}: angle {a:.2e}″, rate {r:.2e}″/s")
    return ex


if __name__ == "__main__":
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("figures")
    report()
    for p in make_maneuver_figures(out):
        print(p)
