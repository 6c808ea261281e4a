"""Physical ranges of the numeric keys of scenario files: one table, the checks and the docs.

Every number of a scenario file (TOML keys, CSV columns) lies in a closed interval
stated here; a value outside is refused with the reader's named error
(``source: field (line N): must be within [lo, hi], got v``), like a NaN or a wrong
type. The table :data:`RANGES` maps the documented key (``satellites[].rate_deg_s``,
units in the key's name) to ``(lo, hi)``; ``docs/scenarios.md`` lists the same numbers
(a test compares them). Keys whose upper end is the scenario's horizon (times from the
epoch) carry :data:`HORIZON` as ``hi``: ``[0, duration]`` s. The bounds are wide
enough for any real mission and narrow enough that a unit slip (km for m, deg for rad)
or a typo (``1e300``) cannot pass.

SGP4 (the TLE propagator) is meaningful for days to weeks around a TLE's epoch: every
instant of the horizon must lie within :data:`MAX_TLE_AGE_DAYS` of the epoch of each
TLE. Epochs lie within :data:`EPOCH_RANGE` (two-digit TLE years cover 1957-2056; the
circular orbits' Earth-rotation and Sun formulas are approximations for this century).
"""

from __future__ import annotations

import datetime as _dt

__all__ = [
    "EPOCH_RANGE",
    "HORIZON",
    "MAX_NAME_CHARS",
    "MAX_SCAN_SPEEDS",
    "MAX_TLE_AGE_DAYS",
    "RANGES",
    "bounds",
    "range_text",
]

#: Marker of an upper bound that is the scenario's horizon (``duration`` [s]).
HORIZON = "horizon"

#: Largest distance between a TLE's epoch and any instant of the horizon [days].
MAX_TLE_AGE_DAYS = 30.0

#: Earliest and latest accepted scenario epoch (UTC).
EPOCH_RANGE = (
    _dt.datetime(1957, 10, 4, tzinfo=_dt.UTC),
    _dt.datetime(2099, 12, 31, 23, 59, 59, tzinfo=_dt.UTC),
)

MAX_SCAN_SPEEDS = 16  # entries of planner.scan_speeds_km_s
MAX_NAME_CHARS = 256  # names and sensor types

_DAY_S = 86400.0

