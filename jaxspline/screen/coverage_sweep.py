"""The sweep stage of the coverage engine: active quads -> runs and pieces, point tiles,
(piece, tile) pairs through the ``quad_range`` kernel, per-(run, sample) quad ranges.

Used by :func:`jaxspline.screen.coverage.coverage_slices`; see its module docstring for
the whole method. Arrays are numpy on the host; the kernel calls are ``jit(vmap)`` with
fixed chunk shapes (``PAIR_CHUNK`` pairs of ``PIECE_QUADS + 1`` samples x ``TILE_SIZE``
points), so one compilation serves every case.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import numpy as np

from jaxspline.screen.coverage_kernels import quad_range, unwrap_lon

__all__ = [
    "PIECE_QUADS",
    "TILE_SIZE",
    "Runs",
    "Tiles",
    "SweepHits",
    "boxes_meet",
    "chunk_size",
    "group_runs",
    "point_tiles",
    "sweep_pairs",
]

PIECE_QUADS = 8  # quads per kernel piece (G)
TILE_SIZE = 64  # grid points per tile
TILE_BAND_DEG = 0.4  # latitude band height of the tiles [deg] (~9 rows of 5 km samples)
PAIR_CHUNK = 2048  # (piece, tile) pairs per kernel call (at most)
MIN_PAIR_CHUNK = 128  # smallest padded pair chunk (small calls pad to a power of two)
PIECE_BLOCK = 4096  # pieces per bounding-box pairing block (bounds host memory)
SHIFTS_DEG = (-360.0, 0.0, 360.0)  # whole-turn shifts tried when boxes are compared


class Runs(NamedTuple):
    """Active quads of every (satellite, roll) group, as runs cut into pieces.

    Attributes:
      piece_u0: int64 [P], union-sample index of each piece's first sample.
      piece_nq: int64 [P], quads in the piece (1..PIECE_QUADS).
      piece_k0: int64 [P], mesh index of the piece's first sample.
      piece_run: int64 [P], run of the piece.
      run_gid: int64 [R], group of each run (runs sorted by group, then time).
      run_start: int64 [R], mesh index of the run's first active quad.
      run_end: int64 [R], mesh index of the run's last active quad.
      stats: dict of counts.
    """

    piece_u0: np.ndarray
    piece_nq: np.ndarray
    piece_k0: np.ndarray
    piece_run: np.ndarray
    run_gid: np.ndarray
    run_start: np.ndarray
    run_end: np.ndarray
    stats: dict


class Tiles(NamedTuple):
    """Grid samples bucketed into tiles of nearby points.

    Attributes:
      pts: float64 [T_n, TILE_SIZE, 2], (lon, lat) [deg], NaN padding.
      idx: int32 [T_n, TILE_SIZE], sample index, -1 padding.
      box: float64 [T_n, 4], (lon_min, lon_max, lat_min, lat_max) [deg].
    """

    pts: np.ndarray
    idx: np.ndarray
    box: np.ndarray


class SweepHits(NamedTuple):
    """Per (run, sample) the first and last containing quad, sorted by (run, first, last).

    Attributes:
      run: int64 [M], run of each entry.
      sample: int32 [M], grid sample index.
      first: int64 [M], mesh index of the first quad containing the sample.
      last: int64 [M], mesh index of the last one.
      irregular: bool [R], a run with a sample in more than two quads or in a
        non-contiguous set of quads (its candidates take the direct sweep).
      stats: dict of counts.
    """

    run: np.ndarray
    sample: np.ndarray
    first: np.ndarray
    last: np.ndarray
    irregular: np.ndarray
    stats: dict


def chunk_size(remaining: int, smallest: int, largest: int) -> int:
    """Padded size of the next fixed-shape chunk: a power of two in [smallest, largest].

    Few distinct shapes (few compilations), little padding on small calls.

    Args:
      remaining: items left (> 0).
      smallest: smallest chunk (a power of two).
      largest: largest chunk (a power of two).
    Returns:
      int, ``min(largest, max(smallest, next power of two >= remaining))``.
    """
    return min(largest, max(smallest, 1 << max(remaining - 1, 0).bit_length()))


def boxes_meet(a, b) -> np.ndarray:
    """Do boxes meet (borders included), trying whole-turn longitude shifts of ``b``?

    Args:
      a: float [..., 4], (lon_min, lon_max, lat_min, lat_max) [deg].
      b: float [..., 4], same layout (broadcast against a).
    Returns:
      bool [...].
    """
    lat = (a[..., 2] <= b[..., 3]) & (a[..., 3] >= b[..., 2])
    lon = np.zeros(lat.shape, bool)
    for k in SHIFTS_DEG:
        lon |= (a[..., 0] <= b[..., 1] + k) & (a[..., 1] >= b[..., 0] + k)
    return lat & lon


def _region_boxes(lon, lat, region) -> np.ndarray:
    ids = np.unique(region)
    box = np.empty((ids.size, 4))
    for i, r in enumerate(ids):
        m = region == r
        box[i] = lon[m].min(), lon[m].max(), lat[m].min(), lat[m].max()
    return box


def _quad_boxes(inner, outer, u):
    """Bounding boxes of quads (u, u+1), longitudes unwrapped towards inner[u]."""
    ref = inner[u, 0]
    xs = np.stack([inner[u, 0], outer[u, 0], inner[u + 1, 0], outer[u + 1, 0]], -1)
    ys = np.stack([inner[u, 1], outer[u, 1], inner[u + 1, 1], outer[u + 1, 1]], -1)
    xs = np.asarray(unwrap_lon(xs, ref[:, None]))
    return np.stack([xs.min(-1), xs.max(-1), ys.min(-1), ys.max(-1)], -1)


def group_runs(inner, outer, hit, u_key, n_samples, g_maxq, lon, lat, region) -> Runs:
    """Active quads (the coarse filter: their box meets a region's box) -> runs, pieces.

    Args:
      inner: float [U, 2], inner-edge (lon, lat) of the union samples [deg].
      outer: float [U, 2], outer-edge (lon, lat) [deg].
      hit: bool [U], both rays of the sample meet the Earth.
      u_key: int64 [U], ``group * n_samples + k`` of each union sample (sorted).
      n_samples: K, the mesh size.
      g_maxq: int64 [G], the largest quad count of a candidate of each group (runs are
        split only at gaps larger than this, so a candidate meets at most one run).
      lon: float [N], grid longitudes [deg].
      lat: float [N], grid latitudes [deg].
      region: int [N], region of each sample.
    Returns:
      Runs.
    """
    u_gid, u_k = u_key // n_samples, u_key % n_samples
    u = np.flatnonzero((u_key[1:] == u_key[:-1] + 1) & (u_k[1:] != 0) & hit[:-1] & hit[1:])
    rbox = _region_boxes(lon, lat, region)
    qbox = _quad_boxes(inner, outer, u)
    active = boxes_meet(qbox[:, None, :], rbox[None, :, :]).any(-1)
    aq = u[active]
    a_gid, a_k = u_gid[aq], u_k[aq]
    gap = np.diff(a_k, prepend=-(2**40))
    same = np.diff(a_gid, prepend=-1) == 0
    new_run = ~same | (gap > g_maxq[a_gid])
    new_stretch = ~same | (gap != 1)
    stretch_first = np.maximum.accumulate(np.where(new_stretch, np.arange(aq.size), 0))
    new_piece = new_stretch | ((np.arange(aq.size) - stretch_first) % PIECE_QUADS == 0)
    run_id = np.cumsum(new_run) - 1
    starts = np.flatnonzero(new_piece)
    nq = np.diff(np.append(starts, aq.size))
    run_last = np.append(np.flatnonzero(new_run)[1:], aq.size)[: int(new_run.sum())] - 1
    stats = {
        "quads": int(u.size),
        "active_quads": int(aq.size),
        "runs": int(new_run.sum()),
        "pieces": int(starts.size),
    }
    return Runs(
        aq[starts],
        nq,
        a_k[starts],
        run_id[starts],
        a_gid[new_run],
        a_k[new_run],
        a_k[run_last],
        stats,
    )


def point_tiles(lon, lat) -> Tiles:
    """Bucket grid samples into tiles: latitude bands of TILE_BAND_DEG, then by longitude.

    Args:
      lon: float [N], longitudes [deg].
      lat: float [N], latitudes [deg].
    Returns:
      Tiles.
    """
    band = np.floor((lat + 90.0) / TILE_BAND_DEG).astype(np.int64)
    order = np.lexsort((lon, band))
    b = band[order]
    first_in_band = np.searchsorted(b, b, side="left")
    pos = np.arange(b.size) - first_in_band
    new_tile = pos % TILE_SIZE == 0
    tile = np.cumsum(new_tile) - 1
    slot = pos % TILE_SIZE
    n_t = int(new_tile.sum())
    pts = np.full((n_t, TILE_SIZE, 2), np.nan)
    idx = np.full((n_t, TILE_SIZE), -1, np.int32)
    pts[tile, slot, 0], pts[tile, slot, 1] = lon[order], lat[order]
    idx[tile, slot] = order
    box = np.stack(
        [
            np.nanmin(pts[..., 0], 1),
            np.nanmax(pts[..., 0], 1),
            np.nanmin(pts[..., 1], 1),
            np.nanmax(pts[..., 1], 1),
        ],
        -1,
    )
    return Tiles(pts, idx, box)


def _piece_vertices(runs: Runs):
    j = np.arange(PIECE_QUADS + 1)
    return runs.piece_u0[:, None] + np.minimum(j[None, :], runs.piece_nq[:, None])


def _pairs(runs: Runs, tiles: Tiles, inner, outer, vidx):
    """(piece, tile) pairs whose boxes meet; piece boxes unwrapped towards their ref."""
    ref = inner[runs.piece_u0, 0]
    xs = np.concatenate([inner[vidx, 0], outer[vidx, 0]], -1)
    ys = np.concatenate([inner[vidx, 1], outer[vidx, 1]], -1)
    xs = np.asarray(unwrap_lon(xs, ref[:, None]))
    pbox = np.stack([xs.min(-1), xs.max(-1), ys.min(-1), ys.max(-1)], -1)
    pp, tt = [], []
    for p0 in range(0, pbox.shape[0], PIECE_BLOCK):
        m = boxes_meet(pbox[p0 : p0 + PIECE_BLOCK, None, :], tiles.box[None, :, :])
        a, b = np.nonzero(m)
        pp.append(a + p0)
        tt.append(b)
    return (
        np.concatenate(pp or [np.zeros(0, np.int64)]),
        np.concatenate(tt or [np.zeros(0, np.int64)]),
        ref,
    )


_pair_kernel = jax.jit(
    jax.vmap(jax.vmap(quad_range, in_axes=(None, None, None, None, 0)), in_axes=(0, 0, 0, 0, 0))
)


def _run_pairs(pp, tt, vidx, nq, ref, tiles: Tiles, inner, outer):
    """Kernel over pairs in fixed chunks -> hit rows (pair index, slot, first, last, count)."""
    out = []
    for c0 in range(0, pp.size, PAIR_CHUNK):
        m = min(PAIR_CHUNK, pp.size - c0)
        sel = np.zeros(chunk_size(m, MIN_PAIR_CHUNK, PAIR_CHUNK), np.int64)
        sel[:m] = np.arange(c0, c0 + m)
        p, v = pp[sel], vidx[pp[sel]]
        first, last, count = _pair_kernel(inner[v], outer[v], nq[p], ref[p], tiles.pts[tt[sel]])
        count = np.asarray(count)[:m]
        b, slot = np.nonzero(count > 0)
        out.append(
            (b + c0, slot, np.asarray(first)[b, slot], np.asarray(last)[b, slot], count[b, slot])
        )
    return out


def sweep_pairs(runs: Runs, tiles: Tiles, inner, outer) -> SweepHits:
    """Per (run, grid sample) the first and last containing quad of the run.

    Args:
      runs: Runs from :func:`group_runs`.
      tiles: Tiles from :func:`point_tiles`.
      inner: float [U, 2], inner-edge (lon, lat) of the union samples [deg].
      outer: float [U, 2], outer-edge (lon, lat) [deg].
    Returns:
      SweepHits.
    """
    vidx = _piece_vertices(runs)
    pp, tt, ref = _pairs(runs, tiles, inner, outer, vidx)
    rows = _run_pairs(pp, tt, vidx, runs.piece_nq, ref, tiles, inner, outer)
    cat = [
        np.concatenate([r[i] for r in rows]) if rows else np.zeros(0, np.int64) for i in range(5)
    ]
    pair, slot, first, last, count = cat
    piece = pp[pair]
    run = runs.piece_run[piece]
    sample = tiles.idx[tt[pair], slot].astype(np.int64)
    first = runs.piece_k0[piece] + first
    last = runs.piece_k0[piece] + last
    n_pts = int(tiles.idx.max()) + 1 if tiles.idx.size else 1
    order = np.argsort(run * n_pts + sample, kind="stable")
    run, sample, first, last, count = (x[order] for x in (run, sample, first, last, count))
    new = np.ones(run.size, bool)
    new[1:] = (run[1:] != run[:-1]) | (sample[1:] != sample[:-1])
    at = np.flatnonzero(new)
    if at.size:
        first = np.minimum.reduceat(first, at)
        last = np.maximum.reduceat(last, at)
        count = np.add.reduceat(count, at)
        run, sample = run[at], sample[at]
    irregular = np.zeros(runs.run_gid.size, bool)
    irregular[np.unique(run[(last - first > 1) | (count != last - first + 1)])] = True
    span = int(runs.run_end.max()) + 2 if runs.run_end.size else 1
    order = np.argsort((run * span + first) * span + last, kind="stable")
    stats = {
        "pairs": int(pp.size),
        "point_quad_tests": int(pp.size) * TILE_SIZE * PIECE_QUADS,
        "run_sample_entries": int(run.size),
        "irregular_runs": int(irregular.sum()),
    }
    return SweepHits(
        run[order], sample[order].astype(np.int32), first[order], last[order], irregular, stats
    )
