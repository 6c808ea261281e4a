"""Which strips the search considers: passes, a roll grid, 10 s slices, their coverage.

1. **Passes.** For each satellite and region, the instants when the region's centroid
   crosses the satellite's cross-track plane (``(X - p) . along`` changes sign from + to
   -, the point in front of the Earth's horizon) with some region sample inside the
   sensor band (+- :data:`PASS_SLACK_DEG`) at that instant.
2. **Sample crossings.** Per pass, every region sample's own crossing instant ``t_j``
   (linear interpolation of ``(X_j - p) . along`` on the 5 s mesh) and its look angle
   ``a_j = atan2((X_j - p) . across, (X_j - p) . nadir)`` there: a strip of roll ``r``
   and field of view ``f`` covers sample ``j`` about when ``|a_j - r| <= f / 2`` and the
   strip spans ``t_j`` (RULES.md geometry: the imaged ground line at an instant lies in
   the plane through the satellite normal to ``along``).
3. **Groups.** Rolls on a grid of :data:`ROLL_STEP_DEG` inside each side of the band
   (edges ``|r| -+ f/2`` kept inside ``[min_edge, max_edge]`` by 1e-4 deg, values on a
   1e-4 deg grid so the solution file writes them exactly); per (pass, roll) with any
   sample near it, the slots spanning those samples' crossings, one slot of slack on
   each side, at least the minimum duration. Groups of one (satellite, roll) whose slots
   meet are merged.
4. **Coverage.** Each slot of each group is one 10 s candidate of R2's engine
   (:func:`jaxspline.screen.coverage.coverage_slices`, exact quad geometry); a strip over
   slots ``[a, b)`` covers the union of its slots' rows (see
   :mod:`jaxspline.search.coverage_problem`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from jaxspline.geometry.frames import geodetic_to_ecef
from jaxspline.search.coverage_problem import CoverProblem, sample_weights
from jaxspline.search.coverage_rules import Margins, conservative_sunlit, sat_rules

__all__ = [
    "CandidateInfo",
    "build_problem",
    "find_groups",
    "frame_vectors",
    "pass_crossings",
    "roll_grid",
    "sample_crossings",
]

#: Roll grid step [deg] (~3 km on the ground at 30 deg off nadir from 550 km).
ROLL_STEP_DEG = 0.25
#: Decimals of the written roll values.
ROLL_DECIMALS = 4
#: A pass is kept if some sample's look angle is within this of the band [deg].
PASS_SLACK_DEG = 1.0
#: Extra look-angle slack when deciding which samples a roll may cover [deg].
ROLL_SLACK_DEG = 0.3
#: Ground speed used to size a pass's search window (a lower bound) [m/s].
MIN_GROUND_SPEED = 6000.0
#: Mesh samples added on each side of a pass window.
WINDOW_PAD = 3


@dataclass(frozen=True)
class CandidateInfo:
    """What the candidate stage produced, for reports.

    Attributes:
      n_passes: passes found (satellite x region crossings in reach).
      n_groups, n_rows, nnz: groups, slot rows and covered-sample entries of the table.
      union_ratio: coverage_ratio of all rows together (what any plan can reach at most).
      seconds: dict of stage timings [s].
    """

    n_passes: int
    n_groups: int
    n_rows: int
    nnz: int
    union_ratio: float
    seconds: dict


def frame_vectors(pos: np.ndarray, vel: np.ndarray):
    """The roll frame (RULES.md): nadir, along, across unit vectors.

    Args:
      pos: float [..., 3] Earth-fixed position [m]; vel: float [..., 3] velocity [m/s].
    Returns:
      (nadir, along, across), float [..., 3] each.
    """
    nadir = -pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    along = vel - np.sum(vel * nadir, axis=-1, keepdims=True) * nadir
    along /= np.linalg.norm(along, axis=-1, keepdims=True)
    return nadir, along, np.cross(along, nadir)


def roll_grid(rules, step_deg: float = ROLL_STEP_DEG) -> np.ndarray:
    """Roll magnitudes [deg] of a satellite's grid, inside the band with 1e-4 deg to spare.

    Args:
      rules: SatRules (min/max edge, fov).
      step_deg: grid step [deg].
    Returns:
      float64 [M] increasing (empty when the band is narrower than the field of view).
    """
    q = 10.0**ROLL_DECIMALS
    lo = np.ceil((rules.min_edge_deg + rules.fov_deg / 2) * q + 1) / q
    hi = np.floor((rules.max_edge_deg - rules.fov_deg / 2) * q - 1) / q
    if hi < lo:
        return np.zeros(0)
    n = int(np.floor((hi - lo) / step_deg + 1e-9))
    vals = np.round(lo + step_deg * np.arange(n + 1), ROLL_DECIMALS)
    if hi - vals[-1] > 1e-9:
        vals = np.append(vals, hi)
    return vals[(vals >= lo) & (vals <= hi)]


def pass_crossings(frames, pos, point: np.ndarray) -> np.ndarray:
    """Mesh indices k where a ground point crosses the cross-track plane between k, k+1.

    Args:
      frames: (nadir, along, across) [K, 3] of one satellite; pos: float [K, 3] [m].
      point: float [3], Earth-fixed point [m].
    Returns:
      int64 indices (point in front of the horizon side: ``(X - p) . nadir > 0``).
    """
    nadir, along, _ = frames
    d = point[None, :] - pos
    u = np.sum(d * along, axis=1)
    front = np.sum(d * nadir, axis=1) > 0
    k = np.nonzero((u[:-1] >= 0) & (u[1:] < 0) & front[:-1])[0]
    return k


def sample_crossings(frames, pos, xyz: np.ndarray, k_lo: int, k_hi: int, step_s: float):
    """Crossing instant and look angle of each point within mesh window [k_lo, k_hi].

    Args:
      frames: (nadir, along, across) [K, 3]; pos: [K, 3]; xyz: float [n, 3] points [m].
      k_lo, k_hi: mesh window (inclusive); step_s: mesh step [s].
    Returns:
      (t [n] seconds from the horizon start, a [n] look angle [deg]); NaN where the point
      does not cross inside the window.
    """
    nadir, along, across = (f[k_lo : k_hi + 1] for f in frames)
    d = xyz[:, None, :] - pos[None, k_lo : k_hi + 1]
    u = np.einsum("nkc,kc->nk", d, along)
    look = np.degrees(
        np.arctan2(np.einsum("nkc,kc->nk", d, across), np.einsum("nkc,kc->nk", d, nadir))
    )
    hit = (u[:, :-1] >= 0) & (u[:, 1:] < 0)
    has = hit.any(axis=1)
    k = np.argmax(hit, axis=1)
    rows = np.arange(xyz.shape[0])
    u0, u1 = u[rows, k], u[rows, k + 1]
    frac = np.where(has, u0 / np.where(has, u0 - u1, 1.0), np.nan)
    t = (k_lo + k + frac) * step_s
    a = look[rows, k] + frac * (look[rows, k + 1] - look[rows, k])
    return np.where(has, t, np.nan), np.where(has, a, np.nan)


def _ground_reach(pos: np.ndarray, look_deg: float) -> float:
    """Largest ground distance [m] a look angle reaches over a track (spherical Earth).

    Earth central angle ``asin(|p| / R sin(a)) - a`` (or the horizon's ``acos(R / |p|)``
    when the ray misses the sphere), ``R`` the WGS84 polar radius (the smaller one, so the
    distance is an over-estimate), times the equatorial radius.
    """
    from jaxspline.screen.coverage_kernels import WGS84_B

    rmax = float(np.max(np.linalg.norm(pos, axis=1)))
    a = np.radians(min(look_deg, 89.0))
    x = rmax / WGS84_B * np.sin(a)
    lam = np.arccos(WGS84_B / rmax) if x >= 1.0 else np.arcsin(x) - a
    return float(lam * 6378137.0)


def _pass_groups(rules, grid, t, a, slot_s, n_slots_total, min_slots):
    """(roll, slot_lo, slot_hi) of one pass from its samples' crossings."""
    ok = np.isfinite(t)
    t, a = t[ok], a[ok]
    out = []
    half = rules.fov_deg / 2 + ROLL_SLACK_DEG
    for sign in (1.0, -1.0):
        rolls = sign * grid
        near = np.abs(a[None, :] - rolls[:, None]) <= half
        for i in np.nonzero(near.any(axis=1))[0]:
            tt = t[near[i]]
            lo = int(np.floor(tt.min() / slot_s)) - 1
            hi = int(np.floor(tt.max() / slot_s)) + 2
            if hi - lo < min_slots:
                hi = lo + min_slots
            lo, hi = max(lo, 0), min(hi, n_slots_total)
            if hi - lo >= min_slots:
                out.append((float(rolls[i]), lo, hi))
    return out


