"""The planning pipeline: one entry point for the CLI, the benchmark and the aeossp adapter.

``plan(scenario) -> PlanResult`` runs, in float64 (inside ``jax.enable_x64``, the
process-wide setting is left alone):

1. **orbits** - every satellite on common ephemeris knots (SGP4 for TLEs), the Sun
   and the Earth's shadow at the knots;
2. **windows** - every visibility window of every target over the horizon
   (:mod:`jaxspline.geometry.windows`);
3. **options** - the valid (target, satellite, start) options on the action grid
   with their boundary states (:mod:`jaxspline.planner.opportunities`);
4. **screening** - per satellite, every option pair closer than the always-feasible
   gap through the satellite's maneuver model (:mod:`jaxspline.screen.models`);
5. **search** - greedy, Lagrangian/DP bound, exact search on tiny instances, LNS
   (:mod:`jaxspline.search`) until the time limit;
6. **repair** - start-time refinement, an independent re-check without margins
   (:mod:`jaxspline.planner.plan_check`), the flown joins and refills as one loop
   (:mod:`jaxspline.planner.repair`): failing observations are dropped, one per
   violation, so the returned plan is valid under every check that ran.

Ctrl-C or SIGTERM during stages 5-6 stops the search: the best plan so far goes
through the repair and is returned with ``report["interrupted"]`` set. Given a
``deadline`` (``jaxspline plan`` passes one), stages 1-4 check it
(:mod:`jaxspline.planner.deadline`): when it passes there, the call stops with
:class:`jaxspline.planner.deadline.TimeLimitError` (what was done, an estimate of the
time needed, the remedy) instead of searching past it; the search then leaves a
reserve for stage 6 and the caller's outputs, and stage 6 leaves out its optional
steps past the limit (:mod:`jaxspline.planner.budget`).
"""

from __future__ import annotations

import functools
import math
import numbers
import os
import resource
import sys
import time

import jax
import numpy as np

from jaxspline.geometry.frames import in_shadow, jd_split, sun_direction
from jaxspline.geometry.orbit import orbit_period
from jaxspline.geometry.routes import AREA
from jaxspline.geometry.windows import visibility_windows_all, window_work
from jaxspline.planner.area_options import area_options, cover_table, merge_options
from jaxspline.planner.assemble import assemble_result
from jaxspline.planner.budget import Budget, deadline_budget, default_budget, refine_steps
from jaxspline.planner.context import PlanContext
from jaxspline.planner.deadline import StageDeadline
from jaxspline.planner.flown_joins import join_limits
from jaxspline.planner.join_screen import (
    channel_states,
    join_far_gap,
    screen_first_joins,
    screen_joins,
)
from jaxspline.planner.memory_guard import (
    MemoryGuard,
    check_stage,
    option_bytes,
    orbit_bytes,
    pair_bytes,
    window_bytes,
)
from jaxspline.planner.opportunities import (
    build_opportunities,
    nadir_rate,
    option_counts,
    reference_points,
)
from jaxspline.planner.repair import dropped_line, repair
from jaxspline.planner.result import PlanResult
from jaxspline.readers.mission import Scenario, orbit_scene
from jaxspline.screen.fused import release_programs
from jaxspline.screen.options import take_options
from jaxspline.screen.pairs import screen_chunks
from jaxspline.search import BatteryModel, Problem, mip_bound, solve
from jaxspline.search import clock as search_clock
from jaxspline.search.store import PairsBuilder, start_order

__all__ = ["build_problem", "plan"]

_NEAR_SLACK = 1e-6  # [s] near pairs reach at least this far past the always-feasible gap
_WINDOW_GUARD = 1e-6  # [s] the near-pair screen reaches this far past far + slack, then cuts
_NEAR_CHUNK = 1 << 13  # candidates per near-pair screening chunk: whole chunks share programs
_NEAR_CHUNK_LARGE = 1 << 18  # ... on satellites of more than _LARGE_SAT options (docs/scale.md)
_LARGE_SAT = 1 << 14  # their tables pad past the shared programs' size anyway
_JOIN_BATCH = 1 << 16  # screened pairs per call of the flown-join screen
_PAIRS, _CANDS = "target-satellite pairs", "candidate options"  # the stages' work units
_REFILL_S = 2.0  # [s] budget of one refill after join rejections
_REFILL_ITERS = 2000  # LNS iterations of one refill in iteration-capped runs
_WORKER_MIN_CPUS = 2  # the bound worker runs only with a second CPU


