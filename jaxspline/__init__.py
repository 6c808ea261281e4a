"""jaxspline: batched, differentiable attitude-maneuver kinematics for agile EO satellites.

Public names are re-exported here from small private-by-convention modules, one
concern each (see README "Architecture"). The library never enables float64 on
import or globally: :func:`plan` runs inside ``jax.enable_x64(True)``; for the kernels,
use that context manager (or ``jax.config.update("jax_enable_x64", True)``) yourself.
"""

from jaxspline.limits import AxisLimits, validate_limits

# --- reach (per-channel reachable sets; SPEC section 1) ---
from jaxspline.reach import (  # noqa: E402
    angle_interval,
    envelopes,
    feasible_durations,
    is_reachable,
    min_peak_accel,
    min_transfer_time,
    rate_interval,
    reach_margin,
    transfer,
)

# --- slew (eigen-axis slew profiles; SPEC section 2) ---
from jaxspline.slew import (
    KIND_CODES,
    SlewProfile,
    bang_bang_time,
    bang_bang_time_kernel,
    bang_coast_bang_time,
    bang_coast_bang_time_kernel,
    profile_state,
    profile_state_kernel,
    scurve_time,
    scurve_time_kernel,
    slew_profile,
    slew_profile_kernel,
    slew_profile_time,
)

# --- flex (flexible-mode residual and simulator) ---
from jaxspline.flex import (
    flexible_body_rate,
    initial_amplitude,
    min_mode_frequency,
    mode_rate_kernel,
    residual_amplitude,
    settling_time,
    tau_for_tolerance,
    tau_for_tolerance_kernel,
)

# --- attitude (quaternion / MRP / rotation matrices) ---
from jaxspline.attitude import (  # noqa: E402
    angular_accel_from_mrp,
    attitude_angle,
    dcm_to_mrp,
    dcm_to_quat,
    mrp_derivs_from_omega,
    mrp_rate,
    mrp_shadow,
    mrp_to_dcm,
    mrp_to_quat,
    omega_from_mrp_derivs,
    omega_from_mrp_rate,
    quat_conjugate,
    quat_multiply,
    quat_normalize,
    quat_rate,
    quat_rotate,
    quat_to_dcm,
    quat_to_mrp,
)

# --- joins (degree-7 joins, vector spline, spatial maneuvers) ---
from jaxspline.joins import (  # noqa: E402
    Maneuver,
    ManeuverCheck,
    attitude_spline,
    join7_coeffs,
    maneuver_check,
    maneuver_check_kernel,
    maneuver_eval,
    maneuver_plan,
    poly_eval,
    spline7_coeffs,
)

# --- retarget (minimum-peak-control retargeting) ---
from jaxspline.retarget import (  # noqa: E402
    ARCSEC,
    AttitudeModel,
    ChannelControl,
    DirectResult,
    RetargetResult,
    attitude_rhs,
    body_control,
    channel_control_eval,
    channel_state,
    euler_rates_matrix,
    min_peak_channel,
    min_peak_channel_kernel,
    min_peak_direct,
    min_peak_linear,
    min_peak_retarget,
    orbital_to_body,
    simulate,
)

# --- geometry (orbit, pointing, routes) ---
from jaxspline.frames import (  # noqa: E402
    ecef_to_geodetic,
    geodetic_to_ecef,
    gmst,
    julian_date,
    sun_direction,
    teme_to_ecef,
)
from jaxspline.orbit import (  # noqa: E402
    CircularOrbit,
    HermiteOrbit,
    circular_orbit,
    circular_orbit_over,
    orbit_position,
    orbit_state,
    propagate_tle,
    sso_inclination,
    tle_orbit,
)
from jaxspline.pointing import (  # noqa: E402
    Scene,
    aim_angles,
    aim_params,
    aim_state,
    boresight,
    off_nadir,
    pointing_angles,
    pointing_state,
    visibility_windows,
)
from jaxspline.routes import (  # noqa: E402
    RouteSet,
    RouteSpec,
    TabulatedRouteModel,
    build_route_options,
    exact_states,
    make_route_set,
    make_route_spec,
    tabulate_route_model,
)

# --- planning (mission types, the pipeline, its result, scenario files) ---
from jaxspline.mission import (  # noqa: E402
    MODELS,
    FlexMode,
    Margins,
    PlannerConfig,
    Power,
    Satellite,
    Scenario,
    Targets,
    make_targets,
)
from jaxspline.planner import Prepared, build_problem, plan  # noqa: E402
from jaxspline.result import Observations, PlanResult  # noqa: E402

