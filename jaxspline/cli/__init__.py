"""The ``jaxspline`` command line.

Compiled programs are kept between runs in a persistent XLA cache (a run of the
default job compiles ~160 programs, 20-40 s on 2 cores, most of its first run):
``$JAXSPLINE_CACHE_DIR``, else ``$XDG_CACHE_HOME/jaxspline/xla`` (``~/.cache`` when
unset). ``JAXSPLINE_CACHE_DIR=off`` (or empty) disables it; a cache directory set for
JAX itself (``JAX_COMPILATION_CACHE_DIR``) is left alone. A folder that cannot be
written (read-only, a full disk) leaves the cache off for the run, said in one line
(:mod:`jaxspline.cli.compile_cache`).

Exit codes (every command): 0 done; 1 the plan or solution failed its check; 2 bad
input (a scenario, case or plan file, a flag; nothing was planned or written); 3 the
scenario is too big for its limits: the time limit ran out before the search could
start, or a stage would need more memory than the run may take (the message estimates
the time or memory needed); 4 an output could not be written (read-only or full disk,
a path that is a file; the previous outputs are left as they were); 5 the output
directory is in use by another run; 70 an internal error (a bug: run again with
``--debug`` for the traceback); 130 interrupted (Ctrl-C or SIGTERM). No Python
traceback reaches the terminal without ``--debug``.

This package: the parser, the sub-command registry, the exit codes and :func:`main`.
Layer 8: may import everything below (``kernels`` ... ``products``); only the
``aeossp`` adapter sits above, and its sub-command is registered by name
(``_SUBCOMMAND_MODULES``), not imported here. One module per sub-command: ``plan``
(``jaxspline plan``), ``bound`` (``jaxspline bound``), ``view`` (``jaxspline view``);
``flags`` checks the flags; ``case_commands`` is what the benchmark adapters' commands
share. The entry point lives in this ``__init__`` so the console
script ``jaxspline = "jaxspline.cli:main"`` and ``python -m jaxspline.cli``
(``__main__``) keep working.
"""

from __future__ import annotations

import argparse
import functools
import os
import re
import signal
import sys
import threading
import time
import traceback
from pathlib import Path

from jaxspline.cli.startup import EXIT_INTERRUPTED  # Ctrl-C / SIGTERM

__all__ = [
    "CACHE_ENV",
    "EXIT_BAD_INPUT",
    "EXIT_BUSY",
    "EXIT_CHECK_FAILED",
    "EXIT_INTERNAL",
    "EXIT_INTERRUPTED",
    "EXIT_OK",
    "EXIT_TIME_LIMIT",
    "EXIT_WRITE",
    "build_parser",
    "OneLineParser",
    "cache_dir",
    "command_of",
    "end_process",
    "main",
    "one_line",
]

CACHE_ENV = "JAXSPLINE_CACHE_DIR"
_CACHE_OFF = ("", "off", "0", "none")
# the command's help: the docstring up to the package notes
_DESCRIPTION = __doc__[: __doc__.index("\n\nExit codes")]

EXIT_OK = 0
EXIT_CHECK_FAILED = 1  # the plan (aeossp: the solution) failed its check
EXIT_BAD_INPUT = 2  # a bad file or flag (argparse uses 2 too)
EXIT_TIME_LIMIT = 3  # the time limit ran out before the search
EXIT_WRITE = 4  # an output could not be written
EXIT_BUSY = 5  # the output directory is locked by another run
EXIT_INTERNAL = 70  # an unexpected error (EX_SOFTWARE of sysexits.h)


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


def _enable_compile_cache():
    """The command's cache (:func:`cache_dir`, :mod:`jaxspline.cli.compile_cache`) unless
    JAX has one set; returns what restores the warnings hook afterwards."""
    import jax

    from jaxspline.cli.compile_cache import enable_cache

    path = cache_dir()
    if jax.config.jax_compilation_cache_dir or path is None:
        return _nothing
    return enable_cache(path)


def _nothing() -> None:
    """Nothing to restore."""


# Each module registers its own sub-command (by name, the key) with ``register(subparsers)``;
# the module sets ``func(args) -> int`` on its parsers. Imported lazily, and only the one
# the command line names: the benchmark adapters' packages (YAML, SGP4) cost ~0.3 s of a
# start, which a plain ``jaxspline plan`` (a rejected scenario above all) does not pay.
_SUBCOMMAND_MODULES = {
    "plan": "jaxspline.cli.plan",
    "bound": "jaxspline.cli.bound",
    "view": "jaxspline.cli.view",
    "aeossp": "jaxspline.aeossp.cli",
    "regional": "jaxspline.regional.cli",
    "stereo": "jaxspline.stereo.cli",
}
_HELP_FLAGS = ("-h", "--help")


