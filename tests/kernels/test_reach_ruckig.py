"""Ruckig (second order, max_jerk = inf) as an independent oracle for jaxspline.kernels.reach.

Ruckig with ``minimum_duration = T`` returns a trajectory of duration exactly T iff the
exact-T transfer is feasible, otherwise the end of the blocked interval (or T_min);
without a minimum duration it returns T_min.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from jaxspline.kernels.limits import AxisLimits
from jaxspline.kernels.reach import is_reachable, reach_margin
from jaxspline.kernels.reach_durations import feasible_durations

ruckig = pytest.importorskip("ruckig")


class _Oracle:
    def __init__(self):
        self.otg = ruckig.Ruckig(1)
        self.inp = ruckig.InputParameter(1)
        self.traj = ruckig.Trajectory(1)

    def duration(self, a1, b1, a2, b2, b, d, T=0.0):
        """Ruckig's duration (nan on a Ruckig error)."""
        inp = self.inp
        inp.current_position = [float(a1)]
        inp.current_velocity = [float(b1)]
        inp.current_acceleration = [0.0]
        inp.target_position = [float(a2)]
        inp.target_velocity = [float(b2)]
        inp.target_acceleration = [0.0]
        inp.max_velocity = [float(b)]
        inp.max_acceleration = [float(d)]
        inp.max_jerk = [math.inf]
        inp.minimum_duration = float(T) if T > 0 else None
        try:
            res = self.otg.calculate(inp, self.traj)
        except (
            RuntimeError,
            ValueError,
            ruckig.RuckigError,
        ):  # e.g. -101: duration above Ruckig's 7.6e3 s cap
            return math.nan
        if res not in (ruckig.Result.Working, ruckig.Result.Finished):
            return math.nan
        return self.traj.duration


def _cases(n, seed):
    """Random cases with edges: |b_i| = b, b1 = b2, D = E0, T = T0, tiny/huge T, tiny b or d."""
    rng = np.random.default_rng(seed)
    b = np.exp(rng.uniform(np.log(1e-2), np.log(5.0), n))
    d = np.exp(rng.uniform(np.log(1e-2), np.log(5.0), n))
    kind = rng.uniform(size=n)
    b = np.where(kind < 0.05, 1e-4 * b, b)
    d = np.where((kind >= 0.05) & (kind < 0.1), 1e-4 * d, d)
    b1 = rng.uniform(-1, 1, n) * b
    b2 = rng.uniform(-1, 1, n) * b
    e = rng.uniform(size=n)
    b1 = np.select([e < 0.12, e < 0.24], [b, -b], b1)
    e2 = rng.uniform(size=n)
    b2 = np.select([e2 < 0.12, e2 < 0.24, e2 < 0.3], [b, -b, b1], b2)
    # displacement on the natural scale b^2/d, capped so durations stay below Ruckig's
    # 7.6e3 s trajectory-duration limit
    scale = b * np.minimum(b / d, 200.0)
    D = rng.uniform(-3, 3, n) * scale * rng.choice([0.1, 1.0, 10.0], n)
    # a1 on the same scale: an O(1) offset on a 1e-10 rad move is ill-conditioned for any
    # oracle working with absolute positions
    a1 = rng.uniform(-3, 3, n) * scale
    e0 = (b1 + b2) * np.abs(b1 - b2) / (2 * d)
    D = np.where(rng.uniform(size=n) < 0.05, e0, D)  # isolated / tangent cases
    a2 = a1 + D
    return a1, b1, a2, b2, b, d, rng


def _pick_times(tm, blo, bhi, b, d, b1, b2, rng):
    n = len(tm)
    t0 = np.abs(b1 - b2) / d
    u = rng.uniform(size=n)
    scale = np.where(np.isfinite(tm), tm, t0) + b / d
    T = rng.uniform(0, 2, n) * scale
    T = np.where(u < 0.05, t0, T)
    T = np.where((u >= 0.05) & (u < 0.1), 1e-6 * b / d, T)
    T = np.where((u >= 0.1) & (u < 0.15), np.minimum(1e4 * scale, 7000.0), T)  # Ruckig cap
    has = bhi > blo
    mid = 0.5 * (blo + bhi)
    T = np.where(has & (u >= 0.15) & (u < 0.35), mid, T)
    T = np.where((u >= 0.35) & (u < 0.4), 0.0, T)
    return np.minimum(T, 7000.0)  # Ruckig refuses durations above ~7.6e3 s


def _run(n, seed):
    a1, b1, a2, b2, b, d, rng = _cases(n, seed)
    lim = AxisLimits(b, d)
    tm, blo, bhi = (np.asarray(x) for x in feasible_durations(a1, b1, a2, b2, lim))
    T = _pick_times(tm, blo, bhi, b, d, b1, b2, rng)
    reach = np.asarray(is_reachable(a1, b1, a2, b2, T, lim), bool)
    margin = np.asarray(reach_margin(a1, b1, a2, b2, T, lim))
    oracle = _Oracle()
    r_tmin = np.array([oracle.duration(*row) for row in zip(a1, b1, a2, b2, b, d, strict=True)])
    r_T = np.array([oracle.duration(*row) for row in zip(a1, b1, a2, b2, b, d, T, strict=True)])
    return dict(
        a1=a1,
        b1=b1,
        a2=a2,
        b2=b2,
        b=b,
        d=d,
        T=T,
        tm=tm,
        blo=blo,
        bhi=bhi,
        reach=reach,
        margin=margin,
        r_tmin=r_tmin,
        r_T=r_T,
    )


