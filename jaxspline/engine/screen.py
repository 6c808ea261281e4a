"""Bulk screening of route-to-route transitions (SPEC section 4).

A *candidate transition* is option i -> option j of two different routes with
``T = t_start[j] - t_end[i] > 0`` (and ``T <= max_gap`` if given). What the
transfer must achieve in T is the maneuver model, the engine's second argument
(:mod:`jaxspline.engine.screen_models`): with AxisLimits, for every attitude
channel c the spacecraft must move from ``(end_angle[i, c], end_rate[i, c])`` to
``(start_angle[j, c], start_rate[j, c])`` in EXACTLY T seconds under ``|f'| <=
rate[c]``, ``|f''| <= accel[c]``; the per-channel exact-T kernels of
:mod:`jaxspline.kernels.reach` decide it (SPEC section 1; feasible durations are
not an interval, so ``T >= t_min`` is not enough). With a
:class:`jaxspline.engine.models.SlewTable`, a rest-to-rest slew through the angle
between ``end_los[i]`` and ``start_los[j]`` (settle and gap margin included) must
fit in T.

:func:`screen_chunks` yields the result chunk by chunk as it comes off the devices
(order contract in its docstring); :func:`screen_transitions` collects it.

Engine layout:

* Candidate runs: valid options (``scan_ok``) are sorted by ``t_start``; for
  each source i the admissible destinations form one contiguous run of that
  order (``t_end[i] < t_start[j] <= t_end[i] + max_gap``, found by
  ``searchsorted``). N^2 pairs are never held at once.
* Fused path (default; :mod:`jaxspline.engine.screen_fused`): each run is cut into
  rows of ``width`` slots (a power of two <= 256 chosen so padding stays <= 6 %),
  and the time-sorted option table (padded to a power of two, so tables of
  similar size share compiled programs) goes to the devices once. Chunk k is
  ``rows`` consecutive rows of the row table (source, first destination, count;
  a few kB per chunk): the screening program builds the slots'
  destination indices by broadcasting (no per-candidate search: XLA's CPU
  ``searchsorted`` ran at 2e7/s), applies the same-route exclusion, forms
  ``T = t_start[dst] - t_end[src]`` in float64 and cast to the table dtype
  (bit-identical to the host path), and runs the model's pair function. A second
  program compacts the kept rows (all different-route pairs, or the feasible
  ones with ``feasible_only``) to the front of the chunk, so only they reach the
  result. The two programs are separate on purpose: fused, XLA's CPU backend
  inlined the kernels into the compaction's gathers and recomputed them (0.3x).
* Host path (:mod:`jaxspline.engine.screen_host`; the reference and benchmark
  baseline for one release, and the fallback with x64 off): a chunk of
  ``chunk_size`` pairs is materialized on the host run by run (``np.repeat``),
  same-route pairs dropped, padded to a fixed length and screened by one
  program that gathers boundary states from the option table on the device.
* Both screen channel-major: the table is stored [C, N] per field, the loop over
  the C channels is a Python loop (C is static) and the channel reductions are
  min/max chains, so every operation runs on contiguous vectors (SIMD-friendly
  on CPU; a vmap over channels inside a vmap over candidates would make C = 2-3
  the minor axis and ran ~5x slower).
* :func:`screen_transitions` writes the chunks into preallocated output columns
  (no final concatenation copy); with ``feasible_only`` only the kept rows are
  stored. The output itself takes 49 bytes per row (float64).
* Sharding: the candidate axis of every chunk is split over all local devices
  with a 1-D :class:`jax.sharding.Mesh` and ``NamedSharding(mesh, P("cand"))``;
  the option table is replicated. On CPU, try it with
  ``XLA_FLAGS=--xla_force_host_platform_device_count=4``.
* Multi-host: start every process with ``jax.distributed.initialize()`` (see the
  JAX "multi-process" guide); ``screen_transitions`` then gives chunk k to
  process ``k % jax.process_count()`` (override with ``process_index`` /
  ``process_count``), each process screens its chunks on its own local devices
  and returns its part; concatenate the parts (e.g. with
  ``jax.experimental.multihost_utils.process_allgather`` or through files).
  No cluster code lives here.
* Precision follows the option table: float64 tables (``jax_enable_x64``) are
  screened in float64, float32 tables in float32 (T is formed in float64 first,
  then cast: on the device by the fused path, on the host with x64 off).

Units: radians, seconds.
"""

from __future__ import annotations

import mmap
from collections.abc import Iterator
from typing import NamedTuple

import jax
import numpy as np
from jax.sharding import Mesh

