"""The output set of ``jaxspline plan``: checked before planning, written whole, published at once.

A plan's files (``plan.json``, ``plan.csv``, ``plan.czml``, figures, page, AEM files)
are one set: a reader must never see files of two runs side by side, nor half a set.
:class:`OutputSet` makes that so:

1. **Before planning** (:meth:`OutputSet.check` without side effects, then
   :meth:`OutputSet.open`): the output directory is a usable path (not empty, not a
   file, not the working directory or one holding it, not holding files other than
   plan outputs, no earlier set unless ``force``); a lock is taken on it
   (``.<name>.lock`` beside it, ``flock``, holding the pid of its run): a second run on
   the same directory fails at once with :class:`OutputBusyError`, unless the pid it
   holds has ended (a child it left behind holds the lock): the lock is then taken over,
   with a note on stderr naming the lock file and the pid; a staging directory
   ``.<name>.<random>.partial`` is created beside it (missing parents are created, and
   removed again on failure) and a probe of :data:`PROBE_BYTES` is written and synced
   there, so a read-only or full disk fails before any work with :class:`OutputError`.
2. **Writing**: every file goes into the staging directory
   (:func:`write_plan_outputs`); an ``OSError`` becomes :class:`OutputError` naming
   the file.
3. **Publishing** (:meth:`OutputSet.publish`): the staging directory replaces the
   output directory in one ``renameat2(RENAME_EXCHANGE)`` (Linux; elsewhere two
   renames, between which the directory is briefly absent), and the previous set is
   removed. A failure at any step leaves the previous set or none, never a mix;
   the staging directory is removed.

Staging and previous-set directories left by a killed run (``SIGKILL``) are removed by
the next run on the same directory, under its lock.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import errno
import fcntl
import fnmatch
import os
import shutil
import stat
import sys
import tempfile
import time
from pathlib import Path

from jaxspline.products.plan_html import HTML_FILE

__all__ = [
    "ATTITUDE_FIGURE",
    "OUTPUT_FILES",
    "PROBE_BYTES",
    "OutputBusyError",
    "OutputError",
    "OutputSet",
    "is_plan_output",
    "rewrite_plan_json",
    "write_plan_outputs",
]

OUTPUT_FILES = (
    "plan.json",
    "plan.csv",
    "plan.czml",
    "ground_track.png",
    "timeline.png",
    "slack.png",
)
ATTITUDE_FIGURE = "attitude.png"  # with --aem (the default)
_AEM_PATTERN = "attitude_*.aem.xml"
PROBE_BYTES = 1 << 20  # written and synced in the staging directory before planning
_PARTIAL = ".partial"  # suffix of staging directories
_OLD = ".old"  # suffix of a previous set being removed
_RENAME_EXCHANGE = 2  # renameat2 flag (linux/fs.h)
_AT_FDCWD = -100
_LOCK_TRIES = 5


class OutputError(Exception):
    """The output set cannot be prepared, written or published (a one-line message)."""


class OutputBusyError(OutputError):
    """Another run holds the lock of the output directory."""


def is_plan_output(name: str) -> bool:
    """Whether ``name`` is a file ``jaxspline plan`` writes (or a temporary of one).

    Args:
      name: a file name (no directory).
    Returns:
      bool.
    """
    known = (*OUTPUT_FILES, ATTITUDE_FIGURE, HTML_FILE)
    base = name[1:] if name.startswith(".") else name  # ".plan.json.x8d.tmp"
    return (
        name in known
        or fnmatch.fnmatchcase(name, _AEM_PATTERN)
        or (name != base and any(base.startswith(k + ".") for k in known))
        or (name != base and fnmatch.fnmatchcase(base, _AEM_PATTERN + ".*"))
    )


def _fail(what: str, exc: OSError) -> OutputError:
    why = exc.strerror or str(exc)
    return OutputError(f"{what}: {why}" + (f" ({exc.filename})" if exc.filename else ""))


class OutputSet:
    """The output directory of one run (module docstring: check, open, write, publish).

    Args:
      outdir: str or Path of the output directory (as given by the user).
      force: replace an earlier set in the directory.
      flag: the option's name in messages (``-o/--outdir``).

    Attributes:
      outdir: Path as given.
      target: the directory itself (symlinks resolved).
      staging: Path of the staging directory (after :meth:`open`), None before.
    """

    def __init__(self, outdir, *, force: bool = False, flag: str = "-o/--outdir"):
        self.flag = flag
        if not isinstance(outdir, str | os.PathLike) or not os.fspath(outdir).strip():
            raise ValueError(f"{flag}: must not be empty, got {outdir!r}")
        if "\x00" in os.fspath(outdir):
            raise ValueError(f"{flag}: must not contain a NUL character, got {outdir!r}")
        self.outdir = Path(outdir)
        self.target = Path(os.path.realpath(self.outdir))
        self.force = force
        self.staging = None
        self._lock_fd = None
        self._made: list[Path] = []  # parent folders this run created

    # --- before planning ---

    def check(self) -> None:
        """The checks without side effects (ValueError / FileExistsError naming the option).

        Raises:
          ValueError: not a usable directory (a file, the working directory, a
            directory with files that are not plan outputs).
          FileExistsError: an earlier set is there and ``force`` is false.
        """
        t, f = self.target, self.flag
        if t.parent == t:
            raise ValueError(f"{f}: {self.outdir} is the root directory")
        cwd = Path(os.path.realpath(os.getcwd()))
        if t == cwd or t in cwd.parents:
            raise ValueError(
                f"{f}: {self.outdir} is the working directory or holds it; the outputs "
                "replace the directory as one set: give a new or an output directory"
            )
        for p in (t, *t.parents):
            if p.exists() and not p.is_dir():
                raise ValueError(f"{f}: {p} is a file, not a directory")
        if not t.is_dir():
            return
        entries = sorted(os.listdir(t))
        foreign = [n for n in entries if not is_plan_output(n)]
        if foreign:
            raise ValueError(
                f"{f}: {self.outdir} holds files that are not outputs of jaxspline plan "
                f"({', '.join(repr(n) for n in foreign[:3])}{', ...' * (len(foreign) > 3)}); "
                "the outputs replace the directory as one set: give a new or an empty directory"
            )
        entries.sort(key=lambda n: (n not in OUTPUT_FILES, n))  # plan.json first
        if entries and not self.force:
            raise FileExistsError(
                f"{self.outdir}/ holds the outputs of an earlier run ({', '.join(entries[:4])}"
                f"{', ...' * (len(entries) > 4)}); use --force to replace them"
            )

    def open(self) -> OutputSet:
        """Lock the directory, create the staging directory and write the probe.

        Returns:
          self.
        Raises:
          OutputBusyError: another run holds the lock.
          OutputError: the folders cannot be created or written (read-only, full disk).
        """
        self.check()
        try:
            self._make_parents()
            self._lock()
            self.check()  # again, under the lock
            self._remove_stale()
            name, parent = self.target.name, self.target.parent
            self.staging = Path(tempfile.mkdtemp(prefix=f".{name}.", suffix=_PARTIAL, dir=parent))
            _probe(self.staging / ".probe")
        except OSError as exc:
            self.close()
            raise _fail(f"{self.flag}: cannot write beside {self.outdir}", exc) from None
        except BaseException:
            self.close()
            raise
        return self

    def _make_parents(self) -> None:
        missing = [p for p in reversed(self.target.parents) if not p.exists()]
        for p in missing:
            try:
                p.mkdir()
            except FileExistsError:  # made by someone else meanwhile: not ours to remove
                continue
            self._made.append(p)

    def _lock(self) -> None:
        path = self.target.parent / f".{self.target.name}.lock"
        for _ in range(_LOCK_TRIES):
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder, ino = _lock_holder(fd), os.fstat(fd).st_ino
                os.close(fd)
                if holder is not None and not _alive(holder):  # held by an orphan of it
                    _take_over(path, ino, holder)
                    continue
                raise OutputBusyError(
                    f"{self.flag}: {self.outdir} is in use by another jaxspline run (lock "
                    f"{path}{f', process {holder}' if holder else ''}); wait for it to "
                    "finish or choose another directory"
                ) from None
            try:  # the file may have been removed by its last holder meanwhile
                same = os.stat(path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                self._lock_fd, self._lock_path = fd, path
                _write_holder(fd)
                return
            os.close(fd)
        raise OutputBusyError(f"{self.flag}: could not lock {path} (it keeps being replaced)")

    def _remove_stale(self) -> None:
        """Staging and previous-set folders of this directory left by killed runs."""
        prefix = f".{self.target.name}."
        for entry in os.scandir(self.target.parent):
            stale = entry.name.endswith((_PARTIAL, _OLD)) and entry.name.startswith(prefix)
            if stale and entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)

    # --- publishing, clean-up ---

    def publish(self) -> Path:
        """Move the staging directory into place as one set; the previous set is removed.

        Returns:
          Path of the output directory (as given).
        Raises:
          OutputError: the rename failed (the previous set is left in place).
        """
        t, staging = self.target, self.staging
        try:
            mode = stat.S_IMODE(os.stat(t).st_mode) if t.is_dir() else 0o777 & ~_umask()
            os.chmod(staging, mode)
            _fsync_dir(staging)
            if t.is_dir():
                old = _swap(staging, t)
                shutil.rmtree(old, ignore_errors=True)
            else:
                os.rename(staging, t)
            _fsync_dir(t.parent)
        except OSError as exc:
            raise _fail(f"{self.flag}: cannot move the outputs into {self.outdir}", exc) from None
        self.staging = None
        self._made = []
        return self.outdir

    def close(self) -> None:
        """Remove the staging directory (if not published) and the folders this run made,
        and release the lock."""
        if self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)
            self.staging = None
        if self._lock_fd is not None:
            with contextlib.suppress(OSError):
                os.unlink(self._lock_path)  # before unlocking: see _lock
            os.close(self._lock_fd)
            self._lock_fd = None
        for p in reversed(self._made):
            with contextlib.suppress(OSError):
                p.rmdir()  # only when still empty
        self._made = []

    def __enter__(self) -> OutputSet:
        return self.open()

    def __exit__(self, *exc) -> None:
        self.close()


def _lock_holder(fd: int) -> int | None:
    """The pid written in a lock file (:func:`_write_holder`), None when there is none."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        return None
    return int(text) if text.isdigit() and int(text) > 0 else None


