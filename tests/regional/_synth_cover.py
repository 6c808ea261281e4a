"""Small synthetic coverage problems for the search and bound tests.

Samples sit on an ``nx x ny`` grid (two regions: left and right half). Each satellite
has a few passes; a pass has ``n_rolls`` groups (rolls) over ``n_slots`` slots; the row
(group g, slot t) of a pass covers the samples with ``x`` in a band of width ``width``
that starts at ``x0 + g`` and ``y`` in ``[y0 + t * dy, y0 + (t + 1) * dy]`` (closed, so
slots of one group share their border samples, as real strips do).
"""

from __future__ import annotations

import numpy as np

from jaxspline.search.coverage_problem import CoverProblem, sample_weights
from jaxspline.search.coverage_rules import Margins, SatRules

SLOT_S = 10.0
MESH_S = 5.0


def rules(**kw) -> SatRules:
    """Default SatRules of a synthetic satellite, fields overridable."""
    base = dict(
        min_dur_s=20.0,
        max_dur_s=60.0,
        min_edge_deg=16.0,
        max_edge_deg=40.0,
        fov_deg=4.8,
        rate_deg_s=1.8,
        accel_deg_s2=0.7,
        settle_s=1.5,
        period_s=5700.0,
        duty_limit_s=np.inf,
        capacity_wh=100.0,
        initial_wh=60.0,
        idle_w=100.0,
        imaging_w=300.0,
        slew_w=50.0,
        charge_w=250.0,
    )
    base.update(kw)
    return SatRules(**base)


def make_problem(
    seed=0,
    n_sats=2,
    passes_per_sat=2,
    n_rolls=4,
    n_slots=6,
    nx=12,
    ny=10,
    width=3,
    dy=2,
    max_actions=4,
    horizon_s=2000.0,
    region_min=None,
    sat_rules=None,
    margins=None,
) -> CoverProblem:
    """A random synthetic CoverProblem (see the module docstring).

    Returns:
      CoverProblem.
    """
    rng = np.random.default_rng(seed)
    xs, ys = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    xs, ys = xs.ravel(), ys.ravel()
    region = (xs >= nx // 2).astype(np.int32)
    wm2 = rng.uniform(0.5, 1.5, xs.size)
    totals = np.bincount(region, weights=wm2) * rng.uniform(1.0, 1.1, 2)
    weight, ratio = sample_weights(region, wm2, totals, np.array([1.0, 2.0]))
    rows, gs = [], []
    n_slot_total = int(horizon_s // SLOT_S)
    for s in range(n_sats):
        starts = np.sort(rng.choice(n_slot_total - n_slots - 2, passes_per_sat, replace=False))
        for p in range(passes_per_sat):
            x0 = int(rng.integers(-2, nx - 2))
            y0 = int(rng.integers(-2, ny // 2))
            slot0 = int(starts[p]) + 1
            for g in range(n_rolls):
                gs.append((s, 20.0 + 0.7 * g + 0.1 * p, slot0, n_slots, len(rows)))
                for t in range(n_slots):
                    lo_x, lo_y = x0 + g, y0 + t * dy
                    m = (xs >= lo_x) & (xs < lo_x + width) & (ys >= lo_y) & (ys <= lo_y + dy)
                    rows.append(np.nonzero(m)[0].astype(np.int32))
    indptr = np.concatenate([[0], np.cumsum([len(r) for r in rows])]).astype(np.int64)
    indices = np.concatenate(rows).astype(np.int32) if rows else np.zeros(0, np.int32)
    g = np.array(gs, dtype=np.float64)
    mesh = np.arange(0.0, horizon_s + MESH_S / 2, MESH_S)
    sunlit = (np.arange(mesh.size - 1)[None, :] // 40 + np.arange(n_sats)[:, None]) % 3 != 0
    rmin = np.full(2, np.nan) if region_min is None else np.asarray(region_min, float)
    prob = CoverProblem(
        indptr=indptr,
        indices=indices,
        group_sat=g[:, 0].astype(np.int32),
        group_roll=g[:, 1],
        group_slot0=g[:, 2].astype(np.int64),
        group_nslots=g[:, 3].astype(np.int64),
        group_row0=g[:, 4].astype(np.int64),
        weight=weight,
        ratio_weight=ratio,
        region=region,
        region_min=rmin,
        rules=tuple(sat_rules or [rules() for _ in range(n_sats)]),
        mesh_s=mesh,
        sunlit_iv=sunlit,
        slot_s=SLOT_S,
        horizon_s=horizon_s,
        max_actions=max_actions,
        margins=Margins() if margins is None else margins,
    )
    prob.validate()
    return prob
