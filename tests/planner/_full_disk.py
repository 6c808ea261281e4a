"""A real full (or read-only) disk for the tests that write: a small tmpfs (needs root).

``full_disk(folder)`` mounts a 64 KiB tmpfs on ``folder / "full"``, fills it with one
file until the kernel says ``ENOSPC`` and yields the mount point; it is unmounted after.
``full_disk(folder, read_only=True)`` mounts it read-only instead (``EROFS``, which root
cannot write either, unlike a folder without write permission).
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
def full_disk(folder, read_only: bool = False):
    """Yield the path of a mounted tmpfs with no space left, or read-only (module docstring)."""
    point = folder / ("read_only" if read_only else "full")
    point.mkdir()
    opts = "ro,size=64k" if read_only else "size=64k"
    cmd = ["mount", "-t", "tmpfs", "-o", opts, "tmpfs", str(point)]
    try:
        done = subprocess.run(cmd, capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        done = None
    if done is None or done.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        if read_only:
            yield point
            return
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