def command_of(argv: list[str]) -> str | None:
    """The sub-command that a command line names, if one is known.

    Args:
      argv: command-line arguments without the program name.
    Returns:
      str, the first argument not a flag when it is a known sub-command; None when it is
      not, or when the top level's help comes first (help lists every sub-command).
    """
    for arg in argv:
        if arg in _HELP_FLAGS:
            return None
        if not arg.startswith("-"):
            return arg if arg in _SUBCOMMAND_MODULES else None
    return None


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``jaxspline`` command (sub-commands register here).

    Every sub-command (and sub-sub-command) also takes ``--debug``.

    Args:
      command: register only this sub-command (:func:`command_of`); None: all of them.
    """
    import importlib

    parser = OneLineParser(prog="jaxspline", description=_DESCRIPTION)
    parser.add_argument("--debug", action="store_true", help=_DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", required=True)
    names = _SUBCOMMAND_MODULES if command is None else (command,)
    for name in names:
        importlib.import_module(_SUBCOMMAND_MODULES[name]).register(sub)
    _add_debug(sub)
    return parser


_DEBUG_HELP = "on an error, also print the Python traceback"
_ARGUMENT = re.compile(r"argument (\S+): (.*)", re.DOTALL)
_NOT_A = re.compile(r"invalid (float|int) value: (.*)", re.DOTALL)


class OneLineParser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line naming the flag and the value.

    ``jaxspline plan --time-limit abc`` ends with ``jaxspline plan: error: --time-limit:
    'abc' is not a number`` and exit 2, not argparse's usage block (``-h`` shows it).
    Its sub-parsers are of this class too (argparse makes them of their parent's class).
    """

    def error(self, message: str):
        """Print ``message`` in one line, as ``PROG: error: FLAG: WHAT``, and exit with 2.

        Args:
          message: argparse's message (``argument --seed: invalid int value: '1.5'``).
        Raises:
          SystemExit: always, code 2.
        """
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {one_line(message)}\n")


def one_line(message: str) -> str:
    """An argparse error message as one line naming the flag (:class:`OneLineParser`).

    Args:
      message: argparse's message.
    Returns:
      str: ``--time-limit: 'abc' is not a number``, ``--seed: '1.5' is not an integer``,
      ``--json: expected one argument``; other messages as they are, on one line.
    """
    found = _ARGUMENT.fullmatch(message)
    if found is not None:
        flag, what = found.groups()
        bad = _NOT_A.fullmatch(what)
        if bad is not None:
            kind = "a number" if bad.group(1) == "float" else "an integer"
            what = f"{bad.group(2)} is not {kind}"
        message = f"{flag}: {what}"
    return " ".join(message.split())


