"""The fused screening path: pairs generated and rows compacted on the device.

:func:`jaxspline.screen.pairs.screen_chunks` (and so ``screen_transitions``) runs
:func:`fused_chunks` when x64 is on (see that module's docstring for the layout).
Each source's run of destinations is cut into rows of ``width`` slots; the
time-sorted option table goes to the devices once, and chunk k costs its ``rows``
rows of the row table. One program screens a chunk with the model's pair function
(the same one as the host path's ``host._chunk_program``,
:mod:`jaxspline.screen.pair_models`), a second compacts the kept rows to the
front. :func:`fused_chunks` yields the compacted chunks one by one, with one chunk
in flight on the devices.

Units: radians, seconds.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import NamedSharding
from jax.sharding import PartitionSpec as P

from jaxspline.kernels.batch import pad_last, padded_size, ragged_positions, round_up
from jaxspline.screen.options import options_dtype
from jaxspline.screen.pair_models import model_arrays
from jaxspline.screen.transitions import (
    Stream,
    Transitions,
    candidate_runs,
    collect,
    device_mesh,
    top_k_merge,
    top_k_score,
)

__all__ = ["fused_chunks", "release_programs", "screen_transitions_fused"]

#: Row widths tried for the [rows, width] candidate layout, widest first.
_WIDTHS = (256, 128, 64, 32, 16, 8, 4, 2, 1)
#: Largest k selected per row by argmax rounds (unrolled); above it a stable sort.
_EXTRACT_MAX_K = 32
#: Smallest padded option table (~1 MB for 3 channels): small tables share programs.
_MIN_TABLE = 1 << 14
#: Fewest rows of a single-chunk screen (tiny screens share one program shape).
_MIN_ROWS = 1 << 6
#: Compiled chunk programs kept per kind (shapes x models; a large screen drops them).
_PROGRAMS_KEPT = 64


def release_programs(n_options: int | None = None) -> None:
    """Drop the compiled chunk programs (:func:`fused_chunks` compiles them again when
    called anew): the executables of a large screen take hundreds of MB, which a caller
    that screens once (the planner) does not need afterwards.

    Args:
      n_options: the options of the screen just done; a screen of at most
        ``_MIN_TABLE`` keeps the programs: every such screen pads its table to that one
        size, so the next small screen (another plan in the same process) runs them
        again, and their executables are small. None drops them whatever the size.
    """
    if n_options is not None and n_options <= _MIN_TABLE:
        return
    for program in (_fused_program, _compact_program, _topk_program):
        program.cache_clear()


def _row_width(counts: np.ndarray, chunk_size: int) -> int:
    """Widest row (power of two <= 256 and <= chunk_size) padding the runs by <= 6 %.

    A source's run of ``counts[k]`` destinations occupies ``ceil(counts[k] / w)``
    rows of ``w`` slots; wide rows make the per-candidate index arithmetic a
    broadcast, narrow rows waste fewer slots on short runs.
    """
    total = int(counts.sum())
    fits = [w for w in _WIDTHS if w <= chunk_size]
    for w in fits:
        if int((-(-counts // w)).sum()) * w <= 1.06 * total:
            return w
    return fits[-1]


@functools.lru_cache(maxsize=_PROGRAMS_KEPT)
def _fused_program(pair, rows: int, width: int, mesh, dtype):
    """jit program screening one chunk: ``rows`` rows of the row table.

    Row r is source position ``row_k[r]`` (time-sorted valid options) and the
    destinations ``row_d[r] + 0 .. row_n[r] - 1`` of the same order. Per slot: the
    same-route exclusion, ``T = t_start[dst] - t_end[src]`` in float64 (then cast to
    ``dtype``, as the host path does) and the model's pair function ``pair``
    (:mod:`jaxspline.screen.pair_models`; per-channel kernels with their channel
    reductions, or the rest-to-rest slew table). The source is constant along a
    row, so its state is gathered once per row. Returns ``(keep, T, feasible,
    margin, effort, t_min)``, each [rows, width]; ``keep`` marks live
    different-route slots (a dropped slot has T = 0 and is infeasible).
    """
    cand = NamedSharding(mesh, P("cand"))

    def run(tab, params, row_k, row_d, row_n):
        fields, te, ts, route, _ = tab
        nv = te.shape[0]
        k = jax.lax.with_sharding_constraint(row_k, cand)
        d0, n = row_d, row_n
        j = jnp.arange(width, dtype=d0.dtype)
        d = jnp.minimum(d0[:, None] + j, nv - 1)  # [rows, width]; padded slots clamped
        kb = k[:, None]
        keep = (j < n[:, None]) & (route[kb] != route[d])
        T = jnp.where(keep, ts[d] - te[kb], 0.0).astype(dtype)
        return (keep, T, *pair(fields, params, kb, d, T))

    return jax.jit(run)


def _prefix_count(sel, block: int = 16):
    """Inclusive prefix count of a bool vector (int32), like ``jnp.cumsum(sel)``.

    XLA's CPU cumsum (a reduce-window) ran at ~3e7 elements/s; here the in-block
    prefix of ``block`` elements is a small float32 matmul with a triangular matrix
    (exact: counts <= block) and only the block totals go through ``cumsum``, ~3x
    faster overall.
    """
    s = sel.size
    if s % block:
        return jnp.cumsum(sel, dtype=jnp.int32)
    x = sel.reshape(-1, block).astype(jnp.float32)
    inner = (x @ jnp.triu(jnp.ones((block, block), jnp.float32))).astype(jnp.int32)
    tot = inner[:, -1]
    return ((jnp.cumsum(tot) - tot)[:, None] + inner).reshape(-1)


@functools.lru_cache(maxsize=_PROGRAMS_KEPT)
def _compact_program(rows: int, width: int, feasible_only: bool):
    """jit program moving the kept slots of one screened chunk to the front (order kept).

    A separate program on purpose: fused into the screening program, XLA's CPU
    backend inlines the elementwise kernels into every consumer of the compaction
    (and recomputes them there); as its own program it reads materialized columns.
    ``slot[q]``, the flat index of the q-th kept slot, comes from a prefix sum and
    one int32 scatter; each column is then one gather, and ``src``/``dst`` are
    rebuilt from the slot's row. Kept = feasible (``feasible_only``) or ``keep``.
    Returns ``(n_pairs, count, src, dst, T, feasible, margin, effort, t_min)``;
    entries past ``count`` are filler.
    """

    def run(order, row_k, row_d, keep, T, feasible, margin, effort, tmin):
        sel = (feasible if feasible_only else keep).reshape(-1)
        s = sel.size
        pos = _prefix_count(sel) - 1
        slot = (
            jnp.zeros(s, jnp.int32)
            .at[jnp.where(sel, pos, s)]
            .set(jnp.arange(s, dtype=jnp.int32), mode="drop", unique_indices=True)
        )
        row, col = slot // width, slot % width
        k = row_k[row]
        d = row_d[row] + col
        nv = order.shape[0]
        src, dst = order[k], order[jnp.minimum(d, nv - 1)]
        cols = [x.reshape(-1)[slot] for x in (T, feasible, margin, effort, tmin)]
        return keep.sum(dtype=jnp.int32), pos[-1] + 1, src, dst, *cols

    return jax.jit(run)


def _row_top_k(score, k: int):
    """The ``k`` largest scores of every row: columns [rows, min(k, width)] and whether
    each pick is real (its score > -inf). Ties go to the lowest column.

    ``k <= _EXTRACT_MAX_K``: ``k`` rounds of a row-wise ``argmax`` (first maximum),
    each removing its pick, so picks come in decreasing order (XLA's CPU ``top_k``
    sorts and ran 2-3x slower on rows of 64-256 slots, and breaks exact ties in no
    fixed order); once a row has no score above -inf left, ``argmax`` may return a
    column picked before, so such picks are not real. Larger ``k``: a stable sort.
    ``k >= width``: every column, in column order.
    """
    rows, width = score.shape
    col_ids = jnp.arange(width, dtype=jnp.int32)
    if k >= width:
        return jnp.broadcast_to(col_ids, (rows, width)), score > -jnp.inf
    if k > _EXTRACT_MAX_K:
        c = jnp.argsort(-score, axis=1, stable=True)[:, :k].astype(jnp.int32)
        return c, jnp.take_along_axis(score, c, axis=1) > -jnp.inf
    cols, real = [], []
    for _ in range(k):
        c = jnp.argmax(score, axis=1).astype(jnp.int32)
        v = jnp.take_along_axis(score, c[:, None], axis=1)[:, 0]
        cols.append(c)
        real.append(v > -jnp.inf)
        score = jnp.where(col_ids[None, :] == c[:, None], -jnp.inf, score)
    return jnp.stack(cols, axis=1), jnp.stack(real, axis=1)


@functools.lru_cache(maxsize=_PROGRAMS_KEPT)
def _topk_program(rows: int, width: int, k: int, by: str):
    """jit program keeping, per row of one screened chunk, its ``k`` feasible slots of
    largest score ``by`` (margin, destination value or value density, see
    ``screen_transitions``; :func:`_row_top_k`; infeasible slots score -inf).

    Returns ``(n_pairs, src position, dst, T, feasible, margin, effort, t_min)``, each
    [rows, k] except the scalar count; ``src position`` is the source's rank in the
    time-sorted table (the caller merges the rows of one source). A row with fewer
    than ``k`` feasible slots fills the rest with picks whose ``feasible`` is False.
    """

    def run(order, value, t_end, row_k, row_d, keep, T, feasible, margin, effort, tmin):
        nv = order.shape[0]
        if by == "margin":
            score = jnp.where(feasible, margin, -jnp.inf)
        else:  # the sorted table's value of every slot's destination
            slot_d = jnp.minimum(row_d[:, None] + jnp.arange(width, dtype=row_d.dtype), nv - 1)
            score = value[slot_d]
            if by == "density":
                span = t_end[slot_d] - t_end[row_k][:, None]
                score = score / jnp.where(feasible, span, 1.0)
            score = jnp.where(feasible, score, -jnp.inf)
        col, real = _row_top_k(score, k)
        d = row_d[:, None] + col
        dst = order[jnp.minimum(d, nv - 1)]
        cols = [jnp.take_along_axis(x, col, axis=1) for x in (T, feasible, margin, effort, tmin)]
        cols[1] = cols[1] & real
        src_pos = jnp.broadcast_to(row_k[:, None], col.shape)
        return keep.sum(dtype=jnp.int32), src_pos, dst, *cols

    return jax.jit(run)


def _bucket(n: int, maximum: int) -> int:
    """Rows per chunk: ``maximum``, or for a single-chunk problem n rounded up to a power
    of two (at least :data:`_MIN_ROWS`): one compiled shape per octave, so the many small
    screens of a process (a plan's satellites, a library user's loop) share programs; the
    padding costs at most one small chunk's work again, far less than a compile."""
    if n >= maximum:
        return maximum
    return min(maximum, max(_MIN_ROWS, 1 << (max(int(n), 1) - 1).bit_length()))