def _merge_groups(groups):
    """Merge (sat, roll, lo, hi) entries of one (sat, roll) whose slot ranges meet."""
    groups = sorted(groups)
    out = []
    for s, r, lo, hi in groups:
        if out and out[-1][0] == s and out[-1][1] == r and lo <= out[-1][3]:
            out[-1][3] = max(out[-1][3], hi)
        else:
            out.append([s, r, lo, hi])
    return out


def find_groups(case, tracks, grid_xyz, step_deg=ROLL_STEP_DEG):
    """All groups (sat, roll, slot_lo, slot_hi) of a case, and the number of passes.

    Args:
      case: Case; tracks: Tracks (R2's :func:`jaxspline.geometry.coverage_tracks.build_tracks`).
      grid_xyz: float [N, 3] Earth-fixed sample positions [m].
      step_deg: roll grid step [deg].
    Returns:
      (groups list of [sat, roll, lo, hi], n_passes).
    """
    slot_s = float(case.time_step_s)
    n_slots_total = int(np.floor(case.horizon_s / slot_s + 1e-9))
    region = case.grid.region
    groups, n_passes = [], 0
    for s, sat in enumerate(case.satellites):
        rules = sat_rules(sat)
        grid = roll_grid(rules, step_deg)
        min_slots = max(1, int(np.ceil(rules.min_dur_s / slot_s - 1e-9)))
        pos = tracks.pos[s]
        frames = frame_vectors(pos, tracks.vel[s])
        for r in range(len(case.regions)):
            xyz = grid_xyz[region == r]
            if xyz.shape[0] == 0:
                continue
            centre = xyz.mean(axis=0)
            reach = np.max(np.linalg.norm(xyz - centre, axis=1))
            w = int(np.ceil(reach / MIN_GROUND_SPEED / tracks.step_s)) + WINDOW_PAD
            far = _ground_reach(pos, rules.max_edge_deg + PASS_SLACK_DEG) + reach
            for k in pass_crossings(frames, pos, centre):
                p = pos[k]
                ang = np.arctan2(np.linalg.norm(np.cross(p, centre)), p @ centre)
                if ang * np.linalg.norm(centre) > far:
                    continue
                k_lo, k_hi = max(0, k - w), min(pos.shape[0] - 1, k + 1 + w)
                t, a = sample_crossings(frames, pos, xyz, k_lo, k_hi, tracks.step_s)
                aa = np.abs(a[np.isfinite(a)])
                lo_b = rules.min_edge_deg - PASS_SLACK_DEG
                hi_b = rules.max_edge_deg + PASS_SLACK_DEG
                if not np.any((aa >= lo_b) & (aa <= hi_b)):
                    continue
                n_passes += 1
                for roll, lo, hi in _pass_groups(
                    rules, grid, t, a, slot_s, n_slots_total, min_slots
                ):
                    groups.append([s, roll, lo, hi])
    return _merge_groups(groups), n_passes


