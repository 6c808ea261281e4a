"""Desired imaging time with a tolerance, and a minimum imaging time: options, plan, checker.

References: every constrained target has an unconstrained twin (same place, same
imaging); the twin's options filtered by the definition (midpoint ``(start + end) / 2``
within ``desired +- tolerance``; ``end - start >= min_duration``) must be exactly the
constrained target's options (brute force over the twin's option table). The checker
is fed forged plans: options of the twins that break the constraints.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import math

import numpy as np
import pytest

from jaxspline import build_problem, plan
from jaxspline.base.elements import circular_orbit_over, gmst, julian_date
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.plan_check import check_plan
from jaxspline.readers.config import PlannerConfig
from jaxspline.readers.mission import POINT, STRIP, Satellite, Scenario, make_targets

EPOCH = dt.datetime(2026, 4, 14, 9, 0, tzinfo=dt.UTC)
DESIRED, TOL = 610.0, 7.0  # [s] target 1: midpoint within [603, 617]
MIN_DUR = 6.0  # [s] target 2: a 35 km strip at 7 km/s (5 s) is too short, at 4 km/s not
SPEEDS = (7000.0, 4000.0)
# (kind, lat, lon, duration, length, azimuth, value): 0/1 and 2/3 are twins
ROWS = [
    (POINT, 46.2, 15.1, 10.0, 0.0, 0.0, 1.0),
    (POINT, 46.2, 15.1, 10.0, 0.0, 0.0, 50.0),
    (STRIP, 45.9, 14.8, 0.0, 35e3, 190.0, 50.0),
    (STRIP, 45.9, 14.8, 0.0, 35e3, 190.0, 1.0),
]


def _scenario(mid=True, min_dur=True) -> Scenario:
    orb = circular_orbit_over(
        math.radians(46.0), math.radians(15.0), 600.0, float(gmst(julian_date(EPOCH)))
    )
    sat = Satellite(
        "agile",
        orb,
        "per_channel",
        AxisLimits(np.radians([3.0, 3.0, 2.0]), np.radians([1.5, 1.5, 1.0])),
        math.radians(30.0),
    )
    kind, lat, lon, dur, length, az, value = (np.array(c) for c in zip(*ROWS, strict=True))
    mid_lo, mid_hi = np.full(4, -np.inf), np.full(4, np.inf)
    if mid:
        mid_lo[1], mid_hi[1] = DESIRED - TOL, DESIRED + TOL
    tg = make_targets(
        kind,
        np.radians(lat),
        np.radians(lon),
        duration=dur,
        length=length,
        azimuth=np.radians(az),
        value=value,
        mid_lo=mid_lo,
        mid_hi=mid_hi,
        min_duration=np.array([0.0, 0.0, MIN_DUR if min_dur else 0.0, 0.0]),
    )
    pc = PlannerConfig(time_step=5.0, geometry_step=5.0, scan_speeds=SPEEDS, refine_steps=0)
    return Scenario("imaging-time", EPOCH, 1200.0, (sat,), tg, pc)


@pytest.fixture(scope="module")
def free():
    """The scenario without the constraints: (scenario, PlanContext)."""
    sc = _scenario(mid=False, min_dur=False)
    return sc, build_problem(sc)


@pytest.fixture(scope="module")
def tight():
    sc = _scenario()
    return sc, build_problem(sc)


def _options(prep, target):
    o = prep.opportunities.options
    m = np.asarray(o.route) == target
    return np.asarray(o.t_start)[m], np.asarray(o.t_end)[m], prep.opportunities.speed[m]


def test_options_are_the_twins_filtered_by_definition(free, tight):
    s0, e0, _ = _options(free[1], 0)  # the free twin of target 1
    assert (
        s0.size > 10 and ((s0 + e0) / 2).min() < DESIRED - TOL < DESIRED + TOL < (s0 + e0).max() / 2
    )
    keep = np.abs((s0 + e0) / 2 - DESIRED) <= TOL
    s1, e1, _ = _options(tight[1], 1)
    np.testing.assert_array_equal(np.sort(s1), np.sort(s0[keep]))
    assert s1.size == 3  # starts 600, 605, 610 on the 5 s grid
    # the strip: only the slow scan is long enough
    s3, e3, v3 = _options(free[1], 3)
    assert set(v3.tolist()) == set(SPEEDS)
    keep = e3 - s3 >= MIN_DUR
    s2, e2, v2 = _options(tight[1], 2)
    assert sorted(zip(s2.tolist(), v2.tolist(), strict=True)) == sorted(
        zip(s3[keep].tolist(), v3[keep].tolist(), strict=True)
    )
    assert set(v2.tolist()) == {4000.0} and np.all(e2 - s2 >= MIN_DUR)
    # the unconstrained twins are unchanged by the constraints of their siblings
    np.testing.assert_array_equal(_options(tight[1], 0)[0], s0)


def test_plan_images_only_inside_the_tolerance():
    sc = _scenario()
    # an iteration cap, not only a clock: the search would otherwise run its whole limit
    res = plan(sc, time_limit=15.0, seed=0, progress=False, max_iters=300)
    assert res.report["valid"], res.report["violations"]
    obs = res.observations
    i1 = np.flatnonzero(obs.target == 1)
    i2 = np.flatnonzero(obs.target == 2)
    assert i1.size == 1 and i2.size == 1  # both are worth 50: the plan takes them
    mid = (obs.start[i1] + obs.end[i1]) / 2
    assert abs(float(mid[0]) - DESIRED) <= TOL + 1e-9
    assert float(obs.end[i2][0] - obs.start[i2][0]) >= MIN_DUR
    assert float(obs.speed[i2][0]) == 4000.0


def _check(sc, prep, chosen):
    """The check of ``chosen`` (options of ``prep``) under the rules of ``sc``."""
    return check_plan(dataclasses.replace(prep, scenario=sc), chosen)


def test_checker_flags_forged_observations(free):
    sc_free, prep = free
    sc_tight = _scenario()
    o = prep.opportunities.options
    route = np.asarray(o.route)
    mid = (np.asarray(o.t_start) + np.asarray(o.t_end)) / 2
    outside = int(np.flatnonzero((route == 1) & (np.abs(mid - DESIRED) > TOL + 1.0))[0])
    inside = int(np.flatnonzero((route == 1) & (np.abs(mid - DESIRED) <= TOL))[0])
    short = int(np.flatnonzero((route == 2) & (prep.opportunities.speed == 7000.0))[0])
    bad, det = _check(sc_tight, prep, [outside])
    assert bad == [outside]
    assert any("outside the desired time window [603, 617]" in v for v in det["violations"])
    bad, det = _check(sc_tight, prep, [inside])
    assert bad == [] and not det["violations"]
    bad, det = _check(sc_tight, prep, [short])
    assert bad == [short] and any("< min_duration 6 s" in v for v in det["violations"])
    assert _check(sc_free, prep, [outside])[0] == []  # the same options pass without them


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"mid_lo": 5.0, "mid_hi": 4.0}, "targets[0].mid_hi"),
        ({"min_duration": -1.0}, "targets[0].min_duration"),
        ({"min_duration": np.inf}, "targets[0].min_duration"),
        ({"duration": 5.0, "min_duration": 6.0}, "targets[0].duration"),
    ],
)
def test_make_targets_validates_the_new_fields(kw, field):
    kw = {"duration": 10.0, **kw}
    with pytest.raises(ValueError, match=field.replace("[", r"\[").replace("]", r"\]")):
        make_targets(POINT, 0.1, 0.2, **kw)


def test_concat_and_defaults_keep_the_fields():
    a = make_targets(POINT, 0.1, 0.2, duration=10.0)
    b = make_targets(STRIP, 0.1, 0.2, length=1e4, mid_lo=1.0, mid_hi=2.0, min_duration=1.0)
    c = a.concat(b)
    assert c.mid_lo.tolist() == [-np.inf, 1.0] and c.min_duration.tolist() == [0.0, 1.0]
    assert dataclasses.fields(c)[-1].name == "min_duration"
