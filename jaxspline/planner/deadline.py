"""The time limit of the stages before the search: a scenario too big for it stops early.

:func:`jaxspline.plan`'s ``time_limit`` bounds the whole call. The search stops at its
own deadline; the stages before it (orbits, windows, options, screening) check a
:class:`StageDeadline` between stages and, inside the options and screening stages,
between blocks of work. When the limit has passed there, :meth:`StageDeadline.check`
raises :class:`TimeLimitError` at once, with what was done, an estimate of the time the
whole run needs and the remedy (:func:`suggested_limit`: twice the estimate, rounded up).

The estimate (given the run's :class:`RunSize`) covers every stage still to come, not
only the running one: the rest of the running stage (its elapsed time over the measured
share of it, or its work model when no share is done yet), then each later stage from
its work model (:func:`stage_seconds`), then what follows the search (the repair and
the caller's outputs, :attr:`StageDeadline.after_s`); all of it at the run's pace. The
work models count the units a stage works on, as well as they are known when the
limit runs out: the target-satellite pairs (exact), the candidate options (once the
windows are known; before, :data:`CANDIDATES_PER_STEP` per pair and time step of the
horizon), the options (once built; before, the candidates) and the near pairs the
screening evaluates, which grow as the square of the options' density in time
(:data:`NEAR_REACH_S`, :data:`CLUSTERING`). Each unit costs the CPU time of
:data:`WORK_SECONDS` and :data:`PAIR_SECONDS`, measured on 2-core runs with the
programs compiled and rounded up about twice.

Compiling XLA programs (tracing, lowering, compiling or loading them from the
persistent cache: the events JAX reports through ``jax.monitoring``) is not counted
against the limit here, up to :data:`COMPILE_ALLOWANCE_S`: a first run on an empty
cache compiles for 10-40 s, which the next runs do not pay, and a small scenario should
not be refused for it. Compile time past the allowance counts, so the stages before the
search never run longer than the limit plus the allowance (plus one block of work).

After the search the same clock serves the stages that follow it
(:mod:`jaxspline.planner.budget`): :attr:`StageDeadline.after_s` is what the caller
needs once :func:`jaxspline.plan` returns (the outputs of ``jaxspline plan``),
:meth:`StageDeadline.pace` how much slower than its CPU time the call runs (a loaded
machine), :meth:`StageDeadline.fits` whether an estimated step still fits before the
limit, and :meth:`StageDeadline.skip` records what was left out because it did not
(:meth:`StageDeadline.record`: the ``"time_limit"`` section of ``plan.json``).
"""

from __future__ import annotations

import math
import os
import threading
import time
from pathlib import Path
from typing import NamedTuple

__all__ = [
    "CANDIDATES_PER_STEP",
    "CLUSTERING",
    "COMPILE_ALLOWANCE_S",
    "EXEC_WAIT_FACTOR",
    "EXEC_WAIT_SLACK_S",
    "JOINS_S_PER_OBS",
    "NEAR_REACH_S",
    "OBSERVATION_EVERY_S",
    "PACE_MAX",
    "PAIR_SECONDS",
    "REPAIR_S_PER_OBS",
    "STAGES",
    "STAGE_SECONDS",
    "RunSize",
    "StageDeadline",
    "TimeLimitError",
    "WORK_SECONDS",
    "compile_seconds",
    "process_start",
    "stage_seconds",
    "startup_seconds",
    "suggested_limit",
]

#: Compile time [s] not counted against the limit (the rest counts).
COMPILE_ALLOWANCE_S = 20.0
#: Largest pace (wall time over CPU time) the estimates of the later stages are scaled by.
PACE_MAX = 3.0
#: A process older than this many times its own CPU time, plus :data:`EXEC_WAIT_SLACK_S`,
#: was created before Python started: a shell ran other commands, then exec'd this one
#: (``bash -c 'pip install ... && jaxspline plan ...'`` execs its last command, which
#: keeps the shell's start time). Python's start-up is CPU-bound, so its CPU time is
#: then the measure of it.
EXEC_WAIT_FACTOR = 3.0
#: [s] added to :data:`EXEC_WAIT_FACTOR` times the CPU time (a slow disk, a loaded machine).
EXEC_WAIT_SLACK_S = 5.0
_PACE_MIN_WALL_S = 1.0  # [s] of wall time before the pace is measured (1 until then)