def _write_holder(fd: int) -> None:
    """Write this process's pid into the lock file it holds (best effort)."""
    with contextlib.suppress(OSError):
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, ended and not yet reaped, does not)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's: it runs
        return True
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state not in ("Z", "X")


def _take_over(path: Path, ino: int, pid: int) -> None:
    """Remove the lock file (inode ``ino``) of process ``pid``, which ended: whatever still
    holds it (a child it left behind) no longer guards a run. Says so on stderr."""
    print(
        f"jaxspline: note: taking over the lock {path} of process {pid}, which has ended",
        file=sys.stderr,
        flush=True,
    )
    with contextlib.suppress(FileNotFoundError):
        if os.stat(path).st_ino == ino:  # not a lock another run has made since
            os.unlink(path)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _probe(path: Path) -> None:
    """Write and sync :data:`PROBE_BYTES` at ``path``, then remove it (OSError if it fails)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        block = b"\0" * (1 << 16)
        for _ in range(PROBE_BYTES // len(block)):
            os.write(fd, block)
        os.fsync(fd)
    finally:
        os.close(fd)
        os.unlink(path)


def _fsync_dir(path: Path) -> None:
    with contextlib.suppress(OSError):  # not every file system syncs directories
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _renameat2():
    name = ctypes.util.find_library("c")
    try:
        fn = ctypes.CDLL(name, use_errno=True).renameat2
    except (OSError, AttributeError, TypeError):
        return None
    fn.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint]
    return fn


def _swap(new: Path, target: Path) -> Path:
    """Put ``new`` at ``target`` (an existing directory) and return where the old one is."""
    fn = _renameat2()
    if fn is not None:
        res = fn(_AT_FDCWD, os.fsencode(new), _AT_FDCWD, os.fsencode(target), _RENAME_EXCHANGE)
        if res == 0:
            return new  # it holds the previous set now
        err = ctypes.get_errno()
        if err not in (errno.EINVAL, errno.ENOSYS, errno.ENOTSUP):
            raise OSError(err, os.strerror(err), str(target))
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=_OLD, dir=target.parent))
    os.rmdir(old)
    os.rename(target, old)  # the directory is absent until the next line
    try:
        os.rename(new, target)
    except OSError:
        os.rename(old, target)  # put the previous set back
        raise
    return old


def write_plan_outputs(
    result, folder, *, plots=True, aem=True, aem_step=10.0, html=True, deadline=None
):
    """Write the files of a plan into ``folder`` (the staging directory of an :class:`OutputSet`).

    Adds the time of the attitude history to ``result.timings``. Given a
    ``deadline``, the optional products (:data:`jaxspline.products.output_budget.PRODUCTS`)
    are written only while their estimate fits before its limit; each one left out
    is recorded (``result.report["time_limit"]["skipped"]``). ``plan.json`` and
    ``plan.csv`` are always written, ``plan.json`` last (it records what was left out).

    Args:
      result: :class:`jaxspline.planner.result.PlanResult`.
      folder: Path, an existing empty directory.
      plots: the PNG figures.
      aem: one CCSDS AEM per satellite (sampled every ``aem_step`` [s]) and attitude.png.
      aem_step: AEM sample step [s].
      html: the web page ``plan.html``.
      deadline: optional :class:`jaxspline.planner.deadline.StageDeadline` of the run.
    Returns:
      ``(page size [bytes], seconds)`` of the page, or None without it.
    Raises:
      OutputError: a file could not be written (naming it; the folder is left as is).
    """
    doing = []  # the product being written, for a message (ENOSPC names no file)
    try:
        return _write_all(result, Path(folder), plots, aem, aem_step, html, deadline, doing)
    except OSError as exc:
        what = doing[-1] if doing and not exc.filename else "the outputs"
        raise _fail(f"cannot write {what}", exc) from None


def _write_all(result, out: Path, plots, aem, aem_step, html, deadline, doing: list):
    from jaxspline.products.plan_view import view_data

    fits = _fits(result, deadline, plots=plots, html=html, aem=aem, aem_step=aem_step)
    view = {"view": view_data(result)}  # what plan.html draws: `jaxspline view` rebuilds it
    doing.append("plan.csv")
    result.to_csv(out / "plan.csv", force=True)
    doing.append(HTML_FILE)
    page = _page(result, out, view) if fits("plan.html") else None
    if fits("plan.czml"):
        from jaxspline.products.czml import write_czml

        doing.append("plan.czml")
        write_czml(result, out / "plan.czml", force=True)
    doing.append("the AEM files")
    attitude = _aems(result, out, aem_step) if fits("AEM files") else None
    if fits("figures"):
        doing.append("the figures")
        _plots(result, attitude, out, deadline if aem else None)
    if deadline is not None:
        result.report["time_limit"] = deadline.record()
    doing.append("plan.json")
    result.to_json(out / "plan.json", force=True, extra=view)
    return page


def _fits(result, deadline, **asked):
    """``fits(product) -> bool``: asked for and (given a ``deadline``) its estimate fits
    before the limit; a product that does not is recorded as skipped."""
    from jaxspline.products.output_budget import REMEDIES, output_seconds

    cost = output_seconds(result.scenario, **asked)

    def fits(name: str) -> bool:
        if name not in cost:
            return False
        if deadline is None or deadline.fits(cost[name]):
            return True
        deadline.skip("outputs", name, REMEDIES[name])
        return False

    return fits


def _page(result, out: Path, view):
    """plan.html; returns ``(size [bytes], seconds)``."""
    from jaxspline.products.plan_html import write_plan_html

    t0 = time.monotonic()
    path = write_plan_html(result.to_dict(extra=view), out / HTML_FILE, force=True)
    return path.stat().st_size, time.monotonic() - t0


def _aems(result, out: Path, aem_step: float):
    """The attitude history and one AEM file per satellite; returns the history."""
    from jaxspline.products.aem import write_aems
    from jaxspline.products.attitude_history import attitude_history

    t0 = time.monotonic()
    attitude = attitude_history(result, aem_step)
    write_aems(result, attitude, out, force=True)
    result.timings["attitude"] = round(time.monotonic() - t0, 3)
    return attitude


def _plots(result, attitude, out: Path, deadline) -> None:
    """The PNG figures; attitude.png only with an attitude history (``deadline``: the
    run's StageDeadline when the AEM files were asked for, to record its absence)."""
    from jaxspline.products.plot_plan import (
        plot_plan_ground_tracks,
        plot_plan_slack,
        plot_plan_timeline,
    )

    plot_plan_ground_tracks(result, out / "ground_track.png")
    plot_plan_timeline(result, out / "timeline.png")
    plot_plan_slack(result, out / "slack.png")
    if attitude is not None:
        from jaxspline.products.plot_attitude import plot_attitude_profile

        plot_attitude_profile(result, attitude, out / ATTITUDE_FIGURE)
    elif deadline is not None:  # the AEM files (and their attitude history) were left out
        deadline.skip("outputs", ATTITUDE_FIGURE, "comes with the AEM files")


def rewrite_plan_json(result, folder) -> None:
    """Write ``plan.json`` of ``folder`` again from ``result`` (e.g. after an interrupt was
    recorded in its report), keeping its ``"view"`` section.

    Args:
      result: PlanResult.
      folder: Path of a written output set.
    """
    import json

    path = Path(folder) / "plan.json"
    view = json.loads(path.read_text(encoding="utf-8")).get("view")
    result.to_json(path, force=True, extra=None if view is None else {"view": view})
