"""The time limit after the search: the run's clock, the search's reserve, the repair's deadline.

No long runs: the clock is faked (``time.monotonic`` / ``time.process_time`` patched) or
the deadline is given in the past, and the repair runs on the small scenarios of
``test_repair`` with the flown-join check replaced by a stub that rejects one
observation (so the refill path runs without compiling the join kernels).
"""

from __future__ import annotations

import functools
import subprocess
import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest
from test_repair import _check, _searched

from jaxspline.planner import budget as bd
from jaxspline.planner import deadline as dl
from jaxspline.planner import repair as rp


class _Clock:
    """A fake clock: ``wall`` and ``cpu`` seconds, moved by hand."""

    def __init__(self, monkeypatch, wall=1000.0, cpu=10.0):
        self.wall, self.cpu = wall, cpu
        monkeypatch.setattr(dl.time, "monotonic", lambda: self.wall)
        monkeypatch.setattr(dl.time, "process_time", lambda: self.cpu)
        monkeypatch.setattr(bd.time, "monotonic", lambda: self.wall)


def test_pace_is_wall_over_cpu_within_its_bounds(monkeypatch):
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 35.0)
    assert d.pace() == 1.0  # too early to tell
    clock.wall += 10.0
    clock.cpu += 4.0  # 40 % of a core: a loaded machine
    assert d.pace() == pytest.approx(2.5)
    clock.cpu += 100.0  # threads: more CPU than wall time
    assert d.pace() == 1.0
    clock.wall += 1000.0
    assert d.pace() == dl.PACE_MAX


def test_fits_skip_and_record(monkeypatch):
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 30.0, after_s=4.0)
    assert d.end == clock.wall + 30.0 and d.after_s == 4.0
    clock.wall += 20.0
    clock.cpu += 10.0  # pace 2
    assert d.fits(5.0) and not d.fits(5.1)
    assert d.fits(1.0, end=clock.wall + 2.0) and not d.fits(1.1, end=clock.wall + 2.0)
    d.skip("outputs", "plan.czml", "give a longer --time-limit")
    rec = d.record()
    assert rec["limit_s"] == 30.0 and rec["pace"] == 2.0 and rec["elapsed_s"] == 20.0
    assert rec["skipped"] == [
        {
            "stage": "outputs",
            "what": "plan.czml",
            "at_s": 20.0,
            "remedy": "give a longer --time-limit",
        }
    ]


def test_startup_ignores_the_wait_of_a_shell_that_execs_the_command():
    # bash -c 'pip install ... && jaxspline plan' execs jaxspline in the shell's process:
    # its age counts pip's minute, its CPU time only Python's own start-up
    assert dl.startup_seconds(64.6, 4.0) == 4.0
    assert dl.startup_seconds(6.0, 4.0) == 6.0  # a plain start: the age (waits on disk)
    assert dl.startup_seconds(14.0, 4.0) == 14.0  # a loaded machine: pace 3.5 still counts
    assert dl.startup_seconds(-1.0, 0.5) == 0.0


def test_process_start_counts_python_not_the_shell_before_it():
    # the module alone (standard library only): Python starts in well under a second;
    # its slack is cut to 0.5 s in the child so the shell need not wait the real 5 s
    code = (
        "import importlib.util as u, time; "
        f"s = u.spec_from_file_location('d', {dl.__file__!r}); m = u.module_from_spec(s); "
        "s.loader.exec_module(m); m.EXEC_WAIT_SLACK_S = 0.5; "
        "print(time.monotonic() - m.process_start())"
    )
    wait_s = 2.0  # > the slack above + EXEC_WAIT_FACTOR x Python's CPU time
    shell = f'sleep {wait_s} && exec {sys.executable} -c "{code}"'
    t0 = time.monotonic()
    out = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, check=True)
    started_ago = float(out.stdout.split()[-1])
    assert started_ago <= time.monotonic() - t0 - wait_s + 0.5


