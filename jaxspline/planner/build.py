"""Stages 1-4 of a plan: orbits, windows, options, screening, into the search's problem.

:func:`build_problem` turns a :class:`~jaxspline.readers.mission.Scenario` into a
:class:`~jaxspline.planner.context.PlanContext`: every satellite on common ephemeris
knots (SGP4 for TLEs) with the Sun and the Earth's shadow; every visibility window
(:mod:`jaxspline.geometry.windows`); the options on the action grid
(:mod:`jaxspline.planner.opportunities`) and, for areas, their strips
(:mod:`jaxspline.planner.area_options`); per satellite, every option pair closer than
the always-feasible gap screened through the satellite's maneuver model
(:mod:`jaxspline.screen.models`, optionally also with the flown degree-7 joins);
then :class:`jaxspline.search.Problem`. :class:`StageClock` times the stages.
"""

from __future__ import annotations

import functools
import math
import resource
import sys
import time
from typing import NamedTuple

import jax
import numpy as np

from jaxspline.base import clock as search_clock
from jaxspline.base.elements import jd_split
from jaxspline.geometry.frames import in_shadow, sun_direction
from jaxspline.geometry.orbit import orbit_period
from jaxspline.geometry.routes import AREA, STEREO
from jaxspline.geometry.windows import orbit_scene, visibility_windows_all, window_work
from jaxspline.planner.area_options import area_options, cover_table, merge_options
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
from jaxspline.planner.stereo_options import merge_stereo, stereo_options
from jaxspline.readers.mission import Scenario
from jaxspline.screen.fused import release_programs
from jaxspline.screen.options import take_options
from jaxspline.screen.pairs import screen_chunks
from jaxspline.screen.transitions import default_chunk_size
from jaxspline.search import BatteryModel, Problem
from jaxspline.search.stereo import ProductTable
from jaxspline.search.store import PairsBuilder, start_order

__all__ = ["StageClock", "build_problem"]

_NEAR_SLACK = 1e-6  # [s] near pairs reach at least this far past the always-feasible gap
_WINDOW_GUARD = 1e-6  # [s] the near-pair screen reaches this far past far + slack, then cuts
_NEAR_CHUNK = 1 << 13  # candidates per near-pair screening chunk: whole chunks share programs
_LARGE_SAT = 1 << 14  # larger satellites screen in the devices' chunk (default_chunk_size):
# their tables pad past the shared programs' size anyway
_JOIN_BATCH = 1 << 16  # screened pairs per call of the flown-join screen
_PAIRS, _CANDS = "target-satellite pairs", "candidate options"  # the stages' work units


def _peak_rss_mb() -> float:
    """Peak resident set size of this process so far [MB] (Linux: ru_maxrss in KiB)."""
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, 1)


class StageClock:
    """Stage timings, peak RSS per stage and progress lines on stderr (one per call of
    :func:`jaxspline.planner.pipeline.plan`, shared by its stages).

    Args:
      name: the scenario's name (the lines' prefix); progress: print the lines.
    """

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
            chunk_size=default_chunk_size() if n > _LARGE_SAT else _NEAR_CHUNK,
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
    clock = _clock or StageClock(sc.name, progress)
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
        opp, window, stereo = _with_stereo(sc, table, scene, opp, window)
        clock.lap("options", f"{len(opp)} options" + _area_line(area) + _stereo_line(stereo))
        held = None if window is None else window[:, 0] >= 0
        if stereo is not None:  # looks and area strips: closed-form transitions
            looks = stereo[1].look_of_row >= 0
            held = looks if held is None else held | looks
        scr = _screening(sc, scene, opp, held, joins, reduce_slack, check, fits)
        tables, far, first, near, slack, lookup, _ = scr
        clock.lap("screening", _screening_line(near, scr.removed, far, lookup is not None))
        check("screening")
        battery = _battery(sc, sunlit)
        cover = None if area is None else cover_table(sc, area, window)
        table_p = None if stereo is None else _product_table(sc, opp, stereo[1])
        values = np.where(sc.targets.kind == AREA, 0.0, sc.targets.value)  # areas: in samples
        if table_p is not None:  # a stereo target: its best product
            st = table_p.stereo_targets
            values[st] = [table_p.best_value(int(t)) for t in st]
        rules = {"cover": cover, "max_actions": sc.planner.max_actions, "duty": _duty(sc),
                 "gap_margin": sc.planner.margins.gap,
                 "joins": _join_rules(sats) if joins and (cover or stereo) else None,
                 "stereo": table_p}  # fmt: skip
        pb = Problem.build(opp, sats, first, near, far, tables, battery, values, lookup, **rules)
        pb.near_slack = slack
    return PlanContext(sc, pb, opp, windows, scene, table, battery, far, area, stereo)


