"""Every registered element, taken from the registry: what its ElementSpec declares is true.

Nothing here lists element names: a new registry entry is picked up by every test (the
patch test, the rigid modes, 1 vs N ranks, the declared data, one crack event for the
elements that crack, the numpy cell matrices of the crack driver).
"""

import dataclasses

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from geofrac import elements
from geofrac.effects.cracking import scene_driver
from geofrac.elements.kinematics import KINDS, dofs_from_gradient
from geofrac.fem.elastic import ElasticProblem
from geofrac.fracture.cells import fe_matrices
from geofrac.materials import d_matrix, lame
from geofrac.scene import SceneError, load_scene, load_scene_collective
from geofrac.scene.load import ELEMENT_INDEPENDENT, SECTION_KEYS
from tests.conftest import JOBS
from tests.elements.helpers import E_MOD, NU, distorted_mesh, free_stiffness
from tests.fem.helpers import solve_job

#: (element, dimension) for every registered element and every dimension it supports.
PAIRS = [(n, d) for n in elements.available() for d in elements.get(n).dims]
#: A valid value of each ``[discretization]`` option.
OPTION_VALUES = {
    "quadrature_degree": "4",
    "zero_mode_penalty": "1e-3",
    "gradient_bc": "free",
    "q_rand": "0.5",
    "domain_seed": "3",
    "renumber": "5",
}
#: A small closed-form job per dimension: (job, overrides, probe).
CASES = {
    2: ("cantilever", ("geometry.parameters.nx=20", "geometry.parameters.ny=4"), "tip"),
    3: ("mms3d", ("geometry.parameters.n=2",), "centre"),
}
#: A tiny crack scene per cracking mode: (job, overrides).
CRACK_SCENES = {
    "edges": ("notched_beam", ("geometry.parameters.h_fine=8", "geometry.parameters.h=30")),
    "grains": ("grain_notched_beam", ("geometry.parameters.h=16", "geometry.parameters.h_fine=16")),
}


def _linear_field(name: str, space: dolfinx.fem.FunctionSpace, G: np.ndarray) -> np.ndarray:
    """DOF values of u = G x on the element's unknowns (extra DOFs from the gradient)."""
    dim = G.shape[0]
    bs = space.dofmap.index_map_bs
    x = space.tabulate_dof_coordinates()[:, :dim]
    d = np.zeros((len(x), bs))
    d[:, :dim] = x @ G.T
    kinematics = elements.get(name).kinematics
    if kinematics is not None:
        d[:, dim:] = dofs_from_gradient(KINDS[kinematics], G[None])[0]
    return d.ravel()