def test_process_start_is_before_now():
    start = dl.process_start()
    assert 0.0 <= time.monotonic() - start < 86400.0 * 365


def _ctx(n_targets, refining, duration=3600.0, rigid=0):
    """The fields of a PlanContext the budget reads: one satellite, per-channel when
    ``refining``, then ``rigid`` rest-to-rest ones; three options a target, on
    satellites in turn."""
    sat = SimpleNamespace(maneuver=SimpleNamespace(rest_to_rest=not refining))
    rest = [SimpleNamespace(maneuver=SimpleNamespace(rest_to_rest=True))] * rigid
    sc = SimpleNamespace(planner=SimpleNamespace(refine_steps=50), satellites=[sat, *rest])
    n = 3 * n_targets
    opts = SimpleNamespace(route=np.repeat(np.arange(n_targets), 3), sat=np.arange(n) % (1 + rigid))
    pb = SimpleNamespace(cover=None, max_actions=None)  # no areas
    return SimpleNamespace(scenario=sc, opportunities=SimpleNamespace(options=opts), problem=pb)


def test_repair_estimate_grows_with_the_steps_that_run():
    plain = bd.repair_seconds(1000, False, False, 2.0)
    assert plain == pytest.approx(bd.CHECK_FIRST_S + bd.CHECK_ROUND_S + bd.CHECK_S_PER_OBS * 1000)
    joins = bd.repair_seconds(1000, True, False, 2.0)
    assert joins > plain + bd.JOINS_FIRST_S + 2.0
    assert bd.repair_seconds(1000, True, True, 2.0) > joins + bd.REFINE_FIRST_S
    assert bd.repair_seconds(2000, True, True, 2.0) > bd.repair_seconds(1000, True, True, 2.0)
    # the refinement moves only the per-channel satellites' observations
    none_moved = bd.repair_seconds(1000, True, True, 2.0, refined=0)
    assert none_moved == pytest.approx(joins + bd.REFINE_FIRST_S + 3 * bd.REFINE_ROUND_S)
    half = bd.repair_seconds(1000, True, True, 2.0, refined=500)
    assert half == pytest.approx(none_moved + 3 * 500 * bd.REFINE_S_PER_OBS)


def test_search_leaves_the_reserve_scaled_by_the_pace(monkeypatch):
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 60.0, after_s=5.0)
    clock.wall += 10.0
    clock.cpu += 5.0  # pace 2
    ctx = _ctx(1000, refining=False)
    b = bd.deadline_budget(ctx, d, flown_joins=False, refill_s=2.0)
    repair = 2.0 * bd.repair_seconds(1000, False, False, 2.0)  # every target planned
    assert b.search_end == pytest.approx(d.end - repair - 10.0)
    assert b.repair_end == pytest.approx(d.end - 10.0)  # the outputs' share is kept
    assert b.split["reserve_s"] == {"repair": round(repair, 2), "outputs": 10.0}
    assert b.split["before_search_s"] == 10.0 and d.split is b.split
    assert not b.refining


