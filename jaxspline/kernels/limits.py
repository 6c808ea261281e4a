"""Parameter bundles (pytrees) for kinematic limits."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from jaxspline.kernels.validate import check_positive

__all__ = ["AxisLimits", "validate_limits"]


class AxisLimits(NamedTuple):
    """Kinematic bounds of one attitude channel (or of an eigen-axis slew).

    Attributes:
      rate: bound b on |f'| [rad/s], > 0.
      accel: bound d on |f''| [rad/s^2], > 0.
      jerk: bound on |f'''| [rad/s^3], > 0; ``inf`` (default) means unbounded,
        which is the model of SPEC section 1.

    A NamedTuple, hence a pytree: fields may be arrays (one entry per channel or
    per candidate) and the bundle passes through ``jit``/``vmap``/``grad``.
    """

    rate: jnp.ndarray | float
    accel: jnp.ndarray | float
    jerk: jnp.ndarray | float = float("inf")


def validate_limits(limits: AxisLimits, name: str = "limits") -> AxisLimits:
    """Eagerly check that ``limits`` is an AxisLimits with positive fields.

    Args:
      limits: AxisLimits (or a plain 2- or 3-tuple), rate [rad/s], accel [rad/s^2],
        jerk [rad/s^3] (may be +inf); scalars or arrays.
      name: argument name used in the error message.
    Returns:
      AxisLimits (the tuple converted).
    Raises:
      ValueError: not an AxisLimits, or a field is not positive (names ``name.field``).
    """
    if not isinstance(limits, AxisLimits):
        if isinstance(limits, tuple) and len(limits) in (2, 3):
            limits = AxisLimits(*limits)
        else:
            raise ValueError(f"{name} must be an AxisLimits(rate, accel[, jerk]), got {limits!r}")
    check_positive(f"{name}.rate", limits.rate)
    check_positive(f"{name}.accel", limits.accel)
    check_positive(f"{name}.jerk", limits.jerk, allow_inf=True)
    return limits