def _add_debug(subparsers) -> None:
    """``--debug`` on every sub-parser below ``subparsers`` (not set: the top level's)."""
    for p in subparsers.choices.values():
        if "--debug" not in p._option_string_actions:
            p.add_argument(
                "--debug", action="store_true", default=argparse.SUPPRESS, help=_DEBUG_HELP
            )
        for action in p._actions:
            if isinstance(action, argparse._SubParsersAction):
                _add_debug(action)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``jaxspline`` console script.

    Args:
      argv: command-line arguments without the program name; None: ``sys.argv[1:]``,
        and this call is the process: it ends the process itself once the command is
        done (:func:`end_process`).
    Returns:
      int, the exit code (module docstring).
    """
    code = _run(argv)
    if argv is None:
        end_process(code)
    return code


def end_process(code: int) -> None:
    """End the command's process now, with exit code ``code``.

    The command is done: its outputs are written and closed. What Python would still do
    at exit is JAX's clean-up of its back ends and the interpreter's teardown, all of it
    after the work (and on a loaded machine far past the time limit). So any child
    process still running (a bound worker) is stopped, the streams are flushed, and the
    process ends at once (``os._exit``).

    Args:
      code: the exit code.
    """
    mp = sys.modules.get("multiprocessing")
    for child in mp.active_children() if mp is not None else ():
        child.terminate()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe: nothing more can reach it
            pass
    os._exit(code)


def _run(argv: list[str] | None) -> int:
    """:func:`main` up to the exit code."""
    from jaxspline.planner.deadline import process_start

    # called as the process (argv None): a time limit counts from the process's start
    started = process_start() if argv is None else time.monotonic()
    parser = build_parser(command_of(sys.argv[1:] if argv is None else argv))
    args = parser.parse_args(argv)
    args.started = started
    debug = bool(getattr(args, "debug", False))
    main_thread = threading.current_thread() is threading.main_thread()
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    old_hook = sys.unraisablehook
    if main_thread:
        for s in old:  # SIGTERM like Ctrl-C (clean-up runs); both remembered if swallowed
            signal.signal(s, _terminate)
        sys.unraisablehook = functools.partial(_unraisable, old_hook)
    restore = _nothing  # the cache's warnings hook, once it is set
    try:
        restore = _enable_compile_cache()
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        print(
            "jaxspline: interrupted (outputs are published as whole sets: none is partial)",
            file=sys.stderr,
        )
        return EXIT_INTERRUPTED
    except Exception as exc:  # noqa: BLE001 - every error ends in one line and a code
        return _report(exc, debug)
    finally:
        if main_thread:
            # called as the process (argv None): the work is done, later signals only
            # race the exit; called from Python: hand the handlers back
            for s, h in old.items():
                signal.signal(s, signal.SIG_IGN if argv is None else h)
            sys.unraisablehook = old_hook
        restore()


def _report(exc: Exception, debug: bool) -> int:
    """Print ``exc`` as one line (with the traceback before it under ``--debug``) and
    return its exit code."""
    from jaxspline.planner.deadline import TimeLimitError
    from jaxspline.planner.memory_guard import MemoryLimitError
    from jaxspline.products.outputs import OutputBusyError, OutputError

    code, label = _classify(exc, TimeLimitError, MemoryLimitError, OutputBusyError, OutputError)
    if debug:
        traceback.print_exception(exc, file=sys.stderr)
    text = _text(exc).replace("\r", " ").replace("\n", " ").strip() or type(exc).__name__
    if code == EXIT_INTERNAL:
        text = f"{type(exc).__name__}: {text}"
        if not debug:
            text += " (a bug: run again with --debug for the traceback, and report it)"
    print(f"jaxspline: {label}: {text}", file=sys.stderr)
    return code


def _text(exc: Exception) -> str:
    """The message of ``exc``; an ``OSError`` of the system as ``FILE: reason`` (Python
    writes ``[Errno 28] No space left on device: 'FILE'``)."""
    if isinstance(exc, OSError) and exc.strerror and len(exc.args) >= 2:
        names = [
            repr(n) if n == "" else str(n) for n in (exc.filename, exc.filename2) if n is not None
        ]
        return f"{' -> '.join(names)}: {exc.strerror}" if names else exc.strerror
    return str(exc)


def _classify(exc, time_limit, memory_limit, busy, output) -> tuple[int, str]:
    """(exit code, label) of an exception (module docstring)."""
    if isinstance(exc, time_limit):
        return EXIT_TIME_LIMIT, "time limit"
    if isinstance(exc, memory_limit):  # too big for its memory: exit 3 as for the time
        return EXIT_TIME_LIMIT, "memory limit"
    if isinstance(exc, busy):
        return EXIT_BUSY, "busy"
    if isinstance(exc, output):
        return EXIT_WRITE, "cannot write"
    if isinstance(exc, ValueError | FileExistsError | FileNotFoundError | IsADirectoryError):
        return EXIT_BAD_INPUT, "error"
    if isinstance(exc, OSError):  # writing a --json / solution file, a full disk, ...
        return EXIT_WRITE, "cannot write"
    if isinstance(exc, MemoryError):
        return EXIT_INTERNAL, "out of memory"
    return EXIT_INTERNAL, "internal error"


def _terminate(signum, frame):
    """Ctrl-C and SIGTERM: ``KeyboardInterrupt``, and the signal remembered in case the
    exception lands in a finalizer that drops it (:func:`jaxspline.base.clock.note_signal`)."""
    from jaxspline.base.clock import note_signal

    note_signal(signal.Signals(signum).name)
    raise KeyboardInterrupt


def _unraisable(previous, unraisable) -> None:
    """``sys.unraisablehook`` of a command: a ``KeyboardInterrupt`` that a finalizer or
    garbage-collector callback dropped is not printed (it was remembered and is raised
    again at the next check); anything else as Python prints it."""
    if not isinstance(unraisable.exc_value, KeyboardInterrupt):
        previous(unraisable)
