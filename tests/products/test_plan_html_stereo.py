"""plan.html with stereo targets: the view's stereo section and the page's marks and joins.

A small stereo plan: case_0001 of the stereo_imaging training set (131 stereo targets,
10 satellites) cut to its first :data:`HORIZON_S` seconds and planned for a few seconds
(skipped when the case folder is absent). Checked:

* the view's ``stereo`` section names every stereo request with the report's product,
  quality, convergence and overlap; its looks are observations of that target of kind
  "stereo" in time order, as many as the report's looks, and the angle at the target
  between their satellites (mid-imaging) is the report's convergence (the report names
  looks by option ids: this holds the mapping to observation indices to the geometry);
  a plan holding stray looks of a target keeps the product's looks; a scenario without
  stereo targets gets no ``stereo`` key and an otherwise equal view;
* the page (built by ``jaxspline view`` from ``plan.json``, and directly from the result:
  the same stereo data): one marker per stereo target by product kind, one join per
  consecutive looks of a product (sum of looks - 1), bar midpoint to bar midpoint on
  the looks' satellites' rows; joins across satellites from a hand-made view;
* in Chromium (skipped without it unless ``JAXSPLINE_REQUIRE_BROWSER=1``, as
  ``test_plan_html``): no console error or network request, the product colours drawn
  on map and timeline, a click on a stereo target zooms the timeline to its looks, the
  satellite filter still filters the map.
"""

import dataclasses
import io
import itertools
import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from jaxspline.base.elements import geodetic_to_ecef
from jaxspline.cli import main
from jaxspline.geometry.frames import angle_between
from jaxspline.planner.result import Observations
from jaxspline.products import plan_html_stereo as stereo
from jaxspline.products.plan_html import PASS_PAD_S, _plan_page, plan_document, read_plan
from jaxspline.products.plan_html_columns import epoch_ms
from jaxspline.products.plan_view import _mid_positions, view_data

CASE = Path("/work/shared/data/stereo_imaging/train/case_0001")
HORIZON_S = 3.0 * 3600.0
TIME_LIMIT_S = 10.0
CONVERGENCE_TOL_DEG = 0.01  # the report rounds to 1e-4 deg; mid-times are the options'
CHROMIUM = os.environ.get("JAXSPLINE_CHROMIUM") or shutil.which("chromium")
REQUIRE_BROWSER = "JAXSPLINE_REQUIRE_BROWSER"
VIEWPORT = {"width": 1440, "height": 1500}
COLOR_TOL = 12


def _hex_rgb(color: str):
    return tuple(int(color[i : i + 2], 16) for i in (1, 3, 5))


@pytest.fixture(scope="module")
def result():
    if not CASE.is_dir():
        pytest.skip(f"stereo case not found: {CASE}")
    import jaxspline
    from jaxspline.stereo.adapter import case_scenario

    sc = case_scenario(CASE)
    tg = dataclasses.replace(sc.targets, t_hi=np.minimum(sc.targets.t_hi, HORIZON_S))
    sc = dataclasses.replace(sc, duration=HORIZON_S, targets=tg)
    res = jaxspline.plan(sc, time_limit=TIME_LIMIT_S, progress=False)
    assert any(r["product"] for r in res.report["stereo"]), "no stereo product planned"
    return res


@pytest.fixture(scope="module")
def page(result, tmp_path_factory):
    """plan.json written as `jaxspline plan` does, and plan.html from `jaxspline view`."""
    d = tmp_path_factory.mktemp("stereo_html")
    result.to_json(d / "plan.json", extra={"view": view_data(result)})
    assert main(["view", str(d / "plan.json")]) == 0
    return d, read_plan(d / "plan.json"), d / "plan.html"


def _convergences(result, looks, target: int) -> list[float]:
    """Angles [deg] at the target between the satellites of every two looks."""
    sc, obs = result.scenario, result.observations
    r = _mid_positions(sc, obs)
    tg = sc.targets
    g = geodetic_to_ecef(tg.lat[target], tg.lon[target], tg.alt[target])
    pairs = itertools.combinations(looks, 2)
    return [math.degrees(float(angle_between(r[i] - g, r[j] - g))) for i, j in pairs]


