"""The Lagrangian bound iterated in a second process while the search runs.

The search proper (greedy, LNS) is single-threaded Python; the bound's per-satellite
DP is numpy. On a machine with a second core, :class:`BoundWorker` forks a process
that iterates :func:`jaxspline.search.lagrangian.upper_bound` over the same
:class:`Problem` until the search's deadline, and hands back its bound. The worker
relaxes the battery (the search's own Lagrangian phase prices its budgets): on the
unseen 12 x 12 h instance the priced bound converged 0.37 % lower (45,659 against
45,827) at 2.4 times the time an iteration (0.51 against 0.21 s). It credits a run of
consecutive options of one target once (``merge_repeats``, the strengthened relaxation of
:mod:`jaxspline.search.lagrangian`). The fork shares the problem's arrays copy-on-write
(nothing is pickled on the way in), and with them the DP's block layout when the parent
prepared it (``dp``: the search's own Lagrangian phase uses the same one, so it is
prepared once, before the fork); the child only runs numpy code (no JAX) and sends
three numbers back. Any bound is an upper bound of every plan, so the search reports the
smaller of its own and the worker's, and with an iteration cap the worker's result is a
function of the problem and the cap alone.

Plans (``plans=True``, the time-limited search): the worker's DP paths at its prices are
often much better starting points than the search's own plan on large instances (each
satellite's path packs its timeline as the prices advise). Every so often (at an
iteration that lowers the bound, from :data:`_PLAN_FIRST_IT` iterations on, once the
iterations since its last repair took :data:`_PLAN_RATIO` times that repair's CPU time)
the worker repairs that iteration's paths into a feasible plan
(:func:`jaxspline.search.lagrangian.plan_from_paths`: every insertion re-checked, battery
included) in a timeline of its own, sweeps it (:func:`jaxspline.search.sweeps`, while a
round pays :data:`_SWEEP_MIN_RATE`), and when the plan is worth more than the last one
it published, writes it into an array shared with the parent (no pipe: neither side
ever waits). The search adopts it when it beats its own
(:meth:`BoundWorker.plan`, polled by the LNS). What the search finds then depends on the
timing of the two processes, so an iteration-capped search (reproducible) never asks
for plans. Once the bound has converged, the worker's CPU would idle until the
deadline: the worker then improves its last repaired plan by an LNS of its own
(:meth:`_Repairs.walk`) and publishes it the same way, every :data:`_WALK_SLICE_S`
seconds in which it got better. Such a worker's bound has converged at the step factor
:data:`SEARCH_MU_MIN`, coarser than the bound alone's (:data:`BOUND_MU_MIN`), so that
the search gets the core sooner for a bound a little higher.

The child ignores SIGINT (a Ctrl-C reaches the whole process group; the parent decides)
and is terminated when the parent stops early or gives up waiting.
"""

from __future__ import annotations

import gc
import math
import multiprocessing as mp
import random
import signal
import time
import warnings

import numpy as np

from jaxspline.search.dp import dp_prepare
from jaxspline.search.lagrangian import BOUND_MU_MIN, BoundResult, plan_from_paths, upper_bound
from jaxspline.search.lns import greedy, greedy_order, lns
from jaxspline.search.lns_energy import EnergyRank
from jaxspline.search.memory import trim_heap
from jaxspline.search.orphans import die_with_parent
from jaxspline.search.problem import Problem
from jaxspline.search.status import BoundStatus
from jaxspline.search.sweep import sweeps
from jaxspline.search.timeline import Timeline

__all__ = ["SEARCH_MU_MIN", "BoundWorker"]

_GRACE_S = 30.0  # [s] the parent waits this long past the deadline for the last iteration
_PLAN_FIRST_IT = 4  # the worker's first plan repair follows this many iterations
_PLAN_RATIO = 3.0  # DP CPU time between two repairs, in units of the last repair's
#: Step factor at which the bound of a worker that also searches (``plans``) has
#: converged: its core then goes to the search (on the constellation day the bound is
#: 0.07 % above the one at :data:`BOUND_MU_MIN`, reached ~95 iterations, ~90 s, earlier).
SEARCH_MU_MIN = 1e-2
_WALK_SLICE_S = 2.0  # [s] the converged worker's LNS publishes its plan this often
_WALK_END_S = 0.5  # [s] its last publication comes this long before the deadline
_WALK_SEED = 7919  # its random stream (the search's LNS has its own)
_SWEEP_SEED = 104729  # the random stream of the sweeps after each repair
#: a repaired plan's sweeps (:func:`jaxspline.search.sweeps`) stop at a round that gains
#: less than this share of the plan's value per second: the LNS's pace from such a plan
#: on the constellation day (85,467 to 86,746 in 15 s); the first rounds there gain
#: 0.1-0.3 %/s
_SWEEP_MIN_RATE = 1e-3


class _Shared:
    """The plan the worker publishes: its options (padded with -1), the plan's value and
    a publication count, in shared memory made before the fork. ``size``: the most
    observations a plan can hold (one a point or strip target, every area option)."""

    def __init__(self, ctx, size: int):
        self.lock = ctx.Lock()
        self.plan = ctx.RawArray("l", max(1, size))
        self.meta = ctx.RawArray("d", 2)  # publications, value
        self.n = size

    def publish(self, value: float, plan) -> None:
        """Write a plan (child side)."""
        with self.lock:
            self.plan[: self.n] = list(plan) + [-1] * (self.n - len(plan))
            self.meta[1] = value
            self.meta[0] += 1.0

    def read(self, seen: int):
        """``(count, value, plan)`` when more than ``seen`` plans were published, else None."""
        if int(self.meta[0]) <= seen:  # a float's read is atomic enough for this test
            return None
        with self.lock:
            plan = [c for c in self.plan[: self.n] if c >= 0]
            return int(self.meta[0]), float(self.meta[1]), plan


