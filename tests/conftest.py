"""Tests run in float64 by default (the library itself never flips x64 on import)."""

import os
import pathlib
import sys

# shared helpers cross folders (``from test_screen import ...`` in tests/sequences): every
# test folder is importable, so a file also runs alone (pytest adds only its own folder)
_HERE = pathlib.Path(__file__).parent
sys.path[:0] = [str(d) for d in sorted(_HERE.iterdir()) if d.is_dir() and d.name[0] not in "._"]

os.environ.setdefault("XLA_FLAGS", "")
os.environ.setdefault("JAXSPLINE_CACHE_DIR", "off")  # tests never write to the user's cache
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
