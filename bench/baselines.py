"""Baselines on the same inputs: numpy vectorized and pure-Python versions of the formulas,
and Ruckig per call. Written from SPEC section 1/2 formulas, independently of the JAX code.
"""

from __future__ import annotations

import math

import numpy as np


# ---------------------------------------------------------------- numpy, vectorized
def np_angle_interval(a1, b1, b2, T, b, d):
    """Reachable end-angle interval (SPEC §1 envelope integrals), numpy."""
    s, dd = b1 + b2, (b1 - b2) ** 2
    hi = np.where(
        (s + d * T) / 2 <= b,
        a1 - dd / (4 * d) + T * s / 2 + d * T * T / 4,
        a1 - ((b - b1) ** 2 + (b - b2) ** 2) / (2 * d) + b * T,
    )
    lo = np.where(
        (s - d * T) / 2 >= -b,
        a1 + dd / (4 * d) + T * s / 2 - d * T * T / 4,
        a1 + ((b + b1) ** 2 + (b + b2) ** 2) / (2 * d) - b * T,
    )
    ok = (np.abs(b1) <= b) & (np.abs(b2) <= b) & (np.abs(b1 - b2) <= d * T)
    return np.where(ok, lo, np.inf), np.where(ok, hi, -np.inf)


def np_is_reachable(a1, b1, a2, b2, T, b, d):
    """Membership of (a2, b2) in P(a1, b1, T), numpy."""
    lo, hi = np_angle_interval(a1, b1, b2, T, b, d)
    return (lo <= a2) & (a2 <= hi)


def np_bang_coast_bang_time(angle, rate, accel):
    """Rest-to-rest bang(-coast)-bang slew time, numpy."""
    a = np.abs(angle)
    return np.where(a <= rate * rate / accel, 2 * np.sqrt(a / accel), a / rate + rate / accel)


# ---------------------------------------------------------------- pure Python, scalar
def py_is_reachable(a1, b1, a2, b2, T, b, d):
    """Membership, one candidate, plain Python floats."""
    if abs(b1) > b or abs(b2) > b or abs(b1 - b2) > d * T:
        return False
    s = b1 + b2
    if (s + d * T) / 2 <= b:
        hi = a1 - (b1 - b2) ** 2 / (4 * d) + T * s / 2 + d * T * T / 4
    else:
        hi = a1 - ((b - b1) ** 2 + (b - b2) ** 2) / (2 * d) + b * T
    if (s - d * T) / 2 >= -b:
        lo = a1 + (b1 - b2) ** 2 / (4 * d) + T * s / 2 - d * T * T / 4
    else:
        lo = a1 + ((b + b1) ** 2 + (b + b2) ** 2) / (2 * d) - b * T
    return lo <= a2 <= hi


def py_bang_coast_bang_time(angle, rate, accel):
    """Rest-to-rest bang(-coast)-bang slew time, one candidate."""
    a = abs(angle)
    return 2 * math.sqrt(a / accel) if a <= rate * rate / accel else a / rate + rate / accel


# ---------------------------------------------------------------- Ruckig, per call
def ruckig_available() -> bool:
    try:
        import ruckig  # noqa: F401
    except ImportError:
        return False
    return True


def ruckig_is_reachable(a1, b1, a2, b2, T, b, d):
    """Second-order Ruckig (jerk = inf) with minimum_duration = T: feasible iff it returns T."""
    from ruckig import InputParameter, Result, Ruckig, Trajectory

    otg, inp, traj = Ruckig(1), InputParameter(1), Trajectory(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [a1], [b1], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [a2], [b2], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [b], [d], [float("inf")]
    inp.minimum_duration = T
    res = otg.calculate(inp, traj)
    if res not in (Result.Working, Result.Finished):
        return False
    return abs(traj.duration - T) <= 1e-9 * max(1.0, T)


def ruckig_rest_to_rest_time(angle, rate, accel):
    """Second-order Ruckig rest-to-rest duration (bang-coast-bang)."""
    from ruckig import InputParameter, Ruckig, Trajectory

    otg, inp, traj = Ruckig(1), InputParameter(1), Trajectory(1)
    inp.current_position, inp.current_velocity, inp.current_acceleration = [0.0], [0.0], [0.0]
    inp.target_position, inp.target_velocity, inp.target_acceleration = [angle], [0.0], [0.0]
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [rate], [accel], [float("inf")]
    otg.calculate(inp, traj)
    return traj.duration