def test_the_greedy_start_moves_the_search_end_to_what_its_plan_needs(monkeypatch):
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 100.0, after_s=5.0)
    clock.wall += 10.0
    clock.cpu += 10.0  # pace 1
    ctx = _ctx(20000, refining=True, rigid=3)  # one per-channel satellite of four
    b = bd.deadline_budget(ctx, d, flown_joins=False, refill_s=2.0)
    first = bd.repair_seconds(20000, False, True, 2.0, refined=5000)  # options split 1:3
    assert b.search_end == pytest.approx(d.end - first - 5.0)
    clock.wall += 5.0
    clock.cpu += 5.0
    end = b.retime([1000, 1000, 1000, 1000])  # the greedy start: a fifth of the targets
    size = bd.PLAN_GROWTH * 4000
    repair = bd.repair_seconds(size, False, True, 2.0, refined=size / 4)
    assert end == pytest.approx(d.end - repair - 5.0) and end > b.search_end
    assert d.split["observations"] == size and d.split["search_s"] == pytest.approx(90 - repair - 5)
    assert d.split["reserve_s"]["repair"] == round(repair, 2)
    rigid_only = b.retime([0, 2000, 1000, 1000])  # nothing to refine: no refinement reserved
    plain = bd.repair_seconds(size, False, False, 2.0)
    assert rigid_only == pytest.approx(d.end - plain - 5.0) and rigid_only > end
    every = bd.repair_seconds(20000, False, True, 2.0)  # never past every target planned
    assert b.retime([10**6, 0, 0, 0]) == pytest.approx(d.end - every - 5.0)
    clock.wall += 40.0  # a loaded machine: the estimate at pace 3 does not fit
    assert b.retime([15000, 0, 0, 0]) == pytest.approx(10.0 + 1000.0 + bd.SEARCH_MIN_SHARE * 90.0)
    capped = bd.deadline_budget(_ctx(20, False), d, flown_joins=False, refill_s=2.0, capped=True)
    assert capped.retime is None  # iteration-capped runs keep their clock-free search


def test_search_gets_its_minimum_share_when_the_reserve_does_not_fit(monkeypatch):
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 20.0, after_s=100.0)
    clock.wall += 12.0
    clock.cpu += 12.0
    b = bd.deadline_budget(_ctx(5000, True), d, flown_joins=True, refill_s=2.0)
    assert b.search_end == pytest.approx(clock.wall + bd.SEARCH_MIN_SHARE * 8.0)
    assert b.refining and b.repair_end < clock.wall  # no time for the optional steps
    pc, said = SimpleNamespace(refine_steps=50), []
    assert bd.refine_steps(pc, b, None, lambda *a: said.append(a)) == 0
    assert [stage for stage, _ in said] == ["refine"]
    assert bd.refine_steps(pc, b, 200, lambda *a: said.append(a)) == 50  # capped: no clock


def test_default_budget_keeps_the_fixed_shares():
    sc = _ctx(10, refining=True).scenario
    b = bd.default_budget(sc, 40.0, 100.0)
    reserve = max(bd.RESERVE_MIN_S, bd.RESERVE_SHARE * 40.0) + bd.REFINE_MAX_S
    assert b.search_end == pytest.approx(140.0 - reserve) and b.repair_end == 140.0
    assert b.refining and b.split == {}


@functools.cache
def _searched_once(seed):
    return _searched(seed)


def _reject_once(calls):
    """A flown-join check that rejects the first observation once, then passes."""

    def reject(sc, scene, opp, chosen):
        calls.append(len(chosen))
        return ([chosen[0]] if len(calls) == 1 else []), {"joins": len(chosen)}

    return reject


@pytest.mark.parametrize("late", [False, True])
def test_repair_leaves_out_its_refills_past_the_deadline_never_its_checks(monkeypatch, late):
    sc, prep, tl = _searched_once(0)
    chosen = [c for c in tl.assigned if c >= 0]
    calls, refills = [], []
    monkeypatch.setattr(rp, "reject_unflyable", _reject_once(calls))
    real_refill = rp._refill
    monkeypatch.setattr(rp, "_refill", lambda *a: refills.append(a[3]) or real_refill(*a))
    deadline = time.monotonic() + (-1.0 if late else 3600.0)
    rep = rp.repair(prep, chosen, flown_joins=True, refill_s=0.2, deadline=deadline)
    assert len(calls) == 2  # the join check ran again on the final plan
    assert rep.dropped["joins"] == 1
    assert _check(sc, prep, rep.opp, rep.chosen)[0] == []  # valid either way
    if late:
        assert refills == [] and [w for w, _ in rep.skipped] == ["refill"]
        assert rep.refilled == 0
        assert rep.chosen == chosen[1:]
    else:
        assert len(refills) == 1 and refills[0] == pytest.approx(0.2) and rep.skipped == ()


