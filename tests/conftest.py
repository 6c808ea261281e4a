"""Tests run in float64 by default (the library itself never flips x64 on import)."""

import os

os.environ.setdefault("XLA_FLAGS", "")
os.environ.setdefault("JAXSPLINE_CACHE_DIR", "off")  # tests never write to the user's cache
import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)
