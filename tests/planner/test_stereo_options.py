"""Stereo options: looks as planner options, products checked by the independent checker.

A stereo_imaging training case is turned into a Scenario here (a helper of the tests, not
the adapter); its products, written as solutions, must be valid for
:func:`jaxspline.stereo.check.check_solution` with the quality the generator computed.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from jaxspline.base.elements import circular_orbit
from jaxspline.geometry.stereo_looks import look_direction, satellite_states
from jaxspline.geometry.windows import orbit_scene
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.opportunities import Opportunities
from jaxspline.planner.stereo_options import merge_stereo, stereo_options
from jaxspline.readers.config import Margins, PlannerConfig
from jaxspline.readers.mission import POINT, STEREO, Satellite, Scenario, make_targets
from jaxspline.readers.stereo_request import Stereo
from jaxspline.screen.stereo_products import (
    PAIRS_PER_TARGET,
    SAFE_OVERLAP_MARGIN,
    TRIPLES_PER_TARGET,
    stereo_products,
)
from jaxspline.stereo.case import SCENE_BANDS_DEG, format_time, load_case
from jaxspline.stereo.check import check_solution

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "stereo"))
from _ref_stereo import DATA  # noqa: E402

CASE1 = DATA / "case_0001"
#: Sub-horizon of the fast tests [s].
HOURS6 = 6 * 3600.0
#: Off-nadir margin of the test scenarios [rad] (the orbit models differ by ~150 m).
MARGINS = Margins(off_nadir=math.radians(0.05))
QUALITY_TOL = 0.02
#: Same-satellite looks of two products packed into one solution keep this apart [s].
PACK_GAP_S = 90.0


def case_scenario(case, duration: float | None = None, product: str = "tri") -> Scenario:
    """A Scenario of a stereo_imaging case (RULES.md): roll-only satellites with the
    case's agility and sensor, one STEREO target per case target, 1 s action grid."""
    m = case.mission
    th, q = m.thresholds, m.quality
    r = math.radians
    sats = tuple(
        Satellite(
            name=s.id,
            orbit=(s.tle1, s.tle2),
            model="roll_only",
            limits=AxisLimits(r(s.rate_deg_s), r(s.accel_deg_s2)),
            off_nadir_max=r(s.max_off_nadir_deg),
            settle=s.settling_s,
            fov=r(s.fov_deg),
            ifov=r(s.ifov_deg),
            strip_duration=(s.min_duration_s, s.max_duration_s),
        )
        for s in case.satellites
    )
    tg = case.targets
    dur = case.horizon_s if duration is None else float(duration)
    targets = make_targets(
        np.full(len(tg), STEREO),
        np.radians([t.lat_deg for t in tg]),
        np.radians([t.lon_deg for t in tg]),
        alt=[t.elevation_m for t in tg],
        t_lo=0.0,
        t_hi=dur,
        name=[t.id for t in tg],
    )
    stereo = tuple(
        Stereo(
            name=t.id,
            target=i,
            radius=t.aoi_radius_m,
            product=product,
            min_overlap=th.min_overlap,
            convergence=(r(th.min_convergence_deg), r(th.max_convergence_deg)),
            band=tuple(r(x) for x in SCENE_BANDS_DEG[t.scene_type]),
            max_scale_ratio=th.max_pixel_scale_ratio,
            max_separation=m.max_pair_separation_s,
            cross_satellite=m.allow_cross_satellite,
            anchor_off_nadir=r(th.anchor_max_off_nadir_deg),
            weights=(q.geometry, q.overlap, q.resolution),
            tri_bonus=q.tri_bonus[t.scene_type],
        )
        for i, t in enumerate(tg)
    )
    pc = PlannerConfig(
        time_step=1.0,
        geometry_step=1.0,
        sun_elevation_min=r(th.min_solar_elevation_deg),
        margins=MARGINS,
    )
    return Scenario(case.case_id, case.start, dur, sats, targets, pc, stereo=stereo)


