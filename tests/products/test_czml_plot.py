"""CZML export and plan figures on a small hand-made PlanResult (one circular orbit, one TLE)."""

import datetime as dt
import json

import numpy as np
import pytest

from jaxspline.base.elements import circular_orbit
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.result import Observations, PlanResult
from jaxspline.products.czml import write_czml
from jaxspline.products.plot_plan import (
    plot_plan_ground_tracks,
    plot_plan_slack,
    plot_plan_timeline,
)
from jaxspline.readers.mission import Satellite, Scenario, make_targets

ISS_TLE = (
    "1 25544U 98067A   26103.50000000  .00016717  00000-0  10270-3 0  9005",
    "2 25544  51.6400 208.9163 0006317  69.9862  25.2906 15.49560000 10001",
)
EPOCH = dt.datetime(2026, 4, 13, 12, 0, tzinfo=dt.UTC)
DURATION = 3.0 * 3600.0
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
LEO_NORM = (6.6e6, 7.5e6)  # m, |r| of a LEO satellite


def _iso(when: dt.datetime) -> str:
    return when.strftime("%Y-%m-%dT%H:%M:%S.%fZ")


@pytest.fixture(scope="module")
def result():
    rng = np.random.default_rng(7)
    sats = (
        Satellite("alpha", circular_orbit(600e3, raan=0.3)),
        Satellite(
            "beta",
            ISS_TLE,
            model="eigen_axis",
            limits=AxisLimits(np.radians(2.0), np.radians(1.0)),
        ),
    )
    n = 12
    kind = np.where(np.arange(n) % 4 == 0, 1, 0)
    targets = make_targets(
        kind,
        np.radians(rng.uniform(-60.0, 60.0, n)),
        np.radians(rng.uniform(-180.0, 180.0, n)),
        duration=10.0,
        length=40e3,
    )
    sc = Scenario("czml-test", EPOCH, DURATION, sats, targets)
    start = np.array([300.0, 1800.0, 7000.0, 900.0, 5000.0])
    obs = Observations(
        sat=np.array([0, 0, 0, 1, 1]),
        target=np.array([1, 2, 3, 4, 5]),
        start=start,
        end=start + np.array([10.0, 10.0, 12.5, 10.0, 10.0]),
        maneuver=np.array([30.0, 42.0, 18.0, 25.0, 60.0]),
        slack=np.array([0.0, 4.0, 350.0, 0.02, 2500.0]),
        value=np.ones(5),
        speed=np.zeros(5),
        roll=np.full(5, np.nan),
        pitch=np.full(5, np.nan),
    )
    tb = np.linspace(0.0, DURATION, 40)
    return PlanResult(
        scenario=sc,
        observations=obs,
        value=5.0,
        bound=6.0,
        gap=1.0,
        bound_converged=True,
        report={"valid": True},
        stats={},
        timings={},
        battery={"alpha": (tb, 100.0 - 5.0 * np.sin(tb / 2000.0))},
    )


@pytest.fixture(scope="module")
def czml(result, tmp_path_factory):
    path = tmp_path_factory.mktemp("czml") / "plan.czml"
    assert write_czml(result, path, step=60.0) == path
    return path, json.loads(path.read_text(encoding="utf-8"))


def test_czml_document_clock(result, czml):
    _, doc = czml
    assert isinstance(doc, list)
    head = doc[0]
    assert head["id"] == "document" and head["version"] == "1.0"
    want = f"{_iso(EPOCH)}/{_iso(EPOCH + dt.timedelta(seconds=DURATION))}"
    assert head["clock"]["interval"] == want
    ids = [p["id"] for p in doc]
    assert len(ids) == len(set(ids))
    n_sat, n_tgt, n_obs = 2, len(result.scenario.targets), len(result.observations)
    assert len(doc) == 1 + n_sat + n_tgt + 2 * n_obs  # + a sensor footprint per observation


def test_czml_satellites(result, czml):
    _, doc = czml
    packets = {p["id"]: p for p in doc}
    for k, sat in enumerate(result.scenario.satellites):
        p = packets[f"sat-{k}"]
        assert p["name"] == sat.name and "label" in p and "path" in p
        pos = p["position"]
        assert pos["referenceFrame"] == "FIXED"
        assert pos["interpolationAlgorithm"] == "LAGRANGE"
        samples = np.asarray(pos["cartesian"]).reshape(-1, 4)
        assert samples.shape[0] >= 2
        assert samples[0, 0] == 0.0 and samples[-1, 0] == DURATION
        assert np.all(np.diff(samples[:, 0]) > 0)
        norm = np.linalg.norm(samples[:, 1:], axis=1)
        assert np.all((norm > LEO_NORM[0]) & (norm < LEO_NORM[1]))


