"""The ``jaxspline`` command line.

Compiled programs are kept between runs in a persistent XLA cache (a run of the
default job compiles ~160 programs, 20-40 s on 2 cores, most of its first run):
``$JAXSPLINE_CACHE_DIR``, else ``$XDG_CACHE_HOME/jaxspline/xla`` (``~/.cache`` when
unset). ``JAXSPLINE_CACHE_DIR=off`` (or empty) disables it; a cache directory set for
JAX itself (``JAX_COMPILATION_CACHE_DIR``) is left alone.

This package: the parser, the sub-command registry and :func:`main`. Layer 7: may
import everything below (``kernels`` ... ``io``); only the ``aeossp`` adapter sits above,
and its sub-command is registered by name (``_SUBCOMMANDS``), not imported here. One
module per sub-command: ``plan`` (``jaxspline plan``), ``bound`` (``jaxspline bound``),
``view`` (``jaxspline view``). The entry point lives in this ``__init__`` so the console
script ``jaxspline = "jaxspline.cli:main"`` and ``python -m jaxspline.cli``
(``__main__``) keep working.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from pathlib import Path

__all__ = ["CACHE_ENV", "cache_dir", "main"]

CACHE_ENV = "JAXSPLINE_CACHE_DIR"
_CACHE_OFF = ("", "off", "0", "none")
# the command's help: the docstring up to the package notes
_DESCRIPTION = __doc__[: __doc__.index("\n\nThis package:")]


def cache_dir() -> Path | None:
    """The persistent compilation cache directory of the command (module docstring).

    Returns:
      Path, or None when disabled.
    """
    env = os.environ.get(CACHE_ENV)
    if env is not None:
        return None if env.strip().lower() in _CACHE_OFF else Path(env).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "jaxspline" / "xla"


def _enable_compile_cache() -> None:
    import jax

    if jax.config.jax_compilation_cache_dir:
        return
    path = cache_dir()
    if path is None:
        return
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:  # read-only home: run without the cache
        return
    jax.config.update("jax_compilation_cache_dir", str(path))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)


# Each module registers its own sub-commands with ``register(subparsers)``; the module
# sets ``func(args) -> int`` on its parsers. Imported lazily to keep start-up fast.
_SUBCOMMAND_MODULES = (
    "jaxspline.cli.plan",
    "jaxspline.cli.bound",
    "jaxspline.cli.view",
    "jaxspline.aeossp.cli",
    "jaxspline.regional.cli",
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``jaxspline`` command (sub-commands register here)."""
    import importlib

    parser = argparse.ArgumentParser(prog="jaxspline", description=_DESCRIPTION)
    sub = parser.add_subparsers(dest="command", required=True)
    for name in _SUBCOMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``jaxspline`` console script.

    Args:
      argv: command-line arguments without the program name; None: ``sys.argv[1:]``.
    Returns:
      int, the exit code.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    _enable_compile_cache()
    old_term = signal.getsignal(signal.SIGTERM)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _terminate)  # like Ctrl-C: clean-up runs
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        print(f"jaxspline: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(
            "jaxspline: interrupted (outputs are written atomically: none is partial)",
            file=sys.stderr,
        )
        return 130
    finally:
        if threading.current_thread() is threading.main_thread():
            # called as the process (argv None): the work is done, later signals only
            # race the exit; called from Python: hand the handler back
            signal.signal(signal.SIGTERM, signal.SIG_IGN if argv is None else old_term)
            if argv is None:
                signal.signal(signal.SIGINT, signal.SIG_IGN)


def _terminate(signum, frame):
    raise KeyboardInterrupt
