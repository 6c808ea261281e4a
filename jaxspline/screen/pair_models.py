"""Maneuver models of the screening engine: one pair function per model.

The second argument of :func:`jaxspline.screen.pairs.screen_transitions`,
:func:`~jaxspline.screen.pairs.screen_chunks` and
:func:`~jaxspline.screen.pairs.screen_pairs` is a maneuver model:

* :class:`jaxspline.kernels.limits.AxisLimits` - per-channel exact-T reachable sets
  (SPEC section 1): every channel goes from ``(end_angle[i], end_rate[i])`` to
  ``(start_angle[j], start_rate[j])`` in exactly T (:class:`_ChannelPairs`).
* :class:`jaxspline.screen.slew_table.SlewTable` - a tabulated rest-to-rest slew
  (eigen-axis bang-coast-bang or flexible profile, settle and gap margin included)
  through the angle between ``end_los[i]`` and ``start_los[j]`` (:class:`_SlewPairs`).

:func:`model_arrays` is the one dispatch: it validates the model against the option
table and returns the pair function with its option columns and parameters. Every
screening program (the host path's chunk program, the fused row program and
:func:`~jaxspline.screen.pairs.screen_pairs`) calls ``pair(table, params, src, dst,
T) -> (feasible, margin, effort, t_min)`` on candidate vectors. A pair function is a
frozen dataclass (hashable by value and class), so it keys the compile caches.

Units: radians, seconds.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.limits import AxisLimits, validate_limits
from jaxspline.screen.options import RouteOptions, validate_options
from jaxspline.screen.slew_table import SlewTable

__all__ = ["model_arrays", "validate_model"]

#: Rounding guard of the slew-table index (the same as ``SlewTable.__call__``).
_INDEX_EPS = 1e-12
#: Option fields a per-channel model reads (channel-major [C, N] on the device).
_CHANNEL_FIELDS = ("end_angle", "end_rate", "start_angle", "start_rate")
#: Option fields a rest-to-rest model reads (component-major [3, N] on the device).
_LOS_FIELDS = ("end_los", "start_los")


class _ReachKernels(NamedTuple):
    """The per-candidate kernels the engine screens with (hashable: keys the compile cache)."""

    is_reachable_kernel: object
    reach_margin_kernel: object
    min_peak_accel_kernel: object
    min_transfer_time_kernel: object


def _reach() -> _ReachKernels:
    """The reach kernels (indirection so tests can substitute stand-ins)."""
    from jaxspline.kernels import reach, reach_durations

    return _ReachKernels(
        reach.is_reachable_kernel,
        reach.reach_margin_kernel,
        reach_durations.min_peak_accel_kernel,
        reach_durations.min_transfer_time_kernel,
    )


def _check_limits(limits: AxisLimits, c: int):
    """Validated per-channel (rate [C], accel [C]) float64 numpy arrays of AxisLimits."""
    limits = validate_limits(limits)
    if np.shape(limits.rate) not in ((), (c,)) or np.shape(limits.accel) not in ((), (c,)):
        raise ValueError(
            f"limits.rate/accel must be scalars or shape ({c},) (one per channel), got "
            f"{np.shape(limits.rate)} and {np.shape(limits.accel)}"
        )
    rate = np.broadcast_to(np.asarray(limits.rate, float), (c,))
    accel = np.broadcast_to(np.asarray(limits.accel, float), (c,))
    return rate, accel


def _channel_limits(limits: AxisLimits, c: int, dtype):
    rate, accel = _check_limits(limits, c)
    return jnp.asarray(rate, dtype), jnp.asarray(accel, dtype)


def _channel(reach, a1, b1, a2, b2, T, rate, accel):
    """One channel of a batch of candidates: (ok, margin, d*/accel, t_min), each [n].

    a1, b1, a2, b2, T: [n] contiguous vectors; rate, accel: scalars of this channel.
    The reach kernels are elementwise, so applying them to whole [n] vectors is the
    same arithmetic as vmapping the one-candidate kernel, with unit-stride SIMD.
    """
    ok = reach.is_reachable_kernel(a1, b1, a2, b2, T, rate, accel)
    m = reach.reach_margin_kernel(a1, b1, a2, b2, T, rate, accel)
    eff = reach.min_peak_accel_kernel(a1, b1, a2, b2, T, rate) / accel
    tmin = reach.min_transfer_time_kernel(a1, b1, a2, b2, rate, accel)
    return ok, m, eff, tmin


def _all_channels(reach, table, src, dst, T, rate, accel):
    """(feasible, margin, effort, t_min) of candidates src -> dst over every channel.

    ``table`` = (end_angle, end_rate, start_angle, start_rate), channel-major [C, N];
    ``src`` / ``dst`` index its columns (any shape broadcasting with T). Channels are
    reduced by min/max chains; a candidate with T <= 0 is infeasible.
    """
    end_angle, end_rate, start_angle, start_rate = table
    outs = []
    for c in range(end_angle.shape[0]):
        a1, b1 = end_angle[c][src], end_rate[c][src]
        a2, b2 = start_angle[c][dst], start_rate[c][dst]
        outs.append(_channel(reach, a1, b1, a2, b2, T, rate[c], accel[c]))
    cols = list(zip(*outs, strict=True))
    ok = functools.reduce(jnp.logical_and, cols[0])
    m = functools.reduce(jnp.minimum, cols[1])
    eff = functools.reduce(jnp.maximum, cols[2])
    tmin = functools.reduce(jnp.maximum, cols[3])
    pos = T > 0
    return ok & pos, jnp.where(pos, m, -jnp.inf), jnp.where(pos, eff, jnp.inf), tmin


@dataclasses.dataclass(frozen=True)
class _ChannelPairs:
    """Per-channel exact-T pair function (SPEC section 1), reduced over channels.

    ``table`` = (end_angle, end_rate, start_angle, start_rate), channel-major [C, N];
    ``params`` = (rate [C] [rad/s], accel [C] [rad/s^2]). Returns ``(feasible,
    margin [rad], effort, t_min [s])`` as :func:`_all_channels`.

    Attributes:
      reach: the reach kernels (:func:`_reach`).
    """

    reach: _ReachKernels

    def __call__(self, table, params, src, dst, T):
        """Screen candidates src -> dst with durations T.

        Args:
          table: the model's option columns (class docstring), device arrays [F, N].
          params: the model's parameters (class docstring).
          src, dst: int arrays indexing the table's columns, broadcasting with T.
          T: transfer durations [s]; T <= 0 is infeasible.
        Returns:
          (feasible bool, margin, effort, t_min), broadcast to T's shape.
        """
        rate, accel = params
        return _all_channels(self.reach, table, src, dst, T, rate, accel)


@dataclasses.dataclass(frozen=True)
class _SlewPairs:
    """Rest-to-rest pair function: a :class:`~jaxspline.screen.slew_table.SlewTable` lookup.

    ``table`` = (end_los, start_los), component-major [3, N], unit vectors
    (:func:`model_arrays` normalizes them); ``params`` = (time [S + 1],), the table's
    required times [s] at ``theta_k = pi (k / S)^2``. With ``u = end_los[src]``,
    ``v = start_los[dst]``: the angle ``theta = atan2(|u x v|, u . v)`` [rad],
    evaluated as ``2 atan2(|u - v|, |u + v|)`` (the same angle for unit vectors, and
    exactly 0 for equal ones: XLA's CPU backend contracts the cross product's
    ``a b - c d`` into a fused multiply-add, which leaves a rounding residue of ~1e-16
    there, enough to move the lookup off ``theta_0``), then
    ``k = min(ceil(S sqrt(theta / pi) - 1e-12), S)`` (as ``SlewTable.__call__``),
    ``t_req = time[k]`` and

    * feasible = ``T > 0 and T >= t_req``,
    * margin = ``T - t_req`` [s] (-inf for T <= 0),
    * effort = ``t_req / T`` (<= 1 iff feasible; +inf for T <= 0),
    * t_min = ``t_req`` [s].
    """

    def __call__(self, table, params, src, dst, T):
        """Screen candidates src -> dst with durations T.

        Args:
          table: the model's option columns (class docstring), device arrays [F, N].
          params: the model's parameters (class docstring).
          src, dst: int arrays indexing the table's columns, broadcasting with T.
          T: transfer durations [s]; T <= 0 is infeasible.
        Returns:
          (feasible bool, margin, effort, t_min), broadcast to T's shape.
        """
        end_los, start_los = table
        (time,) = params
        size = time.shape[0] - 1
        u = [end_los[c][src] for c in range(3)]
        v = [start_los[c][dst] for c in range(3)]
        d = [a - b for a, b in zip(u, v, strict=True)]
        s = [a + b for a, b in zip(u, v, strict=True)]
        half = jnp.arctan2(
            jnp.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]),
            jnp.sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]),
        )
        theta = jnp.clip(2.0 * half, 0.0, math.pi)
        k = jnp.minimum(jnp.ceil(size * jnp.sqrt(theta / math.pi) - _INDEX_EPS), size)
        t_req = time[k.astype(jnp.int32)]
        pos = T > 0
        safe_T = jnp.where(pos, T, 1.0)
        feasible = pos & (T >= t_req)
        margin = jnp.where(pos, T - t_req, -jnp.inf)
        effort = jnp.where(pos, t_req / safe_T, jnp.inf)
        return feasible, margin, effort, t_req


def validate_model(model, options: RouteOptions, name: str = "model") -> None:
    """Check a maneuver model against an option table (eagerly, at the public boundary).

    Args:
      model: AxisLimits (per channel) or SlewTable (rest to rest).
      options: RouteOptions the model screens.
      name: argument name used in the error messages.
    Raises:
      ValueError: naming the argument when the model is of another type, its
        limits or table are invalid, or a rest-to-rest model meets options without
        ``end_los`` / ``start_los`` of shape [N, 3].
    """
    c = validate_options(options)
    if isinstance(model, AxisLimits):
        _check_limits(model, c)
        return
    if not isinstance(model, SlewTable):
        raise ValueError(
            f"{name} must be an AxisLimits (per channel) or a models.SlewTable (rest to rest), "
            f"got {type(model).__name__}"
        )
    time = np.asarray(model.time)
    size = model.size
    if not (isinstance(size, int | np.integer) and size >= 1):
        raise ValueError(f"{name}.size must be an int >= 1, got {size!r}")
    if time.shape != (size + 1,):
        raise ValueError(f"{name}.time must have shape ({size + 1},), got {time.shape}")
    if np.isnan(time.astype(float)).any() or (time < 0).any():
        raise ValueError(f"{name}.time must be >= 0 and not NaN, got min {np.nanmin(time)!r}")
    n = np.shape(options.t_start)[0]
    for f in _LOS_FIELDS:
        los = getattr(options, f)
        if los is None:
            raise ValueError(f"options.{f} is None: a SlewTable {name} needs lines of sight")
        if np.shape(los) != (n, 3):
            raise ValueError(f"options.{f} must have shape ({n}, 3), got {np.shape(los)}")
        norm = np.linalg.norm(np.asarray(los, np.float64), axis=1)
        if not (np.isfinite(norm).all() and (norm > 0).all()):
            k = int(np.flatnonzero(~(np.isfinite(norm) & (norm > 0)))[0])
            raise ValueError(f"options.{f} must be finite non-zero vectors, got row {k}: {los[k]}")


def model_arrays(model, options: RouteOptions, dtype, order=None):
    """The pair function of a model with its option columns and parameters (host arrays).

    Args:
      model: AxisLimits or SlewTable (validated with :func:`validate_model`).
      options: RouteOptions.
      dtype: the dtype the engine computes in.
      order: optional int [M], the options to take (in this order); None: all.
    Returns:
      ``(pair, table, params)``: the pair function (:class:`_ChannelPairs` or
      :class:`_SlewPairs`), a tuple of contiguous field-major numpy arrays [F, M] of
      ``dtype`` and a tuple of parameter arrays of ``dtype``.
    """
    if isinstance(model, AxisLimits):
        c = np.shape(options.start_angle)[1]
        pair, fields = _ChannelPairs(_reach()), _CHANNEL_FIELDS
        params = tuple(np.asarray(x) for x in _channel_limits(model, c, dtype))
    else:
        pair, fields = _SlewPairs(), _LOS_FIELDS
        params = (np.asarray(model.time, np.dtype(dtype)),)
    sel = slice(None) if order is None else order
    cols = [np.asarray(getattr(options, f))[sel] for f in fields]
    if pair == _SlewPairs():
        cols = [x / np.linalg.norm(x.astype(np.float64), axis=1, keepdims=True) for x in cols]
    table = tuple(np.ascontiguousarray(x.T, np.dtype(dtype)) for x in cols)
    return pair, table, params