def _peak_rss_mb() -> float:
    """Peak resident set size of this process so far [MB] (Linux: ru_maxrss in KiB)."""
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)


class _Clock:
    """Stage timings and progress lines on stderr."""

    def __init__(self, name: str, progress: bool):
        self.t0 = time.monotonic()
        self.last = self.t0
        self.name = name
        self.progress = progress
        self.timings = {}
        self.peak_rss_mb = {}  # process peak RSS at the end of each stage [MB]
        self.bar = None
        self.bar_t0 = self.t0

    def lap(self, stage: str, msg: str = ""):
        now = time.monotonic()
        self.timings[stage] = round(now - self.last, 3)
        self.peak_rss_mb[stage] = _peak_rss_mb()
        self.last = now
        self.say(stage, msg)

    def search_bar(self, seconds: float):
        """A progress bar over the search budget (None without progress)."""
        if not self.progress:
            return None
        from tqdm import tqdm

        return tqdm(
            total=round(max(seconds, 0.0), 1),
            desc=f"[plan {self.name}] search",
            unit="s",
            bar_format="{desc} {bar} {n:.0f}/{total:.0f} s {postfix}",
            file=sys.stderr,
            leave=False,
        )

    def say(self, stage: str, msg: str):
        bar = getattr(self, "bar", None)
        if bar is not None:
            bar.n = round(min(time.monotonic() - self.bar_t0, bar.total), 1)
            bar.set_postfix_str(f"{stage}: {msg}", refresh=True)
            return
        if self.progress:
            print(
                f"[plan {self.name}] {stage:9s} {msg}  ({time.monotonic() - self.t0:5.1f} s)",
                file=sys.stderr,
                flush=True,
            )


def plan(
    scenario: Scenario,
    *,
    time_limit: float | None = None,
    seed: int = 0,
    progress: bool = True,
    max_iters: int | None = None,
    certify: float = 0.0,
    flown_joins: bool = False,
    deadline: StageDeadline | None = None,
    memory: MemoryGuard | None = None,
) -> PlanResult:
    """Plan a scenario: the best observations found within ``time_limit`` seconds.

    Args:
      scenario: a :class:`jaxspline.readers.mission.Scenario`.
      time_limit: wall-clock budget [s] for the whole call (default
        ``scenario.planner.default_time_limit``).
      seed: random seed of the search (runs are deterministic for a seed and
        ``max_iters``; a time limit only truncates the search).
      progress: stage lines on stderr.
      max_iters: optional cap on search iterations: the search and the refills then
        run to their caps whatever the clock says, and the plan is identical on every
        run (``time_limit`` only sizes the reserved shares; Ctrl-C still stops).
      certify: extra seconds, after the time limit, for a tighter certificate: the
        option model solved as a 0/1 program by HiGHS
        (:func:`jaxspline.search.mip_bound`, needs scipy); the reported bound is the
        smaller of its dual bound and the Lagrangian one. 0 (default): skip.
      flown_joins: also drop observations whose degree-7 joins (SPEC section 3) exceed
        the limits after re-timing (:func:`jaxspline.planner.flown_joins.reject_unflyable`),
        so the plan is flyable as :func:`jaxspline.products.attitude_history.attitude_history`
        exports it; off by default: the satellites' maneuver models alone decide (as the
        aeossp rules). The transitions are then also screened with the joins
        (:mod:`jaxspline.planner.join_screen`).
      deadline: optional :class:`jaxspline.planner.deadline.StageDeadline` (``jaxspline
        plan`` passes one): the stages before the search check it and stop with
        :class:`jaxspline.planner.deadline.TimeLimitError` once it has passed; the
        search leaves a reserve estimated for the repair and the caller's outputs
        (:func:`jaxspline.planner.budget.deadline_budget`); the result's
        ``report["time_limit"]`` records the split and what was left out. Without it
        (the default) the search leaves a fixed share of ``time_limit``
        (:func:`jaxspline.planner.budget.default_budget`).
      memory: optional :class:`jaxspline.planner.memory_guard.MemoryGuard`: the stages
        before the search stop before they allocate more than it allows.
    Returns:
      :class:`jaxspline.planner.result.PlanResult`.
    Raises:
      jaxspline.planner.deadline.TimeLimitError: ``deadline`` passed before the search.
      jaxspline.planner.memory_guard.MemoryLimitError: a stage would not fit ``memory``.
    """
    if not isinstance(scenario, Scenario):
        raise ValueError(f"scenario must be a jaxspline Scenario, got {type(scenario).__name__}")
    limit = scenario.planner.default_time_limit if time_limit is None else time_limit
    if not (isinstance(limit, int | float) and math.isfinite(limit) and limit > 0):
        raise ValueError(f"time_limit must be a number > 0, got {time_limit!r}")
    if not (isinstance(certify, int | float) and math.isfinite(certify) and certify >= 0):
        raise ValueError(f"certify must be a number of seconds >= 0, got {certify!r}")
    if max_iters is not None and (
        isinstance(max_iters, bool) or not isinstance(max_iters, numbers.Integral) or max_iters < 1
    ):
        raise ValueError(f"max_iters must be an integer >= 1, got {max_iters!r}")
    with jax.enable_x64(True):
        args = (float(limit), int(seed), bool(progress), max_iters, certify, flown_joins)
        return _plan(scenario, *args, deadline, memory)