def test_a_call_whose_checks_would_end_far_past_the_limit_stops_before_the_search(monkeypatch):
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 10.0, "3 targets", after_s=1.0, must_s=0.5)
    clock.wall += 25.0  # the compile allowance let the stages before the search run late
    clock.cpu += 25.0
    ctx = _ctx(2000, refining=False)
    need = bd.mandatory_seconds(ctx, True, 0.5)
    first = bd.CHECK_FIRST_S + bd.JOINS_FIRST_S  # loading the checks' programs
    n = bd.TYPICAL_PLAN_SHARE * 2000
    assert need == pytest.approx(2 * (bd.CHECK_S_PER_OBS + bd.JOINS_S_PER_OBS) * n + first + 0.5)
    assert 25.0 + need - 10.0 > bd.LATE_MAX_S
    with pytest.raises(dl.TimeLimitError, match="would end .* past the limit; 3 targets") as e:
        bd.deadline_budget(ctx, d, flown_joins=True, refill_s=2.0)
    assert e.value.stage == "search" and e.value.estimate == pytest.approx(25.0 + need)
    b = bd.deadline_budget(ctx, d, flown_joins=True, refill_s=2.0, capped=True)  # reproducible
    assert b.search_end == pytest.approx(clock.wall)  # nothing left: a quarter of nothing
    assert bd.deadline_budget(_ctx(10, False), d, flown_joins=True, refill_s=2.0)  # small: late


def test_a_small_scenario_whose_stages_ran_late_on_a_loaded_machine_is_refused(monkeypatch):
    # the probe's case: 12 targets, three maneuver models, --time-limit 25; the stages
    # before the search ended at 37.9 s at pace 3, and the checks (their programs'
    # first calls, 15.2 s there) ended the run 29.8 s past the limit: now refused
    clock = _Clock(monkeypatch)
    d = dl.StageDeadline(clock.wall, 25.0, after_s=1.0, must_s=0.5)
    clock.wall += 37.9
    clock.cpu += 37.9 / 3.0
    with pytest.raises(dl.TimeLimitError, match="would end 2[0-9] s past the limit"):
        bd.deadline_budget(_ctx(12, False), d, flown_joins=True, refill_s=2.0)


def test_a_stage_stopped_before_any_share_gives_a_lower_bound():
    # a stage that has not finished its first block (0 %) cannot extrapolate its rate:
    # the message still says how much more time is needed, as a lower bound
    d = dl.StageDeadline(time.monotonic() - 50.0, 20.0, "50000 targets")
    with pytest.raises(dl.TimeLimitError) as err:
        d.check("screening", 0.0, stage_t0=time.monotonic() - 30.0)
    msg = str(err.value)
    assert "0 % through it" in msg and "need more than" in msg
    assert err.value.estimate is None
    spent = float(msg.split("need more than ")[1].split(" s")[0])
    assert spent >= 49.0 - dl.COMPILE_ALLOWANCE_S
    assert "well above" in msg


def test_an_areas_strips_count_as_observations_per_pass():
    """With areas the plan's most observations are the point targets with options plus,
    per pass, the strips it holds: ``floor((slots + 1) / (shortest + 1))`` (a slot apart),
    at most the action cap (a synthetic problem: two satellites, two passes of 6 slots)."""
    from _synth_area import make

    s = make(3, n_sats=2, passes=2, pass_slots=6, min_slots=2, n_points=3)
    pb = s.pb
    opts = SimpleNamespace(route=np.asarray(pb.option_target), sat=np.asarray(pb.option_sat))
    ctx = SimpleNamespace(opportunities=SimpleNamespace(options=opts), problem=pb)
    points = len({o.target for o in s.opts if not o.area})
    per_pass = (6 + 1) // (2 + 1)
    assert bd._targets(ctx) == points + 2 * 2 * per_pass
    pb.max_actions = 5
    assert bd._targets(ctx) == points + 5