_COMPILE_EVENTS = frozenset(
    (
        "/jax/core/compile/jaxpr_trace_duration",
        "/jax/core/compile/jaxpr_to_mlir_module_duration",
        "/jax/core/compile/backend_compile_duration",
    )
)
_compiled = [0.0]  # seconds spent compiling in this process, since the first call below
_lock = threading.Lock()
_listening = []


def _on_event(event: str, duration: float, **kwargs) -> None:
    if event in _COMPILE_EVENTS:
        with _lock:
            _compiled[0] += duration


def compile_seconds() -> float:
    """Seconds this process has spent compiling XLA programs (since the first call).

    Returns:
      float [s]: the durations of JAX's trace, lowering and compile events.
    """
    if not _listening:
        import jax

        with _lock:
            if not _listening:
                jax.monitoring.register_event_duration_secs_listener(_on_event)
                _listening.append(True)
    return _compiled[0]


def process_start() -> float:
    """When this process started, on the ``time.monotonic`` clock [s].

    A command's time limit counts from here, so starting Python and importing JAX
    (2-7 s) count too. Reads the process's age from ``/proc/self/stat`` (Linux),
    corrected by :func:`startup_seconds` for a process that a shell exec'd after other
    work; elsewhere, or when that fails, the current time.

    Returns:
      float [s], at most ``time.monotonic()``.
    """
    try:
        fields = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        started = int(fields[_STAT_STARTTIME]) / os.sysconf("SC_CLK_TCK")  # since boot
        age = time.clock_gettime(time.CLOCK_BOOTTIME) - started
    except (OSError, ValueError, IndexError, AttributeError):
        return time.monotonic()
    return time.monotonic() - startup_seconds(age, time.process_time())


def startup_seconds(age_s: float, cpu_s: float) -> float:
    """How long ago this Python process started, from its age and its CPU time [s].

    The age counts from the process's creation, which for a command a shell exec'd is
    the shell's start (:data:`EXEC_WAIT_FACTOR`): an age far above the CPU time used
    means the process waited before Python ran, and the CPU time stands for the
    start-up then.

    Args:
      age_s: seconds since the process was created (``/proc/self/stat``).
      cpu_s: its CPU time so far (``time.process_time()``).
    Returns:
      float >= 0 [s].
    """
    age_s, cpu_s = max(float(age_s), 0.0), max(float(cpu_s), 0.0)
    if age_s > EXEC_WAIT_FACTOR * cpu_s + EXEC_WAIT_SLACK_S:
        return min(cpu_s, age_s)
    return age_s


#: The stages before the search, in order.
STAGES = ("loading", "orbits", "windows", "options", "screening")
#: CPU seconds a unit of a stage's work takes (windows: per target and satellite;
#: options: per candidate option, :func:`jaxspline.planner.opportunities.option_counts`;
#: screening: per option, its far gaps and first observation, the near pairs aside:
#: :data:`PAIR_SECONDS`). Fitted to 2-core runs of 5,000 to 100,000 targets with the
#: programs compiled (5e-6, 8e-6 and 4.3e-5), rounded up.
WORK_SECONDS = {"windows": 2e-5, "options": 2e-5, "screening": 1e-4}
#: [s] of CPU every stage takes besides its units (loading its compiled programs).
STAGE_SECONDS = 2.0
#: CPU seconds of the screening per candidate near pair (fitted 7e-8, rounded up).
PAIR_SECONDS = 1.5e-7
#: Candidate options per target-satellite pair and time step of the horizon, before the
#: windows are known (measured 3e-4 to 9e-4 on targets spread over the globe, 6.4e-4 on
#: land strips; a scenario whose satellites are placed over its targets has more, and
#: its estimate is made again from its candidates once the windows are known).
CANDIDATES_PER_STEP = 7e-4
#: [s] the gap a near pair spans at most, besides the options' own length (the far gaps
#: of the packaged satellites: 41-188 s).
NEAR_REACH_S = 150.0
#: How much more near pairs a satellite's options have than if they were spread evenly
#: over the horizon (targets cluster on land and under the ground tracks; measured 2-9).
CLUSTERING = 4.0
#: [s] of CPU the repair takes per observation of the plan (the independent checks and
#: the start-time refinement of its rounds; :mod:`jaxspline.planner.budget` has the
#: detailed model, measured 1.8e-3), plus :data:`STAGE_SECONDS` per step.
REPAIR_S_PER_OBS = 3e-3
#: [s] of CPU the flown-join checks add per observation (three rounds; measured 7.2e-3).
JOINS_S_PER_OBS = 1e-2
#: [s] a satellite takes at least per observation in the estimate of a plan's size.
OBSERVATION_EVERY_S = 30.0
_REPAIR_STEPS = 3  # the repair's steps that load programs (check, joins, refinement)


