"""The Lagrangian bound iterated in a second process while the search runs.

The search proper (greedy, LNS) is single-threaded Python; the bound's per-satellite
DP is numpy. On a machine with a second core, :class:`BoundWorker` forks a process
that iterates :func:`jaxspline.search.lagrangian.upper_bound` over the same
:class:`Problem` until the search's deadline, and hands back its bound. The worker
relaxes the battery (the search's own Lagrangian phase prices its budgets): the
per-pair energy terms would be derived anew in every iteration, and the relaxed bound is
the looser one by little (docs/scale.md). It credits a run of consecutive options of
one target once (``merge_repeats``, the strengthened relaxation of
:mod:`jaxspline.search.lagrangian`). The fork shares the problem's arrays copy-on-write
(nothing is pickled on the way in), and with them the DP's block layout when the parent
prepared it (``dp``: the search's own Lagrangian phase uses the same one, so it is
prepared once, before the fork); the child only runs numpy code (no JAX) and sends
three numbers back. Any bound is an upper bound of every plan, so the search reports the
smaller of its own and the worker's; the plan itself is never touched, and with an
iteration cap the worker's result is a function of the problem and the cap alone.

The child ignores SIGINT (a Ctrl-C reaches the whole process group; the parent decides)
and is terminated when the parent stops early or gives up waiting.
"""

from __future__ import annotations

import gc
import math
import multiprocessing as mp
import signal
import time
import warnings

from jaxspline.search.lagrangian import BoundResult, upper_bound
from jaxspline.search.memory import trim_heap
from jaxspline.search.problem import Problem
from jaxspline.search.status import BoundStatus

__all__ = ["BoundWorker"]

_GRACE_S = 30.0  # [s] the parent waits this long past the deadline for the last iteration


def _run(conn, pb: Problem, plan_value: float, deadline: float, max_iters, dp):
    """Child: iterate the bound, send (bound, iterations, status, seconds)."""
    gc.disable()  # never finalize the parent's (JAX) objects in the child
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    res = upper_bound(pb, plan_value, deadline, max_iters, energy=False, merge_repeats=True, dp=dp)
    conn.send((float(res.bound), int(res.iterations), res.status.value, float(res.seconds)))
    conn.close()


class BoundWorker:
    """A forked process iterating the bound (see module docstring).

    Args:
      pb: Problem (shared with the child copy-on-write).
      plan_value: float, a value some plan reaches (sets the step size only; see
        :func:`upper_bound`).
      deadline: float, ``time.monotonic()`` value at which the child stops [s].
      max_iters: cap on its iterations (None: the deadline alone).
      dp: the problem's :func:`jaxspline.search.dp.dp_prepare` (shared like ``pb``;
        None: the child prepares it).
    """

    def __init__(self, pb: Problem, plan_value: float, deadline: float, max_iters=None, dp=None):
        ctx = mp.get_context("fork")
        self._conn, child = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(
            target=_run, args=(child, pb, plan_value, deadline, max_iters, dp), daemon=True
        )
        trim_heap()  # the child maps the parent's resident pages: no free ones among them
        with warnings.catch_warnings():  # JAX warns of any fork; the child runs no JAX
            warnings.filterwarnings("ignore", message=r"os\.fork\(\) was called")
            self._proc.start()
        child.close()
        self.deadline = deadline

    def result(self, wait: bool = True) -> BoundResult | None:
        """The worker's bound, or None when it failed or did not finish in time.

        Args:
          wait: wait for it (up to the deadline plus :data:`_GRACE_S`, without limit
            when the deadline is +inf, i.e. in iteration-capped runs); False: take
            it only if it is ready now.
        Returns:
          BoundResult (``best`` empty) or None; the process is gone afterwards.
        """
        if not wait:
            timeout = 0.0
        elif math.isinf(self.deadline):
            timeout = None
        else:
            timeout = max(0.0, self.deadline - time.monotonic()) + _GRACE_S
        out = None
        try:
            if self._conn.poll(timeout):
                bound, its, status, seconds = self._conn.recv()
                out = BoundResult([], bound, its, BoundStatus(status), seconds)
        except (EOFError, OSError):  # the child died: no bound from it
            out = None
        self.stop()
        return out

    @property
    def alive(self) -> bool:
        """Whether the child process still runs."""
        return self._proc.is_alive()

    def stop(self) -> None:
        """Terminate the child if it still runs and release the pipe."""
        if self._proc.is_alive():
            self._proc.terminate()
        self._proc.join(timeout=5.0)
        self._conn.close()