def test_view_stereo_entries_match_the_report(result, page):
    _, doc, _ = page
    view, rows, report = doc["view"]["stereo"], doc["observations"], result.report["stereo"]
    sc = result.scenario
    assert [e["target"] for e in view] == [r["target"] for r in report]
    assert [e["product"] for e in view] == [r["product"] for r in report]
    names = list(sc.targets.name)
    for e, rep, req in zip(view, report, sc.stereo, strict=True):
        t = int(req.target)
        assert e["target"] == names[t]
        assert e["lon_deg"] == pytest.approx(math.degrees(sc.targets.lon[t]), abs=1e-4)
        assert e["lat_deg"] == pytest.approx(math.degrees(sc.targets.lat[t]), abs=1e-4)
        for key in ("candidates", "quality", "convergence_deg", "overlap"):
            assert e[key] == rep.get(key), key
        assert len(e["looks"]) == len(rep["looks"])
        if not e["product"]:
            assert e["looks"] == []
            continue
        assert len(e["looks"]) == {"pair": 2, "tri": 3}[e["product"]]
        for i in e["looks"]:
            assert rows[i]["target"] == e["target"] and rows[i]["kind"] == "stereo"
        starts = [rows[i]["start_s"] for i in e["looks"]]
        assert starts == sorted(starts)
        conv = _convergences(result, e["looks"], t)
        assert min(abs(c - e["convergence_deg"]) for c in conv) < CONVERGENCE_TOL_DEG


