"""Transition streams for the sequencers: option order, validation, admissible rows.

The sequencers of :mod:`jaxspline.sequences.sequencer` read screened transitions either
as one :class:`~jaxspline.screen.pairs.Transitions` or as an iterable of
``Transitions`` chunks (e.g. from a generator that screens chunk by chunk). A
stream lists its rows grouped by source option, sources in increasing
``(t_start, option index)`` order; one source's rows may span consecutive
chunks, destinations come in any order. A single ``Transitions`` is sorted into
that order first (a stream of one chunk).

A feasible transition i -> j has ``t_start[j] > t_end[i] >= t_start[i]``, so
every predecessor of an option comes earlier in that order and all of its rows
are read before the option's first row as a source. The solvers push values
forward along the rows; a source's own state is complete when its first row
arrives, as long as no source of the same chunk feeds it. :func:`option_order`
therefore cuts the time-ordered options into *batches* with no feasible
transition inside a batch (every option of a batch starts no later than every
earlier option of the batch ends), and :func:`batch_segments` cuts the rows of a
chunk at batch boundaries: the rows of one segment never feed each other.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from typing import NamedTuple

import numpy as np

from jaxspline.screen.options import RouteOptions, validate_options
from jaxspline.screen.transitions import Transitions


class OptionOrder(NamedTuple):
    """Time order of the options and its batches (numpy int64 arrays).

    Attributes:
      nodes: [V], the ``scan_ok`` options in increasing ``(t_start, index)`` order.
      rank: [N], position of every option in the ``(t_start, index)`` order of all
        options (the order sources must follow in a stream).
      pos: [N], position of an option in ``nodes``, -1 if not ``scan_ok``.
      batch: [V], batch of each position of ``nodes`` (non-decreasing).
      batch_end: [B], one past the last position of each batch.
    """

    nodes: np.ndarray
    rank: np.ndarray
    pos: np.ndarray
    batch: np.ndarray
    batch_end: np.ndarray


def option_order(options: RouteOptions) -> OptionOrder:
    """The time order of ``options`` and its batches without inner transitions.

    A batch is a maximal run of consecutive ``nodes`` where each option starts
    no later than every earlier option of the run ends, so no transition
    (``t_start[j] > t_end[i]``) joins two options of one batch.

    Args:
      options: RouteOptions (validated here).
    Returns:
      OptionOrder.
    Raises:
      ValueError: from :func:`~jaxspline.screen.options.validate_options`.
    """
    validate_options(options)
    ts = np.asarray(options.t_start, np.float64)
    te = np.asarray(options.t_end, np.float64)
    n = ts.size
    order = np.argsort(ts, kind="stable")
    rank = np.empty(n, np.int64)
    rank[order] = np.arange(n)
    ok = np.asarray(options.scan_ok, bool)
    nodes = order[ok[order]].astype(np.int64)
    pos = np.full(n, -1, np.int64)
    pos[nodes] = np.arange(nodes.size)
    batch = np.empty(nodes.size, np.int64)
    b, end_min = -1, -np.inf
    for k, (s, e) in enumerate(zip(ts[nodes].tolist(), te[nodes].tolist(), strict=True)):
        if s > end_min:
            b, end_min = b + 1, e
        else:
            end_min = min(end_min, e)
        batch[k] = b
    batch_end = np.searchsorted(batch, np.arange(b + 1), side="right").astype(np.int64)
    return OptionOrder(nodes, rank, pos, batch, batch_end)


def admissible_rows(
    options: RouteOptions, order: OptionOrder, transitions
) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Validated (src, dst) of the admissible rows, chunk by chunk in stream order.

    A row is admissible when it is feasible, both options are ``scan_ok``, the
    routes differ and ``t_start[dst] > t_end[src]``. The type of ``transitions``
    is checked here, each chunk when it is read.

    Args:
      options: RouteOptions the transitions were screened on.
      order: ``option_order(options)``.
      transitions: a Transitions (sorted by source first) or an iterable of
        Transitions chunks in stream order.
    Returns:
      Iterator of (src, dst) int64 arrays, one pair per chunk.
    Raises:
      ValueError: ``transitions`` is neither (eagerly); while iterating, a chunk
        is not a Transitions, its indices are out of range, or its sources go
        back in ``(t_start, index)`` order (naming the offending source).
    """
    if isinstance(transitions, Transitions):
        chunks: Iterable = (_sorted_by_source(transitions, order.rank),)
    elif isinstance(transitions, (str, bytes, dict)) or not isinstance(transitions, Iterable):
        raise ValueError(
            "transitions must be a Transitions or an iterable of Transitions chunks, "
            f"got {type(transitions).__name__}"
        )
    else:
        chunks = transitions
    return _rows(options, order, chunks)


