"""Reference for the tests: how far a plain SGP4 TEME + GMST82 model is from the checker.

Moved out of :mod:`jaxspline.aeossp.check` (only the tests use it).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from jaxspline.aeossp.case import Case
from jaxspline.aeossp.check_frames import (
    Ephemeris,
    _rot3,
    angle_deg,
    ecef_to_gcrf_matrix,
    geodetic_to_ecef,
    gmst82,
    sunlit,
    teme_to_ecef,
)


def frame_difference(
    case: Case, satellite_ids=None, step_s: float = 30.0, max_pairs: int = 4000, seed: int = 0
) -> dict[str, Any]:
    """Measure how far a plain "SGP4 TEME + GMST82 rotation" model is from this checker.

    For each satellite (default: all) and every ``step_s`` over the horizon, every task
    within ``max_off_nadir_deg`` (checker geometry) is a sample. Compared models:
    ``teme84`` (SGP4 WGS84, Earth-fixed = R3(GMST82) TEME, slews in TEME) and ``teme72``
    (the same with SGP4's classic WGS72 constants). Reports the max |Δ| of the off-nadir
    angle (deg), of the slew angle (deg) for random pairs of samples of one satellite
    1-180 s apart, of the nadir->target angle, and the fraction of resource-grid instants
    whose sunlit flag differs when the shadow test uses TEME instead of GCRF positions.
    """
    rng = np.random.default_rng(seed)
    chosen = [
        s for s in case.satellites if satellite_ids is None or s.satellite_id in satellite_ids
    ]
    tt = case.task_table()
    tgt = geodetic_to_ecef(tt["latitude_deg"], tt["longitude_deg"], tt["altitude_m"])
    ts = np.arange(0.0, case.duration_s + 0.5 * step_s, step_s)
    res = {
        "off_nadir": {"teme84": 0.0, "teme72": 0.0},
        "slew": {"teme84": 0.0, "teme72": 0.0},
        "nadir_slew": {"teme84": 0.0, "teme72": 0.0},
    }
    n_samples = n_pairs = 0
    sun_flip = sun_total = 0
    for sat in chosen:
        e84, e72 = Ephemeris(sat, case.horizon_start), Ephemeris(sat, case.horizon_start, "wgs72")
        unix = e84.unix(ts)
        ecef = e84.ecef(ts)
        mgc = ecef_to_gcrf_matrix(unix)
        gc = np.einsum("nij,nj->ni", mgc, ecef)
        t84, t72 = e84.teme(ts), e72.teme(ts)
        ecef72 = teme_to_ecef(t72, unix)
        los = tgt[None, :, :] - ecef[:, None, :]
        off = angle_deg(-ecef[:, None, :], los)
        up = np.sum((ecef[:, None, :] - tgt[None]) * tgt[None], -1) > 0
        it, ik = np.nonzero((off <= sat.max_off_nadir_deg) & up)
        if it.size == 0:
            continue
        n_samples += it.size
        off72 = angle_deg(-ecef72[it], tgt[ik] - ecef72[it])
        res["off_nadir"]["teme72"] = max(
            res["off_nadir"]["teme72"], float(np.max(np.abs(off72 - off[it, ik])))
        )
        # Earth-fixed is identical in the teme84 model: difference is exactly zero.
        r3t = np.swapaxes(_rot3(gmst82(unix)), -1, -2)  # Earth-fixed -> TEME
        los_gc = np.einsum("nij,nj->ni", mgc[it], tgt[ik]) - gc[it]
        los84 = np.einsum("nij,nj->ni", r3t[it], tgt[ik]) - t84[it]
        los72 = np.einsum("nij,nj->ni", r3t[it], tgt[ik]) - t72[it]
        nad = angle_deg(-gc[it], los_gc)
        res["nadir_slew"]["teme84"] = max(
            res["nadir_slew"]["teme84"], float(np.max(np.abs(angle_deg(-t84[it], los84) - nad)))
        )
        res["nadir_slew"]["teme72"] = max(
            res["nadir_slew"]["teme72"], float(np.max(np.abs(angle_deg(-t72[it], los72) - nad)))
        )
        a = rng.integers(0, it.size, size=8 * max_pairs // max(1, len(chosen)))
        b = rng.integers(0, it.size, size=a.size)
        dt = ts[it[b]] - ts[it[a]]
        sel = (dt > 0) & (dt <= 180.0)
        a, b = a[sel], b[sel]
        if a.size:
            n_pairs += a.size
            ref = angle_deg(los_gc[a], los_gc[b])
            res["slew"]["teme84"] = max(
                res["slew"]["teme84"], float(np.max(np.abs(angle_deg(los84[a], los84[b]) - ref)))
            )
            res["slew"]["teme72"] = max(
                res["slew"]["teme72"], float(np.max(np.abs(angle_deg(los72[a], los72[b]) - ref)))
            )
        tr = np.arange(0.0, case.duration_s, case.resource_step_s) + 0.5 * case.resource_step_s
        ur = e84.unix(tr)
        sun_flip += int(np.sum(sunlit(e84.gcrf(tr), ur) != sunlit(e84.teme(tr), ur)))
        sun_total += tr.size
    res.update(n_samples=n_samples, n_pairs=n_pairs, n_satellites=len(chosen))
    res["sunlit_flag_mismatch_teme"] = sun_flip / sun_total if sun_total else 0.0
    return res
