"""Stereo products of the stereo_imaging checker: pairs, tri-stereo sets, their quality.

The checker (:mod:`jaxspline.stereo.check`) hands over one :class:`Look` per observation
that passed the access test; here every pair and every triple of looks of one target is
judged by RULES.md ("Stereo pair", "Tri-stereo set"):

* mode: the same satellite in the same access interval, or two satellites when the
  mission allows it; midpoints at most ``max_stereo_pair_separation_s`` apart;
* pair: overlap >= ``min_overlap_fraction``, convergence in [min, max], pixel-scale ratio
  <= ``max_pixel_scale_ratio`` (tolerances 1e-6 as official); quality
  ``wg Qg + wo Qo + wr Qr``;
* triple: all three edges pass the mode rules, common overlap >= the threshold, at least
  two edges are valid pairs, one look within the near-nadir anchor limit; quality
  ``min(1, best valid edge + beta R)``.

Overlaps are the lattice quadrature of :func:`~jaxspline.stereo.check_geometry.disk_lattice`,
one value per pair whether judged alone or inside a triple (the official checker draws
fresh random points for each role).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations

import numpy as np

from jaxspline.aeossp.check_frames import angle_deg
from jaxspline.stereo.case import SCENE_BANDS_DEG, Case
from jaxspline.stereo.check_geometry import disk_lattice, inside_strip, target_ecef

__all__ = [
    "Look",
    "PairResult",
    "Product",
    "TripleResult",
    "evaluate_products",
    "geometry_quality",
    "pair_mode",
]

#: Tolerance of the overlap, convergence, ratio, separation and anchor tests (official).
TOL = 1e-6
#: Overlap at which Qo saturates.
FULL_OVERLAP = 0.95
#: Pixel-scale ratio excess at which Qr reaches 0.
RATIO_SPAN = 0.5
#: Convergence distance from the band at which Qg reaches 0 [deg].
BAND_FALLOFF_DEG = 10.0
#: Redundancy (two valid pairs) and anchor shares of the tri-stereo bonus factor R.
R_PAIRS, R_ANCHOR = 0.6, 0.4


@dataclass(frozen=True)
class Look:
    """One observation that passed the access test, as the products see it.

    Attributes:
      action: index in the solution's ``actions``.
      sat: satellite index.
      target: target index.
      start_s: start [s from the horizon start].
      end_s: end [s].
      mid_s: midpoint [s].
      sat_mid: float [3], Earth-fixed satellite position at the midpoint [m].
      off_nadir_deg: combined off-nadir angle of the steering [deg].
      slant_m: boresight slant range at the midpoint [m].
      pixel_scale_m: ``slant_m`` x IFOV [m].
      half_width_m: strip half-width ``slant_m tan(FOV / 2)`` [m].
      poly: float [K, 2], the strip's ground track in the target's east / north plane [m].
      access_id: index of its merged access interval among those of (satellite, target).
    """

    action: int
    sat: int
    target: int
    start_s: float
    end_s: float
    mid_s: float
    sat_mid: np.ndarray
    off_nadir_deg: float
    slant_m: float
    pixel_scale_m: float
    half_width_m: float
    poly: np.ndarray
    access_id: int


@dataclass(frozen=True)
class PairResult:
    """One evaluated pair (its two looks passed the mode rules).

    Attributes:
      target_id: the target.
      actions: the two action indices.
      mode: ``same_pass`` or ``cross_satellite``.
      separation_s: time between the midpoints [s].
      convergence_deg: convergence angle at the target [deg].
      overlap: share of the AOI inside both strips.
      pixel_scale_ratio: larger / smaller pixel scale.
      quality: pair quality (computed for invalid pairs too).
      failed: the failed tests among ``overlap``, ``convergence``, ``pixel_scale``.
    """

    target_id: str
    actions: tuple
    mode: str
    separation_s: float
    convergence_deg: float
    overlap: float
    pixel_scale_ratio: float
    quality: float
    failed: tuple

    @property
    def valid(self) -> bool:
        """No test failed."""
        return not self.failed


@dataclass(frozen=True)
class TripleResult:
    """One evaluated triple (all three edges passed the mode rules).

    Attributes:
      target_id: the target.
      actions: the three action indices.
      common_overlap: share of the AOI inside all three strips.
      valid_pairs: how many of its three edges are valid pairs.
      anchor: one look is within the near-nadir anchor limit.
      quality: ``min(1, best valid edge quality + beta R)`` (0 without a valid edge).
      failed: the failed tests among ``common_overlap``, ``pairs``, ``anchor``.
    """

    target_id: str
    actions: tuple
    common_overlap: float
    valid_pairs: int
    anchor: bool
    quality: float
    failed: tuple

    @property
    def valid(self) -> bool:
        """No test failed."""
        return not self.failed


@dataclass(frozen=True)
class Product:
    """The best valid product of one target.

    Attributes:
      kind: ``pair`` or ``triple``.
      actions: its action indices.
      quality: its quality.
      weakest_overlap: the overlap its validity leans on most: a pair's overlap; for a
        triple the smaller of the common overlap and the second-best valid edge overlap.
      safest_overlap: the largest ``weakest_overlap`` among all valid products of the
        target (how far its coverage stands above the overlap threshold).
    """

    kind: str
    actions: tuple
    quality: float
    weakest_overlap: float
    safest_overlap: float


def pair_mode(case: Case, a: Look, b: Look) -> str | None:
    """The stereo mode of two looks of one target, or None if they may not pair.

    Args:
      case: Case (mission policy).
      a: Look.
      b: Look.
    Returns:
      ``same_pass``, ``cross_satellite`` or None.
    """
    m = case.mission
    if abs(a.mid_s - b.mid_s) - TOL > m.max_pair_separation_s:
        return None
    if a.sat == b.sat:
        return "same_pass" if a.access_id == b.access_id else None
    return "cross_satellite" if m.allow_cross_satellite else None


def geometry_quality(convergence_deg: float, scene_type: str) -> float:
    """Qg: 1 inside the scene's preferred band, falling by 0.1 per degree outside.

    Args:
      convergence_deg: convergence angle [deg].
      scene_type: the target's scene type.
    Returns:
      float in [0, 1].
    """
    lo, hi = SCENE_BANDS_DEG[scene_type]
    if lo <= convergence_deg <= hi:
        return 1.0
    e = min(abs(convergence_deg - lo), abs(convergence_deg - hi))
    return max(0.0, 1.0 - e / BAND_FALLOFF_DEG)


def _pair(case, target, center, a: Look, b: Look, mode: str, overlap: float) -> PairResult:
    th, q = case.mission.thresholds, case.mission.quality
    gamma = float(angle_deg(a.sat_mid - center, b.sat_mid - center))
    ratio = max(a.pixel_scale_m, b.pixel_scale_m) / min(a.pixel_scale_m, b.pixel_scale_m)
    failed = []
    if overlap + TOL < th.min_overlap:
        failed.append("overlap")
    if not th.min_convergence_deg - TOL <= gamma <= th.max_convergence_deg + TOL:
        failed.append("convergence")
    if ratio > th.max_pixel_scale_ratio + TOL:
        failed.append("pixel_scale")
    quality = (
        q.geometry * geometry_quality(gamma, target.scene_type)
        + q.overlap * min(1.0, overlap / FULL_OVERLAP)
        + q.resolution * max(0.0, 1.0 - (ratio - 1.0) / RATIO_SPAN)
    )
    return PairResult(
        target.id,
        (a.action, b.action),
        mode,
        abs(a.mid_s - b.mid_s),
        gamma,
        overlap,
        ratio,
        quality,
        tuple(failed),
    )


def _triple(case, target, looks, edges, common: float) -> TripleResult:
    th = case.mission.thresholds
    valid = [e for e in edges if e.valid]
    anchor = any(x.off_nadir_deg <= th.anchor_max_off_nadir_deg + TOL for x in looks)
    r = (R_PAIRS if len(valid) >= 2 else 0.0) + (R_ANCHOR if anchor else 0.0)
    beta = case.mission.quality.tri_bonus[target.scene_type]
    quality = min(1.0, max(e.quality for e in valid) + beta * min(1.0, r)) if valid else 0.0
    failed = []
    if common + TOL < th.min_overlap:
        failed.append("common_overlap")
    if len(valid) < 2:
        failed.append("pairs")
    if not anchor:
        failed.append("anchor")
    acts = tuple(x.action for x in looks)
    return TripleResult(target.id, acts, common, len(valid), anchor, quality, tuple(failed))


def _target_products(case: Case, target, looks: list) -> tuple[list, list]:
    """Every pair and triple of one target's looks."""
    pts, center = disk_lattice(target.aoi_radius_m), target_ecef(target)
    masks = np.array([inside_strip(pts, x.poly, x.half_width_m) for x in looks], dtype=float)
    n = len(looks)
    pairs: dict = {}
    for i, j in combinations(range(n), 2):
        mode = pair_mode(case, looks[i], looks[j])
        if mode is not None:
            overlap = float(np.mean(masks[i] * masks[j]))
            pairs[i, j] = _pair(case, target, center, looks[i], looks[j], mode, overlap)
    triples = []
    for i, j, k in combinations(range(n), 3):
        edges = [pairs.get(e) for e in ((i, j), (i, k), (j, k))]
        if any(e is None for e in edges):
            continue
        common = float(np.mean(masks[i] * masks[j] * masks[k]))
        triples.append(_triple(case, target, [looks[i], looks[j], looks[k]], edges, common))
    return list(pairs.values()), triples