def fused_chunks(
    options, model, max_gap, chunk_size, progress, feasible_only, pi, pc, top_k=None,
    top_k_by="margin",
):  # fmt: skip
    """Fused path of :func:`~jaxspline.screen.pairs.screen_chunks` (arguments validated).

    The time-sorted option table (the model's fields, :func:`model_arrays`; padded to
    a power of two) goes to the devices once; a row table (source, first
    destination, count; a source's run is cut into rows of ``width`` slots) stays on
    the host and chunk k sends its rows ``k * rows .. (k + 1) * rows - 1``. The
    programs depend on (model, rows, width, padded table size) only, so the
    planner's per-satellite screens can share them. Only the compacted rows come back.

    Args:
      options, model, max_gap, chunk_size, progress, feasible_only, top_k, top_k_by: as
        :func:`~jaxspline.screen.pairs.screen_transitions`.
      pi, pc: this process's index and the process count.
    Returns:
      ``(total, dtype, chunks)``: the number of candidate slots (same-route pairs
      included), the compute dtype and a generator of :class:`Transitions`, one per
      chunk of this process in source order (with ``top_k``, the merged best rows
      of the sources that became final).
    """
    dtype = options_dtype(options)
    runs = candidate_runs(options, max_gap)
    total = int(runs.counts.sum())
    if total == 0:
        return 0, dtype, iter(())
    mesh = device_mesh()
    rt = _row_table(runs, chunk_size, mesh.devices.size)
    o = runs.order
    tab, pair, params, put = _device_table(options, model, dtype, o, mesh)
    program = _fused_program(pair, rt.rows, rt.width, mesh, np.dtype(dtype))
    if top_k is not None:
        topk = _topk_program(rt.rows, rt.width, min(int(top_k), rt.width), top_k_by)
        value = put(np.asarray(options.value, np.float64)[o])

        def compact(order, rk, rd, *out):
            return topk(order, value, tab[1], rk, rd, *out)
    else:
        compact = _compact_program(rt.rows, rt.width, bool(feasible_only))

    cand = NamedSharding(mesh, P("cand"))

    def screened(rows):  # one chunk's rows: screened, then compacted, on the devices
        rk, rd, rn = (jax.device_put(a, cand) for a in rows)
        return compact(tab[-1], rk, rd, *program(tab, params, rk, rd, rn))

    chunks = _chunks(rt, screened, functools.partial(_rows_of, o, top_k), total, progress, pi, pc)
    if top_k is not None:
        score = top_k_score(options, top_k_by)
        return total, dtype, top_k_merge(chunks, int(top_k), score)
    return total, dtype, chunks