def _sunlit_intervals(tracks) -> np.ndarray:
    """Conservative charging flags [S, K-1]: both mesh ends sunlit, one interval of guard."""
    return np.stack([conservative_sunlit(lit, guard=1) for lit in tracks.sunlit])


def _table(case, tracks, groups, slot_s):
    """Run the coverage engine on every (group, slot) row; returns CSR arrays."""
    from jaxspline.screen.coverage import Candidates, coverage_slices

    ratio = slot_s / tracks.step_s
    per = int(round(ratio))
    if abs(ratio - per) > 1e-9:
        raise ValueError(
            f"manifest.json: time_step_s ({slot_s}) must be a multiple of "
            f"coverage_sample_step_s ({tracks.step_s})"
        )
    g = np.array(groups, dtype=np.float64).reshape(-1, 4)
    n = (g[:, 3] - g[:, 2]).astype(np.int64)
    gi = np.repeat(np.arange(len(groups)), n)
    slot = np.repeat(g[:, 2].astype(np.int64), n) + (
        np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    )
    cands = Candidates(
        sat=g[gi, 0].astype(np.int32),
        k0=(slot * per).astype(np.int32),
        n=np.full(slot.size, per + 1, np.int32),
        roll_deg=g[gi, 1],
    )
    fov = np.array([s.sensor.fov_deg for s in case.satellites], dtype=np.float64)
    res = coverage_slices(
        tracks.pos, tracks.vel, fov, cands, case.grid.lon_deg, case.grid.lat_deg, case.grid.region
    )
    table = res.csr()
    bad = np.bincount(gi[~res.valid], minlength=len(groups)) > 0
    return table.indptr, table.indices, n, bad, res.stats


