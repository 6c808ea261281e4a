"""Figure of the flown profile of a plan: rate, acceleration and jerk against the limits.

One row per satellite, three columns (rate, acceleration, jerk), over the whole
horizon, from :func:`jaxspline.products.attitude_history.attitude_history`. Each panel shows
the quantity the join check limits (:mod:`jaxspline.planner.flown_joins`) as a fraction of its
limit: |ω|/rate, |ε|/accel and, for flexible satellites, |ε'|/(accel/tau); for
``per_channel`` satellites the largest roll/pitch/yaw rate or acceleration ratio.
Where a model has no limit (jerk of ``eigen_axis`` and ``per_channel``) the panel
shows |ε'| in deg/s³. Joins are drawn in the satellite's colour, scans and nadir in
grey; the dashed line is the limit.
"""

from __future__ import annotations

import jax
import numpy as np

from jaxspline.planner.attitude_laws import state_angles
from jaxspline.planner.flown_joins import join_limits
from jaxspline.products.attitude_history import PHASES, plan_scene
from jaxspline.products.czml import SATELLITE_COLORS
from jaxspline.products.plot import pyplot, save_figure

__all__ = ["plot_attitude_profile"]

SECONDS_PER_HOUR = 3600.0
LAW_COLOR = "0.55"
ROW_HEIGHT_IN = 1.7
WIDTH_IN = 13.0
_JOIN = PHASES.index("join")


def _flown_ratios(scene, k: int, sat, hist) -> np.ndarray:
    """Checked rate, acceleration and jerk of a history as fractions of the limits.

    NaN in the jerk column where the model has no jerk limit (see module docstring).

    Args:
      scene: Scene of the plan's satellites.
      k: int, satellite index in the scene.
      sat: Satellite (its limits).
      hist: AttitudeHistory of the satellite (N samples).
    Returns:
      numpy float [N, 3], ratios (dimensionless; <= 1 within the limits).
    """
    norm, chan = join_limits(sat)
    n = hist.t.size
    out = np.full((n, 3), np.nan)
    if chan is not None:
        with jax.enable_x64(True):
            _, rate, acc = state_angles(
                scene, np.full(n, k), hist.q, hist.omega, hist.accel, hist.t
            )
        out[:, 0] = np.max(np.abs(rate) / np.broadcast_to(chan.rate, (3,)), -1)
        out[:, 1] = np.max(np.abs(acc) / np.broadcast_to(chan.accel, (3,)), -1)
    else:
        out[:, 0] = np.linalg.norm(hist.omega, axis=-1) / norm.rate
        out[:, 1] = np.linalg.norm(hist.accel, axis=-1) / norm.accel
    if np.isfinite(norm.jerk) and chan is None:
        out[:, 2] = np.linalg.norm(hist.jerk, axis=-1) / norm.jerk
    return out


def plot_attitude_profile(result, attitude, path) -> None:
    """Write the flown-profile figure of ``attitude`` to ``path``.

    Args:
      result: PlanResult.
      attitude: :class:`PlanAttitude` of the plan.
      path: str or Path of the image (written atomically).
    """
    plt = pyplot()
    sc = result.scenario
    with jax.enable_x64(True):
        scene = plan_scene(sc)
    sats = sc.satellites
    fig, axes = plt.subplots(
        len(sats), 3, figsize=(WIDTH_IN, ROW_HEIGHT_IN * len(sats) + 0.6), squeeze=False
    )
    titles = ("rate / limit", "acceleration / limit", "jerk / limit (or |ε'| deg/s³)")
    for k, s in enumerate(sats):
        h = attitude.histories[s.name]
        r = _flown_ratios(scene, k, s, h)
        th = h.t / SECONDS_PER_HOUR
        join = h.phase == _JOIN
        color = SATELLITE_COLORS[k % len(SATELLITE_COLORS)]
        for c in range(3):
            ax = axes[k, c]
            y = r[:, c]
            limited = np.isfinite(y).any()
            if not limited:
                y = np.degrees(np.linalg.norm(h.jerk, axis=-1))
            ax.plot(th, np.where(join, np.nan, y), color=LAW_COLOR, lw=0.6)
            ax.plot(th, np.where(join, y, np.nan), color=color, lw=0.8)
            if limited:
                ax.axhline(1.0, color="k", ls="--", lw=0.8)
                ax.set_ylim(0.0, max(1.1, float(np.nanmax(y)) * 1.05))
            else:
                ax.text(0.99, 0.95, "|ε'| [deg/s³], no limit", transform=ax.transAxes,
                        ha="right", va="top", fontsize=7)  # fmt: skip
            ax.grid(alpha=0.3)
            if k == 0:
                ax.set_title(titles[c], fontsize=9)
            if c == 0:
                ax.set_ylabel(f"{s.name}\n{s.model}", fontsize=8)
            if k == len(sats) - 1:
                ax.set_xlabel("hours from epoch")
    sm = attitude.summary
    fig.suptitle(
        f"{sc.name}: flown profile, {sm['joins']} joins ({sm['retimed']} re-timed, "
        f"{result.report.get('joins', {}).get('rejected', 0)} rejected by the planner); "
        "joins in colour, scans and nadir in grey",
        fontsize=10,
    )
    fig.tight_layout()
    save_figure(fig, path)
