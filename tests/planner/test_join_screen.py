"""The join screen against the exact check of the flown joins, and its use by the planner.

Reference: :func:`jaxspline.planner.flown_joins.plan_joins`, which plans the spatial
degree-7 MRP join between the scan laws and checks it on 129 samples (per-channel
angles through the orbital frame for ``per_channel``). Every screened pair is checked
as its own one-satellite plan (copies of one orbit), without the re-timing.
"""

import dataclasses
import datetime as dt
from types import SimpleNamespace

import jax
import numpy as np
import pytest

from jaxspline.base.elements import circular_orbit_over, gmst, julian_date
from jaxspline.geometry.windows import orbit_scene
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.flown_joins import NADIR, plan_joins
from jaxspline.planner.join_screen import channel_states, screen_first_joins, screen_joins
from jaxspline.products.attitude_history import observation_laws
from jaxspline.readers.config import PlannerConfig
from jaxspline.readers.mission import FlexMode, Satellite, Scenario, make_targets
from jaxspline.search import Problem

EPOCH = dt.datetime(2026, 4, 14, 12, 30, tzinfo=dt.UTC)
DURATION = 900.0
OVER = (46.0, 15.0, 450.0)  # sub-satellite point [deg, deg] at t [s]
POINTS = [(55.0, 17.0), (50.0, 12.0), (46.0, 15.5), (40.5, 14.0), (44.0, 19.0)]
POINT_S = 10.0
STARTS = np.arange(300.0, 560.0, 20.0)  # option starts [s]
MAX_GAP = 120.0  # [s] pairs screened
AGREE = 0.9  # the screen and the exact check agree on at least this share of pairs
FALSE_PASS = 0.05  # at most this share of screened-in pairs fail the exact check
PAIRS = 150  # random pairs per model checked exactly


def _sats(orb):
    deg = np.radians
    return (
        Satellite("pc", orb, "per_channel", AxisLimits(deg([3.0, 3.0, 2.0]), deg([1.5, 1.5, 1.0]))),
        Satellite("ea", orb, "eigen_axis", AxisLimits(deg(1.8), deg(0.4)), settle=2.0),
        Satellite(
            "fx",
            orb,
            "flexible",
            AxisLimits(deg(1.5), deg(0.3)),
            settle=1.0,
            flex=FlexMode(2 * np.pi * 0.5, 0.01, deg(0.006)),
        ),
    )


def _scenario(sats):
    deg = np.radians
    tg = make_targets(
        [0] * len(POINTS),
        deg([p[0] for p in POINTS]),
        deg([p[1] for p in POINTS]),
        duration=[POINT_S] * len(POINTS),
    )
    return Scenario("screen", EPOCH, DURATION, sats, tg, PlannerConfig())


@pytest.fixture(scope="module")
def case():
    gmst0 = float(gmst(julian_date(EPOCH)))
    orb = circular_orbit_over(np.radians(OVER[0]), np.radians(OVER[1]), OVER[2], gmst0)
    sats = _sats(orb)
    sc = _scenario(sats)
    # options: every satellite x target x start (point laws; the test needs no visibility)
    grid = np.meshgrid(range(3), range(len(POINTS)), STARTS, indexing="ij")
    s, tg, t0 = (g.ravel() for g in grid)
    params = observation_laws(sc, tg, np.zeros(tg.size))
    opp = SimpleNamespace(
        options=SimpleNamespace(sat=s, t_start=t0, t_end=t0 + POINT_S, route=tg), params=params
    )
    i, j = np.meshgrid(np.arange(s.size), np.arange(s.size), indexing="ij")
    gap = t0[j] - (t0[i] + POINT_S)
    keep = (s[i] == s[j]) & (gap > 0) & (gap <= MAX_GAP) & (tg[i] != tg[j])
    src, dst = i[keep], j[keep]
    rng = np.random.default_rng(0)  # PAIRS per model: each is a plan of its own below
    pick = np.concatenate(
        [rng.permutation(np.flatnonzero(s[src] == k))[:PAIRS] for k in range(len(sats))]
    )
    src, dst = src[pick], dst[pick]
    with jax.enable_x64(True):
        scene = orbit_scene(sc)[1]
        states = channel_states(scene, sats, opp)
        screened = screen_joins(sats, opp, states, src, dst)
        first = screen_first_joins(sats, opp, states, np.arange(s.size))
        # exact: each pair as its own plan of one satellite (copies of the orbit)
        p = src.size
        copies = tuple(dataclasses.replace(sats[k], name=f"c{n}") for n, k in enumerate(s[src]))
        sc_p = Scenario("copies", EPOCH, DURATION, copies, sc.targets, PlannerConfig())
        scene_p = orbit_scene(sc_p)[1]
        who = np.repeat(np.arange(p), 2)
        pair = np.stack([src, dst], -1).ravel()
        joins = plan_joins(scene_p, copies, who, t0[pair], t0[pair] + POINT_S, params[pair])
    mid = (joins.before != NADIR) & (joins.after != NADIR)
    exact = np.zeros(p, bool)
    exact[joins.sat[mid]] = joins.ok[mid] & ~joins.retimed[mid]
    return SimpleNamespace(sats=sats, s=s, src=src, dst=dst, screened=screened, exact=exact,
                           first=first, t0=t0)  # fmt: skip


def test_screen_agrees_with_the_exact_flown_check(case):
    model = case.s[case.src]
    for k in range(3):
        m = model == k
        assert m.sum() > 50
        scr, ex = case.screened[m], case.exact[m]
        assert 0 < ex.sum() < m.sum(), "the test needs passing and failing pairs"
        assert np.mean(scr == ex) >= AGREE, (k, np.mean(scr == ex))
        assert np.mean(~ex[scr]) <= FALSE_PASS, (k, np.mean(~ex[scr]))


def test_first_join_from_nadir(case):
    # starts of 300-540 s: the first join from nadir at t = 0 is long and always passes
    assert case.first.all()


def test_problem_lookup_makes_removed_rest_to_rest_pairs_infeasible(case):
    """A rest-to-rest pair the screen removed is infeasible for the search (need = inf)."""
    from jaxspline.search.battery import BatteryModel

    n = case.s.size
    o = SimpleNamespace(
        sat=case.s,
        route=np.zeros(n, np.int64),
        t_start=case.t0,
        t_end=case.t0 + POINT_S,
        start_los=np.tile([0.0, 0.0, 1.0], (n, 1)),
        end_los=np.tile([0.0, 0.0, 1.0], (n, 1)),
    )
    from jaxspline.screen.slew_table import slew_table

    tables = [None] + [slew_table(s) for s in case.sats[1:]]
    keep = case.screened
    near = (case.src[keep], case.dst[keep], np.full(keep.sum(), 1.0))
    bat = BatteryModel(np.ones((3, 2), bool), [None] * 3, 5.0)
    far = [1e9] * 3
    for lookup, expect_inf in ((None, False), (np.ones(3, bool), True)):
        pb = Problem.build(SimpleNamespace(options=o), case.sats, np.zeros(n), near, far, tables,
                           bat, [1.0], lookup)  # fmt: skip
        gone = np.flatnonzero(~keep & (case.s[case.src] > 0))
        assert gone.size
        pairs = zip(case.src[gone], case.dst[gone], strict=True)
        needs = [pb.need(int(a), int(b)) for a, b in pairs]
        assert np.all(np.isinf(needs)) == expect_inf