def look_actions(case, so, rows) -> list:
    """Solution actions of option rows of :class:`StereoOptions` ``so``."""
    lk = so.looks
    return [
        {
            "type": "observation",
            "satellite_id": case.satellites[int(lk.sat[i])].id,
            "target_id": case.targets[int(lk.target[i])].id,
            "start_time": format_time(case.time_at(float(lk.t_start[i]))),
            "end_time": format_time(case.time_at(float(lk.t_end[i]))),
            "off_nadir_along_deg": float(np.degrees(lk.along[i])),
            "off_nadir_across_deg": float(np.degrees(lk.across[i])),
        }
        for i in rows
    ]


def pack(so, products) -> list:
    """Products packed into solutions: one product a target per solution, same-satellite
    looks of different products at least :data:`PACK_GAP_S` apart. Returns lists of
    product indices."""
    lk = so.looks
    bins = []  # per solution: (targets, [(sat, t0, t1)], products)

    def fits(b, tgt, mine) -> bool:
        targets, spans, _ = b
        return tgt not in targets and not any(
            s == s2 and t0 < t3 + PACK_GAP_S and t2 < t1 + PACK_GAP_S
            for s, t0, t1 in mine
            for s2, t2, t3 in spans
        )

    for p in products:
        rows = [int(i) for i in so.products.looks[p] if i >= 0]
        mine = [(lk.sat[i], lk.t_start[i], lk.t_end[i]) for i in rows]
        tgt = int(so.products.target[p])
        b = next((b for b in bins if fits(b, tgt, mine)), None)
        if b is None:
            b = (set(), [], [])
            bins.append(b)
        b[0].add(tgt)
        b[1].extend(mine)
        b[2].append(p)
    return [items for _, _, items in bins]


def check_products(case, so, chosen) -> list:
    """Check the products ``chosen`` with the checker; returns (claimed quality, checker
    quality or None when it finds the product not valid) per product."""
    out = []
    for items in pack(so, chosen):
        rows = [int(i) for p in items for i in so.products.looks[p] if i >= 0]
        rep = check_solution(case, {"actions": look_actions(case, so, rows)})
        assert rep.valid, [str(v) for v in rep.violations]
        found = {frozenset(x.actions): x for x in rep.pairs + rep.triples}
        k = 0
        for p in items:
            n = int(so.products.size[p])
            res = found.get(frozenset(range(k, k + n)))
            k += n
            out.append((float(so.products.quality[p]), res.quality if res and res.valid else None))
    return out


@pytest.fixture(scope="module")
def case1():
    return load_case(CASE1)


@pytest.fixture(scope="module")
def built(case1):
    sc = case_scenario(case1, HOURS6)
    table, scene = orbit_scene(sc)
    return sc, scene, stereo_options(sc, table, scene)


def test_products_are_valid_for_the_checker(case1, built):
    _, _, so = built
    pr = so.products
    assert len(pr) > 0 and (pr.size == 3).any()
    score = pr.quality * pr.confidence
    best = [int(np.flatnonzero(pr.target == t)[np.argmax(score[pr.target == t])])
            for t in np.unique(pr.target)]  # fmt: skip
    rng = np.random.default_rng(7)
    others = rng.choice(len(pr), size=min(24, len(pr)), replace=False).tolist()
    thin = np.argsort(pr.overlap)[:16].tolist()  # nearest the overlap threshold
    res = check_products(case1, so, sorted(set(best + others + thin)))
    claimed, got = np.array([c for c, _ in res]), [g for _, g in res]
    assert all(g is not None for g in got), f"{sum(g is None for g in got)} products invalid"
    np.testing.assert_allclose(np.array(got), claimed, atol=QUALITY_TOL)


def test_option_rows_follow_the_roll_law(built):
    sc, scene, so = built
    o, lk = so.opp.options, so.looks
    assert isinstance(so.opp, Opportunities) and len(so) == len(lk) > 0
    assert np.all(np.diff(o.sat) >= 0)  # sorted by satellite, then start
    same = np.diff(o.sat) == 0
    assert np.all(np.diff(o.t_start)[same] >= 0)
    np.testing.assert_array_equal(o.route, lk.target)
    np.testing.assert_array_equal(so.opp.params[:, 7], 2.0)
    # roll-only satellites compare lines of sight Earth-fixed: the steering's boresight
    for t, los in ((lk.t_start, o.start_los), (lk.t_end, o.end_los)):
        pos, vel = satellite_states(scene, lk.sat, t)
        np.testing.assert_allclose(los, look_direction(pos, vel, lk.along, lk.across), atol=1e-9)
    assert np.all(np.degrees(lk.off_nadir) <= 35.0)
    np.testing.assert_allclose(so.off_nadir, lk.off_nadir)


