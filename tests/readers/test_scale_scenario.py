"""scripts/make_scale_scenario.py: deterministic, loadable, on land, shares and model cycle.

Also: the shipped ``jaxspline/data/constellation_day.toml`` is exactly what the script's
``day`` preset writes, and loads.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from jaxspline import load_scenario
from jaxspline.base.land import is_land
from jaxspline.readers.mission import STRIP

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "jaxspline" / "data"


def _script():
    spec = importlib.util.spec_from_file_location(
        "make_scale_scenario", ROOT / "scripts" / "make_scale_scenario.py"
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up while executing it
    spec.loader.exec_module(mod)
    return mod


mss = _script()
TINY = mss.Spec(
    name="tiny", satellites=7, planes=2, hours=2.0, targets=300, constrained=0.3, seed=5
)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """The tiny instance written twice (two folders) and loaded once."""
    a, b = tmp_path_factory.mktemp("a") / "tiny.toml", tmp_path_factory.mktemp("b") / "tiny.toml"
    mss.write(TINY, a)
    mss.write(TINY, b)
    return a, b, load_scenario(a)


def test_same_seed_same_files_other_seed_other_targets(tiny):
    a, b, _ = tiny
    csv_a, csv_b = (p.with_name("tiny_targets.csv") for p in (a, b))
    assert a.read_bytes() == b.read_bytes()
    assert csv_a.read_bytes() == csv_b.read_bytes()
    other = mss.build(replace(TINY, seed=6), "x.csv")[1]
    assert other != csv_a.read_text(encoding="utf-8")


def test_tiny_loads_with_the_counts_asked(tiny):
    _, _, sc = tiny
    tg = sc.targets
    assert len(sc.satellites) == 7 and len(tg) == 300
    assert math.isclose(sc.duration, 2 * 3600.0)
    assert int((tg.kind == STRIP).sum()) == round(0.1 * 300)  # strip share exactly 10 %
    constrained = np.isfinite(tg.t_lo) | (tg.sensor != "")
    assert int(constrained.sum()) == round(0.3 * 300)
    win = np.isfinite(tg.t_lo)
    assert np.all(tg.t_lo[win] >= 0) and np.all(tg.t_hi[win] <= sc.duration)
    assert np.all(tg.t_hi[win] - tg.t_lo[win] >= 600.0)
    assert np.all(np.isfinite(tg.t_lo) == np.isfinite(tg.t_hi))


def test_every_target_on_land(tiny):
    tg = tiny[2].targets
    assert is_land(np.degrees(tg.lat), np.degrees(tg.lon)).all()
    lat = np.degrees(tg.lat)
    assert lat.min() >= mss.LAT_RANGE_DEG[0] and lat.max() <= mss.LAT_RANGE_DEG[1]


def test_models_cycle_and_orbits_are_sun_synchronous_550_km(tiny):
    from jaxspline.base.elements import sso_inclination

    sats = tiny[2].satellites
    assert [s.model for s in sats] == [mss.MODEL_CYCLE[i % 3] for i in range(7)]
    assert [s.sensor for s in sats].count("infrared") == 1  # sat 5 (i = 4)
    assert sats[4].sensor == "infrared"
    for s in sats:
        assert math.isclose(float(s.orbit.inclination), sso_inclination(550e3), rel_tol=1e-12)
    # two planes, 4 + 3 satellites, RAANs 3 h of local time (45 deg) apart
    raan = sorted({round(float(s.orbit.raan), 9) for s in sats})
    assert len(raan) == 2
    assert math.isclose(math.degrees(raan[1] - raan[0]), 45.0, abs_tol=1e-6)


def test_tle_satellites_come_first_from_the_default():
    sats = mss.satellite_tables(replace(TINY, satellites=9, tles=True))
    default = [s for s in mss._default_toml()["satellites"] if "tle" in s]
    assert sats[:6] == default
    assert [s["model"] for s in sats[6:]] == list(mss.MODEL_CYCLE)


def test_bad_spec_names_the_field():
    with pytest.raises(ValueError, match="strip_fraction"):
        replace(TINY, strip_fraction=1.5).validate()


def test_shipped_constellation_day_is_the_day_preset():
    toml, csv_text, rows, _ = mss.build(
        mss.PRESETS["day"],
        "constellation_day_targets.csv",
        "day",
        "jaxspline/data/constellation_day.toml",
    )
    assert (DATA / "constellation_day.toml").read_text(encoding="utf-8") == toml
    assert (DATA / "constellation_day_targets.csv").read_text(encoding="utf-8") == csv_text
    sc = load_scenario(DATA / "constellation_day.toml")
    tg = sc.targets
    assert len(sc.satellites) == 24 and len(tg) == 20000 and sc.duration == 86400.0
    models = [s.model for s in sc.satellites]
    assert all(models.count(m) == 8 for m in mss.MODEL_CYCLE)
    share = float((np.isfinite(tg.t_lo) | (tg.sensor != "")).mean())
    assert abs(share - 1 / 3) < 0.01
    rand = np.char.startswith(tg.name.astype(str), "land_")
    assert rand.sum() == 20000 - 1500
    assert is_land(np.degrees(tg.lat[rand]), np.degrees(tg.lon[rand])).all()
    assert abs(float((tg.kind[rand] == STRIP).mean()) - 0.1) < 1e-3
