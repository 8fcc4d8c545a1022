"""output.lines: CSV columns and values on a linear field, the PNG, outside points, publishing."""

import csv
import json
from pathlib import Path

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.io.lines import DIRECTORY, sample_points
from geofrac.io.outdir import SUBDIRECTORIES
from geofrac.model.scene import Line
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

# jobs/patch_test.toml: u = 0.002 x, v = -0.0006 y (exact), plane stress E = 97, ν = 0.25
LINE = (
    "output.lines.diag={start=[0.5, 4.5], end=[4.5, 0.5], points=9, "
    'fields=["displacement", "stress", "von_mises"]}'
)


@pytest.fixture
def out(tmp_path):
    """One output directory for every rank (rank 0's)."""
    comm = MPI.COMM_WORLD
    return Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))


def _run(tmp_path, *overrides):
    scene = load_scene_collective(
        MPI.COMM_WORLD, JOBS / "patch_test.toml", list(overrides), out=tmp_path
    )
    try:
        return run_scene(scene, MPI.COMM_WORLD, verbose=False)
    finally:
        MPI.COMM_WORLD.Barrier()  # rank 0 has written the files every rank reads


def test_sample_points_are_equally_spaced_with_both_ends():
    s, xyz = sample_points(Line((1.0, 2.0), (4.0, 6.0), points=6))
    assert s == pytest.approx(np.linspace(0.0, 5.0, 6), abs=1e-15)
    assert xyz[0].tolist() == [1.0, 2.0, 0.0] and xyz[-1].tolist() == [4.0, 6.0, 0.0]


@pytest.mark.mpi
def test_line_csv_holds_the_exact_linear_field_and_a_png(out):
    tmp_path = out
    summary = _run(tmp_path, LINE)
    entry = summary["results"]["lines"]["diag"]
    assert entry["csv"] == "lines/diag.csv" and entry["points"] == 9
    if MPI.COMM_WORLD.rank == 0:  # rank 0 publishes and lists the files
        assert {"lines/diag.csv", "lines/diag.png"} <= set(summary["files"])
    with open(tmp_path / "lines" / "diag.csv") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == [
        *("s", "x", "y", "u_x", "u_y"),
        *("stress_xx", "stress_yy", "stress_zz", "stress_xy", "von_mises"),
    ]
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (9, 10)
    x, y = np.linspace(0.5, 4.5, 9), np.linspace(4.5, 0.5, 9)
    assert data[:, 0] == pytest.approx(np.hypot(x - 0.5, y - 4.5), abs=1e-12)
    assert data[:, 1] == pytest.approx(x, abs=1e-12) and data[:, 2] == pytest.approx(y, abs=1e-12)
    assert data[:, 3] == pytest.approx(0.002 * x, abs=1e-14)
    assert data[:, 4] == pytest.approx(-0.0006 * y, abs=1e-14)
    c = 97.0 / (1 - 0.25**2)
    sxx, syy = c * (0.002 - 0.25 * 0.0006), c * (-0.0006 + 0.25 * 0.002)
    assert data[:, 5] == pytest.approx(sxx, rel=1e-10)
    assert data[:, 6] == pytest.approx(syy, rel=1e-10)
    assert data[:, 9] == pytest.approx(np.sqrt(sxx**2 - sxx * syy + syy**2), rel=1e-10)
    png = (tmp_path / "lines" / "diag.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


@pytest.mark.mpi
def test_a_line_leaving_the_mesh_stops_the_run_before_the_solve(out):
    tmp_path = out
    outside = "output.lines.far={start=[1.0, 1.0], end=[7.0, 1.0], points=7}"
    with pytest.raises(RunError) as info:
        _run(tmp_path, outside)
    text = str(info.value)
    assert "output.lines.far: sample 5 (s = 5) at [6.0, 1.0] lies outside the mesh" in text
    assert "(2 points in all)" in text
    assert not (tmp_path / "summary.json").exists()  # nothing published
    assert not (tmp_path / "lines").exists()
    status = json.loads((tmp_path / "incomplete" / "summary.json").read_text())["status"]
    assert status.startswith("error: output.lines.far")


@pytest.mark.mpi
def test_a_new_run_removes_the_previous_runs_lines(out):
    tmp_path = out
    _run(tmp_path, LINE)
    assert (tmp_path / "lines" / "diag.csv").is_file()
    summary = _run(tmp_path)
    assert "lines" not in summary["results"]
    assert not (tmp_path / "lines").exists()
    assert DIRECTORY in SUBDIRECTORIES
