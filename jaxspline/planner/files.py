"""Atomic file output: a crash or a full disk never leaves a half-written file behind.

Every output of jaxspline (plans, plots, benchmark reports, aeossp solutions) is
written to a temporary file in the destination directory and moved into place
with ``os.replace`` (atomic on POSIX). The result gets the permissions a plain
``open(path, "w")`` would give (``0o666`` minus the umask), not ``mkstemp``'s 0600.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "atomic_write_text", "refuse_overwrite"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def refuse_overwrite(path, force: bool) -> None:
    """Refuse to overwrite an existing file unless ``force``.

    Args:
      path: str or Path.
      force: allow overwriting.
    Raises:
      FileExistsError: naming ``path`` if it exists and ``force`` is false.
    """
    if not force and Path(path).exists():
        raise FileExistsError(f"{path} exists (use --force to overwrite)")


@contextlib.contextmanager
def atomic_path(path, suffix: str = ".tmp"):
    """Yield a temporary path next to ``path``; on success move it onto ``path`` atomically.

    On an exception the temporary file is removed and ``path`` is left untouched.
    Missing parent directories are created. An ``OSError`` that names no file (a full
    disk: ``ENOSPC`` while writing or closing) is raised again naming ``path``.

    Args:
      path: str or Path, the destination.
      suffix: suffix of the temporary name, so writers that pick a format by
        extension (matplotlib) see it.
    Yields:
      str, the temporary path to write.
    """
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    directory.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=directory)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except OSError as exc:
        if exc.filename is not None or exc.errno is None:
            raise
        raise type(exc)(exc.errno, exc.strerror, str(path)) from exc
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def atomic_write_text(path, text: str, *, force: bool = True) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically; refuse to overwrite unless ``force``.

    Args:
      path: str or Path.
      text: the content.
      force: allow overwriting.
    Returns:
      Path of the written file.
    Raises:
      FileExistsError: ``path`` exists and ``force`` is false.
    """
    refuse_overwrite(path, force)
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)
    return Path(path)
