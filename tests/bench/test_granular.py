"""``geofrac bench granular`` on a coarse grain beam."""

import json

import pytest


def test_granular_bench_reports_rates_phases_and_fields(tmp_path):
    from geofrac.cli import main

    out = tmp_path / "g.json"
    coarse = ["--set", "geometry.parameters.h=16", "--set", "geometry.parameters.h_fine=16"]
    code = main(
        ["bench", "granular", "--cases", "beam", "--events", "4", "--json", str(out), *coarse]
    )
    assert code == 0
    (rec,) = json.loads(out.read_text())
    assert rec["case"] == "beam" and rec["element"] == "efmm"
    assert rec["events"] == 4 and rec["events_per_s"] > 0
    assert {"assemble_s", "solve_s", "criterion_s", "update_s"} <= set(rec)
    assert rec["cracked_interfaces"] == 4
    assert sum(rec["grains_by_field"].values()) == rec["grains"]


def test_granular_bench_rejects_an_unknown_case():
    from geofrac.cli import main

    with pytest.raises(SystemExit, match="unknown case"):
        main(["bench", "granular", "--cases", "nope"])
