"""A regional case written as a scenario file reads back as the scenario its adapter plans.

``scripts/scenario_toml.py`` writes a case as TOML plus sample files; the scenario reader
(``jaxspline.load_scenario``) must give back what ``case_scenario`` builds: the same
satellites (model, limits, sensor fields, battery, duty), the same areas (samples to the
written precision, priorities, least shares) and the same planner settings, so
``jaxspline plan`` plans the problem ``jaxspline regional solve`` plans.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

import jaxspline as js
from jaxspline.regional.adapter import case_scenario

ROOT = Path(__file__).resolve().parents[2]
DATA = Path("/work/shared/data/regional_coverage/train")
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")


def _script():
    spec = importlib.util.spec_from_file_location(
        "scenario_toml", ROOT / "scripts/scenario_toml.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("case", ["case_0001", "case_0004"])
def test_the_written_scenario_reads_back_as_the_adapters(tmp_path, case):
    want = case_scenario(DATA / case)
    path = _script().write_scenario(want, tmp_path / "s", 0, None)
    got = js.load_scenario(path)
    assert got.planner == want.planner
    assert got.duration == want.duration and got.epoch == want.epoch
    for a, b in zip(got.satellites, want.satellites, strict=True):
        assert (a.name, a.model, a.sensor, tuple(a.orbit)) == (
            b.name,
            b.model,
            b.sensor,
            tuple(b.orbit),
        )
        for f in ("off_nadir_max", "settle", "fov", "duty"):
            assert getattr(a, f) == pytest.approx(getattr(b, f), rel=1e-12), f
        np.testing.assert_allclose(a.edge_band, b.edge_band, rtol=1e-12)
        np.testing.assert_allclose(a.strip_duration, b.strip_duration, rtol=1e-12)
        np.testing.assert_allclose(a.limits.rate, b.limits.rate, rtol=1e-12)
        np.testing.assert_allclose(a.limits.accel, b.limits.accel, rtol=1e-12)
        assert a.power == b.power
    assert [a.name for a in got.areas] == [a.name for a in want.areas]
    for a, b in zip(got.areas, want.areas, strict=True):
        np.testing.assert_allclose(a.samples[:, :2], b.samples[:, :2], atol=1e-8)
        np.testing.assert_allclose(a.samples[:, 2], b.samples[:, 2], rtol=1e-10)
        assert math.isnan(a.min_share) == math.isnan(b.min_share)
        if not math.isnan(b.min_share):
            assert a.min_share == pytest.approx(b.min_share)
    np.testing.assert_allclose(got.targets.value, want.targets.value, rtol=1e-12)
    with pytest.raises(SystemExit, match="exists"):
        _script().write_scenario(want, tmp_path / "s", 0, None)
