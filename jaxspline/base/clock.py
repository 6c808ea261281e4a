"""The search's clock: wall time until a stop is requested, then +inf.

Every search stage compares :func:`now` with its deadline, so one call of
:func:`request_stop` (the planner's Ctrl-C / SIGTERM handler) makes every running
stage finish its current move and return its best plan, exactly as if its deadline
had passed. Stages whose deadline is ``+inf`` (the first greedy pass, which must
complete) are not cut: ``inf > inf`` is false.
"""

from __future__ import annotations

import contextlib
import math
import signal
import threading
import time

__all__ = [
    "catch_signals",
    "clear_stop",
    "note_signal",
    "now",
    "raise_pending_signal",
    "request_stop",
    "stop_requested",
]

_STOP = threading.Event()
_PENDING: list[str] = []  # a signal whose KeyboardInterrupt may have been swallowed


def now() -> float:
    """``time.monotonic()``, or ``+inf`` once a stop was requested [s]."""
    return math.inf if _STOP.is_set() else time.monotonic()


def request_stop() -> None:
    """Make every deadline of the search pass now (safe from a signal handler)."""
    _STOP.set()


def clear_stop() -> None:
    """Forget a stop request (at the start of a new search)."""
    _STOP.clear()


def stop_requested() -> bool:
    """True after :func:`request_stop` until :func:`clear_stop`."""
    return _STOP.is_set()


def note_signal(name: str) -> None:
    """Remember a signal a handler turns into ``KeyboardInterrupt`` (safe from a handler).

    Python runs a signal handler in whatever frame is executing, a garbage-collector
    callback or a finalizer included, where the exception is printed as "ignored" and
    dropped: the signal would be lost. Remembered here, it is raised again at the next
    check (:func:`raise_pending_signal`, the stage checks before the search) or taken
    as the first signal by the next :func:`catch_signals` block.

    Args:
      name: the signal's name (``"SIGTERM"``).
    """
    _PENDING[:] = [name]


def _take_pending() -> str | None:
    return _PENDING.pop() if _PENDING else None


def raise_pending_signal() -> None:
    """Raise ``KeyboardInterrupt`` for a remembered signal (:func:`note_signal`), once."""
    if _take_pending() is not None:
        raise KeyboardInterrupt


@contextlib.contextmanager
def catch_signals(first=None, *, abort_on_second: bool = False):
    """Inside the block, SIGINT / SIGTERM are caught instead of ending the process.

    The first signal calls ``first(name)``; later ones are ignored, except that with
    ``abort_on_second`` a second SIGINT raises ``KeyboardInterrupt``. Off the main
    thread (where Python cannot install handlers) the block runs unguarded.

    Args:
      first: callable ``first(signal_name)`` told of the first signal, or None.
      abort_on_second: a second SIGINT aborts (``KeyboardInterrupt``).
    Yields:
      dict with key ``"signal"``: None, or the name of the first signal received.
    """
    state = {"signal": None}
    if threading.current_thread() is not threading.main_thread():
        yield state
        return

    def handler(signum, frame):
        if state["signal"] is not None:
            if abort_on_second and signum == signal.SIGINT:
                raise KeyboardInterrupt
            return
        state["signal"] = signal.Signals(signum).name
        if first is not None:
            first(state["signal"])

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    pending = _take_pending()  # a signal just before the block, possibly swallowed
    if pending is not None:
        handler(signal.Signals[pending], None)
    try:
        yield state
    finally:
        for s, h in old.items():
            signal.signal(s, h)