def batch_segments(
    order: OptionOrder, src: np.ndarray, dst: np.ndarray
) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
    """Cut stream-ordered admissible rows at batch boundaries.

    Args:
      order: OptionOrder of the options.
      src, dst: int64 [M], admissible rows in stream order.
    Returns:
      Iterator of (batch, src, dst) per run of rows whose sources share a batch.
    """
    if src.size == 0:
        return
    bt = order.batch[order.pos[src]]
    cut = np.flatnonzero(bt[1:] != bt[:-1]) + 1
    for lo, hi in zip(np.r_[0, cut].tolist(), np.r_[cut, src.size].tolist(), strict=True):
        yield int(bt[lo]), src[lo:hi], dst[lo:hi]


def _check_chunk(chunk, n: int):
    if not isinstance(chunk, Transitions):
        raise ValueError(f"transitions chunks must be Transitions, got {type(chunk).__name__}")
    src = np.asarray(chunk.src, np.int64).reshape(-1)
    dst = np.asarray(chunk.dst, np.int64).reshape(-1)
    feas = np.asarray(chunk.feasible, bool).reshape(-1)
    if not (src.size == dst.size == feas.size):
        raise ValueError(
            f"transitions.src/dst/feasible must have one length, got {src.size}, {dst.size}, "
            f"{feas.size}"
        )
    if src.size and (min(src.min(), dst.min()) < 0 or max(src.max(), dst.max()) >= n):
        raise ValueError(f"transitions.src/dst must index the {n} options")
    return src, dst, feas


def _sorted_by_source(tr: Transitions, rank: np.ndarray) -> Transitions:
    src, dst, feas = _check_chunk(tr, rank.size)
    src, dst = src[feas], dst[feas]
    o = np.argsort(rank[src], kind="stable")
    ones = np.ones(o.size, bool)
    return Transitions(src[o], dst[o], None, ones, None, None, None, 0)


def _rows(options: RouteOptions, order: OptionOrder, chunks: Iterable):
    route = np.asarray(options.route, np.int64)
    ok = np.asarray(options.scan_ok, bool)
    ts = np.asarray(options.t_start, np.float64)
    te = np.asarray(options.t_end, np.float64)
    rank = order.rank
    last = -1  # the last source read so far
    for chunk in chunks:
        src, dst, feas = _check_chunk(chunk, rank.size)
        if src.size == 0:
            continue
        r = rank[src]
        back = np.flatnonzero(r[1:] < r[:-1]) + 1
        k = 0 if last >= 0 and r[0] < rank[last] else (int(back[0]) if back.size else -1)
        if k >= 0:
            prev = last if k == 0 else int(src[k - 1])
            s = int(src[k])
            raise ValueError(
                "transitions must list sources in increasing (t_start, index) order: source "
                f"{s} (t_start={ts[s]!r}) follows source {prev} (t_start={ts[prev]!r})"
            )
        last = int(src[-1])
        keep = feas & ok[src] & ok[dst] & (route[src] != route[dst]) & (ts[dst] > te[src])
        yield src[keep], dst[keep]
