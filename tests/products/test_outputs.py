"""The output set of ``jaxspline plan`` (:mod:`jaxspline.products.outputs`), without planning.

* checks before planning: empty path, a file on the way, the working directory, files
  that are not outputs, an earlier set without ``force``;
* publishing: a new directory appears whole; an earlier set is replaced whole (files
  of the old set that the new one lacks are gone), with the directory's mode kept;
* failures: an error while writing, or a failing probe (a full disk), leaves the
  previous set untouched and no staging directory, and removes the folders the run made;
* the lock: a second set on the same directory fails at once (also from another
  process, where the command exits 5), and works again once the first is closed;
  a killed run's staging directory is removed by the next run; the lock of a killed
  run that a child of it still holds is taken over, with a note naming it.
"""

from __future__ import annotations

import contextlib
import errno
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from test_cli_errors import SCENARIO  # the one-satellite, one-target scenario

from jaxspline.products import outputs as outputs_module
from jaxspline.products.outputs import (
    OutputBusyError,
    OutputError,
    OutputSet,
    is_plan_output,
)


def _write_set(folder, names=("plan.json", "plan.csv"), text="new"):
    for n in names:
        (folder / n).write_text(f"{text} {n}")


def _publish(outdir, names=("plan.json", "plan.csv"), text="new", force=False):
    with OutputSet(outdir, force=force) as out:
        _write_set(out.staging, names, text)
        out.publish()


def _hidden(parent):
    return sorted(p.name for p in parent.iterdir() if p.name.startswith("."))


def test_plan_output_names():
    for name in ("plan.json", "plan.html", "attitude.png", "attitude_sat-1.aem.xml",
                 ".plan.json.x8d2.tmp", ".attitude_a.aem.xml.q1.tmp"):  # fmt: skip
        assert is_plan_output(name), name
    for name in ("notes.txt", "plan.jsonx", "attitude_a.xml", ".bashrc", "plan"):
        assert not is_plan_output(name), name


@pytest.mark.parametrize("bad", ["", "   ", "a\x00b"])
def test_empty_or_nul_paths_are_refused(bad):
    with pytest.raises(ValueError, match=r"-o/--outdir: must not"):
        OutputSet(bad)


def test_checks_before_planning(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ValueError, match="is a file, not a directory"):
        OutputSet(tmp_path / "file" / "out").check()
    with pytest.raises(ValueError, match="is a file, not a directory"):
        OutputSet(tmp_path / "file").check()
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="working directory"):
        OutputSet(".").check()
    with pytest.raises(ValueError, match="working directory"):
        OutputSet(tmp_path.parent).check()
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    with pytest.raises(ValueError, match="not outputs of jaxspline plan.*'notes.txt'"):
        OutputSet(mine, force=True).check()
    old = tmp_path / "old"
    old.mkdir()
    (old / "plan.json").write_text("{}")
    with pytest.raises(FileExistsError, match=r"plan\.json.*--force"):
        OutputSet(old).check()
    OutputSet(old, force=True).check()
    OutputSet(tmp_path / "new" / "deeper").check()  # missing folders are fine
    assert not (tmp_path / "new").exists()  # check() has no side effects


def test_new_directory_appears_whole(tmp_path):
    out = tmp_path / "a" / "b" / "out"
    with OutputSet(out) as s:
        assert s.staging.parent == out.parent and not out.exists()
        assert (out.parent / ".out.lock").exists()
        _write_set(s.staging)
        assert not out.exists()  # nothing visible before publishing
        s.publish()
    assert sorted(p.name for p in out.iterdir()) == ["plan.csv", "plan.json"]
    assert _hidden(out.parent) == []  # staging and lock gone
    mode = out.stat().st_mode & 0o777
    assert mode == 0o777 & ~_umask()  # as a plain mkdir, not mkdtemp's 0700


def _umask():
    m = os.umask(0)
    os.umask(m)
    return m


def test_earlier_set_is_replaced_whole(tmp_path):
    out = tmp_path / "out"
    _publish(out, ("plan.json", "plan.csv", "slack.png"), "old")
    os.chmod(out, 0o750)
    with pytest.raises(FileExistsError):
        _publish(out)
    _publish(out, force=True)
    assert sorted(p.name for p in out.iterdir()) == ["plan.csv", "plan.json"]  # no slack.png
    assert (out / "plan.json").read_text() == "new plan.json"
    assert out.stat().st_mode & 0o777 == 0o750
    assert _hidden(tmp_path) == []


def test_swap_without_renameat2(tmp_path, monkeypatch):
    monkeypatch.setattr(outputs_module, "_renameat2", lambda: None)
    out = tmp_path / "out"
    _publish(out, text="old")
    _publish(out, force=True)
    assert (out / "plan.json").read_text() == "new plan.json"
    assert _hidden(tmp_path) == []