#: key -> (lo, hi) of every numeric key (units in the key's name; see the module doc).
RANGES: dict[str, tuple] = {
    "scenario.duration_s": (1.0, 30 * _DAY_S),
    "scenario.duration_h": (1.0 / 3600.0, 30 * 24.0),
    "satellites[].altitude_km": (150.0, 30000.0),
    "satellites[].inclination_deg": (0.0, 180.0),
    "satellites[].raan_deg": (-360.0, 360.0),
    "satellites[].arg_lat_deg": (-360.0, 360.0),
    "satellites[].over.lat_deg": (-90.0, 90.0),
    "satellites[].over.lon_deg": (-180.0, 180.0),
    "satellites[].over.t_s": (0.0, HORIZON),
    "satellites[].rate_deg_s": (0.01, 90.0),
    "satellites[].accel_deg_s2": (0.001, 90.0),
    "satellites[].off_nadir_max_deg": (0.01, 80.0),
    "satellites[].settle_s": (0.0, 600.0),
    "satellites[].swath_km": (0.01, 5000.0),
    "satellites[].fov_deg": (0.001, 80.0),
    "satellites[].ifov_deg": (1e-7, 1.0),
    "satellites[].pixels": (1, 1_000_000),
    "satellites[].edge_off_nadir_deg": (0.0, 80.0),
    "satellites[].strip_duration_s": (0.0, 3600.0),
    "satellites[].duty_s_per_orbit": (0.01, 86400.0),
    "satellites[].flex.freq_hz": (0.001, 100.0),
    "satellites[].flex.damping": (0.0, 1.0),
    "satellites[].flex.tolerance_deg": (1e-9, 10.0),
    "satellites[].power.capacity_wh": (0.001, 1e6),
    "satellites[].power.initial_wh": (0.0, 1e6),
    "satellites[].power.idle_w": (0.0, 1e5),
    "satellites[].power.imaging_w": (0.0, 1e5),
    "satellites[].power.slew_w": (0.0, 1e5),
    "satellites[].power.charge_w": (0.0, 1e5),
    "targets[].lat_deg": (-90.0, 90.0),
    "targets[].lon_deg": (-180.0, 180.0),
    "targets[].alt_m": (-12000.0, 12000.0),
    "targets[].duration_s": (0.01, 3600.0),
    "targets[].length_km": (0.01, 10000.0),
    "targets[].azimuth_deg": (-360.0, 360.0),
    "targets[].priority": (1e-6, 1e6),
    "targets[].window_s": (0.0, HORIZON),
    "targets[].desired_s": (0.0, HORIZON),
    "targets[].tolerance_s": (0.0, HORIZON),
    "targets[].min_duration_s": (0.0, 3600.0),
    "targets[].radius_m": (10.0, 100_000.0),
    "targets[].band_deg": (0.0, 90.0),
    "targets[].tri_bonus": (0.0, 1.0),
    "areas[].priority": (1e-6, 1e6),
    "areas[].min_coverage": (0.0, 1.0),
    "areas[].window_s": (0.0, HORIZON),
    "areas[].grid_km": (0.01, 1000.0),
    "stereo.radius_m": (10.0, 100_000.0),
    "stereo.min_overlap": (0.01, 1.0),
    "stereo.convergence_deg": (0.0, 90.0),
    "stereo.band_deg": (0.0, 90.0),
    "stereo.max_scale_ratio": (1.0, 100.0),
    "stereo.max_separation_s": (0.0, 30 * _DAY_S),
    "stereo.anchor_off_nadir_deg": (0.0, 80.0),
    "stereo.quality_weights": (0.0, 1.0),
    "stereo.tri_bonus": (0.0, 1.0),
    "stereo.quality_weight": (0.0, 1.0),
    "random_targets.seed": (0, 2**63 - 1),
    "random_targets.count": (1, 1_000_000),
    "random_targets.lat_deg": (-90.0, 90.0),
    "random_targets.lon_deg": (-180.0, 180.0),
    "random_targets.strip_fraction": (0.0, 1.0),
    "random_targets.duration_s": (0.01, 3600.0),
    "random_targets.length_km": (0.01, 10000.0),
    "random_targets.azimuth_deg": (-360.0, 360.0),
    "random_targets.priority": (1, 1_000_000),
    "planner.time_step_s": (0.01, 3600.0),
    "planner.geometry_step_s": (0.01, 3600.0),
    "planner.scan_speeds_km_s": (0.01, 100.0),
    "planner.sun_elevation_min_deg": (-90.0, 90.0),
    "planner.off_nadir_margin_deg": (0.0, 10.0),
    "planner.horizon_margin": (0.0, 1.0),
    "planner.gap_margin_s": (0.0, 600.0),
    "planner.battery_margin_wh": (0.0, 1e6),
    "planner.shadow_guard_steps": (0, 1000),
    "planner.exact_max_options": (0, 500),  # mission.MAX_EXACT_OPTIONS
    "planner.lagrangian_share": (0.0, 0.99),
    "planner.refine_steps": (0, 100_000),
    "planner.time_limit_s": (0.01, 7 * _DAY_S),
    "planner.max_actions": (1, 1_000_000),
    "planner.area_roll_step_deg": (0.001, 10.0),
    "planner.area_pitch_step_deg": (0.1, 80.0),
    "planner.duty_margin_s": (0.0, 600.0),
}


def bounds(key: str, horizon: float | None = None) -> dict:
    """``{"lo": ..., "hi": ...}`` of a key of :data:`RANGES`, for the field readers.

    Args:
      key: documented key, e.g. ``"satellites[].rate_deg_s"``.
      horizon: the scenario's duration [s], the upper end of times from the epoch
        (None: the longest horizon, ``scenario.duration_s``'s upper end).
    Returns:
      dict with ``lo`` and ``hi`` (keywords of :func:`jaxspline.readers.fields.check_float`).
    """
    lo, hi = RANGES[key]
    if hi == HORIZON:
        hi = RANGES["scenario.duration_s"][1] if horizon is None else horizon
    return {"lo": lo, "hi": hi}


def _text(x) -> str:
    if x == HORIZON:
        return "the horizon"
    if isinstance(x, int) or (float(x) == int(x) and abs(x) >= 1000):
        return f"{int(x):,}"
    return f"{x:g}"


def range_text(key: str) -> str:
    """``[lo, hi]`` of a key as ``docs/scenarios.md`` writes it (``[0.01, 90]``).

    Args:
      key: a key of :data:`RANGES`.
    Returns:
      str; thousands with commas, times from the epoch up to ``the horizon``.
    """
    lo, hi = RANGES[key]
    return f"[{_text(lo)}, {_text(hi)}]"
