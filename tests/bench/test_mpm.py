"""``geofrac bench mpm`` end to end on a small selection."""

import json

import pytest


def test_bench_mpm_writes_records_table_and_plot(cli, tmp_path):
    out = tmp_path / "out"
    code, stdout, _ = cli(
        "bench", "mpm", "--W", "1000,12500", "--shapes", "mpm,cpgimp", "--schemes", "musl",
        "--json", tmp_path / "b.json", "--out", out,
    )  # fmt: skip
    assert code == 0
    assert "particle-steps/s" in stdout
    records = json.loads((tmp_path / "b.json").read_text())["records"]
    assert len(records) == 4
    keys = {"scheme", "shape", "smoothing", "dim", "particles", "ranks", "particle_steps_per_s"}
    assert all(keys <= set(r) for r in records)
    by = {(r["shape"], r["W"]): r for r in records}
    assert by[("mpm", 1000.0)]["stress_error_rms"] < 0.02
    # cell crossing spoils the point-particle MPM at W = 12500 more than cpGIMP (Fig. 4.14)
    assert by[("mpm", 12500.0)]["stress_error_rms"] > by[("cpgimp", 12500.0)]["stress_error_rms"]
    assert (out / "mpm_bar.png").stat().st_size > 0


def test_bench_mpm_refuses_unknown_names(cli, tmp_path):
    with pytest.raises(SystemExit, match="--shapes"):
        cli("bench", "mpm", "--shapes", "gimp", "--out", tmp_path)
