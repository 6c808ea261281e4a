"""The battery-priced bound where a budget is already spent before any load.

Reference: the timeline itself (written to refuse every insertion once the battery
starts below the margin), so the only plan is the empty one; a bound must stay >= 0.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from test_timeline_battery import DT, _problem

from jaxspline.readers.mission import Power
from jaxspline.search import BatteryModel, Timeline, greedy, upper_bound


def test_a_budget_spent_before_any_load_never_pulls_the_bound_below_zero():
    """Initial level under the margin: no insertion fits and the energy-priced bound
    stays >= 0 (a budget <= 0 priced would drive it to -inf)."""
    rng = np.random.default_rng(3)
    n_steps = 120
    pb, lit = _problem(rng, n_steps, n_sats=2)
    power = Power(capacity_wh=40.0, initial_wh=2.0, idle_w=5.0, imaging_w=300.0,
                  slew_w=100.0, charge_w=0.0)  # fmt: skip
    battery = BatteryModel(lit, [power, power], DT, margin_wh=5.0)
    pb = dataclasses.replace(pb, battery=battery)
    tl = Timeline(pb)
    greedy(tl, math.inf)
    assert tl.value == 0.0
    # step target: the empty plan's 0, iterated far past the usual step floor
    res = upper_bound(pb, 0.0, math.inf, max_iters=2000, energy=True, mu_min=1e-9)
    assert res.bound >= 0.0
