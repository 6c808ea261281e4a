"""Reproduce the figures of the reachable-sets paper (SPEC section 1) with jaxspline.kernels.reach.

Figs. 1-4: envelopes of f and f' with a feasible Theorem-1 trajectory for the paper's
boundary data. Figs. 5-8: the pair set P(a1, b1, T) in the (b2, a2) plane for the four
regimes of Theorem 6, with a Ruckig (second order) membership check overlaid when the
``ruckig`` package is available.

The paper does not print its limits; b = 0.25 deg/s, d = 0.02 deg/s^2 give the stated
envelope shapes for all four trajectory figures (asserted below).

Usage: python scripts/reach_figures.py OUTDIR
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.reach import angle_interval, envelopes, is_reachable, transfer

DEG = math.pi / 180.0
RATE_DEG = 0.25  # b [deg/s]
ACCEL_DEG = 0.02  # d [deg/s^2]

# (title, a1, a2, b1, b2, T) in degrees, deg/s, s  (paper section 2, Figs. 1-4)
TRAJECTORY_CASES = [
    ("Fig. 1: two-link / two-link", -20.005332, -20.023954, 0.00307, 0.003174, 4.0),
    ("Fig. 2: upper two-link, lower three-link", 30.0, 27.0, -0.2, 0.05, 28.0),
    ("Fig. 3: upper three-link, lower two-link", 27.0, 30.0, -0.05, 0.2, 28.0),
    ("Fig. 4: three-link / three-link", 30.0, 35.0, -0.05, 0.05, 50.0),
]
SHAPES = [(True, True), (True, False), (False, True), (False, False)]  # (upper 2-link, lower 2)

# (title, b1 [deg/s], T [s]) for Figs. 5-8 (paper section 3, cases a, c, d, b)
PAIR_CASES = [
    ("Fig. 5: -b <= b1 - dT, b1 + dT <= b", 0.0, 5.0),
    ("Fig. 6: -b <= b1 - dT, b1 + dT > b", 0.15, 10.0),
    ("Fig. 7: -b > b1 - dT, b1 + dT <= b", -0.15, 10.0),
    ("Fig. 8: -b > b1 - dT, b1 + dT > b", 0.05, 30.0),
]


def _float64():
    import jax

    jax.config.update("jax_enable_x64", True)


def _trajectory_figure(path, title, a1, a2, b1, b2, T, shape):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    b, d = RATE_DEG * DEG, ACCEL_DEG * DEG
    lim = AxisLimits(b, d)
    # angles relative to a1 (keeps float precision for Fig. 1's 0.02 deg move)
    y_a = 0.5 * (b1 + b2 + ACCEL_DEG * T)
    y_c = 0.5 * (b1 + b2 - ACCEL_DEG * T)
    assert (y_a <= RATE_DEG, y_c >= -RATE_DEG) == shape, title
    rel = (a2 - a1) * DEG
    assert bool(is_reachable(0.0, b1 * DEG, rel, b2 * DEG, T, lim)), title
    t = np.linspace(0.0, T, 2001)
    f_lo, f_hi = (np.asarray(x) / DEG + a1 for x in envelopes(0.0, b1 * DEG, b2 * DEG, T, lim, t))
    ang, rate, _ = transfer(0.0, b1 * DEG, rel, b2 * DEG, T, lim, t)
    ang = np.asarray(ang) / DEG + a1
    rate = np.asarray(rate) / DEG
    F_hi = np.minimum(np.minimum(b1 + ACCEL_DEG * t, b2 + ACCEL_DEG * (T - t)), RATE_DEG)
    F_lo = np.maximum(np.maximum(b1 - ACCEL_DEG * t, b2 - ACCEL_DEG * (T - t)), -RATE_DEG)

    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    ax0.plot(t, f_hi, "C3", label="upper envelope $f_{hi}$")
    ax0.plot(t, f_lo, "C0", label="lower envelope $f_{lo}$")
    ax0.plot(t, ang, "k", lw=2, label="Theorem-1 trajectory")
    ax0.plot([0, T], [a1, a2], "ko", ms=5)
    ax0.set_ylabel("angle f [deg]")
    ax0.legend(loc="best", fontsize=8)
    ax0.ticklabel_format(useOffset=False)
    ax1.plot(t, F_hi, "C3", label="$F_{hi}$")
    ax1.plot(t, F_lo, "C0", label="$F_{lo}$")
    ax1.plot(t, rate, "k", lw=2, label="trajectory rate")
    ax1.axhline(RATE_DEG, color="0.6", ls=":", lw=1)
    ax1.axhline(-RATE_DEG, color="0.6", ls=":", lw=1)
    ax1.set_ylabel("rate f' [deg/s]")
    ax1.set_xlabel("t [s]")
    ax1.legend(loc="best", fontsize=8)
    fig.suptitle(
        f"{title}\n$a_1$={a1}°, $a_2$={a2}°, $b_1$={b1}°/s, $b_2$={b2}°/s, T={T} s;"
        f" limits b={RATE_DEG}°/s, d={ACCEL_DEG}°/s²",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _ruckig_member(b1, a2, b2, T, b, d):
    """Ruckig (second order) accepts exactly duration T iff (a2, b2) is in P (None if absent)."""
    try:
        import ruckig
    except ImportError:
        return None
    otg, inp, traj = ruckig.Ruckig(1), ruckig.InputParameter(1), ruckig.Trajectory(1)
    out = []
    for x, v in zip(a2, b2, strict=True):
        inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [b1], [0.0]
        inp.target_position, inp.target_velocity, inp.target_acceleration = [x], [v], [0.0]
        inp.max_velocity, inp.max_acceleration, inp.max_jerk = [b], [d], [math.inf]
        inp.minimum_duration = T
        try:
            otg.calculate(inp, traj)
            out.append(abs(traj.duration - T) <= 1e-9 * T)
        except Exception:  # noqa: BLE001 - Ruckig errors: treat as "no answer"
            out.append(None)
    return out


def _pair_figure(path, title, b1, T, seed):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    b, d = RATE_DEG * DEG, ACCEL_DEG * DEG
    lim = AxisLimits(b, d)
    lower = max(-RATE_DEG, b1 - ACCEL_DEG * T)
    upper = min(RATE_DEG, b1 + ACCEL_DEG * T)
    g = np.linspace(lower, upper, 801)
    lo, hi = (np.asarray(x) / DEG for x in angle_interval(0.0, b1 * DEG, g * DEG, T, lim))
    fig, ax = plt.subplots(figsize=(7, 5))
    ax.fill_between(g, lo, hi, color="C2", alpha=0.25, label="P (closed form)")
    ax.plot(g, hi, "C3", label="upper bound hi($b_2$)")
    ax.plot(g, lo, "C0", label="lower bound lo($b_2$)")
    sw_hi = 2 * RATE_DEG - ACCEL_DEG * T - b1
    sw_lo = -2 * RATE_DEG + ACCEL_DEG * T - b1
    for sw, c, which in ((sw_hi, "C3", "upper"), (sw_lo, "C0", "lower")):
        if lower < sw < upper:
            ax.axvline(sw, color=c, ls=":", lw=1, label=f"{which}: two-/three-link switch")
    # Ruckig membership check on random points around P
    rng = np.random.default_rng(seed)
    n = 400
    pad = 0.1 * (hi.max() - lo.min())
    span = upper - lower
    pb2 = rng.uniform(max(-RATE_DEG, lower - 0.2 * span), min(RATE_DEG, upper + 0.2 * span), n)
    pa2 = rng.uniform(lo.min() - pad, hi.max() + pad, n)
    member = _ruckig_member(b1 * DEG, pa2 * DEG, pb2 * DEG, T, b, d)
    ours = np.asarray(is_reachable(0.0, b1 * DEG, pa2 * DEG, pb2 * DEG, T, lim))
    note = ""
    if member is not None:
        m = np.array([bool(x) for x in member])
        ax.plot(pb2[m], pa2[m], "g.", ms=4, label="Ruckig: feasible")
        ax.plot(pb2[~m], pa2[~m], "x", color="0.5", ms=3, label="Ruckig: infeasible")
        note = f"; Ruckig agrees on {int(np.sum(m == ours))}/{n} random points"
    ax.set_xlabel("$b_2$ [deg/s]")
    ax.set_ylabel("$a_2 - a_1$ [deg]")
    ax.set_xlim(-RATE_DEG * 1.05, RATE_DEG * 1.05)
    ax.legend(loc="best", fontsize=7, framealpha=0.85)
    ax.set_title(
        f"{title}\n$b_1$={b1}°/s, T={T} s, b={RATE_DEG}°/s, d={ACCEL_DEG}°/s²{note}", fontsize=9
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def make_reach_figures(outdir) -> list[Path]:
    """Write the eight reachable-set figures as PNG files into ``outdir``; return their paths.

    Figs. 1-4: envelopes f_lo, f_hi and F_lo, F_hi with the Theorem-1 trajectory for the
    paper's data; Figs. 5-8: the pair set P in the (b2, a2) plane, Ruckig-checked.
    Limits b = 0.25 deg/s, d = 0.02 deg/s^2. Plots are in degrees. Enables float64.
    """
    _float64()
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, (case, shape) in enumerate(zip(TRAJECTORY_CASES, SHAPES, strict=True), start=1):
        path = outdir / f"reach_fig{k}.png"
        _trajectory_figure(path, *case, shape)
        paths.append(path)
    for k, case in enumerate(PAIR_CASES, start=5):
        path = outdir / f"reach_fig{k}.png"
        _pair_figure(path, *case, seed=k)
        paths.append(path)
    return paths


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python scripts/reach_figures.py OUTDIR")
    for p in make_reach_figures(sys.argv[1]):
        print(p)
