"""The memory guard: a scenario too big for the memory stops before a stage allocates it.

The stages before the search allocate in proportion to the scenario: the orbits per
satellite and ephemeris knot (``duration / geometry_step_s``), the windows' pre-screen
per target of a block and knot and per window (a sample of the targets' pre-screen,
:func:`jaxspline.geometry.windows.window_work`), the options' samples per candidate
start (``1 / time_step_s``) and geometry knot inside it (``1 / geometry_step_s``), the
near-pair store per pair of options closer than the always-feasible gap. Before each
of these stages :class:`MemoryGuard` compares an upper-ish estimate of the bytes it
will add (this module's functions, from the scenario's keys and what the earlier
stages found) with the memory the process may still take (:meth:`MemoryGuard.room`:
:data:`MEMORY_SHARE` of the system's ``MemAvailable``, within a cgroup's limit,
within ``--max-memory``), and raises :class:`MemoryLimitError` when it does not fit:
one line naming the stage, the keys that drive it with their values, the estimate,
what is available and the remedy.

The per-item constants were measured (peak RSS, ``/usr/bin/time -v``; the windows'
with ``tracemalloc``; docs/cli.md
*The memory limit*) and rounded up: the estimate is meant to stay above what a run
takes, so a run that fits is never stopped.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

__all__ = [
    "CANDIDATE_BYTES",
    "CELL_BYTES",
    "FINE_PAIR_BYTES",
    "GB",
    "KNOT_BYTES",
    "MB",
    "MEMORY_SHARE",
    "PAIR_BYTES",
    "SAMPLE_BYTES",
    "SORT_PAIR_BYTES",
    "STAGE_BYTES",
    "WINDOW_BYTES",
    "MemoryGuard",
    "MemoryLimitError",
    "available_bytes",
    "check_stage",
    "near_pair_counts",
    "option_bytes",
    "orbit_bytes",
    "pair_bytes",
    "rss_bytes",
    "window_bytes",
]

GB = float(1 << 30)
MB = float(1 << 20)
#: Share of the system's available memory a run may take (the rest: other processes,
#: the page cache, a forked bound worker's own pages).
MEMORY_SHARE = 0.8
#: [bytes] per satellite and ephemeris knot: orbit tables, the Sun, the shadow and the
#: windows' cone (measured ~280).
KNOT_BYTES = 400
#: [bytes] per (target, coarse knot) cell of the windows' largest block of targets: the
#: pre-screen's dot products and masks (:func:`jaxspline.geometry.windows.window_work`;
#: measured with the next, ~6).
CELL_BYTES = 16
#: [bytes] per (target, knot) pair the windows' largest block evaluates: the pairs'
#: indices, their sort and the exact geometry (measured ~100 per estimated pair).
FINE_PAIR_BYTES = 192
#: [bytes] per window: the windows and their sort.
WINDOW_BYTES = 128
#: [bytes] per sample of a checked candidate: its times, owner, aim law and geometry
#: (measured ~250).
SAMPLE_BYTES = 320
#: [bytes] per candidate option: its row, its states as an option and the search's
#: problem (~0.5 KB an option, docs/scale.md *Memory*).
CANDIDATE_BYTES = 1024
#: [bytes] per candidate near pair: the store (8), the bound's cost (4) and slack
#: (docs/scale.md *Memory*: 12 bytes a near pair).
PAIR_BYTES = 16
#: [bytes] per candidate near pair of the largest satellite: the sort of its pairs (32),
#: and the next satellite's streamed pairs (12) held while it sorts in the background.
SORT_PAIR_BYTES = 44
#: [bytes] every stage adds whatever its size: its compiled programs and work buffers
#: (the default job's stages each add 30-170 MB).
STAGE_BYTES = 256 << 20
_CGROUP = Path("/sys/fs/cgroup")
_Estimate = tuple[float, str, Callable[[float], str]]  # bytes, drivers, remedy(factor)


class MemoryLimitError(Exception):
    """A stage would need more memory than the process may take (a one-line message).

    Attributes:
      stage: the stage that was about to run (``"options"``, ...).
      need: its estimate [bytes].
      room: the memory available to it [bytes].
    """

    def __init__(self, msg: str, stage: str, need: float, room: float):
        super().__init__(msg)
        self.stage, self.need, self.room = stage, need, room


def _meminfo_available() -> float | None:
    """``MemAvailable`` of ``/proc/meminfo`` [bytes] (None where there is none)."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return float(line.split()[1]) * 1024.0
    except (OSError, ValueError, IndexError):
        return None
    return None


def _cgroup_available() -> float | None:
    """What the process's cgroup (v2) still allows [bytes] (None: no limit)."""
    try:
        limit = (_CGROUP / "memory.max").read_text().strip()
        if limit == "max":
            return None
        return float(limit) - float((_CGROUP / "memory.current").read_text())
    except (OSError, ValueError):
        return None