def _best(pairs: list, triples: list) -> Product | None:
    found = [("pair", p.actions, p.quality, p.overlap) for p in pairs if p.valid]
    by_actions = {frozenset(p.actions): p for p in pairs}
    for t in triples:
        if t.valid:
            edges = [by_actions[frozenset(e)] for e in combinations(t.actions, 2)]
            second = sorted((e.overlap for e in edges if e.valid), reverse=True)[1]
            found.append(("triple", t.actions, t.quality, min(t.common_overlap, second)))
    if not found:
        return None
    best = max(found, key=lambda f: f[2])  # the first of equal qualities: pairs first
    return Product(*best, safest_overlap=max(f[3] for f in found))


def evaluate_products(case: Case, looks: list) -> tuple[list, list, dict]:
    """Pairs, triples and the best product of every target.

    Args:
      case: Case.
      looks: list of Look (any order; grouped by target here).
    Returns:
      (pairs, triples, best): lists of PairResult and TripleResult, and target id ->
      Product (None for a target without a valid product), in the case's target order.
    """
    by_target: dict = {}
    for x in looks:
        by_target.setdefault(x.target, []).append(x)
    pairs, triples, best = [], [], {}
    for k, target in enumerate(case.targets):
        mine = sorted(by_target.get(k, []), key=lambda x: x.action)
        p, t = _target_products(case, target, mine) if len(mine) >= 2 else ([], [])
        pairs += p
        triples += t
        best[target.id] = _best(p, t)
    return pairs, triples, best
