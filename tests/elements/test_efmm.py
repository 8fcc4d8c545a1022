"""EFMM on DOLFINx: the C kernels against the numpy reference, rigid modes, parallel runs."""

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.elements import efmm_numpy as ref
from geofrac.elements.efmm import domain_data, efmm
from geofrac.materials import d_matrix
from tests.fem.helpers import solve_job

D = d_matrix(1000.0, 0.2, 2, plane="stress")


def _distorted_square(comm, n=5, m=4, amount=None):
    """Unit square, n x m cells per side, interior vertices moved by a coordinate hash.

    Each coordinate moves by up to 0.2 of the smaller cell side unless ``amount`` is given.
    """
    amount = 0.2 / max(n, m) if amount is None else amount
    mesh = dolfinx.mesh.create_unit_square(comm, n, m)
    x = mesh.geometry.x
    inside = (x[:, 0] > 1e-9) & (x[:, 0] < 1 - 1e-9) & (x[:, 1] > 1e-9) & (x[:, 1] < 1 - 1e-9)
    shift = amount * np.stack(
        [np.sin(37 * x[:, 0] + 11 * x[:, 1]), np.cos(23 * x[:, 0] - 17 * x[:, 1])]
    )
    x[inside, :2] += shift[:, inside].T
    return mesh


def _dense(K):
    """A copy of a sequential PETSc matrix as a numpy array; destroys ``K``."""
    try:
        M = K.convert("dense")
        out = M.getDenseArray().copy()
        M.destroy()
    finally:
        K.destroy()
    return out


def _reference(mesh, q_rand, seed):
    """The numpy reference stiffness on the mesh's own arrays, in the DOF order of V."""
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (2,)))
    nodes, dofs = mesh.geometry.dofmaps[0], V.dofmap.list
    n = V.dofmap.index_map.size_local
    points = np.zeros((n, 2))
    points[dofs.ravel()] = mesh.geometry.x[nodes.ravel(), :2]
    ids = np.zeros(n, dtype=np.int64)
    ids[dofs.ravel()] = np.asarray(mesh.geometry.input_global_indices)[nodes.ravel()]
    domains = ref.integration_domains(points, dofs, q_rand, seed=seed, ids=ids)
    K = np.zeros((2 * n, 2 * n))
    for i in range(n):
        Ki, d = ref.node_stiffness(points, dofs, D, domains=domains, node=i)
        K[np.ix_(d, d)] += Ki
    return K


@pytest.mark.parametrize("q_rand", [0.0, 0.5])
def test_kernel_stiffness_equals_the_numpy_reference(q_rand):
    mesh = _distorted_square(MPI.COMM_SELF)
    element = efmm(mesh)
    element.setup(D, q_rand, seed=3)
    dense = _dense(element.stiffness())
    element.destroy()
    expected = _reference(mesh, q_rand, 3)
    assert np.abs(dense - expected).max() < 1e-12 * np.abs(expected).max()


def test_assembled_stiffness_of_a_free_mesh_has_exactly_three_zero_eigenvalues():
    mesh = _distorted_square(MPI.COMM_SELF, 6, 5)
    element = efmm(mesh)
    element.setup(D, 0.5, seed=1)
    dense = _dense(element.stiffness())
    element.destroy()
    assert np.abs(dense - dense.T).max() < 1e-12 * np.abs(dense).max()
    eig = np.linalg.eigvalsh(0.5 * (dense + dense.T))
    assert np.count_nonzero(np.abs(eig) < 1e-10 * eig.max()) == 3
    assert eig[3] > 1e-4 * eig.max()


@pytest.mark.mpi
@pytest.mark.parametrize("q_rand", [0.0, 0.7])
def test_domains_tile_the_distributed_mesh(q_rand):
    comm = MPI.COMM_WORLD
    mesh = _distorted_square(comm, 9, 7)
    data = domain_data(mesh, q_rand, seed=5)
    n = mesh.topology.index_map(2).size_local
    x = mesh.geometry.x[mesh.geometry.dofmaps[0][:n]][:, :, :2]
    subs = ref.cell_subtriangles(x, data.values[:n])
    area = ref.triangle_areas(subs)
    assert area.min() > 0
    total = comm.allreduce(area.sum(), op=MPI.SUM)
    assert abs(total - 1.0) < 1e-14
    d = x[:, 1:] - x[:, :1]
    cells = np.abs(d[:, 0, 0] * d[:, 1, 1] - d[:, 0, 1] * d[:, 1, 0]) / 2
    assert np.abs(area.sum(axis=(1, 2)) - cells).max() < 1e-15  # each cell exactly
    assert data.clamped == 0


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("q_rand", [0.0, 0.3])
def test_one_and_two_ranks_give_the_same_solution(q_rand):
    """The cantilever's probes, errors and energy agree on 1 rank and on all ranks."""
    overrides = (
        "geometry.parameters.nx=24",
        "geometry.parameters.ny=6",
        f"discretization.q_rand={q_rand}",
        "discretization.domain_seed=4",
        "output.probes={tip=[8.0, 0.0], mid=[4.0, 0.5], root=[0.5, -0.75]}",
    )
    results = []
    for comm in (MPI.COMM_SELF, MPI.COMM_WORLD):
        solution = solve_job("cantilever_efmm", *overrides, comm=comm)
        solution.problem.destroy()
        results.append(solution.results)
    serial, parallel = results
    for name in ("tip", "mid", "root"):
        assert np.allclose(serial["probes"][name], parallel["probes"][name], rtol=0, atol=1e-10)
    for key in ("u", "energy"):
        assert abs(serial["errors"][key] - parallel["errors"][key]) < 1e-10
    # and the same on every rank
    tips = MPI.COMM_WORLD.allgather(parallel["probes"]["tip"])
    assert all(t == tips[0] for t in tips)


