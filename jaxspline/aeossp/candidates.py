"""Grid-aligned observation candidates and slew-transition screening (aeossp_standard).

A candidate is one (task, satellite, start) with the start on the action grid
inside ``[release, due - duration]`` such that at EVERY grid instant from the
start to the end (both included) the target is above the local horizon and the
off-nadir angle is ``<= max_off_nadir - margin`` (RULES.md rule 5; the grid is
the gcd of the action and geometry steps, so it contains every instant the
checker samples).

Screening is vectorized: per satellite a matrix product of target and
sub-satellite unit vectors finds the (task, instant) pairs within a
conservative Earth-central angle of the reach cone; only those are tested
exactly; runs of consecutive good instants (a sliding-window minimum done by
run-length encoding) give the valid start intervals, which are then thinned.

Transitions between two candidates of one satellite need
``gap >= t_bcb(theta) + settling + margin`` with ``theta`` the angle between the
inertial (TEME) lines of sight at the previous end and the next start
(RULES.md rule 7). The angle is rotation invariant, so TEME and GCRF give the
same value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jaxspline.aeossp.geometry import GridGeometry, ecef_to_teme, target_ecef

__all__ = [
    "Candidates",
    "SatParams",
    "bcb_time_np",
    "build_candidates",
    "los_angle",
    "nadir_gaps",
    "sat_params",
]


@dataclass(frozen=True)
class SatParams:
    """Per-satellite arrays (index = position in ``case.satellites``).

    rate [rad/s], accel [rad/s^2], settle [s], max_off_nadir [rad],
    capacity / initial [Wh], idle / imaging / slew / charge power [W], infrared (bool).
    """

    rate: np.ndarray
    accel: np.ndarray
    settle: np.ndarray
    max_off_nadir: np.ndarray
    capacity: np.ndarray
    initial: np.ndarray
    idle: np.ndarray
    imaging: np.ndarray
    slew: np.ndarray
    charge: np.ndarray
    infrared: np.ndarray


def sat_params(case) -> SatParams:
    """Collect the satellites' attitude and battery parameters of ``case`` as arrays."""
    ss = case.satellites

    def arr(f):
        return np.array([f(s) for s in ss], dtype=float)

    return SatParams(
        rate=np.radians(arr(lambda s: s.max_slew_rate_deg_s)),
        accel=np.radians(arr(lambda s: s.max_slew_accel_deg_s2)),
        settle=arr(lambda s: s.settling_time_s),
        max_off_nadir=np.radians(arr(lambda s: s.max_off_nadir_deg)),
        capacity=arr(lambda s: s.battery_capacity_wh),
        initial=arr(lambda s: s.initial_battery_wh),
        idle=arr(lambda s: s.idle_power_w),
        imaging=arr(lambda s: s.imaging_power_w),
        slew=arr(lambda s: s.slew_power_w),
        charge=arr(lambda s: s.sunlit_charge_power_w),
        infrared=np.array([s.sensor_type == "infrared" for s in ss], dtype=bool),
    )


def bcb_time_np(theta, rate, accel):
    """Rest-to-rest bang-coast-bang slew time [s] (numpy, for the solver's hot loop).

    ``t = 2 sqrt(theta/a)`` if ``theta <= v^2/a`` else ``theta/v + v/a``
    (theta [rad], v [rad/s], a [rad/s^2]). Same formula as
    :func:`jaxspline.slew.bang_coast_bang_time` (tests check agreement); this
    copy avoids a JAX dispatch per insertion test. Reference: RULES.md rule 7.
    """
    theta = np.abs(theta)
    return np.where(
        theta <= rate * rate / accel,
        2.0 * np.sqrt(theta / accel),
        theta / rate + rate / accel,
    )


def los_angle(u, v):
    """Angle [rad] between unit vectors ``u`` and ``v`` [..., 3] via ``atan2(|u x v|, u . v)``."""
    cr = np.cross(u, v)
    return np.arctan2(np.sqrt(np.sum(cr * cr, axis=-1)), np.sum(u * v, axis=-1))