def _orbits(sc: Scenario):
    pc = sc.planner
    table, scene = orbit_scene(sc)
    t = np.asarray(table.orbit.t)
    knots = (t >= -1e-9) & (t <= sc.duration + pc.geometry_step + 1e-9)
    jd, fr = jd_split(sc.epoch_jd, t[knots])
    sun = sun_direction(jd, fr)
    r = np.asarray(table.orbit.r)[:, knots]
    n = int(math.ceil(sc.duration / pc.geometry_step - 1e-9)) + 1
    sunlit = ~in_shadow(r, sun[None])[:, :n]
    return table, scene, sunlit


def _near_pairs(sc, opp, tables, far, slack, join_filter=None, tick=None, skip=None):
    """Feasible pairs i -> j (same satellite) with 0 < gap < far + slack, with their need.

    The slack (the shortest observation) lets the DP process a block of starts that
    wide at once (:func:`jaxspline.search.dp_prepare`). Each satellite's options
    stream through the fused screen (:func:`jaxspline.screen.pairs.screen_chunks`)
    with its maneuver model: AxisLimits for ``per_channel`` (need = min(t_min, gap)),
    its SlewTable for rest-to-rest models (need = t_req). The sub-table gets
    ``route = arange(n)`` (the screen excludes equal routes; the planner wants pairs of
    the same target too) and ``scan_ok`` everywhere. The screen's window
    ``gap <= max_gap`` is widened by ``_WINDOW_GUARD`` and the pairs are then cut with
    the planner's own test ``t_end[i] > t_start[j] - far - slack`` (strict), so the
    result does not depend on how either side rounds. ``join_filter(src, dst) -> bool``
    (the flown-join screen) runs on batches of ``_JOIN_BATCH`` pairs. Chunks go into a
    :class:`jaxspline.search.store.PairsBuilder` (one satellite sorted in a thread).
    ``tick(share done)`` (a StageDeadline's clock) is called after every chunk. Options
    where ``skip`` holds (the area options: their transitions have a closed form,
    :mod:`jaxspline.search.problem`) are left out.

    Returns:
      (NearPairs, pairs removed by ``join_filter``).
    """
    o = opp.options
    builder = PairsBuilder(len(opp), start_order(o.t_start, o.sat), background=True)
    removed = 0
    for k, sat in enumerate(sc.satellites):
        ids = np.flatnonzero((o.sat == k) if skip is None else (o.sat == k) & ~skip)
        if ids.size < 2:
            continue
        n = ids.size
        sub = take_options(o, ids)._replace(route=np.arange(n), scan_ok=np.ones(n, bool))
        pending, held = [], 0
        for tr in screen_chunks(
            sub,
            tables[k],
            max_gap=far[k] + slack + _WINDOW_GUARD,
            chunk_size=_NEAR_CHUNK_LARGE if n > _LARGE_SAT else _NEAR_CHUNK,
            feasible_only=True,
            progress=False,
            process_index=0,  # every pair of these satellites here, also under
            process_count=1,  # jax.distributed (shards split by satellite, not chunk)
        ):
            if tick is not None and tr.src.size:  # sources come in start order
                tick((ids[0] + (int(tr.src.max()) + 1) * ids.size / n) / len(opp))
            ii, jj = ids[tr.src], ids[tr.dst]
            keep = o.t_end[ii] > o.t_start[jj] - far[k] - slack
            need = sat.maneuver.need(tr.t_min, tr.T)
            part = (ii[keep], jj[keep], need[keep])
            if join_filter is None:
                builder.add(*part)
                continue
            pending.append(part)
            held += part[0].size
            if held >= _JOIN_BATCH:
                removed += _filtered(builder, pending, join_filter)
                pending, held = [], 0
        if pending:
            removed += _filtered(builder, pending, join_filter)
        builder.close()
    return builder.build(), removed


