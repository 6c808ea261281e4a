"""The coverage bound's enumeration: its witness pairs are valid for the checker, its
looks pass the access test; and, built from its looks, checks of products that need a
second pass or a near-nadir anchor."""

from __future__ import annotations

import pytest
from _ref_stereo import DATA

from jaxspline.stereo.bound import candidate_looks, coverage_bound
from jaxspline.stereo.case import load_case
from jaxspline.stereo.check import check_solution


def check(case, actions):
    return check_solution(case, {"actions": actions})


pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="training cases not available")


@pytest.fixture(scope="module")
def case1():
    return load_case(DATA / "case_0001")


def test_witness_pairs_are_valid_alone(case1):
    idx = [case1.target_index()[t] for t in ("vegetated_016", "rugged_060", "rugged_047")]
    b = coverage_bound(case1, targets=idx)
    assert "vegetated_016" in b.coverable and "rugged_060" in b.coverable
    assert b.coverage_bound == len(b.coverable) / len(case1.targets)
    for tid in b.coverable:
        tb = b.targets[tid]
        actions = sorted((x.to_action(case1) for x in tb.pair), key=lambda a: a["start_time"])
        r = check_solution(case1, {"actions": actions})
        assert r.num_covered == 1 and r.best[tid] is not None
        assert r.best[tid].quality == pytest.approx(tb.pair_quality, abs=0.01)
        assert tb.pair_quality <= tb.quality_bound <= min(1.0, tb.pair_quality + 0.12)
    assert b.targets["rugged_047"].num_looks == 0  # never in view and in daylight


def test_candidate_looks_pass_the_access_test(case1):
    looks = candidate_looks(case1, 0, step_s=20.0)
    assert len(looks) > 5
    sample = looks[:: max(1, len(looks) // 6)]
    r = check_solution(case1, {"actions": [x.to_action(case1) for x in sample]})
    assert not [v for v in r.violations if v.rule in ("access", "off_nadir", "duration")]


def test_two_passes_of_one_satellite_never_pair(case1):
    looks = candidate_looks(case1, 0, 10.0)
    by_pass: dict = {}
    for x in looks:
        by_pass.setdefault(x.sat, {}).setdefault(x.pass_id, x)
    sat, passes = next((k, v) for k, v in by_pass.items() if len(v) >= 2)
    first, second = list(passes.values())[:2]
    r = check(case1, [first.to_action(case1), second.to_action(case1)])
    assert r.valid, r.violations
    assert len({d.access_interval for d in r.derived}) == 2
    assert r.pairs == [] and r.num_covered == 0


def test_an_anchored_triple_earns_the_scene_bonus(case1):
    """vegetated_016 has an anchored triple among the bound's looks (see test_stereo_bound)."""
    looks = candidate_looks(case1, 0, 10.0)
    anchors = [x for x in looks if x.off_nadir_deg <= 10.0]
    found = None
    for a in anchors:
        same = [x for x in looks if x.sat == a.sat and x.pass_id == a.pass_id and x is not a]
        for i, x in enumerate(same):
            for y in same[i + 1 :]:
                trio = sorted([a, x, y], key=lambda z: z.start_s)
                r = check(case1, [z.to_action(case1) for z in trio])
                if r.valid and any(t.valid for t in r.triples):
                    found = r
                    break
            if found:
                break
        if found:
            break
    assert found is not None
    (t,) = found.triples
    best_edge = max(p.quality for p in found.pairs if p.valid)
    bonus = case1.mission.quality.tri_bonus["vegetated"]
    assert t.anchor and t.valid_pairs >= 2
    assert t.quality == pytest.approx(min(1.0, best_edge + bonus))
    assert found.best["vegetated_016"].quality == pytest.approx(max(t.quality, best_edge))


@pytest.mark.slow
@pytest.mark.parametrize("n", range(1, 6))
def test_every_training_case_has_coverable_targets(n):
    b = coverage_bound(load_case(DATA / f"case_000{n}"))
    assert 0.5 < b.coverage_bound <= 1.0 and b.quality_bound <= b.coverage_bound
