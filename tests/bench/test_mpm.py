"""``geofrac bench mpm`` end to end on a small selection."""

import json

import pytest


def _records(cli, tmp_path, *args):
    """Run ``geofrac bench mpm ARGS --json F --out tmp``; return the records."""
    code, _, _ = cli("bench", "mpm", *args, "--json", tmp_path / "r.json", "--out", tmp_path)
    assert code == 0
    return json.loads((tmp_path / "r.json").read_text())["records"]


def test_bench_mpm_writes_records_table_and_plot(cli, tmp_path):
    out = tmp_path / "out"
    code, stdout, _ = cli(
        "bench", "mpm", "--cases", "bar", "--W", "1000,12500", "--shapes", "mpm,cpgimp",
        "--schemes", "musl",
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


def test_bench_mpm_translating_bar_reports_energy_drift(cli, tmp_path):
    records = _records(
        cli, tmp_path, "--cases", "translating", "--shapes", "cpgimp", "--schemes", "usf",
        "--t-end", "2",
    )  # fmt: skip
    assert [r["smoothing"] for r in records] == ["none", "mls 2 cells", "mls 2 cells consistent"]
    # before the first wall hit (t = 11.25) the bar only flies: energy is conserved
    assert all(0 <= r["energy_drift_max"] < 1e-6 for r in records)
    assert all(0 <= r["energy_drift_work_max"] < 1e-6 for r in records)
    assert (tmp_path / "mpm_translating.png").stat().st_size > 0


def test_bench_mpm_impact_bar_reports_stress_error_and_overshoot(cli, tmp_path):
    records = _records(
        cli, tmp_path, "--cases", "impact", "--shapes", "cpgimp", "--schemes", "musl"
    )
    assert [(r["case"], r["smoothing"]) for r in records] == [
        ("impact_bar", "none"),
        ("impact_bar", "mls 2 cells"),
    ]
    assert all(0 < r["stress_error_rms"] < 0.2 and r["stress_overshoot"] > 1 for r in records)
    assert (tmp_path / "mpm_impact.png").stat().st_size > 0


def test_bench_mpm_block_records_2d_throughput(cli, tmp_path):
    records = _records(
        cli, tmp_path, "--cases", "block", "--shapes", "mpm", "--particles", "400", "--steps", "2"
    )
    assert [(r["case"], r["dim"], r["particles"], r["smoothing"]) for r in records] == [
        ("block2d", 2, 400, "none"),
        ("block2d", 2, 400, "mls 2 cells"),
    ]
    assert all(r["particle_steps_per_s"] > 0 for r in records)
    assert all(r["ranks"] == 1 and r["warmup_seconds"] >= 0 for r in records)
    assert all(r["backend"] == "numba" and len(r["per_rank"]) == 1 for r in records)


def test_bench_mpm_refuses_unknown_names(cli, capsys, tmp_path):
    with pytest.raises(SystemExit):
        cli("bench", "mpm", "--shapes", "gimp", "--out", tmp_path)
    err = capsys.readouterr().err
    assert "--shapes" in err and "unknown shape 'gimp'" in err