def _filtered(builder, parts, join_filter) -> int:
    """Add the pairs of ``parts`` that pass ``join_filter``; returns how many failed."""
    src, dst, need = (np.concatenate(x) for x in zip(*parts, strict=True))
    keep = join_filter(src, dst)
    builder.add(src[keep], dst[keep], need[keep])
    return int((~keep).sum())


def build_problem(
    scenario: Scenario,
    *,
    progress: bool = False,
    joins: bool = False,
    reduce_slack=None,
    deadline: StageDeadline | None = None,
    memory: MemoryGuard | None = None,
    _clock=None,
) -> PlanContext:
    """Stages 1-4 of :func:`plan` (orbits, windows, options, screening), no search.

    Args:
      scenario: Scenario.
      progress: show progress bars.
      joins: also screen every transition with the degree-7 join the plan will fly
        (:mod:`jaxspline.planner.join_screen`): pairs up to the join far gap are
        screened and kept only when both the model and the join screen pass them,
        and an option is a first observation only when the join from nadir passes.
      reduce_slack: optional callable ``local -> global`` on the near-pair slack (the
        shortest observation [s], the DP's block width): processes that each build
        a shard of the satellites pass the minimum over all of them, so every shard
        screens the same window as a single process would.
      deadline: optional :class:`jaxspline.planner.deadline.StageDeadline` checked
        between the stages and inside options and screening
        (:class:`jaxspline.planner.deadline.TimeLimitError` once it has passed).
      memory: optional :class:`jaxspline.planner.memory_guard.MemoryGuard` checked before
        the orbits, windows, options and near pairs are built (``MemoryLimitError`` when
        they would not fit).
      _clock: private; the stage timer of an enclosing :func:`plan` call.
    Returns:
      :class:`jaxspline.planner.context.PlanContext`: the search's problem and what the
      later stages share.
    """
    sc = scenario
    clock = _clock or _Clock(sc.name, progress)
    check = _stage_check(deadline, clock)
    fits = functools.partial(check_stage, memory)
    with jax.enable_x64(True):
        sats = sc.satellites
        fits("orbits", lambda: orbit_bytes(sc))
        table, scene, sunlit = _orbits(sc)
        clock.lap("orbits", f"{len(sats)} satellites, {sunlit.shape[1]} knots")
        check("orbits")
        pairs = len(sc.targets) * len(sats)
        fits("windows", lambda: window_bytes(sc, window_work(*_window_args(sc, scene, table))))
        windows = _windows(sc, scene, table, check("windows", 0, work=lambda: (pairs, _PAIRS)))
        n_tg = len(np.unique(windows.target))
        clock.lap("windows", f"{len(windows)} windows for {n_tg}/{len(sc.targets)} targets")
        check("windows")
        fits("options", lambda: option_bytes(sc, *option_counts(sc, windows)))
        cands = check("options", 0, work=lambda: (option_counts(sc, windows)[0], _CANDS))
        opp = build_opportunities(sc, scene, table.usable, windows, tick=cands)
        area, window = area_options(sc, table, scene), None
        if area is not None:
            opp, window = merge_options(opp, area)
        clock.lap("options", f"{len(opp)} options" + _area_line(area))
        tick = check("screening", 0, work=lambda: (len(opp), "options"))
        beat = tick or _no_tick  # between the steps before the near pairs (each may be long)
        tables = [s.maneuver.screen_model(s, sc.planner.margins.gap) for s in sats]
        beat(0.0)
        omega = nadir_rate(scene)
        far, first = _far_and_first(sats, opp, tables, omega, beat)
        slack = _near_slack(opp, reduce_slack)
        lookup = join_filter = None
        if joins and len(opp):
            far, first, join_filter = _join_screens(sats, scene, opp, far, first, omega, beat)
            lookup = np.ones(len(sats), bool)
        beat(0.0)
        reach = np.asarray(far) + slack + _NEAR_SLACK + _WINDOW_GUARD
        fits("screening", lambda: pair_bytes(sc, opp.options, reach))
        tick = check("screening", 0, since=time.monotonic(), work=lambda: (len(opp), "options"))
        skip = None if window is None else window[:, 0] >= 0
        near, removed = _near_pairs(
            sc, opp, tables, far, slack + _NEAR_SLACK, join_filter, tick=tick, skip=skip
        )
        release_programs(len(opp))  # the screen's compiled chunk programs are done with
        clock.lap("screening", _screening_line(near, removed, far, lookup is not None))
        check("screening")
        battery = _battery(sc, sunlit)
        cover = None if area is None else cover_table(sc, area, window)
        values = np.where(sc.targets.kind == AREA, 0.0, sc.targets.value)  # areas: in samples
        rules = {"cover": cover, "max_actions": sc.planner.max_actions, "duty": _duty(sc),
                 "gap_margin": sc.planner.margins.gap,
                 "joins": _join_rules(sats) if joins and cover is not None else None}  # fmt: skip
        pb = Problem.build(opp, sats, first, near, far, tables, battery, values, lookup, **rules)
        pb.near_slack = slack
    return PlanContext(sc, pb, opp, windows, scene, table, battery, far, areas=area)