@dataclass(frozen=True)
class Candidates:
    """Struct-of-arrays of observation candidates, sorted by (satellite, start, task).

    Attributes:
      task, sat: [C] int indices into ``case.tasks`` / ``case.satellites``.
      start, end: [C] int grid indices (time = index * step_s from horizon start).
      los_start, los_end: [C, 3] inertial (TEME) unit lines of sight at start / end.
      nadir_gap: [C] required gap [s] (slew from nadir + settling + margin) if first.
      step_s: grid step [s].
    """

    task: np.ndarray
    sat: np.ndarray
    start: np.ndarray
    end: np.ndarray
    los_start: np.ndarray
    los_end: np.ndarray
    nadir_gap: np.ndarray
    step_s: float

    def __len__(self) -> int:
        return int(self.task.shape[0])


def _los(tgt, geo: GridGeometry, sat, k):
    d = tgt - geo.sat_ecef[sat, k]
    d = ecef_to_teme(d, geo.gmst[k])
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def nadir_gaps(los, sat, k, geo: GridGeometry, sp: SatParams, gap_margin_s: float):
    """Required gap [s] before a first action: slew from nadir (``-r_sat``) at its start.

    Uses :func:`jaxspline.slew.bang_coast_bang_time` (jit + broadcast) on the batch.
    """
    from jaxspline.slew import bang_coast_bang_time

    if len(sat) == 0:
        return np.zeros(0)
    r = geo.sat_teme[sat, k]
    nadir = -r / np.linalg.norm(r, axis=-1, keepdims=True)
    theta = los_angle(nadir, los)
    t = np.asarray(bang_coast_bang_time(theta, sp.rate[sat], sp.accel[sat]), dtype=float)
    return t + sp.settle[sat] + gap_margin_s


