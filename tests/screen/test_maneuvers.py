"""The maneuver-model protocol: the built-in models, the registry, a model in one file.

References: a new rest-to-rest model written here (a constant-rate turn, time = angle /
rate, no acceleration phase) is planned through the same machinery as the built-in ones;
its screened feasibility and required times are checked against the angle between the
lines of sight computed independently with numpy (``arccos`` of the dot product).
"""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from test_screen_models import _los_options

from jaxspline.base.elements import circular_orbit_over
from jaxspline.base.models import BUILTIN_MODELS as MODELS
from jaxspline.kernels.limits import AxisLimits
from jaxspline.readers.mission import Satellite
from jaxspline.readers.scenario import parse_scenario
from jaxspline.screen import pairs as screen
from jaxspline.screen.models import (
    EigenAxis,
    ManeuverModel,
    RestToRest,
    maneuver_model,
    model_names,
    register_model,
)
from jaxspline.screen.slew_table import slew_table

SETTLE, GAP, SIZE = 1.5, 0.25, 4096
RATE = math.radians(1.0)


class ConstantRate(RestToRest):
    """Turns at its rate bound from the first instant (an infinitely stiff wheel)."""

    name = "test_constant_rate"

    def profile_time(self, sat, theta):
        return np.asarray(theta, np.float64) / float(sat.limits.rate)


def _sat(model):
    orb = circular_orbit_over(math.radians(46.0), math.radians(15.0), 300.0, 0.0, altitude=550e3)
    return Satellite("cr", orb, model=model, limits=AxisLimits(RATE, RATE), settle=SETTLE)


def test_builtin_models_follow_the_protocol():
    assert MODELS == ("per_channel", "eigen_axis", "flexible", "roll_only")
    for name in MODELS:
        m = maneuver_model(name)
        assert isinstance(m, ManeuverModel) and m.name == name
    assert not maneuver_model("per_channel").rest_to_rest
    assert maneuver_model("flexible").extra_fields == ("flex",)


def test_a_new_model_is_one_class_and_screens_like_the_numpy_reference():
    register_model(ConstantRate())
    assert "test_constant_rate" in model_names()
    sat = _sat("test_constant_rate")
    table = slew_table(sat, GAP, size=SIZE)
    opt = _los_options(7)
    tr = screen.screen_transitions(opt, table, progress=False, chunk_size=512)
    cos = np.sum(opt.end_los[tr.src] * opt.start_los[tr.dst], -1)
    exact = np.arccos(np.clip(cos, -1.0, 1.0)) / RATE + SETTLE + GAP
    assert 0.1 < tr.feasible.mean() < 0.9
    # the table bounds the exact time from above, by at most one cell's rise: the widest
    # cell of the grid pi (k/N)^2 spans 2 pi / N rad
    cell = 2.0 * math.pi / SIZE / RATE
    t = tr.t_min[tr.feasible]
    assert np.all(t >= exact[tr.feasible]) and np.all(t - exact[tr.feasible] <= cell)
    clear = np.abs(tr.T - exact) > cell  # away from the table's rounding band
    np.testing.assert_array_equal(tr.feasible[clear], (tr.T >= exact)[clear])
    need = sat.maneuver.pair_requirements(sat, opt, tr.src, tr.dst, table)
    np.testing.assert_array_equal(np.isfinite(need), tr.feasible)
    far = sat.maneuver.far_gap(sat, opt, np.arange(len(opt.route)), 1e-3, table)
    assert far >= (2 * sat.off_nadir_max + 1e-3 * far) / RATE + SETTLE + GAP


def test_register_model_rejects_incomplete_and_taken_names():
    with pytest.raises(ValueError, match="lacks members"):
        register_model(object())

    class Taken(EigenAxis):
        pass

    with pytest.raises(ValueError, match="'eigen_axis' is taken"):
        register_model(Taken())

    class BadLaw(ConstantRate):
        name = "test_bad_law"
        attitude_law = "spin"

    with pytest.raises(ValueError, match="attitude_law"):
        register_model(BadLaw())


def test_unknown_model_names_the_field():
    with pytest.raises(ValueError, match=r"satellite 'cr': model must be one of .*'rigid'"):
        _sat("rigid")
    toml = (
        '[scenario]\nepoch = "2026-04-14T00:00:00Z"\nduration_s = 600.0\n'
        "[[satellites]]\naltitude_km = 600.0\nmodel = 'rigid'\n"
        "[[targets]]\nlat_deg = 46.0\nlon_deg = 15.0\n"
    )
    with pytest.raises(ValueError, match=r"satellites\[0\]\.model.*must be one of.*'rigid'"):
        parse_scenario(tomllib.loads(toml), text=toml)
