"""A child ends with its parent (:func:`jaxspline.search.orphans.die_with_parent`), on real
processes: a parent killed with SIGKILL runs no clean-up, so only the child itself (the
kernel's parent-death signal, or its watch thread where there is none) can end it.

Each test starts a parent process that forks a child which calls the function and then
sleeps a minute, kills the parent with SIGKILL and waits a few seconds for the child to
be gone. Without the call the child would sleep on (the control case checks that).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

# the parent: forks a child that (unless told "none") follows it, prints the child's pid
PARENT = textwrap.dedent(
    """
    import os, sys, time
    from jaxspline.search import orphans
    how = sys.argv[1]
    parent = os.getpid()
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        if how == "watch":
            orphans._PRCTL = None  # as where prctl is missing
        got = orphans.die_with_parent(parent) if how != "none" else "none"
        os.write(w, (got + "\\n").encode())
        time.sleep(60)
        os._exit(0)
    os.close(w)
    print(pid, os.read(r, 64).decode().strip(), flush=True)
    time.sleep(60)
    """
)


def _gone(pid: int, wait_s: float) -> bool:
    """Whether process ``pid`` ended (or is a zombie) within ``wait_s`` seconds."""
    t_end = time.monotonic() + wait_s
    while time.monotonic() < t_end:
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except FileNotFoundError:
            return True
        if stat.rsplit(")", 1)[1].split()[0] in ("Z", "X"):
            return True
        time.sleep(0.05)
    return False


def _orphan_after_kill(how: str, wait_s: float) -> tuple[str, bool]:
    parent = subprocess.Popen(
        [sys.executable, "-c", PARENT, how], stdout=subprocess.PIPE, text=True
    )
    child = None
    try:
        pid, got = parent.stdout.readline().split()
        child = int(pid)
        parent.kill()  # SIGKILL: no clean-up in the parent
        parent.wait()
        return got, _gone(child, wait_s)
    finally:
        parent.kill()
        parent.wait()
        if child is not None and not _gone(child, 0.0):
            os.kill(child, signal.SIGKILL)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_a_child_ends_when_its_parent_is_killed():
    got, gone = _orphan_after_kill("signal", 3.0)
    assert got == "signal"
    assert gone, "the child outlived its parent"


def test_without_prctl_the_watch_thread_ends_the_child():
    got, gone = _orphan_after_kill("watch", 3.0)
    assert got == "watch"
    assert gone, "the child outlived its parent"


def test_a_child_that_does_not_follow_its_parent_outlives_it():
    # the control: the two tests above would fail without the call
    got, gone = _orphan_after_kill("none", 1.5)
    assert got == "none" and not gone


def test_a_parent_gone_before_the_call_ends_the_child_at_once():
    # a pid that is not this process's parent: it "ended" before the signal was armed
    code = "import os; from jaxspline.search.orphans import die_with_parent\n"
    code += "die_with_parent(os.getppid() + 1, watch=False); print('survived')"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == -signal.SIGKILL and "survived" not in out.stdout