def _stage_check(deadline: StageDeadline | None, clock):
    """``check(stage, done=1, what="", since=None, work=None)``: with ``done`` = 1 it
    checks the deadline at the end of a stage; with ``done`` = 0 it returns the stage's
    ``tick(share)`` (None without a deadline). A stage starts at the clock's last lap;
    ``since`` starts the part of it the shares measure (its time before counts whole in
    the estimate: the near pairs after the far gaps and join screens); ``work() ->
    (units, name)`` is the stage's work (:meth:`StageDeadline.check`)."""

    def check(stage, done=1.0, what="", since=None, work=None):
        search_clock.raise_pending_signal()  # a Ctrl-C / SIGTERM a finalizer swallowed
        if deadline is None:
            return None
        if done >= 1.0:
            return deadline.check(stage, 1.0, clock.last, what)
        start = clock.last if since is None else since
        return lambda share: deadline.check(stage, share, start, what, work)

    return check


def _windows(sc: Scenario, scene, table, tick=None):
    """Stage 2: every visibility window of every target's reference point on every
    satellite allowed to image it (sensor type), within the off-nadir limit and the
    horizon (both minus their margins) and the target's imaging window (``tick``: the
    clock, between blocks of targets)."""
    return visibility_windows_all(*_window_args(sc, scene, table), tick=tick)


def _window_args(sc: Scenario, scene, table) -> tuple:
    """The arguments of :func:`visibility_windows_all` (and ``window_work``) of stage 2."""
    pc = sc.planner
    tg = sc.targets
    sensors = np.array([s.sensor for s in sc.satellites])
    allowed = (tg.sensor[None, :] == "") | (tg.sensor[None, :] == sensors[:, None])
    # areas have options of their own (area_options); a model that cannot track a
    # point images area strips only
    tracks = np.array([s.maneuver.tracks_points for s in sc.satellites])
    allowed &= (tg.kind != AREA)[None, :] & tracks[:, None]
    limit_k = np.array([s.off_nadir_max for s in sc.satellites]) - pc.margins.off_nadir
    times = (pc.margins.horizon, tg.t_lo, tg.t_hi, sc.duration)
    return (scene, table.ok, reference_points(sc), allowed, limit_k, *times)


def _area_line(area) -> str:
    """The options line's part on the areas (empty without areas)."""
    if area is None:
        return ""
    g = area.groups
    samples = sum(len(x) for x in area.grids)
    return (
        f" ({len(area)} area strips: {samples} samples, {g.n_passes} passes, "
        f"{len(g)} roll groups, {area.indices.size} covered entries)"
    )


