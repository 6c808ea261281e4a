"""Tests run in float64 by default (the library itself never flips x64 on import)."""

import os
import pathlib
import shutil
import sys
import tempfile

# shared helpers cross folders (``from test_screen import ...`` in tests/sequences): every
# test folder is importable, so a file also runs alone (pytest adds only its own folder)
_HERE = pathlib.Path(__file__).parent
sys.path[:0] = [str(d) for d in sorted(_HERE.iterdir()) if d.is_dir() and d.name[0] not in "._"]

# Python bytecode: an environment with PYTHONDONTWRITEBYTECODE set makes every process
# the run starts (xdist workers, CLI runs, doc pages) compile the package's and the tests'
# sources again, ~0.6 CPU-s each; the run writes the __pycache__ folders (ignored by git)
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

# Most of the suite's time is compiling small programs that run once. The tests compile
# with XLA's unoptimized CPU back end (the loop emitters, LLVM at -O0) in one piece (no
# parallel code generation: the workers already fill the cores, and the split's pieces
# each cost their own setup): the same semantics, less CPU time.
# An XLA_FLAGS of your own replaces these (XLA_FLAGS= runs the tests with the defaults).
TEST_XLA_FLAGS = (
    "--xla_cpu_use_fusion_emitters=false --xla_backend_optimization_level=0"
    " --xla_cpu_parallel_codegen_split_count=1"
)
os.environ.setdefault("XLA_FLAGS", TEST_XLA_FLAGS)
# One persistent XLA cache for the whole run, in a temporary folder (never the user's
# cache): made by the first process (pytest itself, or its only process without xdist),
# inherited through the environment by the xdist workers and every ``jaxspline``
# subprocess a test starts, and removed when the run ends. Most of the suite's time is
# compiling the same programs again in other processes (a run of the CLI compiles ~160).
_CACHE_ENV = "JAXSPLINE_CACHE_DIR"
_OWN_CACHE = _CACHE_ENV not in os.environ
if _OWN_CACHE:
    os.environ[_CACHE_ENV] = tempfile.mkdtemp(prefix="jaxspline-test-xla-")
import pytest  # noqa: E402


@pytest.hookimpl(trylast=True)
def pytest_configure(config):
    """float64 and the run's cache in every process that collects and runs tests; not in
    the xdist controller, which only hands them out (importing JAX there would delay the
    workers' start by a second)."""
    distributing = config.getoption("dist", "no") != "no" and not config.option.collectonly
    if distributing and not os.environ.get("PYTEST_XDIST_WORKER"):
        return
    import jax

    jax.config.update("jax_enable_x64", True)
    if os.environ[_CACHE_ENV].strip().lower() not in ("", "off", "0", "none"):
        jax.config.update("jax_compilation_cache_dir", os.environ[_CACHE_ENV])
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
        jax.config.update("jax_persistent_cache_min_entry_size_bytes", 0)


@pytest.hookimpl(trylast=True)
def pytest_unconfigure(config):
    """The process that made the run's cache folder removes it; an xdist worker then ends.

    A worker has sent its results to the controller (``pytest_sessionfinish``) by now, and
    the controller waits for its process to end. Exiting normally, JAX's exit handler
    frees the worker's thousands of compiled programs one by one and the interpreter then
    frees every object, seconds at the end of every run; ``os._exit`` leaves both to the
    operating system.
    """
    if _OWN_CACHE:
        shutil.rmtree(os.environ[_CACHE_ENV], ignore_errors=True)
    if os.environ.get("PYTEST_XDIST_WORKER"):
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)
