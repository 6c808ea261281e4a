"""The coverage bound's child process (:func:`jaxspline.regional.solve.start_bound`) ends
with its parent, also when the parent is killed with SIGKILL (no clean-up runs).

A parent process starts the child as ``regional solve`` does, then is killed. The child's
program is replaced by one that only sleeps (a ``jaxspline`` package of a few lines put
first on the child's ``PYTHONPATH``), so the child would outlive its parent by a minute
unless it follows it; :func:`start_bound` itself runs unchanged.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

# the parent: the real package, then the fake one for its child
PARENT = textwrap.dedent(
    """
    import os, sys, time
    from jaxspline.regional.solve import start_bound
    os.environ["PYTHONPATH"] = sys.argv[1]
    proc, path = start_bound(None, 1.0, 60.0)
    print(proc.pid, flush=True)
    time.sleep(60)
    """
)
SLEEPER = "import time\ntime.sleep(60)\n"


def _gone(pid: int, wait_s: float) -> bool:
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


def test_the_bound_child_ends_when_its_parent_is_killed(tmp_path):
    fake = tmp_path / "fake"
    (fake / "jaxspline" / "search").mkdir(parents=True)
    (fake / "jaxspline" / "__init__.py").write_text("")
    (fake / "jaxspline" / "search" / "__init__.py").write_text("")
    (fake / "jaxspline" / "search" / "coverage_bound.py").write_text(SLEEPER)
    parent = subprocess.Popen(
        [sys.executable, "-c", PARENT, str(fake)],
        stdout=subprocess.PIPE,
        text=True,
        cwd=tmp_path,  # `python -m` looks in the working directory first
    )
    child = None
    try:
        child = int(parent.stdout.readline())
        time.sleep(1.5)  # the child runs its program: it sleeps
        assert not _gone(child, 0.0)
        parent.kill()
        parent.wait()
        assert _gone(child, 3.0), "the bound's child outlived its parent"
    finally:
        parent.kill()
        parent.wait()
        if child is not None and not _gone(child, 0.0):
            os.kill(child, signal.SIGKILL)
