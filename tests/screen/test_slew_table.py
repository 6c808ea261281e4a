"""The rest-to-rest SlewTable is an upper bound of the exact slew time.

Reference: :func:```sat.maneuver.slew_time```, the exact profile time (slew
kernel + settle + gap margin) that the plan's final check uses. The flexible
profile's time is not monotone in the angle (SPEC section 2: profile A ends at
``7/6 omega^2/eps`` with ``sqrt(28/3) b`` and profile C starts there at ``3 b``), so a
table read at grid nodes alone under-estimates it in the grid cell holding that switch.
Every lookup (numpy batched, Python scalar, and the fused JAX screen the planner uses
for its near pairs) must be >= the exact time at >= 1e5 angles over [0, pi], dense
around the switch, around 1.63 rad (the switch of the slow flexible satellite below)
and around every grid node.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import jaxspline
from jaxspline.base.elements import circular_orbit_over
from jaxspline.geometry.frames import angle_between
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.mission import FlexMode, Satellite
from jaxspline.screen import pairs as screen
from jaxspline.screen import slew_table
from jaxspline.screen.options import RouteOptions

_SC = jaxspline.default_scenario()
_GAP = float(_SC.planner.margins.gap)  # what planner.plan passes to slew_table
_REST = [s for s in _SC.satellites if s.maneuver.rest_to_rest]


def _slow_flexible():
    """Flexible satellite whose A -> C switch is at 1.63 rad (test_screen_models' limits)."""
    orb = circular_orbit_over(math.radians(46.0), math.radians(15.0), 300.0, 0.0, altitude=550e3)
    return Satellite(
        "slow-flex",
        orb,
        model="flexible",
        limits=AxisLimits(np.radians(2.0), np.radians(0.05)),
        settle=2.0,
        flex=FlexMode(freq=2 * np.pi * 0.5, damping=0.01, tolerance=1e-6),
    )


# (satellite, table size): every rest-to-rest satellite of the default scenario at the
# planner's table size, plus the slow flexible one at the planner's size and at 4096
CASES = [(s, None) for s in _REST] + [(_slow_flexible(), None), (_slow_flexible(), 4096)]
IDS = [f"{s.name}-{n or 'default'}" for s, n in CASES]


def _switch(sat):
    """A -> C switch angle of a flexible satellite [rad] (SPEC section 2), else None."""
    if sat.model != "flexible":
        return None
    return 7.0 / 6.0 * float(sat.limits.rate) ** 2 / float(sat.limits.accel)


def _angles(sat, size):
    """>= 1e5 test angles over [0, pi] [rad]."""
    rng = np.random.default_rng(20)
    nodes = math.pi * (np.arange(size + 1) / size) ** 2
    parts = [
        rng.uniform(0.0, math.pi, 40_000),
        np.linspace(0.0, math.pi, 20_001),
        np.linspace(1.62, 1.64, 20_001),
        np.logspace(-16, -3, 2_000),
        nodes[:: max(1, size // 8192)],
        np.nextafter(nodes, np.inf)[:: max(1, size // 8192)],
        (nodes * (1.0 + 1e-12))[:: max(1, size // 8192)],
    ]
    sw = _switch(sat)
    if sw is not None:
        parts += [
            sw + np.linspace(-2e-3, 2e-3, 20_001),
            sw * (1.0 + np.arange(-50, 51) * 2.0**-52),
        ]
    theta = np.clip(np.concatenate(parts), 0.0, math.pi)
    assert theta.size >= 100_000
    return theta


def _table(sat, size):
    return (
        slew_table.slew_table(sat, _GAP) if size is None else slew_table.slew_table(sat, _GAP, size)
    )


@pytest.mark.parametrize(("sat", "size"), CASES, ids=IDS)
def test_slew_table_never_below_exact_time(sat, size):
    table = _table(sat, size)
    theta = _angles(sat, table.size)
    exact = np.asarray(sat.maneuver.slew_time(sat, theta, _GAP))
    batched = table(theta)
    under = exact - batched
    assert (under > 0).sum() == 0, (
        f"batched lookup below the exact time at {(under > 0).sum()} of {theta.size} "
        f"angles, by up to {under.max():.3g} s at theta = {theta[np.argmax(under)]!r}"
    )
    scalar = np.array([table.scalar(float(x)) for x in theta])
    np.testing.assert_array_equal(scalar, batched)
    # tight: the excess is the rise of the time over one grid cell, except in the one
    # cell that holds the flexible A -> C switch, which keeps the whole drop
    # (sqrt(28/3) - 3) omega/eps (plus that rise)
    over = batched - exact
    k = np.minimum(np.ceil(table.size * np.sqrt(theta / math.pi) - 1e-12), table.size)
    sw = _switch(sat)
    away = np.ones(theta.size, bool)
    if sw is not None:
        k_sw = math.ceil(table.size * math.sqrt(sw / math.pi) - 1e-12)
        away = np.abs(k - k_sw) > 1
        drop = (math.sqrt(28.0 / 3.0) - 3.0) * float(sat.limits.rate / sat.limits.accel)
        assert over[~away].max() < drop + 0.05
    limit = 0.05 if size is None else 0.5  # 4096 cells: 16x the planner's cell width
    assert over[away].max() < limit and over[away].mean() < limit / 10


@pytest.mark.parametrize(("sat", "size"), CASES[-3:-1], ids=IDS[-3:-1])
def test_slew_table_screen_lookup_never_below_the_plan_check(sat, size):
    """The fused JAX screen (the planner's near pairs) against the plan check's angle."""
    table = _table(sat, size)
    theta = _angles(sat, table.size)[::2]
    n = theta.size
    rng = np.random.default_rng(5)
    u = rng.normal(size=(n, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    w = np.cross(u, rng.normal(size=(n, 3)))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    v = np.cos(theta)[:, None] * u + np.sin(theta)[:, None] * w
    # options 0..n-1 end looking along u, options n..2n-1 start looking along v
    z = np.zeros((2 * n, 1))
    t0 = 1000.0 * np.arange(2 * n)
    opt = RouteOptions(
        route=np.arange(2 * n, dtype=np.int32),
        t_start=t0,
        t_end=t0 + 1.0,
        start_angle=z,
        start_rate=z,
        end_angle=z,
        end_rate=z,
        value=np.ones(2 * n),
        scan_ok=np.ones(2 * n, bool),
        start_los=np.concatenate([u, v]),
        end_los=np.concatenate([u, v]),
    )
    src, dst = np.arange(n), n + np.arange(n)
    t_req = screen.screen_pairs(opt, table, src, dst).t_min
    exact = np.asarray(sat.maneuver.slew_time(sat, angle_between(u, v), _GAP))  # plan_check's
    under = exact - t_req
    assert (under > 0).sum() == 0, f"{(under > 0).sum()} pairs, up to {under.max():.3g} s"
    # the planner's numpy path (first_requirements, pair_requirements) likewise; its angle
    # formula differs from the screen's by rounding, so the cells may differ near 0
    assert np.all(sat.maneuver.pair_requirements(sat, opt, src, dst, table) >= exact)