def _duty(sc: Scenario):
    """Per satellite ``(orbit period, duty - margin)`` [s], or None (no satellite has a
    duty rule)."""
    if all(s.duty is None for s in sc.satellites):
        return None
    m = sc.planner.margins.duty
    return [
        None if s.duty is None else (orbit_period(s.orbit), float(s.duty) - m)
        for s in sc.satellites
    ]


def _join_rules(sats) -> list:
    """Per satellite the limits its flown joins keep (:attr:`Problem.joins`)."""
    out = []
    for s in sats:
        norm, per = join_limits(s)
        if per is None:
            out.append((float(norm.rate), float(norm.accel), float(norm.jerk)))
        else:
            out.append((np.asarray(per.rate), np.asarray(per.accel), math.inf))
    return out


def _no_tick(share: float) -> None:
    """The stage clock of a call without a deadline: nothing to check."""


def _far_and_first(sats, opp, tables, omega, tick=_no_tick):
    """Per satellite, through its maneuver model and screening table: the always-feasible
    gap ``far`` [S] [s] (``omega`` [S]: nadir turn rates [rad/s]) and, per option, the
    time ``first`` [N] [s] a first observation needs from rest (inf: never first);
    ``tick(0)`` after each satellite."""
    o = opp.options
    far = np.zeros(len(sats))
    first = np.full(len(opp), np.inf)
    for k, s in enumerate(sats):
        ids = np.flatnonzero(o.sat == k)
        far[k] = s.maneuver.far_gap(s, o, ids, float(omega[k]), tables[k])
        first[ids] = s.maneuver.first_requirements(s, o, ids, tables[k])
        tick(0.0)
    return far, first


def _near_slack(opp, reduce_slack) -> float:
    """The near-pair slack: the shortest observation [s] (reduced across processes by
    ``reduce_slack`` when given; 0 when there is none)."""
    o = opp.options
    slack = float(np.min(o.t_end - o.t_start)) if len(opp) else math.inf
    if reduce_slack is not None:
        slack = float(reduce_slack(slack))
    return slack if math.isfinite(slack) else 0.0


def _join_screens(sats, scene, opp, far, first, omega, tick=_no_tick):
    """The flown-join screens (:mod:`jaxspline.planner.join_screen`): the far gaps
    widened to the joins' (``far`` [S] [s], ``omega`` [S] nadir turn rates), the first
    requirements ``first`` [N] with options whose join from nadir fails set to inf, and
    the pair filter ``(src, dst) -> bool`` of the near-pair screen (``tick(0)`` between
    the steps). Returns ``(far, first, join_filter)``."""
    states = channel_states(scene, sats, opp)
    tick(0.0)
    far = np.array([join_far_gap(*x) for x in zip(sats, far, omega, strict=True)])
    tick(0.0)
    first = first.copy()
    first[~screen_first_joins(sats, opp, states, np.arange(len(opp)))] = np.inf
    return far, first, functools.partial(screen_joins, sats, opp, states)


def _screening_line(near, removed: int, far, joins: bool) -> str:
    """The progress line of stage 4: near pairs (and those the join screen removed),
    bytes per pair, the range of the far gaps."""
    screened = f" ({removed} removed by the join screen)" if joins else ""
    return (
        f"{len(near)} feasible near pairs{screened}, {near.nbytes / max(len(near), 1):.1f} "
        f"B/pair; far gaps {far.min(initial=np.inf):.0f}-{far.max(initial=0.0):.0f} s"
    )


def _battery(sc: Scenario, sunlit) -> BatteryModel:
    """The conservative battery model of the satellites (``sunlit`` [S, n+1] on the
    geometry knots) with the planner's margins."""
    pc = sc.planner
    return BatteryModel(
        sunlit,
        [s.power for s in sc.satellites],
        pc.geometry_step,
        pc.margins.battery_wh,
        pc.margins.shadow_guard,
    )


def _cpus() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not on Linux
        return os.cpu_count() or 1