class _Repairs:
    """Child side: repair the DP paths into plans now and then (module docstring)."""

    def __init__(self, pb: Problem, shared: _Shared, deadline: float, dp):
        self.pb, self.shared, self.deadline, self.dp = pb, shared, deadline, dp
        self.rng = random.Random(_SWEEP_SEED)
        self.tl = self.order = None
        self.best = -math.inf
        self.mark = time.process_time()  # CPU clock at the end of the last repair
        self.cost = 0.0  # CPU seconds of the last repair

    def __call__(self, it: int, paths, improved: bool) -> None:
        now = time.process_time()
        if not improved or it < _PLAN_FIRST_IT or now - self.mark < _PLAN_RATIO * self.cost:
            return
        if self.tl is None:
            self.tl = Timeline(self.pb)
            self.order = greedy_order(self.tl)
        plan_from_paths(self.tl, paths, self.order, self.deadline)
        sweeps(self.tl, self.dp, self.deadline, self.rng, min_rate=_SWEEP_MIN_RATE)
        if self.tl.value > self.best:
            self.best = self.tl.value
            self.shared.publish(self.tl.value, self.tl.plan())
        self.mark = time.process_time()
        self.cost = self.mark - now

    def start(self, order, above: float) -> None:
        """Build the greedy plan of ``order`` and publish it when worth more than ``above``
        (it is then the plan the walk starts from while no repair beat it)."""
        tl = Timeline(self.pb)
        greedy(tl, self.deadline, order)
        if tl.value > above:
            self.tl, self.order, self.best = tl, greedy_order(tl), tl.value
            self.shared.publish(tl.value, tl.plan())

    def walk(self) -> None:
        """After the bound converged: improve the last repaired plan (the greedy's when
        there was none) by an LNS of its own until the deadline, publishing it after every
        slice of :data:`_WALK_SLICE_S` seconds in which it beat the last publication."""
        if self.tl is None:
            self.tl = Timeline(self.pb)
            greedy(self.tl, self.deadline)
        rng = random.Random(_WALK_SEED)
        rank = EnergyRank(self.pb, self.tl.target_options)  # once, not every slice
        while (now := time.monotonic()) < self.deadline - _WALK_END_S:
            end = min(self.deadline - _WALK_END_S, now + _WALK_SLICE_S)
            lns(self.tl, end, rng, rank=rank)
            if self.tl.value > self.best:
                self.best = self.tl.value
                self.shared.publish(self.tl.value, self.tl.plan())


def _run(conn, pb: Problem, plan_value: float, deadline: float, max_iters, dp, shared, first):
    """Child: iterate the bound (publishing plans into ``shared`` unless None, the greedy
    plan of order ``first`` first unless None), send (bound, iterations, status,
    seconds)."""
    gc.disable()  # never finalize the parent's (JAX) objects in the child
    die_with_parent(mp.parent_process().pid)  # even when the parent is killed (SIGKILL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if dp is None:
        dp = dp_prepare(pb)
    hook = None if shared is None else _Repairs(pb, shared, deadline, dp)
    if hook is not None and first is not None:
        hook.start(first, plan_value)
    res = upper_bound(
        pb,
        plan_value,
        deadline,
        max_iters,
        energy=False,
        merge_repeats=True,
        dp=dp,
        on_paths=hook,
        mu_min=BOUND_MU_MIN if hook is None else SEARCH_MU_MIN,
    )
    conn.send((float(res.bound), int(res.iterations), res.status.value, float(res.seconds)))
    conn.close()
    if hook is not None and res.status == BoundStatus.CONVERGED:  # the core is free: search too
        hook.walk()


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
      plans: also repair the DP paths into plans now and then (module docstring) and
        publish them for :meth:`plan`.
      first: with ``plans``, a target order the child first builds a greedy plan in
        (:func:`jaxspline.search.greedy`), publishing it when it is worth more than
        ``plan_value``, before it iterates the bound (the search's second greedy start,
        by value per Wh, built on this core while the search's LNS runs); None: none.
    """

    def __init__(
        self,
        pb: Problem,
        plan_value: float,
        deadline: float,
        max_iters=None,
        dp=None,
        plans=False,
        first=None,
    ):
        ctx = mp.get_context("fork")
        self._conn, child = ctx.Pipe(duplex=False)
        size = pb.n_targets
        closed = pb.closed_options()
        if closed is not None:
            size += int(np.count_nonzero(closed))
        self._shared = _Shared(ctx, size) if plans else None
        self._seen = 0
        args = (child, pb, plan_value, deadline, max_iters, dp, self._shared, first)
        self._proc = ctx.Process(target=_run, args=args, daemon=True)
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

    def plan(self, above: float):
        """The worker's latest published plan when it is worth more than ``above``.

        Never waits; each published plan is handed out once at most.

        Args:
          above: the value to beat.
        Returns:
          ``(value, plan)`` (the plan's options, :meth:`Timeline.plan`) or None.
        """
        got = None if self._shared is None else self._shared.read(self._seen)
        if got is None:
            return None
        self._seen, value, assigned = got
        return (value, assigned) if value > above else None

    @property
    def plans(self) -> bool:
        """Whether the worker publishes plans (``plans`` of the constructor)."""
        return self._shared is not None

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
