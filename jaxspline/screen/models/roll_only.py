"""The ``roll_only`` model: one roll axis, a bang-coast-bang slew, then settling.

A roll-only satellite (the regional_coverage benchmark's, RULES.md) keeps its body in the
local frame of its track (:func:`jaxspline.geometry.pointing.roll_frame`) and turns about
one axis only. During a strip the roll is held fixed (the pointing law
:func:`jaxspline.geometry.pointing.roll_look_direction`); between two strips it turns by
``delta = |r2 - r1|``, at rest at both ends, time-optimally under the rate bound ``w`` and
the acceleration bound ``a`` (bang-coast-bang)::

    slew(delta) = 2 sqrt(delta / a)     if delta <= w^2 / a  (triangle, peak rate sqrt(a delta))
                = delta / w + w / a     otherwise            (trapezoid, coast at w)

and then settles for ``s``: a transition fits a gap ``g`` iff ``g >= slew(delta) + s``;
its margin is ``g - slew(delta) - s``.

Units: one angle unit u throughout (rad or deg): delta [u], w [u/s], a [u/s^2]; times [s].

The same formula in three forms:

* kernels of one candidate (jit/vmap-able, branchless, finite values and gradients,
  infeasible as a value): :func:`roll_transition_kernel`, :func:`roll_profile_kernel`;
  the slew time itself is :func:`jaxspline.kernels.slew.bang_coast_bang_time_kernel`;
  the public wrappers :func:`roll_transition`, :func:`roll_profile` validate and
  broadcast;
* host numpy for search loops that cannot afford a JAX dispatch per call
  (:func:`roll_slew_time`, :func:`roll_need`, :func:`roll_min_gap`), equal to the
  kernels bit for bit (tests);
* :class:`RollOnly`, the :class:`~jaxspline.screen.models.base.ManeuverModel` of a
  planner satellite (``model = "roll_only"``, rad): it images area strips only (a roll
  held fixed, :func:`jaxspline.geometry.pointing.roll_params`; point and strip targets
  need pitch), compares its lines of sight in the Earth-fixed frame (the benchmark's
  slew angle) and has no requirement before its first observation.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxspline.kernels.batch import batched
from jaxspline.kernels.safe import safe_sqrt
from jaxspline.kernels.slew import bang_coast_bang_time_kernel
from jaxspline.kernels.validate import cast_broadcast, check_finite, check_positive
from jaxspline.screen.models.rest_to_rest import RestToRest

__all__ = [
    "RollLimits",
    "RollOnly",
    "RollTransition",
    "roll_min_gap",
    "roll_need",
    "roll_profile",
    "roll_profile_kernel",
    "roll_slew_time",
    "roll_transition",
    "roll_transition_kernel",
]


class RollLimits(NamedTuple):
    """Agility of one roll axis (a pytree; fields broadcast).

    Attributes:
      rate: rate bound w [u/s], > 0 (inf: bang-bang).
      accel: acceleration bound a [u/s^2], > 0.
      settle: settling time after each slew [s], >= 0 (a planner may add its safety
        margin here).
    """

    rate: object
    accel: object
    settle: object


class RollTransition(NamedTuple):
    """A roll change in a gap, feasibility as a value.

    Attributes:
      feasible: bool, ``margin >= 0`` (False for a NaN gap).
      margin: gap - need [s] (negative: short by that much).
      need: slew time + settling [s].
    """

    feasible: object
    margin: object
    need: object


def roll_transition_kernel(delta, gap, rate, accel, settle):
    """A rest-to-rest roll change ``delta`` in a gap, one candidate.

    ``need = slew(|delta|) + settle`` (:func:`bang_coast_bang_time_kernel`),
    ``margin = gap - need``, ``feasible = margin >= 0``.

    Args:
      delta: roll change [u] (its magnitude is used).
      gap: time available [s] (inf: always feasible).
      rate: rate bound w [u/s], > 0.
      accel: acceleration bound a [u/s^2], > 0.
      settle: settling time [s].
    Returns:
      :class:`RollTransition`; finite values and gradients at delta = 0 and at the switch
      ``|delta| = w^2 / a``.
    """
    need = bang_coast_bang_time_kernel(delta, rate, accel) + settle
    margin = gap - need
    return RollTransition(margin >= 0.0, margin, need)


def roll_profile_kernel(delta, rate, accel, t):
    """Acceleration, rate and angle of the bang-coast-bang roll slew at time t, one candidate.

    With ``t_a = min(w / a, sqrt(|delta| / a))`` (accelerating), ``t_c = max(|delta| / w -
    w / a, 0)`` (coasting) and ``T = 2 t_a + t_c``: acceleration ``+a`` on ``[0, t_a)``,
    0 on the coast, ``-a`` on ``[t_a + t_c, T)``; the angle goes from 0 to ``delta`` (sign
    of delta), at rest at both ends and held outside ``[0, T]``.

    Args:
      delta: roll change [u] (signed).
      rate: rate bound w [u/s], > 0 (inf: no coast).
      accel: acceleration bound a [u/s^2], > 0.
      t: time since the slew start [s].
    Returns:
      ``(accel_t [u/s^2], rate_t [u/s], angle_t [u])``; finite values and gradients.
    """
    phi = jnp.abs(delta)
    sign = jnp.where(delta < 0, -1.0, 1.0)
    t_a = jnp.minimum(rate / accel, safe_sqrt(phi / accel))
    t_c = jnp.maximum(phi / rate - rate / accel, 0.0)
    total = 2.0 * t_a + t_c
    u = jnp.clip(t, 0.0, total)
    left = total - u  # time to the end
    peak = accel * t_a
    speeding = u < t_a
    braking = u >= t_a + t_c
    inside = (t >= 0.0) & (t < total)
    acc = jnp.where(speeding, accel, jnp.where(braking, -accel, 0.0))
    vel = jnp.where(speeding, accel * u, jnp.where(braking, accel * left, peak))
    ang = jnp.where(
        speeding,
        0.5 * accel * u * u,
        jnp.where(braking, phi - 0.5 * accel * left * left, 0.5 * peak * t_a + peak * (u - t_a)),
    )
    return sign * jnp.where(inside, acc, 0.0), sign * vel, sign * ang


_transition_batched = batched(roll_transition_kernel)
_profile_batched = batched(roll_profile_kernel)


def _check_limits(limits: RollLimits) -> None:
    check_positive("limits.rate", limits.rate, allow_inf=True)
    check_positive("limits.accel", limits.accel)
    check_finite("limits.settle", limits.settle)
    if np.any(np.asarray(limits.settle) < 0):
        raise ValueError(f"limits.settle must be >= 0, got {limits.settle!r}")


def roll_transition(delta, gap, limits: RollLimits) -> RollTransition:
    """:func:`roll_transition_kernel` broadcast over its arguments.

    Args:
      delta: roll change(s) [u], finite.
      gap: gap(s) [s], not NaN (inf allowed).
      limits: RollLimits.
    Returns:
      RollTransition of the broadcast shape.
    Raises:
      ValueError: naming ``delta``, ``gap`` or the ``limits`` field.
    """
    check_finite("delta", delta)
    check_finite("gap", gap, allow_inf=True)
    _check_limits(limits)
    args = cast_broadcast(
        delta=delta, gap=gap, rate=limits.rate, accel=limits.accel, settle=limits.settle
    )
    return RollTransition(*_transition_batched(*args))


def roll_profile(delta, limits: RollLimits, t):
    """Acceleration, rate and angle of roll slews at times t (for plots), broadcasting.

    Args:
      delta: roll change(s) [u], finite.
      limits: RollLimits (``settle`` unused: the profile is the slew alone).
      t: time(s) since the slew start [s], finite.
    Returns:
      ``(accel_t [u/s^2], rate_t [u/s], angle_t [u])``, see :func:`roll_profile_kernel`.
    Raises:
      ValueError: naming ``delta``, ``t`` or the ``limits`` field.
    """
    check_finite("delta", delta)
    check_finite("t", t)
    _check_limits(limits)
    args = cast_broadcast(delta=delta, rate=limits.rate, accel=limits.accel, t=t)
    return _profile_batched(*args)


def roll_slew_time(delta, rate, accel) -> np.ndarray:
    """Host (numpy) slew time ``slew(|delta|)`` [s], equal to the kernel's bit for bit.

    Args:
      delta: float or array, roll change [u].
      rate: rate bound w [u/s], > 0 (inf allowed).
      accel: acceleration bound a [u/s^2], > 0.
    Returns:
      float64 array of the broadcast shape [s]; 0 for delta = 0.
    """
    d = np.abs(np.asarray(delta, dtype=np.float64))
    w = np.asarray(rate, dtype=np.float64)
    a = np.asarray(accel, dtype=np.float64)
    tri = 2.0 * np.sqrt(d / a)
    trap = d / w + w / a
    return np.where(d <= w * w / a, tri, trap)


def roll_need(delta, limits: RollLimits) -> np.ndarray:
    """Host (numpy) time a roll change needs: ``slew(|delta|) + settle`` [s].

    Args:
      delta: float or array, roll change [u].
      limits: RollLimits.
    Returns:
      float64 array [s].
    """
    return roll_slew_time(delta, limits.rate, limits.accel) + limits.settle


def roll_min_gap(delta, limits: RollLimits, drift, iterations: int) -> np.ndarray:
    """Host (numpy) smallest gap when the angle to turn grows with the gap.

    The smallest ``g`` with ``g >= need(|delta| + drift g)`` (:func:`roll_need`), e.g.
    when the rule measures the slew between Earth-fixed look directions, which turn
    with the orbit at up to ``drift`` during the gap. Fixed-point iteration from
    ``g_0 = need(|delta|)``: ``need`` is increasing, so the iterates increase and never
    pass the smallest fixed point; they converge when ``drift need' < 1``.

    Args:
      delta: float or array, roll change [u].
      limits: RollLimits.
      drift: float, growth of the angle per second of gap [u/s] (>= 0).
      iterations: int, fixed-point steps after ``g_0``.
    Returns:
      float64 array [s], the last iterate (at most the smallest fixed point: add a
      slack for a safe gap).
    """
    d = np.abs(np.asarray(delta, dtype=np.float64))
    g = roll_need(d, limits)
    for _ in range(int(iterations)):
        g = roll_need(d + drift * g, limits)
    return g


class RollOnly(RestToRest):
    """Roll-only slews as a :class:`~jaxspline.screen.models.base.ManeuverModel`.

    The profile time is :func:`roll_slew_time` of the satellite's scalar limits [rad].
    Through the protocol (slew tables of angles between Earth-fixed lines of sight) the
    answers are conservative: for roll-only looks ``cos r1 nadir1 + sin r1 across`` and
    the same at r2 (across fixed, as on a circular orbit), ``cos(theta) = cos r1 cos r2
    (nadir1 . nadir2) + sin r1 sin r2 <= cos(r2 - r1)`` for ``|r| < 90 deg``, so the
    line-of-sight angle is at least the roll change.
    """

    name = "roll_only"
    los_frame = "earth_fixed"
    tracks_points = False
    first_from_nadir = False

    def first_requirements(self, sat, options, idx, screen_model):
        """No requirement before a first observation (the roll is free at the start).

        Returns:
          numpy float [K], zeros.
        """
        return np.zeros(np.shape(idx)[0])

    def profile_time(self, sat, theta) -> np.ndarray:
        """Bang-coast-bang time [s] through angles theta [rad] (numpy)."""
        return roll_slew_time(theta, float(sat.limits.rate), float(sat.limits.accel))

    def limits(self, sat) -> RollLimits:
        """The satellite's :class:`RollLimits` [rad, rad/s, rad/s^2, s]."""
        return RollLimits(float(sat.limits.rate), float(sat.limits.accel), float(sat.settle))
