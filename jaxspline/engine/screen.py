"""Bulk screening of route-to-route transitions (SPEC section 4).

A *candidate transition* is option i -> option j of two different routes with
``T = t_start[j] - t_end[i] > 0`` (and ``T <= max_gap`` if given). For every
attitude channel c the spacecraft must move from ``(end_angle[i, c],
end_rate[i, c])`` to ``(start_angle[j, c], start_rate[j, c])`` in EXACTLY T
seconds under ``|f'| <= rate[c]``, ``|f''| <= accel[c]``; the per-channel
exact-T kernels of :mod:`jaxspline.kernels.reach` decide it (SPEC section 1; feasible
durations are not an interval, so ``T >= t_min`` is not enough).

Engine layout:

* Candidate runs: valid options (``scan_ok``) are sorted by ``t_start``; for
  each source i the admissible destinations form one contiguous run of that
  order (``t_end[i] < t_start[j] <= t_end[i] + max_gap``, found by
  ``searchsorted``). N^2 pairs are never held at once.
* Fused path (default; :mod:`jaxspline.engine.screen_fused`): each run is cut into
  rows of ``width`` slots (a power of two <= 256 chosen so padding stays <= 6 %),
  and the time-sorted option table plus the row table (source, first
  destination, count) go to the devices once. Chunk k is ``rows`` consecutive
  rows and costs one scalar argument: the screening program builds the slots'
  destination indices by broadcasting (no per-candidate search: XLA's CPU
  ``searchsorted`` ran at 2e7/s), applies the same-route exclusion, forms
  ``T = t_start[dst] - t_end[src]`` in float64 and cast to the table dtype
  (bit-identical to the host path), and runs the per-channel kernels. A second
  program compacts the kept rows (all different-route pairs, or the feasible
  ones with ``feasible_only``) to the front of the chunk, so only they reach the
  result. The two programs are separate on purpose: fused, XLA's CPU backend
  inlined the kernels into the compaction's gathers and recomputed them (0.3x).
* Host path (private, :func:`_screen_transitions_host`; the reference and
  benchmark baseline for one release, and the fallback with x64 off): a chunk of
  ``chunk_size`` pairs is materialized on the host run by run (``np.repeat``),
  same-route pairs dropped, padded to a fixed length and screened by
  :func:`_chunk_program`, which gathers boundary states from the option table on
  the device.
* Both screen channel-major: the table is stored [C, N] per field, the loop over
  the C channels is a Python loop (C is static) and the channel reductions are
  min/max chains, so every operation runs on contiguous vectors (SIMD-friendly
  on CPU; a vmap over channels inside a vmap over candidates would make C = 2-3
  the minor axis and ran ~5x slower).
* Results are written chunk by chunk into preallocated output columns (no final
  concatenation copy); with ``feasible_only`` only the kept rows are stored. The
  output itself takes 49 bytes per row (float64).
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

import functools
import mmap
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding
from jax.sharding import PartitionSpec as P

from jaxspline.engine.options import RouteOptions, options_dtype, validate_options
from jaxspline.kernels._batch import padded_size
from jaxspline.kernels._validate import check_positive
from jaxspline.kernels.limits import AxisLimits, validate_limits

__all__ = [
    "best_per_source",
    "Transitions",
    "screen_transitions",
    "screen_pairs",
]


class Transitions(NamedTuple):
    """Screened candidate transitions (struct of numpy arrays, M candidates).

    Attributes:
      src, dst: int64 [M], option indices (into the RouteOptions given) of the
        end option i and the start option j.
      T: [M] transfer duration t_start[j] - t_end[i] [s], > 0.
      feasible: bool [M], every channel can make the transfer in exactly T.
      margin: [M] reach margin [rad], min over channels of
        ``reach.reach_margin_kernel`` (>= 0 iff feasible, up to rounding).
      effort: [M] max over channels of d*_c / accel_c, where d*_c is the least
        acceleration bound that makes channel c feasible in T
        (``reach_durations.min_peak_accel_kernel``; SPEC section 1, dual problem,
        seed retarget-scan eq. 13): <= 1 iff feasible; +inf if the rate bound
        alone forbids it.
      t_min: [M] max over channels of the shortest transfer time [s]
        (``reach_durations.min_transfer_time_kernel``); a necessary bound only.
      n_screened: number of candidates screened by this call (this process).
    """

    src: np.ndarray
    dst: np.ndarray
    T: np.ndarray
    feasible: np.ndarray
    margin: np.ndarray
    effort: np.ndarray
    t_min: np.ndarray
    n_screened: int


# ----------------------------------------------------------------------------
# validation of the shared contract
# ----------------------------------------------------------------------------


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


def _channel_limits(limits: AxisLimits, c: int, dtype):
    limits = validate_limits(limits)
    if np.shape(limits.rate) not in ((), (c,)) or np.shape(limits.accel) not in ((), (c,)):
        raise ValueError(
            f"limits.rate/accel must be scalars or shape ({c},) (one per channel), got "
            f"{np.shape(limits.rate)} and {np.shape(limits.accel)}"
        )
    rate = np.broadcast_to(np.asarray(limits.rate, float), (c,))
    accel = np.broadcast_to(np.asarray(limits.accel, float), (c,))
    return jnp.asarray(rate, dtype), jnp.asarray(accel, dtype)


# ----------------------------------------------------------------------------
# per-channel kernels over candidate vectors and the compiled chunk program
# ----------------------------------------------------------------------------


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


@functools.lru_cache(maxsize=8)
def _chunk_program(reach):
    """jit program screening one chunk: (feasible, margin, effort, t_min), each [n].

    Channel-major layout: the option table arrives transposed ([C, N] per field),
    the loop over the C channels is a Python loop (C is static) and the reductions
    over channels are min/max chains, so every operation runs on contiguous [n]
    candidate vectors. A padded slot has T = 0 and comes out infeasible; callers
    drop padded slots anyway.
    """

    def run(end_angle, end_rate, start_angle, start_rate, rate, accel, src, dst, T):
        table = (end_angle, end_rate, start_angle, start_rate)
        return _all_channels(reach, table, src, dst, T, rate, accel)

    return jax.jit(run)


def _mesh():
    devs = jax.local_devices()
    return Mesh(np.array(devs), ("cand",))


class _Screener:
    """Holds the device copy of the option table and screens index chunks."""

    def __init__(self, options: RouteOptions, limits: AxisLimits):
        c = validate_options(options)
        self.dtype = options_dtype(options)
        self.mesh = _mesh()
        self.ndev = self.mesh.devices.size
        rep = NamedSharding(self.mesh, P())
        self.cand = NamedSharding(self.mesh, P("cand"))
        rate, accel = _channel_limits(limits, c, self.dtype)
        # channel-major [C, N]: each channel's column is one contiguous vector
        self.table = [
            jax.device_put(
                jnp.asarray(np.ascontiguousarray(np.asarray(getattr(options, f)).T), self.dtype),
                rep,
            )
            for f in ("end_angle", "end_rate", "start_angle", "start_rate")
        ]
        self.limits = [jax.device_put(rate, rep), jax.device_put(accel, rep)]
        self.t_start = np.asarray(options.t_start, np.float64)
        self.t_end = np.asarray(options.t_end, np.float64)
        self.program = _chunk_program(_reach())

    def padded_size(self, n: int, chunk_size: int) -> int:
        """Fixed length for a chunk of n: a power of two (>= 1024) <= chunk_size, multiple of ndev.

        Few distinct lengths means few compilations.
        """
        return padded_size(n, chunk_size, self.ndev)

    def dispatch(self, src: np.ndarray, dst: np.ndarray, size: int, T: np.ndarray | None = None):
        """Start screening pairs (len <= size, padded to ``size``); returns a pending handle.

        ``T`` (float64, optional) is ``t_start[dst] - t_end[src]`` if the caller has it.
        JAX dispatch is asynchronous: the host prepares the next chunk while the
        devices screen this one. ``collect`` waits for the result.
        """
        n = src.size
        if T is None:
            T = self.t_start[dst] - self.t_end[src]
        s = np.zeros(size, np.int32)
        d = np.zeros(size, np.int32)
        t = np.zeros(size, np.dtype(self.dtype))
        s[:n], d[:n], t[:n] = src, dst, T
        args = [jax.device_put(a, self.cand) for a in (s, d, t)]
        return src, dst, t[:n], self.program(*self.table, *self.limits, *args)

    @staticmethod
    def collect(pending):
        """(src, dst, T, feasible, margin, effort, t_min) as numpy arrays of a dispatched chunk."""
        src, dst, T, out = pending
        n = src.size
        feas, margin, effort, tmin = (np.asarray(o)[:n] for o in out)
        return src, dst, T, feas, margin, effort, tmin

    def screen(self, src: np.ndarray, dst: np.ndarray, size: int):
        """Screen pairs synchronously: (T, feasible, margin, effort, t_min) numpy arrays."""
        return self.collect(self.dispatch(src, dst, size))[2:]


# ----------------------------------------------------------------------------
# public entry points
# ----------------------------------------------------------------------------


def _empty(dtype) -> Transitions:
    f = np.zeros(0, np.dtype(dtype))
    i = np.zeros(0, np.int64)
    return Transitions(i, i, f, np.zeros(0, bool), f, f, f, 0)


def screen_transitions(
    options: RouteOptions,
    limits: AxisLimits,
    *,
    max_gap: float | None = None,
    chunk_size: int = 2**18,
    progress: bool = True,
    feasible_only: bool = False,
    process_index: int | None = None,
    process_count: int | None = None,
    top_k: int | None = None,
) -> Transitions:
    """Screen every candidate transition between options of different routes.

    Candidates are all pairs (i, j) with ``route[i] != route[j]``, ``scan_ok``
    on both, and ``0 < T = t_start[j] - t_end[i]`` (``<= max_gap`` [s] if
    given). Each is screened per channel at its exact T with the reach kernels
    (SPEC section 1: envelopes F_hi/F_lo, Theorem 6 pair set; the dual least
    peak acceleration of seed retarget-scan eq. 13) and reduced over channels.

    Args:
      options: RouteOptions table (N options, C channels).
      limits: AxisLimits with ``rate`` [rad/s] and ``accel`` [rad/s^2], scalars
        or arrays of shape [C] (one per channel). ``jerk`` is ignored (the model
        of SPEC section 1 has none).
      max_gap: optional upper bound on T [s]; bounds the work to the pairs that
        lie within ``max_gap`` of each other in time.
      chunk_size: candidates per compiled batch (memory ~ 150 bytes each; the
        fused path rounds it to whole rows of up to 256 slots).
      progress: show a tqdm bar over candidates.
      feasible_only: keep only feasible candidates in the result (compacted on
        the device; saves memory when most candidates fail).
      process_index, process_count: multi-host split of chunks (defaults:
        ``jax.process_index()``, ``jax.process_count()``).
      top_k: keep for every source only its ``top_k`` feasible successors of
        largest margin (implies ``feasible_only``). Selected per row of up to 256
        destinations on the device and merged per source on the host, so memory
        is O(rows x top_k) instead of O(candidates). With several processes, each
        returns the best of its own chunks: merge the parts with
        :func:`best_per_source`.

    Returns:
      Transitions (numpy arrays), in the order (source by t_start, then
      destination by t_start); with ``top_k``, per source by decreasing margin.

    Pairs are generated inside the compiled program from the time-sorted option
    table and per-source run offsets, and only the kept rows (all different-route
    pairs, or the feasible ones with ``feasible_only``) are compacted on the device
    and returned. With x64 off, the host-generated path runs instead (same results).
    """
    c = validate_options(options)
    validate_limits(limits)
    check_positive("chunk_size", chunk_size)
    if max_gap is not None:
        check_positive("max_gap", max_gap)
    if top_k is not None and not (isinstance(top_k, int | np.integer) and top_k >= 1):
        raise ValueError(f"top_k must be a positive int or None, got {top_k!r}")
    chunk_size = int(chunk_size)
    pi = jax.process_index() if process_index is None else int(process_index)
    pc = jax.process_count() if process_count is None else int(process_count)
    if not (pc >= 1 and 0 <= pi < pc):
        raise ValueError(f"process_index must be in [0, process_count), got {pi}, {pc}")
    del c
    feasible_only = feasible_only or top_k is not None
    args = (options, limits, max_gap, chunk_size, progress, feasible_only, pi, pc)
    if jax.dtypes.canonicalize_dtype(np.float64) == np.float64:  # x64 on (also in a context)
        from jaxspline.engine.screen_fused import screen_transitions_fused

        return screen_transitions_fused(*args, top_k=top_k)
    tr = _screen_transitions_host(*args)  # T needs float64 on the device
    if top_k is None:
        return tr
    valid = np.flatnonzero(np.asarray(options.scan_ok, bool))
    order = valid[np.argsort(np.asarray(options.t_start)[valid], kind="stable")]
    rank = np.empty(len(options.t_start), np.int64)  # sources in t_start order, as fused
    rank[order] = np.arange(order.size)
    keep = best_per_source(rank[tr.src], tr.margin, int(top_k))
    return Transitions(*(x[keep] for x in tr[:-1]), n_screened=tr.n_screened)


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
    rank = np.arange(s.size) - np.repeat(first, np.diff(np.r_[first, s.size]))
    return order[rank < k]


def _screen_transitions_host(
    options, limits, max_gap, chunk_size, progress, feasible_only, pi, pc
) -> Transitions:
    """The host-generated path (pairs built with ``np.repeat`` per chunk, every row returned).

    Kept private for one release as the reference and benchmark baseline of the fused
    path, and as the fallback when x64 is off (the fused path forms T in float64 on
    the device). Arguments as :func:`screen_transitions`, already validated.
    """
    screener = _Screener(options, limits)

    route = np.asarray(options.route)
    valid = np.flatnonzero(np.asarray(options.scan_ok, bool))
    order = valid[np.argsort(screener.t_start[valid], kind="stable")]
    ts_sorted = screener.t_start[order]
    te_src = screener.t_end[order]
    lo = np.searchsorted(ts_sorted, te_src, side="right")
    if max_gap is None:
        hi = np.full_like(lo, order.size)
    else:
        hi = np.searchsorted(ts_sorted, te_src + float(max_gap), side="right")
    counts = np.maximum(hi - lo, 0).astype(np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)])
    total = int(starts[-1])
    if total == 0:
        return _empty(screener.dtype)

    route_sorted = np.asarray(route)[order]
    base = lo - starts[:-1]  # destination position of candidate g of source k: base[k] + g
    sink = _Sink(total, screener.dtype, feasible_only)
    n_screened = 0
    pending = None
    from tqdm.auto import tqdm

    bar = tqdm(total=total, unit="cand", disable=not progress, desc="screen")
    for k, g0 in enumerate(range(0, total, chunk_size)):
        g1 = min(g0 + chunk_size, total)
        if k % pc != pi:
            bar.update(g1 - g0)
            continue
        # sources k0..k1-1 own the candidates g0..g1-1 (runs laid end to end)
        k0 = int(np.searchsorted(starts, g0, side="right")) - 1
        k1 = int(np.searchsorted(starts, g1, side="left"))
        cnt = np.minimum(starts[k0 + 1 : k1 + 1], g1) - np.maximum(starts[k0:k1], g0)
        d_pos = np.repeat(base[k0:k1], cnt) + np.arange(g0, g1, dtype=np.int64)
        keep = np.repeat(route_sorted[k0:k1], cnt) != route_sorted[d_pos]
        src = np.repeat(order[k0:k1], cnt)
        T = ts_sorted[d_pos] - np.repeat(te_src[k0:k1], cnt)
        dst = order[d_pos]
        if not keep.all():
            src, dst, T = src[keep], dst[keep], T[keep]
        if src.size:
            size = screener.padded_size(g1 - g0, chunk_size)
            nxt = screener.dispatch(src, dst, size, T)  # runs while the previous chunk is collected
            n_screened += src.size
            if pending is not None:
                sink.add(screener.collect(pending))
            pending = nxt
        bar.update(g1 - g0)
    if pending is not None:
        sink.add(screener.collect(pending))
    bar.close()
    return sink.result(n_screened)


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

    def add(self, cols):
        """Add a screened chunk (every row; only the feasible ones are kept if asked)."""
        if self.feasible_only:
            self.parts.append(tuple(a[cols[3]] for a in cols))
            return
        self.add_rows(cols)

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


def screen_pairs(
    options: RouteOptions, limits: AxisLimits, src, dst, *, chunk_size: int = 2**18
) -> Transitions:
    """Screen given option pairs src[m] -> dst[m] (no route / scan_ok / T filter).

    Same kernels and outputs as :func:`screen_transitions`; a pair with
    ``T <= 0`` is infeasible (margin -inf, effort +inf).

    Args:
      options: RouteOptions of N options and C channels.
      limits: AxisLimits per channel.
      src: int [M], source option indices.
      dst: int [M], destination option indices.
      chunk_size: pairs per compiled call.
    Returns:
      Transitions of the M pairs.
    Raises:
      ValueError: src and dst differ in length, or invalid options / limits.
    """
    validate_options(options)
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
    screener = _Screener(options, limits)
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


def __getattr__(name: str):
    """``screen.screen_sequences`` lives in :mod:`jaxspline.engine.screen_sequences`.

    Imported on first access: that module builds on this one.
    """
    if name == "screen_sequences":
        from jaxspline.engine.screen_sequences import screen_sequences

        return screen_sequences
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
