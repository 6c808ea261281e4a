"""Independent check of a plan's steps: rebuild every maneuver, sample it, check every rule.

Words: *validate* is the eager check of arguments (ValueError); *check* is an
independent re-check of a result, returned as a report (this module,
:mod:`jaxspline.planner.plan_check`, :mod:`jaxspline.aeossp.check`,
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

from jaxspline.kernels.batch import map_chunked
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


_TRANSITION_CHUNK = 16  # transitions per compiled trajectory call (padded)


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
    cfg = _settings(c, steps, limits, samples, rtol)
    s = _float_steps(steps)
    v, blame = _plan_rule_violations(steps.scan_ok, s, windows, cfg.rtol)
    v_rate, blame_rate, peak_rate = _boundary_rate_violations(s, cfg, np.zeros(c))
    v_man, blame_man, peak_rate, peak_accel = _maneuver_violations(s, cfg, peak_rate)
    v = v + v_rate + v_man
    blame = blame | blame_rate | blame_man
    return StepsReport(not v, v, peak_rate, peak_accel, tuple(sorted(blame)))


class _Settings(NamedTuple):
    """What every check of :func:`check_steps` compares against: the bounds ``rate``
    [C] [rad/s] and ``accel`` [C] [rad/s^2] in float64, the relative tolerance
    ``rtol``, the dtype the maneuvers are rebuilt in, and the samples per maneuver."""

    rate: np.ndarray
    accel: np.ndarray
    rtol: float
    dtype: np.dtype
    samples: int


class _Steps(NamedTuple):
    """The plan's K steps as plain numpy arrays: ``route`` [K] as given, the start and
    end times ``ts``, ``te`` [K] and the boundary states ``sa``, ``sr`` (start angle,
    rate) and ``ea``, ``er`` (end angle, rate) [K, C] in float64."""

    route: np.ndarray
    ts: np.ndarray
    te: np.ndarray
    sa: np.ndarray
    sr: np.ndarray
    ea: np.ndarray
    er: np.ndarray


def _settings(c: int, steps: RouteOptions, limits, samples, rtol) -> _Settings:
    """Validate ``limits`` and ``samples`` (ValueError) and resolve the settings of the
    check: ``rtol`` defaults to 1e-9 in float64 and 1e-4 in float32 (the dtype of
    ``steps``), the bounds are broadcast to the ``c`` channels."""
    limits = validate_limits(limits)
    if int(samples) < 3:
        raise ValueError(f"samples must be >= 3, got {samples!r}")
    dtype = np.dtype(options_dtype(steps))
    if rtol is None:
        rtol = 1e-9 if dtype == np.float64 else 1e-4
    rate = np.broadcast_to(np.asarray(limits.rate, np.float64), (c,))
    accel = np.broadcast_to(np.asarray(limits.accel, np.float64), (c,))
    return _Settings(rate, accel, rtol, dtype, int(samples))


def _float_steps(steps: RouteOptions) -> _Steps:
    """The fields of ``steps`` the checks read, as numpy arrays (times and states in
    float64, so that every check runs in double precision whatever the plan's dtype)."""
    return _Steps(
        route=np.asarray(steps.route),
        ts=np.asarray(steps.t_start, np.float64),
        te=np.asarray(steps.t_end, np.float64),
        sa=np.asarray(steps.start_angle, np.float64),
        sr=np.asarray(steps.start_rate, np.float64),
        ea=np.asarray(steps.end_angle, np.float64),
        er=np.asarray(steps.end_rate, np.float64),
    )


def _plan_rule_violations(scan_ok, s: _Steps, windows, rtol) -> tuple[list[str], set[int]]:
    """The plan rules that need no maneuver: ``scan_ok`` on every step, each route at
    most once (its repeats after the first step are blamed), and, when ``windows`` is
    given, every start time inside its window (to ``rtol * (1 + |t|)``). Returns the
    violations and the blamed steps."""
    v: list[str] = []
    blame: set[int] = set()
    route, ts = s.route, s.ts
    for k in np.flatnonzero(~np.asarray(scan_ok, bool)):
        v.append(f"step {k} (route {route[k]}): scan_ok is False")
        blame.add(int(k))
    _, first, counts = np.unique(route, return_index=True, return_counts=True)
    for r_first, cnt in zip(first, counts, strict=True):
        if cnt > 1:
            at = np.flatnonzero(route == route[r_first]).tolist()
            v.append(f"route {route[r_first]} imaged {cnt} times (steps {at})")
            blame.update(at[1:])
    if windows is not None:
        lo_w, hi_w = (np.broadcast_to(np.asarray(w, np.float64), (ts.shape[0],)) for w in windows)
        tol_t = rtol * (1.0 + np.abs(ts))
        for k in np.flatnonzero((ts < lo_w - tol_t) | (ts > hi_w + tol_t)):
            v.append(
                f"step {k} (route {route[k]}): start {ts[k]!r} s outside window "
                f"[{lo_w[k]!r}, {hi_w[k]!r}]"
            )
            blame.add(int(k))
    return v, blame


def _boundary_rate_violations(
    s: _Steps, cfg: _Settings, peak_rate: np.ndarray
) -> tuple[list[str], set[int], np.ndarray]:
    """The scan boundary states (start and end rates of every step) within the rate
    bound. Returns the violations, the blamed steps and ``peak_rate`` [C] raised to
    the largest boundary |rate| of each channel."""
    v: list[str] = []
    blame: set[int] = set()
    for name, x in (("start_rate", s.sr), ("end_rate", s.er)):
        peak_rate = np.maximum(peak_rate, np.abs(x).max(axis=0, initial=0.0))
        bad = np.abs(x) > cfg.rate * (1.0 + cfg.rtol)
        for k, ch in zip(*np.nonzero(bad), strict=True):
            v.append(f"step {k} channel {ch}: |{name}| = {abs(x[k, ch])!r} > rate {cfg.rate[ch]!r}")
            blame.add(int(k))
    return v, blame, peak_rate


def _maneuver_violations(
    s: _Steps, cfg: _Settings, peak_rate: np.ndarray
) -> tuple[list[str], set[int], np.ndarray, np.ndarray]:
    """Every transition ``k -> k + 1`` in turn: T > 0, then the rebuilt maneuver's
    checks (:func:`_transition_violations`); a failing transition blames step
    ``k + 1``. Returns the violations, the blamed steps, ``peak_rate`` [C] raised to the
    maneuvers' peaks and the maneuvers' ``peak_accel`` [C] (a copy: the input stays)."""
    v: list[str] = []
    blame: set[int] = set()
    peak_rate = peak_rate.copy()
    peak_accel = np.zeros(peak_rate.shape[0])
    gaps = s.ts[1:] - s.te[:-1]
    flown = np.flatnonzero(gaps > 0)
    t, traj = _trajectories(s, cfg, flown)
    row = {int(k): i for i, k in enumerate(flown)}
    for k in range(s.ts.shape[0] - 1):
        T = gaps[k]
        if not T > 0:
            found = [f"steps {k} -> {k + 1} overlap or touch: T = {T!r} s (needs T > 0)"]
        else:
            i = row[k]
            found, peaks = _transition_violations(k, t[i], [x[i] for x in traj], s, cfg)
            for ch, pr, pa in peaks:
                peak_rate[ch] = max(peak_rate[ch], pr)
                peak_accel[ch] = max(peak_accel[ch], pa)
        if found:
            v += found
            blame.add(k + 1)
    return v, blame, peak_rate, peak_accel


def _trajectories(s: _Steps, cfg: _Settings, ks: np.ndarray):
    """The rebuilt maneuvers of the transitions ``k -> k + 1`` of ``ks`` (each with a
    duration T > 0), from the end state of step k to the start state of step k+1:
    their sample times [n, samples] (``np.linspace(0, T, samples)`` each) and
    (angle, rate, accel) [n, C, samples] in float64, computed in the steps' dtype in
    chunks of :data:`_TRANSITION_CHUNK` transitions (one compiled shape)."""
    T = s.ts[ks + 1] - s.te[ks]
    t = np.linspace(0.0, T, cfg.samples, axis=-1)
    if ks.size == 0:
        return t, [np.zeros((0, cfg.rate.shape[0], cfg.samples))] * 3
    dtype = cfg.dtype
    lim = AxisLimits(cfg.rate[:, None].astype(dtype), cfg.accel[:, None].astype(dtype))
    ends = (s.ea[ks], s.er[ks], s.sa[ks + 1], s.sr[ks + 1])
    args = [x[:, :, None].astype(dtype) for x in ends]
    args += [T[:, None, None].astype(dtype), t[:, None, :].astype(dtype)]

    def run(a1, b1, a2, b2, dur, tt):
        return _transfer(a1, b1, a2, b2, dur, lim, tt)

    return t, [np.asarray(x, np.float64) for x in map_chunked(run, args, _TRANSITION_CHUNK)]


def _transition_violations(k: int, t, traj, s: _Steps, cfg: _Settings):
    """Check every channel of the rebuilt maneuver of transition ``k -> k + 1``: ``traj``
    = its (angle, rate, accel) [C, samples] at the times ``t`` (:func:`_trajectories`).
    Returns the violations and, per channel with a trajectory, ``(channel, peak |rate|,
    peak |accel|)``; a channel with no trajectory in exactly T is a violation with no
    peaks."""
    T = t[-1]
    a1, b1, a2, b2 = s.ea[k], s.er[k], s.sa[k + 1], s.sr[k + 1]
    f, fd, fdd = traj
    v: list[str] = []
    peaks = []
    for ch in range(cfg.rate.shape[0]):
        tag = f"transition {k} -> {k + 1} (T = {T:.6g} s) channel {ch}"
        if not (np.isfinite(f[ch]).all() and np.isfinite(fd[ch]).all()):
            v.append(f"{tag}: no trajectory (not reachable in exactly T)")
            continue
        ends = (a1[ch], b1[ch], a2[ch], b2[ch])
        found, pr, pa = _channel_violations(
            tag, t, (f[ch], fd[ch], fdd[ch]), ends, cfg.rate[ch], cfg.accel[ch], cfg.rtol
        )
        v += found
        peaks.append((ch, pr, pa))
    return v, peaks


def _channel_violations(tag, t, samples, ends, rate, accel, rtol):
    """The checks of one channel of one sampled maneuver: ``samples`` = (angle, rate,
    accel) at the times ``t``, which run from 0 to the duration T = ``t[-1]``; ``ends``
    = the boundary states (a1, b1, a2, b2); ``rate``, ``accel`` = this channel's bounds.
    Checks the four boundary states, the peak rate and acceleration (returned
    accelerations and finite-difference slopes of the rate), and the angle as the
    trapezoid integral of the rate. Returns the violations (each prefixed with
    ``tag``), the peak |rate| and the peak |accel|."""
    f, fd, fdd = samples
    a1, b1, a2, b2 = ends
    T = t[-1]
    v: list[str] = []
    atol = rtol * (1.0 + abs(a1) + abs(a2) + rate * T)
    rtol_rate = rtol * rate + rtol * accel * T
    for what, got, want, tol in (
        ("start angle", f[0], a1, atol),
        ("start rate", fd[0], b1, rtol_rate),
        ("end angle", f[-1], a2, atol),
        ("end rate", fd[-1], b2, rtol_rate),
    ):
        if abs(got - want) > tol:
            v.append(f"{tag}: {what} {got!r} != boundary state {want!r}")
    dt = np.diff(t)
    slope = np.abs(np.diff(fd)) / dt
    pr = np.abs(fd).max()
    pa = max(slope.max(), np.abs(fdd[np.isfinite(fdd)]).max(initial=0.0))
    if pr > rate * (1.0 + rtol):
        v.append(f"{tag}: peak rate {pr!r} > limit {rate!r}")
    if pa > accel * (1.0 + rtol) + rtol * rate / T:
        v.append(f"{tag}: peak acceleration {pa!r} > limit {accel!r}")
    integral = f[0] + np.concatenate([[0.0], np.cumsum(0.5 * (fd[1:] + fd[:-1]) * dt)])
    # trapezoid error on a piecewise-linear rate: <= accel dt^2 / 4 per kink (<= 4 kinks)
    tol_int = atol + accel * dt.max() ** 2 * 2.0
    dev = np.abs(integral - f).max()
    if dev > tol_int:
        v.append(f"{tag}: angle is not the integral of the rate (max deviation {dev!r})")
    return v, pr, pa
