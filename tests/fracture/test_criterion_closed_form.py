"""The crack criterion against closed forms (Edo (2016), eqs. 2.20-2.21).

σ1 of an edge is the mean of the largest principal stresses of its two cells at the
edge midpoint (Edo (2016), §2.3.2, with eq. 2.20), r = f_t / σ1 and the edge with the
least r cracks. Under a uniform stress every edge's σ1 is the principal stress of that
tensor, which is computed here independently (eigenvalues of the 2 x 2 tensor), and the
first event's load factor is f_t / σ1.
"""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.fracture.cells import principal_max
from geofrac.fracture.criterion import edge_principal, select_edges
from geofrac.fracture.topology import edge_mesh
from geofrac.mls.shape import linear_fit, strain_matrix
from tests.fracture.helpers import grid_mesh
from tests.fracture.reference import run_case

SCENE = Path(__file__).resolve().parent / "scenes" / "uniform_strain.toml"

E, NU, FT = 97.0, 0.25, 3.0  # the scene's material
#: plane-stress D (Voigt, engineering shear)
D = E / (1 - NU**2) * np.array([[1.0, NU, 0.0], [NU, 1.0, 0.0], [0.0, 0.0, (1 - NU) / 2]])

#: (σ_xx, σ_yy, σ_xy): uniaxial tension, biaxial, pure shear, tension with shear
STRESSES = [(2.0, 0.0, 0.0), (1.0, 3.0, 0.0), (0.0, 0.0, 1.5), (0.5, -1.0, 2.0)]


def closed_form_sigma1(s: tuple[float, float, float]) -> float:
    """Largest eigenvalue of [[σ_xx, σ_xy], [σ_xy, σ_yy]]."""
    return float(np.linalg.eigvalsh(np.array([[s[0], s[2]], [s[2], s[1]]]))[-1])


