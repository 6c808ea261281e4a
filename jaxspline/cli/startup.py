"""The command's first seconds: a Ctrl-C or SIGTERM while Python imports the package.

Importing ``jaxspline`` (JAX, numpy, scipy, ...) takes 2-8 s before
:func:`jaxspline.cli.main` installs the command's own signal handlers. Until then a
Ctrl-C ended the command with a ``KeyboardInterrupt`` traceback through the imports,
and a SIGTERM killed it without a word. :func:`install_startup_signals` (run when
``jaxspline/__init__.py`` imports this module, before anything else) makes both end the
process at once with exit 130 and one line (nothing was done or written yet) - but
only when the process runs the
command (``python -m jaxspline.cli ...``, ``python -m jaxspline.aeossp ...``, the
``jaxspline`` console script), only from the main thread, and only over the default
handlers: importing the library leaves a program's signal handling alone.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

__all__ = ["EXIT_INTERRUPTED", "INSTALLED", "install_startup_signals", "runs_the_command"]

EXIT_INTERRUPTED = 130  # exit code after Ctrl-C / SIGTERM (128 + SIGINT, the shell convention)
_COMMAND = "jaxspline"
_OPTIONS_WITH_VALUE = ("-X", "-W", "--check-hash-based-pycs")  # python OPTION VALUE


def runs_the_command(orig_argv=None) -> bool:
    """Whether this process runs the ``jaxspline`` command (not a program importing it).

    Args:
      orig_argv: the interpreter's command line (default ``sys.orig_argv``).
    Returns:
      bool: ``python -m jaxspline[.x]`` or a console script named ``jaxspline``.
    """
    argv = list(sys.orig_argv if orig_argv is None else orig_argv)
    i = 1
    while i < len(argv):  # the interpreter's own options, up to -m, -c or the script
        arg = argv[i]
        if arg.startswith("-m"):
            module = arg[2:] or (argv[i + 1] if i + 1 < len(argv) else "")
            return module.split(".")[0] == _COMMAND
        if arg in _OPTIONS_WITH_VALUE:
            i += 2
        elif arg.startswith("-") and arg != "-" and not arg.startswith("-c"):
            i += 1
        else:
            break
    script = argv[i] if i < len(argv) else ""
    return not script.startswith("-") and os.path.basename(script) == _COMMAND


def _interrupted(signum, frame) -> None:
    """Before the command's handlers: one line, exit 130 at once (nothing to clean up)."""
    name = signal.Signals(signum).name
    os.write(2, f"jaxspline: interrupted ({name}) while starting: nothing was done\n".encode())
    os._exit(EXIT_INTERRUPTED)


def install_startup_signals() -> bool:
    """Install the start-up handlers of SIGINT and SIGTERM (module docstring).

    Returns:
      bool, whether they were installed.
    """
    if threading.current_thread() is not threading.main_thread() or not runs_the_command():
        return False
    done = False
    defaults = ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, signal.SIG_DFL))
    for sig, default in defaults:
        if signal.getsignal(sig) is default:
            signal.signal(sig, _interrupted)
            done = True
    return done


#: Whether importing this module installed the start-up handlers (``jaxspline/__init__.py``
#: imports it first).
INSTALLED = install_startup_signals()
