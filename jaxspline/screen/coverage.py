"""Strip coverage engine: candidate strips -> covered grid samples, as a compact table.

Public API (float64 inside; array arguments are numpy):

* ``Candidates(sat, k0, n, roll_deg)``: struct of arrays, one row per candidate strip of
  satellite ``sat`` (int32, index into the track arrays) starting at mesh sample ``k0``
  (int32; the action grid of 10 s lies on the 5 s mesh: ``k0 = start_s / step``) with
  ``n`` samples (int32, ``duration_s / step + 1`` >= 2, so ``n - 1`` quads) and roll
  ``roll_deg`` (float64 [deg]).
* ``coverage_slices(pos, vel, fov_deg, candidates, lon_deg, lat_deg, region)
  -> CoverageSlices(lo, hi, valid, pool)``: candidate c covers the grid samples
  ``pool[lo[c]:hi[c]]`` (int32 sample indices into lon/lat, each once, unsorted);
  ``valid[c]`` is False when a ray of the strip misses the Earth (then ``lo == hi``).
  ``pos``/``vel`` are ``Tracks.pos``/``Tracks.vel`` [S, K, 3] (m, m/s, Earth-fixed),
  ``fov_deg`` [S] the satellites' cross-track fields of view [deg], ``region`` [N] the
  sample's region index (the coarse filter works per region bounding box).
* ``CoverageSlices.csr(c0, c1) -> CoverageTable(indptr int64 [C'+1], indices int32,
  valid)``: the CSR rows of candidates ``c0..c1-1`` (stream chunks to bound memory);
  ``CoverageSlices.gains(w)``: ``sum(w[covered])`` per candidate in O(M + C) (for a
  greedy: pass the weights of still-uncovered samples, zero for covered ones).
* ``coverage_table(...)``: ``coverage_slices(...).csr()`` in one call.
* Kernels (:mod:`jaxspline.screen.coverage_kernels`): ``edge_points``, ``quad_range``;
  batched helpers here: ``strip_quads`` (edge points of one strip) and
  ``covered_samples`` (direct sweep of one strip, the reference for the engine).

Semantics: RULES.md's geometry (see :mod:`jaxspline.screen.coverage_kernels`), a sample
inside or on the border of any quad. Longitudes are unwrapped across the antimeridian (the
true geometry); the official verifier (as ``jaxspline.regional.check`` reads it) builds
quads from raw longitudes, so a quad crossing +-180 deg spans the long way round there. No
region of the benchmark's library lies within 44 deg of +-180 deg, so a strip that covers a
region sample never crosses it and both agree; strips crossing it are scored differently
(this engine never claims the verifier's long-way "phantom" coverage). Per action, the
covered sets equal those of the independent checker :mod:`jaxspline.regional.check`
(tested).

How (the sweep structure). Candidates are grouped by (satellite, roll). Per group the
edge points are computed once on the union of the candidates' sample ranges; quads whose
bounding box misses every region's bounding box are dropped (the coarse filter); the
remaining quads form runs (a run never has a gap larger than the group's longest
candidate), cut into pieces of ``PIECE_QUADS`` quads. Grid samples are bucketed into
tiles of ``TILE_SIZE`` nearby points; each (piece, tile) pair whose bounding boxes meet
goes through the ``quad_range`` kernel (jit(vmap), fixed chunk shapes). Per (run, sample)
this records the first and last quad that contains the sample; a sub-strip with quads
``[qa, qb]`` then covers exactly the samples whose range meets ``[qa, qb]``. Inside a run
the samples are sorted by (first, last); when every sample lies in a contiguous range of
at most two quads (the normal case), each candidate's covered set is one contiguous slice
of that order, read from a per-run table of bounds indexed by quad; any other run falls
back to the direct per-candidate sweep (its result appended to the pool). Per-candidate
host steps stream over ``CAND_CHUNK`` candidates.

Cost (case_0001, 3.6 M candidates = every pass near a region x 0.5 deg roll grid x 10 s
starts x every duration; bench/results/COVERAGE.md): ~2.3 s CPU after an ~6 s
compilation, 18.5 bytes per candidate (lo, hi, valid) plus a pool of 1.2 M sample ids for
212 M covered (candidate, sample) entries; the CSR of all rows would be 0.9 GB.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxspline.screen.coverage_kernels import edge_points, quad_range
from jaxspline.screen.coverage_sweep import (
    PIECE_QUADS,
    chunk_size,
    group_runs,
    point_tiles,
    sweep_pairs,
)

__all__ = [
    "Candidates",
    "CoverageTable",
    "CoverageSlices",
    "strip_quads",
    "covered_samples",
    "coverage_slices",
    "coverage_table",
]

EDGE_CHUNK = 1 << 15  # samples per edge-point call (at most; fixed shapes, padded)
MIN_EDGE_CHUNK = 1 << 10  # smallest padded edge-point chunk
CAND_CHUNK = 1 << 20  # candidates per host step (bounds the per-candidate temporaries)
MIN_STRIP_BUCKET = 16  # direct sweeps pad a strip to a power of two >= this (few compiles)


class Candidates(NamedTuple):
    """Candidate strips, a struct of arrays (one row per candidate).

    Attributes:
      sat: int32 [C], satellite index (into the track arrays).
      k0: int32 [C], first mesh sample (start time / mesh step).
      n: int32 [C], number of mesh samples (duration / step + 1, >= 2).
      roll_deg: float64 [C], roll [deg].
      pitch_deg: float64 [C], pitch [deg] (None: 0, the roll-only law).
    """

    sat: np.ndarray
    k0: np.ndarray
    n: np.ndarray
    roll_deg: np.ndarray
    pitch_deg: np.ndarray | None = None


class CoverageTable(NamedTuple):
    """Candidate -> covered samples in CSR form.

    Attributes:
      indptr: int64 [C+1]; row c is ``indices[indptr[c]:indptr[c+1]]``.
      indices: int32 [nnz], grid sample indices (unsorted within a row, no repeats).
      valid: bool [C], every ray of the strip meets the Earth (else the row is empty).
    """

    indptr: np.ndarray
    indices: np.ndarray
    valid: np.ndarray

    @property
    def nbytes(self) -> int:
        """Bytes of the arrays."""
        return int(self.indptr.nbytes + self.indices.nbytes + self.valid.nbytes)


class CoverageSlices(NamedTuple):
    """Candidate -> covered samples as slices of a shared pool.

    Attributes:
      lo: int64 [C], start of candidate c's slice of ``pool``.
      hi: int64 [C], end (exclusive); ``lo == hi`` covers nothing.
      valid: bool [C], every ray of the strip meets the Earth (and SGP4 succeeded).
      pool: int32 [M], grid sample indices.
      stats: dict of engine counts (groups, runs, pieces, pairs, fallbacks, times).
    """

    lo: np.ndarray
    hi: np.ndarray
    valid: np.ndarray
    pool: np.ndarray
    stats: dict

    @property
    def nbytes(self) -> int:
        """Bytes of the arrays (lo, hi, valid, pool)."""
        return int(self.lo.nbytes + self.hi.nbytes + self.valid.nbytes + self.pool.nbytes)

    def counts(self) -> np.ndarray:
        """Number of covered samples per candidate, int64 [C]."""
        return self.hi - self.lo

    def csr(self, c0: int = 0, c1: int | None = None) -> CoverageTable:
        """CSR rows of candidates ``c0..c1-1`` (materialized: 4 bytes per entry).

        Args:
          c0: first candidate.
          c1: end candidate (exclusive), default all.
        Returns:
          CoverageTable with ``c1 - c0`` rows.
        """
        lo, hi = self.lo[c0:c1], self.hi[c0:c1]
        cnt = hi - lo
        indptr = np.zeros(cnt.size + 1, np.int64)
        np.cumsum(cnt, out=indptr[1:])
        starts = np.repeat(lo - indptr[:-1], cnt)
        idx = self.pool[starts + np.arange(indptr[-1], dtype=np.int64)]
        return CoverageTable(indptr, idx, self.valid[c0:c1])

    def gains(self, weight: np.ndarray) -> np.ndarray:
        """``sum(weight[covered])`` per candidate.

        Args:
          weight: float [N], per grid sample (e.g. 0 for already covered samples).
        Returns:
          float64 [C].
        """
        cs = np.zeros(self.pool.size + 1)
        np.cumsum(np.asarray(weight, np.float64)[self.pool], out=cs[1:])
        return cs[self.hi] - cs[self.lo]


_edges_batch = jax.jit(jax.vmap(edge_points))
_ranges_batch = jax.jit(jax.vmap(quad_range, in_axes=(None, None, None, None, 0)))


def strip_quads(pos, vel, roll_deg: float, fov_deg: float, pitch_deg: float = 0.0):
    """Edge points of one strip (every sample of it).

    Args:
      pos: float [n, 3], Earth-fixed positions at the strip's samples [m].
      vel: float [n, 3], Earth-fixed velocities [m/s].
      roll_deg: roll [deg].
      fov_deg: cross-track field of view [deg].
      pitch_deg: pitch [deg] (0: the roll-only law).
    Returns:
      (inner [n, 2], outer [n, 2], hit [n]) numpy: (lon, lat) [deg] of the edge ground
      points, and whether both rays meet the Earth.
    """
    with jax.enable_x64(True):
        pos = jnp.asarray(pos, jnp.float64)
        n = pos.shape[0]
        r = jnp.full((n,), roll_deg, jnp.float64)
        f = jnp.full((n,), fov_deg, jnp.float64)
        q = jnp.full((n,), pitch_deg, jnp.float64)
        inner, outer, hit = _edges_batch(pos, jnp.asarray(vel, jnp.float64), r, f, q)
    return np.asarray(inner), np.asarray(outer), np.asarray(hit)


def covered_samples(inner, outer, lon_deg, lat_deg) -> np.ndarray:
    """Grid samples covered by one strip, by a direct sweep over all its quads.

    Args:
      inner: float [n, 2], inner-edge (lon, lat) of the strip's samples [deg] (n >= 2).
      outer: float [n, 2], outer-edge (lon, lat) [deg].
      lon_deg: float [N], grid sample longitudes [deg].
      lat_deg: float [N], grid sample latitudes [deg].
    Returns:
      int64 [m], sorted indices of the covered samples.
    """
    inner = np.asarray(inner, np.float64)
    if inner.ndim != 2 or inner.shape[0] < 2:
        raise ValueError(f"inner: expected shape [n >= 2, 2], got {inner.shape}")
    pts = np.stack([np.asarray(lon_deg, np.float64), np.asarray(lat_deg, np.float64)], -1)
    n = inner.shape[0]
    pad = np.minimum(np.arange(max(MIN_STRIP_BUCKET, 1 << (n - 1).bit_length())), n - 1)
    with jax.enable_x64(True):
        _, _, count = _ranges_batch(
            jnp.asarray(inner[pad]),
            jnp.asarray(np.asarray(outer, np.float64)[pad]),
            n - 1,
            inner[0, 0],
            jnp.asarray(pts),
        )
    return np.flatnonzero(np.asarray(count) > 0)


def _check_inputs(pos, vel, fov_deg, cands: Candidates, lon, lat, region):
    s, k = pos.shape[:2]
    if pos.shape != (s, k, 3) or vel.shape != pos.shape:
        raise ValueError(f"pos, vel: expected equal shapes [S, K, 3], got {pos.shape}, {vel.shape}")
    if fov_deg.shape != (s,):
        raise ValueError(f"fov_deg: expected shape [{s}], got {fov_deg.shape}")
    c = cands.sat.shape[0]
    for name in ("sat", "k0", "n", "roll_deg"):
        if getattr(cands, name).shape != (c,):
            raise ValueError(f"candidates.{name}: expected shape [{c}]")
    if c and (cands.sat.min() < 0 or cands.sat.max() >= s):
        raise ValueError(
            f"candidates.sat: must lie in [0, {s}), got [{cands.sat.min()}, {cands.sat.max()}]"
        )
    if c and cands.n.min() < 2:
        raise ValueError(f"candidates.n: must be >= 2 samples, got {cands.n.min()}")
    if c and (cands.k0.min() < 0 or (cands.k0.astype(np.int64) + cands.n - 1).max() >= k):
        raise ValueError(f"candidates.k0, n: strips must lie inside the mesh [0, {k})")
    if not np.all(np.isfinite(cands.roll_deg)):
        raise ValueError("candidates.roll_deg: must be finite")
    if not (lon.shape == lat.shape == region.shape and lon.ndim == 1):
        raise ValueError(
            "lon_deg, lat_deg, region: expected equal shapes [N], got "
            f"{lon.shape}, {lat.shape}, {region.shape}"
        )


def _as_candidates(c: Candidates) -> Candidates:
    roll = np.asarray(c.roll_deg, np.float64).ravel()
    pitch = np.zeros_like(roll) if c.pitch_deg is None else c.pitch_deg
    return Candidates(
        np.asarray(c.sat, np.int32).ravel(),
        np.asarray(c.k0, np.int32).ravel(),
        np.asarray(c.n, np.int32).ravel(),
        roll,
        np.broadcast_to(np.asarray(pitch, np.float64).ravel(), roll.shape),
    )


def _groups(cands: Candidates):
    """Group id per candidate (by satellite, exact roll and pitch) and each group's
    (sat, roll, pitch)."""
    rolls, r_inv = np.unique(cands.roll_deg, return_inverse=True)
    pitches, p_inv = np.unique(cands.pitch_deg, return_inverse=True)
    key = (cands.sat.astype(np.int64) * pitches.size + p_inv.ravel()) * rolls.size + r_inv.ravel()
    keys, gid = np.unique(key, return_inverse=True)
    g_sat = keys // (rolls.size * pitches.size)
    g_pitch = pitches[(keys // rolls.size) % pitches.size]
    return gid.ravel().astype(np.int64), g_sat, rolls[keys % rolls.size], g_pitch


def _union_samples(gid, k0, n, n_samples):
    """Per group, the union of candidate sample ranges, flattened and sorted by (gid, k)."""
    key_a = gid * n_samples + k0
    order = np.argsort(key_a, kind="stable")
    key_a = key_a[order]
    key_b = key_a + (n[order].astype(np.int64) - 1)
    reach = np.maximum.accumulate(key_b)
    new = np.ones(key_a.size, bool)
    new[1:] = key_a[1:] > reach[:-1] + 1  # starts after everything so far (+ adjacency)
    start = key_a[new]
    end = np.maximum.reduceat(key_b, np.flatnonzero(new)) if key_a.size else start
    length = end - start + 1
    offset = np.repeat(np.cumsum(length) - length, length)
    u_key = np.repeat(start, length) + (np.arange(int(length.sum())) - offset)
    return u_key


def _edges(pos, vel, fov, g_sat, g_roll, g_pitch, u_key, n_samples):
    """Edge points (inner, outer [U, 2], hit [U]) of every union sample, in fixed chunks."""
    u_gid, u_k = u_key // n_samples, u_key % n_samples
    sat = g_sat[u_gid]
    u = u_key.size
    inner, outer, hit = np.empty((u, 2)), np.empty((u, 2)), np.empty(u, bool)
    for c0 in range(0, u, EDGE_CHUNK):
        sl = slice(c0, min(c0 + EDGE_CHUNK, u))
        m = sl.stop - sl.start
        idx = np.zeros(chunk_size(m, MIN_EDGE_CHUNK, EDGE_CHUNK), np.int64)
        idx[:m] = np.arange(sl.start, sl.stop)
        p = jnp.asarray(pos[sat[idx], u_k[idx]])
        v = jnp.asarray(vel[sat[idx], u_k[idx]])
        r = jnp.asarray(g_roll[u_gid[idx]])
        f = jnp.asarray(fov[sat[idx]])
        q = jnp.asarray(g_pitch[u_gid[idx]])
        i_, o_, h_ = _edges_batch(p, v, r, f, q)
        inner[sl], outer[sl], hit[sl] = np.asarray(i_)[:m], np.asarray(o_)[:m], np.asarray(h_)[:m]
    return inner, outer, hit


def _validity(hit, u_key, gid, k0, n, n_samples):
    """valid[c]: every sample of candidate c hits (candidate chunks bound the temporaries)."""
    miss = np.zeros(hit.size + 1, np.int64)
    np.cumsum(~hit, out=miss[1:])
    valid = np.empty(gid.size, bool)
    for c0 in range(0, gid.size, CAND_CHUNK):
        sl = slice(c0, c0 + CAND_CHUNK)
        u0 = np.searchsorted(u_key, gid[sl] * n_samples + k0[sl])
        valid[sl] = miss[u0 + n[sl]] == miss[u0]
    return valid


def coverage_slices(pos, vel, fov_deg, candidates: Candidates, lon_deg, lat_deg, region):
    """Covered grid samples of every candidate strip (the sweep engine, float64).

    Args:
      pos: float [S, K, 3], Earth-fixed positions on the mesh [m] (``Tracks.pos``).
      vel: float [S, K, 3], Earth-fixed velocities [m/s] (``Tracks.vel``).
      fov_deg: float [S], cross-track field of view per satellite [deg].
      candidates: Candidates (C rows).
      lon_deg: float [N], grid sample longitudes [deg].
      lat_deg: float [N], grid sample latitudes [deg].
      region: int [N], region index of each sample (coarse filter per region box).
    Returns:
      CoverageSlices.
    Raises:
      ValueError: naming the argument on bad shapes or out-of-range candidates.
    """
    t0 = time.perf_counter()
    pos, vel = np.asarray(pos, np.float64), np.asarray(vel, np.float64)
    fov = np.asarray(fov_deg, np.float64).ravel()
    cands = _as_candidates(candidates)
    lon, lat = np.asarray(lon_deg, np.float64), np.asarray(lat_deg, np.float64)
    region = np.asarray(region).ravel()
    _check_inputs(pos, vel, fov, cands, lon, lat, region)
    k_all = pos.shape[1]
    gid, g_sat, g_roll, g_pitch = _groups(cands)
    u_key = _union_samples(gid, cands.k0, cands.n, k_all)
    with jax.enable_x64(True):
        inner, outer, hit = _edges(pos, vel, fov, g_sat, g_roll, g_pitch, u_key, k_all)
        valid = _validity(hit, u_key, gid, cands.k0, cands.n, k_all)
        g_maxq = np.zeros(g_sat.size, np.int64)
        np.maximum.at(g_maxq, gid, cands.n.astype(np.int64) - 1)
        runs = group_runs(inner, outer, hit, u_key, k_all, g_maxq, lon, lat, region)
        tiles = point_tiles(lon, lat)
        res = sweep_pairs(runs, tiles, inner, outer)
    t1 = time.perf_counter()
    geo = (u_key, inner, outer, lon, lat)
    lo, hi, pool, fb = _slices(res, runs, gid, cands, k_all, valid, geo)
    stats = {
        "candidates": int(cands.sat.size),
        "groups": int(g_sat.size),
        "union_samples": int(u_key.size),
        **runs.stats,
        **res.stats,
        "fallback_candidates": int(fb),
        "sweep_s": t1 - t0,
        "slices_s": time.perf_counter() - t1,
        "piece_quads": PIECE_QUADS,
    }
    return CoverageSlices(lo, hi, valid, pool, stats)


def _run_of(runs, gid, qa, qb, n_samples):
    """The run each candidate's quads [qa, qb] meet (-1 if none); at most one by design."""
    r_end = runs.run_gid * n_samples + runs.run_end
    r = np.searchsorted(r_end, gid * n_samples + qa, side="left")
    rc = np.minimum(r, max(r_end.size - 1, 0))
    ok = (
        (r < r_end.size) & (runs.run_gid[rc] == gid) & (runs.run_start[rc] <= qb)
        if r_end.size
        else np.zeros(gid.size, bool)
    )
    return np.where(ok, r, -1)


