"""The screened-transition table and the plumbing the screening paths share.

:class:`Transitions` (the result table), the candidate runs (:func:`candidate_runs`), the device
mesh (:func:`device_mesh`), a screen in progress (:class:`Stream`), the host-side top-k merge
(:func:`top_k_merge`, :func:`best_per_source`) and the collection of chunks into
preallocated columns (:func:`collect`). The fused path (:mod:`jaxspline.screen.fused`),
the host path (:mod:`jaxspline.screen.host`), the sequence screen
(:mod:`jaxspline.sequences.route_screen`) and the entry points (:mod:`jaxspline.screen.pairs`)
build on it; it imports none of them, so the screening modules form no import circle.
"""

from __future__ import annotations

import mmap
from collections.abc import Iterator
from typing import NamedTuple

import jax
import numpy as np
from jax.sharding import Mesh

from jaxspline.kernels.batch import ragged_positions
from jaxspline.screen.options import RouteOptions

__all__ = ["Transitions", "best_per_source", "default_chunk_size"]

#: Candidates per screening chunk on CPU devices: a chunk's temporaries (~150 bytes a
#: candidate) stay within the caches' reach (bench/results/SCREENING.md).
CPU_CHUNK = 1 << 18
#: ... on accelerators: 16x fewer chunks, so per-chunk dispatch, host syncs and
#: transfers stop bounding the rate (~0.6 GB of temporaries a chunk on the device).
ACCEL_CHUNK = 1 << 22


class Transitions(NamedTuple):
    """Screened candidate transitions (struct of numpy arrays, M candidates).

    The columns ``margin``, ``effort`` and ``t_min`` depend on the maneuver model
    (:mod:`jaxspline.screen.pair_models`); with either model a candidate with
    ``T <= 0`` is infeasible, its margin -inf and its effort +inf.

    Attributes:
      src, dst: int64 [M], option indices (into the RouteOptions given) of the
        end option i and the start option j.
      T: [M] transfer duration t_start[j] - t_end[i] [s], > 0.
      feasible: bool [M]. AxisLimits: every channel can make the transfer in
        exactly T. SlewTable: ``T >= t_req``, the tabulated rest-to-rest time.
      margin: [M]. AxisLimits: reach margin [rad], min over channels of
        ``reach.reach_margin_kernel`` (>= 0 iff feasible, up to rounding).
        SlewTable: time margin ``T - t_req`` [s] (>= 0 iff feasible).
      effort: [M]. AxisLimits: max over channels of d*_c / accel_c, where d*_c is
        the least acceleration bound that makes channel c feasible in T
        (``reach_durations.min_peak_accel_kernel``; SPEC section 1, dual problem,
        seed retarget-scan eq. 13): <= 1 iff feasible; +inf if the rate bound
        alone forbids it. SlewTable: ``t_req / T`` (<= 1 iff feasible).
      t_min: [M] [s]. AxisLimits: max over channels of the shortest transfer time
        (``reach_durations.min_transfer_time_kernel``); a necessary bound only.
        SlewTable: ``t_req`` (settle and gap margin included).
      n_screened: number of candidates screened by this call (this process); in a
        chunk of :func:`screen_chunks`, by that chunk.
    """

    src: np.ndarray
    dst: np.ndarray
    T: np.ndarray
    feasible: np.ndarray
    margin: np.ndarray
    effort: np.ndarray
    t_min: np.ndarray
    n_screened: int


def default_chunk_size(chunk_size: int | None = None) -> int:
    """``chunk_size`` if given, else the screening chunk for the local devices:
    :data:`CPU_CHUNK` on CPU, :data:`ACCEL_CHUNK` on a GPU or TPU."""
    if chunk_size is not None:
        return chunk_size
    return CPU_CHUNK if jax.local_devices()[0].platform == "cpu" else ACCEL_CHUNK


def device_mesh():
    """The 1-D mesh ``("cand",)`` over all local devices: the candidate axis of every
    screening chunk is split over it (the option table is replicated)."""
    devs = jax.local_devices()
    return Mesh(np.array(devs), ("cand",))