class RunSize(NamedTuple):
    """What the estimate of a run's time starts from (module docstring).

    Attributes:
      targets: number of targets.
      satellites: number of satellites.
      duration_s: the horizon [s].
      time_step_s: the planner's time step [s] (candidate starts are this far apart).
      repair: a plan is searched, repaired and written after the stages (``jaxspline
        plan``); False: nothing of it follows (``jaxspline bound``).
      joins: the repair checks the flown joins (``jaxspline plan --aem``).
    """

    targets: int
    satellites: int
    duration_s: float
    time_step_s: float
    repair: bool = True
    joins: bool = False


def stage_seconds(size: RunSize, known: dict | None = None) -> dict:
    """CPU seconds of every stage of a run on an idle machine, from its work models.

    Args:
      size: the run's :class:`RunSize`.
      known: the units a stage works on where they are known (``{"options": candidate
        options, "screening": options}``); the others are estimated (module docstring).
    Returns:
      dict stage -> float [s]: ``"windows"``, ``"options"``, ``"screening"`` and, with
      ``size.repair``, ``"repair"``.
    """
    known = known or {}
    sats, horizon = max(size.satellites, 1), max(size.duration_s, 1.0)
    pairs = size.targets * size.satellites
    steps = horizon / max(size.time_step_s, 1e-3)
    cands = known.get("options", pairs * steps * CANDIDATES_PER_STEP)
    options = known.get("screening", cands)
    near = CLUSTERING * NEAR_REACH_S * options * options / (sats * horizon)
    out = {
        "windows": STAGE_SECONDS + pairs * WORK_SECONDS["windows"],
        "options": STAGE_SECONDS + cands * WORK_SECONDS["options"],
        "screening": STAGE_SECONDS + options * WORK_SECONDS["screening"] + near * PAIR_SECONDS,
    }
    if size.repair:
        plan = min(0.5 * size.targets, options, sats * horizon / OBSERVATION_EVERY_S)
        each = REPAIR_S_PER_OBS + size.joins * JOINS_S_PER_OBS
        out["repair"] = _REPAIR_STEPS * STAGE_SECONDS + plan * each
    return out


_STAT_STARTTIME = 19  # field 22 of /proc/PID/stat (starttime), counted after "(comm) "
_NICE_LIMITS = (10, 20, 30, 60, 90, 120, 180, 300, 600, 900, 1200, 1800, 3600, 7200, 14400)
_NICE_LIMITS += (28800, 86400)


class TimeLimitError(Exception):
    """The time limit ran out before the search could start (a one-line message).

    Attributes:
      stage: the stage that was running (``"options"``, ``"screening"``, ...).
      elapsed: seconds since the call started.
      estimate: estimated seconds the run needs: the whole run given a :class:`RunSize`,
        else the stages before the search (None: unknown).
    """

    def __init__(self, msg: str, stage: str, elapsed: float, estimate: float | None):
        super().__init__(msg)
        self.stage, self.elapsed, self.estimate = stage, elapsed, estimate


def suggested_limit(estimate: float) -> int:
    """A round time limit [s] leaving the search as much time as the rest of the run.

    Args:
      estimate: seconds the run needs besides the search.
    Returns:
      int, the smallest of 10, 20, 30, 60, 90, 120, 180, 300, ... s at least twice
      ``estimate``
      (or twice the estimate rounded up when it is longer than a day).
    """
    want = 2.0 * estimate
    return next((n for n in _NICE_LIMITS if n >= want), math.ceil(want))