class _RowTable(NamedTuple):
    """The candidate layout: a source's run of destinations cut into rows of ``width``
    slots, padded to ``nchunks * rows`` rows (host numpy, int32 or int64)."""

    row_k: np.ndarray  # [nchunks * rows] source position in the time-sorted table
    row_d: np.ndarray  # first destination position of the row
    row_n: np.ndarray  # live slots of the row (0 for padding)
    width: int  # slots per row
    rows: int  # rows per chunk
    nchunks: int
    per_chunk: np.ndarray  # [nchunks] candidate slots per chunk (progress)


def _row_table(runs, chunk_size: int, ndev: int) -> _RowTable:
    """The row table of the candidate runs (:func:`candidate_runs`) for ``ndev`` devices."""
    width = _row_width(runs.counts, chunk_size)
    nrows = -(-runs.counts // width)
    row_k, first = ragged_positions(nrows)
    first = first * width
    row_d = runs.lo[row_k] + first
    row_n = np.minimum(runs.counts[row_k] - first, width)
    rows = round_up(_bucket(nrows.sum(), max(1, chunk_size // width)), ndev)
    nchunks = -(-row_k.size // rows)
    pad = nchunks * rows - row_k.size
    itype = np.int32 if row_k.size < 2**31 and runs.order.size < 2**31 else np.int64
    row_k, row_d, row_n = (
        np.concatenate([a, np.zeros(pad, a.dtype)]).astype(itype) for a in (row_k, row_d, row_n)
    )
    per_chunk = np.add.reduceat(np.asarray(row_n), np.arange(0, nchunks * rows, rows))
    return _RowTable(row_k, row_d, row_n, width, rows, nchunks, per_chunk)


def _device_table(options, model, dtype, order, mesh):
    """The time-sorted option table on the devices, replicated: ``(tab, pair, params,
    put)`` with ``tab = (model fields, t_end, t_start, route, order)`` and ``put`` the
    function that sends one more column.

    The option axis is padded to a power of two (at least ``_MIN_TABLE``): programs are
    reused across tables of similar size (the planner screens one table per satellite).
    """
    rep = NamedSharding(mesh, P())
    nv_pad = padded_size(max(order.size, _MIN_TABLE))

    def put(a):
        return jax.device_put(pad_last(a, nv_pad), rep)

    pair, fields, params = model_arrays(model, options, dtype, order)
    tab = (
        tuple(put(a) for a in fields),
        put(np.asarray(options.t_end, np.float64)[order]),
        put(np.asarray(options.t_start, np.float64)[order]),
        put(np.asarray(options.route)[order]),
        put(order.astype(np.int64)),
    )
    params = tuple(jax.device_put(a, rep) for a in params)
    return tab, pair, params, put


def _rows_of(order, top_k, p):
    """One compacted chunk back on the host: a :class:`Transitions`, or with ``top_k``
    ``(src position, columns, n_screened)`` of the feasible picks of the row top-k's."""
    if top_k is not None:
        kept, pos, *cols = (np.asarray(x) for x in p)
        ok = cols[2].reshape(-1)
        pos = pos.reshape(-1)[ok]
        cols = [x.reshape(-1)[ok] for x in cols]
        return pos, [order[pos], *cols], int(kept)
    kept, count, *cols = p
    m = int(count)
    return Transitions(*(np.asarray(x)[:m] for x in cols), n_screened=int(kept))


def _chunks(rt: _RowTable, screened, rows_of, total, progress, pi, pc):
    """This process's chunks in order, with one chunk in flight on the devices: chunk k
    is dispatched (``screened``) before chunk k - 1 comes back (``rows_of``)."""
    pending = None
    from tqdm.auto import tqdm

    bar = tqdm(total=total, unit="cand", disable=not progress, desc="screen")
    try:
        for k in range(rt.nchunks):
            if k % pc == pi:
                sl = slice(k * rt.rows, (k + 1) * rt.rows)  # the chunk's rows: a few kB
                nxt = screened((rt.row_k[sl], rt.row_d[sl], rt.row_n[sl]))
                if pending is not None:
                    yield rows_of(pending)
                pending = nxt
            bar.update(int(rt.per_chunk[k]))
        if pending is not None:
            yield rows_of(pending)
    finally:
        bar.close()


def screen_transitions_fused(
    options, model, max_gap, chunk_size, progress, feasible_only, pi, pc, top_k=None
) -> Transitions:
    """:func:`fused_chunks` collected into one :class:`Transitions` (arguments validated).

    Args:
      options, model, max_gap, chunk_size, progress, feasible_only: as
        :func:`~jaxspline.screen.pairs.screen_transitions`.
      pi, pc: this process's index and the process count.
      top_k: as :func:`~jaxspline.screen.pairs.screen_transitions`.
    Returns:
      Transitions.
    """
    feasible_only = feasible_only or top_k is not None
    total, dtype, chunks = fused_chunks(
        options, model, max_gap, chunk_size, progress, feasible_only, pi, pc, top_k
    )
    return collect(Stream(total, dtype, top_k is None, chunks), feasible_only)
