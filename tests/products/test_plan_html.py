"""plan.html in a real browser: headless Chromium opens the page of a small plan offline.

The plan is made by hand (as in test_czml_plot: one circular orbit, one TLE, a dozen
targets with strips, an area with its samples and one area strip, a battery curve),
written as ``plan.json`` with its
``"view"`` section, and the page is rebuilt from that file by ``jaxspline view`` -
the path a user takes. Chromium (the Debian package ``chromium`` on the ``PATH``, or the
program ``$JAXSPLINE_CHROMIUM`` names) is driven by Playwright without a browser download
(``executable_path``); it loads the page from a ``file://`` URL in an offline context
where every non-file request is aborted and recorded. Without a browser the tests that
need one are skipped, saying so, unless ``JAXSPLINE_REQUIRE_BROWSER=1`` requires them
(``.ci/run`` installs Chromium and sets it): then they fail.

Checked: no console error and no network request; the map and timeline canvases are
drawn (screenshot pixels of the land and satellite colours in their regions; the
screenshot is kept in the test's tmp dir); the page's data hold one imaged-target glyph
per observation with plan.json's numbers; hovering a target shows its tooltip; the
satellite check boxes and the timeline's time range filter the map; the header's
numbers equal plan.json's.
"""

import datetime as dt
import io
import json
import os
import shutil

import numpy as np
import pytest

from jaxspline.base.elements import circular_orbit
from jaxspline.cli import main
from jaxspline.kernels.limits import AxisLimits
from jaxspline.planner.result import Observations, PlanResult
from jaxspline.products.plan_html import PASS_PAD_S, plan_document, read_plan, write_plan_html
from jaxspline.products.plan_view import view_data
from jaxspline.readers.mission import Area, Satellite, Scenario, make_targets

ISS_TLE = (
    "1 25544U 98067A   26103.50000000  .00016717  00000-0  10270-3 0  9005",
    "2 25544  51.6400 208.9163 0006317  69.9862  25.2906 15.49560000 10001",
)
EPOCH = dt.datetime(2026, 4, 13, 12, 0, tzinfo=dt.UTC)
DURATION = 3.0 * 3600.0
CHROMIUM = os.environ.get("JAXSPLINE_CHROMIUM") or shutil.which("chromium")
REQUIRE_BROWSER = "JAXSPLINE_REQUIRE_BROWSER"  # "1": a missing browser fails the tests
VIEWPORT = {"width": 1440, "height": 1400}
LAND_RGB = (0xEF, 0xEA, 0xE0)
COLOR_TOL = 12  # per channel, antialiasing


def _hex_rgb(color: str):
    return tuple(int(color[i : i + 2], 16) for i in (1, 3, 5))


