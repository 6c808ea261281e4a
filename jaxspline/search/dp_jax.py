"""The bound's DP forward pass as one ``jax.lax.scan`` over start blocks (any JAX device).

The same recursion as :func:`jaxspline.search.dp.dp_forward`, every satellite at once:
the scan walks the blocks of :func:`jaxspline.search.dp.dp_prepare` in start order and
each step reads fixed-size windows (the largest block's options, pairs and absorbed
options) out of the flat arrays with ``lax.dynamic_slice``, masking what lies past the
block, so nothing is padded per block and the device holds the pair table once (4 bytes
a pair). A step: absorb the options that became far into the per-satellite running
maxima (``.at[].max``), gather the predecessors' values, segment-max them per row
(rows found by ``searchsorted`` in the block's row pointers), write the block's
``best``. Float64 (the values are summed over thousands of options): the calls run
under ``jax.enable_x64``. The paths are recovered on the host by
:func:`jaxspline.search.dp.backtrack`.

Not used by the planner's forked bound worker (JAX does not survive a fork); the bench
(``python -m bench --section bound``) times it against the numpy form on any device.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.search.dp import DPData, backtrack
from jaxspline.search.problem import Problem

__all__ = ["JaxDP"]


class JaxDP:
    """Device-resident DP structure of one problem; :meth:`forward` per price vector.

    Args:
      pb: Problem.
      d: its :func:`jaxspline.search.dp.dp_prepare`.
      device: a ``jax.Device`` (default: JAX's default device).
    """

    def __init__(self, pb: Problem, d: DPData, device=None):
        self.pb, self.d = pb, d
        n, n_s = pb.n_options, pb.n_sats
        ptr = pb.pairs.ptr
        g = np.asarray(d.groups, np.int64).reshape(-1, 2)
        ga, gb = g[:, 0], g[:, 1]
        self.b_max = int(max(1, (gb - ga).max(initial=1)))
        npairs = ptr[gb] - ptr[ga]
        self.p_max = int(max(1, npairs.max(initial=1)))
        na = np.diff(d.absorb_at)
        self.a_max = int(max(1, na.max(initial=1)))
        bm, pm, am = self.b_max, self.p_max, self.a_max
        with jax.enable_x64(True):
            put = lambda x: jax.device_put(x, device)  # noqa: E731
            self._xs = put(
                np.stack([ga, gb - ga, ptr[ga], npairs, d.absorb_at[:-1], na], 1).astype(np.int64)
            )
            self._order = put(np.r_[d.order, np.full(bm, n)].astype(np.int32))
            self._sat = put(np.r_[d.sat, n_s].astype(np.int32))
            self._tg = put(np.r_[d.target, -1].astype(np.int32))
            self._sat_o = put(np.r_[d.sat_order, np.full(bm, n_s)].astype(np.int32))
            self._base_o = put(np.r_[d.base_order, np.full(bm, -np.inf)])
            self._absorb = put(np.r_[d.absorb, np.full(am, n)].astype(np.int32))
            self._src = put(np.r_[pb.pairs.src, np.zeros(pm, np.int32)].astype(np.int32))
            self._ptr = put(np.r_[ptr, np.full(bm + 1, ptr[-1])].astype(np.int64))
            self._n, self._n_s = n, n_s
            self._fwd = jax.jit(self._scan, static_argnums=2)
            self._fwd_many = jax.jit(self._scan_many, static_argnums=2)
        self.device = device

    def _scan(self, w, arc, merge_repeats):
        """best [N] (dummy slot dropped) for option values ``w`` [N] and pair costs ``arc``."""
        n, n_s = self._n, self._n_s
        bm, pm, am = self.b_max, self.p_max, self.a_max
        io_b, io_p, io_a = jnp.arange(bm), jnp.arange(pm), jnp.arange(am)
        w_pad = jnp.concatenate([w, jnp.full(1, -jnp.inf, w.dtype)])
        arc_pad = jnp.concatenate([arc, jnp.zeros(pm, arc.dtype)])
        ds = jax.lax.dynamic_slice

        def step(carry, x):
            best, run = carry
            ga, nb, pa, npp, aa, na = x[0], x[1], x[2], x[3], x[4], x[5]
            a_ids = ds(self._absorb, (aa,), (am,))
            a_ok = io_a < na
            run = run.at[jnp.where(a_ok, self._sat[a_ids], n_s)].max(
                jnp.where(a_ok, best[a_ids], -jnp.inf)
            )
            j_ids = ds(self._order, (ga,), (bm,))
            j_ok = io_b < nb
            v = jnp.maximum(ds(self._base_o, (ga,), (bm,)), run[ds(self._sat_o, (ga,), (bm,))])
            src = ds(self._src, (pa,), (pm,))
            pv = jnp.where(io_p < npp, best[src] - ds(arc_pad, (pa,), (pm,)), -jnp.inf)
            rowptr = ds(self._ptr, (ga,), (bm + 1,)) - pa
            seg = jnp.clip(jnp.searchsorted(rowptr, io_p, side="right") - 1, 0, bm - 1)
            if merge_repeats:  # a repeat adds nothing: its pair costs the option's value
                dst = j_ids[seg]
                pv = pv - jnp.where(self._tg[src] == self._tg[dst], w_pad[dst], 0.0)
            near = jax.ops.segment_max(pv, seg, num_segments=bm, indices_are_sorted=True)
            v = jnp.maximum(v, near)
            j_at = jnp.where(j_ok, j_ids, n)
            best = best.at[j_at].set(jnp.where(j_ok, w_pad[j_at] + v, -jnp.inf))
            return (best, run), None

        init = (jnp.full(n + 1, -jnp.inf, w.dtype), jnp.full(n_s + 1, -jnp.inf, w.dtype))
        (best, _), _ = jax.lax.scan(step, init, self._xs)
        return best[:n]

    def _scan_many(self, ws, arc, merge_repeats):
        """best [K, N] for K value vectors ``ws`` [K, N] (one scan, the rows side by side)."""
        return jax.vmap(lambda w: self._scan(w, arc, merge_repeats))(ws)

    def _arc(self, arc):
        """The pair costs as a float64 device array (zeros where ``arc`` is None)."""
        a = np.zeros(len(self.pb.pairs)) if arc is None else np.asarray(arc, np.float64)
        return jax.device_put(a, self.device)

    def forward(self, w, arc=None, merge_repeats: bool = False) -> np.ndarray:
        """The DP values (float64 [N]) as :func:`jaxspline.search.dp.dp_forward` gives them.

        Args:
          w: float [N], option values.
          arc: optional float [P], near-pair costs (``pb.pairs`` order).
          merge_repeats: as :func:`jaxspline.search.dp.dp_forward`.
        Returns:
          float64 numpy [N].
        """
        with jax.enable_x64(True):
            w = jax.device_put(np.asarray(w, np.float64), self.device)
            return np.asarray(self._fwd(w, self._arc(arc), bool(merge_repeats)))

    def forward_many(self, ws, arc=None, merge_repeats: bool = False) -> np.ndarray:
        """:meth:`forward` for K value vectors at once (one scan whose steps carry K rows).

        The scan's depth is the number of blocks whatever K is, so on an accelerator K
        price vectors (several step sizes of a subgradient step, the plain and the
        strengthened bound) cost about what one does.

        Args:
          ws: float [K, N], option values, one vector a row.
          arc: optional float [P], near-pair costs shared by the rows.
          merge_repeats: as :func:`jaxspline.search.dp.dp_forward`.
        Returns:
          float64 numpy [K, N].
        """
        ws = np.asarray(ws, np.float64)
        if ws.ndim != 2 or ws.shape[1] != self._n:
            raise ValueError(f"ws: expected shape (K, {self._n}), got {ws.shape}")
        with jax.enable_x64(True):
            w = jax.device_put(ws, self.device)
            return np.asarray(self._fwd_many(w, self._arc(arc), bool(merge_repeats)))

    def paths(self, w, arc=None, used=None, merge_repeats: bool = False):
        """``(paths, values)`` as :func:`jaxspline.search.dp.dp_paths` (forward on the device,
        back-tracking on the host)."""
        best = self.forward(w, arc, merge_repeats)
        w = np.asarray(w, np.float64)
        return backtrack(self.pb, self.d, w, best, arc, used, merge_repeats)
