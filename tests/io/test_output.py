"""Run output: XDMF readable by meshio and pyvista with the expected fields; summary.json."""

import json

import dolfinx_solver  # noqa: F401

import meshio
import numpy as np
import pytest
import pyvista
from mpi4py import MPI

from geofrac.pipeline import run_scene
from geofrac.scene import load_scene
from tests.conftest import JOBS


@pytest.fixture(scope="module")
def quickstart_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("quickstart")
    scene = load_scene(JOBS / "quickstart.toml", out=out)
    summary = run_scene(scene, MPI.COMM_WORLD, verbose=False)
    return out, summary


def test_xdmf_loads_in_meshio_with_all_fields(quickstart_run):
    out, summary = quickstart_run
    with meshio.xdmf.TimeSeriesReader(out / "results.xdmf") as reader:
        points, cells = reader.read_points_cells()
        assert reader.num_steps == 1
        _, point_data, cell_data = reader.read_data(0)
    n_cells = sum(len(c.data) for c in cells)
    assert points.shape == (summary["mesh"]["vertices"], 2)
    assert n_cells == summary["mesh"]["cells"]
    assert point_data["displacement"].shape == (len(points), 3)
    assert cell_data["stress"][0].shape == (n_cells, 9)
    assert cell_data["von_mises"][0].shape[0] == n_cells
    # the displacement at the tip vertex is the probed (and nearly exact) value
    tip = np.argmin(np.linalg.norm(points - [10.0, 0.0], axis=1))
    assert point_data["displacement"][tip, 1] == pytest.approx(
        summary["results"]["probes"]["tip"][1], rel=1e-10
    )
    # the shear stress follows the parabola τxy = P/(2I) (D²/4 - y²) (Edo (2016), eq. 3.31e)
    # near mid-span
    centres = points[cells[0].data].mean(axis=1)
    near = np.linalg.norm(centres - [5.0, 0.0], axis=1) < 0.2
    exact = 1.0 / (2.0 / 12.0) * (0.25 - centres[near, 1] ** 2)
    np.testing.assert_allclose(cell_data["stress"][0][near, 1], exact, rtol=0.03)
    # a true row-major 3×3 tensor (what ParaView expects): τyx = τxy, no out-of-plane terms
    stress = cell_data["stress"][0]
    np.testing.assert_allclose(stress[:, 3], stress[:, 1], rtol=1e-12)
    np.testing.assert_allclose(stress[:, [2, 5, 6, 7, 8]], 0.0, atol=1e-12)
    # bending stress σx = -P(L-x)y/I peaks near 6PL/D² = 60 at the fixed end's outer cells
    assert 40.0 < np.abs(stress[:, 0]).max() < 60.0


def test_xdmf_loads_in_pyvista(quickstart_run):
    out, summary = quickstart_run
    grid = pyvista.read(out / "results.xdmf")
    assert grid.n_points == summary["mesh"]["vertices"]
    assert grid.n_cells == summary["mesh"]["cells"]
    assert set(grid.point_data.keys()) >= {"displacement"}
    assert set(grid.cell_data.keys()) >= {"stress", "von_mises"}


def test_summary_has_the_documented_keys(quickstart_run):
    out, _ = quickstart_run
    summary = json.loads((out / "summary.json").read_text())
    for key in ("scene", "versions", "ranks", "mesh", "dofs", "timings_s", "results", "status"):
        assert key in summary
    assert summary["status"] == "ok"
    assert summary["ranks"] == MPI.COMM_WORLD.size
    assert set(summary["mesh"]) >= {"cells", "vertices"}
    assert summary["scene"]["sha256"] == load_scene(JOBS / "quickstart.toml").sha256
    assert {"mesh", "compile", "assemble", "solve", "output", "total"} <= set(summary["timings_s"])
    assert summary["versions"]["dolfinx"].startswith("0.11")
    assert set(summary["results"]["probes"]) == {"tip", "mid_span"}
    assert summary["results"]["errors"]["u_relative"] < 1e-3


def test_fields_can_be_restricted(tmp_path):
    scene = load_scene(JOBS / "quickstart.toml", ['output.fields=["von_mises"]'], out=tmp_path)
    run_scene(scene, MPI.COMM_WORLD, verbose=False)
    with meshio.xdmf.TimeSeriesReader(tmp_path / "results.xdmf") as reader:
        reader.read_points_cells()
        _, point_data, cell_data = reader.read_data(0)
    assert not point_data and set(cell_data) == {"von_mises"}


def test_xdmf_can_be_switched_off(tmp_path):
    scene = load_scene(JOBS / "quickstart.toml", ["output.xdmf=false"], out=tmp_path)
    run_scene(scene, MPI.COMM_WORLD, verbose=False)
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == [
        "summary.json"
    ]


def test_rerun_replaces_previous_output(tmp_path):
    scene = load_scene(JOBS / "quickstart.toml", out=tmp_path)
    run_scene(scene, MPI.COMM_WORLD, verbose=False)
    stale = load_scene(JOBS / "quickstart.toml", ["output.xdmf=false"], out=tmp_path)
    run_scene(stale, MPI.COMM_WORLD, verbose=False)
    assert not (tmp_path / "results.xdmf").exists()


@pytest.mark.mpi
@pytest.mark.parametrize("element", ["rgnt", "gnt", "p2"])
def test_nodal_and_cell_stress_and_strain_of_the_patch_test_are_exact(tmp_path_factory, element):
    """Cell and nodal recovery reproduce the uniform state (nodal sums cross ranks)."""
    comm = MPI.COMM_WORLD
    out = comm.bcast(str(tmp_path_factory.mktemp("patch")) if comm.rank == 0 else None, root=0)
    fields = '["displacement", "stress", "strain", "stress_nodal", "strain_nodal"]'
    scene = load_scene(
        JOBS / "patch_test.toml",
        [f"discretization.element={element}", f"output.fields={fields}"],
        out=out,
    )
    summary = run_scene(scene, comm, verbose=False)
    assert summary["status"] == "ok"
    if comm.rank != 0:
        return
    with meshio.xdmf.TimeSeriesReader(f"{out}/results.xdmf") as reader:
        points, _ = reader.read_points_cells()
        _, point_data, cell_data = reader.read_data(0)
    E, nu = 97.0, 0.25  # jobs/patch_test.toml, plane stress
    exx, eyy = 0.002, -0.0006
    sxx = E / (1 - nu**2) * (exx + nu * eyy)
    syy = E / (1 - nu**2) * (eyy + nu * exx)
    stress = np.array([[sxx, 0, 0], [0, syy, 0], [0, 0, 0]]).ravel()
    strain = np.array([[exx, 0, 0], [0, eyy, 0], [0, 0, -nu / (1 - nu) * (exx + eyy)]]).ravel()
    assert point_data["stress_nodal"].shape == (len(points), 9)
    np.testing.assert_allclose(
        point_data["stress_nodal"], np.tile(stress, (len(points), 1)), atol=1e-12
    )
    np.testing.assert_allclose(
        point_data["strain_nodal"], np.tile(strain, (len(points), 1)), atol=1e-14
    )
    np.testing.assert_allclose(
        cell_data["stress"][0], np.tile(stress, (len(cell_data["stress"][0]), 1)), atol=1e-12
    )
    np.testing.assert_allclose(
        cell_data["strain"][0], np.tile(strain, (len(cell_data["strain"][0]), 1)), atol=1e-14
    )
