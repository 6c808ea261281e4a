"""The outputs of ``jaxspline plan`` under its time limit: what they cost, what is left out.

The plan is the hand-made one of ``test_czml_plot``; the deadline is given in the past
(nothing optional fits) or far ahead (everything does), so no test waits for a clock.
"""

from __future__ import annotations

import json
import time

import pytest
from test_czml_plot import result  # noqa: F401 - the module fixture

from jaxspline.planner.deadline import StageDeadline
from jaxspline.products import output_budget as ob
from jaxspline.products.outputs import write_plan_outputs


def test_every_product_has_a_cost_and_a_remedy(result):  # noqa: F811
    sc = result.scenario
    cost = ob.output_seconds(sc, plots=True, html=True, aem=True, aem_step=10.0)
    assert set(cost) == {"plan files", *ob.PRODUCTS} and set(ob.REMEDIES) == set(ob.PRODUCTS)
    assert all(v > 0 for v in cost.values())
    states = len(sc.satellites) * sc.duration / 10.0
    assert cost["AEM files"] == pytest.approx(ob.AEM_S_PER_STATE * states)
    finer = ob.output_seconds(sc, plots=True, html=True, aem=True, aem_step=1.0)
    assert finer["AEM files"] == pytest.approx(10 * cost["AEM files"])
    bare = ob.output_seconds(sc, plots=False, html=False, aem=False, aem_step=10.0)
    assert set(bare) == {"plan files", "plan.czml"}


def test_past_the_limit_only_the_plan_files_are_written(result, tmp_path):  # noqa: F811
    deadline = StageDeadline(time.monotonic() - 100.0, 10.0)
    page = write_plan_outputs(result, tmp_path, deadline=deadline)
    assert page is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.csv", "plan.json"]
    skipped = json.loads((tmp_path / "plan.json").read_text())["report"]["time_limit"]["skipped"]
    assert [s["what"] for s in skipped] == list(ob.PRODUCTS)  # attitude.png is a figure
    assert all(s["stage"] == "outputs" and s["remedy"] for s in skipped)
    assert skipped[0]["remedy"] == ob.REMEDIES["plan.html"]


def test_a_product_that_fits_is_written_one_that_does_not_is_left_out(
    result,  # noqa: F811
    tmp_path,
    monkeypatch,
):
    deadline = StageDeadline(time.monotonic(), 3600.0)
    real = ob.output_seconds

    def costs(sc, **asked):  # the page and the figures would take 10 days
        slow = ("plan.html", "figures")
        return {k: 1e6 if k in slow else v for k, v in real(sc, **asked).items()}

    monkeypatch.setattr(ob, "output_seconds", costs)
    write_plan_outputs(result, tmp_path, plots=True, aem=False, html=True, deadline=deadline)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.csv", "plan.czml", "plan.json"]
    doc = json.loads((tmp_path / "plan.json").read_text())
    skipped = doc["report"]["time_limit"]["skipped"]
    assert [s["what"] for s in skipped] == ["plan.html", "figures"]
    assert doc["report"]["time_limit"]["limit_s"] == 3600.0


def test_a_write_error_names_the_file(result, tmp_path, monkeypatch):  # noqa: F811
    """A full disk raises ENOSPC from write(), which names no file: the message names
    the product being written (the probe of issue 30 got 'cannot write the outputs')."""
    import errno
    import os

    from jaxspline.products import czml
    from jaxspline.products.outputs import OutputError

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(czml, "write_czml", full)
    with pytest.raises(OutputError, match="cannot write plan.czml: No space left on device"):
        write_plan_outputs(result, tmp_path, plots=False, aem=False, html=False)