def uniform_edge_sigma1(s: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """(σ1 per edge, whether the edge has two cells) on a grid under the uniform stress s."""
    mesh = edge_mesh(*grid_mesh(6))
    stress = np.broadcast_to(np.array(s, dtype=float), (mesh.num_cells, 3, 3))
    return edge_principal(mesh, principal_max(stress)), ~mesh.boundary_edges


@pytest.mark.parametrize("s", STRESSES)
def test_uniform_stress_gives_every_edge_the_principal_stress(s):
    sigma1, interior = uniform_edge_sigma1(s)
    assert interior.sum() > 50 and (~interior).sum() > 10
    np.testing.assert_allclose(sigma1, closed_form_sigma1(s), rtol=1e-12)


def test_edge_stress_is_the_mean_of_its_two_cells():
    """Two cells with different σ1 at the shared edge: the edge gets their mean."""
    coords = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    mesh = edge_mesh(coords, np.array([[0, 1, 2], [1, 3, 2]]))
    s1 = np.array([[4.0, 4.0, 4.0], [1.0, 1.0, 1.0]])
    sigma1 = edge_principal(mesh, s1)
    shared = np.flatnonzero(~mesh.boundary_edges)
    assert len(shared) == 1
    assert sigma1[shared[0]] == pytest.approx(2.5, rel=1e-14)
    outer = mesh.boundary_edges
    np.testing.assert_allclose(np.sort(sigma1[outer]), [1.0, 1.0, 4.0, 4.0], rtol=1e-14)


@pytest.mark.parametrize("s", STRESSES)
def test_first_event_load_factor_is_strength_over_principal_stress(s):
    sigma1, _ = uniform_edge_sigma1(s)
    edges, r = select_edges(sigma1, np.ones(len(sigma1), bool), FT)
    assert r == pytest.approx(FT / closed_form_sigma1(s), rel=1e-12)
    assert edges.tolist() == [0]  # all tied: the lowest id


def test_compression_has_no_tensile_edge():
    sigma1, _ = uniform_edge_sigma1((-1.0, -2.0, 0.5))
    assert closed_form_sigma1((-1.0, -2.0, 0.5)) < 0
    edges, r = select_edges(sigma1, np.ones(len(sigma1), bool), FT)
    assert len(edges) == 0 and r == float("inf")


def test_mls_fit_reproduces_a_uniform_strain():
    """The MLS strain (eq. 2.19) of a linear field is its strain, whatever the weights."""
    coords, cells = grid_mesh(6)
    eps = np.array([0.002, -0.0005, 0.0013])  # ε_xx, ε_yy, γ_xy
    grad = np.array([[eps[0], 0.5 * eps[2]], [0.5 * eps[2], eps[1]]])
    u = coords @ grad.T + np.array([0.3, -0.1])  # plus a translation
    centre = coords[cells[20]].mean(axis=0)
    near = np.flatnonzero(np.hypot(*(coords - centre).T) < 2.5)
    fit = linear_fit(centre, 2.6, near, coords=coords[near])
    assert fit is not None
    np.testing.assert_allclose(strain_matrix(fit) @ u[near].ravel(), eps, atol=1e-15)


@pytest.mark.parametrize("strain", [(0.002, -0.0005, 0.0), (0.001, 0.0005, 0.002)])
def test_driver_first_event_under_uniform_strain(strain):
    """The event loop on a square under a uniform strain: r = f_t / σ1 (closed form).

    Every edge that may crack is interior (edges of cells touching the held boundary
    are frozen), so the mean of two equal cell values is that value.
    """
    sets = [f"exact.{k}={v}" for k, v in zip(("exx", "eyy", "gxy"), strain, strict=True)]
    events = run_case(str(SCENE), [*sets, "cracking.criterion=principal"], MPI.COMM_SELF)
    sigma = D @ np.array(strain)
    assert events.count == 1 and events.end_reason == "max_events"
    assert events.load_factor[0] == pytest.approx(FT / closed_form_sigma1(sigma), rel=1e-9)


@pytest.mark.parametrize("criterion", ["traction"])
@pytest.mark.parametrize("strain", [(0.002, -0.0005, 0.0), (0.001, 0.0005, 0.002)])
def test_first_event_under_uniform_strain_by_traction(strain, criterion):
    """The traction criterion's first event: r = f_t / max n·σ·n over the crack sites.

    The sites are the interior edges of
    the cells that touch no boundary node (the whole boundary is held); the edge
    normals come from the mesh's coordinates, the traction from the closed-form stress.
    """
    from geofrac.effects.cracking import scene_driver
    from geofrac.scene import load_scene_collective

    sets = [f"exact.{k}={v}" for k, v in zip(("exx", "eyy", "gxy"), strain, strict=True)]
    scene = load_scene_collective(MPI.COMM_SELF, SCENE, [*sets, f"cracking.criterion={criterion}"])
    driver = scene_driver(scene, MPI.COMM_SELF)
    try:
        driver.run()
    finally:
        driver.problem.destroy()
    mesh = driver.state.mesh
    x, cells = mesh.coords, mesh.cells
    pairs = np.sort(np.concatenate([cells[:, [1, 2]], cells[:, [2, 0]], cells[:, [0, 1]]]), axis=1)
    keys, count = np.unique(pairs, axis=0, return_counts=True)
    boundary_nodes = np.unique(keys[count == 1])
    held_cells = np.isin(cells, boundary_nodes).any(axis=1)
    held = np.unique(
        np.sort(np.concatenate([c[[[1, 2], [2, 0], [0, 1]]] for c in cells[held_cells]]), axis=1),
        axis=0,
    )
    sites = keys[(count == 2) & ~(keys[:, None, :] == held[None]).all(axis=2).any(axis=1)]
    t = x[sites[:, 1]] - x[sites[:, 0]]
    n = np.stack([-t[:, 1], t[:, 0]], axis=1) / np.hypot(*t.T)[:, None]
    sx, sy, sxy = D @ np.array(strain)
    traction = sx * n[:, 0] ** 2 + sy * n[:, 1] ** 2 + 2 * sxy * n[:, 0] * n[:, 1]
    rows = driver.rows
    assert len(rows) == 1
    assert rows[0]["load_factor"] == pytest.approx(FT / traction.max(), rel=1e-9)


@pytest.mark.parametrize("strain", [(0.002, -0.0005, 0.0), (0.001, 0.0005, 0.002)])
def test_direction_criterion_starts_a_crack_across_sigma1(strain):
    """No tip before the first event: r = f_t / σ1, on an edge nearly across σ1.

    Under a uniform stress every edge has the same σ1, so the new crack may start
    anywhere; it takes the edge at that place whose normal lies nearest to σ1's
    direction (closed form: the eigenvector of the stress), within 30° on this mesh.
    """
    sets = [f"exact.{k}={v}" for k, v in zip(("exx", "eyy", "gxy"), strain, strict=True)]
    events = run_case(
        str(SCENE), [*sets, "cracking.criterion=direction"], MPI.COMM_SELF, drawing=True
    )
    sigma = D @ np.array(strain)
    assert events.count == 1
    assert events.load_factor[0] == pytest.approx(FT / closed_form_sigma1(sigma), rel=1e-9)
    (a, b) = events.sites[0]
    t = (b - a) / np.hypot(*(b - a))
    _, vec = np.linalg.eigh(np.array([[sigma[0], sigma[2]], [sigma[2], sigma[1]]]))
    along = abs(float(t @ vec[:, -1]))  # |cos| of the edge to σ1: 0 when the edge is across
    assert along <= np.sin(np.radians(30.0))
