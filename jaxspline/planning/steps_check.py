"""Independent check of a plan's steps: rebuild every maneuver, sample it, check every rule.

Words: *validate* is the eager check of arguments (ValueError); *check* is an
independent re-check of a result, returned as a report (this module,
:mod:`jaxspline.planning.plan_check`, :mod:`jaxspline.aeossp.check`,
:func:`jaxspline.kernels.join_check.maneuver_check`).

The screening engine decides feasibility with closed-form kernels; this module
does not trust that verdict. For each transition of a plan it rebuilds the
Theorem-1 trajectory (convex combination of the envelope curves, SPEC section 1,
:func:`jaxspline.kernels.reach.transfer`), samples it densely and checks with numpy,
on the samples only:

* boundary continuity: the maneuver starts at the end state of step k and ends
  at the start state of step k+1 (angle and rate, every channel);
* the rate bound ``|f'| <= rate`` on the samples and at the scan boundary states;
* the acceleration bound: ``|f''|`` as returned, and the finite-difference
  slopes of the sampled rate (exact for a Lipschitz rate, whatever the
  switching times are);
* angle/rate consistency: the sampled angle equals the trapezoid integral of
  the sampled rate (a trajectory whose angle and rate disagree is rejected);
* the plan rules: time order without overlap (T > 0), start times inside the
  windows, each route at most once, ``scan_ok`` on every step.

Units: radians, seconds.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxspline.kernels.limits import AxisLimits, validate_limits
from jaxspline.screen.options import RouteOptions, options_dtype, validate_options

__all__ = ["StepsReport", "check_steps"]


class StepsReport(NamedTuple):
    """Result of :func:`check_steps`.

    Attributes:
      ok: True iff no violation was found.
      violations: human-readable descriptions, one per violation.
      peak_rate: [C] largest |rate| [rad/s] over all sampled maneuvers and the
        scan boundary states, per channel.
      peak_accel: [C] largest |accel| [rad/s^2] over all maneuvers (max of the
        returned accelerations and the finite-difference slopes of the rate).
      bad_steps: sorted indices of the steps to blame, one per failing rule: the later
        step of a failing transition ``k -> k + 1`` (``k + 1``), the step itself for a
        step rule (scan, window, boundary rate), the repeats of a route after its
        first step. Dropping them leaves a plan whose remaining transitions are new
        and need a re-check.
    """

    ok: bool
    violations: list[str]
    peak_rate: np.ndarray
    peak_accel: np.ndarray
    bad_steps: tuple[int, ...] = ()


def _transfer(a1, b1, a2, b2, T, limits, t):
    """Theorem-1 trajectory (angle, rate, accel) at t: :func:`jaxspline.kernels.reach.transfer`."""
    from jaxspline.kernels import reach

    return reach.transfer(a1, b1, a2, b2, T, limits, t)


def check_steps(
    steps: RouteOptions,
    limits: AxisLimits,
    windows=None,
    samples: int = 2001,
    *,
    rtol: float | None = None,
) -> StepsReport:
    """Check a plan given as its K steps (a RouteOptions table in plan order).

    Args:
      steps: RouteOptions with K rows, the plan's options in the order flown.
      limits: AxisLimits, ``rate`` [rad/s] and ``accel`` [rad/s^2] scalars or
        [C] per channel.
      windows: optional ``(t0_min [K], t0_max [K])`` [s], the allowed start
        times of each step's route.
      samples: samples per maneuver (>= 3), including both ends.
      rtol: relative tolerance of every check (default 1e-9 in float64, 1e-4 in
        float32, following the dtype of ``steps``); angle checks use
        ``rtol * (1 + |a1| + |a2| + rate T)`` [rad].

    Returns:
      StepsReport(ok, violations, peak_rate [C], peak_accel [C]).
    """
    c = validate_options(steps, "steps")
    limits = validate_limits(limits)
    if int(samples) < 3:
        raise ValueError(f"samples must be >= 3, got {samples!r}")
    samples = int(samples)
    dtype = np.dtype(options_dtype(steps))
    if rtol is None:
        rtol = 1e-9 if dtype == np.float64 else 1e-4
    rate = np.broadcast_to(np.asarray(limits.rate, np.float64), (c,))
    accel = np.broadcast_to(np.asarray(limits.accel, np.float64), (c,))
    k_steps = np.shape(steps.t_start)[0]
    route = np.asarray(steps.route)
    ts = np.asarray(steps.t_start, np.float64)
    te = np.asarray(steps.t_end, np.float64)
    sa, sr = np.asarray(steps.start_angle, np.float64), np.asarray(steps.start_rate, np.float64)
    ea, er = np.asarray(steps.end_angle, np.float64), np.asarray(steps.end_rate, np.float64)
    v: list[str] = []
    blame: set[int] = set()
    peak_rate = np.zeros(c)
    peak_accel = np.zeros(c)

    # plan rules
    for k in np.flatnonzero(~np.asarray(steps.scan_ok, bool)):
        v.append(f"step {k} (route {route[k]}): scan_ok is False")
        blame.add(int(k))
    _, first, counts = np.unique(route, return_index=True, return_counts=True)
    for r_first, cnt in zip(first, counts, strict=True):
        if cnt > 1:
            at = np.flatnonzero(route == route[r_first]).tolist()
            v.append(f"route {route[r_first]} imaged {cnt} times (steps {at})")
            blame.update(at[1:])
    if windows is not None:
        lo_w, hi_w = (np.broadcast_to(np.asarray(w, np.float64), (k_steps,)) for w in windows)
        tol_t = rtol * (1.0 + np.abs(ts))
        for k in np.flatnonzero((ts < lo_w - tol_t) | (ts > hi_w + tol_t)):
            v.append(
                f"step {k} (route {route[k]}): start {ts[k]!r} s outside window "
                f"[{lo_w[k]!r}, {hi_w[k]!r}]"
            )
            blame.add(int(k))
    # scan boundary states within the rate bound
    for name, x in (("start_rate", sr), ("end_rate", er)):
        peak_rate = np.maximum(peak_rate, np.abs(x).max(axis=0, initial=0.0))
        bad = np.abs(x) > rate * (1.0 + rtol)
        for k, ch in zip(*np.nonzero(bad), strict=True):
            v.append(f"step {k} channel {ch}: |{name}| = {abs(x[k, ch])!r} > rate {rate[ch]!r}")
            blame.add(int(k))

    # maneuvers
    for k in range(k_steps - 1):
        before = len(v)
        T = ts[k + 1] - te[k]
        if not T > 0:
            v.append(f"steps {k} -> {k + 1} overlap or touch: T = {T!r} s (needs T > 0)")
            blame.add(k + 1)
            continue
        t = np.linspace(0.0, T, samples)
        a1, b1, a2, b2 = ea[k], er[k], sa[k + 1], sr[k + 1]
        f, fd, fdd = (
            np.asarray(x, np.float64)
            for x in _transfer(
                a1[:, None].astype(dtype),
                b1[:, None].astype(dtype),
                a2[:, None].astype(dtype),
                b2[:, None].astype(dtype),
                dtype.type(T),
                AxisLimits(rate[:, None].astype(dtype), accel[:, None].astype(dtype)),
                t[None, :].astype(dtype),
            )
        )
        for ch in range(c):
            tag = f"transition {k} -> {k + 1} (T = {T:.6g} s) channel {ch}"
            if not (np.isfinite(f[ch]).all() and np.isfinite(fd[ch]).all()):
                v.append(f"{tag}: no trajectory (not reachable in exactly T)")
                continue
            atol = rtol * (1.0 + abs(a1[ch]) + abs(a2[ch]) + rate[ch] * T)
            rtol_rate = rtol * rate[ch] + rtol * accel[ch] * T
            ends = (
                ("start angle", f[ch, 0], a1[ch], atol),
                ("start rate", fd[ch, 0], b1[ch], rtol_rate),
                ("end angle", f[ch, -1], a2[ch], atol),
                ("end rate", fd[ch, -1], b2[ch], rtol_rate),
            )
            for what, got, want, tol in ends:
                if abs(got - want) > tol:
                    v.append(f"{tag}: {what} {got!r} != boundary state {want!r}")
            dt = np.diff(t)
            slope = np.abs(np.diff(fd[ch])) / dt
            pr = np.abs(fd[ch]).max()
            pa = max(slope.max(), np.abs(fdd[ch][np.isfinite(fdd[ch])]).max(initial=0.0))
            peak_rate[ch] = max(peak_rate[ch], pr)
            peak_accel[ch] = max(peak_accel[ch], pa)
            if pr > rate[ch] * (1.0 + rtol):
                v.append(f"{tag}: peak rate {pr!r} > limit {rate[ch]!r}")
            if pa > accel[ch] * (1.0 + rtol) + rtol * rate[ch] / T:
                v.append(f"{tag}: peak acceleration {pa!r} > limit {accel[ch]!r}")
            integral = f[ch, 0] + np.concatenate(
                [[0.0], np.cumsum(0.5 * (fd[ch, 1:] + fd[ch, :-1]) * dt)]
            )
            # trapezoid error on a piecewise-linear rate: <= accel dt^2 / 4 per kink (<= 4 kinks)
            tol_int = atol + accel[ch] * dt.max() ** 2 * 2.0
            dev = np.abs(integral - f[ch]).max()
            if dev > tol_int:
                v.append(f"{tag}: angle is not the integral of the rate (max deviation {dev!r})")
        if len(v) > before:
            blame.add(k + 1)
    return StepsReport(not v, v, peak_rate, peak_accel, tuple(sorted(blame)))
