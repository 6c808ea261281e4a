"""Plan figures (matplotlib, imported lazily, Agg backend). All inputs are numpy arrays.

Angles arrive in radians and are drawn in degrees. Each function writes one PNG
atomically (temporary file in the same directory, then ``os.replace``).
"""

from __future__ import annotations

import numpy as np

from jaxspline.planning.files import atomic_path

__all__ = ["plot_ground_track", "plot_attitude", "plot_margins", "save_figure"]

_CH = ("roll", "pitch", "yaw")


def pyplot():
    """matplotlib.pyplot on the Agg backend, imported on first use (plots are optional)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path) -> None:
    """Save ``fig`` to ``path`` atomically (temp file in the same directory + os.replace).

    Args:
      fig: matplotlib Figure; it is closed afterwards, also on failure.
      path: str or Path; written as PNG at 110 dpi.
    """
    try:
        with atomic_path(path, suffix=".tmp.png") as tmp:
            fig.savefig(tmp, dpi=110)
    finally:
        pyplot().close(fig)


def plot_ground_track(
    path,
    track_lat,
    track_lon,
    cand_lat,
    cand_lon,
    cand_kind,
    cand_end_lat,
    cand_end_lon,
    chosen,
    title="",
    visible=None,
    track_t=None,
):
    """Ground track with candidate routes (grey; invisible ones faint) and chosen ones (numbered).

    Args:
      path: str or Path of the image.
      track_lat: float [M], sub-satellite latitudes [rad].
      track_lon: float [M], sub-satellite longitudes [rad].
      cand_lat: float [R], route start latitudes [rad].
      cand_lon: float [R], route start longitudes [rad].
      cand_kind: int [R], 0 point / 1 strip.
      cand_end_lat: float [R], strip end latitudes [rad].
      cand_end_lon: float [R], strip end longitudes [rad].
      chosen: int [K], route indices in plan order.
      title: figure title.
      visible: bool [R], routes with at least one feasible option (None: all).
      track_t: float [M], times of the track points [s] (labelled every 100 s).
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(10, 8))
    d = np.degrees
    r = np.arange(len(cand_lat))
    vis = np.ones(len(cand_lat), bool) if visible is None else np.asarray(visible, bool)
    pt = np.asarray(cand_kind) == 0
    for mask, alpha, lab in ((vis, 0.6, "candidate"), (~vis, 0.2, "no feasible option")):
        m = mask & pt
        ax.plot(
            d(cand_lon[m]),
            d(cand_lat[m]),
            ".",
            color="0.45",
            alpha=alpha,
            ms=5,
            label=f"{lab} point" if m.any() else None,
        )
        first = True
        for i in r[mask & ~pt]:
            ax.plot(
                d([cand_lon[i], cand_end_lon[i]]),
                d([cand_lat[i], cand_end_lat[i]]),
                "-",
                color="0.45",
                alpha=alpha,
                lw=1.5,
                label=f"{lab} strip" if first else None,
            )
            first = False
    ax.plot(d(track_lon), d(track_lat), "-", color="tab:blue", lw=1.2, label="ground track")
    if track_t is not None:
        track_t = np.asarray(track_t)
        for tk in np.arange(0.0, track_t[-1] + 1e-9, 100.0):
            i = int(np.argmin(np.abs(track_t - tk)))
            ax.plot(d(track_lon[i]), d(track_lat[i]), "^", color="tab:blue", ms=5)
            ax.annotate(
                f"t={tk:g} s",
                (d(track_lon[i]), d(track_lat[i])),
                xytext=(5, -3),
                textcoords="offset points",
                fontsize=7,
                color="tab:blue",
            )
    cmap = plt.get_cmap("plasma")
    k = len(chosen)
    for n, i in enumerate(chosen):
        col = cmap(0.1 + 0.8 * n / max(k - 1, 1))
        if cand_kind[i] == 0:
            ax.plot(d(cand_lon[i]), d(cand_lat[i]), "o", color=col, ms=7, mec="k", mew=0.5)
        else:
            ax.plot(
                d([cand_lon[i], cand_end_lon[i]]),
                d([cand_lat[i], cand_end_lat[i]]),
                "-",
                color=col,
                lw=4,
            )
        ax.annotate(
            str(n + 1),
            (d(cand_lon[i]), d(cand_lat[i])),
            xytext=(4, 4),
            textcoords="offset points",
            fontsize=8,
            weight="bold",
        )
    ax.plot([], [], "o", color=cmap(0.5), mec="k", label=f"chosen ({k}, numbered in order)")
    lat_all = np.concatenate([cand_lat, cand_end_lat])
    lon_all = np.concatenate([cand_lon, cand_end_lon])
    pad = np.radians(1.0)
    ax.set_xlim(d(lon_all.min() - pad), d(lon_all.max() + pad))
    ax.set_ylim(d(lat_all.min() - pad), d(lat_all.max() + pad))
    ax.set_aspect(1.0 / np.cos(np.mean(lat_all)))
    ax.set_xlabel("longitude [deg]")
    ax.set_ylabel("latitude [deg]")
    ax.set_title(title or "ground track and routes")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_attitude(path, t, angle, rate, accel, rate_limit, accel_limit, scans, title=""):
    """Angle, rate and acceleration of each channel over time against the limits.

    Args:
      path: str or Path of the image.
      t: float [M], times [s].
      angle: float [M, 3], channel angles [rad] (NaN breaks the line).
      rate: float [M, 3], channel rates [rad/s].
      accel: float [M, 3], channel accelerations [rad/s^2].
      rate_limit: float [3], rate bounds [rad/s].
      accel_limit: float [3], acceleration bounds [rad/s^2].
      scans: list of (t_start, t_end) [s], shaded as imaging.
      title: figure title.
    """
    plt = pyplot()
    fig, axes = plt.subplots(3, 3, figsize=(13, 8), sharex=True)
    d = np.degrees
    rows = (
        (angle, "angle [deg]", None),
        (rate, "rate [deg/s]", rate_limit),
        (accel, "accel [deg/s²]", accel_limit),
    )
    for i, (y, lab, lim) in enumerate(rows):
        for c in range(3):
            ax = axes[i, c]
            for a, b in scans:
                ax.axvspan(a, b, color="tab:green", alpha=0.12, lw=0)
            ax.plot(t, d(y[:, c]), color="tab:blue", lw=1.0)
            if lim is not None:
                for s in (1, -1):
                    ax.axhline(s * d(lim[c]), color="tab:red", ls="--", lw=1)
                ax.set_ylim(-1.25 * d(lim[c]), 1.25 * d(lim[c]))
            if i == 0:
                ax.set_title(_CH[c])
            if c == 0:
                ax.set_ylabel(lab)
            if i == 2:
                ax.set_xlabel("t [s from epoch]")
            ax.grid(alpha=0.3)
    fig.suptitle(title or "attitude per channel (green: imaging; red dashed: limits)")
    fig.tight_layout()
    save_figure(fig, path)