def _check(res, label):
    n = len(res["T"])
    # Ruckig refuses trajectories longer than ~7.6e3 s: those cases are out of its range
    in_range = (res["tm"] < 7000.0) & (res["bhi"] < 7000.0)
    ok_r = np.isfinite(res["r_tmin"]) & np.isfinite(res["r_T"])
    # Ruckig itself occasionally throws on exact edge inputs (e.g. a1 = a2, b1 = b2 = b)
    n_err = np.sum(~ok_r & in_range)
    assert n_err <= 0.002 * n
    ok_r &= in_range
    tm, T, r_T, r_tmin = res["tm"], res["T"], res["r_T"], res["r_tmin"]
    # --- min_transfer_time
    rel = np.abs(tm - r_tmin) / np.maximum(tm, 1e-6 * res["b"] / res["d"])  # abs near T = 0
    rel = np.where(ok_r, rel, 0.0)
    # D = E0 exactly: T0 is an isolated feasible point before a blocked interval; Ruckig
    # skips it and returns the end of the block (a measure-zero difference)
    isolated = (res["blo"] == tm) & (res["bhi"] > tm)
    rel_iso = np.abs(res["bhi"] - r_tmin) / res["bhi"]
    rel = np.where(isolated & (rel_iso < 1e-7), 0.0, rel)
    tmin_agree = np.sum(ok_r & (rel < 1e-7))
    # --- is_reachable: ruckig returned exactly T
    r_feasible = np.abs(r_T - T) <= 1e-9 * np.maximum(T, res["b"] / res["d"])
    scale = np.abs(res["a1"]) + np.abs(res["a2"]) + res["b"] * T + res["b"] ** 2 / res["d"]
    ambiguous = np.abs(res["margin"]) <= 1e-9 * scale
    agree = (r_feasible == res["reach"]) & ok_r
    clear = ok_r & ~ambiguous
    # --- blocked interval: inside it Ruckig jumps to its end
    inside = ok_r & (T > res["blo"]) & (T < res["bhi"]) & (T > res["tm"])
    dev_block = np.abs(r_T - res["bhi"]) / res["bhi"]
    dev_block = np.where(inside, dev_block, 0.0)
    print(
        f"\n[reach/ruckig {label}] n={n} out of Ruckig's range={np.sum(~in_range)}, "
        f"Ruckig errors={n_err}; "
        f"min_transfer_time agree {tmin_agree}/{ok_r.sum()} (rel dev max {rel.max():.2e}, "
        f"99.9% {np.quantile(rel[ok_r], 0.999):.1e}; "
        f"{np.sum(isolated & ok_r)} isolated-T0 cases = Ruckig's block end); "
        f"is_reachable agree {agree.sum()}/{ok_r.sum()} "
        f"(clear cases {np.sum(agree & clear)}/{clear.sum()}, reachable {res['reach'].sum()}); "
        f"blocked-interval end vs ruckig: {inside.sum()} cases, max rel dev {dev_block.max():.2e}"
    )
    assert np.sum(~ok_r) <= 0.05 * n
    assert tmin_agree == ok_r.sum(), np.flatnonzero(ok_r & (rel >= 1e-7))[:5]
    assert np.all(agree[clear]), np.flatnonzero(clear & ~agree)[:5]
    assert np.sum(agree) >= ok_r.sum() - 0.002 * n
    assert inside.sum() > 0.02 * n
    assert dev_block.max() < 1e-7
    return res


def test_ruckig_oracle_default():
    _check(_run(2000, seed=101), "default")


@pytest.mark.slow
def test_ruckig_oracle_large():
    _check(_run(40000, seed=202), "slow")


def test_blocked_interval_ends_are_feasible():
    """Both ends of the blocked interval are feasible durations; Ruckig accepts them."""
    res = _run(1000, seed=303)
    has = (res["bhi"] > res["blo"]) & (res["bhi"] < 7000.0)
    idx = np.flatnonzero(has)[:100]
    oracle = _Oracle()
    worst = 0.0
    for i in idx:
        args = (res[k][i] for k in ("a1", "b1", "a2", "b2", "b", "d"))
        args = tuple(args)
        # Ruckig's own root finder can fail exactly at a boundary; probe 1e-9 outside the block
        ends = [res["bhi"][i] * (1 + 1e-9)]
        if res["blo"][i] > res["tm"][i]:  # else T0 is an isolated point: nothing just below
            ends.append(res["blo"][i] * (1 - 1e-9))
        for end in ends:
            dur = oracle.duration(*args, end)
            worst = max(worst, abs(dur - end) / end)
    print(f"\n[reach/ruckig] blocked ends accepted: {idx.size} cases, max rel dev {worst:.2e}")
    assert idx.size > 20
    assert worst < 1e-7