from jaxspline.engine.options import RouteOptions, validate_options
from jaxspline.engine.screen_models import validate_model
from jaxspline.kernels._batch import ragged_positions
from jaxspline.kernels._validate import check_positive

#: Scores a top-k screen can rank successors by.
_TOP_K_BY = ("margin", "value", "density")

__all__ = [
    "best_per_source",
    "Transitions",
    "screen_chunks",
    "screen_transitions",
    "screen_pairs",
]


class Transitions(NamedTuple):
    """Screened candidate transitions (struct of numpy arrays, M candidates).

    The columns ``margin``, ``effort`` and ``t_min`` depend on the maneuver model
    (:mod:`jaxspline.engine.screen_models`); with either model a candidate with
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


def _mesh():
    devs = jax.local_devices()
    return Mesh(np.array(devs), ("cand",))


class _Runs(NamedTuple):
    """Candidate runs: the ``scan_ok`` options sorted by ``(t_start, index)``; source
    position k's destinations are the sorted positions ``lo[k] .. lo[k] + counts[k] - 1``
    (``t_end[src] < t_start[dst] <= t_end[src] + max_gap``)."""

    order: np.ndarray
    lo: np.ndarray
    counts: np.ndarray


def _runs(options: RouteOptions, max_gap) -> _Runs:
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
    return _Runs(order, lo, np.maximum(hi - lo, 0).astype(np.int64))


# ----------------------------------------------------------------------------
# public entry points
# ----------------------------------------------------------------------------


def _empty(dtype) -> Transitions:
    f = np.zeros(0, np.dtype(dtype))
    i = np.zeros(0, np.int64)
    return Transitions(i, i, f, np.zeros(0, bool), f, f, f, 0)


class _Stream(NamedTuple):
    """A screen in progress: candidate slots, compute dtype, sink kind and the chunks."""

    total: int
    dtype: object
    lazy: bool
    chunks: Iterator[Transitions]


def _stream(
    options, model, max_gap, chunk_size, progress, feasible_only, top_k, pi, pc, top_k_by="margin"
) -> _Stream:
    """Validate the arguments eagerly and start the screen's chunk generator."""
    validate_options(options)
    validate_model(model, options)
    check_positive("chunk_size", chunk_size)
    if max_gap is not None:
        check_positive("max_gap", max_gap)
    if top_k is not None and not (isinstance(top_k, int | np.integer) and top_k >= 1):
        raise ValueError(f"top_k must be a positive int or None, got {top_k!r}")
    if top_k_by not in _TOP_K_BY:
        raise ValueError(f"top_k_by must be one of {_TOP_K_BY}, got {top_k_by!r}")
    chunk_size = int(chunk_size)
    pi = jax.process_index() if pi is None else int(pi)
    pc = jax.process_count() if pc is None else int(pc)
    if not (pc >= 1 and 0 <= pi < pc):
        raise ValueError(f"process_index must be in [0, process_count), got {pi}, {pc}")
    feasible_only = feasible_only or top_k is not None
    args = (options, model, max_gap, chunk_size, progress, feasible_only, pi, pc)
    if jax.dtypes.canonicalize_dtype(np.float64) == np.float64:  # x64 on (also in a context)
        from jaxspline.engine.screen_fused import fused_chunks

        total, dtype, chunks = fused_chunks(*args, top_k=top_k, top_k_by=top_k_by)
        return _Stream(total, dtype, top_k is None, chunks)
    from jaxspline.engine.screen_host import host_chunks

    total, dtype, order, chunks = host_chunks(*args)  # T needs float64 on the device
    if top_k is not None:
        rank = np.empty(len(options.t_start), np.int64)  # sources in t_start order, as fused
        rank[order] = np.arange(order.size)
        parts = ((rank[c.src], c[:-1], c.n_screened) for c in chunks)
        chunks = _top_k_merge(parts, int(top_k), _top_k_score(options, top_k_by))
    return _Stream(total, dtype, False, chunks)


def _top_k_score(options, top_k_by: str):
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


def _top_k_merge(parts, k: int, score) -> Iterator[Transitions]:
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


def _collect(stream: _Stream, feasible_only: bool) -> Transitions:
    """All chunks of a stream in one Transitions (written into a :class:`_Sink`)."""
    if stream.total == 0:
        for _ in stream.chunks:  # runs the generator to its end (closes the bar)
            pass
        return _empty(stream.dtype)
    sink = _Sink(stream.total, stream.dtype, feasible_only, lazy=stream.lazy)
    n_screened = 0
    for chunk in stream.chunks:
        sink.add_rows(chunk[:-1])
        n_screened += chunk.n_screened
    return sink.result(n_screened)