def _search(pb, budget: Budget, seed, max_iters, pc, clock):
    """Stage 5 with a progress bar over the search budget (re-sized when the budget's
    ``retime`` moves the search's end)."""
    clock.bar = clock.search_bar(budget.search_end - time.monotonic())
    clock.bar_t0 = time.monotonic()

    def retime(per_sat) -> float:
        end = budget.retime(per_sat)
        if clock.bar is not None:
            clock.bar.total = round(max(end - clock.bar_t0, 0.0), 1)
        return end

    try:
        return solve(
            pb,
            budget.search_end,
            seed=seed,
            lagrangian_share=pc.lagrangian_share,
            exact_max_options=pc.exact_max_options,
            max_iters=max_iters,
            bound_worker=pc.bound_worker and _cpus() >= _WORKER_MIN_CPUS,
            report=clock.say,
            retime=None if budget.retime is None else retime,
        )
    finally:
        if clock.bar is not None:
            clock.bar.close()
        clock.bar = None


def _plan(
    sc: Scenario, limit, seed, progress, max_iters, certify, flown_joins, deadline, memory=None
) -> PlanResult:
    """:func:`plan` after its argument checks (inside ``jax.enable_x64``): stages 1-4,
    then search and repair under the signal guard, the optional HiGHS certificate, and
    the result."""
    clock = _Clock(sc.name, progress)
    budget = default_budget(sc, limit, clock.t0)
    ctx = build_problem(sc, joins=flown_joins, deadline=deadline, memory=memory, _clock=clock)
    if deadline is not None:
        budget = deadline_budget(
            ctx, deadline, flown_joins=flown_joins, refill_s=_REFILL_S, capped=max_iters is not None
        )
    res, rep, interrupted = _search_and_repair(ctx, budget, seed, max_iters, flown_joins, clock)
    for what, at in rep.skipped if deadline is not None else ():
        deadline.skip("repair", what, "give a longer --time-limit (or planner.time_limit_s)", at)
    clock.lap(
        "repair",
        f"{len(rep.chosen)} observations valid, dropped {dropped_line(rep.dropped)}"
        + (f", {rep.refilled} refilled" if flown_joins else ""),
    )
    mip = None
    if certify > 0:
        mip = mip_bound(ctx.problem, certify)
        clock.lap("certify", f"HiGHS bound {mip.bound:.6g} ({mip.status})")
    result = assemble_result(
        ctx,
        res,
        rep,
        mip,
        flown_joins=flown_joins,
        interrupted=interrupted,
        timings=clock.timings,
        peak_rss_mb=clock.peak_rss_mb,
    )
    if deadline is not None:  # the caller adds what its outputs leave out
        result.report["time_limit"] = deadline.record()
    if memory is not None:  # beside the measured peaks (stats.peak_rss_mb)
        result.stats["memory_estimate_mb"] = dict(memory.estimates_mb)
    return result


def _search_and_repair(ctx: PlanContext, budget: Budget, seed, max_iters, flown_joins, clock):
    """Stages 5-6 under the signal guard: the first Ctrl-C or SIGTERM stops the search
    and the best plan so far goes through the repair, whose optional steps end by
    ``budget.repair_end`` in time-bound runs. Returns (search result,
    :class:`jaxspline.planner.repair.Repaired`, the signal's name or None)."""
    pc = ctx.scenario.planner
    search_clock.clear_stop()

    def stopping(name):
        search_clock.request_stop()
        clock.say(
            "stop",
            f"{name}: stopping the search; the best plan so far is checked "
            "and returned (Ctrl-C again to abort)",
        )

    with search_clock.catch_signals(stopping, abort_on_second=True) as stop:
        res = _search(ctx.problem, budget, seed, max_iters, pc, clock)
        tl = res.timeline
        clock.lap("search", f"value {tl.value:.6g}, bound {res.bound:.6g} ({res.bound_status})")
        steps, t_steps = refine_steps(pc, budget, max_iters, clock.say), time.monotonic()
        capped = max_iters is not None
        rep = repair(
            ctx,
            tl.plan(),
            refine_steps=steps,
            flown_joins=flown_joins,
            refill_s=math.inf if capped else _REFILL_S,
            refill_iters=_REFILL_ITERS if capped else None,
            seed=seed,
            report=clock.say,
            deadline=None if capped else budget.repair_end,
        )
        if budget.refining and not steps:
            first = ("start-time refinement", t_steps)
            rep = rep._replace(skipped=(first, *rep.skipped))
    search_clock.clear_stop()
    return res, rep, stop["signal"]