def test_czml_targets_and_observations(result, czml):
    _, doc = czml
    packets = {p["id"]: p for p in doc}
    sc, obs = result.scenario, result.observations
    imaged = set(obs.target.tolist())
    for r in range(len(sc.targets)):
        p = packets[f"target-{r}"]
        lon, lat, _ = p["position"]["cartographicDegrees"]
        assert lat == pytest.approx(np.degrees(sc.targets.lat[r]))
        assert lon == pytest.approx(np.degrees(sc.targets.lon[r]))
        green = p["point"]["color"]["rgba"][1] > p["point"]["color"]["rgba"][0]
        assert green == (r in imaged)
    for i in range(len(obs)):
        p = packets[f"obs-{i}"]
        want = f"{_iso(sc.at(obs.start[i]))}/{_iso(sc.at(obs.end[i]))}"
        assert p["availability"] == want
        refs = p["polyline"]["positions"]["references"]
        assert refs == [f"sat-{obs.sat[i]}#position", f"target-{obs.target[i]}#position"]


def test_czml_sensor_footprints(result, czml):
    """Points: a disc as wide as the swath; strips: the swept footprint, growing in frames."""
    _, doc = czml
    packets = {p["id"]: p for p in doc}
    sc, obs = result.scenario, result.observations
    for i in range(len(obs)):
        p = packets[f"footprint-{i}"]
        assert p["availability"] == f"{_iso(sc.at(obs.start[i]))}/{_iso(sc.at(obs.end[i]))}"
        r, sat = int(obs.target[i]), sc.satellites[int(obs.sat[i])]
        if sc.targets.kind[r] == 0:
            assert p["ellipse"]["semiMajorAxis"] == sat.swath / 2
            continue
        frames = p["polygon"]["positions"]
        assert frames[0]["interval"].startswith(_iso(sc.at(obs.start[i])))
        assert frames[-1]["interval"].endswith(_iso(sc.at(obs.end[i])))
        first, last = (
            np.reshape(f["cartographicDegrees"], (-1, 3)) for f in (frames[0], frames[-1])
        )
        assert len(last) > len(first) >= 5  # the footprint grows along the strip
        # the start of the strip lies inside the footprint's first ring (between its sides)
        lon0, lat0 = np.degrees(sc.targets.lon[r]), np.degrees(sc.targets.lat[r])
        assert np.abs(first[:, 0] - lon0).min() < 0.2 and np.abs(first[:, 1] - lat0).min() < 0.2
    assert not any(k.startswith(("area-", "taken-")) for k in packets)  # no areas here


def test_czml_refuses_overwrite(result, czml):
    path, _ = czml
    before = path.read_bytes()
    with pytest.raises(FileExistsError):
        write_czml(result, path)
    assert path.read_bytes() == before
    write_czml(result, path, force=True)
    assert json.loads(path.read_text(encoding="utf-8"))[0]["id"] == "document"


def test_czml_rejects_bad_step(result, tmp_path):
    with pytest.raises(ValueError, match="step"):
        write_czml(result, tmp_path / "x.czml", step=0.0)


@pytest.mark.parametrize(
    "plot", [plot_plan_ground_tracks, plot_plan_timeline, plot_plan_slack], ids=lambda f: f.__name__
)
def test_plan_figures_are_png(result, tmp_path, plot):
    path = tmp_path / f"{plot.__name__}.png"
    plot(result, path)
    data = path.read_bytes()
    assert len(data) > 1000 and data[:8] == PNG_MAGIC
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary file left


def test_timeline_and_slack_without_battery_or_observations(result, tmp_path):
    empty = Observations(*(np.zeros(0, x.dtype) for x in result.observations))
    bare = PlanResult(
        scenario=result.scenario,
        observations=empty,
        value=0.0,
        bound=0.0,
        gap=0.0,
        bound_converged=True,
        report={"valid": True},
        stats={},
        timings={},
    )
    for plot in (plot_plan_timeline, plot_plan_slack):
        path = tmp_path / f"{plot.__name__}.png"
        plot(bare, path)
        assert path.read_bytes()[:8] == PNG_MAGIC
