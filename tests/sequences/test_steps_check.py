"""The independent validator catches every kind of planted defect."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from jaxspline.kernels.limits import AxisLimits
from jaxspline.screen import pairs as screen
from jaxspline.screen.options import RouteOptions, take_options
from jaxspline.sequences import sequencer as sequence
from jaxspline.sequences import steps_check

# the screening fixtures and references live with the screen tests
sys.path.insert(0, str(Path(__file__).parents[1] / "screen"))
from test_screen import LIMITS, reach_kernels, synthetic_options  # noqa: E402, F401


def steps_of(opt, idx):
    return take_options(opt, idx)


@pytest.fixture
def good_plan(reach_kernels):  # noqa: F811
    rng = np.random.default_rng(4)
    opt = synthetic_options(rng, n_routes=7, per_route=3, horizon=400.0)
    tr = screen.screen_transitions(opt, LIMITS, progress=False)
    plan = sequence.exact_plan(opt, tr)
    assert plan.chosen.size >= 3
    return opt, plan


def test_good_plan_passes(good_plan):
    opt, plan = good_plan
    steps = steps_of(opt, plan.chosen)
    rep = steps_check.check_steps(steps, LIMITS, windows=(steps.t_start - 1, steps.t_start + 1))
    assert rep.ok and rep.violations == []
    assert np.all(rep.peak_rate <= LIMITS.rate * (1 + 1e-9))
    assert np.all(rep.peak_accel <= LIMITS.accel * (1 + 1e-9))
    assert np.all(rep.peak_accel > 0)
    # float32 plan passes with float32 tolerances
    s32 = RouteOptions(
        *(a.astype(np.float32) if a is not None and a.dtype == np.float64 else a for a in steps)
    )
    assert steps_check.check_steps(s32, LIMITS).ok
    # a single step and the empty plan are valid
    assert steps_check.check_steps(steps_of(opt, plan.chosen[:1]), LIMITS).ok
    assert steps_check.check_steps(steps_of(opt, plan.chosen[:0]), LIMITS).ok


def _violations(steps, **kw):
    rep = steps_check.check_steps(steps, LIMITS, **kw)
    assert not rep.ok
    return " | ".join(rep.violations)


def test_planted_overlap(good_plan):
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    shift = s.t_start[1] - s.t_end[0] + 2.0  # step 1 starts 2 s before step 0 ends
    s = s._replace(t_start=s.t_start.copy(), t_end=s.t_end.copy())
    s.t_start[1:] -= shift
    s.t_end[1:] -= shift
    assert "overlap" in _violations(s)


def test_planted_too_short_transfer(good_plan):
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    s = s._replace(t_start=s.t_start.copy(), t_end=s.t_end.copy())
    gap = s.t_start[1] - s.t_end[0]
    s.t_start[1:] -= gap - 0.05  # T = 0.05 s, far too short for the angle change
    s.t_end[1:] -= gap - 0.05
    text = _violations(s)
    assert "transition 0 -> 1" in text and "overlap" not in text


def test_planted_repeated_route(good_plan):
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    s.route[2] = s.route[0]
    assert f"route {s.route[0]} imaged 2 times" in _violations(s)


def test_planted_out_of_window(good_plan):
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    lo, hi = s.t_start - 5.0, s.t_start + 5.0
    hi[1] = s.t_start[1] - 0.5
    assert "step 1" in _violations(s, windows=(lo, hi))


def test_planted_rate_violation_and_scan_flag(good_plan):
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    s.start_rate[1, 0] = 1.2 * LIMITS.rate[0]
    assert "start_rate" in _violations(s)
    s = steps_of(opt, plan.chosen)
    s.scan_ok[0] = False
    assert "scan_ok" in _violations(s)


def test_numpy_checks_do_not_trust_the_trajectory(good_plan, monkeypatch):
    """Faulty trajectories (as a buggy kernel could return) are rejected by the samples."""
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    real = steps_check._transfer

    def too_fast(*args):
        f, fd, fdd = (np.asarray(x) for x in real(*args))
        return f, 3.0 * fd, fdd  # rate exceeds the bound, angle no longer its integral

    monkeypatch.setattr(steps_check, "_transfer", too_fast)
    text = _violations(s)
    assert "peak rate" in text or "rate" in text
    assert "integral" in text

    def straight(a1, b1, a2, b2, T, limits, t):
        # straight-line angle: right end angles, wrong boundary rates, accel not reported
        lam = np.asarray(t) / T
        f = (1 - lam) * a1 + lam * a2
        fd = np.broadcast_to((a2 - a1) / T, f.shape)
        return f, fd, np.zeros_like(f)

    monkeypatch.setattr(steps_check, "_transfer", straight)
    text = _violations(s)
    assert "start rate" in text or "end rate" in text

    def jerky(*args):
        f, fd, fdd = (np.asarray(x) for x in real(*args))
        wiggle = 1e-4 * np.sin(np.linspace(0, 400 * np.pi, f.shape[-1]))
        return f, fd + wiggle, np.zeros_like(fdd)  # accel hidden, visible in rate slopes

    monkeypatch.setattr(steps_check, "_transfer", jerky)
    assert "acceleration" in _violations(s)


def test_value_errors(good_plan):
    opt, plan = good_plan
    s = steps_of(opt, plan.chosen)
    with pytest.raises(ValueError, match="samples"):
        steps_check.check_steps(s, LIMITS, samples=2)
    with pytest.raises(ValueError, match="limits.accel"):
        steps_check.check_steps(s, AxisLimits(rate=0.1, accel=-1.0))
    with pytest.raises(ValueError, match="steps"):
        steps_check.check_steps(s._replace(end_rate=s.end_rate[:, :1]), LIMITS)