def _fallback(cand, hits, runs, gid, cands, n_samples, geo):
    """Direct sweeps of candidates whose run is irregular, against the run's samples."""
    u_key, inner, outer, lon, lat = geo
    k0, n = cands.k0[cand].astype(np.int64), cands.n[cand].astype(np.int64)
    run = _run_of(runs, gid[cand], k0, k0 + n - 2, n_samples)
    u0 = np.searchsorted(u_key, gid[cand] * n_samples + k0)
    ptr = np.searchsorted(hits.run, np.arange(hits.irregular.size + 1))
    rows = []
    for i in range(cand.size):
        pts = hits.sample[ptr[run[i]] : ptr[run[i] + 1]]
        sl = slice(u0[i], u0[i] + n[i])
        got = covered_samples(inner[sl], outer[sl], lon[pts], lat[pts])
        rows.append(pts[got].astype(np.int32))
    return rows


def _bound_tables(hits, runs, n_samples):
    """Per run r and quad q of its span: pool bounds of the samples whose range meets q.

    ``lo_t`` is the first sample with (first, last) >= (q - 1, q), ``hi_t`` one past the
    last with first <= q (for regular runs, where last - first <= 1). Indexed by
    ``off[r] + q - run_start[r]``.
    """
    span = runs.run_end - runs.run_start + 1
    off = np.zeros(span.size + 1, np.int64)
    np.cumsum(span, out=off[1:])
    r = np.repeat(np.arange(span.size), span)
    q = runs.run_start[r] + (np.arange(off[-1]) - off[r])
    big = 2 * n_samples + 4
    gkey = hits.run * big + 2 * hits.first + (hits.last - hits.first)
    lo_t = np.searchsorted(gkey, r * big + 2 * q - 1, side="left")
    hi_t = np.searchsorted(gkey, r * big + 2 * q + 1, side="right")
    return off, lo_t, hi_t


