"""Benchmark workloads: random candidate inputs and the kernels that consume them.

Every workload has one-candidate JAX kernel (batched here once with ``jit(vmap)``,
the way the screening engine uses it) and, where one exists, a numpy-vectorized,
a pure-Python and a Ruckig baseline computing the same quantity on the same inputs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

# channel limits used by every workload: 2 deg/s, 1 deg/s^2 (typical agile EO satellite)
RATE = np.deg2rad(2.0)
ACCEL = np.deg2rad(1.0)
JERK = np.deg2rad(1.0)


def reach_inputs(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Random exact-T transitions (about half reachable): a1, b1, a2, b2, T."""
    rng = np.random.default_rng(seed)
    T = rng.uniform(0.5, 60.0, n)
    b1 = rng.uniform(-RATE, RATE, n)
    b2 = np.clip(b1 + rng.uniform(-1, 1, n) * ACCEL * T, -RATE, RATE)
    a1 = rng.uniform(-0.5, 0.5, n)
    a2 = a1 + rng.uniform(-1.0, 1.0, n) * RATE * T
    return dict(a1=a1, b1=b1, a2=a2, b2=b2, T=T)


def slew_inputs(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Random eigen-axis slew angles in [0, 60 deg]."""
    rng = np.random.default_rng(seed)
    return dict(angle=rng.uniform(0.0, np.deg2rad(60.0), n))


def maneuver_inputs(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Random spatial maneuvers: attitudes within 20 deg, small boundary rates, T in 20-60 s."""
    rng = np.random.default_rng(seed)

    def quat(scale):
        axis = rng.normal(size=(n, 3))
        axis /= np.linalg.norm(axis, axis=1, keepdims=True)
        ang = rng.uniform(0, scale, (n, 1))
        return np.concatenate([np.cos(ang / 2), np.sin(ang / 2) * axis], axis=1)

    def vec(scale):
        return rng.uniform(-scale, scale, (n, 3))

    return dict(
        q0=quat(0.2),
        w0=vec(0.005),
        e0=vec(1e-4),
        j0=np.zeros((n, 3)),
        q1=quat(0.35),
        w1=vec(0.005),
        e1=vec(1e-4),
        j1=np.zeros((n, 3)),
        T=rng.uniform(20.0, 60.0, n),
    )


@dataclass
class Workload:
    """One benchmarked quantity: inputs, the JAX kernel, and its baselines."""

    name: str
    make_inputs: Callable[[int, int], dict]
    args: tuple[str, ...]  # input names, in kernel argument order
    jax_kernel: Callable  # f(*candidate_args) for ONE candidate (limits closed over)
    numpy_fn: Callable | None = None  # f(*arrays) -> array
    python_fn: Callable | None = None  # f(*floats) -> value
    ruckig_fn: Callable | None = None  # f(*floats) -> value
    max_batch: float = 1e7  # largest batch for this workload
    out_bytes: int = 8
    notes: str = ""
    # further numpy baselines, e.g. "numpy_lean": a hand-written formula without the
    # kernel's tolerance handling (fewer array passes, so a stricter baseline)
    extra: dict = field(default_factory=dict)


def workloads() -> list[Workload]:
    """All benchmarked workloads (kernels imported from jaxspline)."""
    import jaxspline.kernels.join_check as J
    import jaxspline.kernels.reach as R
    import jaxspline.kernels.reach_durations as RD
    import jaxspline.kernels.slew as S
    from bench import baselines as B
    from bench.numpy_port import numpy_module

    NR = numpy_module("jaxspline.kernels.reach")  # same formulas, numpy arrays
    NRD = numpy_module("jaxspline.kernels.reach_durations")
    NS = numpy_module("jaxspline.kernels.slew")
    b, d = RATE, ACCEL
    ws = [
        Workload(
            "is_reachable",
            reach_inputs,
            ("a1", "b1", "a2", "b2", "T"),
            lambda a1, b1, a2, b2, T: R.is_reachable_kernel(a1, b1, a2, b2, T, b, d),
            numpy_fn=lambda a1, b1, a2, b2, T: NR.is_reachable_kernel(a1, b1, a2, b2, T, b, d),
            python_fn=lambda a1, b1, a2, b2, T: B.py_is_reachable(a1, b1, a2, b2, T, b, d),
            ruckig_fn=lambda a1, b1, a2, b2, T: B.ruckig_is_reachable(a1, b1, a2, b2, T, b, d),
            max_batch=1e8,
            out_bytes=1,
            extra={
                "numpy_lean": lambda a1, b1, a2, b2, T: B.np_is_reachable(a1, b1, a2, b2, T, b, d)
            },
        ),
        Workload(
            "angle_interval",
            reach_inputs,
            ("a1", "b1", "b2", "T"),
            lambda a1, b1, b2, T: R.angle_interval_kernel(a1, b1, b2, T, b, d),
            numpy_fn=lambda a1, b1, b2, T: NR.angle_interval_kernel(a1, b1, b2, T, b, d),
            max_batch=1e8,
            out_bytes=16,
            extra={"numpy_lean": lambda a1, b1, b2, T: B.np_angle_interval(a1, b1, b2, T, b, d)},
        ),
        Workload(
            "min_transfer_time",
            reach_inputs,
            ("a1", "b1", "a2", "b2"),
            lambda a1, b1, a2, b2: RD.min_transfer_time_kernel(a1, b1, a2, b2, b, d),
            numpy_fn=lambda a1, b1, a2, b2: NRD.min_transfer_time_kernel(a1, b1, a2, b2, b, d),
        ),
        Workload(
            "min_peak_accel",
            reach_inputs,
            ("a1", "b1", "a2", "b2", "T"),
            lambda a1, b1, a2, b2, T: RD.min_peak_accel_kernel(a1, b1, a2, b2, T, b),
            numpy_fn=lambda a1, b1, a2, b2, T: NRD.min_peak_accel_kernel(a1, b1, a2, b2, T, b),
        ),
        Workload(
            "bang_coast_bang_time",
            slew_inputs,
            ("angle",),
            lambda angle: S.bang_coast_bang_time_kernel(angle, b, d),
            numpy_fn=lambda angle: B.np_bang_coast_bang_time(angle, b, d),
            python_fn=lambda angle: B.py_bang_coast_bang_time(angle, b, d),
            ruckig_fn=lambda angle: B.ruckig_rest_to_rest_time(angle, b, d),
        ),
        Workload(
            "slew_profile_ABCD",
            slew_inputs,
            ("angle",),
            lambda angle: S.slew_profile_kernel(angle, b, d, b / d, "auto")[5],
            numpy_fn=lambda angle: NS.slew_profile_kernel(angle, b, d, b / d, "auto")[5],
            notes="profile kind chosen per candidate (A/C/D), tau = omega/eps for D",
        ),
        Workload(
            "scurve_time",
            slew_inputs,
            ("angle",),
            lambda angle: S.scurve_time_kernel(angle, b, d, JERK),
            numpy_fn=lambda angle: NS.scurve_time_kernel(angle, b, d, JERK),
        ),
        Workload(
            "maneuver_check_129",
            maneuver_inputs,
            ("q0", "w0", "e0", "j0", "q1", "w1", "e1", "j1", "T"),
            lambda *a: J.maneuver_check_kernel(*a, b, d, JERK, n_samples=129)[3],
            max_batch=1e4,  # best in calls of 1e4-2e4 (maneuver_check chunks at 16384)
            out_bytes=1,
            notes="degree-7 MRP join + 129-sample |w|,|e|,|e'| check per candidate",
        ),
    ]
    return ws