class StageDeadline:
    """The clock of one call: started at ``t0``, ``limit`` seconds long, compile time aside.

    Args:
      t0: start of the call [s, ``time.monotonic``].
      limit: its time limit [s].
      scale: a line naming the scenario's size (in the error message).
      allowance: compile time not counted [s] (default :data:`COMPILE_ALLOWANCE_S`).
      after_s: estimated seconds the caller needs after :func:`jaxspline.plan` returns
        (on an idle machine; the outputs of ``jaxspline plan``), kept out of the search.
      must_s: the part of ``after_s`` that is never left out (``plan.json``, ``plan.csv``).
      size: the run's :class:`RunSize`: the estimate in the message is the whole run's
        (module docstring); None: the stages up to the running one only.
      goal: what the stages prepare, in the message (``"the search"``).
      flags: where the limit is set, in the message's remedy.

    Attributes:
      t0: as given.
      limit: as given.
      scale: as given.
      allowance: as given.
      after_s: as given.
      must_s: as given.
      size: as given.
      goal: as given.
      flags: as given.
      known: the units of work of the stages, as they became known (:meth:`check`).
      compiled0: :func:`compile_seconds` when the deadline was made.
      skipped: what was left out because of the limit (:meth:`skip`).
      split: how the limit was split (:meth:`record`; set by the planner).
    """

    def __init__(
        self,
        t0,
        limit,
        scale="",
        allowance=COMPILE_ALLOWANCE_S,
        after_s=0.0,
        must_s=0.0,
        *,
        size: RunSize | None = None,
        goal: str = "the search",
        flags: str = "--time-limit or planner.time_limit_s",
    ):
        self.t0, self.limit, self.scale, self.allowance = t0, limit, scale, allowance
        self.after_s, self.must_s = float(after_s), float(must_s)
        self.size, self.goal, self.flags = size, goal, flags
        self.known: dict = {}
        self.compiled0 = compile_seconds()
        self._wall0, self._cpu0 = time.monotonic(), time.process_time()
        self.skipped: list[dict] = []
        self.split: dict = {}

    @property
    def end(self) -> float:
        """The limit's end [s, ``time.monotonic``]: ``t0 + limit``."""
        return self.t0 + self.limit

    def pace(self) -> float:
        """Wall time over this process's CPU time since the deadline was made.

        Returns:
          float in [1, :data:`PACE_MAX`]: 1 on an idle machine (or within the first
          second), about 2.5 when the process gets 40 % of a core; the estimates of
          the later stages (CPU seconds) are multiplied by it.
        """
        wall = time.monotonic() - self._wall0
        cpu = time.process_time() - self._cpu0
        if wall < _PACE_MIN_WALL_S or cpu <= 0.0:
            return 1.0
        return min(max(wall / cpu, 1.0), PACE_MAX)

    def fits(self, seconds: float, end: float | None = None) -> bool:
        """Whether a step estimated at ``seconds`` (idle) ends by ``end`` at the current pace.

        Args:
          seconds: the step's estimate [s of CPU time].
          end: its end [s, monotonic] (default: :attr:`end`).
        Returns:
          bool.
        """
        end = self.end if end is None else end
        return time.monotonic() + seconds * self.pace() <= end

    def skip(self, stage: str, what: str, remedy: str, at: float | None = None) -> None:
        """Record that ``what`` was left out of ``stage`` because of the limit.

        Args:
          stage: ``"repair"`` or ``"outputs"``.
          what: what was left out (``"plan.czml"``, ``"refill"``).
          remedy: how to get it (``"give a longer --time-limit"``).
          at: when it was left out [s, monotonic] (default: now).
        """
        at = round((time.monotonic() if at is None else at) - self.t0, 2)
        self.skipped.append({"stage": stage, "what": what, "at_s": at, "remedy": remedy})

    def record(self) -> dict:
        """The ``"time_limit"`` section of ``plan.json``: the limit, its split, the pace
        and what was left out.

        Returns:
          dict, JSON-ready.
        """
        return {
            "limit_s": self.limit,
            **self.split,
            "pace": round(self.pace(), 3),
            "elapsed_s": round(time.monotonic() - self.t0, 2),
            "skipped": list(self.skipped),
        }

    def check(self, stage: str, done=1.0, stage_t0=None, what="", work=None):
        """Raise :class:`TimeLimitError` when the limit has passed (compile time aside).

        Args:
          stage: the running stage.
          done: share of the stage done, in [0, 1].
          stage_t0: when the stage started [s, monotonic] (None: the call's start).
          what: what the stage works on (``"1.9 M options"``), for the message.
          work: optional callable returning ``(units, name)``, the stage's work
            (``(918734, "options")``; called only when the limit has passed): with
            nothing done yet, the estimate of the stage is its work model
            (:func:`stage_seconds`; without a :attr:`size`, its units times its
            :data:`WORK_SECONDS`) at the run's pace.
        Raises:
          TimeLimitError: naming the stage, its progress, the estimate and the remedy.
        """
        now = time.monotonic()
        compiling = min(compile_seconds() - self.compiled0, self.allowance)
        if now - self.t0 - compiling <= self.limit:
            return
        elapsed = now - self.t0
        start = self.t0 if stage_t0 is None else stage_t0
        work = None if work is None else work()
        if work is not None:
            self.known[stage] = work[0]
        rest, basis = self._rest(stage, done, now - start, work)
        spent = now - self.t0 - compiling
        estimate = None if rest is None else spent + rest
        later = self._later(stage)
        progress = f"{100 * done:.0f} % through it" if done < 1 else "at its end"
        if work is not None and done < 1:
            progress += f" of {work[0]:,} {work[1]}"
        raise TimeLimitError(
            f"time limit of {self.limit:.4g} s reached before {self.goal}, in stage {stage!r} "
            f"after {elapsed:.1f} s ({compile_seconds() - self.compiled0:.1f} s of it compiling; "
            f"{progress}"
            f"{'; ' + what if what else ''}{'; ' + self.scale if self.scale else ''}): "
            f"{self._need(estimate, later, basis, spent, now - start, stage)} "
            f"({self.flags}), or plan fewer targets or satellites, "
            "a shorter horizon, or a coarser planner.time_step_s",
            stage,
            elapsed,
            None if estimate is None else estimate + (later or 0.0),
        )

    def _rest(self, stage: str, done: float, in_stage: float, work):
        """(seconds the running stage still needs at the run's pace or None, the basis
        of the estimate for the message)."""
        if done > 0:
            return in_stage / min(done, 1.0) - in_stage, ""
        pace = self.pace()
        if self.size is not None and stage in WORK_SECONDS:
            need = stage_seconds(self.size, self.known)[stage] * pace
        elif work is not None and stage in WORK_SECONDS:
            need = work[0] * WORK_SECONDS[stage] * pace
        else:
            return None, ""
        if work is None:
            return max(need - in_stage, 0.0), ""
        each = WORK_SECONDS[stage]
        return max(need - in_stage, 0.0), (
            f" (its work: {work[0]:,} {work[1]} at ~{1e3 * each:.2g} ms of CPU each, "
            f"x {pace:.2g} for the machine's load)"
        )

    def _later(self, stage: str) -> float | None:
        """Seconds of what follows the running stage at the run's pace (the later stages,
        the repair and the outputs), None without a :attr:`size`."""
        if self.size is None:
            return None
        first = STAGES.index(stage) + 1 if stage in STAGES else len(STAGES)
        cost = stage_seconds(self.size, self.known)
        later = sum(cost[s] for s in STAGES[first:] if s in cost) + cost.get("repair", 0.0)
        return (later + self.after_s) * self.pace()

    def _need(self, estimate, later, basis: str, spent: float, in_stage: float, stage: str):
        """The message's estimate and suggested limit (a lower bound without an estimate)."""
        if estimate is not None and later is not None:
            what = ", the repair and the outputs" if self.size.repair else ""
            return (
                f"at this pace the whole run needs ~{estimate + later:.0f} s or more "
                f"(~{estimate:.0f} s until {self.goal}{basis}, then ~{later:.0f} s for the "
                f"later stages{what}); give a time limit of "
                f"{suggested_limit(estimate + later)} s or more"
            )
        if estimate is not None:
            return (
                f"at this pace the stages before {self.goal} alone need ~{estimate:.0f} s or "
                f"more{basis}; give a time limit of {suggested_limit(estimate)} s or more"
            )
        return (  # not even a first share of the stage done: what is known is a lower bound
            f"the stages before {self.goal} need more than {spent:.0f} s at this pace "
            f"({in_stage:.1f} s in {stage!r} did not finish a first share of it); give "
            f"a time limit well above {suggested_limit(spent)} s"
        )