def plot_margins(path, margins, chosen_before=None, chosen_after=None, title=""):
    """Histogram of reach margins of the feasible screened transitions (degrees, log y).

    Args:
      path: str or Path of the image.
      margins: float [N], margins [rad] (non-finite ones dropped).
      chosen_before: float [K-1], margins of the plan's transitions before refinement
        [rad], drawn as rug marks (None: none).
      chosen_after: float [K-1], the same after refinement [rad].
      title: figure title.
    """
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(8, 4.5))
    m = np.degrees(np.asarray(margins, np.float64))
    m = m[np.isfinite(m)]
    if m.size:
        ax.hist(m, bins=60, color="0.6", label=f"feasible candidates ({m.size})")
        ax.set_yscale("log")
    for vals, col, lab in (
        (chosen_before, "tab:orange", "plan transitions (before refine)"),
        (chosen_after, "tab:blue", "plan transitions (after refine)"),
    ):
        if vals is not None and len(vals):
            v = np.degrees(np.asarray(vals, np.float64))
            ax.plot(v, np.full(v.shape, 0.8), "|", color=col, ms=18, mew=2, label=lab)
    ax.set_xlabel("reach margin, min over channels [deg]")
    ax.set_ylabel("count")
    ax.set_title(title or "transition margins")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)
