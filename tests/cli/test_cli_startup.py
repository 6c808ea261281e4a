"""What a start of the ``jaxspline`` command costs: a rejected scenario pays JAX, not the rest.

A run that is refused before any planning (a bad flag, a bad scenario) spends nearly all
its time importing; issue 30 asks for such a rejection within 3 s. The command therefore
registers only the sub-command its line names (the benchmark adapters bring YAML and
SGP4), and optax (with ``jax.scipy``) is imported where the start-time refinement runs,
not when the package is imported. Once the command is done, it ends its process at
once (``jaxspline.cli.end_process``).
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import pytest

from jaxspline.cli import build_parser, command_of

_HEAVY = ("optax", "yaml", "sgp4", "jaxspline.aeossp", "jaxspline.regional", "jaxspline.stereo")

_PROBE = """
import sys
from jaxspline.cli import main
code = main(["plan", sys.argv[1], "-o", sys.argv[2]])
print(code, [m for m in {heavy!r} if m in sys.modules])
"""


@pytest.mark.parametrize(
    "argv, command",
    [
        (["plan", "s.toml"], "plan"),
        (["--debug", "view", "p.json"], "view"),
        (["aeossp", "solve", "c"], "aeossp"),
        (["regional", "--help"], "regional"),
        (["--help", "plan"], None),  # the top level's help lists every sub-command
        (["-h"], None),
        (["nonsense"], None),  # argparse names the choices: all of them are registered
        ([], None),
    ],
)
def test_the_command_line_names_its_sub_command(argv, command):
    assert command_of(argv) == command


def test_the_full_parser_has_every_sub_command_and_one_has_only_its_own():
    def choices(parser):
        sub = next(a for a in parser._actions if isinstance(a.choices, dict))
        return set(sub.choices)

    assert choices(build_parser()) == {"plan", "bound", "view", "aeossp", "regional", "stereo"}
    for name in ("plan", "aeossp"):
        assert choices(build_parser(name)) == {name}


def test_a_rejected_plan_imports_neither_optax_nor_the_adapters(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("x = 1\n", encoding="utf-8")
    probe = _PROBE.format(heavy=_HEAVY)
    out = subprocess.run(
        [sys.executable, "-c", probe, str(bad), str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.stdout.split(None, 1) == ["2", "[]\n"], (out.stdout, out.stderr)
    assert "bad.toml: x (line 1): unknown section or key" in out.stderr


_END = """
import multiprocessing as mp, sys, time
from jaxspline.cli import end_process
child = mp.get_context("fork").Process(target=time.sleep, args=(60,))
child.start()
print(child.pid)
sys.stdout.write("written, not flushed")
end_process(4)
"""


def test_the_command_ends_its_process_at_once_with_its_children_stopped():
    # JAX's clean-up at exit took up to ~13 s on a loaded machine after the work was done
    out = subprocess.run(
        [sys.executable, "-c", _END], stdout=subprocess.PIPE, text=True, timeout=60
    )
    pid, rest = out.stdout.split("\n", 1)
    assert out.returncode == 4 and rest == "written, not flushed"
    assert _ends(int(pid)), "the child still runs"


def _ends(pid: int, wait_s: float = 5.0) -> bool:
    """Whether process ``pid`` is gone (or a zombie: ended, not yet reaped) within ``wait_s``."""
    status = Path(f"/proc/{pid}/status")
    t_end = time.monotonic() + wait_s
    while time.monotonic() < t_end:
        try:
            if "\tZ" in status.read_text().split("State:", 1)[1].split("\n", 1)[0]:
                return True
        except (FileNotFoundError, ProcessLookupError):
            return True
        time.sleep(0.05)
    return False
