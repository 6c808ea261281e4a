"""``jaxspline bound --time-limit`` bounds the whole command, from the start of its process.

On a scenario whose preparation (windows, options, screening of 20,000 targets) takes
seconds: a limit too short for it stops the command with exit 3, the estimate and the
remedy, by the limit (plus the compile time not counted, which the message states); a
limit it fits ends the command at the limit, the iterations included (a step-size
target far above any plan keeps them from converging before it).
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time

import pytest
from test_cli_plan import SMALL

_TOLERANCE_S = 3.0  # [s] past the limit: the last iteration, the process's end
_TIMEOUT_S = 300
BIG = (
    SMALL.replace("duration_s = 1800.0", "duration_s = 21600.0")
    .replace("count = 30", "count = 20000")
    .replace("lat_deg = [43.0, 49.0]", "lat_deg = [-60.0, 60.0]")
    .replace("lon_deg = [11.0, 17.0]", "lon_deg = [-180.0, 180.0]")
)


@pytest.fixture(scope="module")
def big(tmp_path_factory):
    path = tmp_path_factory.mktemp("bound") / "big.toml"
    path.write_text(BIG, encoding="utf-8")
    return path


def _bound(scen, *extra):
    """``jaxspline bound`` in its own process: (exit code, stdout, stderr, wall seconds)."""
    cmd = [sys.executable, "-m", "jaxspline.cli", "bound", str(scen), *extra]
    t0 = time.monotonic()
    done = subprocess.run(cmd, env=dict(os.environ), capture_output=True, timeout=_TIMEOUT_S)
    wall = time.monotonic() - t0
    return done.returncode, done.stdout.decode(), done.stderr.decode(errors="replace"), wall


def test_a_limit_too_short_for_the_preparation_stops_bound_with_exit_3(big):
    code, _, err, wall = _bound(big, "--time-limit", "3")
    assert code == 3, err
    assert err.startswith("jaxspline: time limit: time limit of 3 s reached before the bound's ")
    assert "the whole run needs ~" in err and "give a time limit of" in err, err
    assert "(--time-limit)" in err and err.count("\n") == 1, err
    compiling = float(re.search(r"\(([\d.]+) s of it compiling", err).group(1))
    assert wall <= 3.0 + min(compiling, 20.0) + _TOLERANCE_S, err


def test_the_iterations_end_at_the_limit_of_the_whole_command(big):
    # the preparation takes ~7 s on an idle machine: room for it on a loaded one
    code, out, err, wall = _bound(big, "--time-limit", "30", "--target", "1e9")
    assert code == 0, err
    assert re.match(r"bound \S+ \(time, \d+ iterations", out), out  # stopped by the clock
    assert wall <= 30.0 + _TOLERANCE_S, out