def build_candidates(
    case,
    geo: GridGeometry,
    sp: SatParams,
    *,
    off_nadir_margin_deg: float = 0.05,
    horizon_margin: float = 0.02,
    gap_margin_s: float = 0.5,
    thin: int = 2,
    chunk: int = 512,
    coarse: int = 12,
) -> Candidates:
    """Screen every (task, satellite, start) and return the valid, thinned candidates.

    Args:
      case: the loaded case.
      geo: grid geometry of :func:`jaxspline.aeossp.geometry.propagate_grid`.
      sp: :func:`sat_params` of the case.
      off_nadir_margin_deg: required off-nadir angle <= limit - margin [deg].
      horizon_margin: required sine of the target elevation-like quantity
        ``(r_sat - r_tgt) . r_tgt_hat / |r_sat - r_tgt|`` (> 0 in the rules).
      gap_margin_s: added to every required slew gap [s].
      thin: keep every ``thin``-th valid start of a run (on the action grid) plus the
        last valid start of the run.
      chunk: tasks per matrix block.
      coarse: stride of the coarse pre-screen [grid steps].
    Returns:
      :class:`Candidates`.
    """
    step = geo.step_s
    stride = max(1, int(round(case.action_step_s / step)))
    tt = case.task_table()
    n_last = geo.times_s.shape[0] - 1
    tgt = target_ecef(tt["latitude_deg"], tt["longitude_deg"], tt["altitude_m"])
    tgt_hat = tgt / np.linalg.norm(tgt, axis=-1, keepdims=True)
    dur = tt["duration_s"] / step
    dur_ok = (np.abs(dur - np.round(dur)) < 1e-9) & (
        np.abs(
            tt["duration_s"] / case.action_step_s - np.round(tt["duration_s"] / case.action_step_s)
        )
        < 1e-9
    )
    dur_i = np.round(dur).astype(np.int64)
    # first / last admissible start on the action grid
    first = np.ceil(tt["release_s"] / case.action_step_s - 1e-9).astype(np.int64) * stride
    last = (
        np.floor((tt["due_s"] - tt["duration_s"]) / case.action_step_s + 1e-9).astype(np.int64)
        * stride
    )
    first = np.maximum(first, 0)
    last = np.minimum(last, n_last - dur_i)
    usable = dur_ok & (dur_i > 0) & (last >= first)

    out = {k: [] for k in ("task", "sat", "start")}
    for j in range(len(case.satellites)):
        tasks_j = np.nonzero(usable & (tt["infrared"] == sp.infrared[j]))[0]
        if tasks_j.size == 0 or not geo.sgp4_ok[j].any():
            continue
        r_ecef = geo.sat_ecef[j]
        good_t = geo.sgp4_ok[j]
        rn = np.linalg.norm(np.where(good_t[:, None], r_ecef, 0.0), axis=-1)
        r_max = float(np.nanmax(rn[good_t]))
        eta = sp.max_off_nadir[j]
        r_min_t = float(np.min(np.linalg.norm(tgt[tasks_j], axis=-1)))
        lam = math.asin(min(1.0, r_max / r_min_t * math.sin(eta))) - eta + math.radians(1.0)
        u_s = np.where(good_t[:, None], r_ecef / np.where(rn > 0, rn, 1.0)[:, None], 0.0)
        cos_lim = math.cos(eta - math.radians(off_nadir_margin_deg))
        # coarse screen every `coarse` instants with a widened cone (the sub-satellite
        # point moves < 0.07 deg/s Earth-fixed, i.e. < 0.035*coarse*step deg half-way)
        cw = math.radians(0.035 * coarse * step + 0.5)
        cos_lam_c = math.cos(min(math.pi, lam + cw))
        u_c = np.ascontiguousarray(u_s[::coarse].T)  # [3, n_coarse]
        kc = np.arange(u_c.shape[1])[None, :] * coarse
        half = np.arange(-(coarse // 2) - 1, coarse // 2 + 2)
        for c0 in range(0, tasks_j.size, chunk):
            tk = tasks_j[c0 : c0 + chunk]
            lo_t, hi_t = first[tk, None], (last + dur_i)[tk, None]
            th = tgt_hat[tk]
            dots = th[:, 0:1] * u_c[0] + th[:, 1:2] * u_c[1] + th[:, 2:3] * u_c[2]
            m = (dots > cos_lam_c) & (kc >= lo_t - coarse) & (kc <= hi_t + coarse)
            ii, kci = np.nonzero(m)
            if ii.size == 0:
                continue
            ks = (kci[:, None] * coarse + half[None, :]).ravel()
            ii = np.repeat(ii, half.size)
            key = np.unique(ii * (n_last + 1) + np.clip(ks, 0, n_last))
            ii, ks = key // (n_last + 1), key % (n_last + 1)
            inwin = (ks >= first[tk[ii]]) & (ks <= (last + dur_i)[tk[ii]])
            ii, ks = ii[inwin], ks[inwin]
            ti = tk[ii]
            p = tgt[ti]
            r = r_ecef[ks]
            d = p - r
            dn = np.linalg.norm(d, axis=-1)
            hor = np.sum(-d * tgt_hat[ti], axis=-1) / dn > horizon_margin
            cos_off = np.sum(-r * d, axis=-1) / (np.linalg.norm(r, axis=-1) * dn)
            ok = hor & (cos_off >= cos_lim) & good_t[ks]
            ti, ks = ti[ok], ks[ok]
            if ti.size == 0:
                continue
            # runs of consecutive instants for the same task
            brk = np.ones(ti.size, dtype=bool)
            brk[1:] = (ti[1:] != ti[:-1]) | (ks[1:] != ks[:-1] + 1)
            r0_idx = np.nonzero(brk)[0]
            r1_idx = np.append(r0_idx[1:], ti.size) - 1
            rt = ti[r0_idx]
            s_lo = np.maximum(ks[r0_idx], first[rt])
            s_hi = np.minimum(ks[r1_idx] - dur_i[rt], last[rt])
            # align to the action grid
            s_lo = -((-s_lo) // stride) * stride
            s_hi = (s_hi // stride) * stride
            keep = s_hi >= s_lo
            rt, s_lo, s_hi = rt[keep], s_lo[keep], s_hi[keep]
            for t_i, a, b in zip(rt.tolist(), s_lo.tolist(), s_hi.tolist(), strict=True):
                starts = list(range(a, b + 1, stride * thin))
                if starts[-1] != b:
                    starts.append(b)
                out["task"].extend([t_i] * len(starts))
                out["sat"].extend([j] * len(starts))
                out["start"].extend(starts)
    task = np.asarray(out["task"], dtype=np.int64)
    sat = np.asarray(out["sat"], dtype=np.int64)
    start = np.asarray(out["start"], dtype=np.int64)
    order = np.lexsort((task, start, sat))
    task, sat, start = task[order], sat[order], start[order]
    end = start + dur_i[task]
    los_s = _los(tgt[task], geo, sat, start)
    los_e = _los(tgt[task], geo, sat, end)
    ng = nadir_gaps(los_s, sat, start, geo, sp, gap_margin_s)
    return Candidates(task, sat, start, end, los_s, los_e, ng, step)