def _slice_chunk(hits, runs, tables, gid, qa, qb, n_samples):
    """(lo, hi, run) of a chunk of candidates with quads [qa, qb] (table look-ups)."""
    run = _run_of(runs, gid, qa, qb, n_samples)
    rr = np.maximum(run, 0)
    if tables is None:
        return np.zeros(qa.size, np.int64), np.zeros(qa.size, np.int64), run
    off, lo_t, hi_t = tables
    rs, re = runs.run_start[rr], runs.run_end[rr]
    lo = lo_t[off[rr] + np.clip(qa, rs, re) - rs]
    hi = hi_t[off[rr] + np.clip(qb, rs, re) - rs]
    return lo, hi, run


def _slices(hits, runs, gid, cands, n_samples, valid, geo):
    """lo, hi into the pool per candidate (in candidate chunks), the pool, #fallbacks."""
    c = gid.size
    tables = _bound_tables(hits, runs, n_samples) if runs.run_start.size else None
    lo, hi = np.zeros(c, np.int64), np.zeros(c, np.int64)
    irregular = np.zeros(c, bool)
    for c0 in range(0, c, CAND_CHUNK):
        sl = slice(c0, c0 + CAND_CHUNK)
        qa = cands.k0[sl].astype(np.int64)
        lo_c, hi_c, run = _slice_chunk(
            hits, runs, tables, gid[sl], qa, qa + cands.n[sl] - 2, n_samples
        )
        use = (run >= 0) & valid[sl]
        if hits.irregular.size:
            irregular[sl] = use & hits.irregular[np.maximum(run, 0)]
        use &= ~irregular[sl]
        lo[sl], hi[sl] = np.where(use, lo_c, 0), np.where(use, hi_c, 0)
    pool = hits.sample
    fb = np.flatnonzero(irregular)
    if fb.size:
        rows = _fallback(fb, hits, runs, gid, cands, n_samples, geo)
        sizes = np.array([r.size for r in rows], np.int64)
        lo[fb] = pool.size + np.cumsum(sizes) - sizes
        hi[fb] = lo[fb] + sizes
        pool = np.concatenate([pool, *rows])
    return lo, hi, pool, fb.size


def coverage_table(pos, vel, fov_deg, candidates: Candidates, lon_deg, lat_deg, region):
    """``coverage_slices(...).csr()``: the whole CSR table in one call.

    Args:
      pos: as for :func:`coverage_slices`.
      vel: as for :func:`coverage_slices`.
      fov_deg: as for :func:`coverage_slices`.
      candidates: as for :func:`coverage_slices`.
      lon_deg: as for :func:`coverage_slices`.
      lat_deg: as for :func:`coverage_slices`.
      region: as for :func:`coverage_slices`.
    Returns:
      CoverageTable (all C rows; 8 bytes per candidate + 4 per covered sample).
    """
    return coverage_slices(pos, vel, fov_deg, candidates, lon_deg, lat_deg, region).csr()