def screen_chunks(
    options: RouteOptions,
    model,
    *,
    max_gap: float | None = None,
    chunk_size: int = 2**18,
    progress: bool = True,
    feasible_only: bool = True,
    top_k: int | None = None,
    process_index: int | None = None,
    process_count: int | None = None,
    top_k_by: str = "margin",
) -> Iterator[Transitions]:
    """Screen like :func:`screen_transitions`, yielding the result chunk by chunk.

    Each chunk is a :class:`Transitions` whose ``n_screened`` counts the candidates
    screened for it; the chunks come off the devices as they are screened (the next
    chunk is already dispatched while the caller handles one), so memory is one chunk.
    Concatenating the chunks (and summing ``n_screened``) gives exactly
    :func:`screen_transitions` with the same arguments.

    Order contract (streaming consumers rely on it): rows are grouped by source and
    the sources come in increasing ``(t_start, index)`` order, i.e. the stable
    argsort of ``t_start`` over the ``scan_ok`` options; within a source,
    destinations by ``(t_start, index)``. A source's rows may span consecutive
    chunks, and a chunk may hold no rows (its candidates all failed or were
    filtered). With ``top_k``, each source's merged best rows (by decreasing
    ``top_k_by`` score) are yielded exactly once, in one chunk, when the source is final; the last
    chunk may then carry rows with ``n_screened = 0``. With several processes, each
    yields its own chunks in this order.

    With x64 off the host-generated path runs (T needs float64 on the device): its
    chunks follow the same contract.

    Args:
      options: RouteOptions table (N options, C channels).
      model: AxisLimits (per channel) or :class:`jaxspline.engine.models.SlewTable`
        (rest to rest; needs ``options.end_los`` / ``start_los``), see
        :func:`screen_transitions`.
      max_gap: optional upper bound on T [s].
      chunk_size: candidates per compiled batch.
      progress: show a tqdm bar over candidates.
      feasible_only: yield only feasible rows (default True here).
      top_k: keep for every source only its ``top_k`` feasible successors of
        largest ``top_k_by`` score (implies ``feasible_only``).
      top_k_by: ``"margin"``, ``"value"`` or ``"density"``, see :func:`screen_transitions`.
      process_index: this process's index in the multi-host split of chunks (default
        ``jax.process_index()``).
      process_count: number of processes sharing the chunks (default ``jax.process_count()``).
    Returns:
      An iterator of Transitions chunks (arguments are checked before it is returned).
    Raises:
      ValueError: an argument (options, model, max_gap, chunk_size, top_k,
        process_index) is invalid; names it and its value.
    """
    stream = _stream(
        options, model, max_gap, chunk_size, progress, feasible_only, top_k,
        process_index, process_count, top_k_by,
    )  # fmt: skip
    return stream.chunks


def screen_transitions(
    options: RouteOptions,
    model,
    *,
    max_gap: float | None = None,
    chunk_size: int = 2**18,
    progress: bool = True,
    feasible_only: bool = False,
    process_index: int | None = None,
    process_count: int | None = None,
    top_k: int | None = None,
    top_k_by: str = "margin",
) -> Transitions:
    """Screen every candidate transition between options of different routes.

    Candidates are all pairs (i, j) with ``route[i] != route[j]``, ``scan_ok``
    on both, and ``0 < T = t_start[j] - t_end[i]`` (``<= max_gap`` [s] if
    given). With AxisLimits, each is screened per channel at its exact T with the
    reach kernels (SPEC section 1: envelopes F_hi/F_lo, Theorem 6 pair set; the
    dual least peak acceleration of seed retarget-scan eq. 13) and reduced over
    channels; with a SlewTable, by the tabulated rest-to-rest time through the
    angle between ``end_los[i]`` and ``start_los[j]`` (SPEC section 2).

    Args:
      options: RouteOptions table (N options, C channels).
      model: the maneuver model (:mod:`jaxspline.engine.screen_models`):
        AxisLimits with ``rate`` [rad/s] and ``accel`` [rad/s^2], scalars or
        arrays of shape [C] (``jerk`` is ignored: the model of SPEC section 1 has
        none), or a :class:`jaxspline.engine.models.SlewTable` (then
        ``options.end_los`` and ``start_los`` [N, 3] are required).
      max_gap: optional upper bound on T [s]; bounds the work to the pairs that
        lie within ``max_gap`` of each other in time.
      chunk_size: candidates per compiled batch (memory ~ 150 bytes each; the
        fused path rounds it to whole rows of up to 256 slots).
      progress: show a tqdm bar over candidates.
      feasible_only: keep only feasible candidates in the result (compacted on
        the device; saves memory when most candidates fail).
      process_index: this process's index in the multi-host split of chunks (default
        ``jax.process_index()``).
      process_count: number of processes sharing the chunks (default ``jax.process_count()``).
      top_k: keep for every source only its ``top_k`` feasible successors of
        largest ``top_k_by`` score (implies ``feasible_only``). Selected per row of up to 256
        destinations on the device and merged per source on the host, so memory
        is O(rows x top_k) instead of O(candidates). With several processes, each
        returns the best of its own chunks: merge the parts with
        :func:`best_per_source`.
      top_k_by: the score ``top_k`` ranks feasible successors i -> j by:
        ``"margin"`` (the reach margin: the most robust transitions), ``"value"``
        (``value[j]``) or ``"density"`` (``value[j] / (t_end[j] - t_end[i])``, the
        value per second of timeline the successor takes, transfer and imaging:
        the score of :func:`~jaxspline.engine.sequence.greedy`, and the one to use
        when a sequencer consumes the top-k rows; > 0 for every feasible pair).
        Ties go to the earlier destination in ``(t_start, index)`` order.

    Returns:
      Transitions (numpy arrays), in the order (source by t_start, then
      destination by t_start); with ``top_k``, per source by decreasing score.
      The collection of :func:`screen_chunks` with the same arguments.
    Raises:
      ValueError: an argument is invalid; names it and its value.

    Pairs are generated inside the compiled program from the time-sorted option
    table and per-source run offsets, and only the kept rows (all different-route
    pairs, or the feasible ones with ``feasible_only``) are compacted on the device
    and returned. With x64 off, the host-generated path runs instead (same results).
    """
    stream = _stream(
        options, model, max_gap, chunk_size, progress, feasible_only, top_k,
        process_index, process_count, top_k_by,
    )  # fmt: skip
    return _collect(stream, feasible_only or top_k is not None)


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