@pytest.mark.parametrize(("name", "dim"), PAIRS)
def test_patch_test_linear_fields_leave_no_interior_residual(name, dim):
    """K d_lin = 0 at every DOF off the boundary, for a general linear field u = G x.

    This is the patch test on a free distorted mesh: with the boundary DOFs prescribed
    from u, the interior equations are satisfied by the interpolant of u, so the FE
    solution reproduces the uniform strain exactly (Edo (2016) 2.4.2).
    """
    mesh = distorted_mesh(dim, (3,) * dim)
    K, element = free_stiffness(name, mesh)
    space = element.unknowns
    rng = np.random.default_rng(7)
    G = rng.uniform(-1.0, 1.0, (dim, dim))
    d = _linear_field(name, space, G)
    mesh.topology.create_connectivity(dim - 1, dim)
    facets = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    boundary = dolfinx.fem.locate_dofs_topological(space, dim - 1, facets)
    bs = space.dofmap.index_map_bs
    interior = np.setdiff1d(np.arange(len(d) // bs), boundary)
    rows = (interior[:, None] * bs + np.arange(bs)).ravel()
    r = K @ d
    assert len(rows) > 0
    assert np.abs(r[rows]).max() < 1e-11 * np.abs(K).max() * np.abs(d).max()
    element.destroy()


@pytest.mark.parametrize(("name", "dim"), PAIRS)
def test_free_mesh_has_exactly_the_rigid_body_zero_modes(name, dim):
    """3 zero eigenvalues in 2D and 6 in 3D, with the element's default zero-mode penalty."""
    K, element = free_stiffness(name, distorted_mesh(dim))
    assert np.allclose(K, K.T, atol=1e-12 * np.abs(K).max())
    eig = np.linalg.eigvalsh(0.5 * (K + K.T))
    n_rigid = 3 if dim == 2 else 6
    # rigid modes sit at round-off (measured <= 2e-16 λmax); the next eigenvalue, for
    # RGNT/RGNQ the penalised constant-rotation mode of order α μ |Ω| (measured >= 4e-9
    # λmax with α = 1e-6), stands clear above the zero threshold
    assert np.abs(eig[:n_rigid]).max() < 1e-12 * eig[-1]
    assert eig[n_rigid] > 1e-10 * eig[-1]
    element.destroy()


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize(("name", "dim"), PAIRS)
def test_one_and_n_ranks_give_the_same_closed_form_solve(name, dim):
    """Probe and error norms of a small closed-form solve agree on 1 rank and on all ranks."""
    job, overrides, probe = CASES[dim]
    overrides = (*overrides, f"discretization.element={name}")
    results = []
    for comm in (MPI.COMM_SELF, MPI.COMM_WORLD):
        solution = solve_job(job, *overrides, comm=comm)
        solution.problem.destroy()
        results.append(solution.results)
    serial, parallel = results
    # to round-off of the largest component (a component near 0 carries no digits)
    scale = np.abs(serial["probes"][probe]).max()
    np.testing.assert_allclose(
        parallel["probes"][probe], serial["probes"][probe], rtol=0, atol=1e-10 * scale
    )
    for key in ("u_relative", "energy_relative"):  # P3, GNT, P2: exact to ~1e-7..1e-11
        assert (
            abs(parallel["errors"][key] - serial["errors"][key])
            < 1e-8 * serial["errors"][key] + 1e-9
        )
    # against the closed form: a coarse mesh, but not a wrong one
    assert serial["errors"]["u_relative"] < 0.5
    gathered = MPI.COMM_WORLD.allgather(parallel["probes"][probe])
    assert all(np.array_equal(g, gathered[0]) for g in gathered)


@pytest.mark.parametrize("name", elements.available())
def test_declared_data_is_what_the_element_builds(name):
    spec = elements.get(name)
    assert spec.name == name and spec.description
    assert issubclass(spec.problem_class(), ElasticProblem)
    assert set(spec.vertex_dofs) == set(spec.dims)
    for dim in spec.dims:
        mesh = distorted_mesh(dim)
        element = spec.build(mesh)
        assert element.name == name
        assert element.unknowns.dofmap.index_map_bs == spec.vertex_dofs[dim]
        if spec.kinematics is not None:
            kind = KINDS[spec.kinematics]
            assert kind.gdim == dim and kind.block_size == spec.vertex_dofs[dim]
        element.destroy()
    # the zero-mode penalty is an option exactly when there is a default for it
    assert ("zero_mode_penalty" in spec.options) == (spec.zero_mode_penalty is not None)
    if spec.cracking is not None:
        assert 2 in spec.dims  # the crack drivers are 2D


@pytest.mark.parametrize(("name", "dim"), PAIRS)
def test_loader_takes_the_declared_options_and_refuses_the_others(name, dim):
    spec = elements.get(name)
    job = CASES[dim][0]
    base = [f"discretization.element={name}"]
    assert spec.options <= set(SECTION_KEYS["discretization"])
    scene = load_scene(JOBS / f"{job}.toml", base)
    default = 0.0 if spec.zero_mode_penalty is None else spec.zero_mode_penalty
    assert scene.discretization.zero_mode_penalty == default
    for key in SECTION_KEYS["discretization"][1:]:
        override = f"discretization.{key}={OPTION_VALUES[key]}"
        if key in spec.options or key in ELEMENT_INDEPENDENT:
            load_scene(JOBS / f"{job}.toml", [*base, override])
        else:
            with pytest.raises(SceneError, match=f"applies only to elements .*not '{name}'"):
                load_scene(JOBS / f"{job}.toml", [*base, override])


def _u_error(name: str, nu: float) -> float:
    """Relative displacement error of the plane-strain cantilever, as docs/locking.py."""
    solution = solve_job(
        "cantilever",
        "material.plane=strain",
        "geometry.parameters.nx=80",
        "geometry.parameters.ny=8",
        f"discretization.element={name}",
        f"material.nu={nu}",
        "output.probes={}",
        comm=MPI.COMM_SELF,
    )
    solution.problem.destroy()
    return solution.results["errors"]["u_relative"]


def _cook_tip(name: str, nu: float, n: int) -> float:
    """Tip deflection of Cook's membrane in plane strain on the n x n mesh."""
    solution = solve_job(
        "cook_membrane",
        f"geometry.parameters.n={n}",
        f"discretization.element={name}",
        f"material.nu={nu}",
        comm=MPI.COMM_SELF,
    )
    solution.problem.destroy()
    return solution.results["probes"]["tip"][1]


def _cook_error(name: str, nu: float) -> float:
    """|Relative tip error| on the 16 x 16 mesh against P3 on 32 x 32.

    docs/locking.py takes P3 on 64 x 64; the two references differ by 1.2e-3.
    """
    return abs(_cook_tip(name, nu, 16) / _cook_tip("p3", nu, 32) - 1.0)


@pytest.mark.parametrize("name", [n for n in elements.available() if 2 in elements.get(n).dims])
def test_declared_locking_threshold_is_where_the_error_grows_tenfold(name):
    """The declared ``locking_nu`` is the measured one (docs/stability.md, "Locking").

    Plane strain, two specimens: the cantilever (L2 displacement error) and Cook's
    membrane (tip deflection error). Locked means an error exceeds 10 times its ν = 0.3
    value and 5 % on either specimen. Locked at ``locking_nu``, not at a ν five times
    farther from 0.5; an element declared free of locking is not locked at 0.49999.
    """
    spec = elements.get(name)
    base = (_u_error(name, 0.3), _cook_error(name, 0.3))

    def locked(nu: float) -> bool:
        errors = (_u_error(name, nu), _cook_error(name, nu))
        return any(e > max(10.0 * b, 0.05) for e, b in zip(errors, base, strict=True))

    if spec.locking_nu is None:
        assert not locked(0.49999)
    else:
        assert locked(spec.locking_nu)
        assert not locked(0.5 - 5.0 * (0.5 - spec.locking_nu))


@pytest.mark.parametrize("name", [n for n in elements.available() if elements.get(n).cracking])
def test_every_cracking_element_runs_one_crack_event(name):
    job, overrides = CRACK_SCENES[elements.get(name).cracking]
    scene = load_scene_collective(
        MPI.COMM_WORLD,
        JOBS / f"{job}.toml",
        [*overrides, f"discretization.element={name}", "cracking.max_events=1"],
    )
    driver = scene_driver(scene, MPI.COMM_WORLD)
    try:
        res = driver.run()
    finally:
        driver.problem.destroy()
    assert res["events"] == 1 and res["end_reason"] == "max_events"
    # the two drivers name their crack sites differently (edges, grain interfaces)
    new = res.get("new_cracked_edges", res.get("new_cracked_interfaces"))
    assert new is not None and new >= 1


@pytest.mark.parametrize(
    "name", [n for n in elements.available() if elements.get(n).cracking == "edges"]
)
def test_numpy_cell_matrices_equal_the_elements_own_assembly(name):
    """One source of truth: the crack driver's numpy cells equal the element's assembly.

    ``fracture.cells.fe_matrices`` summed over a two-triangle mesh equal the element's
    own DOLFINx stiffness (with its default zero-mode penalty).
    """
    spec = elements.get(name)
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, 1, 1)
    mesh.geometry.x[:, :2] += np.array([[0.1, -0.05], [0.0, 0.2], [-0.15, 0.0], [0.05, 0.1]])[
        : len(mesh.geometry.x)
    ]
    K, element = free_stiffness(name, mesh)
    _, mu = lame(E_MOD, NU, 2)
    alpha = spec.zero_mode_penalty or 0.0
    cells = mesh.geometry.dofmaps[0]
    x = mesh.geometry.x[cells][:, :, :2]
    Ke = fe_matrices(spec, x, d_matrix(E_MOD, NU, 2), thickness=1.0, penalty=alpha * mu)
    space = element.unknowns
    bs = space.dofmap.index_map_bs
    dense = np.zeros_like(K)
    for c in range(len(cells)):
        blocks = space.dofmap.cell_dofs(c)
        dofs = (blocks[:, None] * bs + np.arange(bs)).ravel()
        dense[np.ix_(dofs, dofs)] += Ke[c]
    element.destroy()
    np.testing.assert_allclose(dense, K, atol=1e-12 * np.abs(K).max())


def test_an_element_is_one_factory_and_one_registry_entry(monkeypatch):
    """A new element needs its module (here p2's factory, reused) and one registry line.

    The loader, the problem choice and the run then take it with nothing else changed.
    """
    twin = dataclasses.replace(elements.get("p2"), name="p2_twin", description="P2, renamed")
    monkeypatch.setitem(elements.REGISTRY, "p2_twin", twin)
    results = {}
    for name in ("p2_twin", "p2"):
        solution = solve_job("cantilever", f"discretization.element={name}", comm=MPI.COMM_SELF)
        assert solution.scene.discretization.element == name
        solution.problem.destroy()
        results[name] = solution.results
    twin_results = results["p2_twin"]
    tip, exact = twin_results["probes"]["tip"][1], twin_results["exact_probes"]["tip"][1]
    assert tip == pytest.approx(exact, rel=0.01)  # Timoshenko's closed form
    assert tip == results["p2"]["probes"]["tip"][1]
