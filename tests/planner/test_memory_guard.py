"""The memory guard (:mod:`jaxspline.planner.memory_guard`): estimates from the scenario's
keys, checked against an injected room, without allocating what they estimate."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from jaxspline.geometry.windows import Windows
from jaxspline.planner import memory_guard as mg
from jaxspline.planner.opportunities import option_counts
from jaxspline.readers.scenario import parse_scenario

TOML = """
[scenario]
epoch = "2026-04-14T00:00:00Z"
duration_s = 3600.0
[[satellites]]
altitude_km = 600.0
[[satellites]]
altitude_km = 650.0
[[targets]]
lat_deg = 46.0
lon_deg = 15.0
duration_s = 10.0
[planner]
time_step_s = 0.01
geometry_step_s = 0.01
"""


@pytest.fixture(scope="module")
def sc():
    return parse_scenario(tomllib.loads(TOML), "tiny.toml", TOML)


def _guard(gb, **kw):
    return mg.MemoryGuard(available=lambda: gb * mg.GB, **kw)


def test_the_options_estimate_is_refused_with_the_keys_the_estimate_and_the_remedy(sc):
    # one 600 s window of one 10 s point target: 59,001 starts of 1,002 samples each
    win = Windows(np.array([0]), np.array([0]), np.array([1000.0]), np.array([1600.0]))
    cands, samples = option_counts(sc, win)
    assert cands == 59_001 and samples == 59_001 * 1_002
    est = mg.option_bytes(sc, cands, samples)
    assert est[0] == pytest.approx(mg.CANDIDATE_BYTES * cands + mg.SAMPLE_BYTES * samples)
    _guard(64.0).check("options", est)  # ~17.9 GB of 0.8 x 64 GB: fits
    guard = _guard(4.0)
    with pytest.raises(mg.MemoryLimitError) as exc:
        guard.check("options", est)
    msg, e = str(exc.value), exc.value
    assert e.stage == "options" and e.need > e.room == pytest.approx(3.2 * mg.GB)
    assert "stage 'options' would need ~17.9 GB" in msg, msg
    assert "planner.time_step_s = 0.01, planner.geometry_step_s = 0.01" in msg, msg
    assert "59,001 candidate options" in msg and "3.2 GB are available" in msg, msg
    # 17.9 / 3.2 = 5.6 times too much: a 0.06 s action grid needs 6 times less
    assert "raise planner.time_step_s to >= 0.06" in msg, msg
    assert "\n" not in msg and guard.estimates_mb["options"] > 18_000


def test_the_orbit_estimate_and_the_max_memory_limit(sc):
    need, drivers, remedy = mg.orbit_bytes(sc)
    assert need == mg.KNOT_BYTES * 360_001 * 2
    assert "2 satellites x 360,001 knots" in drivers and "geometry_step_s = 0.01" in drivers
    assert "planner.geometry_step_s to >= 0.04" in remedy(4.0)
    guard = _guard(1000.0, max_bytes=0.25 * mg.GB)  # --max-memory 0.25, below what is held
    room, said = guard.room()
    assert room < 0.25 * mg.GB and said.startswith("--max-memory 0.25 GB less the")
    with pytest.raises(mg.MemoryLimitError, match="stage 'orbits' would need ~0.5 GB") as exc:
        guard.check("orbits", (need, drivers, remedy))
    # less room than a stage's own programs: no step helps, only more memory
    assert str(exc.value).endswith(" or more") and "give --max-memory " in str(exc.value)
    assert "geometry_step_s to >=" not in str(exc.value)
    with pytest.raises(mg.MemoryLimitError, match="free memory") as exc:
        _guard(0.1).check("orbits", (need, drivers, remedy))
    mg.MemoryGuard(available=lambda: None).check("orbits", (1e18, "", remedy))  # unknown: pass


def test_near_pair_counts_match_a_brute_force_count():
    rng = np.random.default_rng(5)
    sat = rng.integers(0, 3, 400)
    t0 = np.sort(rng.uniform(0.0, 3000.0, 400))
    t1 = t0 + rng.uniform(5.0, 30.0, 400)
    reach = np.array([60.0, 120.0, 30.0])
    same = sat[:, None] == sat[None, :]
    gap = t0[None, :] - t1[:, None]
    inside = same & (gap >= -1e-6) & (gap <= reach[sat][:, None])
    per_sat = [int(inside[sat == k].sum()) for k in range(3)]
    assert mg.near_pair_counts(sat, t0, t1, reach) == (sum(per_sat), max(per_sat))


def test_available_memory_is_read_from_the_system():
    avail = mg.available_bytes()
    assert avail is None or avail > 0


# three days at 1 s over 600 targets: the orbits (~0.36 GB with a stage's programs) fit
# in 0.8 x 0.55 GB, the windows' blocks of 512 targets x 21,600 coarse knots do not
# (their estimate: a sample of the targets' pre-screen, geometry.windows.window_work)
WINDOWS_TOML = """
[scenario]
epoch = "2026-04-14T00:00:00Z"
duration_s = 259200.0
[[satellites]]
altitude_km = 600.0
[random_targets]
count = 600
seed = 3
lat_deg = [-60.0, 60.0]
[planner]
time_step_s = 1.0
geometry_step_s = 1.0
"""


def test_the_windows_estimate_stops_the_run_before_the_stage(monkeypatch):
    from jaxspline.planner import build as pipeline

    def never(*args, **kwargs):
        raise AssertionError("the windows stage ran")

    monkeypatch.setattr(pipeline, "visibility_windows_all", never)
    sc = parse_scenario(tomllib.loads(WINDOWS_TOML), "days.toml", WINDOWS_TOML)
    guard = _guard(0.55)
    with pytest.raises(mg.MemoryLimitError) as exc:
        pipeline.build_problem(sc, memory=guard)
    msg, e = str(exc.value), exc.value
    assert e.stage == "windows" and e.room < e.need < 2 * e.room, msg
    assert msg.startswith("stage 'windows' would need ~0.6 GB (600 targets, 1 satellites x "), msg
    assert "259,203 knots, up to " in msg and "planner.geometry_step_s = 1)" in msg, msg
    # 0.6 GB over 0.44 GB, less a stage's programs: a 1.64 s geometry step fits
    assert "raise planner.geometry_step_s to >= 1.64 " in msg and "shorter horizon" in msg, msg
    assert guard.estimates_mb["orbits"] < guard.estimates_mb["windows"]


def test_the_windows_estimate_stays_above_what_the_stage_allocates():
    import tracemalloc

    import jax

    from jaxspline.planner import build as pipeline

    toml = WINDOWS_TOML.replace("259200.0", "86400.0").replace("count = 600", "count = 200")
    sc = parse_scenario(tomllib.loads(toml), "day.toml", toml)
    with jax.enable_x64(True):
        table, scene, _ = pipeline._orbits(sc)
        args = pipeline._window_args(sc, scene, table)
        need = mg.window_bytes(sc, pipeline.window_work(*args))[0]
        tracemalloc.start()
        try:
            windows = pipeline.visibility_windows_all(*args)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    assert peak < need < 4 * peak and len(windows) > 100