def build_problem(case, tracks=None, step_deg=ROLL_STEP_DEG, margins=None, log=None):
    """The CoverProblem of a case (see the module docstring).

    Args:
      case: Case.
      tracks: Tracks (built when None).
      step_deg: roll grid step [deg].
      margins: Margins for the search (default ``Margins()``).
      log: optional callable(str) for progress lines.
    Returns:
      (CoverProblem, CandidateInfo).
    """
    from jaxspline.geometry.coverage_tracks import build_tracks

    margins = Margins() if margins is None else margins
    secs = {}
    t0 = time.perf_counter()
    tracks = build_tracks(case) if tracks is None else tracks
    sunlit_iv = _sunlit_intervals(tracks)
    secs["tracks"] = time.perf_counter() - t0
    grid = case.grid
    xyz = geodetic_to_ecef(np.radians(grid.lat_deg), np.radians(grid.lon_deg))
    t1 = time.perf_counter()
    slot_s = float(case.time_step_s)
    groups, n_passes = find_groups(case, tracks, xyz, step_deg)
    secs["passes"] = time.perf_counter() - t1
    if log:
        log(f"  {n_passes} passes, {len(groups)} groups ({secs['passes']:.1f} s)")
    t2 = time.perf_counter()
    indptr, indices, nslots, bad, stats = _table(case, tracks, groups, slot_s)
    secs["coverage"] = time.perf_counter() - t2
    prob = _assemble(case, tracks, groups, indptr, indices, nslots, bad, sunlit_iv, margins)
    weight = prob.weight
    union = np.zeros(prob.n_samples, bool)
    union[prob.indices] = True
    info = CandidateInfo(
        n_passes,
        prob.n_groups,
        prob.n_rows,
        int(prob.indices.size),
        float(weight[union].sum()),
        secs,
    )
    if log:
        log(
            f"  {info.n_rows} rows, {info.nnz} entries, union coverage "
            f"{info.union_ratio:.4f} ({secs['coverage']:.1f} s)"
        )
    return prob, info


def _assemble(case, tracks, groups, indptr, indices, nslots, bad, sunlit_iv, margins):
    """Drop groups with a ray off the Earth and build the CoverProblem."""
    g = np.array(groups, dtype=np.float64).reshape(-1, 4)
    row0 = np.concatenate([[0], np.cumsum(nslots)[:-1]]).astype(np.int64)
    keep = ~bad
    if not keep.all():
        rows = np.concatenate(
            [np.arange(r, r + n) for r, n in zip(row0[keep], nslots[keep], strict=True)]
        )
        counts = np.diff(indptr)[rows]
        starts = np.repeat(indptr[rows] - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
        indices = indices[starts + np.arange(counts.sum())]
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        g, nslots = g[keep], nslots[keep]
        row0 = np.concatenate([[0], np.cumsum(nslots)[:-1]]).astype(np.int64)
    grid = case.grid
    weight, ratio = sample_weights(
        grid.region, grid.weight_m2, grid.region_total_m2, [r.weight for r in case.regions]
    )
    rmin = np.array(
        [np.nan if r.min_coverage is None else r.min_coverage for r in case.regions], float
    )
    prob = CoverProblem(
        indptr=indptr.astype(np.int64),
        indices=indices.astype(np.int32),
        group_sat=g[:, 0].astype(np.int32),
        group_roll=g[:, 1],
        group_slot0=g[:, 2].astype(np.int64),
        group_nslots=nslots.astype(np.int64),
        group_row0=row0,
        weight=weight,
        ratio_weight=ratio,
        region=grid.region.astype(np.int32),
        region_min=rmin,
        rules=tuple(sat_rules(s) for s in case.satellites),
        mesh_s=tracks.t_s.astype(np.float64),
        sunlit_iv=sunlit_iv,
        slot_s=float(case.time_step_s),
        horizon_s=float(case.horizon_s),
        max_actions=int(case.max_actions),
        margins=margins,
    )
    prob.validate()
    return prob
