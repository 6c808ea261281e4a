"""Refinement of start times: a route the grid cannot fit is inserted after refinement."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from _ref_refine import LinearRouteModel

from jaxspline.kernels.limits import AxisLimits
from jaxspline.screen import pairs as screen
from jaxspline.sequences import refine
from jaxspline.sequences import sequencer as sequence

# the screening fixtures and references live with the screen tests
sys.path.insert(0, str(Path(__file__).parents[1] / "screen"))
from test_screen import reach_kernels, ref_reachable  # noqa: E402, F401

LIM = AxisLimits(rate=np.array([0.05, 0.05]), accel=np.array([0.01, 0.01]))


def three_route_model():
    """A (fixed, ends at t = 10 s), B (window [15, 35] s, 5 s long), C (fixed at 40 s).

    Channel 0: A ends at 0 rad, B sits at 0.3 rad, C starts at 0 rad, all at rest.
    Rest-to-rest in exactly T reaches |D| <= b T - b^2/d (T >= b/d = 5 s), so
    0.3 rad needs T >= 11 s on both sides: t0_B in [21, 24] s. A grid of 5 start
    times (15, 20, 25, 30, 35 s) misses that interval. Channel 1 adds a small
    pitch-lead-like drift (0.001 rad/s of t0) and a slow scan on B.
    """
    return LinearRouteModel(
        angle0=np.array([[0.0, 0.0], [0.3, 0.01], [0.0, 0.0]]),
        lead=np.array([[0.0, 0.0], [0.0, 0.001], [0.0, 0.0]]),
        scan_rate=np.array([[0.0, 0.0], [0.0, 0.0005], [0.0, 0.0]]),
        t_ref=np.array([0.0, 25.0, 40.0]),
        duration=np.array([10.0, 5.0, 10.0]),
        t0_min=np.array([0.0, 15.0, 40.0]),
        t0_max=np.array([0.0, 35.0, 40.0]),
        value=np.array([3.0, 2.0, 3.0]),
    )


def test_refinement_inserts_route_the_grid_cannot_fit(reach_kernels):  # noqa: F811
    model = three_route_model()
    opts = model.grid_options(5)
    tr = screen.screen_transitions(opts, LIM, progress=False)
    grid = sequence.exact_plan(opts, tr)
    # the exact discrete optimum cannot contain B (route 1) on this grid
    assert 1 not in opts.route[grid.chosen].tolist()
    assert grid.value == pytest.approx(6.0)
    out = refine.try_insert(grid, opts, model, LIM, route=1, steps=200)
    assert out is not None
    plan, res = out
    assert opts.route[plan.chosen].tolist() == [0, 1, 2] and plan.value == pytest.approx(8.0)
    assert res.ok, res.report.violations
    assert res.margin_before.min() < 0 <= res.margin_after.min()
    t_b = res.t0[1]
    assert 21.0 - 1e-6 <= t_b <= 24.0 + 1e-6
    # independent check of the refined transitions with the numpy reference formula
    s = res.steps
    for k in range(2):
        T = s.t_start[k + 1] - s.t_end[k]
        assert np.all(
            ref_reachable(
                s.end_angle[k],
                s.end_rate[k],
                s.start_angle[k + 1],
                s.start_rate[k + 1],
                T,
                LIM.rate,
                LIM.accel,
                tol=1e-12,
            )
        )
    print(f"\nB start {t_b:.3f} s; margins before {res.margin_before} after {res.margin_after}")


def test_effort_objective_reduces_effort_and_stays_feasible(reach_kernels):  # noqa: F811
    model = three_route_model()
    opts = model.grid_options(41)  # fine grid: 0.5 s steps in B's window
    tr = screen.screen_transitions(opts, LIM, progress=False)
    plan = sequence.exact_plan(opts, tr)
    assert opts.route[plan.chosen].tolist() == [0, 1, 2]
    res = refine.refine_plan(plan, opts, model, LIM, objective="effort", steps=200)
    assert res.ok
    assert res.effort_after.sum() <= res.effort_before.sum() + 1e-12
    print(f"\neffort before {res.effort_before} after {res.effort_after}, B at {res.t0[1]:.3f} s")
    assert np.all(res.effort_after <= 1 + 1e-9)
    # the symmetric optimum puts B in the middle of [21, 24]
    assert res.t0[1] == pytest.approx(22.5, abs=0.3)
    res2 = refine.refine_plan(plan, opts, model, LIM, steps=200)
    assert res2.ok and res2.margin_after.min() >= res2.margin_before.min() - 1e-12
    assert np.all(np.isfinite(res2.history))


def test_costs_have_finite_gradients_at_window_edges_and_overlap(reach_kernels):  # noqa: F811
    import jax
    import jax.numpy as jnp

    model = three_route_model()
    route = jnp.array([0, 1, 2])

    @jax.jit
    def grads(t):
        def f(t):
            m, e = refine.plan_costs(model, route, t, LIM.rate, LIM.accel)
            return jnp.sum(m), jnp.sum(jnp.where(jnp.isfinite(e), e, 0.0))

        return jax.jacrev(lambda t: jnp.stack(f(t)))(t)

    # window edges, the feasibility interval edges 21 and 24 s, overlap with C (T <= 0)
    for t_b in (15.0, 21.0, 24.0, 35.0, 39.9, 45.0):
        g = grads(jnp.array([0.0, t_b, 40.0]))
        assert np.all(np.isfinite(np.asarray(g))), t_b


def test_value_errors(reach_kernels):  # noqa: F811
    model = three_route_model()
    opts = model.grid_options(3)
    plan = sequence.Plan(np.array([0, 3, 6]), 0.0)
    with pytest.raises(ValueError, match="objective"):
        refine.refine_plan(plan, opts, model, LIM, objective="nope")
    with pytest.raises(ValueError, match="steps"):
        refine.refine_plan(plan, opts, model, LIM, steps=0)
    with pytest.raises(ValueError, match="plan.chosen"):
        refine.refine_plan(sequence.Plan(np.array([0, 99]), 0.0), opts, model, LIM)
    with pytest.raises(ValueError, match="already"):
        refine.try_insert(plan, opts, model, LIM, route=1)
