"""The time limit of the stages before the search: a scenario too big for it stops early.

:func:`jaxspline.plan`'s ``time_limit`` bounds the whole call. The search stops at its
own deadline; the stages before it (orbits, windows, options, screening) check a
:class:`StageDeadline` between stages and, inside the options and screening stages,
between blocks of work. When the limit has passed there, :meth:`StageDeadline.check`
raises :class:`TimeLimitError` at once, with what was done, an estimate of the time the
stages need (their elapsed time over the measured share of the stage) and the remedy.

Compiling XLA programs (tracing, lowering, compiling or loading them from the
persistent cache: the events JAX reports through ``jax.monitoring``) is not counted
against the limit here, up to :data:`COMPILE_ALLOWANCE_S`: a first run on an empty
cache compiles for 10-40 s, which the next runs do not pay, and a small scenario should
not be refused for it. Compile time past the allowance counts, so the stages before the
search never run longer than the limit plus the allowance (plus one block of work).
"""

from __future__ import annotations

import math
import threading
import time

__all__ = [
    "COMPILE_ALLOWANCE_S",
    "StageDeadline",
    "TimeLimitError",
    "compile_seconds",
    "suggested_limit",
]

#: Compile time [s] not counted against the limit (the rest counts).
COMPILE_ALLOWANCE_S = 20.0

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


_NICE_LIMITS = (10, 20, 30, 60, 120, 300, 600, 1200, 1800, 3600, 7200, 14400, 28800, 86400)


class TimeLimitError(Exception):
    """The time limit ran out before the search could start (a one-line message).

    Attributes:
      stage: the stage that was running (``"options"``, ``"screening"``, ...).
      elapsed: seconds since the call started.
      estimate: estimated seconds the stages before the search need (None: unknown).
    """

    def __init__(self, msg: str, stage: str, elapsed: float, estimate: float | None):
        super().__init__(msg)
        self.stage, self.elapsed, self.estimate = stage, elapsed, estimate


def suggested_limit(estimate: float) -> int:
    """A round time limit [s] leaving the search as much time as the stages before it.

    Args:
      estimate: seconds the stages before the search need.
    Returns:
      int, the smallest of 10, 20, 30, 60, 120, ... s at least twice ``estimate``
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

    Attributes:
      t0: as given.
      limit: as given.
      scale: as given.
      allowance: as given.
      compiled0: :func:`compile_seconds` when the deadline was made.
    """

    def __init__(self, t0, limit, scale="", allowance=COMPILE_ALLOWANCE_S):
        self.t0, self.limit, self.scale, self.allowance = t0, limit, scale, allowance
        self.compiled0 = compile_seconds()

    def check(self, stage: str, done: float = 1.0, stage_t0: float | None = None, what=""):
        """Raise :class:`TimeLimitError` when the limit has passed (compile time aside).

        Args:
          stage: the running stage.
          done: share of the stage done, in [0, 1].
          stage_t0: when the stage started [s, monotonic] (None: the call's start).
          what: what the stage works on (``"1.9 M options"``), for the message.
        Raises:
          TimeLimitError: naming the stage, its progress, the estimate and the remedy.
        """
        now = time.monotonic()
        compiling = min(compile_seconds() - self.compiled0, self.allowance)
        if now - self.t0 - compiling <= self.limit:
            return
        elapsed = now - self.t0
        start = self.t0 if stage_t0 is None else stage_t0
        estimate = None
        if done > 0:
            estimate = (start - self.t0) + (now - start) / min(done, 1.0) - compiling
        progress = f"{100 * done:.0f} % through it" if done < 1 else "at its end"
        need = (
            f"at this pace the stages before the search alone need ~{estimate:.0f} s or more; "
            f"give a time limit of {suggested_limit(estimate)} s or more"
            if estimate is not None
            else "give a longer time limit"
        )
        raise TimeLimitError(
            f"time limit of {self.limit:.4g} s reached before the search, in stage {stage!r} "
            f"after {elapsed:.1f} s ({compile_seconds() - self.compiled0:.1f} s of it compiling; "
            f"{progress}"
            f"{'; ' + what if what else ''}{'; ' + self.scale if self.scale else ''}): {need} "
            "(--time-limit or planner.time_limit_s), or plan fewer targets or satellites, "
            "a shorter horizon, or a coarser planner.time_step_s",
            stage,
            elapsed,
            estimate,
        )