# --- operations (attitude history of a plan, join check, CCSDS AEM export) ---
from jaxspline.aem import read_aem, write_aems  # noqa: E402
from jaxspline.attitude_history import (  # noqa: E402
    AttitudeHistory,
    PlanAttitude,
    attitude_history,
)
from jaxspline.plan_joins import Joins, plan_joins  # noqa: E402
from jaxspline.scenario import default_scenario, load_scenario, load_targets_csv  # noqa: E402

# --- engine (screen, sequence, refine, validate, scenario) ---
from jaxspline.screen import (  # noqa: E402
    Transitions,
    screen_pairs,
    screen_sequences,
    screen_transitions,
)
from jaxspline.sequence import Plan, beam_search, exact_plan, greedy  # noqa: E402
from jaxspline.refine import (  # noqa: E402
    LinearRouteModel,
    RefineResult,
    refine_plan,
    try_insert,
)
from jaxspline.validate import ValidationReport, validate_plan  # noqa: E402

__all__ = [
    "attitude_history",
    "AttitudeHistory",
    "Joins",
    "PlanAttitude",
    "plan_joins",
    "read_aem",
    "write_aems",
    "MODELS",
    "FlexMode",
    "Margins",
    "PlannerConfig",
    "Power",
    "Satellite",
    "Targets",
    "make_targets",
    "Prepared",
    "build_problem",
    "plan",
    "Observations",
    "PlanResult",
    "load_targets_csv",
    "aim_angles",
    "aim_params",
    "aim_state",
    "angle_interval",
    "angular_accel_from_mrp",
    "ARCSEC",
    "attitude_angle",
    "attitude_rhs",
    "attitude_spline",
    "AttitudeModel",
    "AxisLimits",
    "bang_bang_time",
    "bang_bang_time_kernel",
    "bang_coast_bang_time",
    "bang_coast_bang_time_kernel",
    "beam_search",
    "body_control",
    "boresight",
    "build_route_options",
    "channel_control_eval",
    "channel_state",
    "ChannelControl",
    "circular_orbit",
    "circular_orbit_over",
    "CircularOrbit",
    "dcm_to_mrp",
    "dcm_to_quat",
    "default_scenario",
    "DirectResult",
    "ecef_to_geodetic",
    "envelopes",
    "euler_rates_matrix",
    "exact_plan",
    "exact_states",
    "feasible_durations",
    "flexible_body_rate",
    "geodetic_to_ecef",
    "gmst",
    "greedy",
    "HermiteOrbit",
    "initial_amplitude",
    "is_reachable",
    "join7_coeffs",
    "julian_date",
    "KIND_CODES",
    "LinearRouteModel",
    "load_scenario",
    "make_route_set",
    "make_route_spec",
    "Maneuver",
    "maneuver_check",
    "maneuver_check_kernel",
    "maneuver_eval",
    "maneuver_plan",
    "ManeuverCheck",
    "min_mode_frequency",
    "min_peak_accel",
    "min_peak_channel",
    "min_peak_channel_kernel",
    "min_peak_direct",
    "min_peak_linear",
    "min_peak_retarget",
    "min_transfer_time",
    "mode_rate_kernel",
    "mrp_derivs_from_omega",
    "mrp_rate",
    "mrp_shadow",
    "mrp_to_dcm",
    "mrp_to_quat",
    "off_nadir",
    "omega_from_mrp_derivs",
    "omega_from_mrp_rate",
    "orbit_position",
    "orbit_state",
    "orbital_to_body",
    "Plan",
    "pointing_angles",
    "pointing_state",
    "poly_eval",
    "profile_state",
    "profile_state_kernel",
    "propagate_tle",
    "quat_conjugate",
    "quat_multiply",
    "quat_normalize",
    "quat_rate",
    "quat_rotate",
    "quat_to_dcm",
    "quat_to_mrp",
    "rate_interval",
    "reach_margin",
    "refine_plan",
    "RefineResult",
    "residual_amplitude",
    "RetargetResult",
    "RouteSet",
    "RouteSpec",
    "Scenario",
    "Scene",
    "screen_pairs",
    "screen_sequences",
    "screen_transitions",
    "scurve_time",
    "scurve_time_kernel",
    "settling_time",
    "simulate",
    "slew_profile",
    "slew_profile_kernel",
    "slew_profile_time",
    "SlewProfile",
    "spline7_coeffs",
    "sso_inclination",
    "sun_direction",
    "tabulate_route_model",
    "TabulatedRouteModel",
    "tau_for_tolerance",
    "tau_for_tolerance_kernel",
    "teme_to_ecef",
    "tle_orbit",
    "transfer",
    "Transitions",
    "try_insert",
    "validate_limits",
    "validate_plan",
    "ValidationReport",
    "visibility_windows",
]

__version__ = "0.1.0"
