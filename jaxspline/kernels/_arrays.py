"""Small numpy helpers for ragged batches and fixed-shape padding (used across the engine)."""

from __future__ import annotations

import numpy as np

__all__ = ["pad_rows", "ragged_positions"]


def ragged_positions(counts):
    """Owner and position of every element of runs laid end to end.

    For ``counts = [2, 0, 3]``: owner ``[0, 0, 2, 2, 2]``, position ``[0, 1, 0, 1, 2]``.
    """
    counts = np.asarray(counts, np.int64)
    owner = np.repeat(np.arange(counts.size), counts)
    pos = np.arange(int(counts.sum())) - np.repeat(np.cumsum(counts) - counts, counts)
    return owner, pos


def pad_rows(x, size: int):
    """``x`` (leading axis n <= size) with its last row repeated up to ``size`` rows.

    Compiled kernels see a few fixed shapes instead of one per batch size.
    """
    x = np.asarray(x)
    pad = size - x.shape[0]
    return np.concatenate([x, np.repeat(x[-1:], pad, 0)]) if pad > 0 else x
