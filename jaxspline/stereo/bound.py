"""Which targets of a stereo_imaging case can be covered at all: an upper bound on coverage.

For every target, :func:`candidate_looks` enumerates looks on a time grid over the
horizon: per satellite pass (the target within the off-nadir limit), one look centred on
each grid instant, steered so that its boresight meets the ellipsoid at the target's foot
point (straight below the centre along the geocentric up, where the strip's ground track
is laid), long enough for its strip to cross the AOI (at least ``min_obs_duration_s``),
and kept only if it passes the checker's access test over its whole window. Every pair
of looks is then judged by the checker's pair rules (mode, separation, overlap with the
checker's lattice, convergence, pixel-scale ratio) with no other look competing for the
satellites. A valid tri-stereo set needs two valid pairs, so the targets with a valid
pair are all the targets any solution can cover (up to the grid: a target covered only
between grid instants is missed); :func:`coverage_bound` counts them and also bounds
each target's quality (the best valid pair, plus the scene's tri-stereo bonus when an
anchored valid triple exists among the looks).

The geometry is the checker's (:mod:`jaxspline.stereo.check_geometry`), so a pair found
here is valid for :func:`jaxspline.stereo.check.check_solution` when imaged alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from jaxspline.stereo.case import SCENE_BANDS_DEG, Case
from jaxspline.stereo.check_geometry import (
    Track,
    access_mask,
    disk_lattice,
    enu_basis,
    foot_point,
    inside_strip,
    off_nadir_to_deg,
    solar_elevation_deg,
    steering_angles,
    strip_polyline,
    target_ecef,
)

__all__ = ["CandidateLook", "CoverageBound", "TargetBound", "candidate_looks", "coverage_bound"]

#: Coarse scan step of the passes [s].
SCAN_STEP_S = 10.0
#: Extra off-nadir and Sun elevation allowed in the coarse scan [deg] (the fine test decides).
SCAN_MARGIN_DEG = 2.0
#: Lattice points of the bound's overlap quadrature.
BOUND_POINTS = 1024
TOL = 1e-6


@dataclass(frozen=True)
class CandidateLook:
    """One look of the enumeration.

    Attributes:
      sat: satellite index.
      target: target index.
      start_s: start [s from the horizon start] (whole seconds).
      end_s: end [s].
      along_deg: along-track steering [deg].
      across_deg: across-track steering [deg].
      off_nadir_deg: combined off-nadir angle [deg].
      pass_id: index of the satellite's pass over the target.
    """

    sat: int
    target: int
    start_s: float
    end_s: float
    along_deg: float
    across_deg: float
    off_nadir_deg: float
    pass_id: int

    def to_action(self, case: Case) -> dict:
        """The look as a solution action.

        Args:
          case: the Case.
        Returns:
          dict (``type``, ids, ISO times, steering angles).
        """
        from jaxspline.stereo.case import format_time

        return {
            "type": "observation",
            "satellite_id": case.satellites[self.sat].id,
            "target_id": case.targets[self.target].id,
            "start_time": format_time(case.time_at(self.start_s)),
            "end_time": format_time(case.time_at(self.end_s)),
            "off_nadir_along_deg": round(self.along_deg, 6),
            "off_nadir_across_deg": round(self.across_deg, 6),
        }


@dataclass(frozen=True)
class TargetBound:
    """The enumeration's verdict on one target.

    Attributes:
      target_id: the target.
      num_looks: looks that passed the access test.
      pair: the valid pair of highest quality (two CandidateLook), or None.
      pair_quality: its quality (0 without a valid pair).
      quality_bound: ``min(1, pair_quality + beta)`` when an anchored valid triple
        exists, else ``pair_quality``.
      safest_overlap: the largest overlap among its valid pairs (0 without one).
    """

    target_id: str
    num_looks: int
    pair: tuple | None
    pair_quality: float
    quality_bound: float
    safest_overlap: float


@dataclass
class CoverageBound:
    """Result of :func:`coverage_bound`.

    Attributes:
      case_id: the case.
      coverable: ids of the targets with a valid pair among the looks.
      coverage_bound: ``len(coverable) / number of targets``.
      quality_bound: mean over all targets of ``TargetBound.quality_bound``.
      targets: target id -> TargetBound.
    """

    case_id: str
    coverable: list
    coverage_bound: float
    quality_bound: float
    targets: dict = field(default_factory=dict)


def _passes(track: Track, center: np.ndarray, limit_deg: float, min_sun: float, horizon_s):
    """[lo, hi] [s] of the coarse runs where the target is near the off-nadir limit and
    the Sun near or above its minimum elevation."""
    t = np.arange(0.0, horizon_s + SCAN_STEP_S / 2, SCAN_STEP_S)
    pos, _ = track.ecef(t)
    near = off_nadir_to_deg(pos, center) <= limit_deg + SCAN_MARGIN_DEG
    near &= np.sum(pos * center, axis=-1) > 0.0
    idx = np.flatnonzero(near)
    near[idx] &= solar_elevation_deg(center, track.unix(t[idx])) >= min_sun - SCAN_MARGIN_DEG
    edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(int), [0]])))
    return [
        (max(0.0, t[a] - SCAN_STEP_S), min(horizon_s, t[b - 1] + SCAN_STEP_S))
        for a, b in zip(edges[::2], edges[1::2], strict=True)
    ]


def candidate_looks(case: Case, target: int, step_s: float = 10.0, tracks=None) -> list:
    """Looks at one target on a grid of centres, each passing the access test.

    Args:
      case: Case.
      target: target index.
      step_s: spacing of the look centres [s].
      tracks: optional list of Track per satellite (reused across targets).
    Returns:
      list of CandidateLook.
    """
    tgt = case.targets[target]
    center = target_ecef(tgt)
    aim = foot_point(center)
    min_sun = case.mission.thresholds.min_solar_elevation_deg
    tracks = tracks or [Track(s, case.start) for s in case.satellites]
    looks = []
    for k, sat in enumerate(case.satellites):
        passes = _passes(tracks[k], center, sat.max_off_nadir_deg, min_sun, case.horizon_s)
        for pid, (lo, hi) in enumerate(passes):
            mids = np.arange(math.ceil(lo / step_s) * step_s, hi + 1e-9, step_s)
            if not len(mids):
                continue
            pos, vel = tracks[k].ecef(mids)
            speed = np.linalg.norm(vel, axis=-1) * 6.371e6 / np.linalg.norm(pos, axis=-1)
            dur = np.clip(
                np.ceil(2.0 * tgt.aoi_radius_m / speed) + 2.0,
                sat.min_duration_s,
                sat.max_duration_s,
            )
            dur = np.ceil(dur)
            starts = np.round(mids - dur / 2.0)
            ends = starts + dur
            mid_pos, mid_vel = tracks[k].ecef((starts + ends) / 2.0)
            al, ac = steering_angles(mid_pos, mid_vel, aim)
            off = np.degrees(np.arctan(np.hypot(np.tan(np.radians(al)), np.tan(np.radians(ac)))))
            for j in np.flatnonzero(off <= sat.max_off_nadir_deg - 1e-3):
                if starts[j] < 0 or ends[j] > case.horizon_s:
                    continue
                samples = np.arange(starts[j], ends[j] + 0.5, sat.access_step_s)
                if access_mask(tracks[k], center, sat.max_off_nadir_deg, min_sun, samples).all():
                    looks.append(
                        CandidateLook(
                            k, target, float(starts[j]), float(ends[j]), float(al[j]),
                            float(ac[j]), float(off[j]), pid,
                        )
                    )  # fmt: skip
    return looks


def _look_geometry(case: Case, looks: list, tracks: list, center: np.ndarray, pts) -> dict:
    """Per look: satellite at the midpoint, pixel scale, strip mask over the lattice."""
    basis = enu_basis(center)
    sat_mid, scale, masks = [], [], []
    for x in looks:
        sat = case.satellites[x.sat]
        pos, _ = tracks[x.sat].ecef(np.array([(x.start_s + x.end_s) / 2.0]))
        poly = strip_polyline(
            tracks[x.sat], basis, center, x.start_s, x.end_s, x.along_deg, x.across_deg
        )
        slant = float(np.linalg.norm(foot_point(center) - pos[0]))
        half = slant * math.tan(math.radians(sat.fov_deg / 2.0))
        sat_mid.append(pos[0])
        scale.append(slant * math.radians(sat.ifov_deg))
        masks.append(inside_strip(pts, poly, half))
    return dict(
        sat_mid=np.array(sat_mid), scale=np.array(scale), masks=np.array(masks, dtype=float)
    )


def _pair_tables(case: Case, tgt, looks: list, geo: dict, center: np.ndarray) -> tuple:
    """(valid [L, L], quality [L, L], overlap [L, L], mode_ok [L, L]) of all look pairs."""
    m, th, q = case.mission, case.mission.thresholds, case.mission.quality
    mid = np.array([(x.start_s + x.end_s) / 2.0 for x in looks])
    sat = np.array([x.sat for x in looks])
    pid = np.array([x.pass_id for x in looks])
    same = sat[:, None] == sat[None, :]
    mode = np.abs(mid[:, None] - mid[None, :]) - TOL <= m.max_pair_separation_s
    mode &= np.where(same, pid[:, None] == pid[None, :], m.allow_cross_satellite)
    np.fill_diagonal(mode, False)
    u = geo["sat_mid"] - center
    u = u / np.linalg.norm(u, axis=-1, keepdims=True)
    cross = np.linalg.norm(np.cross(u[:, None, :], u[None, :, :]), axis=-1)
    gamma = np.degrees(np.arctan2(cross, u @ u.T))
    s = geo["scale"]
    ratio = np.maximum(s[:, None], s[None, :]) / np.minimum(s[:, None], s[None, :])
    overlap = geo["masks"] @ geo["masks"].T / geo["masks"].shape[1]
    valid = mode & (overlap + TOL >= th.min_overlap) & (ratio <= th.max_pixel_scale_ratio + TOL)
    valid &= (gamma >= th.min_convergence_deg - TOL) & (gamma <= th.max_convergence_deg + TOL)
    lo, hi = SCENE_BANDS_DEG[tgt.scene_type]
    e = np.maximum(0.0, np.maximum(lo - gamma, gamma - hi))
    quality = (
        q.geometry * np.maximum(0.0, 1.0 - e / 10.0)
        + q.overlap * np.minimum(1.0, overlap / 0.95)
        + q.resolution * np.maximum(0.0, 1.0 - (ratio - 1.0) / 0.5)
    )
    return valid, np.where(valid, quality, 0.0), overlap, mode


def _has_triple(case: Case, looks: list, geo: dict, valid, mode) -> bool:
    """Some anchored triple with two valid edges and enough common overlap exists."""
    th = case.mission.thresholds
    masks, n_pts = geo["masks"], geo["masks"].shape[1]
    for a in [i for i, x in enumerate(looks) if x.off_nadir_deg <= th.anchor_max_off_nadir_deg]:
        s = np.flatnonzero(mode[a])
        if len(s) < 2:
            continue
        va = valid[a, s].astype(int)
        count = va[:, None] + va[None, :] + valid[np.ix_(s, s)]
        common = (masks[a] * masks[s]) @ masks[s].T / n_pts
        ok = mode[np.ix_(s, s)] & (count >= 2) & (common + TOL >= th.min_overlap)
        if ok.any():
            return True
    return False


def _target_bound(case: Case, t: int, tracks: list, step_s: float) -> TargetBound:
    tgt = case.targets[t]
    looks = candidate_looks(case, t, step_s, tracks)
    if len(looks) < 2:
        return TargetBound(tgt.id, len(looks), None, 0.0, 0.0, 0.0)
    center = target_ecef(tgt)
    geo = _look_geometry(case, looks, tracks, center, disk_lattice(tgt.aoi_radius_m, BOUND_POINTS))
    valid, quality, overlap, mode = _pair_tables(case, tgt, looks, geo, center)
    if not valid.any():
        return TargetBound(tgt.id, len(looks), None, 0.0, 0.0, 0.0)
    i, j = np.unravel_index(int(np.argmax(quality)), quality.shape)
    best = float(quality[i, j])
    bonus = case.mission.quality.tri_bonus[tgt.scene_type]
    qb = min(1.0, best + bonus) if _has_triple(case, looks, geo, valid, mode) else best
    safest = float(np.max(np.where(valid, overlap, 0.0)))
    return TargetBound(tgt.id, len(looks), (looks[i], looks[j]), best, qb, safest)


def coverage_bound(case: Case, step_s: float = 10.0, targets=None) -> CoverageBound:
    """Targets with a valid stereo pair when no other look competes (module docstring).

    Args:
      case: Case.
      step_s: spacing of the look centres [s] (smaller: slower, tighter).
      targets: optional target indices to examine (default: all; the ratios stay over
        all targets of the case).
    Returns:
      CoverageBound.
    """
    tracks = [Track(s, case.start) for s in case.satellites]
    idx = range(len(case.targets)) if targets is None else targets
    per = {case.targets[t].id: _target_bound(case, t, tracks, step_s) for t in idx}
    coverable = [tid for tid, b in per.items() if b.pair is not None]
    n = len(case.targets)
    return CoverageBound(
        case_id=case.case_id,
        coverable=coverable,
        coverage_bound=len(coverable) / n,
        quality_bound=sum(b.quality_bound for b in per.values()) / n,
        targets=per,
    )
