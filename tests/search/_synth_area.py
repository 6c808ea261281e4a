"""Small synthetic area problems for the search tests, and their brute-force references.

A problem is built directly as a :class:`jaxspline.search.Problem` with a
:class:`jaxspline.search.cover.CoverTable` (no scenario, no JAX): satellites image
point targets (one or two options each, random start and length) and area strips.
Each satellite has passes of a few roll groups over slots of :data:`SLOT_S` seconds
over a grid of samples (:func:`make`): like real strips, neighbouring slots and
neighbouring rolls share a border, and passes and satellites cross each other.

Every satellite is rest-to-rest: the transition time between two lines of sight is
:func:`ref_need`, a step function of the angle between them (a settle time at 0),
read by the problem through a :class:`jaxspline.screen.slew_table.SlewTable` whose
entries sample the same steps. A group holds its roll: its line of sight is
``(sin r, 0, cos r)``; a point option looks at a roll of its own.

The references here never read the problem's arrays for what they check: they keep
the rows as Python sets (:attr:`Synth.rows`), every option as a plain record
(:attr:`Synth.opts`), and evaluate the rules themselves (:func:`feasible`,
:func:`plan_value`, :func:`enumerate_plans`, :func:`optimum` by HiGHS over the
enumerated per-satellite plans).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from jaxspline.search import BatteryModel, Problem
from jaxspline.search.cover import CoverTable
from jaxspline.search.store import NearPairs

SLOT_S = 10.0
#: (largest angle [deg], transition time [s]) steps of the synthetic slew model; the
#: rolls are multiples of 5 deg, so no realized angle lies near a step.
STEPS = ((2.5, 4.0), (7.5, 8.0), (12.5, 13.0), (22.5, 17.0), (180.0, 24.0))
FAR_S = 30.0  # every transition fits in this gap
TABLE_SIZE = 1 << 12


def ref_need(angle_rad: float) -> float:
    """Transition time [s] for a turn of ``angle_rad`` (the step function of :data:`STEPS`)."""
    deg = math.degrees(angle_rad)
    for top, t in STEPS:
        if deg <= top:
            return t
    return STEPS[-1][1]


def _table():
    from jaxspline.screen.slew_table import SlewTable

    theta = math.pi * (np.arange(TABLE_SIZE + 1) / TABLE_SIZE) ** 2
    return SlewTable(np.array([ref_need(float(x)) for x in theta]), TABLE_SIZE)


def los(roll_deg: float) -> tuple:
    r = math.radians(roll_deg)
    return (math.sin(r), 0.0, math.cos(r))


def angle(u, v) -> float:
    c = np.cross(u, v)
    return math.atan2(float(np.linalg.norm(c)), float(np.dot(u, v)))


@dataclass
class Opt:
    """One option as the references see it."""

    sat: int
    start: float
    end: float
    target: int
    roll: float  # [deg]: its line of sight (start and end)
    area: bool
    samples: frozenset = frozenset()  # an area option's covered samples
    window: tuple = (-1, -1, -1)  # an area option's (group, a, b)


@dataclass
class Synth:
    """A synthetic problem and what the references know of it.

    Attributes:
      pb: the Problem.
      opts: per option id its :class:`Opt`.
      rows: per row (group slot) the set of its samples.
      weight: float [N], each sample's value.
      point_value: per point target its value (targets 0..P-1; the areas follow).
      duty: per satellite ``(period, limit)`` or None.
      max_actions: the plan's cap or None.
    """

    pb: Problem
    opts: list
    rows: list
    weight: np.ndarray
    point_value: list
    duty: list | None
    max_actions: int | None
    groups: list = field(default_factory=list)  # (sat, roll, slot0, nslots, area)


def make(
    seed: int,
    n_sats: int = 1,
    passes: int = 1,
    groups: int = 3,
    pass_slots: int = 6,
    n_points: int = 3,
    nx: int = 8,
    ny: int = 10,
    min_slots: int = 1,
    max_slots: int = 3,
    max_actions: int | None = None,
    duty: tuple | None = None,
    area_min=None,
) -> Synth:
    """A random synthetic problem (module docstring).

    Samples lie on an ``nx x ny`` grid (x across the tracks, y along them), the left
    half area 0, the right half area 1. Group g of a pass covers the columns
    ``[x0 + 2 g, x0 + 2 g + 2]`` (neighbouring rolls share a column, as neighbouring
    strips share their border) and its slot t the rows ``[y0 + 2 t, y0 + 2 t + 2]`` (one
    slot's last row is the next one's first).
    """
    rng = np.random.default_rng(seed)
    xs, ys = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij"))
    area_of = (xs >= nx // 2).astype(np.int64)
    n_areas = 2
    raw = rng.uniform(0.2, 1.0, xs.size)
    share = raw / np.bincount(area_of, weights=raw)[area_of]
    prio = rng.uniform(2.0, 10.0, n_areas)
    weight = prio[area_of] * share
    horizon_slots = passes * (pass_slots + 4) + 2
    ggroups, rows = [], []
    for k in range(n_sats):
        for p in range(passes):
            p0 = 1 + p * (pass_slots + 4)
            x0 = int(rng.integers(-1, max(nx - 2 * groups, 0) + 1))
            y0 = int(rng.integers(-2, max(ny - 2 * pass_slots, 0) + 3))
            roll0 = int(rng.integers(-4, 1)) * 5
            for g in range(groups):
                lo = int(rng.integers(0, 2)) if g else 0
                hi = pass_slots - (int(rng.integers(0, 2)) if g != groups - 1 else 0)
                band = (xs >= x0 + 2 * g) & (xs <= x0 + 2 * g + 2)
                ggroups.append(
                    (k, float(roll0 + 5 * g), p0 + lo, hi - lo, int(x0 + 2 * g >= nx // 2))
                )
                for t in range(lo, hi):
                    m = band & (ys >= y0 + 2 * t) & (ys <= y0 + 2 * t + 2)
                    rows.append(frozenset(np.flatnonzero(m).tolist()))
    # options: area windows, then points
    opts = []
    row0 = np.concatenate([[0], np.cumsum([g[3] for g in ggroups])[:-1]])
    for gi, (k, roll, s0, n, a) in enumerate(ggroups):
        for length in range(min_slots, min(max_slots, n) + 1):
            for i in range(n - length + 1):
                cov = frozenset().union(*rows[row0[gi] + i : row0[gi] + i + length])
                if not cov:
                    continue
                t0, t1 = (s0 + i) * SLOT_S, (s0 + i + length) * SLOT_S
                window = (gi, s0 + i, s0 + i + length)
                opts.append(Opt(k, t0, t1, n_points + a, roll, True, cov, window))
    point_value = [float(v) for v in rng.integers(1, 6, n_points)]
    for t in range(n_points):
        for _ in range(int(rng.integers(1, 3))):
            k = int(rng.integers(n_sats))
            s = float(rng.uniform(0.0, horizon_slots * SLOT_S - 10.0))
            roll = float(rng.choice(np.arange(-20, 25, 5)))
            opts.append(Opt(k, round(s, 3), round(s + rng.uniform(3.0, 8.0), 3), t, roll, False))
    opts.sort(key=lambda o: (o.sat, o.start, o.target, o.end))
    cover = _cover(opts, rows, ggroups, weight, area_of, share, n_points, horizon_slots)
    cover.min_slots = np.full(n_sats, min_slots, np.int64)
    cover.max_slots = np.full(n_sats, max_slots, np.int64)
    if area_min is not None:
        cover.area_min = np.asarray(area_min, np.float64)
    duties = None if duty is None else [duty] * n_sats
    pb = _problem(opts, cover, point_value, n_sats, max_actions, duties)
    return Synth(pb, opts, rows, weight, point_value, duties, max_actions, ggroups)


def _cover(opts, rows, ggroups, weight, area_of, share, n_points, horizon_slots) -> CoverTable:
    """The CoverTable of the rows and options (strips of 1 slot and more)."""
    n_areas = int(area_of.max()) + 1
    indptr = np.concatenate([[0], np.cumsum([len(r) for r in rows])]).astype(np.int64)
    indices = np.array([s for r in rows for s in sorted(r)], np.int32)
    g = ggroups
    win = np.array([o.window for o in opts], np.int64).reshape(-1, 3)
    cover = CoverTable(
        indptr=indptr,
        indices=indices,
        group_sat=np.array([x[0] for x in g], np.int64),
        group_roll=np.array([x[1] for x in g], np.float64),
        group_pitch=np.zeros(len(g)),
        group_slot0=np.array([x[2] for x in g], np.int64),
        group_nslots=np.array([x[3] for x in g], np.int64),
        group_area=np.array([x[4] for x in g], np.int64),
        weight=weight,
        area=area_of.astype(np.int64),
        share=share,
        area_target=np.arange(n_points, n_points + n_areas, dtype=np.int64),
        area_min=np.full(n_areas, np.nan),
        slot_s=SLOT_S,
        n_slots=horizon_slots,
        min_slots=np.ones(1, np.int64),  # set by the caller
        max_slots=np.ones(1, np.int64),
        option_group=win[:, 0].copy(),
        option_a=win[:, 1].copy(),
        option_b=win[:, 2].copy(),
    )
    return cover


def _problem(opts, cover, point_value, n_sats, max_actions, duties) -> Problem:
    """The Problem: options in (satellite, start) order, every feasible point pair near."""
    n = len(opts)
    n_areas = cover.n_areas
    src, dst, need = [], [], []
    for i, a in enumerate(opts):
        for j, b in enumerate(opts):
            if a.area or b.area or a.sat != b.sat or i == j:
                continue
            gap = b.start - a.end
            t = ref_need(angle(los(a.roll), los(b.roll)))
            if 0.0 <= gap < FAR_S + 100.0 and gap >= t:
                src.append(i), dst.append(j), need.append(t)
    need = np.array(need, np.float64)
    sat = [o.sat for o in opts]
    lo = [int(np.searchsorted(sat, k, "left")) for k in range(n_sats)]
    hi = [int(np.searchsorted(sat, k, "right")) for k in range(n_sats)]
    n_targets = len(point_value) + n_areas
    target_options = [[] for _ in range(n_targets)]
    for c, o in enumerate(opts):
        target_options[o.target].append(c)
    table = _table()
    lit = np.ones((n_sats, 2), bool)
    return Problem(
        n_sats=n_sats,
        target_value=point_value + [0.0] * n_areas,
        option_target=[o.target for o in opts],
        option_sat=sat,
        option_start=[o.start for o in opts],
        option_end=[o.end for o in opts],
        option_first=[0.0] * n,
        option_start_los=[los(o.roll) for o in opts],
        option_end_los=[los(o.roll) for o in opts],
        tables=[table] * n_sats,
        pairs=NearPairs.from_arrays(n, np.array(src, np.int64), np.array(dst, np.int64), need),
        far=[FAR_S] * n_sats,
        battery=BatteryModel(lit, [None] * n_sats, 1e6),
        target_options=target_options,
        sat_lo=lo,
        sat_hi=hi,
        sat_starts=[[o.start for o in opts[a:b]] for a, b in zip(lo, hi, strict=True)],
        near_slack=100.0,
        cover=cover,
        max_actions=max_actions,
        duty=duties,
    )


# ----------------------------------------------------------------- references
def duty_peak(intervals, period: float) -> float:
    """Most imaging time [s] inside any window of length ``period`` (exact: the windowed
    sum is piecewise linear in the window's end, so its maximum lies where the end or the
    start of the window meets an interval's end point)."""
    ends = {b for _, b in intervals} | {a + period for a, _ in intervals}
    ends |= {a for a, _ in intervals} | {b + period for _, b in intervals}
    best = 0.0
    for t in ends:
        best = max(best, sum(max(0.0, min(b, t) - max(a, t - period)) for a, b in intervals))
    return best


def feasible(s: Synth, plan) -> bool:
    """Whether a plan (option ids) keeps every rule, checked from the records alone."""
    if s.max_actions is not None and len(plan) > s.max_actions:
        return False
    pts = [s.opts[c].target for c in plan if not s.opts[c].area]
    if len(pts) != len(set(pts)):
        return False
    by_sat = {}
    for c in plan:
        by_sat.setdefault(s.opts[c].sat, []).append(s.opts[c])
    for k, seq in by_sat.items():
        seq.sort(key=lambda o: o.start)
        for a, b in zip(seq, seq[1:], strict=False):
            if b.start - a.end < ref_need(angle(los(a.roll), los(b.roll))) - 1e-9:
                return False
        if s.duty is not None:
            period, limit = s.duty[k]
            if duty_peak([(o.start, o.end) for o in seq], period) > limit + 1e-9:
                return False
    return True


def plan_value(s: Synth, plan) -> float:
    """Point values of the distinct point targets plus the weight of the covered samples."""
    pts = {s.opts[c].target for c in plan if not s.opts[c].area}
    cov = set()
    for c in plan:
        if s.opts[c].area:
            cov |= s.opts[c].samples
    return sum(s.point_value[t] for t in pts) + float(sum(s.weight[i] for i in cov))


def enumerate_plans(s: Synth, k: int, most: int | None = None) -> list:
    """Every feasible plan of satellite k alone (tuples of option ids in time order), the
    empty one included, with at most ``most`` observations."""
    ids = sorted((c for c, o in enumerate(s.opts) if o.sat == k), key=lambda c: s.opts[c].start)
    cap = most if most is not None else (s.max_actions if s.max_actions is not None else 10**9)
    out = []
    duty = None if s.duty is None else s.duty[k]

    def grow(seq, targets, pos):
        out.append(tuple(seq))
        if len(seq) >= cap:
            return
        last = s.opts[seq[-1]] if seq else None
        for j in range(pos, len(ids)):
            c = ids[j]
            o = s.opts[c]
            if not o.area and o.target in targets:
                continue
            if last is not None:
                if o.start - last.end < ref_need(angle(los(last.roll), los(o.roll))) - 1e-9:
                    continue
            if duty is not None:
                iv = [(s.opts[x].start, s.opts[x].end) for x in seq] + [(o.start, o.end)]
                if duty_peak(iv, duty[0]) > duty[1] + 1e-9:
                    continue
            seq.append(c)
            grow(seq, targets | ({o.target} if not o.area else set()), j + 1)
            seq.pop()

    grow([], frozenset(), 0)
    return out


def optimum(s: Synth) -> tuple[float, list]:
    """The best plan's value and options: HiGHS (``scipy.optimize.milp``) choosing one
    enumerated plan per satellite, each point target at most once, the action cap, the
    samples covered by the chosen plans."""
    from scipy.optimize import Bounds, LinearConstraint, milp
    from scipy.sparse import lil_matrix

    n_sats = s.pb.n_sats
    plans = [(k, p) for k in range(n_sats) for p in enumerate_plans(s, k)]
    n_p, n_s = len(plans), s.weight.size
    n_t = len(s.point_value)
    nv = n_p + n_s
    cost = np.zeros(nv)
    for i, (_, p) in enumerate(plans):
        cost[i] = -sum(s.point_value[s.opts[c].target] for c in p if not s.opts[c].area)
    cost[n_p:] = -s.weight
    rows = n_sats + n_t + n_s + 1
    a = lil_matrix((rows, nv))
    lo, hi = np.zeros(rows), np.zeros(rows)
    for i, (k, p) in enumerate(plans):
        a[k, i] = 1.0
        for c in p:
            o = s.opts[c]
            if not o.area:
                a[n_sats + o.target, i] = 1.0
        cov = set().union(*(s.opts[c].samples for c in p if s.opts[c].area))
        for j in cov:
            a[n_sats + n_t + j, i] = -1.0
        a[rows - 1, i] = len(p)
    lo[:n_sats], hi[:n_sats] = 1.0, 1.0
    lo[n_sats : n_sats + n_t], hi[n_sats : n_sats + n_t] = -np.inf, 1.0
    for j in range(n_s):  # y_j <= sum of the plans covering j
        a[n_sats + n_t + j, n_p + j] = 1.0
    lo[n_sats + n_t : rows - 1], hi[n_sats + n_t : rows - 1] = -np.inf, 0.0
    lo[-1] = -np.inf
    hi[-1] = s.max_actions if s.max_actions is not None else 10**9
    integrality = np.r_[np.ones(n_p), np.zeros(n_s)]
    res = milp(
        cost,
        constraints=LinearConstraint(a.tocsr(), lo, hi),
        integrality=integrality,
        bounds=Bounds(0.0, 1.0),
        options={"mip_rel_gap": 0.0},
    )
    assert res.success, res.message
    chosen = [c for i, (_, p) in enumerate(plans) if res.x[i] > 0.5 for c in p]
    return -float(res.fun), chosen
