"""The heap trim hands freed pages back (Linux/glibc) and is harmless elsewhere."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from jaxspline.search.memory import trim_heap


def _rss_kib() -> int:
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) for line in fh if line.startswith("VmRSS:"))


def test_trim_heap_returns_a_bool():
    assert trim_heap() in (True, False)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc and /proc")
def test_trim_heap_gives_back_freed_heap_pages():
    # blocks under glibc's mmap threshold come from the heap; freed, they stay resident
    blocks = [np.ones(1 << 13) for _ in range(1600)]  # 64 KiB each, 100 MiB in all
    keep = blocks[-1]  # the heap's top stays in use: no automatic trim at the top
    del blocks
    before = _rss_kib()
    assert trim_heap()
    assert keep.sum() == keep.size
    assert _rss_kib() < before - 50 * 1024  # most of the 100 MiB went back
