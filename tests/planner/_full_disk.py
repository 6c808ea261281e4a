"""A real full disk for the tests that write: a small tmpfs, filled up (needs root).

``full_disk(folder)`` mounts a 64 KiB tmpfs on ``folder / "full"``, fills it with one
file until the kernel says ``ENOSPC`` and yields the mount point; it is unmounted after.
Where mounting is not allowed (not root, no tmpfs, a container without the capability)
the test is skipped, and the in-process tests with a simulated ``ENOSPC`` still run.
"""

from __future__ import annotations

import contextlib
import errno
import os
import subprocess

import pytest


@contextlib.contextmanager
def full_disk(folder):
    """Yield the path of a mounted tmpfs with no space left (module docstring)."""
    point = folder / "full"
    point.mkdir()
    cmd = ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(point)]
    try:
        done = subprocess.run(cmd, capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        done = None
    if done is None or done.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        fd = os.open(point / "filler", os.O_WRONLY | os.O_CREAT, 0o600)
        try:
            with contextlib.suppress(OSError):
                while True:
                    os.write(fd, b"\0" * 4096)
            with pytest.raises(OSError) as exc:
                os.write(fd, b"\0")
            assert exc.value.errno == errno.ENOSPC
        finally:
            os.close(fd)
        yield point
    finally:
        subprocess.run(["umount", str(point)], capture_output=True, timeout=30)
