"""Kernels: the per-candidate mathematics of the papers, one candidate each, batched once.

``limits`` (parameter bundles), ``reach`` (per-channel reachable sets, SPEC §1),
``reach_durations`` (feasible durations, minimum transfer time and peak acceleration),
``slew`` (eigen-axis slew profiles, SPEC §2), ``flex`` (flexible-mode residual),
``attitude`` (quaternions, MRPs), ``joins`` (degree-7 joins, spatial maneuvers),
``join_check`` (their sampled limit check), ``channel_join`` (peaks of the
channel-wise degree-7 join),
``retarget_channel`` / ``retarget`` (minimum-peak control: one channel, 3-D).
Helpers every layer shares: ``safe`` (numerical guards, the double-where trick),
``validate`` (eager input checks at the public boundary), ``batch`` (batching, padding,
chunked evaluation).
"""

from jaxspline.kernels.attitude import angular_accel_from_mrp as angular_accel_from_mrp
from jaxspline.kernels.attitude import attitude_angle as attitude_angle
from jaxspline.kernels.attitude import dcm_to_mrp as dcm_to_mrp
from jaxspline.kernels.attitude import dcm_to_quat as dcm_to_quat
from jaxspline.kernels.attitude import mrp_derivs_from_omega as mrp_derivs_from_omega
from jaxspline.kernels.attitude import mrp_rate as mrp_rate
from jaxspline.kernels.attitude import mrp_shadow as mrp_shadow
from jaxspline.kernels.attitude import mrp_to_dcm as mrp_to_dcm
from jaxspline.kernels.attitude import mrp_to_quat as mrp_to_quat
from jaxspline.kernels.attitude import omega_from_mrp_derivs as omega_from_mrp_derivs
from jaxspline.kernels.attitude import omega_from_mrp_rate as omega_from_mrp_rate
from jaxspline.kernels.attitude import quat_conjugate as quat_conjugate
from jaxspline.kernels.attitude import quat_multiply as quat_multiply
from jaxspline.kernels.attitude import quat_normalize as quat_normalize
from jaxspline.kernels.attitude import quat_rate as quat_rate
from jaxspline.kernels.attitude import quat_rotate as quat_rotate
from jaxspline.kernels.attitude import quat_to_dcm as quat_to_dcm
from jaxspline.kernels.attitude import quat_to_mrp as quat_to_mrp
from jaxspline.kernels.batch import batched as batched
from jaxspline.kernels.batch import map_chunked as map_chunked
from jaxspline.kernels.batch import pad_last as pad_last
from jaxspline.kernels.batch import pad_rows as pad_rows
from jaxspline.kernels.batch import padded_size as padded_size
from jaxspline.kernels.batch import ragged_positions as ragged_positions
from jaxspline.kernels.batch import round_up as round_up
from jaxspline.kernels.channel_join import DEFAULT_JOIN_SAMPLES as DEFAULT_JOIN_SAMPLES
from jaxspline.kernels.channel_join import channel_join_peaks as channel_join_peaks
from jaxspline.kernels.flex import flexible_body_rate as flexible_body_rate
from jaxspline.kernels.flex import initial_amplitude as initial_amplitude
from jaxspline.kernels.flex import min_mode_frequency as min_mode_frequency
from jaxspline.kernels.flex import mode_rate_kernel as mode_rate_kernel
from jaxspline.kernels.flex import residual_amplitude as residual_amplitude
from jaxspline.kernels.flex import settling_time as settling_time
from jaxspline.kernels.flex import tau_for_tolerance as tau_for_tolerance
from jaxspline.kernels.flex import tau_for_tolerance_kernel as tau_for_tolerance_kernel
from jaxspline.kernels.join_check import maneuver_check as maneuver_check
from jaxspline.kernels.join_check import maneuver_check_kernel as maneuver_check_kernel
from jaxspline.kernels.joins import Maneuver as Maneuver
from jaxspline.kernels.joins import attitude_spline as attitude_spline
from jaxspline.kernels.joins import join7_coeffs as join7_coeffs
from jaxspline.kernels.joins import maneuver_eval as maneuver_eval
from jaxspline.kernels.joins import maneuver_plan as maneuver_plan
from jaxspline.kernels.joins import poly_eval as poly_eval
from jaxspline.kernels.joins import spline7_coeffs as spline7_coeffs
from jaxspline.kernels.limits import AxisLimits as AxisLimits
from jaxspline.kernels.limits import validate_limits as validate_limits
from jaxspline.kernels.reach import angle_interval as angle_interval
from jaxspline.kernels.reach import angle_interval_kernel as angle_interval_kernel
from jaxspline.kernels.reach import envelopes as envelopes
from jaxspline.kernels.reach import envelopes_kernel as envelopes_kernel
from jaxspline.kernels.reach import is_reachable as is_reachable
from jaxspline.kernels.reach import is_reachable_kernel as is_reachable_kernel
from jaxspline.kernels.reach import rate_interval as rate_interval
from jaxspline.kernels.reach import rate_interval_kernel as rate_interval_kernel
from jaxspline.kernels.reach import reach_margin as reach_margin
from jaxspline.kernels.reach import reach_margin_kernel as reach_margin_kernel
from jaxspline.kernels.reach import transfer as transfer
from jaxspline.kernels.reach import transfer_kernel as transfer_kernel
from jaxspline.kernels.reach_durations import feasible_durations as feasible_durations
from jaxspline.kernels.reach_durations import feasible_durations_kernel as feasible_durations_kernel
from jaxspline.kernels.reach_durations import min_peak_accel as min_peak_accel
from jaxspline.kernels.reach_durations import min_peak_accel_kernel as min_peak_accel_kernel
from jaxspline.kernels.reach_durations import min_transfer_time as min_transfer_time
from jaxspline.kernels.reach_durations import min_transfer_time_kernel as min_transfer_time_kernel
from jaxspline.kernels.retarget import AttitudeModel as AttitudeModel
from jaxspline.kernels.retarget import body_control as body_control
from jaxspline.kernels.retarget import euler_rates_matrix as euler_rates_matrix
from jaxspline.kernels.retarget import min_peak_retarget as min_peak_retarget
from jaxspline.kernels.retarget import orbital_to_body as orbital_to_body
from jaxspline.kernels.retarget import simulate as simulate
from jaxspline.kernels.retarget_channel import ARCSEC as ARCSEC
from jaxspline.kernels.retarget_channel import ChannelControl as ChannelControl
from jaxspline.kernels.retarget_channel import channel_control_eval as channel_control_eval
from jaxspline.kernels.retarget_channel import channel_state as channel_state
from jaxspline.kernels.retarget_channel import min_peak_channel as min_peak_channel
from jaxspline.kernels.retarget_channel import min_peak_channel_kernel as min_peak_channel_kernel
from jaxspline.kernels.retarget_channel import min_peak_linear as min_peak_linear
from jaxspline.kernels.safe import pos_or_one as pos_or_one
from jaxspline.kernels.safe import safe_div as safe_div
from jaxspline.kernels.safe import safe_norm as safe_norm
from jaxspline.kernels.safe import safe_sqrt as safe_sqrt
from jaxspline.kernels.slew import KIND_CODES as KIND_CODES
from jaxspline.kernels.slew import SlewProfile as SlewProfile
from jaxspline.kernels.slew import bang_bang_time as bang_bang_time
from jaxspline.kernels.slew import bang_bang_time_kernel as bang_bang_time_kernel
from jaxspline.kernels.slew import bang_coast_bang_time as bang_coast_bang_time
from jaxspline.kernels.slew import bang_coast_bang_time_kernel as bang_coast_bang_time_kernel
from jaxspline.kernels.slew import profile_state as profile_state
from jaxspline.kernels.slew import profile_state_kernel as profile_state_kernel
from jaxspline.kernels.slew import scurve_time as scurve_time
from jaxspline.kernels.slew import scurve_time_kernel as scurve_time_kernel
from jaxspline.kernels.slew import slew_profile as slew_profile
from jaxspline.kernels.slew import slew_profile_kernel as slew_profile_kernel
from jaxspline.kernels.slew import slew_profile_time as slew_profile_time
from jaxspline.kernels.validate import as_float_array as as_float_array
from jaxspline.kernels.validate import broadcast_named as broadcast_named
from jaxspline.kernels.validate import cast_broadcast as cast_broadcast
from jaxspline.kernels.validate import check_finite as check_finite
from jaxspline.kernels.validate import check_nonnegative as check_nonnegative
from jaxspline.kernels.validate import check_positive as check_positive
from jaxspline.kernels.validate import common_float as common_float
from jaxspline.kernels.validate import finite_vector as finite_vector
from jaxspline.kernels.validate import float_dtype_of as float_dtype_of
from jaxspline.kernels.validate import is_concrete as is_concrete
from jaxspline.kernels.validate import to_device as to_device
