"""jaxspline: batched, differentiable attitude-maneuver kinematics for agile EO satellites.

Public names are re-exported here from small private-by-convention modules, one
concern each (see README "Architecture"). The library never enables float64 on
import; call ``jax.config.update("jax_enable_x64", True)`` for double precision
(the CLI, tests and benchmarks do).
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
from jaxspline.orbit import (  # noqa: E402
    CircularOrbit,
    HermiteOrbit,
    circular_orbit,
    circular_orbit_over,
    ecef_to_geodetic,
    geodetic_to_ecef,
    gmst,
    julian_date,
    orbit_position,
    orbit_state,
    propagate_tle,
    sso_inclination,
    sun_direction,
    teme_to_ecef,
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
from jaxspline.scenario import (  # noqa: E402
    PlannerOptions,
    Scenario,
    default_scenario,
    load_scenario,
)
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

__version__ = "0.1.0"
