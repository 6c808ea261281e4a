"""Batching, padding and chunked evaluation: one home for every layer.

A kernel is written for one candidate and batched once, here (:func:`batched`).
Host-side loops pad their batches to a few fixed shapes (:func:`padded_size`,
:func:`round_up`, :func:`pad_rows`) so compiled programs are reused, and long
batches run in fixed-size chunks (:func:`map_chunked`): bounded memory, one compile.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

__all__ = [
    "batched",
    "map_chunked",
    "pad_last",
    "pad_rows",
    "padded_size",
    "ragged_positions",
    "round_up",
]


def batched(fn, signature: str | None = None, excluded=frozenset()):
    """``jit(vectorize(fn))``: a per-candidate kernel mapped over leading axes.

    Args:
      fn: kernel of one candidate.
      signature: ``jnp.vectorize`` core signature, e.g. ``"(4),(3)->(3)"``
        (None: all arguments are scalars).
      excluded: positions of arguments passed through unbatched (e.g. a Scene).

    Returns:
      The jitted, broadcasting function.
    """
    return jax.jit(jnp.vectorize(fn, excluded=excluded, signature=signature))


def ragged_positions(counts):
    """Owner and position of every element of runs laid end to end.

    For ``counts = [2, 0, 3]``: owner ``[0, 0, 2, 2, 2]``, position ``[0, 1, 0, 1, 2]``.

    Args:
      counts: int [R], run lengths.

    Returns:
      (owner int [sum(counts)], position int [sum(counts)]).
    """
    counts = np.asarray(counts, np.int64)
    owner = np.repeat(np.arange(counts.size), counts)
    pos = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    return owner, pos


def round_up(n: int, multiple: int) -> int:
    """The smallest multiple of ``multiple`` that is >= n.

    Args:
      n: int >= 0.
      multiple: int > 0.
    Returns:
      int.
    """
    return -(-int(n) // multiple) * multiple


def padded_size(n: int, maximum: int | None = None, multiple: int = 1) -> int:
    """Fixed batch length for n rows: a power of two >= max(n, 1024).

    Few distinct lengths means few compilations.

    Args:
      n: rows to evaluate.
      maximum: cap on the power of two (the chunk size), or None.
      multiple: the result is rounded up to a multiple of this (e.g. the device count).
    """
    size = max(1024, 1 << (max(int(n), 1) - 1).bit_length())
    if maximum is not None:
        size = min(maximum, size)
    return round_up(size, multiple)


def pad_last(x, size: int) -> np.ndarray:
    """``x`` (host) with zeros appended along its last axis up to ``size`` (a padded
    table: indices past the true length are never read).

    Args:
      x: array-like [..., n], n <= size.
      size: length wanted.
    Returns:
      numpy array [..., size], the dtype of x.
    """
    x = np.asarray(x)
    return np.pad(x, [(0, 0)] * (x.ndim - 1) + [(0, size - x.shape[-1])])


def pad_rows(x, size: int):
    """``x`` with its last row repeated up to ``size`` rows.

    Compiled kernels see a few fixed shapes instead of one per batch size. numpy
    arrays stay numpy, JAX arrays stay on the device.

    Args:
      x: array [n, ...], n <= size (n >= 1).
      size: number of rows wanted.
    Returns:
      array [size, ...] of the same kind and dtype as x.
    """
    xp = jnp if isinstance(x, jax.Array) else np
    x = xp.asarray(x)
    pad = size - x.shape[0]
    return xp.concatenate([x, xp.repeat(x[-1:], pad, 0)]) if pad > 0 else x


def map_chunked(fn, args, chunk: int, *, to_numpy: bool = True, desc: str | None = None):
    """``fn(*args)`` over consecutive leading-axis chunks, each padded to ``chunk`` rows.

    One compiled shape serves every call (compilation, not evaluation, dominates
    small batches) and memory stays bounded for long batches.

    Args:
      fn: function of arrays [chunk, ...] returning a tuple of arrays [chunk, ...].
      args: arrays with the same leading length n >= 1.
      chunk: rows per call.
      to_numpy: results as numpy arrays (else JAX arrays, left on the device).
      desc: progress-bar label (tqdm), or None for no bar.

    Returns:
      List of fn's outputs, each concatenated over the chunks [n, ...].
    """
    n = int(np.shape(args[0])[0])
    starts = range(0, n, chunk)
    if desc is not None:
        from tqdm.auto import tqdm

        starts = tqdm(starts, desc=desc, unit="chunk", leave=False)
    outs = []
    for a in starts:
        b = min(n, a + chunk)
        res = fn(*(pad_rows(x[a:b], chunk) for x in args))
        outs.append([np.asarray(r)[: b - a] if to_numpy else r[: b - a] for r in res])
    cat = np.concatenate if to_numpy else jnp.concatenate
    return [cat(col) for col in zip(*outs, strict=True)]
