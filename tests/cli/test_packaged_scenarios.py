"""Every packaged scenario (``jaxspline/data/*.toml``) runs with the default flags.

``jaxspline plan SCENARIO`` checks its flags and outputs before it plans: the AEM step
(at most 50,000 attitude states over all the AEM files), the AEM file names, the output
directory. Each packaged scenario passes them with no flag given; the planning itself
is replaced by a stop (the constellation day plans for minutes). Without ``--aem-step``
a scenario whose default step would exceed the cap gets a coarser one, said on stderr in
one line; an ``--aem-step`` given on the command line is never changed.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import jaxspline
from jaxspline.cli import plan as plan_cli
from jaxspline.readers.scenario import load_scenario

DATA = Path(jaxspline.__file__).parent / "data"
PACKAGED = sorted(DATA.glob("*.toml"))


class _Planning(Exception):
    """Raised where the run would start planning: every check before it passed."""


def _stop(*args, **kwargs):
    raise _Planning


def test_there_are_packaged_scenarios():
    assert {p.name for p in PACKAGED} >= {"default.toml", "constellation_day.toml"}


@pytest.mark.parametrize("path", PACKAGED, ids=[p.stem for p in PACKAGED])
def test_a_packaged_scenario_passes_the_checks_with_default_flags(path, tmp_path, monkeypatch):
    monkeypatch.setattr(plan_cli, "_plan", _stop)
    with pytest.raises(_Planning):
        plan_cli.run_plan(str(path), tmp_path / "out", progress=False)


def test_the_default_aem_step_is_raised_to_fit_the_cap_and_said(tmp_path, monkeypatch, capsys):
    day = DATA / "constellation_day.toml"
    sc = load_scenario(day)
    n, horizon = len(sc.satellites), sc.duration
    assert horizon / plan_cli.AEM_STEP_S * n > plan_cli.MAX_AEM_STATES  # the default: too many
    seen = {}

    def deadline(sc, limit, t_start, **asked):
        seen.update(asked)
        return _stop()

    monkeypatch.setattr(plan_cli, "_deadline", deadline)
    with pytest.raises(_Planning):
        plan_cli.run_plan(str(day), tmp_path / "out", progress=False)
    step = seen["aem_step"]
    # 24 satellites x 24 h: 41.5 s at least; the first of the steps offered that fits
    assert step == 45.0
    assert horizon / step * n <= plan_cli.MAX_AEM_STATES < horizon / 30.0 * n
    err = capsys.readouterr().err
    assert err == (
        "jaxspline: note: AEM files sampled every 45 s: the default 10 s over the 86400 s "
        "horizon and 24 satellites would be 207,360 attitude states (at most 50,000); "
        "--aem-step sets the step\n"
    )
    # a step given on the command line is the user's: refused, not changed
    with pytest.raises(ValueError, match="--aem-step: 10 s over the 86400 s horizon"):
        plan_cli.run_plan(str(day), tmp_path / "out", progress=False, aem_step=10.0)
