"""Per-satellite exact DP coordinated by Lagrangian target prices: plans and an upper bound.

Relaxing "each target is imaged at most once" with prices ``lam_t`` splits the problem
into one longest-path problem per satellite over its options in start order
(:func:`dp_paths`): ``best[j] = w_j - lam_t(j) + max(base_j, far predecessors, near
compatible predecessors)``, far ones (gap >= ``far[sat]``, always compatible) through
a running maximum, near ones through the screened feasible pairs. In
:func:`lagrangian` the battery enters as energy budgets from the horizon start priced by
``nu >= 0`` (:mod:`jaxspline.search.energy`: options and near pairs pay for their
energy, the bound gains each price times its budget); otherwise it is dropped.
``UB(lam) = sum_k DP_k(lam) + sum_t lam_t (+ sum_b nu_b B_b / unit_b)``.

Weak duality with repeats. The rules let a plan image a target more than once (it
counts once), and dropping a repeat is not always possible (an observation can be
the bridge that makes a long maneuver feasible). Let a plan image target t ``n_t`` times.
Its satellites' sequences are feasible paths, so ``sum_k DP_k >= sum_t n_t (w_t -
lam_t)`` and ``UB >= sum_t [n_t w_t - (n_t - 1) lam_t]``. For ``0 <= lam_t <= w_t``
each term is ``>= w_t`` if ``n_t >= 1`` and ``>= 0`` otherwise: UB >= the plan's value.
Prices are therefore kept in ``[0, w_t]`` (projected subgradient), which makes UB an
upper bound of every plan of the option model, repeats included.

Repeats in a row count once (the strengthened relaxation, ``merge_repeats``). Within
one pass a satellite can often image a target twice in a row (two of its options a few
seconds apart, joined by a near pair); the plain DP credits both (``2 (w_t - lam_t)``)
and the prices alone cannot take this back, since lowering it needs ``lam_t -> w_t``,
which makes the target worthless to every other satellite. With ``merge_repeats`` a
near pair between two options of one target costs the second option's value, so a run
of consecutive options of one target on one path is credited once. The argument above
holds with ``n_t`` the number of such runs (>= 1 when t is imaged; a plan's path takes
every near pair it uses, and a DP that does not merge a run, e.g. through a far
transition, only overestimates): the bound stays valid for every plan, repeats
included. On the 0.5 h slice of the 12 x 12 h preset it closes most of the integrality
gap (docs/scale.md); the DP's cost is one extra subtraction per repeat pair. The
search's Lagrangian phase iterates the plain relaxation (its DP paths seed its repaired
plans, which stay as they were); :func:`upper_bound`, the bound worker and the sharded
bound iterate the strengthened one.

Areas. The relaxation prices samples as it prices targets: an area sample ``s`` of
weight ``w_s`` has a price ``0 <= lam_s <= w_s``, a row (one slot of a roll group) is
credited the ``w_s - lam_s`` of its samples (a sample on the border of two slots of one
strip twice: the credit only grows, so the bound stays valid), and the bound gains
``sum_s lam_s``: ``UB = sum_k DP_k + AREA + sum_t lam_t + sum_s lam_s``, where the area
options (never screened pair by pair) leave the satellites' DPs and ``AREA`` is the
exact value of their own relaxation at the row credits
(:func:`jaxspline.search.pass_bound.area_dp`: per pass, a knapsack over passes under the
action cap). Relaxing the coupling of the two on one satellite only raises the bound.
The argument above holds with ``n_s`` the number of chosen rows covering s; the
subgradient of a sample is that number minus one.

Stereo targets. Their looks leave the satellites' DPs too, and the bound adds each
stereo target's best product value (what it collects when no other look competes).

The action cap. With ``max_actions`` and options of both kinds (points or strips and
area strips) the cap couples them; a price ``mu >= 0`` on it relaxes the coupling: every
option of a satellite's DP pays ``mu``, a pass with ``r`` runs of :func:`area_dp` pays
``r mu`` (its knapsack keeps the cap too) and the bound gains ``mu max_actions``. A plan
of ``n <= max_actions`` actions is charged at most ``n mu`` (a merged repeat is charged
once, a look never), so the bound stays above it; the subgradient is the relaxed
solution's charged actions minus the cap. Without points it never binds (the knapsack
keeps the cap: ``mu`` stays 0).

Every :data:`_REPAIR_EVERY`-th iteration also repairs the DP paths into a feasible
plan (each target once, heaviest first, re-checked insertion incl. battery, then greedy
fill); its value sets the step size.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from jaxspline.base import clock
from jaxspline.search.cover import gather_ranges
from jaxspline.search.dp import dp_paths, dp_prepare
from jaxspline.search.energy import EnergyBudgets
from jaxspline.search.lns import greedy
from jaxspline.search.pass_bound import area_dp, pass_layout, run_options
from jaxspline.search.problem import Problem
from jaxspline.search.status import BoundStatus
from jaxspline.search.timeline import Timeline

__all__ = ["BoundResult", "lagrangian", "plan_from_paths", "run_targets", "upper_bound"]

_STALL_ITERS = 4  # iterations without a better bound before the step halves
_MU_MIN = 1e-4  # the iteration stops (stalled) below this step factor
#: ... in :func:`upper_bound` (the bound alone: worker, ``jaxspline bound``). The halvings
#: from 1e-3 to 1e-4 lowered the converged bound by 0.009 % on the 12 x 12 h preset
#: (23,705.6 -> 23,703.5, iterations 231 -> 329) and by 0.0085 % on the constellation
#: day (97,812.2 -> 97,803.9, 310 -> 409 iterations: more than a 540 s run has).
BOUND_MU_MIN = 1e-3
_GAP_TOL = 1e-9  # bound - best plan below this: optimal
_REPAIR_EVERY = 4  # DP iterations per repaired plan (a repair costs ~2 block DPs)
_SAMPLE_PRICE0 = 0.8  # start price of an area sample, a share of its weight
#: ... with area samples priced (their many prices move slowly: on a regional_coverage
#: training case 10 stalls lowered the converged bound from 0.99977 to 0.99761)
_AREA_STALL_ITERS = 10


def run_targets(targets: np.ndarray) -> np.ndarray:
    """The targets a path is credited for by the strengthened relaxation: ``targets`` (its
    options' targets, in time order) with each run of one target kept once."""
    if targets.size:
        return targets[np.r_[True, targets[1:] != targets[:-1]]]
    return targets


def plan_from_paths(tl: Timeline, paths, order_fill, deadline: float) -> None:
    """Replace the plan of ``tl`` by one repaired from DP paths.

    Each target once (heaviest first, earliest option), then the paths' area options,
    every insertion re-checked (maneuvers, battery), then a greedy fill: a feasible plan
    whatever the paths.

    Args:
      tl: Timeline (its plan is replaced).
      paths: per satellite the option ids of a DP path.
      order_fill: target order of the greedy fill.
      deadline: float, ``time.monotonic()`` value at which the fill stops [s].
    """
    pb = tl.pb
    tl.restore([])
    chosen = sorted(
        (c for p in paths for c in p),
        key=lambda c: (-pb.target_value[pb.option_target[c]], pb.option_start[c]),
    )
    for c in chosen:
        if tl.assigned[pb.option_target[c]] < 0 and tl.check(c) is not None:
            if not pb.is_area(c) or tl.cover.gain(*_window(pb, c)) > 0.0:
                tl.insert(c)
    greedy(tl, deadline, order_fill)


def _window(pb: Problem, c: int) -> tuple:
    """(group, a, b) of area option c."""
    cv = pb.cover
    return int(cv.option_group[c]), int(cv.option_a[c]), int(cv.option_b[c])


@dataclass(frozen=True)
class BoundResult:
    """Outcome of :func:`lagrangian`.

    Attributes:
      best: the options of the best repaired plan (:meth:`Timeline.plan`).
      bound: the smallest upper bound seen (``inf`` if no iteration ran).
      iterations: subgradient iterations.
      status: :class:`BoundStatus`: ``OPTIMAL`` (bound met by a plan), ``CONVERGED``
        (zero subgradient or the step fell below its floor) or ``TIME`` (stopped by
        the deadline / cap).
      seconds: wall time of the iteration [s] (0 where not measured).
    """

    best: list
    bound: float
    iterations: int
    status: BoundStatus
    seconds: float = 0.0


class Prices:
    """Projected Polyak subgradient iteration on the prices (shared by both users).

    ``lam`` holds the target prices, the area samples' prices, then (``energy``) the
    prices of the energy budgets the unpriced DP optimum overdraws
    (:mod:`jaxspline.search.energy`), then (``price_cap`` with an action cap and
    options outside the areas) the price of the cap (module docstring).
    ``lam += mu (UB - plan_value) / |g|^2 g`` with ``g = takers - 1`` (targets) and
    ``g = (usage - budget) / unit`` (budgets, in observations' worth of energy),
    projected on ``[0, w]`` / ``[0, inf)``; after
    :data:`_STALL_ITERS` iterations without a better bound ``mu`` halves and the prices
    restart from the best ones seen, until ``mu < mu_min`` (converged). ``dp``: the
    problem's :func:`dp_prepare`, where the caller has it (None: prepared here).
    """

    def __init__(
        self,
        pb: Problem,
        energy: bool = False,
        merge_repeats: bool = False,
        dp=None,
        mu_min: float = _MU_MIN,
        price_cap: bool = True,
    ):
        self.pb = pb
        self.mu_min = float(mu_min)
        self.merge = bool(merge_repeats)
        self.d = dp_prepare(pb) if dp is None else dp
        self.target_value = np.asarray(pb.target_value, np.float64)
        self.option_target = np.asarray(pb.option_target, np.int64)
        self.cv = pb.cover
        sample_w = np.zeros(0) if self.cv is None else self.cv.weight
        self.n_tg, self.n_sm = self.target_value.size, sample_w.size
        self.area_options = []
        closed = pb.closed_options()
        self.area = np.zeros(0, np.int64) if closed is None else np.flatnonzero(closed)
        # below any path's value: area options and looks have relaxations of their own
        self.shut = -(float(self.target_value.sum() + sample_w.sum()) + 1.0)
        self.stereo_const = 0.0  # each stereo target's best product: the relaxation of looks
        if pb.stereo is not None:
            st = pb.stereo.stereo_targets
            self.stereo_const = float(sum(pb.stereo.best_value(int(t)) for t in st))
        if self.cv is not None:
            self.lay = pass_layout(self.cv, pb.max_actions)
            self.rows = np.zeros(0, np.int64)
            self.capped = []  # passes whose cover cap bounds them (area_dp)
        self.cap_at = None  # index of the action cap's price in lam (None: not priced)
        self.en = EnergyBudgets(pb) if energy else None
        if self.en is not None:
            if self.en.m:
                # price only the budgets the unpriced optimum overdraws (any subset is
                # valid; the others rarely bind and would slow every iteration)
                paths, _ = dp_paths(pb, self.d, self._values(np.zeros(self.n_tg + self.n_sm)),
                                    None, used := [])  # fmt: skip
                self.en.restrict(self.en.subgradient(paths, used) > 0.0)
            if not self.en.m:
                self.en = None
        m = self.en.m if self.en is not None else 0
        if price_cap and pb.max_actions is not None and self.area.size < pb.n_options:
            self.cap_at = self.n_tg + self.n_sm + m
        self.en_slice = slice(self.n_tg + self.n_sm, self.n_tg + self.n_sm + m)
        # prices: targets (in [0, w]) then energy budgets (>= 0, see search.energy); the
        # bound gains each price times its constraint's right-hand side
        n_cap = 0 if self.cap_at is None else 1
        self.hi = np.r_[self.target_value, sample_w, np.full(m + n_cap, np.inf)]
        if pb.stereo is not None:  # their looks are shut: no price to find
            self.hi[pb.stereo.stereo_targets] = 0.0
        self.rhs = np.ones(self.hi.size)
        if m:
            self.rhs[self.en_slice] = self.en.budget / self.en.unit
        if self.cap_at is not None:
            self.rhs[self.cap_at] = float(pb.max_actions)
        self.lam = np.zeros(self.hi.size)
        # samples start most of the way to their weight: a row is credited little at first
        self.lam[self.n_tg : self.n_tg + self.n_sm] = _SAMPLE_PRICE0 * sample_w
        self.best_lam = self.lam.copy()
        self.ub, self.mu, self.stall, self.it = math.inf, 1.0, 0, 0

    def solve_dp(self):
        """DP paths at the current prices; updates the bound. Returns the paths (per
        satellite; with areas one more list, the area options of the chosen runs)."""
        self.it += 1
        w = self._values(self.lam)
        arc, self.used = None, None
        if self.en is not None:
            node_pen, arc_pen = self.en.penalties(self.lam[self.en_slice])
            w, arc, self.used = w - node_pen, arc_pen, []
        paths, vals = dp_paths(self.pb, self.d, w, arc, self.used, self.merge)
        if self.cv is None:
            self._record(vals, paths)
            return paths
        credit = self.cv.weight - self.lam[self.n_tg : self.n_tg + self.n_sm]
        self.capped, self.runs = [], []
        total, self.rows = area_dp(
            self.cv, self.lay, self.cv.row_values(credit), credit, self.capped,
            self._cap_price(self.lam), self.runs,
        )  # fmt: skip
        self._record([*vals, total], paths)
        self.area_options = run_options(self.cv, self.rows)
        return [*paths, self.area_options]

    def _cap_price(self, lam: np.ndarray) -> float:
        """The action cap's price in ``lam`` (0 where it is not priced)."""
        if self.cap_at is None or lam.size <= self.cap_at:
            return 0.0
        return float(lam[self.cap_at])

    def _values(self, lam: np.ndarray) -> np.ndarray:
        """Option values of the satellites' DPs at prices ``lam``: ``w_t - lam_t`` of a
        target's option, less the action cap's price; an area option is shut (the areas
        have :func:`area_dp`)."""
        w = self.target_value[self.option_target] - lam[self.option_target]
        w -= self._cap_price(lam)
        if self.area.size:
            w[self.area] = self.shut
        return w

    def _record(self, vals, paths):
        """Bound of this iteration from the satellites' DP values (satellite order)."""
        bound = float(sum(vals) + self.lam @ self.rhs) + self.stereo_const
        if bound < self.ub - _GAP_TOL:
            self.ub, self.best_lam, self.stall = bound, self.lam.copy(), 0
        else:
            self.stall += 1
        self.paths = paths

    def _takers(self, paths) -> np.ndarray:
        """Number of paths taking each target (float [T])."""
        cnt = np.zeros(self.target_value.size)
        for p in paths:
            t = self.option_target[p]
            if self.merge:  # a run of one target is one credited visit
                t = run_targets(t)
            np.add.at(cnt, t, 1.0)
        return cnt

    def _sample_takers(self) -> np.ndarray:
        """Number of passes covering each sample in the relaxation's solution (float [N
        samples]): the chosen rows' samples, once per pass; every sample a capped pass can
        cover."""
        cv, lay = self.cv, self.lay
        cnt = np.zeros(self.n_sm)
        capped = np.asarray(self.capped, np.int64)
        rows = self.rows[~np.isin(lay.row_pass[self.rows], capped)]
        if rows.size:
            pos, which = gather_ranges(cv.indptr, rows)
            key = np.unique(lay.row_pass[rows[which]] * self.n_sm + cv.indices[pos])
            np.add.at(cnt, key % self.n_sm, 1.0)
        if capped.size:
            pos, _ = gather_ranges(lay.pass_ptr, capped)
            np.add.at(cnt, lay.pass_samples[pos], 1.0)
        return cnt

    def _actions(self) -> float:
        """Actions the relaxed solution is charged for: its DP paths' options (a merged
        run once) and the areas' runs."""
        n = 0
        for p in self.paths[: self.pb.n_sats]:
            t = self.option_target[p]
            n += (run_targets(t) if self.merge else t).size
        return float(n + sum(self.runs if self.cv is not None else []))

    def _subgradient(self) -> np.ndarray:
        g = self._takers(self.paths[: self.pb.n_sats]) - 1.0
        if self.cv is not None:
            g = np.r_[g, self._sample_takers() - 1.0]
        if self.used is not None:
            g = np.r_[g, self.en.subgradient(self.paths, self.used)]
        if self.cap_at is not None:
            g = np.r_[g, self._actions() - float(self.pb.max_actions)]
        return g

    def step(self, plan_value: float) -> bool:
        """Move the prices toward ``plan_value``, a value some plan reaches; False when the
        iteration has converged."""
        if self.stall >= (_STALL_ITERS if self.cv is None else _AREA_STALL_ITERS):
            self.mu, self.stall, self.lam = self.mu * 0.5, 0, self.best_lam.copy()
            return self.mu >= self.mu_min
        g = self._subgradient()
        lam, hi = self.lam, self.hi
        g[((lam <= 0.0) & (g < 0.0)) | ((lam >= hi) & (g > 0.0))] = 0.0
        gn = float(np.dot(g, g))
        if gn == 0.0 or self.mu < self.mu_min:
            return False
        self.lam = np.clip(lam + self.mu * max(self.ub - plan_value, 1e-3) / gn * g, 0.0, hi)
        return True


def lagrangian(tl: Timeline, deadline: float, order_fill, max_iters=None, report=None, dp=None):
    """Lagrangian phase with repaired plans (see module docstring).

    The step target is the best repaired plan's value; ``tl`` ends at the best plan.

    Args:
      tl: Timeline over the problem (its plan is replaced).
      deadline: float, ``time.monotonic()`` value at which to stop [s].
      order_fill: target order used to fill each repaired plan greedily.
      max_iters: cap on the subgradient iterations (None: the deadline alone).
      report: callable ``report(iteration, bound, best_value)`` or None.
      dp: the problem's :func:`dp_prepare` (None: prepared here).
    Returns:
      BoundResult.
    """
    pb = tl.pb
    best = tl.plan()
    best_w = tl.value
    if pb.n_options == 0:
        return BoundResult(best, 0.0, 0, BoundStatus.OPTIMAL)
    pr = Prices(pb, energy=True, dp=dp)
    status = BoundStatus.TIME
    while clock.now() < deadline and (max_iters is None or pr.it < max_iters):
        paths = pr.solve_dp()
        if (pr.it - 1) % _REPAIR_EVERY == 0:
            plan_from_paths(tl, paths, order_fill, deadline)
            if tl.value > best_w:
                best_w, best = tl.value, tl.plan()
        if pr.ub - best_w <= _GAP_TOL * max(1.0, pr.ub):
            status = BoundStatus.OPTIMAL
            break
        if not pr.step(best_w):
            status = BoundStatus.CONVERGED
            break
        if report is not None:
            report(pr.it, pr.ub, best_w)
    tl.restore(best)
    return BoundResult(best, pr.ub, pr.it, status)


def upper_bound(
    pb: Problem,
    plan_value: float,
    deadline: float,
    max_iters=None,
    energy: bool = False,
    merge_repeats: bool = True,
    dp=None,
    on_paths=None,
    mu_min: float = BOUND_MU_MIN,
) -> BoundResult:
    """The Lagrangian bound alone (no plan repair): smallest UB within the budget.

    Deterministic for a given ``max_iters``.

    Args:
      pb: Problem.
      plan_value: float, a value some plan reaches (it sets the step size only; any value
        gives a valid bound).
      deadline: float, ``time.monotonic()`` value at which to stop [s].
      max_iters: cap on the iterations (None: the deadline alone).
      energy: price the battery budgets of :mod:`jaxspline.search.energy` too
        (off: the battery is dropped).
      merge_repeats: the strengthened relaxation (module docstring): consecutive
        options of one target joined by a near pair are credited once. False: the
        plain relaxation, as the search's Lagrangian phase iterates it.
      dp: the problem's :func:`dp_prepare` (None: prepared here).
      on_paths: optional callable ``on_paths(iteration, paths, improved)`` called with
        the DP paths of every iteration (before the price step; it must not change
        them); ``improved``: this iteration gave the smallest bound so far.
      mu_min: the step factor below which the iteration has converged (default
        :data:`BOUND_MU_MIN`; the search's Lagrangian phase stops at 1e-4).
    Returns:
      BoundResult with status ``CONVERGED`` or ``TIME`` (cap / deadline reached).
    """
    if pb.n_options == 0:
        return BoundResult([], 0.0, 0, BoundStatus.OPTIMAL)
    t0 = time.monotonic()
    pr = Prices(pb, energy=energy, merge_repeats=merge_repeats, dp=dp, mu_min=mu_min)
    status = BoundStatus.TIME
    while clock.now() < deadline and (max_iters is None or pr.it < max_iters):
        paths = pr.solve_dp()
        if on_paths is not None:
            on_paths(pr.it, paths, pr.stall == 0)
        if not pr.step(plan_value):
            status = BoundStatus.CONVERGED
            break
    return BoundResult([], pr.ub, pr.it, status, time.monotonic() - t0)
