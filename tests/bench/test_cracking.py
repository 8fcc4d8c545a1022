"""``geofrac bench cracking``: ``--set`` reaches every case; contact figures are reported."""

import json

import pytest


@pytest.fixture
def jaeger_case(monkeypatch):
    """A small contact case: jobs/jaeger_joint.toml (one joint, crack-face contact on)."""
    from geofrac.bench import cracking

    monkeypatch.setitem(cracking.CASES, "jaeger", ("jaeger_joint", ()))


def _bench(tmp_path, *overrides: str) -> dict:
    from geofrac.cli import main

    out = tmp_path / "c.json"
    sets = [a for o in overrides for a in ("--set", o)]
    code = main(
        ["bench", "cracking", "--cases", "jaeger", "--events", "1", "--json", str(out), *sets]
    )
    assert code == 0
    (rec,) = json.loads(out.read_text())
    return rec


def test_set_overrides_reach_the_case_and_contact_is_reported(tmp_path, jaeger_case):
    fine = _bench(tmp_path)
    coarse = _bench(tmp_path, "geometry.parameters.h=5.0", "geometry.parameters.beta=60")
    assert coarse["dofs"] < fine["dofs"] / 2
    assert coarse["results"]["events_by_mode"]["slip"] == 1
    for rec in (fine, coarse):
        assert rec["contact_iterations_per_event"] >= 0.0
        assert rec["contact_worst_gap"] <= 0.0
        assert rec["results"]["contact"]["pairs"] > 0


def test_parts_and_memory_are_reported_per_rank(tmp_path, jaeger_case):
    """Every part of the work has a time per rank; they lie within the phases' times."""
    from geofrac.fracture.linear import PARTS

    rec = _bench(tmp_path)
    parts, phases = rec["part_s_per_rank"], rec["phase_s_per_rank"]
    assert set(parts) == set(PARTS)
    for per_rank in (*parts.values(), *phases.values(), rec["peak_rss_mb_per_rank"]):
        assert len(per_rank) == rec["ranks"]
    assert parts["factorise"][0] > 0.0  # the run's first reference
    assert parts["stresses"][0] > 0.0 and parts["crack"][0] > 0.0
    # the parts are measured inside the phases, so they cannot exceed them
    assert sum(v[0] for v in parts.values()) <= sum(v[0] for v in phases.values()) + 1e-6
    assert rec["peak_rss_mb_per_rank"][0] > 50.0  # a Python process with PETSc loaded
