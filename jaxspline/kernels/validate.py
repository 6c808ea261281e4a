"""Eager input validation at the public boundary.

Kernels never raise; public wrappers call these helpers on *concrete* inputs
before dispatching to the batched kernel. Every error is a ``ValueError`` that
names the offending argument and shows its value. Traced inputs (inside a user's
``jit``/``vmap``/``grad``) cannot be inspected and are passed through unchecked.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "to_device",
    "is_concrete",
    "as_float_array",
    "check_positive",
    "check_nonnegative",
    "check_finite",
    "broadcast_named",
    "float_dtype_of",
    "cast_broadcast",
    "common_float",
    "finite_vector",
]


def to_device(x):
    """``jnp.asarray(x)`` without a compiled program for host data.

    ``jnp.asarray`` of a numpy array outside a trace compiles a small program for every
    new shape and dtype; ``jax.device_put`` copies it with the same dtype and weak type
    (x64 or not). Anything else (JAX arrays, tracers, Python values) goes to ``jnp.asarray``.

    Args:
      x: array-like.
    Returns:
      JAX array, a copy for numpy input.
    """
    if isinstance(x, (np.ndarray, np.generic)) and x.dtype != object:
        return jax.device_put(x, may_alias=False)
    return jnp.asarray(x)


def is_concrete(x) -> bool:
    """True when ``x`` holds actual values (not a tracer inside jit/vmap/grad).

    Args:
      x: any array-like or tracer.
    Returns:
      bool.
    """
    return not isinstance(x, jax.core.Tracer)


def _show(value) -> str:
    arr = np.asarray(value)
    if arr.size <= 6:
        return repr(arr.tolist())
    return f"array(shape={arr.shape}, min={np.nanmin(arr)!r}, max={np.nanmax(arr)!r})"


def float_dtype_of(*xs):
    """Common floating dtype of the inputs (JAX's default float if none are floating).

    Args:
      *xs: array-likes of any shape.
    Returns:
      a numpy floating dtype.
    """
    dts = [jnp.result_type(x) for x in xs if x is not None]
    dt = jnp.result_type(*dts) if dts else jnp.result_type(float)
    if not jnp.issubdtype(dt, jnp.floating):
        dt = jnp.result_type(float)
    return dt


def as_float_array(name: str, x, dtype=None):
    """Convert ``x`` to a floating JAX array, raising a named ValueError on failure.

    Args:
      name: argument name used in the error message.
      x: array-like of any shape.
      dtype: target floating dtype; None keeps a floating input's dtype.
    Returns:
      float array, the shape of x.
    Raises:
      ValueError: x is not numeric (message names ``name``).
    """
    try:
        arr = to_device(x)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric array-like, got {x!r}") from exc
    if dtype is None:
        dtype = arr.dtype if jnp.issubdtype(arr.dtype, jnp.floating) else jnp.result_type(float)
    return arr.astype(dtype)


def check_finite(name: str, x, allow_inf: bool = False) -> None:
    """Reject NaN (and, unless ``allow_inf``, infinities) in concrete ``x``.

    Tracers are not checked (kernels never raise).

    Args:
      name: argument name used in the error message.
      x: array-like of any shape.
      allow_inf: accept ±inf.
    Raises:
      ValueError: naming ``name`` and the offending value.
    """
    if not is_concrete(x):
        return
    arr = np.asarray(x)
    bad = np.isnan(arr) if allow_inf else ~np.isfinite(arr)
    if bad.any():
        raise ValueError(f"{name} must be {'not NaN' if allow_inf else 'finite'}, got {_show(x)}")


def check_positive(name: str, x, allow_inf: bool = False) -> None:
    """Reject non-positive or NaN entries in concrete ``x`` (``+inf`` allowed if asked).

    Args:
      name: argument name used in the error message.
      x: array-like of any shape.
      allow_inf: accept +inf.
    Raises:
      ValueError: naming ``name`` and the offending value.
    """
    if not is_concrete(x):
        return
    check_finite(name, x, allow_inf=allow_inf)
    if (np.asarray(x) <= 0).any():
        raise ValueError(f"{name} must be > 0, got {_show(x)}")


def check_nonnegative(name: str, x, allow_inf: bool = False) -> None:
    """Reject negative or NaN entries in concrete ``x``.

    Args:
      name: argument name used in the error message.
      x: array-like of any shape.
      allow_inf: accept +inf.
    Raises:
      ValueError: naming ``name`` and the offending value.
    """
    if not is_concrete(x):
        return
    check_finite(name, x, allow_inf=allow_inf)
    if (np.asarray(x) < 0).any():
        raise ValueError(f"{name} must be >= 0, got {_show(x)}")


def broadcast_named(**arrays):
    """Broadcast named arrays together; on failure name every argument and its shape.

    Args:
      **arrays: name -> array of any shape.
    Returns:
      list of the broadcast arrays in the given order.
    Raises:
      ValueError: the shapes do not broadcast (every name and shape listed).
    """
    shapes = {k: jnp.shape(v) for k, v in arrays.items()}
    try:
        shape = jnp.broadcast_shapes(*shapes.values())
    except ValueError as exc:
        desc = ", ".join(f"{k}{s}" for k, s in shapes.items())
        raise ValueError(f"arguments are not broadcastable: {desc}") from exc
    return tuple(jnp.broadcast_to(v, shape) for v in arrays.values())


def _is_weak(x) -> bool:
    """Python scalars and weakly typed arrays, which do not set a result dtype.

    Args:
      x: any value.
    Returns:
      bool.
    """
    return isinstance(x, int | float) or bool(getattr(x, "weak_type", False))


def cast_broadcast(**named):
    """Cast named inputs to one float dtype and broadcast them (named errors on failure).

    The dtype is set by the non-weak inputs (JAX's default float when all are
    Python scalars), so float32 arrays stay float32 next to Python constants.

    Args:
      **named: name -> array-like of any shape.
    Returns:
      list of float arrays of the common broadcast shape, in the given order.
    Raises:
      ValueError: an input is not numeric or the shapes do not broadcast (named).
    """
    dt = float_dtype_of(*[v for v in named.values() if not _is_weak(v)])
    return broadcast_named(**{k: as_float_array(k, v, dt) for k, v in named.items()})


def common_float(*xs):
    """Cast inputs to their common floating dtype (weak Python floats follow arrays).

    Integer-only inputs become JAX's default float. Used inside kernels (traced
    values welcome) and after the eager checks of the public wrappers.

    Args:
      *xs: array-likes or tracers of any shape (not broadcast).
    Returns:
      list of float arrays, shapes unchanged.
    """
    dt = jnp.result_type(*xs)
    if not jnp.issubdtype(dt, jnp.floating):
        dt = jnp.result_type(float)
    return tuple(jnp.asarray(x, dt) for x in xs)


def finite_vector(name: str, x, last: int | None = None):
    """``x`` as a floating array, checked finite, whose last axis has length ``last``.

    Args:
      name: argument name used in the error message.
      x: array-like, float [..., last].
      last: required length of the last axis; None accepts any shape.
    Returns:
      float array, the shape of x.
    Raises:
      ValueError: naming ``name`` (shape or value).
    """
    arr = as_float_array(name, x)
    if last is not None and (arr.ndim == 0 or arr.shape[-1] != last):
        raise ValueError(f"{name} must have last axis of length {last}, got shape {arr.shape}")
    check_finite(name, arr)
    return arr


def positive_duration(T):
    """``T`` as a float array, checked finite and > 0 (a maneuver's duration [s])."""
    T = as_float_array("T", T)
    check_positive("T", T)
    return T


def boundary_states(q0, w0, e0, j0, q1, w1, e1, j1):
    """The end states of a maneuver, checked: quaternions [..., 4], body rate, acceleration
    and jerk [..., 3] (finite); a missing jerk (None) is zero."""
    q0, q1 = finite_vector("q0", q0, 4), finite_vector("q1", q1, 4)
    w0, e0, w1, e1 = (
        finite_vector(n, x, 3) for n, x in (("w0", w0), ("e0", e0), ("w1", w1), ("e1", e1))
    )
    j0 = jnp.zeros_like(e0) if j0 is None else finite_vector("j0", j0, 3)
    j1 = jnp.zeros_like(e1) if j1 is None else finite_vector("j1", j1, 3)
    return q0, w0, e0, j0, q1, w1, e1, j1
