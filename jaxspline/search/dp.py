"""The per-satellite longest-path DP of the bound, every satellite in one pass over start blocks.

Relaxing "each target is imaged at most once" with prices splits the problem into one
longest-path problem per satellite over its options in start order:
``best[j] = w_j + max(base_j, far predecessors, near compatible predecessors)`` with
``base_j = 0`` where j may be its satellite's first observation (else ``-inf``), far
predecessors (gap >= ``far[sat]``, always compatible) through a running maximum per
satellite, and near ones through the screened feasible pairs (:class:`NearPairs`).

All satellites advance together: options are cut into blocks of starts at most
``width`` apart (:func:`dp_prepare`); a block's predecessors all start before it, so
one block is one vectorized step (:func:`dp_forward`, numpy; :mod:`jaxspline.search.dp_jax`
holds the same recursion as one ``jax.lax.scan``). The block layout (absorbed options,
pair ranges, rows with pairs) is computed once per problem, so a step is a handful of
numpy calls on slices. :func:`backtrack` recovers each satellite's optimal sequence from
``best``; :func:`dp_paths` is forward + backtrack.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np

from jaxspline.search.problem import Problem

__all__ = ["DPData", "NeedPrice", "backtrack", "dp_forward", "dp_paths", "dp_prepare"]

_PATH_TOL = 1e-9  # tolerance of the path back-tracking
_CHUNK_BLOCKS = 64  # the most blocks whose absorbs one forward step applies at once


@dataclass
class DPData:
    """Structure of the per-satellite longest-path DP (module docstring).

    Options are processed in start order (``order``, the row order of ``pb.pairs``)
    in blocks of starts at most ``width`` apart (``groups``: slices of ``order``, so a
    block's near predecessors are one contiguous range of ``pb.pairs``). With
    ``width`` <= the shortest observation, a predecessor of any option of a block
    starts before the block, so a block is one vectorized step; with
    ``width`` <= ``near_slack``, a far predecessor that only becomes far inside the
    block (``end + far`` between the block's first start and the option's start) is
    among the near pairs. ``absorb`` lists options by ``end + far[sat]``, the time
    from which they are far predecessors of everything.

    Attributes:
      order: int [N], option ids sorted by start (then satellite).
      sat: int [N], satellite of each option.
      start: float [N], start time of each option [s].
      groups: list of ``(ga, gb)``: block ``order[ga:gb]``.
      first_ok: bool [N], the option may be its satellite's first observation.
      absorb: int [N], option ids sorted by ``end + far[sat]``.
      absorb_t: float [N], those times [s] (sorted across blocks; within the range a
        block absorbs, ``absorb`` is by satellite).
      absorb_at: int [B + 1], block b absorbs ``absorb[absorb_at[b]:absorb_at[b + 1]]``
        into the running maxima before its step.
      sat_order: int [N], ``sat[order]``.
      base_order: float [N], ``0`` where ``order[i]`` may be first, else ``-inf``.
      ready: float [N], ``end + far[sat]`` of each option: from then on it is a far
        predecessor of every option of its satellite [s].
      target: int [N], target of each option (an area option: a number of its own,
        ``n_targets`` and up, so no two of them are a repeat).
      repeat_pos, repeat_dst: positions (``pb.pairs`` order, ascending) and destinations
        of the near pairs joining two options of one target (a repeat);
        repeat_at: int [B + 1], block b's repeats are ``repeat_pos[repeat_at[b]:repeat_at[b + 1]]``.
      absorb_sats, absorb_cuts: per block the satellites of its absorbed options and
        where each satellite's run starts (``absorb`` is by satellite within a block).
      rows_at: per block the first pair of each row up to its last row with pairs
        (0-based in the block's pair range); rows_pen: per such row ``-inf`` if it
        has no pair, else 0.
      max_pairs: the most near pairs of one block (the size of the forward pass's buffer).
      steps: per block the bounds and slices of one forward step (see ``_steps``).
      chunks: runs of consecutive blocks whose absorbed options all lie in earlier
        runs, so their running maxima are found at once (see ``_chunks``).
    """

    order: np.ndarray
    sat: np.ndarray
    start: np.ndarray
    groups: list
    first_ok: np.ndarray
    absorb: np.ndarray
    absorb_t: np.ndarray
    absorb_at: np.ndarray | None = None
    sat_order: np.ndarray | None = None
    base_order: np.ndarray | None = None
    ready: np.ndarray | None = None
    target: np.ndarray | None = None
    repeat_pos: np.ndarray | None = None
    repeat_dst: np.ndarray | None = None
    repeat_at: np.ndarray | None = None
    absorb_sats: list | None = None
    absorb_cuts: list | None = None
    rows_at: list | None = None
    rows_pen: list | None = None
    max_pairs: int = 0
    steps: list | None = None
    chunks: list | None = None


@dataclass(frozen=True)
class NeedPrice:
    """Near-pair costs proportional to the pair's required time, priced by destination:
    pair ``i -> j`` costs ``rate[j] * max(need - tol, 0)``.

    The DP derives them block by block where it reads the pairs (:func:`dp_forward`,
    :func:`backtrack`), so no array the size of the pair table is made.

    Attributes:
      rate: float [N], price per second of required time into each option.
      need: float32 [P], the pairs' required times (``pb.pairs.need``).
      tol: seconds taken off each required time before pricing.
    """

    rate: np.ndarray
    need: np.ndarray
    tol: float

    def of(self, pairs, dst_rate: np.ndarray) -> np.ndarray:
        """Costs of the pairs ``pairs`` (a slice or positions) whose destinations' rates
        are ``dst_rate`` (the same arithmetic wherever the DP asks: float64 throughout)."""
        out = self.need[pairs].astype(np.float64)
        out -= self.tol
        np.maximum(out, 0.0, out=out)
        out *= dst_rate
        return out


def _block_bounds(so: np.ndarray, width: float) -> list:
    """Block limits over sorted starts ``so``: each block spans at most ``width`` [s]."""
    n = so.size
    bounds = [0]
    while bounds[-1] < n:
        b0 = bounds[-1]
        b1 = int(np.searchsorted(so, so[b0] + width, side="right"))
        bounds.append(max(b1, int(np.searchsorted(so, so[b0], side="right"))))
    return bounds


def dp_prepare(pb: Problem) -> DPData:
    """Group the options in start-order blocks for :func:`dp_forward` (computed once).

    Args:
      pb: Problem.
    Returns:
      DPData.
    """
    n = pb.n_options
    s = np.asarray(pb.option_start, np.float64)
    e = np.asarray(pb.option_end, np.float64)
    sat = np.asarray(pb.option_sat, np.int64)
    far = np.asarray(pb.far, np.float64)
    order = pb.pairs.rows  # start order (Problem keeps the pair rows so)
    so = s[order]
    width = min(float(np.min(e - s)), pb.near_slack) if n else 0.0
    bounds = _block_bounds(so, width)
    groups = list(zip(bounds[:-1], bounds[1:], strict=True))
    rt = e + far[sat] if n else np.zeros(0)
    ab = np.argsort(rt, kind="stable")
    first_ok = np.asarray(pb.option_first, np.float64) <= s
    absorb_t = rt[ab]
    # block b absorbs every option far (end + far <= its first start) by then
    absorb_at = np.r_[0, np.searchsorted(absorb_t, so[bounds[:-1]], side="right")]
    absorb_at = np.maximum.accumulate(absorb_at).astype(np.int64)
    # within each block's absorbed range, options by satellite (one reduceat a block)
    blk = np.repeat(np.arange(len(groups)), np.diff(absorb_at))
    ab[: absorb_at[-1]] = ab[: absorb_at[-1]][np.lexsort((sat[ab[: absorb_at[-1]]], blk))]
    absorb_t = rt[ab]
    absorb_sats, absorb_cuts, rows_at, rows_pen, rep = [], [], [], [], []
    ptr, src = pb.pairs.ptr, pb.pairs.src
    tg = np.asarray(pb.option_target, np.int64)
    closed = pb.closed_options()
    if closed is not None:  # area options and looks: numbers of their own, never repeats
        area = np.flatnonzero(closed)
        tg = tg.copy()
        tg[area] = pb.n_targets + np.arange(area.size)
    for b, (ga, gb) in enumerate(groups):
        ks = sat[ab[absorb_at[b] : absorb_at[b + 1]]]
        cut = np.flatnonzero(np.r_[True, ks[1:] != ks[:-1]]) if ks.size else ks
        absorb_sats.append(ks[cut])
        absorb_cuts.append(cut)
        cnt = np.diff(ptr[ga : gb + 1])
        m = int(np.flatnonzero(cnt)[-1]) + 1 if cnt.any() else 0  # rows to the last with pairs
        rows_at.append(ptr[ga : ga + m] - ptr[ga])
        rows_pen.append(np.where(cnt[:m] == 0, -np.inf, 0.0))
        dst = np.repeat(order[ga:gb], cnt)  # one block's pairs at a time (memory)
        rep.append(np.flatnonzero(tg[src[ptr[ga] : ptr[gb]]] == tg[dst]) + ptr[ga])
    repeat_pos = np.concatenate(rep) if rep else np.zeros(0, np.int64)
    repeat_at = np.r_[0, np.cumsum([r.size for r in rep])].astype(np.int64)
    d = DPData(
        order=order,
        sat=sat,
        start=s,
        groups=groups,
        first_ok=first_ok,
        absorb=ab,
        absorb_t=absorb_t,
        absorb_at=absorb_at,
        sat_order=sat[order],
        base_order=np.where(first_ok, 0.0, -np.inf)[order],
        ready=rt,
        target=tg,
        repeat_pos=repeat_pos,
        repeat_dst=pb.pairs.rows[np.searchsorted(ptr, repeat_pos, side="right") - 1],
        repeat_at=repeat_at,
        absorb_sats=absorb_sats,
        absorb_cuts=absorb_cuts,
        rows_at=rows_at,
        rows_pen=rows_pen,
        max_pairs=int(np.diff(ptr[bounds]).max()) if len(bounds) > 1 else 0,
    )
    d.steps = _steps(d, ptr)
    d.chunks = _chunks(d, pb.n_sats, float(np.min(far)) if far.size else 0.0)
    return d


def _steps(d: DPData, ptr: np.ndarray) -> list:
    """Per block the Python ints and slices :func:`dp_forward` needs (no per-pass indexing).

    One tuple a block: ``(ga, gb, pa, pz, rows_at, rows_pen, ra, rz, rep_local)`` with
    ``rows_pen`` None where every row has pairs and ``rep_local`` the block's repeat
    positions relative to its first pair ``pa``.
    """
    steps = []
    for b, (ga, gb) in enumerate(d.groups):
        pa, pz = int(ptr[ga]), int(ptr[gb])
        ra, rz = int(d.repeat_at[b]), int(d.repeat_at[b + 1])
        pen = d.rows_pen[b] if np.isinf(d.rows_pen[b]).any() else None
        steps.append(
            (int(ga), int(gb), pa, pz, d.rows_at[b], pen, ra, rz, d.repeat_pos[ra:rz] - pa)
        )
    return steps


def _chunks(d: DPData, n_sats: int, far_min: float) -> list:
    """Runs of blocks starting less than ``far_min`` after the run's first block.

    An option absorbed by block b (``end + far <= start(b)``) then starts before the
    run's first block, so every running maximum of the run comes from values known when
    the run begins. One tuple a run: ``(b0, b1, aa, az, cuts, mpos, ga, gb, vpos)``:
    blocks ``b0..b1-1``, their absorbed options ``absorb[aa:az]`` cut by (block,
    satellite) at ``cuts``, each cut's place ``mpos`` in the flat ``[b1 - b0 + 1, S]``
    table of running maxima (row 0: before the run; row ``1 + i``: after block
    ``b0 + i``), and for the run's options ``order[ga:gb]`` their place ``vpos`` in it.
    """
    so = d.start[d.order]
    first = np.array([so[ga] for ga, _ in d.groups])
    chunks, b0, n_b = [], 0, len(d.groups)
    while b0 < n_b:
        b1 = int(np.searchsorted(first, first[b0] + far_min, side="left"))
        b1 = max(b0 + 1, min(b1, b0 + _CHUNK_BLOCKS, n_b))
        aa = int(d.absorb_at[b0])
        cuts = [d.absorb_cuts[b] + (int(d.absorb_at[b]) - aa) for b in range(b0, b1)]
        mpos = [(1 + b - b0) * n_sats + d.absorb_sats[b] for b in range(b0, b1)]
        ga, gb = d.groups[b0][0], d.groups[b1 - 1][1]
        sizes = [hi - lo for lo, hi in d.groups[b0:b1]]
        vpos = (1 + np.repeat(np.arange(b1 - b0), sizes)) * n_sats + d.sat_order[ga:gb]
        chunks.append(
            (b0, b1, aa, int(d.absorb_at[b1]), np.concatenate(cuts), np.concatenate(mpos))
            + (ga, gb, vpos)
        )
        b0 = b1
    return chunks


def _rates(arc: NeedPrice, d: DPData, ga: int, rows_at, n_pairs: int) -> np.ndarray:
    """Each pair's destination rate in the block starting at ``order[ga]`` (its rows
    ``rows_at``, ``n_pairs`` pairs)."""
    counts = np.diff(np.append(rows_at, n_pairs))
    return np.repeat(arc.rate[d.order[ga : ga + counts.size]], counts)


def dp_forward(
    pb: Problem, d: DPData, w: np.ndarray, arc=None, merge_repeats: bool = False
) -> np.ndarray:
    """The DP values ``best`` (float [N]) of every option for option values ``w``.

    One block a step, into preallocated buffers (a block's near pairs are gathered
    into ``buf`` by ``np.take``; the per-block bounds are Python ints of ``d.steps``).
    The running maxima and their part of each option's value are found a run of
    blocks at a time (``d.chunks``).

    Args:
      pb: Problem.
      d: its :func:`dp_prepare`.
      w: float [N], option values.
      arc: optional float [P], the cost of each near pair (``pb.pairs`` order), or a
        :class:`NeedPrice` deriving them.
      merge_repeats: an option reached from an option of its own target through a near
        pair adds nothing (its value ``w`` is that pair's cost): consecutive repeats of
        a target count once (see :mod:`jaxspline.search.lagrangian`).
    Returns:
      float [N]: the best value of a sequence ending with each option (``-inf``: none).
    """
    src, n_s = pb.pairs.src, pb.n_sats
    best = np.full(len(w), -np.inf)
    run = np.full(n_s, -np.inf)
    order, base_o, absorb = d.order, d.base_order, d.absorb
    w_o = w[order]
    w_rep = w[d.repeat_dst] if merge_repeats else None
    buf = np.empty(d.max_pairs)
    priced = isinstance(arc, NeedPrice)
    for b0, b1, aa, az, cuts, mpos, g0, g1, vpos in d.chunks:
        m = np.full((b1 - b0 + 1) * n_s, -np.inf)  # running maxima before / after each block
        m[:n_s] = run
        if az > aa:  # options far from here on: into their satellites' running maxima
            m[mpos] = np.maximum.reduceat(best[absorb[aa:az]], cuts)
        m = np.maximum.accumulate(m.reshape(b1 - b0 + 1, n_s), axis=0)
        run = m[-1]
        val = m.reshape(-1)[vpos]
        np.maximum(base_o[g0:g1], val, out=val)
        for ga, gb, pa, pz, rows_at, pen, ra, rz, rloc in d.steps[b0:b1]:
            v = val[ga - g0 : gb - g0]
            if pz > pa:
                pv = np.take(best, src[pa:pz], out=buf[: pz - pa], mode="clip")
                if priced:
                    rates = _rates(arc, d, ga, rows_at, pz - pa)
                    np.subtract(pv, arc.of(slice(pa, pz), rates), out=pv)
                elif arc is not None:
                    np.subtract(pv, arc[pa:pz], out=pv)
                if merge_repeats and rz > ra:
                    pv[rloc] -= w_rep[ra:rz]
                near = np.maximum.reduceat(pv, rows_at)
                if pen is not None:
                    near += pen  # rows without pairs: -inf
                vm = v[: near.size]
                np.maximum(vm, near, out=vm)
            v += w_o[ga:gb]
            best[order[ga:gb]] = v
    return best


def _far_predecessor(pb: Problem, d: DPData, best, top, j: int, rest) -> int:
    """Lowest-id far predecessor of option j providing ``rest`` (-1: none).

    ``top`` is the running maximum of ``best`` over each satellite's ids (:func:`backtrack`):
    ids before the first one whose running maximum reaches ``rest`` provide less, so the
    scan starts there (the same option as a scan from the satellite's first id).
    """
    lo = pb.sat_lo[d.sat[j]]
    need = rest - _PATH_TOL
    i0 = lo + int(np.searchsorted(top[lo:j], need))
    fp = i0 + np.flatnonzero(d.ready[i0:j] <= d.start[j])  # ids below j start earlier
    hit = fp[best[fp] >= need]
    return int(hit[0]) if hit.size else -1


def _running_max(pb: Problem, best: np.ndarray) -> np.ndarray:
    """Running maximum of ``best`` over each satellite's option ids (float [N])."""
    top = np.empty_like(best)
    for lo, hi in zip(pb.sat_lo, pb.sat_hi, strict=True):
        np.maximum.accumulate(best[lo:hi], out=top[lo:hi])
    return top


def _near_step(pb: Problem, d: DPData, w, best, arc, merge_repeats, node, rest):
    """One back-tracking step of several satellites at once (one current option each).

    For each option ``node[i]`` the first (lowest-id) near predecessor providing
    ``rest[i]``, as the per-row scan of :func:`backtrack` finds it, over the
    concatenated rows.

    Returns:
      (pos, prev): int arrays: the pair position and predecessor option of each node,
      ``-1`` where no near predecessor provides the value.
    """
    ptr, r = pb.pairs.ptr, pb.pairs.row_of[node]
    q0 = ptr[r]
    cnt = ptr[r + 1] - q0
    seg = np.cumsum(cnt) - cnt  # each row's first element in the concatenation
    idx = np.arange(int(cnt.sum()), dtype=np.int64) + np.repeat(q0 - seg, cnt)
    s = pb.pairs.src[idx]
    cv = best[s]
    if isinstance(arc, NeedPrice):
        cv -= arc.of(idx, np.repeat(arc.rate[node], cnt))
    elif arc is not None:
        cv -= arc[idx]
    if merge_repeats:  # a repeat of the node's target costs the node's value
        m = d.target[s] == np.repeat(d.target[node], cnt)
        cv[m] -= np.repeat(w[node], cnt)[m]
    hits = np.flatnonzero(cv >= np.repeat(rest - _PATH_TOL, cnt))
    pos = np.full(node.size, -1, np.int64)
    prev = np.full(node.size, -1, np.int64)
    if hits.size:
        f = hits[np.minimum(np.searchsorted(hits, seg), hits.size - 1)]
        ok = (f >= seg) & (f < seg + cnt)  # the row's first hit, if it has one
        pos[ok], prev[ok] = idx[f[ok]], s[f[ok]]
    return pos, prev


def _walk(pb: Problem, d: DPData, w, best, top, merge_repeats, j: int, steps: list) -> list:
    """One satellite's path back from option j without pair costs, scalar by scalar.

    Each row is scanned from its first source at or after the first id whose running
    maximum ``top`` reaches the value: the sources before provide less (a repeat's cost
    ``w[j] >= 0`` only lowers them), so a step reads a few pairs, not the whole row.
    Where ``merge_repeats`` and ``w[j] < 0`` (a repeat worth more than its source) the
    row is scanned whole. Near-pair positions are appended to ``steps``.

    Returns:
      the path, from its end.
    """
    src, ptr, row_of = (memoryview(a) for a in (pb.pairs.src, pb.pairs.ptr, pb.pairs.row_of))
    bm, wm, tm, tg = memoryview(best), memoryview(w), memoryview(top), memoryview(d.target)
    first_ok, lo = memoryview(d.first_ok), pb.sat_lo[d.sat[j]]
    path = [j]
    while True:
        rest = bm[j] - wm[j]  # the value the predecessor (or the start) provides
        if first_ok[j] and rest <= _PATH_TOL:
            break
        need, wj, tj = rest - _PATH_TOL, wm[j], tg[j]
        r = row_of[j]
        q, q1 = ptr[r], ptr[r + 1]
        if not (merge_repeats and wj < 0.0):
            q = bisect.bisect_left(src, bisect.bisect_left(tm, need, lo, j), q, q1)
        while q < q1:
            i = src[q]
            if bm[i] - (wj if merge_repeats and tg[i] == tj else 0.0) >= need:
                break
            q += 1
        if q < q1:
            steps.append(q)
            j = src[q]
        else:
            j = _far_predecessor(pb, d, best, top, j, rest)
            if j < 0:  # cannot happen; stop defensively
                break
        path.append(j)
    return path


def backtrack(pb: Problem, d: DPData, w, best, arc=None, used=None, merge_repeats=False):
    """Each satellite's optimal sequence from the DP values ``best`` of :func:`dp_forward`.

    Walks back from each satellite's best option: the first near predecessor (lowest
    id) that provides the value, else the first far one, until a first observation.
    Without pair costs one satellite at a time, a few pairs a step (:func:`_walk`);
    with them all satellites together, one step of every unfinished path per numpy
    pass over the current options' rows (:func:`_near_step`). Far predecessors (rare)
    are found one at a time.

    Args:
      pb: the problem; d: its :class:`DPData`.
      w: option values, as :func:`dp_forward`.
      best: the result of :func:`dp_forward`.
      arc: optional per-pair costs, as :func:`dp_forward`.
      used: optional list; the near-pair positions of the paths are appended to it
        (satellite by satellite, each path from its end).
      merge_repeats: as :func:`dp_forward`.
    Returns:
      ``(paths, values)``: per satellite the option ids of an optimal sequence (time
      order) and its value (0 for the empty sequence).
    """
    n_s = pb.n_sats
    paths, values, steps = [[] for _ in range(n_s)], [0.0] * n_s, [[] for _ in range(n_s)]
    for k in range(n_s):
        lo, hi = pb.sat_lo[k], pb.sat_hi[k]
        if hi > lo and best[lo:hi].max() > 0.0:
            paths[k].append(lo + int(np.argmax(best[lo:hi])))
            values[k] = float(best[paths[k][0]])
    best = np.ascontiguousarray(best, np.float64)  # read through memoryviews
    top = _running_max(pb, best)
    if arc is None:
        w = np.ascontiguousarray(w, np.float64)
        for k in range(n_s):
            if paths[k]:
                paths[k] = _walk(pb, d, w, best, top, merge_repeats, paths[k][0], steps[k])
    else:
        _walk_all(pb, d, (w, best, arc, top), merge_repeats, paths, steps)
    if used is not None:
        used.extend(q for k in range(n_s) for q in steps[k])
    return [p[::-1] for p in paths], values


def _walk_all(pb: Problem, d: DPData, arrays, merge_repeats, paths, steps) -> None:
    """All satellites' paths back together (:func:`backtrack` with pair costs), extending
    ``paths`` (each holding its end option) and ``steps`` (near-pair positions)."""
    w, best, arc, top = arrays
    sats = np.flatnonzero([len(p) > 0 for p in paths])
    node = np.asarray([paths[k][0] for k in sats.tolist()], np.int64)
    while sats.size:
        rest = best[node] - w[node]  # the value the predecessor (or the start) provides
        go = ~(d.first_ok[node] & (rest <= _PATH_TOL))
        sats, node, rest = sats[go], node[go], rest[go]
        pos, prev = _near_step(pb, d, w, best, arc, merge_repeats, node, rest)
        for i in np.flatnonzero(prev < 0).tolist():
            prev[i] = _far_predecessor(pb, d, best, top, int(node[i]), rest[i])
        for k, q, j in zip(sats.tolist(), pos.tolist(), prev.tolist(), strict=True):
            if q >= 0:
                steps[k].append(q)
            if j >= 0:
                paths[k].append(j)
        sats, node = sats[prev >= 0], prev[prev >= 0]  # -1: cannot happen; stop defensively


def dp_paths(pb: Problem, d: DPData, w: np.ndarray, arc=None, used=None, merge_repeats=False):
    """Exact per-satellite maximum-value sequences for option values ``w``.

    Args:
      pb: Problem.
      d: its :func:`dp_prepare`.
      w: float [N], option values.
      arc: optional cost of each near pair, in ``pb.pairs`` order (far transitions and
        first observations cost nothing).
      used: optional list; the near-pair positions (``pb.pairs`` order) of the
        returned paths are appended to it.
      merge_repeats: as :func:`dp_forward`.
    Returns ``(paths, values)``: per satellite the option ids of an optimal sequence
    (time order) and its value (0 for the empty sequence). Battery not modelled.
    """
    best = dp_forward(pb, d, w, arc, merge_repeats)
    return backtrack(pb, d, w, best, arc, used, merge_repeats)