def test_error_while_writing_leaves_the_previous_set(tmp_path):
    out = tmp_path / "out"
    _publish(out, text="old")
    with pytest.raises(RuntimeError), OutputSet(out, force=True) as s:
        _write_set(s.staging, ("plan.json",))
        raise RuntimeError("the disk is full")
    assert sorted(p.name for p in out.iterdir()) == ["plan.csv", "plan.json"]
    assert (out / "plan.json").read_text() == "old plan.json"
    assert _hidden(tmp_path) == []


def test_full_disk_fails_before_planning(tmp_path, monkeypatch):
    def full(path):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr(outputs_module, "_probe", full)
    out = tmp_path / "new" / "out"
    with pytest.raises(OutputError, match="No space left on device"):
        OutputSet(out).open()
    assert not (tmp_path / "new").exists()  # the folders it made are gone again


def test_failed_publish_keeps_the_previous_set(tmp_path, monkeypatch):
    out = tmp_path / "out"
    _publish(out, text="old")

    def broken(new, target):
        raise OSError(errno.EIO, os.strerror(errno.EIO), str(target))

    monkeypatch.setattr(outputs_module, "_swap", broken)
    with pytest.raises(OutputError, match="cannot move the outputs"):
        _publish(out, force=True)
    assert (out / "plan.json").read_text() == "old plan.json"
    assert _hidden(tmp_path) == []


def test_a_second_set_on_the_same_directory_fails_at_once(tmp_path):
    out = tmp_path / "out"
    with OutputSet(out):
        t0 = time.monotonic()
        with pytest.raises(OutputBusyError, match="in use by another jaxspline run"):
            OutputSet(out).open()
        assert time.monotonic() - t0 < 1.0
    _publish(out)  # free again
    assert (out / "plan.json").exists()


def test_stale_staging_of_a_killed_run_is_removed(tmp_path):
    stale = tmp_path / ".out.k1ll3d.partial"
    stale.mkdir()
    (stale / "plan.json").write_text("half")
    other = tmp_path / ".other.k1ll3d.partial"  # another directory's: left alone
    other.mkdir()
    _publish(tmp_path / "out")
    assert _hidden(tmp_path) == [".other.k1ll3d.partial"]


HOLD = textwrap.dedent(
    """
    import sys, time
    from jaxspline.products.outputs import OutputSet
    with OutputSet(sys.argv[1]):
        print("locked", flush=True)
        time.sleep(120)
    """
)


def test_the_command_exits_5_while_another_process_holds_the_directory(tmp_path, capsys):
    from jaxspline.cli import EXIT_BUSY, main

    out = tmp_path / "out"
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert holder.stdout.readline().strip() == "locked"
        scen = tmp_path / "s.toml"
        scen.write_text(SCENARIO, encoding="utf-8")
        t0 = time.monotonic()
        assert main(["plan", str(scen), "-o", str(out), "--quiet"]) == EXIT_BUSY
        assert time.monotonic() - t0 < 30.0  # at once: no planning
        err = capsys.readouterr().err
        assert err.startswith("jaxspline: busy: -o/--outdir:") and "in use" in err, err
        assert "Traceback" not in err
    finally:
        holder.kill()
        holder.wait()


# a run whose child (forked while it held the lock) outlives it: the child keeps the lock
HOLD_WITH_CHILD = textwrap.dedent(
    """
    import os, sys, time
    from jaxspline.products.outputs import OutputSet
    with OutputSet(sys.argv[1]):
        child = os.fork()
        if child == 0:
            time.sleep(60)
            os._exit(0)
        print(os.getpid(), child, flush=True)
        time.sleep(60)
    """
)


def test_a_lock_whose_run_was_killed_is_taken_over_with_a_note(tmp_path, capsys):
    out = tmp_path / "out"
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLD_WITH_CHILD, str(out)], stdout=subprocess.PIPE, text=True
    )
    child = None
    try:
        pid, child = (int(x) for x in holder.stdout.readline().split())
        with pytest.raises(OutputBusyError, match=f"process {pid}"):  # it runs: busy
            OutputSet(out).open()
        holder.kill()  # SIGKILL: its child still holds the lock
        holder.wait()
        os.kill(child, 0)  # (it does)
        _publish(out)
        err = capsys.readouterr().err
        lock = tmp_path / ".out.lock"
        note = f"jaxspline: note: taking over the lock {lock} of process {pid}, which has ended"
        assert err == note + "\n"
        assert (out / "plan.json").exists()
    finally:
        holder.kill()
        holder.wait()
        if child is not None:
            with contextlib.suppress(ProcessLookupError):
                os.kill(child, signal.SIGKILL)
