"""Elastic solves against exact solutions: Timoshenko cantilever and the patch test."""

import json

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.elements import available, get, make_element
from geofrac.errors import RunError
from geofrac.fem.elastic import exact_ufl, make_problem
from geofrac.fem.post import error_norms
from geofrac.meshing.distribute import build_mesh
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene
from tests.conftest import JOBS
from tests.fem.helpers import errors_and_tip, solve_job


def test_p3_reproduces_the_cubic_timoshenko_solution():
    # the exact displacement is a cubic polynomial: P3 must be exact up to round-off
    sol = solve_job("quickstart", "discretization.element=p3")
    errors, _, _ = errors_and_tip(sol)
    sol.problem.destroy()
    assert errors["u_relative"] < 1e-8
    assert errors["energy_relative"] < 1e-8


def test_p2_tip_deflection_within_one_percent_of_timoshenko():
    sol = solve_job("quickstart")
    _, tip, exact = errors_and_tip(sol)
    sol.problem.destroy()
    assert exact == pytest.approx(40.25, rel=1e-14)  # PL³/3EI + (4+5ν)PD²L/24EI
    assert tip == pytest.approx(exact, rel=1e-2)


def test_cst_converges_at_rate_two_on_the_thesis_meshes():
    errs, nodes = [], []
    for ny in (4, 8):
        sol = solve_job(
            "cantilever", f"geometry.parameters.nx={10 * ny}", f"geometry.parameters.ny={ny}"
        )
        errs.append(sol.results["errors"]["u"])
        nodes.append(sol.mesh_counts()["vertices"])
        sol.problem.destroy()
    rate = -np.log(errs[1] / errs[0]) / np.log(np.sqrt(nodes[1] / nodes[0]))
    assert 1.8 < rate < 2.2


@pytest.mark.mpi
@pytest.mark.parametrize(
    ("element", "extra"),
    [(n, ()) for n in available() if 2 in get(n).dims]
    + [  # random integration domains of the patch-method elements
        (n, ("discretization.q_rand=0.5", "discretization.domain_seed=7"))
        for n in available()
        if "q_rand" in get(n).options
    ],
)
def test_patch_test_on_a_distorted_mesh(element, extra):
    """Hard case: every element reproduces uniform strain on a badly distorted mesh."""
    scene = load_scene(JOBS / "patch_test.toml", [f"discretization.element={element}", *extra])
    tagged = build_mesh(scene.geometry, MPI.COMM_WORLD)
    mesh = tagged.mesh
    x = mesh.geometry.x
    a, h = scene.geometry.parameters["a"], scene.geometry.parameters["h"]
    interior = (x[:, 0] > 1e-9) & (x[:, 0] < a - 1e-9) & (x[:, 1] > 1e-9) & (x[:, 1] < a - 1e-9)
    # deterministic in the coordinates, so ghosts move with their owners on any partition
    shift = (
        0.3
        * h
        * np.stack(
            [np.sin(37.0 * x[:, 0] + 11.0 * x[:, 1]), np.cos(23.0 * x[:, 0] - 17.0 * x[:, 1])]
        )
    )
    x[interior, :2] += shift[:, interior].T
    # the mesh must really be distorted, and still valid
    cells = mesh.geometry.dofmaps[0]
    p = x[cells][:, :, :2]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert np.all(np.abs(area) > 0)
    assert len(np.unique(np.sign(area))) == 1, "perturbation inverted a cell"
    edges = np.stack([p[:, 1] - p[:, 0], p[:, 2] - p[:, 1], p[:, 0] - p[:, 2]], axis=1)
    lengths = np.linalg.norm(edges, axis=2)
    worst = mesh.comm.allreduce((lengths.max(axis=1) / lengths.min(axis=1)).max(), op=MPI.MAX)
    assert worst > 4.0, "mesh is not distorted enough"

    element_ = make_element(scene.discretization.element, mesh)
    problem = make_problem(tagged, element_, scene)
    problem.assemble()
    uh = problem.solve()
    u_exact, _ = exact_ufl(problem.exact, mesh)
    errors = error_norms(uh, u_exact, problem.lam, mu=problem.mu)
    own = problem.error_norms()  # EFMM: the energy of its patch stresses
    problem.destroy()
    assert errors["u_relative"] < 1e-10
    assert errors["energy_relative"] < 1e-9
    assert own["energy_relative"] < 1e-9


