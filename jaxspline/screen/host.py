"""The host-generated screening path and the pairs screener.

:func:`host_chunks` is the path :func:`jaxspline.screen.pairs.screen_chunks` takes
with x64 off (the fused path forms T in float64 on the device), kept as the
reference and benchmark baseline of the fused path: a chunk of ``chunk_size``
pairs is materialized on the host run by run (``np.repeat``), same-route pairs
dropped, padded to a fixed length and screened by :func:`_chunk_program`, which
gathers the boundary states from the option table on the device.
:class:`Screener` also screens given pairs for
:func:`~jaxspline.screen.pairs.screen_pairs`.

Units: radians, seconds.
"""

from __future__ import annotations

import functools

import jax
import numpy as np
from jax.sharding import NamedSharding
from jax.sharding import PartitionSpec as P

from jaxspline.kernels.batch import pad_last, padded_size
from jaxspline.screen.options import RouteOptions, options_dtype, validate_options
from jaxspline.screen.pair_models import model_arrays
from jaxspline.screen.transitions import Transitions, candidate_runs, device_mesh

__all__ = ["host_chunks"]


@functools.lru_cache(maxsize=8)
def _chunk_program(pair):
    """jit program screening one chunk: (feasible, margin, effort, t_min), each [n].

    ``pair`` is the model's pair function (:mod:`jaxspline.screen.pair_models`).
    Field-major layout: the option table arrives transposed ([F, N] per field), so
    every operation runs on contiguous [n] candidate vectors. A padded slot has T = 0
    and comes out infeasible; callers drop padded slots anyway.
    """

    def run(table, params, src, dst, T):
        return pair(table, params, src, dst, T)

    return jax.jit(run)


class Screener:
    """Holds the device copy of the option table and screens index chunks."""

    def __init__(self, options: RouteOptions, model):
        validate_options(options)
        self.dtype = options_dtype(options)
        self.mesh = device_mesh()
        self.ndev = self.mesh.devices.size
        rep = NamedSharding(self.mesh, P())
        self.cand = NamedSharding(self.mesh, P("cand"))
        pair, table, params = model_arrays(model, options, self.dtype)
        # field-major [F, N]: each channel's column is one contiguous vector; N padded to a
        # power of two, so tables of similar size share the compiled program
        n_pad = padded_size(np.asarray(options.t_start).shape[0])
        self.table = tuple(jax.device_put(pad_last(a, n_pad), rep) for a in table)
        self.params = tuple(jax.device_put(a, rep) for a in params)
        self.t_start = np.asarray(options.t_start, np.float64)
        self.t_end = np.asarray(options.t_end, np.float64)
        self.program = _chunk_program(pair)

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
        return src, dst, t[:n], self.program(self.table, self.params, *args)

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


def host_chunks(options, model, max_gap, chunk_size, progress, feasible_only, pi, pc):
    """Host path of :func:`~jaxspline.screen.pairs.screen_chunks` (arguments validated).

    Args:
      options, model, max_gap, chunk_size, progress, feasible_only: as
        :func:`~jaxspline.screen.pairs.screen_transitions`.
      pi, pc: this process's index and the process count.
    Returns:
      ``(total, dtype, order, chunks)``: the number of candidate slots (same-route
      pairs included), the compute dtype, the time-sorted valid options (int [V])
      and a generator of :class:`Transitions`, one per chunk of this process, in
      source order (only the feasible rows with ``feasible_only``).
    """
    screener = Screener(options, model)
    route = np.asarray(options.route)
    order, lo, counts = candidate_runs(options, max_gap)
    ts_sorted = screener.t_start[order]
    te_src = screener.t_end[order]
    starts = np.concatenate([[0], np.cumsum(counts)])
    total = int(starts[-1])
    route_sorted = route[order]
    base = lo - starts[:-1]  # destination position of candidate g of source k: base[k] + g

    def out(pending):
        cols = screener.collect(pending)
        if feasible_only:
            cols = tuple(a[cols[3]] for a in cols)
        return Transitions(*cols, n_screened=int(pending[0].size))

    def chunks():
        pending = None
        from tqdm.auto import tqdm

        bar = tqdm(total=total, unit="cand", disable=not progress, desc="screen")
        try:
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
                    nxt = screener.dispatch(src, dst, size, T)  # runs while the last is collected
                    if pending is not None:
                        yield out(pending)
                    pending = nxt
                bar.update(g1 - g0)
            if pending is not None:
                yield out(pending)
        finally:
            bar.close()

    return total, screener.dtype, order, chunks()
