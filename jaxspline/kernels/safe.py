"""Numerical guards shared by every kernel: the double-where trick in one place.

Each guard keeps values AND gradients finite everywhere, including exactly at
the case boundary, because the unselected branch never sees a bad input
(``jnp.where`` differentiates both branches).
"""

from __future__ import annotations

import jax.numpy as jnp

__all__ = ["pos_or_one", "safe_div", "safe_norm", "safe_sqrt"]


def pos_or_one(x):
    """``x`` where it is > 0, else 1: a safe argument for sqrt, cbrt or a divisor.

    Args:
      x: array of any shape.

    Returns:
      Array like ``x``.
    """
    return jnp.where(x > 0, x, jnp.ones_like(x))


def safe_sqrt(x):
    """sqrt(max(x, 0)), with value 0 and a zero (finite) gradient at x <= 0.

    Args:
      x: array of any shape.

    Returns:
      Array like ``x``.
    """
    pos = x > 0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, x, 1.0)), 0.0)


def safe_div(num, den, fill=0.0):
    """num / den where den != 0, else ``fill``; finite gradients both ways.

    Args:
      num: numerator, broadcastable with ``den``.
      den: denominator.
      fill: value where ``den == 0``.

    Returns:
      Array of the broadcast shape.
    """
    ok = den != 0
    return jnp.where(ok, num / jnp.where(ok, den, 1.0), fill)


def safe_norm(v):
    """Euclidean norm over the last axis, with a finite (zero) gradient at v = 0.

    Args:
      v: array [..., n].

    Returns:
      Array [...].
    """
    return safe_sqrt(jnp.sum(v * v, axis=-1))