@pytest.mark.mpi
@pytest.mark.parametrize("nu", [0.4999, 0.4999999])
def test_near_incompressible_plane_strain_stays_accurate_with_p2(nu):
    """Hard case: ν → 0.5 in plane strain. P2 stays accurate; validation warns about CST."""
    overrides = ["material.plane=strain", f"material.nu={nu}"]
    sol = solve_job("quickstart", *overrides)
    errors, tip, exact = errors_and_tip(sol)
    sol.problem.destroy()
    assert np.isfinite(tip)
    assert tip == pytest.approx(exact, rel=1e-3)
    assert errors["u_relative"] < 1e-3

    cst = load_scene(JOBS / "quickstart.toml", [*overrides, "discretization.element=cst"])
    assert any("locks volumetrically" in w for w in cst.warnings)
    assert not load_scene(JOBS / "quickstart.toml", overrides).warnings


def test_cst_locking_that_the_warning_describes_is_real():
    sol = solve_job(
        "quickstart", "material.plane=strain", "material.nu=0.4999", "discretization.element=cst"
    )
    _, tip, exact = errors_and_tip(sol)
    sol.problem.destroy()
    assert tip < 0.1 * exact


@pytest.mark.mpi
@pytest.mark.parametrize("preset", ["direct", "iterative"])
def test_singular_system_is_an_error_not_a_result(mpi_tmp_path, preset):
    """Hard case: only u_x is held, so a vertical rigid translation is free."""
    scene = load_scene(
        JOBS / "cantilever.toml",
        [
            "bc.0.value=[0.0]",
            'bc.0.components=["x"]',
            f"solver.preset={preset}",
            "output.probes={}",
        ],
        out=mpi_tmp_path / "run",
    )
    with pytest.raises(RunError, match=r"singular|did not converge"):
        run_scene(scene, MPI.COMM_WORLD, verbose=False)

    MPI.COMM_WORLD.barrier()
    summary = json.loads((mpi_tmp_path / "run" / "incomplete" / "summary.json").read_text())
    assert summary["status"].startswith("error: linear solver")
    assert not (mpi_tmp_path / "run" / "results.xdmf").exists()
    assert not (mpi_tmp_path / "run" / "summary.json").exists()


@pytest.mark.mpi
def test_probe_outside_the_mesh_fails_before_the_solve(mpi_tmp_path):
    scene = load_scene(
        JOBS / "quickstart.toml", ["output.probes.far=[20.0, 0.0]"], out=mpi_tmp_path / "r"
    )
    with pytest.raises(RunError, match=r"output\.probes"):
        run_scene(scene, MPI.COMM_WORLD, verbose=False)


def test_iterative_and_direct_solvers_agree():
    direct = solve_job("quickstart", "solver.preset=direct")
    iterative = solve_job("quickstart", "solver.preset=iterative")
    tip_d, tip_i = direct.results["probes"]["tip"][1], iterative.results["probes"]["tip"][1]
    assert iterative.results["solver"]["ksp_type"] == "cg"
    assert iterative.results["solver"]["pc_type"] == "gamg"
    assert direct.results["solver"]["pc_type"] == "lu"
    direct.problem.destroy()
    iterative.problem.destroy()
    assert tip_i == pytest.approx(tip_d, rel=1e-7)


def test_user_solver_options_override_the_preset():
    sol = solve_job("quickstart", "solver.preset=iterative", "solver.options.ksp_type=minres")
    assert sol.results["solver"]["ksp_type"] == "minres"
    sol.problem.destroy()