def test_stray_looks_keep_the_products_looks(result):
    """Looks of a target that its product does not use (added here: the first look of the
    earliest pair and the last of the latest, moved to a pair in between) are not taken
    for the product's looks, neither the earlier nor the later."""
    view = view_data(result)["stereo"]
    obs = result.observations
    pairs = sorted(
        (e for e in view if e["product"] == "pair"), key=lambda e: obs.start[e["looks"][0]]
    )
    assert len(pairs) >= 3
    first, a, last = pairs[0], pairs[len(pairs) // 2], pairs[-1]
    t = list(result.scenario.targets.name).index(a["target"])
    grown = obs
    for j in (first["looks"][0], last["looks"][-1]):
        extra = [x[j] for x in obs]
        extra[1] = t  # the target
        grown = Observations(*(np.append(x, v) for x, v in zip(grown, extra, strict=True)))
    assert obs.start[first["looks"][0]] < obs.start[a["looks"][0]]
    assert obs.start[last["looks"][-1]] > obs.start[a["looks"][-1]]
    got = {
        e["target"]: e["looks"]
        for e in view_data(dataclasses.replace(result, observations=grown))["stereo"]
    }
    assert got[a["target"]] == a["looks"]
    assert got[first["target"]] == first["looks"] and got[last["target"]] == last["looks"]


def test_view_without_stereo_targets_is_unchanged(result):
    """The same plan with its stereo targets made point targets: no ``stereo`` key, the
    rest of the view as with them (but the targets' kinds)."""
    sc = result.scenario
    tg = dataclasses.replace(sc.targets, kind=np.zeros_like(sc.targets.kind))
    plain = view_data(
        dataclasses.replace(result, scenario=dataclasses.replace(sc, targets=tg, stereo=()))
    )
    full = view_data(result)
    assert "stereo" not in plain and "stereo" in full
    assert set(full["targets"]["kind"]) == {"stereo"}
    full["targets"]["kind"] = plain["targets"]["kind"]
    assert plain == {k: v for k, v in full.items() if k != "stereo"}


def _sources(doc) -> dict:
    layout = _plan_page(doc)
    names = ("stereo_targets", "stereo_joins", "stereo_looks")
    return {n: dict(layout.select_one({"name": n}).data_source.data) for n in names}


def test_page_marks_stereo_targets_and_joins_their_looks(result, page):
    _, doc, html = page
    text = html.read_text(encoding="utf-8")
    for name in ("stereo_targets", "stereo_joins", "stereo_looks", "stereo_join_legend"):
        assert f'"{name}"' in text, name
    src = _sources(doc)
    view, rows = doc["view"]["stereo"], doc["observations"]
    marks = src["stereo_targets"]
    assert marks["target"] == [e["target"] for e in view]
    want = [stereo.MARKERS[e["product"]] for e in view]
    assert marks["marker"] == want
    assert marks["color"] == [stereo.COLORS[e["product"]] for e in view]
    joins = src["stereo_joins"]
    products = [e for e in view if e["product"]]
    assert len(joins["x0"]) == sum(len(e["looks"]) - 1 for e in products) > 0
    assert len(src["stereo_looks"]["x"]) == sum(len(e["looks"]) for e in products)
    epoch = epoch_ms(doc)
    k = 0
    for e in products:
        mids = [epoch + 500.0 * (rows[i]["start_s"] + rows[i]["end_s"]) for i in e["looks"]]
        for a in range(len(e["looks"]) - 1):
            i, j = e["looks"][a], e["looks"][a + 1]
            assert joins["x0"][k] == pytest.approx(mids[a], abs=1e-3)
            assert joins["x1"][k] == pytest.approx(mids[a + 1], abs=1e-3)
            assert list(joins["y0"][k]) == [rows[i]["satellite"], stereo.JOIN_OFFSET]
            assert list(joins["y1"][k]) == [rows[j]["satellite"], stereo.JOIN_OFFSET]
            assert joins["target"][k] == e["target"]
            k += 1
    # `jaxspline view` on plan.json draws what the result itself gives
    direct = _sources(plan_document(result))
    for name, cols in src.items():
        assert set(cols) == set(direct[name])
        for key, v in cols.items():
            if isinstance(v, np.ndarray) and v.dtype.kind == "f":
                np.testing.assert_allclose(v, direct[name][key], atol=1e-3, err_msg=key)
            else:
                assert list(map(_plain, v)) == list(map(_plain, direct[name][key])), key


def _plain(x):
    return list(x) if isinstance(x, list | tuple) else x


def test_joins_cross_satellites_and_skip_bad_looks():
    """Hand-made view: a triple over two satellites, a pair with a look index outside
    the observations, a target without product."""
    sats = ["a", "b"]
    obs = {
        "sat": np.array([0, 0, 1]),
        "satellite": [sats[k] for k in (0, 0, 1)],
        "t0": np.array([1000.0, 5000.0, 3000.0]),
        "t1": np.array([2000.0, 6000.0, 4000.0]),
        "start": ["s0", "s1", "s2"],
    }
    view = [
        {"target": "T", "lon_deg": 1.0, "lat_deg": 2.0, "product": "tri", "looks": [0, 1, 2],
         "quality": 0.9, "convergence_deg": 12.0, "overlap": 0.95, "candidates": 4},
        {"target": "P", "lon_deg": 3.0, "lat_deg": 4.0, "product": "pair", "looks": [1, 7],
         "quality": 0.5, "convergence_deg": 20.0, "overlap": 0.9, "candidates": 1},
        {"target": "N", "lon_deg": 5.0, "lat_deg": 6.0, "product": None, "looks": [],
         "quality": None, "candidates": 0},
        "not an entry",
    ]  # fmt: skip
    doc = {"view": {"stereo": view}}
    j = stereo.join_columns(doc, obs)
    assert j["x0"] == [1500.0, 3500.0] and j["x1"] == [3500.0, 5500.0]  # time order
    assert j["y0"] == [["a", stereo.JOIN_OFFSET], ["b", stereo.JOIN_OFFSET]]
    assert j["y1"] == [["b", stereo.JOIN_OFFSET], ["a", stereo.JOIN_OFFSET]]
    assert j["target"] == ["T", "T"] and j["color"] == [stereo.TRI_COLOR] * 2
    m = stereo.stereo_columns(doc, obs)
    assert m["target"] == ["T", "P", "N"]
    assert m["marker"] == ["diamond", "triangle", "inverted_triangle"]
    assert m["looks"] == [3, 1, 0]
    assert m["product"] == ["triple", "pair", "none (0 candidates)"]
    assert m["quality"] == ["0.900", "0.500", "-"]
    np.testing.assert_array_equal(m["t0"][:2], [1000.0, 5000.0])
    np.testing.assert_array_equal(m["t1"][:2], [6000.0, 6000.0])
    assert np.isnan(m["t0"][2]) and np.isnan(m["t1"][2])
    assert "3 stereo targets" in stereo.stereo_summary(doc)
    assert stereo.stereo_summary({"view": {}}) == ""
    assert stereo.join_columns({"view": {}}, obs)["x0"] == []


# --- browser ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def browser():
    if not (CHROMIUM and os.path.isfile(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        if os.environ.get(REQUIRE_BROWSER, "").strip() not in ("", "0"):
            pytest.fail(f"chromium not found ({REQUIRE_BROWSER} requires it)")
        pytest.skip(f"chromium not found; set {REQUIRE_BROWSER}=1 to require it")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def loaded(browser, page):
    """The page opened offline: (playwright page, console messages, blocked requests)."""
    _, _, html = page
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
        f"() => {{ const m = Bokeh.documents[0].get_model_by_name('{name}'); return {expr} }}"
    )


def _crop(pg, img, name: str):
    b = pg.evaluate(
        """(name) => {
          const v = Bokeh.index.find_one(Bokeh.documents[0].get_model_by_name(name))
          const c = v.canvas_view.el.getBoundingClientRect()
          const f = v.frame.bbox
          return {left: c.left + f.left, top: c.top + f.top, width: f.width, height: f.height}
        }""",
        name,
    )
    top, left = int(b["top"]), int(b["left"])
    return img[top : top + int(b["height"]), left : left + int(b["width"])]


def _has_color(pixels, rgb) -> int:
    return int(np.sum(np.all(np.abs(pixels[..., :3].astype(int) - rgb) <= COLOR_TOL, axis=-1)))


def test_stereo_page_renders_in_the_browser(loaded, page):
    from PIL import Image

    pg, messages, blocked = loaded
    d, doc, _ = page
    assert [m for m in messages if m[0] in ("error", "pageerror")] == []
    assert blocked == []
    view = doc["view"]["stereo"]
    products = [e for e in view if e["product"]]
    assert _model(pg, "stereo_targets", "m.data_source.data.x.length") == len(view)
    n_joins = sum(len(e["looks"]) - 1 for e in products)
    assert _model(pg, "stereo_joins", "m.data_source.data.x0.length") == n_joins
    shot = d / "plan_html_stereo_screenshot.png"  # kept as a test artifact
    pg.screenshot(path=str(shot), full_page=True)
    img = np.asarray(Image.open(io.BytesIO(shot.read_bytes())).convert("RGB"))
    pair = _hex_rgb(stereo.PAIR_COLOR)
    if any(e["product"] == "pair" for e in view):
        assert _has_color(_crop(pg, img, "map"), pair) > 20
        assert _has_color(_crop(pg, img, "timeline"), pair) > 5


def _isolated_product(view) -> int:
    """The stereo target with a product farthest from every other stereo target [deg]
    (and clear of the map's legend, bottom left): a click hits it alone."""
    xy = np.array([[e["lon_deg"], e["lat_deg"]] for e in view])

    def room(k):
        others = np.delete(xy, k, axis=0)
        return float(np.min(np.hypot(*(others - xy[k]).T))) if len(others) else 1e9

    ok = [k for k, e in enumerate(view) if e["product"] and e["lat_deg"] > -50.0]
    return max(ok, key=room)


def test_click_on_a_stereo_target_zooms_to_its_looks_and_filters_still_work(loaded, page):
    pg, messages, _ = loaded
    _, doc, _ = page
    view, rows = doc["view"]["stereo"], doc["observations"]
    k = _isolated_product(view)
    xy = pg.evaluate(
        """(k) => {
          const doc = Bokeh.documents[0]
          const v = Bokeh.index.find_one(doc.get_model_by_name("map"))
          const d = doc.get_model_by_name("stereo_targets").data_source.data
          const c = v.canvas_view.el.getBoundingClientRect()
          return {x: c.left + v.frame.x_scale.compute(d.x[k]),
                  y: c.top + v.frame.y_scale.compute(d.y[k])}
        }""",
        k,
    )
    pg.mouse.click(xy["x"], xy["y"])
    pg.wait_for_timeout(300)
    epoch = epoch_ms(doc)
    looks = view[k]["looks"]
    lo = epoch + 1e3 * (min(rows[i]["start_s"] for i in looks) - PASS_PAD_S)
    hi = epoch + 1e3 * (max(rows[i]["end_s"] for i in looks) + PASS_PAD_S)
    xr = _model(pg, "timeline", "[m.x_range.start, m.x_range.end]")
    x_bounds = _model(pg, "timeline", "m.x_range.bounds")
    assert xr == pytest.approx([max(lo, x_bounds[0]), min(hi, x_bounds[1])], abs=1.0)
    _model(pg, "timeline", f"m.x_range.setv({{start: {x_bounds[0]}, end: {x_bounds[1]}}})")
    shown = "m.view.filter.booleans.filter((b) => b).length"
    assert _model(pg, "targets_imaged", shown) == len(rows)
    first = doc["view"]["satellites"][0]["name"]
    pg.get_by_text(first, exact=True).click()  # uncheck the first satellite
    pg.wait_for_timeout(200)
    assert _model(pg, "targets_imaged", shown) == sum(o["satellite"] != first for o in rows)
    pg.get_by_text("all satellites").click()
    pg.wait_for_timeout(200)
    assert _model(pg, "targets_imaged", shown) == len(rows)
    assert [m for m in messages if m[0] in ("error", "pageerror")] == []