class Runs(NamedTuple):
    """Candidate runs: the ``scan_ok`` options sorted by ``(t_start, index)``; source
    position k's destinations are the sorted positions ``lo[k] .. lo[k] + counts[k] - 1``
    (``t_end[src] < t_start[dst] <= t_end[src] + max_gap``)."""

    order: np.ndarray
    lo: np.ndarray
    counts: np.ndarray


def candidate_runs(options: RouteOptions, max_gap) -> Runs:
    """The candidate runs of ``options`` (float64 times), shared by both screening paths."""
    t_start = np.asarray(options.t_start, np.float64)
    t_end = np.asarray(options.t_end, np.float64)
    valid = np.flatnonzero(np.asarray(options.scan_ok, bool))
    order = valid[np.argsort(t_start[valid], kind="stable")]
    ts_sorted = t_start[order]
    te_src = t_end[order]
    lo = np.searchsorted(ts_sorted, te_src, side="right")
    if max_gap is None:
        hi = np.full_like(lo, order.size)
    else:
        hi = np.searchsorted(ts_sorted, te_src + float(max_gap), side="right")
    return Runs(order, lo, np.maximum(hi - lo, 0).astype(np.int64))


def empty_transitions(dtype) -> Transitions:
    """A Transitions of no rows in the compute ``dtype``."""
    f = np.zeros(0, np.dtype(dtype))
    i = np.zeros(0, np.int64)
    return Transitions(i, i, f, np.zeros(0, bool), f, f, f, 0)


class Stream(NamedTuple):
    """A screen in progress: candidate slots, compute dtype, sink kind and the chunks."""

    total: int
    dtype: object
    lazy: bool
    chunks: Iterator[Transitions]


def top_k_score(options, top_k_by: str):
    """The ranking score of feasible rows (the 7 Transitions columns): their margin, the
    value of their destination option, or that value per second from the source's end
    to the destination's end (see :func:`screen_transitions`)."""
    if top_k_by == "margin":
        return lambda cols: cols[4]
    value = np.asarray(options.value, np.float64)
    if top_k_by == "value":
        return lambda cols: value[cols[1]]
    t_end = np.asarray(options.t_end, np.float64)
    return lambda cols: value[cols[1]] / (t_end[cols[1]] - t_end[cols[0]])


def top_k_merge(parts, k: int, score) -> Iterator[Transitions]:
    """Per source, its ``k`` rows of largest ``score(cols)``, yielded once the source is
    final (ties: earlier rows first).

    ``parts`` yields ``(key, cols, n_screened)``: ``key`` int [m] the source's time
    rank, non-decreasing over the whole stream, and ``cols`` the 7 feasible-row columns
    of :class:`Transitions`. A source below the largest key seen so far is final (rows
    come in source order); the last source seen is carried into the next part.
    """
    carry = None
    for key, cols, n in parts:
        cols = list(cols)
        if carry is not None:
            key = np.concatenate([carry[0], key])
            cols = [np.concatenate([a, b]) for a, b in zip(carry[1], cols, strict=True)]
        out = [c[:0] for c in cols]
        if key.size:
            done = key < key.max()
            sel = best_per_source(key[done], score(cols)[done], k)
            out = [c[done][sel] for c in cols]
            carry = key[~done], [c[~done] for c in cols]
        yield Transitions(*out, n_screened=int(n))
    if carry is not None:
        sel = best_per_source(carry[0], score(carry[1]), k)
        yield Transitions(*(c[sel] for c in carry[1]), n_screened=0)


def collect(stream: Stream, feasible_only: bool) -> Transitions:
    """All chunks of a stream in one Transitions (written into a :class:`_Sink`)."""
    if stream.total == 0:
        for _ in stream.chunks:  # runs the generator to its end (closes the bar)
            pass
        return empty_transitions(stream.dtype)
    sink = _Sink(stream.total, stream.dtype, feasible_only, lazy=stream.lazy)
    n_screened = 0
    for chunk in stream.chunks:
        sink.add_rows(chunk[:-1])
        n_screened += chunk.n_screened
    return sink.result(n_screened)


