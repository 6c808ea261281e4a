"""Figures for SPEC section 2 (slew profiles of a flexible spacecraft).

Reproduces, with the paper's data (omega = 0.035 rad/s, eps = 0.0035 rad/s^2):

* ``slew_time_vs_angle.png``   paper Figs. 2 and 7: slew time of A, B, C, D
  (tau = 1 s), the automatic choice, bang-coast-bang and an S-curve;
* ``slew_topology.png``        paper Figs. 4 and 7: acceleration histories for
  several angles and the regions of the kinds in the (angle, tau) plane;
* ``slew_flex_response.png``   paper Figs. 5 and 6: body rate of a spacecraft
  with one 2 Hz mode (damping 0.01, modal inertia 0.1) for a 3 deg slew with
  profiles A and B, and the +-0.001 deg/s tube.

Run: ``python scripts/slew_figures.py [outdir]`` (default ``figures/slew``).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import jax
import numpy as np

W, E = 0.035, 0.0035
COLORS = {"A": "tab:blue", "B": "tab:orange", "C": "tab:green", "D": "tab:red"}


def _time_vs_angle(out: Path) -> Path:
    import matplotlib.pyplot as plt

    from jaxspline.kernels import bang_coast_bang_time, scurve_time, slew_profile_time

    b2 = W * W / E
    phi = np.linspace(1e-4, 1.2, 1200)
    deg = np.degrees(phi)
    fig, (ax, axr) = plt.subplots(
        2, 1, figsize=(8, 8), sharex=True, gridspec_kw={"height_ratios": [3, 2]}
    )
    t_auto = np.asarray(slew_profile_time(phi, W, E))
    for kind, tau, label in [
        ("A", None, "A (no const. accel; + coast beyond 2w^2/e)"),
        ("B", None, "B (accel. steps, reference)"),
        ("C", None, "C (7/6 w^2/e .. 2 w^2/e)"),
        ("D", 1.0, "D (tau = 1 s)"),
    ]:
        t = np.asarray(slew_profile_time(phi, W, E, tau, kind))
        ax.plot(deg, t, color=COLORS[kind], lw=1.5, label=label)
        axr.plot(deg, t / t_auto, color=COLORS[kind], lw=1.5)
    ax.plot(
        deg,
        np.asarray(slew_profile_time(phi, W, E)),
        "k-",
        lw=3,
        alpha=0.35,
        label="auto (paper): A | C | D, tau = w/e",
    )
    ax.plot(
        deg,
        np.asarray(slew_profile_time(phi, W, E, 1.0)),
        "k--",
        lw=1,
        label="auto with tau = 1 s (D from its threshold)",
    )
    ax.plot(
        deg,
        np.asarray(bang_coast_bang_time(phi, W, E)),
        ":",
        color="gray",
        lw=2,
        label="bang-coast-bang (rigid, time-optimal)",
    )
    ax.plot(
        deg,
        np.asarray(scurve_time(phi, W, E, E / 1.0)),
        "-.",
        color="purple",
        label="S-curve, jerk = eps / 1 s",
    )
    for x, txt in [
        (7 / 6 * b2, "7/6 w^2/e"),
        (2 * b2, "2 w^2/e"),
        (5 / 6 * W + 7 / 6 * b2, "D(tau=1) threshold"),
    ]:
        ax.axvline(math.degrees(x), color="gray", lw=0.7, ls="--")
        ax.text(math.degrees(x), 2, txt, rotation=90, va="bottom", ha="right", fontsize=8)
    for phi_ex, td in [
        (0.7, 40),
        (157 * E, 34.84),
        (7 / 6 * b2, 30),
        (0.07, 12.6),
        (0.007, 4),
        (0.7, 38.5),
    ]:
        ax.plot(math.degrees(phi_ex), td, "ks", ms=5, mfc="none")
    axr.plot(deg, np.asarray(slew_profile_time(phi, W, E, 1.0)) / t_auto, "k--", lw=1)
    axr.plot(deg, np.asarray(bang_coast_bang_time(phi, W, E)) / t_auto, ":", color="gray", lw=2)
    axr.plot(deg, np.asarray(scurve_time(phi, W, E, E / 1.0)) / t_auto, "-.", color="purple")
    axr.axhline(1.0, color="k", lw=3, alpha=0.35)
    for x in (7 / 6 * b2, 2 * b2, 5 / 6 * W + 7 / 6 * b2):
        axr.axvline(math.degrees(x), color="gray", lw=0.7, ls="--")
    axr.set_ylim(0.7, 1.1)
    axr.set_ylabel("T_d / T_d(auto)")
    axr.set_xlabel("slew angle [deg]")
    axr.grid(alpha=0.3)
    ax.set_ylabel("slew time T_d [s]")
    ax.set_title("Slew time vs angle (w = 2 deg/s, e = 0.2 deg/s^2); squares: paper's examples")
    ax.set_ylim(0, 60)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    path = out / "slew_time_vs_angle.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _topology(out: Path) -> Path:
    import matplotlib.pyplot as plt

    from jaxspline.kernels import profile_state, slew_profile

    b = W / E
    b2 = W * W / E
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 5))
    names = {0: "A", 1: "B", 2: "C", 3: "D"}
    for phi, tau in [(0.07, None), (0.3, None), (0.5, None), (0.7, None), (0.7, 1.0), (1.2, 1.0)]:
        p = slew_profile(phi, W, E, tau)
        t = np.linspace(0, float(p.duration), 600)
        acc = np.asarray(profile_state(p, E, t)[0])
        k = names[int(p.kind)]
        lab = f"{math.degrees(phi):.0f} deg: {k}" + (f", tau={tau:g}" if tau else "")
        ax1.plot(t, acc / E, color=COLORS[k], lw=1.5, alpha=0.4 + 0.6 * phi / 1.2, label=lab)
    ax1.set_xlabel("t [s]")
    ax1.set_ylabel("acceleration / eps")
    ax1.set_title("Acceleration histories (auto choice)")
    ax1.grid(alpha=0.3)
    ax1.legend(fontsize=8)
    # kind regions in (angle, tau)
    phi = np.linspace(0.0, 1.0, 401)
    tau = np.linspace(0.0, b, 201)
    pp, tt = np.meshgrid(phi, tau)
    kind = np.asarray(slew_profile(pp, W, E, tt).kind)
    cmap = plt.matplotlib.colors.ListedColormap([COLORS[k] for k in "ABCD"])
    ax2.pcolormesh(
        np.degrees(pp), tt, kind, cmap=cmap, vmin=-0.5, vmax=3.5, shading="auto", alpha=0.6
    )
    ax2.plot(
        np.degrees(5 / 6 * tau * W + 7 / 6 * b2),
        tau,
        "k-",
        lw=1,
        label="D exists: phi = 5/6 tau w + 7/6 w^2/e",
    )
    ax2.axvline(math.degrees(7 / 6 * b2), color="k", ls="--", lw=1, label="7/6 w^2/e (A | C)")
    ax2.axvline(math.degrees(2 * b2), color="k", ls=":", lw=1, label="2 w^2/e (C ends)")
    for k, (x, y) in {"A": (10, 5), "C": (28, 8.5), "D": (45, 4)}.items():
        ax2.text(x, y, k, fontsize=16, weight="bold")
    ax2.set_xlabel("slew angle [deg]")
    ax2.set_ylabel("tau of profile D [s]")
    ax2.set_title("Auto choice of the kind (paper Figs. 4, 7)")
    ax2.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    path = out / "slew_topology.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def _flex_response(out: Path) -> Path:
    import matplotlib.pyplot as plt

    from jaxspline.kernels import flexible_body_rate, profile_state, settling_time, slew_profile

    eps, phi = 0.004, math.radians(3.0)
    tol = math.radians(0.001)
    t = np.arange(0.0, 25.0, 1e-3)
    fig, axes = plt.subplots(2, 2, figsize=(12, 7))
    for col, kind in enumerate("AB"):
        p = slew_profile(phi, W, eps, kind=kind)
        rate = np.asarray(flexible_body_rate(p, eps, t, 4 * np.pi, 0.01, 0.1))
        ref = np.asarray(profile_state(p, eps, t)[1])
        ts = float(settling_time(t, rate, tol))
        ax = axes[0, col]
        ax.plot(t, np.degrees(rate), color=COLORS[kind], lw=1, label="body rate (flexible)")
        ax.plot(t, np.degrees(ref), "k--", lw=0.8, label="profile rate (rigid)")
        ax.set_title(f"Profile {kind}: 3 deg, e = 0.004 rad/s^2, T_d = {float(p.duration):.2f} s")
        ax.set_ylabel("rate [deg/s]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax = axes[1, col]
        ax.plot(t, np.degrees(rate) * 1e3, color=COLORS[kind], lw=0.8)
        ax.axhspan(-1, 1, color="gray", alpha=0.25, label="+-0.001 deg/s")
        ax.axvline(ts, color="k", lw=1, label=f"settled at {ts:.2f} s")
        ax.set_ylim(-6, 6)
        ax.set_xlim(5, 25)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("rate [1e-3 deg/s]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    fig.suptitle(
        "One elastic mode 2 Hz (free-free), damping 0.01, J_mode/J_body = 0.1 "
        "(paper Figs. 5, 6: A 10.2 s, B 17 s)"
    )
    fig.tight_layout()
    path = out / "slew_flex_response.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def make_slew_figures(outdir) -> list[Path]:
    """Write the SPEC section 2 figures into ``outdir``; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    return [_time_vs_angle(out), _topology(out), _flex_response(out)]


if __name__ == "__main__":
    jax.config.update("jax_enable_x64", True)
    for p in make_slew_figures(sys.argv[1] if len(sys.argv) > 1 else "figures/slew"):
        print(p)
