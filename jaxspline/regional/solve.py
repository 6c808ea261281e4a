"""``solve_case``: a regional_coverage case -> a solution, under one wall-clock budget.

Stages, each checking the clock (one budget from the call, or from ``t_start``):

1. candidates (:func:`jaxspline.planner.coverage_candidates.build_problem`): SGP4 tracks, passes,
   roll grid, 10 s slices and their covered samples (JAX coverage engine, compile
   included);
2. lazy greedy, then LNS until the search deadline
   (:mod:`jaxspline.search.coverage_search`);
3. a final check of every satellite's timeline with the exact refined battery model
   (:func:`jaxspline.search.coverage_rules.battery_levels`), dropping a strip if a rule
   would fail (never expected: the search keeps margins);
4. the Lagrangian upper bound (:mod:`jaxspline.search.coverage_bound`), computed in a child
   process (``python -m jaxspline.search.coverage_bound``) while the search runs, capped by the
   coverage of all candidates together; if that process gives nothing, a short
   in-process run instead.

The budget keeps ``reserve`` seconds back for writing and checking the solution.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass

__all__ = [
    "SolveConfig",
    "collect_bound",
    "final_check",
    "plan_stats",
    "solution_actions",
    "solve_case",
    "start_bound",
]

#: The bound process stops this long before the search ends, to hand its result over [s].
BOUND_COLLECT_S = 1.0
#: Longest wait for the bound process after the search [s].
BOUND_WAIT_S = 5.0
#: Most of the search time spent on reaching regions' minimum coverage first.
MIN_PHASE_SHARE = 0.5
#: The most of a short time limit the reserve and the bound's lead may take (shares of
#: the limit): under ``reserve_min_s / RESERVE_MAX_SHARE`` seconds the fixed minimums would
#: leave the greedy no time at all.
RESERVE_MAX_SHARE = 0.4
BOUND_MAX_SHARE = 0.2


@dataclass(frozen=True)
class SolveConfig:
    """Budget shares and knobs of :func:`solve_case`.

    Attributes:
      reserve_frac, reserve_min_s: time kept back for writing and checking the solution
        (the larger of ``reserve_frac * time_limit`` and ``reserve_min_s``, at most
        :data:`RESERVE_MAX_SHARE` of the limit) [s].
      bound_frac, bound_min_s: time for the bound (the larger of the two, at most
        :data:`BOUND_MAX_SHARE` of the limit) [s].
      roll_step_deg: roll grid step [deg].
    """

    reserve_frac: float = 0.15
    reserve_min_s: float = 6.0
    bound_frac: float = 0.08
    bound_min_s: float = 3.0
    roll_step_deg: float = 0.25


def solution_actions(case, prob, state) -> list[dict]:
    """The benchmark's action list of a plan, in time order.

    Args:
      case: Case; prob: CoverProblem; state: PlanState.
    Returns:
      list of ``strip_observation`` dicts (satellite_id, start_time, duration_s, roll_deg).
    """
    from jaxspline.regional.case import format_time

    out = []
    for g, a, b in sorted(state.strips.values(), key=lambda x: (x[1], int(prob.group_sat[x[0]]))):
        dur = (b - a) * prob.slot_s
        out.append(
            {
                "type": "strip_observation",
                "satellite_id": case.satellites[int(prob.group_sat[g])].id,
                "start_time": format_time(case.time_at(a * prob.slot_s)),
                "duration_s": int(dur) if float(dur).is_integer() else dur,
                "roll_deg": float(prob.group_roll[g]),
            }
        )
    return out


def final_check(state) -> int:
    """Drop strips until every satellite passes the exact rules with margins; returns drops.

    Args:
      state: PlanState, modified in place.
    Returns:
      number of strips removed.
    """
    from jaxspline.search.coverage_rules import battery_levels, duty_ok, gaps_ok

    prob = state.prob
    dropped = 0
    for sat in range(len(prob.rules)):
        while state.by_sat[sat]:
            s, e, r = state.timeline(sat)
            rules = prob.rules[sat]
            ok = gaps_ok(rules, s, e, r, prob.margins) and duty_ok(rules, s, e, prob.margins)
            if ok:
                lvl = battery_levels(
                    rules, prob.mesh_s, prob.sunlit_iv[sat], s, e, r, prob.margins
                )[1]
                ok = float(lvl.min()) >= prob.margins.battery_wh
            if ok:
                break
            worst = min(state.by_sat[sat], key=state.loss)
            state.remove(worst)
            dropped += 1
    return dropped


def start_bound(prob, target: float, seconds: float):
    """Start ``python -m jaxspline.search.coverage_bound`` on a pickled problem (a child process).

    Args:
      prob: CoverProblem; target: a plan value to aim at; seconds: its budget [s].
    Returns:
      (process, temporary file path), or None if it could not start.
    """
    import functools
    import os
    import pickle
    import subprocess
    import tempfile
    import warnings

    from jaxspline.search.orphans import die_with_parent

    try:
        fd, path = tempfile.mkstemp(prefix="jaxspline-bound-", suffix=".pkl")
        with os.fdopen(fd, "wb") as fh:
            pickle.dump((prob, float(target)), fh, protocol=pickle.HIGHEST_PROTOCOL)
        cmd = [
            sys.executable,
            "-m",
            "jaxspline.search.coverage_bound",
            path,
            f"{max(seconds, 1.0):.3f}",
        ]
        env = dict(os.environ, JAX_PLATFORMS=os.environ.get("JAX_PLATFORMS", "cpu"))
        ends = functools.partial(die_with_parent, os.getpid(), watch=False)  # with us
        out, err = subprocess.PIPE, subprocess.DEVNULL
        with warnings.catch_warnings():  # JAX warns of any fork; the child execs at once
            warnings.filterwarnings("ignore", message=r"os\.fork\(\) was called")
            proc = subprocess.Popen(
                cmd, stdout=out, stderr=err, text=True, env=env, preexec_fn=ends
            )
        return proc, path
    except (OSError, ValueError):
        return None


def collect_bound(worker, wait_s: float):
    """The (bound, iterations) a :func:`start_bound` process printed, or None.

    Args:
      worker: what :func:`start_bound` returned; wait_s: longest wait [s].
    Returns:
      (bound, iterations) or None; the process is ended and its file removed either way.
    """
    import os
    import subprocess

    if worker is None:
        return None
    proc, path = worker
    got = None
    try:
        out, _ = proc.communicate(timeout=wait_s)
        bound, iters = out.split()
        got = (float(bound), int(iters))
    except (subprocess.TimeoutExpired, ValueError):
        proc.kill()
        proc.communicate()
    finally:
        try:
            os.unlink(path)
        except OSError:
            pass
    return got


def plan_stats(case, state, bound: float) -> dict:
    """Scores of a plan: coverage_ratio, weighted ratio, per region, actions, bound, gap.

    Args:
      case: Case; state: PlanState; bound: upper bound on coverage_ratio.
    Returns:
      dict.
    """
    covered = state.cnt > 0
    total = float(case.grid.region_total_m2.sum())
    return {
        "coverage_ratio": state.value,
        "weighted_coverage_ratio": float(case.grid.weight_m2[covered].sum()) / total,
        "region_coverage": state.region_cov.tolist(),
        "shortfall": state.shortfall(),
        "actions": state.n_actions(),
        "bound": bound,
        "gap": bound - state.value,
        "min_battery_wh": state.min_battery(),
    }


def solve_case(
    case,
    time_limit: float = 120.0,
    seed: int = 0,
    progress: bool = True,
    t_start: float | None = None,
    config: SolveConfig = SolveConfig(),
):
    """Plan a case within ``time_limit`` seconds.

    Args:
      case: Case (:func:`jaxspline.regional.case.load_case`).
      time_limit: wall-clock budget [s], counted from ``t_start`` (default: now).
      seed: random seed of the search.
      progress: print progress lines to stderr.
      t_start: ``time.perf_counter()`` instant the budget started (e.g. process start).
      config: SolveConfig.
    Returns:
      (solution, stats): ``{"actions": [...]}`` and a dict with coverage_ratio,
      weighted_coverage_ratio, actions, bound, gap, min_battery_wh, timings and counts.
    """
    import jax

    from jaxspline.planner.coverage_candidates import build_problem
    from jaxspline.search.coverage_search import (
        SearchConfig,
        candidate_windows,
        greedy_fill,
        lns,
        meet_minimums,
    )
    from jaxspline.search.coverage_state import PlanState

    if not time_limit > 0:
        raise ValueError(f"time_limit: must be > 0, got {time_limit!r}")
    t0 = time.perf_counter() if t_start is None else t_start
    reserve, bound_s = _shares(time_limit, config)
    end = t0 + time_limit - reserve

    def log(msg):
        if progress:
            print(f"[{time.perf_counter() - t0:6.1f} s] {msg}", file=sys.stderr, flush=True)

    times = {}
    with jax.enable_x64(True):
        prob, info = build_problem(case, step_deg=config.roll_step_deg, log=log)
    times["candidates_s"] = time.perf_counter() - t0
    state = PlanState(prob)
    win = candidate_windows(prob)
    greedy_fill(state, win, end - bound_s)
    times["greedy_s"] = time.perf_counter() - t0 - times["candidates_s"]
    log(f"greedy: coverage {state.value:.5f} with {state.n_actions()} strips")
    worker = start_bound(prob, state.value, end - time.perf_counter() - BOUND_COLLECT_S)
    cfg = SearchConfig(seed=seed)
    mid = time.perf_counter() + MIN_PHASE_SHARE * (end - time.perf_counter())
    state = meet_minimums(state, win, mid, cfg, log=log)
    best, lstats = lns(state, win, end, cfg, log=log)
    dropped = final_check(best)
    log(
        f"search: coverage {best.value:.5f} with {best.n_actions()} strips "
        f"({lstats['iterations']} LNS iterations, {dropped} dropped at the final check)"
    )
    t_b = time.perf_counter()
    bound, bound_its = _final_bound(worker, prob, best.value, info, bound_s, log)
    times["bound_wait_s"] = time.perf_counter() - t_b
    actions = solution_actions(case, prob, best)
    stats = {
        **plan_stats(case, best, bound),
        "bound_iterations": bound_its,
        "union_ratio": info.union_ratio,
        **{k: getattr(info, "n_" + k) for k in ("passes", "groups", "rows")},
        "nnz": info.nnz,
        "dropped": dropped,
        **lstats,
        **times,
        "total_s": time.perf_counter() - t0,
    }
    log(f"bound {bound:.5f} (gap {bound - best.value:.5f}, {bound_its} iterations)")
    return {"actions": actions}, stats


def _shares(time_limit: float, config: SolveConfig) -> tuple[float, float]:
    """(reserve, the bound's lead) [s] of a run of ``time_limit`` seconds (:class:`SolveConfig`),
    each capped at its share of the limit (:data:`RESERVE_MAX_SHARE`, :data:`BOUND_MAX_SHARE`)."""
    reserve = max(config.reserve_frac * time_limit, config.reserve_min_s)
    bound_s = max(config.bound_frac * time_limit, config.bound_min_s)
    return min(reserve, RESERVE_MAX_SHARE * time_limit), min(bound_s, BOUND_MAX_SHARE * time_limit)


def _final_bound(worker, prob, value: float, info, bound_s: float, log):
    """The bound of the search's plan (``value``): the bound process's result, or a short
    in-process one when it gave nothing; capped by the union of every candidate
    (``info.union_ratio``). Returns (bound, iterations)."""
    from jaxspline.search.coverage_bound import lagrangian_bound

    got = collect_bound(worker, BOUND_WAIT_S)
    if got is None:
        log("bound process gave nothing: short in-process bound")
        res = lagrangian_bound(prob, value, time.perf_counter() + bound_s)
        got = (res.bound, res.iterations)
    bound = min(got[0], info.union_ratio)
    if value - 1e-9 < bound < value:  # the union's sum rounds differently
        bound = value
    return bound, got[1]