def best_per_source(src, margin, k: int) -> np.ndarray:
    """Indices of the ``k`` rows of largest margin of every source, grouped by source.

    Rows come out sorted by source (ascending) and, within a source, by decreasing
    margin (ties: earlier rows first). Merges the parts of a multi-process
    ``top_k`` screen as well: concatenate them and select again.

    Args:
      src: int [M], source key of every row (e.g. option id or time rank).
      margin: float [M], the margin to rank by.
      k: int >= 1, rows kept per source.
    Returns:
      int [<= M], row indices.
    """
    src, margin = np.asarray(src), np.asarray(margin)
    if src.size == 0:
        return np.zeros(0, np.int64)
    order = np.lexsort((np.arange(src.size), -margin, src))
    s = src[order]
    first = np.r_[0, np.flatnonzero(s[1:] != s[:-1]) + 1]
    rank = ragged_positions(np.diff(np.r_[first, s.size]))[1]  # position in its source
    return order[rank < k]


def _prefaulted(n: int, dtype) -> np.ndarray:
    """Uninitialized array like ``np.empty(n, dtype)``, its pages mapped up front.

    A result column of a large screen is hundreds of MB of fresh memory; written
    chunk by chunk, its first-touch page faults (and transparent-huge-page
    compaction stalls) cost 1-3 s at 1e7 candidates on the 2-core test VM, more
    than the screening itself. One anonymous ``mmap`` with ``MAP_POPULATE`` (Linux)
    maps all pages in a single system call (~0.3 s for 600 MB). Falls back to
    ``np.empty`` for small arrays or where the flag is unavailable.
    """
    dt = np.dtype(dtype)
    populate = getattr(mmap, "MAP_POPULATE", None)
    nbytes = n * dt.itemsize
    if populate is None or nbytes < (1 << 24):
        return np.empty(n, dt)
    try:
        buf = mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS | populate)
    except (OSError, ValueError):
        return np.empty(n, dt)
    return np.frombuffer(buf, dt, count=n)


class _Sink:
    """Collects screened chunks: into preallocated columns (no final concatenation copy,
    bounded by the candidate count) or, with ``feasible_only``, as a list of the kept rows.

    ``lazy`` (the fused path's ``feasible_only``): the columns are reserved for all
    candidates with ``np.empty``, whose pages become resident only when written, so
    the kept rows are written once, in place, and the peak is the kept rows, not the
    parts plus their concatenation (2x with the list; freed parts also stay in the
    allocator's heap). Falls back to the list if the reservation is refused.
    """

    def __init__(self, total: int, dtype, feasible_only: bool, lazy: bool = False):
        self.feasible_only = feasible_only
        self.cols_dtype = dtype
        self.parts = []
        self.w = 0
        self.cols = None
        f = np.dtype(dtype)
        types = (np.int64, np.int64, f, bool, f, f, f)
        if not feasible_only:
            self.cols = [_prefaulted(total, t) for t in types]
        elif lazy:
            try:
                self.cols = [np.empty(total, t) for t in types]
            except MemoryError:
                self.cols = None

    def add_rows(self, cols):
        """Add rows that are kept as they are (already compacted on the device)."""
        if self.cols is None:
            self.parts.append(tuple(np.array(a) for a in cols))  # copies: frees the chunk buffer
            return
        n = cols[0].size
        for buf, a in zip(self.cols, cols, strict=True):
            buf[self.w : self.w + n] = a
        self.w += n

    def result(self, n_screened: int) -> Transitions:
        if self.cols is not None:
            return Transitions(*(c[: self.w] for c in self.cols), n_screened=n_screened)
        if not self.parts:
            return empty_transitions(self.cols_dtype)._replace(n_screened=n_screened)
        cols = [np.concatenate(col) for col in zip(*self.parts, strict=True)]
        return Transitions(*cols, n_screened=n_screened)
