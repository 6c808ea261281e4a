"""Bulk screening of route-to-route transitions (SPEC section 4).

A *candidate transition* is option i -> option j of two different routes with
``T = t_start[j] - t_end[i] > 0`` (and ``T <= max_gap`` if given). What the
transfer must achieve in T is the maneuver model, the engine's second argument
(:mod:`jaxspline.screen.pair_models`): with AxisLimits, for every attitude
channel c the spacecraft must move from ``(end_angle[i, c], end_rate[i, c])`` to
``(start_angle[j, c], start_rate[j, c])`` in EXACTLY T seconds under ``|f'| <=
rate[c]``, ``|f''| <= accel[c]``; the per-channel exact-T kernels of
:mod:`jaxspline.kernels.reach` decide it (SPEC section 1; feasible durations are
not an interval, so ``T >= t_min`` is not enough). With a
:class:`jaxspline.screen.slew_table.SlewTable`, a rest-to-rest slew through the angle
between ``end_los[i]`` and ``start_los[j]`` (settle and gap margin included) must
fit in T.

:func:`screen_chunks` yields the result chunk by chunk as it comes off the devices
(order contract in its docstring); :func:`screen_transitions` collects it.

Engine layout:

* Candidate runs: valid options (``scan_ok``) are sorted by ``t_start``; for
  each source i the admissible destinations form one contiguous run of that
  order (``t_end[i] < t_start[j] <= t_end[i] + max_gap``, found by
  ``searchsorted``). N^2 pairs are never held at once.
* Fused path (default; :mod:`jaxspline.screen.fused`): each run is cut into
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
* Host path (:mod:`jaxspline.screen.host`; the reference and benchmark
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

from collections.abc import Iterator

import jax
import numpy as np

from jaxspline.kernels.validate import check_positive
from jaxspline.screen.fused import fused_chunks
from jaxspline.screen.host import Screener, host_chunks
from jaxspline.screen.options import RouteOptions, validate_options
from jaxspline.screen.pair_models import validate_model
from jaxspline.screen.transitions import (
    Stream,
    Transitions,
    collect,
    default_chunk_size,
    empty_transitions,
    top_k_merge,
    top_k_score,
)

#: Scores a top-k screen can rank successors by.
_TOP_K_BY = ("margin", "value", "density")

__all__ = ["screen_chunks", "screen_transitions", "screen_pairs"]


def _stream(
    options, model, max_gap, chunk_size, progress, feasible_only, top_k, pi, pc, top_k_by="margin"
) -> Stream:
    """Validate the arguments eagerly and start the screen's chunk generator."""
    validate_options(options)
    validate_model(model, options)
    chunk_size = default_chunk_size(chunk_size)
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
        total, dtype, chunks = fused_chunks(*args, top_k=top_k, top_k_by=top_k_by)
        return Stream(total, dtype, top_k is None, chunks)
    total, dtype, order, chunks = host_chunks(*args)  # T needs float64 on the device
    if top_k is not None:
        rank = np.empty(len(options.t_start), np.int64)  # sources in t_start order, as fused
        rank[order] = np.arange(order.size)
        parts = ((rank[c.src], c[:-1], c.n_screened) for c in chunks)
        chunks = top_k_merge(parts, int(top_k), top_k_score(options, top_k_by))
    return Stream(total, dtype, False, chunks)


def screen_chunks(
    options: RouteOptions,
    model,
    *,
    max_gap: float | None = None,
    chunk_size: int | None = None,
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
      model: AxisLimits (per channel) or :class:`jaxspline.screen.slew_table.SlewTable`
        (rest to rest; needs ``options.end_los`` / ``start_los``), see
        :func:`screen_transitions`.
      max_gap: optional upper bound on T [s].
      chunk_size: candidates per compiled batch (None: :func:`default_chunk_size`, by
        the local devices' platform).
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
    chunk_size: int | None = None,
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
      model: the maneuver model (:mod:`jaxspline.screen.pair_models`):
        AxisLimits with ``rate`` [rad/s] and ``accel`` [rad/s^2], scalars or
        arrays of shape [C] (``jerk`` is ignored: the model of SPEC section 1 has
        none), or a :class:`jaxspline.screen.slew_table.SlewTable` (then
        ``options.end_los`` and ``start_los`` [N, 3] are required).
      max_gap: optional upper bound on T [s]; bounds the work to the pairs that
        lie within ``max_gap`` of each other in time.
      chunk_size: candidates per compiled batch (memory ~ 150 bytes each; the
        fused path rounds it to whole rows of up to 256 slots). None:
        :func:`default_chunk_size`, 2**18 on CPU and 2**22 on an accelerator.
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
        the score of :func:`~jaxspline.sequences.sequencer.greedy_chain`, and the one to use
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
    return collect(stream, feasible_only or top_k is not None)


def _screen_transitions_host(
    options, model, max_gap, chunk_size, progress, feasible_only, pi, pc
) -> Transitions:
    """The host-generated path collected (:mod:`jaxspline.screen.host`).

    Kept private for one release as the reference and benchmark baseline of the fused
    path, and as the fallback when x64 is off (the fused path forms T in float64 on
    the device). Arguments as :func:`screen_transitions`, already validated.
    """
    total, dtype, _, chunks = host_chunks(
        options, model, max_gap, chunk_size, progress, feasible_only, pi, pc
    )
    return collect(Stream(total, dtype, False, chunks), feasible_only)


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
    screener = Screener(options, model)
    if src.size == 0:
        return empty_transitions(screener.dtype)
    parts = []
    for g0 in range(0, src.size, chunk_size):
        s, d = src[g0 : g0 + chunk_size], dst[g0 : g0 + chunk_size]
        size = screener.padded_size(s.size, chunk_size)
        T, feas, margin, effort, tmin = screener.screen(s, d, size)
        parts.append((s, d, T, feas, margin, effort, tmin))
    cols = [np.concatenate(col) for col in zip(*parts, strict=True)]
    return Transitions(*cols, n_screened=int(src.size))