@pytest.fixture(scope="module")
def result():
    rng = np.random.default_rng(11)
    sats = (
        Satellite("alpha", circular_orbit(600e3, raan=0.3)),
        Satellite(
            "beta",
            ISS_TLE,
            model="eigen_axis",
            limits=AxisLimits(np.radians(2.0), np.radians(1.0)),
        ),
    )
    n = 14
    kind = np.r_[np.where(np.arange(n) % 5 == 0, 1, 0), 2]  # the last target: the area
    lat = rng.uniform(-50.0, 50.0, n)
    lon = np.linspace(-170.0, 170.0, n) + rng.uniform(-5.0, 5.0, n)  # spread: hover one
    alat, alon = lat[11] + 3.0, lon[11] + 3.0  # the area, beside a target not imaged
    targets = make_targets(
        kind,
        np.radians(np.r_[lat, alat]),
        np.radians(np.r_[lon, alon]),
        duration=np.r_[np.full(n, 10.0), 0.0],
        length=60e3,
        azimuth=np.radians(30.0),
        value=np.r_[rng.integers(1, 10, n).astype(float), 5.0],
        name=[f"site-{i:02d}" for i in range(n)] + ["block"],
    )
    ring = [
        [alon - 0.6, alat - 0.6],
        [alon + 0.9, alat - 0.6],
        [alon + 0.9, alat + 0.9],
        [alon - 0.6, alat + 0.9],
        [alon - 0.6, alat - 0.6],
    ]
    area = Area(
        name="block", target=n, geometry={"type": "Polygon", "coordinates": [ring]}, spacing=20e3
    )
    sc = Scenario("html-test", EPOCH, DURATION, sats, targets, areas=(area,))
    start = np.array([300.0, 1800.0, 7000.0, 8000.0, 900.0, 5000.0, 9000.0])
    tgt = np.array([0, 2, 4, n, 5, 7, 9])  # the area strip last of alpha's
    nan = np.nan
    obs = Observations(
        sat=np.array([0, 0, 0, 0, 1, 1, 1]),
        target=tgt,
        start=start,
        end=start + np.array([8.0, 10.0, 12.5, 30.0, 9.0, 10.0, 10.0]),
        maneuver=np.array([30.0, 42.0, 18.0, 20.0, 25.0, 60.0, 12.0]),
        slack=np.array([0.0, 4.0, 350.0, 1.0, 0.02, 2500.0, 7.5]),
        value=np.r_[targets.value[[0, 2, 4]], 2.5, targets.value[[5, 7, 9]]],
        speed=np.array([7000.0, 0, 0, 0, 6500.0, 0, 0]),
        roll=np.array([nan, nan, nan, np.radians(20.0), nan, nan, nan]),
        pitch=np.array([nan, nan, nan, np.radians(-5.0), nan, nan, nan]),
    )
    # the area strip's swept ground (a closed ring) and the area's samples, half covered
    strip = np.array([[alon - 0.5, alat - 0.5], [alon + 0.8, alat - 0.5], [alon + 0.8, alat],
                      [alon - 0.5, alat], [alon - 0.5, alat - 0.5]])  # fmt: skip
    footprints = [None, None, None, (strip[:, 0], strip[:, 1]), None, None, None]
    samples = {
        "lon_deg": alon + np.array([-0.3, 0.3, -0.3, 0.3]),
        "lat_deg": alat + np.array([-0.3, -0.3, 0.6, 0.6]),
        "covered": np.array([True, True, False, False]),
    }
    tb = np.linspace(0.0, DURATION, 60)
    r = PlanResult(
        scenario=sc,
        observations=obs,
        value=float(obs.value.sum()),
        bound=float(obs.value.sum()) + 3.5,
        gap=3.5,
        bound_converged=False,
        report={
            "valid": True,
            "checked": len(obs),
            "dropped": {"check": 0, "battery": 0, "joins": 1},
            "violations": [],
            "min_slack_s": 0.0,
            "min_battery_wh": {"alpha": 91.25},
            "joins": {
                "joins": 6,
                "retimed": 1,
                "rejected": 1,
                "violating": 0,
                "max_rate_ratio": 0.9123,
                "max_accel_ratio": 0.8765,
                "max_jerk_ratio": 0.5,
            },
            "areas": [
                {
                    "area": "block",
                    "priority": 5.0,
                    "samples": 4,
                    "samples_covered": 2,
                    "covered_share": 0.5,
                    "value": 2.5,
                    "strips": 1,
                    "reachable_share": 1.0,
                    "min_share": None,
                }
            ],
        },
        stats={"windows": 40, "options": 120, "near_pairs": 77, "bound_status": "time"},
        timings={"orbits": 0.01, "search": 1.5, "repair": 0.25},
        battery={"alpha": (tb, 100.0 - 5.0 * np.sin(tb / 2000.0))},
        areas=[samples],
        footprints=footprints,
    )
    return r