def available_bytes() -> float | None:
    """Memory the system can still give this process [bytes].

    Returns:
      float: the least of ``MemAvailable`` (``/proc/meminfo``) and the cgroup's
      ``memory.max - memory.current``; None where neither is known (no guard then).
    """
    known = [x for x in (_meminfo_available(), _cgroup_available()) if x is not None]
    return max(min(known), 0.0) if known else None


def rss_bytes() -> float:
    """This process's resident set size now [bytes].

    Returns:
      float (0 where unknown: no ``/proc/self/statm``).
    """
    try:
        pages = int(Path("/proc/self/statm").read_text().split()[1])
    except (OSError, ValueError, IndexError):
        return 0.0
    return float(pages * os.sysconf("SC_PAGE_SIZE"))


class MemoryGuard:
    """The memory the stages of one run may take, and the check before each.

    Args:
      max_bytes: what the whole process may hold [bytes] (``--max-memory``); None: no
        own limit.
      share: share of the system's available memory a stage may take.
      available: callable returning the system's available memory [bytes] or None
        (default :func:`available_bytes`; tests inject their own).

    Attributes:
      max_bytes, share: as given.
      estimates_mb: the estimate of every stage checked [MB], with the resident set when
        it was checked (``"<stage> at"``) (``plan.json``'s ``stats.memory_estimate_mb``).
    """

    def __init__(self, max_bytes=None, share=MEMORY_SHARE, available=available_bytes):
        self.max_bytes, self.share, self._available = max_bytes, float(share), available
        self.estimates_mb: dict[str, float] = {}

    def room(self) -> tuple[float, str]:
        """What the next stage may still allocate [bytes], and where the figure comes from.

        Returns:
          (bytes, text): ``inf`` and ``""`` when nothing is known.
        """
        room, said = math.inf, ""
        avail = self._available()
        if avail is not None:
            room = self.share * avail
            said = f"{100 * self.share:.0f} % of the {avail / GB:.1f} GB the system has available"
        if self.max_bytes is not None:
            own = self.max_bytes - rss_bytes()
            if own < room:
                room = max(own, 0.0)
                held = rss_bytes() / GB
                said = f"--max-memory {self.max_bytes / GB:g} GB less the {held:.2f} GB held"
        return room, said

    def check(self, stage: str, estimate) -> None:
        """Raise :class:`MemoryLimitError` when a stage's estimate does not fit in :meth:`room`.

        Args:
          stage: the stage about to run.
          estimate: ``(bytes, drivers, remedy)`` (:func:`orbit_bytes`, :func:`option_bytes`,
            :func:`pair_bytes`): the estimate [bytes], the keys and counts that drive it
            with their values, and ``remedy(factor)``, what to change to need ``factor``
            times less.
        Raises:
          MemoryLimitError: naming the stage, the drivers, the estimate, the room and
            the remedy.
        """
        need, drivers, remedy = estimate
        need += STAGE_BYTES
        self.estimates_mb[stage] = round(need / MB, 1)
        self.estimates_mb[f"{stage} at"] = round(rss_bytes() / MB, 1)
        room, said = self.room()
        if need <= room:
            return
        raise MemoryLimitError(
            f"stage {stage!r} would need ~{need / GB:.1f} GB ({drivers}) but "
            f"{room / GB:.1f} GB are available ({said}): {self._fix(need, room, remedy)}",
            stage,
            need,
            room,
        )

    def _fix(self, need: float, room: float, remedy) -> str:
        """The remedy: the scenario's (for the part of the estimate that scales with it),
        or more memory when even a tiny scenario would not fit (or ``--max-memory``)."""
        more = ""
        if self.max_bytes is not None:
            want = math.ceil(4.0 * (rss_bytes() + need) / GB) / 4.0
            more = f"give --max-memory {want:g} or more"
        if room <= STAGE_BYTES:  # not even a stage's programs fit: no step would help
            return more or "free memory (other processes hold it) and run again"
        fix = remedy((need - STAGE_BYTES) / (room - STAGE_BYTES))
        return f"{fix}; or {more}" if more else fix


def _coarser(step: float, factor: float, unit: float) -> float:
    """``step`` times ``factor`` rounded up to a whole multiple of ``unit`` [s]."""
    return math.ceil(step * factor / unit - 1e-9) * unit


def _steps(sc) -> str:
    pc = sc.planner
    return f"planner.time_step_s = {pc.time_step:g}, planner.geometry_step_s = {pc.geometry_step:g}"


def orbit_bytes(sc) -> _Estimate:
    """The orbits' estimate: :data:`KNOT_BYTES` per satellite and ephemeris knot.

    Args:
      sc: the scenario.
    Returns:
      (bytes, drivers, remedy(factor) -> str).
    """
    gstep = sc.planner.geometry_step
    knots = math.ceil(sc.duration / gstep) + 1
    n_sat = len(sc.satellites)
    drivers = (
        f"{n_sat} satellites x {knots:,} knots: duration_s = {sc.duration:g}, "
        f"planner.geometry_step_s = {gstep:g}"
    )

    def remedy(f):
        return (
            f"raise planner.geometry_step_s to >= {gstep * f:.3g} (and planner.time_step_s "
            "with it), or plan a shorter horizon or fewer satellites"
        )

    return float(KNOT_BYTES) * knots * n_sat, drivers, remedy


