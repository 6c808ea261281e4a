"""A cache folder that takes no writes leaves the compilation cache off, said in one line.

In-process: :func:`jaxspline.cli.compile_cache.enable_cache` on a folder it cannot make
(a path through a file) says so and leaves JAX's settings alone; on a writable one it
sets them, and JAX's warnings about cache entries that could not be written (a disk
filling up later) become one line and turn the cache off, other warnings untouched.
Real processes: ``jaxspline plan`` with its cache on a full or a read-only file system
(a tmpfs; needs root) writes one line about it on stderr, none of JAX's warnings.
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import pytest
from _full_disk import full_disk
from test_cli_plan import SMALL

from jaxspline.cli import compile_cache

NOTE = "jaxspline: note: the compilation cache is off for this run: cannot write "
JAX_WARNING = (
    "Error writing persistent compilation cache entry for 'jit_{}': OSError: "
    "[Errno 28] No space left on device"
)


@pytest.fixture
def jax_config(monkeypatch):
    """JAX's settings as the cache would set them, recorded (the test process keeps its own)."""
    import jax

    calls = []
    monkeypatch.setattr(jax.config, "update", lambda name, value: calls.append((name, value)))
    monkeypatch.setattr(compile_cache, "_turn_off", lambda: calls.append(("off", True)))
    return calls


def test_a_folder_that_cannot_be_made_leaves_the_cache_off(tmp_path, capsys, jax_config):
    (tmp_path / "file").write_text("")
    path = tmp_path / "file" / "xla"
    compile_cache.enable_cache(path)()
    err = capsys.readouterr().err
    assert err == f"{NOTE}{path} (Not a directory); programs are compiled anew\n"
    assert jax_config == []


def test_cache_write_warnings_become_one_line_and_turn_the_cache_off(
    tmp_path, capsys, jax_config, monkeypatch
):
    shown = []
    monkeypatch.setattr(warnings, "showwarning", lambda message, *a, **k: shown.append(message))
    before = warnings.showwarning
    restore = compile_cache.enable_cache(tmp_path / "xla")
    assert ("jax_compilation_cache_dir", str(tmp_path / "xla")) in jax_config
    assert os.listdir(tmp_path / "xla") == []  # the probe is gone
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            for name in ("a", "b", "c"):
                warnings.warn(JAX_WARNING.format(name), UserWarning, stacklevel=1)
            warnings.warn("something else", UserWarning, stacklevel=1)
    finally:
        restore()
    assert warnings.showwarning is before
    note = f"{NOTE}{tmp_path / 'xla'} (No space left on device); programs are compiled anew"
    assert capsys.readouterr().err == note + "\n"
    assert [str(m) for m in shown] == ["something else"]  # shown as before
    assert jax_config.count(("off", True)) == 1


@pytest.mark.parametrize("read_only", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_plan_with_its_cache_on_a_disk_that_takes_no_writes(tmp_path, read_only):
    scen = tmp_path / "small.toml"
    scen.write_text(SMALL, encoding="utf-8")
    with full_disk(tmp_path, read_only=read_only) as disk:
        env = dict(os.environ, JAXSPLINE_CACHE_DIR=str(disk))
        cmd = [sys.executable, "-m", "jaxspline.cli", "plan", str(scen), "-o", str(tmp_path / "o")]
        cmd += ["--no-aem", "--no-plots", "--no-html", "--max-iters", "5", "--quiet"]
        cmd += ["--time-limit", "120"]
        done = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    why = "Read-only file system" if read_only else "No space left on device"
    assert done.stderr == f"{NOTE}{disk} ({why}); programs are compiled anew\n"
