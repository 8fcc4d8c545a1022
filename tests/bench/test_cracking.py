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
