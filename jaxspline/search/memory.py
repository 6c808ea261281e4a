"""Process memory: hand freed heap pages back to the OS.

numpy takes the buffers of its arrays from the C heap (glibc ``malloc``). Past the first
freed large block, glibc serves blocks up to 32 MB from its heap instead of fresh
mappings, and pages freed there stay in the process until the heap is trimmed: after
the pair screen, the process held ~365 MB of such free pages on a 12-satellite, 12 h,
20,000-target scenario (docs/scale.md *Memory*). :func:`trim_heap` returns them, so
the resident set is what the process holds, and a forked child (the bound worker)
starts with no free pages mapped. It changes no value anywhere; on a C library without
``malloc_trim`` it does nothing.
"""

from __future__ import annotations

import ctypes
import functools

__all__ = ["trim_heap"]


@functools.cache
def _malloc_trim():
    """The C library's ``malloc_trim`` (None where there is none)."""
    try:
        fn = ctypes.CDLL(None).malloc_trim  # the symbols of the running process
    except (OSError, AttributeError, TypeError):
        return None
    fn.argtypes, fn.restype = [ctypes.c_size_t], ctypes.c_int
    return fn


def trim_heap() -> bool:
    """Return the heap's free pages to the OS (glibc ``malloc_trim(0)``).

    Returns:
      bool, whether the C library released any memory (False without ``malloc_trim``).
    """
    fn = _malloc_trim()
    return bool(fn(0)) if fn is not None else False