def test_efmm_beats_cst_on_the_thesis_cantilever():
    """Edo (2016), Fig. 3.10: EFMM's displacement error is below CST's on the same mesh."""
    errors = {}
    for element in ("cst", "efmm"):
        solution = solve_job(
            "cantilever_efmm",
            f"discretization.element={element}",
            "geometry.parameters.nx=16",
            "geometry.parameters.ny=4",
            comm=MPI.COMM_SELF,
        )
        solution.problem.destroy()
        errors[element] = solution.results["errors"]
    assert errors["efmm"]["u"] < 0.25 * errors["cst"]["u"]
    assert errors["efmm"]["energy"] < errors["cst"]["energy"]


def test_thickness_scales_the_stiffness_as_the_traction_load():
    """A traction load carries t, so K must too: the same u for t = 1 and t = 4.

    As with the UFL elements the strain energy is 4 times as large. Before the fix EFMM's
    K = Cᵀ A⁻¹ C was per unit thickness and t = 4 gave 4 times the deflection.
    """
    out = {}
    for t in (1.0, 4.0):
        solution = solve_job("cantilever_efmm", f"material.thickness={t}", comm=MPI.COMM_SELF)
        solution.problem.destroy()
        out[t] = (solution.results["probes"]["tip"][1], solution.results["strain_energy"])
    assert out[1.0][0] > 0.1  # the unit load bends the 8 x 2 cantilever by about 0.2
    assert out[4.0][0] == pytest.approx(out[1.0][0], rel=1e-9)
    assert out[4.0][1] == pytest.approx(4.0 * out[1.0][1], rel=1e-9)


@pytest.mark.mpi
def test_an_inverted_mesh_is_a_clear_error_on_every_rank():
    from geofrac.errors import RunError

    # vertices moved by up to 2 cell sides: many triangles fold over their neighbours
    mesh = _distorted_square(MPI.COMM_WORLD, 9, 7, amount=0.2)
    with pytest.raises(RunError, match="same side"):
        domain_data(mesh, 0.0, seed=0)


def test_efmm_rejects_a_mesh_that_is_not_made_of_triangles():
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 2, 2, dolfinx.mesh.CellType.quadrilateral)
    with pytest.raises(ValueError, match="efmm needs triangles"):
        efmm(mesh)


@pytest.mark.mpi
def test_a_run_writes_the_grains_and_the_nodal_stress(mpi_tmp_path):
    """grains.vtu/.xdmf: one polygon per node, areas summing to the beam's, mean stresses."""
    import json

    import h5py
    import pyvista as pv

    from geofrac.pipeline import run_scene
    from geofrac.scene import load_scene_collective
    from tests.conftest import JOBS

    comm = MPI.COMM_WORLD
    out = mpi_tmp_path / "run"
    scene = load_scene_collective(
        comm,
        JOBS / "cantilever_efmm.toml",
        ["discretization.q_rand=0.4", f"output.dir={out.as_posix()}"],
    )
    run_scene(scene, comm, verbose=False)
    if comm.rank == 0:
        summary = json.loads((out / "summary.json").read_text())
        assert summary["status"] == "ok"
        assert summary["results"]["efmm"]["q_rand"] == 0.4
        grid = pv.read(out / "grains.vtu")
        assert grid.n_cells == summary["mesh"]["vertices"] == 27
        assert abs(grid.cell_data["area"].sum() - 16.0) < 1e-12
        stress = grid.cell_data["stress"].reshape(-1, 3, 3)
        # the mean bending stress is tensile below the axis near the root, as Timoshenko's
        low_root = (grid.cell_centers().points[:, 0] < 2) & (
            grid.cell_centers().points[:, 1] < -0.3
        )
        assert low_root.any() and np.all(stress[low_root, 0, 0] > 0)
        with h5py.File(out / "grains.h5") as f:
            assert f["cell_data/stress"].shape == (27, 9)
        assert (out / "grains.xdmf").exists() and (out / "results.xdmf").exists()
    comm.barrier()
