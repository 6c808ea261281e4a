"""The command's persistent XLA compilation cache: on where its folder takes writes.

A cache folder that cannot take an entry (read-only, a full disk, a path through a
file) would make JAX warn once per compiled program, a few lines each, dozens of
times a run. So :func:`enable_cache` first writes a probe of :data:`PROBE_BYTES` there
(not synced: a start-up should cost little, and a file system reserves the blocks of a
write when it takes it): when that fails the cache stays off for the run, said in one
line. Should the disk fill up later, JAX's first warning about a cache entry becomes
one such line too, the cache is turned off and the later ones are not shown.
"""

from __future__ import annotations

import os
import re
import sys
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

__all__ = ["PROBE_BYTES", "enable_cache"]

#: Bytes written in the cache folder before it is used (a large entry's size).
PROBE_BYTES = 1 << 20
_JAX_WARNING = re.compile(r"Error (writing|reading) persistent compilation cache entry")


def enable_cache(path: Path) -> Callable[[], None]:
    """Use ``path`` as JAX's persistent compilation cache if it takes writes (module docstring).

    Args:
      path: the cache folder (made when missing).
    Returns:
      callable restoring what this call changed in :mod:`warnings` (call it when the
      command is done).
    """
    import jax

    try:
        path.mkdir(parents=True, exist_ok=True)
        _probe(path)
    except OSError as exc:
        _say_off(path, exc.strerror or str(exc))
        return _nothing
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)
    previous = warnings.showwarning
    said = []

    def show(message, category, filename, lineno, file=None, line=None):
        if not _JAX_WARNING.match(str(message)):
            return previous(message, category, filename, lineno, file, line)
        if not said:  # the first one: said in one line, and the cache is off
            said.append(message)
            _say_off(path, re.sub(r"^\[Errno \d+\] ", "", str(message).rsplit(": ", 1)[-1]))
            _turn_off()
        return None

    warnings.showwarning = show

    def restore() -> None:
        if warnings.showwarning is show:
            warnings.showwarning = previous

    return restore


def _nothing() -> None:
    """Nothing to restore."""


def _probe(path: Path) -> None:
    """Write :data:`PROBE_BYTES` in ``path``, then remove them (OSError if it fails)."""
    fd, name = tempfile.mkstemp(prefix=".probe-", dir=path)
    try:
        block = b"\0" * (1 << 16)
        for _ in range(PROBE_BYTES // len(block)):
            os.write(fd, block)
    finally:
        os.close(fd)
        os.unlink(name)


def _say_off(path: Path, why: str) -> None:
    print(
        f"jaxspline: note: the compilation cache is off for this run: cannot write {path} "
        f"({why}); programs are compiled anew",
        file=sys.stderr,
        flush=True,
    )


def _turn_off() -> None:
    """Stop JAX from using the cache for the rest of the process."""
    import jax

    jax.config.update("jax_enable_compilation_cache", False)
    try:  # JAX decides once whether the cache is used: make it decide again
        from jax._src import compilation_cache
    except ImportError:  # pragma: no cover - a JAX without it: the warnings stay hidden
        return
    compilation_cache.reset_cache()