@pytest.fixture(scope="module")
def page(result, tmp_path_factory):
    """plan.json written as `jaxspline plan` does, and plan.html from `jaxspline view`."""
    d = tmp_path_factory.mktemp("html")
    result.to_json(d / "plan.json", extra={"view": view_data(result)})
    assert main(["view", str(d / "plan.json")]) == 0
    return d, read_plan(d / "plan.json"), d / "plan.html"


@pytest.fixture(scope="module")
def browser():
    if not (CHROMIUM and os.path.isfile(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        if os.environ.get(REQUIRE_BROWSER, "").strip() not in ("", "0"):
            pytest.fail(
                f"chromium not found ({REQUIRE_BROWSER} requires it): apt-get install -y "
                "chromium (.ci/run does), or set JAXSPLINE_CHROMIUM to the browser's path"
            )
        pytest.skip(f"chromium not found; set {REQUIRE_BROWSER}=1 to require it")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def loaded(browser, page):
    """The page opened offline: (playwright page, console messages, blocked requests)."""
    d, _, html = page
    ctx = browser.new_context(viewport=VIEWPORT, offline=True)
    blocked = []

    def route(r):
        if r.request.url.startswith("file:"):
            return r.continue_()
        blocked.append(r.request.url)
        return r.abort()

    ctx.route("**/*", route)
    pg = ctx.new_page()
    messages = []
    pg.on("console", lambda m: messages.append((m.type, m.text)))
    pg.on("pageerror", lambda e: messages.append(("pageerror", str(e))))
    pg.goto(html.as_uri())
    pg.wait_for_function(
        "() => window.Bokeh && Bokeh.documents.length > 0 && Bokeh.documents[0].is_idle",
        timeout=30_000,
    )
    yield pg, messages, blocked
    ctx.close()


def _model(pg, name: str, expr: str):
    return pg.evaluate(
        f"() => {{ const m = Bokeh.documents[0].get_model_by_name({json.dumps(name)}); "
        f"return {expr} }}"
    )


def _canvas_box(pg, name: str) -> dict:
    """Page coordinates of a figure's canvas and its frame (the plotting area)."""
    return pg.evaluate(
        """(name) => {
          const fig = Bokeh.documents[0].get_model_by_name(name)
          const v = Bokeh.index.find_one(fig)
          const c = v.canvas_view.el.getBoundingClientRect()
          const f = v.frame.bbox
          return {left: c.left + f.left, top: c.top + f.top, width: f.width, height: f.height}
        }""",
        name,
    )


def _screen_xy(pg, renderer: str, i: int) -> dict:
    return pg.evaluate(
        """([renderer, i]) => {
          const doc = Bokeh.documents[0]
          const v = Bokeh.index.find_one(doc.get_model_by_name("map"))
          const d = doc.get_model_by_name(renderer).data_source.data
          const c = v.canvas_view.el.getBoundingClientRect()
          return {x: c.left + v.frame.x_scale.compute(d.x[i]),
                  y: c.top + v.frame.y_scale.compute(d.y[i])}
        }""",
        [renderer, i],
    )


def _has_color(pixels: np.ndarray, rgb) -> int:
    return int(np.sum(np.all(np.abs(pixels[..., :3].astype(int) - rgb) <= COLOR_TOL, axis=-1)))


def test_page_opens_offline_without_errors_and_draws(loaded, page, tmp_path_factory):
    from PIL import Image

    pg, messages, blocked = loaded
    d, doc, _ = page
    errors = [m for m in messages if m[0] in ("error", "pageerror")]
    assert errors == []
    assert blocked == []  # self-contained: nothing but the file itself
    shot = d / "plan_html_screenshot.png"  # kept as a test artifact
    pg.screenshot(path=str(shot), full_page=True)
    img = np.asarray(Image.open(io.BytesIO(shot.read_bytes())).convert("RGB"))
    colors = [_hex_rgb(s["color"]) for s in doc["view"]["satellites"]]
    for fig, must in (("map", [LAND_RGB, colors[0], colors[1]]), ("timeline", colors)):
        b = _canvas_box(pg, fig)
        crop = img[
            int(b["top"]) : int(b["top"] + b["height"]),
            int(b["left"]) : int(b["left"] + b["width"]),
        ]
        assert crop.size and crop.reshape(-1, 3).std(axis=0).max() > 10.0, fig  # not blank
        for rgb in must:
            assert _has_color(crop, rgb) > 20, (fig, rgb)


def test_imaged_target_glyphs_are_the_observations(loaded, page):
    pg, _, _ = loaded
    _, doc, _ = page
    rows = doc["observations"]
    data = _model(pg, "targets_imaged", "m.data_source.data")
    assert len(data["x"]) == len(rows) == doc["summary"]["observations"]
    assert data["target"] == [o["target"] for o in rows]
    assert data["satellite"] == [o["satellite"] for o in rows]
    for col, key in (("maneuver", "maneuver_s"), ("slack", "slack_s"), ("priority", "value")):
        got = _model(pg, "targets_imaged", f"Array.from(m.data_source.data.{col})")
        assert got == pytest.approx([o[key] for o in rows], abs=1e-9), col
    off = _model(pg, "targets_imaged", "Array.from(m.data_source.data.off_nadir)")
    assert off == pytest.approx(doc["view"]["observations"]["off_nadir_deg"], abs=1e-9)
    assert data["start"] == [o["start_utc"][:23].replace("T", " ") for o in rows]
    epoch = dt.datetime.fromisoformat(doc["view"]["epoch_utc"]).timestamp() * 1e3
    t0 = _model(pg, "imaging", "Array.from(m.data_source.data.t0)")
    assert t0 == pytest.approx([epoch + 1e3 * o["start_s"] for o in rows], abs=1e-3)
    n_targets = doc["summary"]["targets"]
    n_free = _model(pg, "targets_not_imaged", "m.data_source.data.x.length")
    assert n_free == n_targets - len({o["target"] for o in rows})
    assert _model(pg, "footprints", "m.data_source.data.xs.length") == len(rows)
    assert _model(pg, "areas", "m.data_source.data.name") == ["block"]
    smp = doc["view"]["areas"][0]["samples"]
    for flag, name in ((1, "area_samples_covered"), (0, "area_samples_uncovered")):
        xs = _model(pg, name, "Array.from(m.data_source.data.x)")
        want = [x for x, c in zip(smp["lon_deg"], smp["covered"], strict=True) if c == flag]
        assert xs == pytest.approx(want, abs=1e-9), name
    assert _model(pg, "strips", "m.data_source.data.xs.length") == sum(
        k == "strip" for k in doc["view"]["targets"]["kind"]
    )
    level = _model(pg, "battery-alpha", "Array.from(m.data_source.data.y)")
    assert level == pytest.approx(doc["view"]["battery"]["alpha"]["level_wh"], abs=1e-9)


def test_hover_on_a_target_shows_its_tooltip_and_a_click_zooms_to_its_pass(loaded, page):
    pg, _, _ = loaded
    _, doc, _ = page
    i = 2  # an isolated point target (the targets are spread in longitude)
    name = doc["observations"][i]["target"]
    xy = _screen_xy(pg, "targets_imaged", i)
    pg.mouse.move(xy["x"] - 30, xy["y"] - 30)
    pg.mouse.move(xy["x"], xy["y"], steps=3)
    tip = pg.locator(".bk-Tooltip", has_text=name)
    tip.first.wait_for(state="visible", timeout=5_000)
    text = tip.first.evaluate("(e) => (e.shadowRoot ?? e).textContent")  # Bokeh: shadow DOM
    o = doc["observations"][i]
    assert o["satellite"] in text and "off-nadir" in text and "slack" in text
    assert o["start_utc"][11:19] in text  # start time (UTC)
    pg.mouse.click(xy["x"], xy["y"])  # a click zooms the timeline to the pass
    pg.wait_for_timeout(200)
    xr = _model(pg, "timeline", "[m.x_range.start, m.x_range.end]")
    epoch = dt.datetime.fromisoformat(doc["view"]["epoch_utc"]).timestamp() * 1e3
    pad = 1e3 * PASS_PAD_S
    assert xr == pytest.approx([epoch + 1e3 * o["start_s"] - pad, epoch + 1e3 * o["end_s"] + pad])
    assert _model(pg, "targets_imaged", "m.view.filter.booleans.filter((b) => b).length") == 1
    _model(pg, "timeline", f"m.x_range.setv({{start: {epoch}, end: {epoch + 1e3 * DURATION}}})")
    pg.mouse.move(5, 5)


def test_satellite_and_time_range_filter_the_map(loaded, page):
    pg, _, _ = loaded
    _, doc, _ = page
    rows = doc["observations"]
    shown = "m.view.filter.booleans.filter((b) => b).length"
    assert _model(pg, "targets_imaged", shown) == len(rows)
    pg.get_by_text("beta", exact=True).click()  # uncheck the second satellite
    pg.wait_for_timeout(200)
    assert _model(pg, "satellite_filter", "m.active") == [0]
    assert _model(pg, "targets_imaged", shown) == sum(o["satellite"] == "alpha" for o in rows)
    n_alpha = _model(pg, "footprints", shown)
    assert n_alpha == sum(o["satellite"] == "alpha" for o in rows)
    epoch = dt.datetime.fromisoformat(doc["view"]["epoch_utc"]).timestamp() * 1e3
    _model(pg, "timeline", f"m.x_range.setv({{start: {epoch + 1.5e6}, end: {epoch + 7.5e6}}})")
    pg.wait_for_timeout(200)
    inside = [o for o in rows if o["satellite"] == "alpha" and 1.5e3 <= o["end_s"]]
    inside = [o for o in inside if o["start_s"] <= 7.5e3]
    assert _model(pg, "targets_imaged", shown) == len(inside) == 2
    assert "alpha" in _model(pg, "filter_status", "m.text")
    pg.get_by_text("all satellites").click()
    _model(pg, "timeline", f"m.x_range.setv({{start: {epoch}, end: {epoch + 1e3 * DURATION}}})")
    pg.wait_for_timeout(200)
    assert _model(pg, "targets_imaged", shown) == len(rows)


def test_header_numbers_equal_plan_json(loaded, page):
    pg, _, _ = loaded
    _, doc, _ = page
    cells = pg.evaluate(
        """() => {
          const out = {}
          const v = Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name("header"))
          for (const e of v.shadow_el.querySelectorAll("[data-key]")) {
            out[e.dataset.key] = e.textContent
          }
          return out
        }"""
    )
    s, rep = doc["summary"], doc["report"]
    expect = {
        "scenario": s["scenario"],
        "satellites": s["satellites"],
        "targets": s["targets"],
        "observations": s["observations"],
        "value": s["value"],
        "total_value": s["total_value"],
        "bound": s["bound"],
        "gap": s["gap"],
        "checked": rep["checked"],
        "violations": len(rep["violations"]),
        "min_slack_s": rep["min_slack_s"],
        "min_battery_wh.alpha": rep["min_battery_wh"]["alpha"],
        "joins": rep["joins"]["joins"],
        "joins_retimed": rep["joins"]["retimed"],
        "joins_rejected": rep["joins"]["rejected"],
        "max_rate_ratio": rep["joins"]["max_rate_ratio"],
        "windows": doc["stats"]["windows"],
        "near_pairs": doc["stats"]["near_pairs"],
        "t_search": doc["timings_s"]["search"],
        "duration_h": DURATION / 3600.0,
    }
    for key, want in expect.items():
        assert key in cells, key
        if isinstance(want, str):
            assert cells[key] == want
        else:
            assert float(cells[key]) == pytest.approx(want, rel=5e-3, abs=1e-12), key
    assert cells["valid"] == "valid"
    assert float(cells["gap_percent"]) == pytest.approx(100 * s["gap"] / s["bound"], rel=5e-3)


def test_plan_json_view_holds_the_areas_samples_and_strip_footprints(result, page):
    """The view of plan.json (what the page draws): the area's polygon and samples with
    their covered flags, the area strip's swept ring as its footprint, its off-nadir
    angle from its roll and pitch."""
    _, doc, _ = page
    (area,) = doc["view"]["areas"]
    assert area["name"] == "block" and area["geometry"] == result.scenario.areas[0].geometry
    smp = result.areas[0]
    assert area["samples"]["covered"] == [1, 1, 0, 0]
    np.testing.assert_allclose(area["samples"]["lon_deg"], smp["lon_deg"], atol=1e-4)
    np.testing.assert_allclose(area["samples"]["lat_deg"], smp["lat_deg"], atol=1e-4)
    feet = doc["view"]["observations"]["footprint"]
    i = [o["kind"] for o in doc["observations"]].index("area")
    np.testing.assert_allclose(feet[i]["lon_deg"], result.footprints[i][0], atol=1e-4)
    np.testing.assert_allclose(feet[i]["lat_deg"], result.footprints[i][1], atol=1e-4)
    off = doc["view"]["observations"]["off_nadir_deg"][i]
    want = np.degrees(np.arccos(np.cos(np.radians(20.0)) * np.cos(np.radians(5.0))))
    assert off == pytest.approx(want, abs=1e-3)  # the view rounds to 3 decimals
    row = doc["observations"][i]
    assert (row["roll_deg"], row["pitch_deg"], row["area_covered_share"]) == (20.0, -5.0, 0.5)
    assert doc["report"]["areas"][0]["covered_share"] == 0.5


def test_write_plan_html_matches_view_and_refuses_overwrite(result, page, tmp_path, capsys):
    d, doc, html = page
    out = write_plan_html(result, tmp_path / "plan.html")
    assert out.stat().st_size == pytest.approx(html.stat().st_size, rel=0.01)
    with pytest.raises(FileExistsError, match="--force"):
        write_plan_html(result, out)
    before = html.read_bytes()
    assert main(["view", str(d / "plan.json")]) == 2  # exists, no --force
    assert "--force" in capsys.readouterr().err and html.read_bytes() == before
    assert main(["view", str(d / "plan.json"), "-o", str(out), "--force"]) == 0
    assert plan_document(result)["view"] == doc["view"]
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporaries


def test_view_of_a_plan_json_without_view_section(result, tmp_path, capsys):
    """plan.json of an older jaxspline: header and timeline, the map has coastlines only."""
    result.to_json(tmp_path / "plan.json")
    assert main(["view", str(tmp_path / "plan.json")]) == 0
    text = (tmp_path / "plan.html").read_text(encoding="utf-8")
    assert "targets_imaged" in text and "timeline" in text
    bad = tmp_path / "bad.json"
    bad.write_text('{"summary": {}}', encoding="utf-8")
    assert main(["view", str(bad)]) == 2
    assert "missing report, observations" in capsys.readouterr().err
    assert main(["view", str(tmp_path / "missing.json")]) == 2


def test_ci_requires_the_browser_and_runs_the_readmes_test_command():
    """``.ci/run`` sets the variable that makes a missing browser fail these tests, then
    runs the README's test command (command 2 of its quick start) as written there."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    readme = (root / "README.md").read_text(encoding="utf-8")
    quick = readme.split("[start:quickstart]", 1)[1].split("[end:quickstart]", 1)[0]
    command = next(line for line in quick.splitlines() if "pytest" in line)
    ci = (root / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    assert command in ci, command
    assert f"export {REQUIRE_BROWSER}=1" in ci[: ci.index(command)]
