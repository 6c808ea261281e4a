"""The ``jaxspline`` command line."""

from __future__ import annotations

import argparse
import sys

__all__ = ["main"]


# Each module registers its own sub-commands with ``register(subparsers)``; the module
# sets ``func(args) -> int`` on its parsers. Imported lazily to keep start-up fast.
_SUBCOMMAND_MODULES = ("jaxspline.cli_plan", "jaxspline.aeossp.cli")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``jaxspline`` command (sub-commands register here)."""
    import importlib

    parser = argparse.ArgumentParser(prog="jaxspline", description=__doc__)
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
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileExistsError, FileNotFoundError) as exc:
        print(f"jaxspline: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