def _screen_transitions_host(
    options, model, max_gap, chunk_size, progress, feasible_only, pi, pc
) -> Transitions:
    """The host-generated path collected (:mod:`jaxspline.engine.screen_host`).

    Kept private for one release as the reference and benchmark baseline of the fused
    path, and as the fallback when x64 is off (the fused path forms T in float64 on
    the device). Arguments as :func:`screen_transitions`, already validated.
    """
    from jaxspline.engine.screen_host import host_chunks

    total, dtype, _, chunks = host_chunks(
        options, model, max_gap, chunk_size, progress, feasible_only, pi, pc
    )
    return _collect(_Stream(total, dtype, False, chunks), feasible_only)


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
            return _empty(self.cols_dtype)._replace(n_screened=n_screened)
        cols = [np.concatenate(col) for col in zip(*self.parts, strict=True)]
        return Transitions(*cols, n_screened=n_screened)


def screen_pairs(options: RouteOptions, model, src, dst, *, chunk_size: int = 2**18) -> Transitions:
    """Screen given option pairs src[m] -> dst[m] (no route / scan_ok / T filter).

    Same kernels and outputs as :func:`screen_transitions`; a pair with
    ``T <= 0`` is infeasible (margin -inf, effort +inf).

    Args:
      options: RouteOptions of N options and C channels.
      model: AxisLimits per channel or a SlewTable (rest to rest), as in
        :func:`screen_transitions`.
      src: int [M], source option indices.
      dst: int [M], destination option indices.
      chunk_size: pairs per compiled call.
    Returns:
      Transitions of the M pairs.
    Raises:
      ValueError: src and dst differ in length, or invalid options / model.
    """
    from jaxspline.engine.screen_host import _Screener

    validate_options(options)
    validate_model(model, options)
    src = np.asarray(src, np.int64).reshape(-1)
    dst = np.asarray(dst, np.int64).reshape(-1)
    n = np.shape(options.t_start)[0]
    for name, a in (("src", src), ("dst", dst)):
        if a.size and (a.min() < 0 or a.max() >= n):
            raise ValueError(
                f"{name} must index options (0..{n - 1}), got min {a.min()} max {a.max()}"
            )
    if src.size != dst.size:
        raise ValueError(f"src and dst must have the same length, got {src.size} and {dst.size}")
    screener = _Screener(options, model)
    if src.size == 0:
        return _empty(screener.dtype)
    parts = []
    for g0 in range(0, src.size, chunk_size):
        s, d = src[g0 : g0 + chunk_size], dst[g0 : g0 + chunk_size]
        size = screener.padded_size(s.size, chunk_size)
        T, feas, margin, effort, tmin = screener.screen(s, d, size)
        parts.append((s, d, T, feas, margin, effort, tmin))
    cols = [np.concatenate(col) for col in zip(*parts, strict=True)]
    return Transitions(*cols, n_screened=int(src.size))
