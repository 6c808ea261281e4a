"""Which looks make a stereo product: every valid pair and triple of a target's looks.

From the candidate looks of :func:`jaxspline.geometry.stereo_looks.stereo_looks`, per
stereo target (its :class:`~jaxspline.readers.stereo_request.Stereo` request), all in
numpy matrices over the target's looks (no loop over pairs):

* **Mode**: two looks of one satellite in one access interval (the same pass), or of
  two satellites when ``cross_satellite``; their midpoints at most ``max_separation``
  apart. Two looks of one satellite must also fit one after the other: the later starts
  after the earlier ends with a gap of at least the satellite's rest-to-rest slew
  between the earlier's end boresight and the later's start boresight (its maneuver
  model's ``slew_time``, settling and the planner's gap margin included).
* **Overlap**: the share of :data:`OVERLAP_POINTS` points of a sunflower lattice over the
  disk (equal-area points, a deterministic quadrature of the area share) inside both
  strips; a strip is the set of points within its half-width of its ground-track
  polyline, both laid flat in the target's geocentric east / north plane (capsules,
  stereo_imaging RULES.md "Overlap"). The benchmark estimates the same share with 100
  seeded random points (80 for a triple's pairs): a pair counts with ``min_overlap +
  overlap_margin``, and each product carries its *confidence*, the chance that the
  benchmark's estimates pass (:func:`pass_probability`: binomial tails of the lattice
  share; a triple's common overlap with 100 points times at least two of its valid
  pairs with 80). The default margin, :data:`OVERLAP_MARGIN`, only covers the lattice's
  own error, so products the benchmark passes by chance are kept, with a confidence
  below 1 (a failed overlap is no violation: the product just does not count); with
  :data:`SAFE_OVERLAP_MARGIN` every kept product passes all but once in ~1000 draws.
* **Pair**: in mode, overlap as above, convergence (the angle at the centre between the
  two satellites at their midpoints) within ``convergence`` less
  :data:`CONVERGENCE_MARGIN`, pixel-scale ratio within ``max_scale_ratio`` less
  :data:`RATIO_MARGIN` (not tested when a satellite has no ``ifov``). Quality
  ``Q = w_g Qg + w_o Qo + w_r Qr`` (:func:`pair_quality`).
* **Triple** (``product = "tri"``): every two of its looks in mode, common overlap
  (all three strips) with the margin, at least two valid pairs among its three, one look
  within ``anchor_off_nadir`` of nadir (the anchor); quality ``min(1, best valid pair +
  tri_bonus)``. Enumerated per anchor look ``a``: a look ``b`` making a valid pair with
  ``a`` and any look ``c`` in mode with both.

Kept per target (:func:`select_products`): at most :data:`PAIRS_PER_TARGET` pairs and
:data:`TRIPLES_PER_TARGET` triples, best expected quality (quality times confidence)
first, ties by the earliest end; at most
:data:`PER_GROUP` of them from one *group* (the same satellites and access intervals)
before any product of a group already that full, so that the search finds alternatives
on other passes when looks conflict. Angles in radians, lengths in metres, times in
seconds.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from jaxspline.base.elements import geodetic_to_ecef
from jaxspline.geometry.frames import angle_between
from jaxspline.geometry.ground import local_axes
from jaxspline.geometry.stereo_looks import StereoLooks

__all__ = [
    "CONVERGENCE_MARGIN",
    "FULL_OVERLAP",
    "OVERLAP_MARGIN",
    "OVERLAP_POINTS",
    "PAIRS_PER_TARGET",
    "PER_GROUP",
    "RATIO_MARGIN",
    "SAFE_OVERLAP_MARGIN",
    "TRIPLES_PER_TARGET",
    "StereoProducts",
    "disk_points",
    "empty_products",
    "pair_quality",
    "pass_probability",
    "select_products",
    "strip_masks",
    "stereo_products",
]

#: Lattice points of the overlap quadrature over one disk.
OVERLAP_POINTS = 512
#: Overlap a product keeps above ``min_overlap`` by default: the lattice's error against
#: exact areas (at most 0.014 over 200 random capsule pairs) and against the benchmark
#: checker's finer lattice (at most 0.012 over ~1100 products of five cases).
OVERLAP_MARGIN = 0.02
#: A margin whose products the benchmark's 100-point estimate fails about once in 1000
#: draws (an area share of 0.9; 0.85 fails once in 15, 0.82 once in 3).
SAFE_OVERLAP_MARGIN = 0.1
#: Random points of the benchmark's overlap estimates: a pair or a triple's common
#: overlap, and each pair inside a triple.
CHECK_POINTS, EDGE_POINTS = 100, 80
#: Convergence kept inside the accepted range [rad] (orbit models differ by ~150 m).
CONVERGENCE_MARGIN = math.radians(0.05)
#: Relative pixel-scale ratio kept below ``max_scale_ratio``.
RATIO_MARGIN = 1e-3
#: Anchor off-nadir kept below ``anchor_off_nadir`` [rad] (written angles are rounded).
ANCHOR_MARGIN = 1e-6
#: Overlap at which Qo saturates; ratio excess at which Qr reaches 0; convergence
#: distance from the band at which Qg reaches 0 [rad].
FULL_OVERLAP = 0.95
RATIO_SPAN = 0.5
BAND_FALLOFF = math.radians(10.0)
#: Products kept per target: pairs, triples, and from one group before the rest.
PAIRS_PER_TARGET = 96
TRIPLES_PER_TARGET = 64
PER_GROUP = 8
_GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


class StereoProducts(NamedTuple):
    """P stereo products (numpy, leading axis P), grouped by target.

    Attributes:
      looks: int64 [P, 3], its looks (ids of the caller's looks; -1 pads a pair).
      target: int64 [P], the target's row in ``scenario.targets``.
      quality: float [P], its quality (pair or triple formula).
      size: int64 [P], 2 (pair) or 3 (triple).
      convergence: float [P], a pair's convergence, a triple's best valid pair's [rad].
      overlap: float [P], the share of the disk in all its strips.
      scale_ratio: float [P], largest over smallest pixel scale of its looks (1 when
        unknown).
      confidence: float [P], chance that the benchmark's overlap estimates find it
        valid (:func:`pass_probability`).
    """

    looks: np.ndarray
    target: np.ndarray
    quality: np.ndarray
    size: np.ndarray
    convergence: np.ndarray
    overlap: np.ndarray
    scale_ratio: np.ndarray
    confidence: np.ndarray

    def __len__(self) -> int:
        return int(self.target.shape[0])

    def take(self, idx) -> StereoProducts:
        """The products ``idx`` (int or bool index along P), in that order."""
        return StereoProducts(*(np.asarray(x)[idx] for x in self))


def empty_products() -> StereoProducts:
    """A :class:`StereoProducts` of no product."""
    f = np.zeros(0)
    i = np.zeros(0, np.int64)
    return StereoProducts(np.zeros((0, 3), np.int64), i, f, i, f, f, f, f)


def disk_points(radius: float, n: int = OVERLAP_POINTS) -> np.ndarray:
    """A sunflower (Vogel) lattice of ``n`` equal-area points over a disk.

    Point k at radius ``R sqrt((k + 1/2) / n)`` and angle ``k pi (3 - sqrt 5)``.

    Args:
      radius: disk radius R [m].
      n: number of points.
    Returns:
      float [n, 2], (east, north) [m].
    """
    k = np.arange(n, dtype=np.float64)
    r = radius * np.sqrt((k + 0.5) / n)
    return np.stack([r * np.cos(k * _GOLDEN_ANGLE), r * np.sin(k * _GOLDEN_ANGLE)], -1)


def strip_masks(track_en, half_width, points) -> np.ndarray:
    """Which points lie in which strip: within its half-width of its polyline.

    Distance to a segment ``a b``: ``|p - a - u (b - a)|`` with ``u = clip((p - a).(b -
    a) / |b - a|^2, 0, 1)`` (0 for a segment of length 0).

    Args:
      track_en: float [L, K, 2], polylines in the plane [m] (repeated points allowed).
      half_width: float [L], half-widths [m].
      points: float [N, 2] [m].
    Returns:
      bool [L, N].
    """
    a = track_en[:, :-1, None, :]
    ab = (track_en[:, 1:] - track_en[:, :-1])[:, :, None, :]
    rel = points[None, None, :, :] - a
    len2 = np.sum(ab * ab, axis=-1)
    u = np.clip(np.sum(rel * ab, axis=-1) / np.where(len2 > 0, len2, 1.0), 0.0, 1.0)
    d2 = np.sum((rel - u[..., None] * ab) ** 2, axis=-1).min(axis=1)
    return d2 <= np.asarray(half_width)[:, None] ** 2


def pass_probability(share, n: int, threshold: float) -> np.ndarray:
    """Chance that ``n`` uniform random points estimate an area ``share`` at or above
    ``threshold``: ``P(X >= k)`` for ``X ~ Binomial(n, share)``, ``k = ceil(n threshold)``
    (the benchmark's test ``X / n + 1e-6 >= threshold``).

    Args:
      share: float [...], area shares in [0, 1]; n: number of points;
      threshold: the least share accepted.
    Returns:
      float [...].
    """
    p = np.clip(np.asarray(share, np.float64), 0.0, 1.0)[..., None]
    k = math.ceil(n * threshold - 1e-6 * n)
    j = np.arange(k, n + 1, dtype=np.float64)
    log_c = np.array([math.lgamma(n + 1) - math.lgamma(x + 1) - math.lgamma(n - x + 1) for x in j])
    with np.errstate(divide="ignore", invalid="ignore"):  # 0 log 0 = 0
        lp = np.where(j > 0, j * np.log(p), 0.0)
        lq = np.where(n - j > 0, (n - j) * np.log1p(-p), 0.0)
    return np.exp(log_c + lp + lq).sum(axis=-1).clip(0.0, 1.0)


def pair_quality(convergence, overlap, ratio, request) -> np.ndarray:
    """Pair quality ``w_g Qg + w_o Qo + w_r Qr`` of a request's weights (broadcasting).

    ``Qg = max(0, 1 - e / 10 deg)`` with ``e`` the distance to the preferred ``band``
    (0 inside, edges included); ``Qo = min(1, overlap / 0.95)``; ``Qr = max(0, 1 -
    (ratio - 1) / 0.5)``.

    Args:
      convergence: float [...] [rad]; overlap: float [...], share of the disk;
      ratio: float [...], pixel-scale ratio (>= 1); request: its Stereo.
    Returns:
      float [...].
    """
    lo, hi = request.band
    e = np.maximum(0.0, np.maximum(lo - convergence, convergence - hi))
    wg, wo, wr = request.weights
    return (
        wg * np.maximum(0.0, 1.0 - e / BAND_FALLOFF)
        + wo * np.minimum(1.0, overlap / FULL_OVERLAP)
        + wr * np.maximum(0.0, 1.0 - (ratio - 1.0) / RATIO_SPAN)
    )


class _Target(NamedTuple):
    """One target's looks and their pair tables (matrices over its L looks)."""

    idx: np.ndarray  # int [L], the looks (ids)
    masks: np.ndarray  # float [L, N], 1 inside the strip
    mode: np.ndarray  # bool [L, L]
    fine: np.ndarray  # bool [L, L]: in mode, convergence and scale ratio pass
    valid: np.ndarray  # bool [L, L]: fine, and the overlap with its margin
    quality: np.ndarray  # float [L, L]
    overlap: np.ndarray  # float [L, L]
    conv: np.ndarray  # float [L, L]
    ratio: np.ndarray  # float [L, L]
    group: np.ndarray  # int [L], its (satellite, access) label


def _compatible(sc, looks: StereoLooks, idx) -> np.ndarray:
    """bool [L, L]: two looks of other satellites, or of one satellite one after the
    other with the slew and settling between them (module docstring, Mode); a model
    without a rest-to-rest slew law (per-channel) gets the least time its fastest
    channel needs, a lower bound: the search checks the exact transition."""
    sat = looks.sat[idx]
    t0, t1 = looks.t_start[idx], looks.t_end[idx]
    same = sat[:, None] == sat[None, :]
    theta = angle_between(looks.los_end[idx][:, None, :], looks.los_start[idx][None, :, :])
    need = np.full(theta.shape, np.inf)
    gap = sc.planner.margins.gap
    for s in np.unique(sat):
        m = sat == s
        sat_s = sc.satellites[int(s)]
        slew = getattr(sat_s.maneuver, "slew_time", None)
        if slew is None:
            need[m] = theta[m] / float(np.max(sat_s.limits.rate))
        else:
            need[m] = slew(sat_s, theta[m], gap)  # rows: the earlier look
    after = t0[None, :] - t1[:, None]  # [i, j]: j starts this long after i ends
    fits = (after >= 0.0) & (after + 1e-9 >= need)
    return ~same | fits | fits.T


def _pair_tables(sc, looks: StereoLooks, idx, request, centre, margin: float) -> _Target:
    """The pair tables of one target's looks ``idx`` (module docstring)."""
    e, n = local_axes(centre / np.linalg.norm(centre))
    rel = looks.track[idx] - centre
    track_en = np.stack([rel @ e, rel @ n], -1)
    masks = strip_masks(track_en, looks.half_width[idx], disk_points(request.radius))
    masks = masks.astype(np.float32)  # counts up to 2^24 are exact
    overlap = (masks @ masks.T).astype(np.float64) / masks.shape[1]
    sat, acc = looks.sat[idx], looks.access[idx]
    mid = (looks.t_start[idx] + looks.t_end[idx]) / 2.0
    same = sat[:, None] == sat[None, :]
    mode = np.where(same, acc[:, None] == acc[None, :], bool(request.cross_satellite))
    mode &= np.abs(mid[:, None] - mid[None, :]) <= request.max_separation
    mode &= _compatible(sc, looks, idx)
    np.fill_diagonal(mode, False)
    u = looks.sat_mid[idx] - centre
    conv = angle_between(u[:, None, :], u[None, :, :])
    s = looks.scale[idx]
    ratio = np.maximum(s[:, None], s[None, :]) / np.minimum(s[:, None], s[None, :])
    known = np.isfinite(ratio)
    ratio = np.where(known, ratio, 1.0)
    lo, hi = request.convergence
    fine = mode & (conv >= lo + CONVERGENCE_MARGIN) & (conv <= hi - CONVERGENCE_MARGIN)
    fine &= ~known | (ratio <= request.max_scale_ratio * (1.0 - RATIO_MARGIN))
    valid = fine & (overlap >= request.min_overlap + margin)
    quality = pair_quality(conv, overlap, ratio, request)
    _, group = np.unique(np.stack([sat, acc], -1), axis=0, return_inverse=True)
    return _Target(idx, masks, mode, fine, valid, quality, overlap, conv, ratio, group.ravel())


def _pairs(tt: _Target, request):
    """Valid pairs: (local looks [Q, 3] with -1, quality, convergence, overlap, ratio,
    confidence)."""
    i, j = np.nonzero(np.triu(tt.valid, 1))
    looks = np.stack([i, j, np.full(i.size, -1)], -1)
    ov = tt.overlap[i, j]
    conf = pass_probability(ov, CHECK_POINTS, request.min_overlap)
    return looks, tt.quality[i, j], tt.conv[i, j], ov, tt.ratio[i, j], conf


def _triples(tt: _Target, looks: StereoLooks, request, margin: float):
    """Valid triples (module docstring, Triple), as :func:`_pairs`; None when there are
    none."""
    off = looks.off_nadir[tt.idx]
    anchors = np.flatnonzero(off <= request.anchor_off_nadir - ANCHOR_MARGIN)
    thr = request.min_overlap + margin
    found = []
    for a in anchors:
        b = np.flatnonzero(tt.valid[a])
        c = np.flatnonzero(tt.mode[a])
        if b.size == 0 or c.size < 2:
            continue
        common = (tt.masks[a] * tt.masks[b]) @ tt.masks[c].T / tt.masks.shape[1]
        ok = tt.mode[np.ix_(b, c)] & (common >= thr)
        count = 1 + tt.valid[a, c][None, :] + tt.valid[np.ix_(b, c)]
        ok &= count >= 2
        bi, ci = np.nonzero(ok)
        found.append(np.sort(np.stack([np.full(bi.size, a), b[bi], c[ci]], -1), axis=1))
    if not found:
        return None
    tri = np.unique(np.concatenate(found), axis=0)
    return _triple_values(tt, tri, request)


def _triple_values(tt: _Target, tri, request):
    """Quality, convergence, common overlap, scale ratio and confidence of triples [Q, 3]."""
    edges = ((0, 1), (0, 2), (1, 2))
    ex = [(tri[:, x], tri[:, y]) for x, y in edges]
    q = np.stack([np.where(tt.valid[i, j], tt.quality[i, j], -1.0) for i, j in ex], -1)
    best = np.argmax(q, axis=1)
    r = np.arange(tri.shape[0])
    e = np.array(edges)[best]
    x, y = tri[r, e[:, 0]], tri[r, e[:, 1]]
    common = np.mean(tt.masks[tri[:, 0]] * tt.masks[tri[:, 1]] * tt.masks[tri[:, 2]], axis=1)
    ratio = np.max([tt.ratio[i, j] for i, j in ex], axis=0)
    quality = np.minimum(1.0, q[r, best] + request.tri_bonus)
    p = [tt.fine[i, j] * pass_probability(tt.overlap[i, j], EDGE_POINTS, request.min_overlap)
         for i, j in ex]  # fmt: skip
    two = p[0] * p[1] + p[0] * p[2] + p[1] * p[2] - 2.0 * p[0] * p[1] * p[2]
    conf = pass_probability(common, CHECK_POINTS, request.min_overlap) * two
    return tri, quality, tt.conv[x, y], common, ratio, conf


def select_products(quality, when, group, keep: int, per_group: int = PER_GROUP):
    """The products to keep: best quality first, ties by earliest ``when``; at most
    ``per_group`` of a group before any product past that rank in its own group.

    Args:
      quality: float [Q] (here the expected quality); when: float [Q], e.g. the
        product's last end [s]; group: int [Q], group labels; keep: most products kept;
        per_group: see above.
    Returns:
      int [<= keep], indices into the Q products, in order of preference.
    """
    order = np.lexsort((when, -np.asarray(quality)))
    g = np.asarray(group)[order]
    by_group = np.argsort(g, kind="stable")
    gs = g[by_group]
    starts = np.flatnonzero(np.concatenate([[True], gs[1:] != gs[:-1]]))
    run = np.repeat(starts, np.diff(np.concatenate([starts, [gs.size]])))
    rank = np.empty(g.size, np.int64)
    rank[by_group] = np.arange(gs.size) - run
    pref = np.lexsort((np.arange(g.size), rank >= per_group))
    return order[pref[:keep]]


def _keep(tt: _Target, looks: StereoLooks, parts, keep: int):
    """The kept products of one kind (``parts`` as :func:`_pairs`), ids as look ids."""
    loc, quality, conv, overlap, ratio, conf = parts
    if loc.shape[0] == 0:
        return None
    ids = np.where(loc >= 0, tt.idx[np.maximum(loc, 0)], -1)
    when = np.where(ids >= 0, looks.t_end[np.maximum(ids, 0)], -np.inf).max(axis=1)
    gl = np.where(loc >= 0, tt.group[np.maximum(loc, 0)], -1)
    _, group = np.unique(np.sort(gl, axis=1), axis=0, return_inverse=True)
    pick = select_products(quality * conf, when, group.ravel(), keep)
    size = (loc >= 0).sum(axis=1)
    tgt = looks.target[ids[pick, 0]]
    return StereoProducts(ids[pick], tgt, quality[pick], size[pick], conv[pick],
                          overlap[pick], ratio[pick], conf[pick])  # fmt: skip


def stereo_products(sc, looks: StereoLooks, overlap_margin: float = OVERLAP_MARGIN):
    """The kept products of every stereo target (module docstring).

    Args:
      sc: Scenario (its stereo requests, satellites and margins).
      looks: :class:`StereoLooks` of its stereo targets.
      overlap_margin: overlap kept above each request's ``min_overlap`` (>= 0; the
        products' ``confidence`` tells how safe each is; :data:`SAFE_OVERLAP_MARGIN`
        keeps only products the benchmark all but surely passes).
    Returns:
      :class:`StereoProducts`, ``looks`` indexing ``looks``, grouped by target in the
      order of ``sc.stereo``: a target's pairs, then its triples, each in order of
      preference (:func:`select_products` on quality times confidence).
    Raises:
      ValueError: ``overlap_margin`` is negative or not finite.
    """
    if not (math.isfinite(overlap_margin) and overlap_margin >= 0.0):
        raise ValueError(f"overlap_margin must be finite and >= 0, got {overlap_margin!r}")
    tg = sc.targets
    parts = []
    for request in sc.stereo:
        row = int(request.target)
        idx = np.flatnonzero(looks.target == row)
        if idx.size < 2:
            continue
        centre = np.asarray(geodetic_to_ecef(tg.lat[row], tg.lon[row], tg.alt[row]))
        tt = _pair_tables(sc, looks, idx, request, centre, overlap_margin)
        parts.append(_keep(tt, looks, _pairs(tt, request), PAIRS_PER_TARGET))
        if request.product == "tri":
            tri = _triples(tt, looks, request, overlap_margin)
            parts.append(None if tri is None else _keep(tt, looks, tri, TRIPLES_PER_TARGET))
    parts = [p for p in parts if p is not None]
    if not parts:
        return empty_products()
    return StereoProducts(*(np.concatenate(cols) for cols in zip(*parts, strict=True)))
