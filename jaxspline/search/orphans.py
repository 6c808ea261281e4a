"""A child process ends with its parent: no worker outlives the command that started it.

A command's helper processes (the forked bound worker of :mod:`jaxspline.search.bound_worker`,
the bound of ``jaxspline bound`` run beside a plan) are stopped by their
parent when it ends normally, on an error or on Ctrl-C. A parent killed outright
(``SIGKILL``, the out-of-memory killer) runs no clean-up, so :func:`die_with_parent`
makes the child end by itself:

* on Linux the kernel sends the child ``SIGKILL`` once its parent ends
  (``prctl(PR_SET_PDEATHSIG)``; strictly, once the parent *thread* that started the child
  ends: start children from a thread that lives as long as the command, the main one);
* elsewhere (no ``prctl``) a daemon thread of the child checks every
  :data:`WATCH_S` seconds whether its parent changed (``os.getppid()``: a child whose
  parent ended is adopted by another process) and ends the process then.

Either way, a parent that ended before the call (between the fork and it) ends the child
at once. The function only calls what this module loaded at import, so it is safe as the
``preexec_fn`` of :class:`subprocess.Popen` (between fork and exec nothing may import).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import threading

__all__ = ["WATCH_S", "die_with_parent"]

#: [s] how often the fallback watch (no ``prctl``) checks the parent.
WATCH_S = 0.5
_PR_SET_PDEATHSIG = 1  # linux/prctl.h


def _load_prctl():
    """libc's ``prctl``, or None where there is none (not Linux)."""
    try:
        fn = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True).prctl
    except (OSError, AttributeError, TypeError):
        return None
    fn.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
    fn.restype = ctypes.c_int
    return fn


_PRCTL = _load_prctl()


def die_with_parent(parent: int, *, watch: bool = True) -> str:
    """Make the calling process (a child) end with its parent (module docstring).

    Call it in the child, first thing after the fork (``preexec_fn`` of
    :class:`subprocess.Popen`; the target of a forked ``multiprocessing`` process).

    Args:
      parent: the parent's pid, as the parent saw it before the fork (``os.getpid()``
        there): a parent already gone is told apart from a live one by it.
      watch: where ``prctl`` is missing, start the watch thread (False: nothing, e.g. in
        a ``preexec_fn``, whose threads do not survive the ``exec``).
    Returns:
      str, how the child follows its parent: ``"signal"`` (``PR_SET_PDEATHSIG``),
      ``"watch"`` (the thread) or ``"none"`` (neither: no ``prctl`` and ``watch`` false).
      When the parent has already ended the call does not return: the process ends.
    """
    how = "none"
    if _PRCTL is not None and _PRCTL(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0:
        how = "signal"
    elif watch:
        how = "watch"
        threading.Thread(target=_watch, args=(parent,), name="die-with-parent", daemon=True).start()
    if os.getppid() != parent:  # it ended before the signal was armed: nothing will come
        os.kill(os.getpid(), signal.SIGKILL)
    return how


def _watch(parent: int) -> None:
    """The fallback: end this process once its parent is no longer ``parent``."""
    stop = threading.Event()
    while not stop.wait(WATCH_S):
        if os.getppid() != parent:
            os.kill(os.getpid(), signal.SIGKILL)