def test_counts_and_sizes(built):
    sc, _, so = built
    pr = so.products
    assert pr.looks.shape == (len(pr), 3)
    assert set(np.unique(pr.size)) <= {2, 3}
    np.testing.assert_array_equal((pr.looks >= 0).sum(axis=1), pr.size)
    assert pr.looks.max() < len(so) and np.all(pr.looks[pr.size == 2, 2] == -1)
    np.testing.assert_array_equal(so.looks.target[pr.looks[:, 0]], pr.target)
    assert np.all((pr.quality > 0) & (pr.quality <= 1.0))
    for t in np.unique(pr.target):
        m = pr.target == t
        assert (pr.size[m] == 2).sum() <= PAIRS_PER_TARGET
        assert (pr.size[m] == 3).sum() <= TRIPLES_PER_TARGET
    used = np.zeros(len(so), bool)
    used[pr.looks[pr.looks >= 0]] = True
    assert used.all() and so.n_candidates >= len(so)


def test_margins_and_confidence(built):
    sc, _, so = built
    pr = so.products
    assert np.all((pr.confidence >= 0.0) & (pr.confidence <= 1.0))
    assert np.all(pr.overlap >= 0.8 + 0.02 - 1e-12)
    risky = pr.overlap < 0.85
    assert risky.any() and np.all(pr.confidence[risky] < 0.95)
    assert np.all(pr.confidence[pr.overlap >= 0.9] > 0.99)
    safe = stereo_products(sc, so.looks, SAFE_OVERLAP_MARGIN)
    assert len(safe) > 0 and np.all(safe.overlap >= 0.9) and np.all(safe.confidence > 0.99)
    assert np.unique(safe.target).size <= np.unique(pr.target).size
    with pytest.raises(ValueError, match="overlap_margin"):
        stereo_products(sc, so.looks, -0.1)


def test_merge_renumbers_products(built):
    _, _, so = built
    other = so.opp  # any table: here the looks themselves, which sort first on ties
    m = merge_stereo(other, so)
    n = len(other) + len(so)
    assert len(m.opp) == n and np.array_equal(np.sort(m.order), np.arange(n))
    rows = np.flatnonzero(m.look_of_row >= 0)
    np.testing.assert_array_equal(np.sort(m.look_of_row[rows]), np.arange(len(so)))
    ids = m.products.looks
    np.testing.assert_array_equal(m.look_of_row[ids[ids >= 0]], so.products.looks[ids >= 0])
    for f in ("sat", "route", "t_start", "t_end", "start_los"):
        got = getattr(m.opp.options, f)[ids[ids >= 0]]
        np.testing.assert_array_equal(got, getattr(so.opp.options, f)[so.products.looks[ids >= 0]])
    key = np.stack([m.opp.options.sat, m.opp.options.t_start])
    assert np.all(np.diff(key[0]) >= 0)
    assert np.all(np.diff(key[1])[np.diff(key[0]) == 0] >= 0)


def test_no_stereo_target_gives_none(case1):
    sat = Satellite("s", circular_orbit(500e3), model="roll_only", limits=AxisLimits(0.03, 0.01))
    tg = make_targets(np.array([POINT]), [0.1], [0.2], duration=5.0)
    sc = Scenario("x", case1.start, 3600.0, (sat,), tg, PlannerConfig(time_step=5.0))
    table, scene = orbit_scene(sc)
    assert stereo_options(sc, table, scene) is None


def test_full_case_products_are_valid(case1):
    """The whole 48 h of case 1 (~6-10 s): coverage near the bound, every target's best
    product valid for the checker."""
    sc = case_scenario(case1)
    table, scene = orbit_scene(sc)
    so = stereo_options(sc, table, scene)
    pr = so.products
    assert np.unique(pr.target).size >= 0.95 * len(case1.targets)  # bound: 128 of 131
    best = [int(np.flatnonzero(pr.target == t)[0]) for t in np.unique(pr.target)]
    res = check_products(case1, so, best)
    assert all(g is not None for _, g in res)
    np.testing.assert_allclose([g for _, g in res], [c for c, _ in res], atol=QUALITY_TOL)