def window_bytes(sc, work) -> _Estimate:
    """The windows' estimate: :data:`CELL_BYTES` a pre-screen cell and
    :data:`FINE_PAIR_BYTES` a pair of the largest block, :data:`WINDOW_BYTES` a window.

    Args:
      sc: the scenario.
      work: :class:`jaxspline.geometry.windows.WindowWork` of the stage.
    Returns:
      (bytes, drivers, remedy(factor) -> str).
    """
    gstep = sc.planner.geometry_step
    drivers = (
        f"{len(sc.targets):,} targets, {len(sc.satellites)} satellites x {work.knots:,} knots, "
        f"up to {work.windows:,} windows; {_steps(sc)}"
    )

    def remedy(f):  # the blocks' work scales as 1 / geometry_step
        return (
            f"raise planner.geometry_step_s to >= {gstep * f:.3g} (and planner.time_step_s "
            "with it), or plan a shorter horizon, fewer targets or satellites"
        )

    block = float(CELL_BYTES) * work.cells + float(FINE_PAIR_BYTES) * work.pairs
    return block + float(WINDOW_BYTES) * work.windows, drivers, remedy


def option_bytes(sc, candidates: int, samples: int) -> _Estimate:
    """The options' estimate: :data:`CANDIDATE_BYTES` a candidate start plus
    :data:`SAMPLE_BYTES` a sample (:func:`jaxspline.planner.opportunities.option_counts`).

    Args:
      sc: the scenario.
      candidates: candidate options (upper bound).
      samples: their samples (upper bound).
    Returns:
      (bytes, drivers, remedy(factor) -> str).
    """
    pc = sc.planner
    drivers = f"{candidates:,} candidate options, {samples:,} samples; {_steps(sc)}"

    def remedy(f):  # candidates scale as 1 / time_step, samples as 1 / (time_step * geometry_step)
        return (
            f"raise planner.time_step_s to >= "
            f"{_coarser(pc.time_step, f, pc.geometry_step):.3g} (a multiple of "
            f"planner.geometry_step_s), or planner.geometry_step_s too, or plan fewer "
            "targets, satellites or a shorter horizon"
        )

    return float(CANDIDATE_BYTES) * candidates + float(SAMPLE_BYTES) * samples, drivers, remedy


def near_pair_counts(sat, t_start, t_end, reach) -> tuple[int, int]:
    """Upper bounds on the near pairs of the options: pairs ``i -> j`` of one satellite
    with ``t_end[i] <= t_start[j] <= t_end[i] + reach[sat]``.

    Args:
      sat: int [N], the options' satellites.
      t_start: float [N] [s].
      t_end: float [N] [s].
      reach: float [S], the longest gap a near pair spans per satellite [s].
    Returns:
      (all pairs, the largest satellite's pairs): int, int.
    """
    total = most = 0
    for k in np.unique(sat):
        ids = np.flatnonzero(sat == k)
        starts = np.sort(t_start[ids])
        ends = t_end[ids]
        lo = np.searchsorted(starts, ends - 1e-6, side="left")
        hi = np.searchsorted(starts, ends + float(reach[k]), side="right")
        n = int((hi - lo).sum())
        total, most = total + n, max(most, n)
    return total, most


def pair_bytes(sc, options, reach) -> _Estimate:
    """The screening's estimate: :data:`PAIR_BYTES` a candidate near pair plus
    :data:`SORT_PAIR_BYTES` a pair of the largest satellite (:func:`near_pair_counts`).

    Args:
      sc: the scenario.
      options: the options (:class:`jaxspline.screen.options.RouteOptions`: ``sat``,
        ``t_start``, ``t_end``).
      reach: float [S], the longest gap a near pair spans per satellite [s].
    Returns:
      (bytes, drivers, remedy(factor) -> str).
    """
    pc = sc.planner
    pairs, most = near_pair_counts(options.sat, options.t_start, options.t_end, reach)
    drivers = f"{options.sat.size:,} options, up to {pairs:,} near pairs; {_steps(sc)}"

    def remedy(f):  # pairs scale as 1 / time_step^2
        return (
            f"raise planner.time_step_s to >= "
            f"{_coarser(pc.time_step, math.sqrt(f), pc.geometry_step):.3g} (a multiple of "
            "planner.geometry_step_s), or plan fewer targets or a shorter horizon"
        )

    return float(PAIR_BYTES) * pairs + float(SORT_PAIR_BYTES) * most, drivers, remedy


def check_stage(memory: MemoryGuard | None, stage: str, estimate: Callable[[], _Estimate]):
    """``memory.check(stage, estimate())``; without a guard nothing, not even the estimate.

    Args:
      memory: the run's guard or None.
      stage: the stage about to run.
      estimate: callable returning the stage's estimate (:func:`orbit_bytes`, ...).
    Raises:
      MemoryLimitError: from :meth:`MemoryGuard.check`.
    """
    if memory is not None:
        memory.check(stage, estimate())