class _Screened(NamedTuple):
    tables: list
    far: np.ndarray
    first: np.ndarray
    near: object
    slack: float
    lookup: np.ndarray | None
    removed: int


def _screening(sc, scene, opp, held, joins, reduce_slack, check, fits) -> _Screened:
    """Stage 4: per satellite its screening table, always-feasible gap ``far`` and the
    options' first requirements, then the near pairs through the maneuver model (and the
    flown-join screen with ``joins``); area strips and looks (``held``) are left out of
    the pair screen."""
    sats = sc.satellites
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
    screened = opp.options if held is None else take_options(opp.options, np.flatnonzero(~held))
    fits("screening", lambda: pair_bytes(sc, screened, reach))
    tick = check("screening", 0, since=time.monotonic(), work=lambda: (len(opp), "options"))
    near, removed = _near_pairs(
        sc, opp, tables, far, slack + _NEAR_SLACK, join_filter, tick=tick, skip=held
    )
    release_programs(len(opp))  # the screen's compiled chunk programs are done with
    return _Screened(tables, far, first, near, slack, lookup, removed)


def _with_stereo(sc, table, scene, opp, window):
    """The options with the stereo targets' looks merged in (``window`` rows carried
    along, -1 for the looks): ``(opp, window, (StereoOptions, StereoMerge) or None)``."""
    stereo = stereo_options(sc, table, scene)
    if stereo is None:
        return opp, window, None
    merged = merge_stereo(opp, stereo)
    if window is not None:
        rows = np.concatenate([window, np.full((len(stereo.opp), 3), -1, np.int64)])
        window = rows[merged.order]
    return merged.opp, window, (stereo, merged)


def _product_table(sc, opp, merged) -> ProductTable:
    """The search's :class:`ProductTable`: each product's looks, target and value (the
    target's priority times its request's share of the product's quality, times the
    chance that the benchmark's overlap estimates find it valid)."""
    p = merged.products
    req = {int(s.target): s for s in sc.stereo}
    share = np.array([req[int(t)].value_share(q) for t, q in zip(p.target, p.quality, strict=True)])
    value = np.asarray(sc.targets.value)[p.target] * share * p.confidence
    return ProductTable(
        [tuple(int(c) for c in row if c >= 0) for row in p.looks],
        p.target,
        value,
        np.asarray(opp.options.route, np.int64),
        np.flatnonzero(sc.targets.kind == STEREO),
        len(sc.targets),
        rank=p.quality * p.confidence,
        confidence=p.confidence,
    )


def _stereo_line(stereo) -> str:
    """The options line's part on the stereo targets (empty without them)."""
    if stereo is None:
        return ""
    st, merged = stereo
    return f" ({len(st.opp)} looks, {len(merged.products)} stereo products)"


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
    allowed &= ~np.isin(tg.kind, (AREA, STEREO))[None, :] & tracks[:, None]
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
    per_pair = f", {near.nbytes / len(near):.1f} B/pair" if len(near) else ""
    return (
        f"{len(near)} feasible near pairs{screened}{per_pair}; far gaps "
        f"{far.min(initial=np.inf):.0f}-{far.max(initial=0.0):.0f} s"
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
