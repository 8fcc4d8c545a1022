"""The stress the crack criterion sees next to a load's end: the Brazilian disc.

The disc of tests/fracture/scenes/brazilian_disc_elastic.toml (D = 50 mm, strips of
2α = 10° under a unit pressure, h ≈ 1 mm, RGNT) is solved elastically on the three gmsh
meshers; each edge gets σ1 as the criterion forms it (Edo (2016), §2.3.2 with eq. 2.20:
the mean over its cells of each cell's largest principal stress at the edge's midpoint)
and is compared with the exact field (:func:`geofrac.validation.brazilian.brazilian_disc_stress`,
Hondros (1959)): σ_c = (2p/π)(sin 2α − α) = 0.05499 p at the centre, σ1 = 0 on the free rim.
"""

import math

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.fem.post import locate_points
from geofrac.fracture.cells import principal_max
from geofrac.fracture.topology import EdgeMesh, edge_mesh
from geofrac.meshing.geo import ALGORITHMS
from geofrac.runner import solve_scene
from geofrac.scene import load_scene
from geofrac.validation.brazilian import brazilian_centre_stress, brazilian_disc_stress
from tests.conftest import REPO

SCENE = REPO / "tests" / "fracture" / "scenes" / "brazilian_disc_elastic.toml"
R, ALPHA, P = 25.0, math.radians(5.0), 1.0  # the scene's radius, half strip, pressure
SIGMA_C = brazilian_centre_stress(P, ALPHA)[0]


def edge_sigma1(problem, coords: np.ndarray, em: EdgeMesh) -> np.ndarray:
    """σ1 per edge (eq. 2.20): the mean over its one or two cells of σ1 at its midpoint."""
    mid = em.midpoints()
    have = [em.edge_cells[:, k] >= 0 for k in (0, 1)]
    edges = np.concatenate([np.flatnonzero(h) for h in have])
    cells = np.concatenate([em.edge_cells[h, k] for k, h in enumerate(have)]).astype(np.int32)
    points = np.c_[mid[edges], np.zeros(len(edges))]
    s = problem.point_tensors(["stress"], points, cells)["stress"]
    s1 = principal_max(np.stack([s[:, 0, 0], s[:, 1, 1], s[:, 0, 1]], axis=-1))
    total, count = np.zeros(len(em.edges)), np.zeros(len(em.edges))
    np.add.at(total, edges, s1)
    np.add.at(count, edges, 1.0)
    return total / count


@pytest.fixture(scope="module", params=sorted(ALGORITHMS))
def disc(request):
    """(mesh edges, σ1_h per edge, exact σ1 per edge, distance to a strip end, σ_xx at 0)."""
    scene = load_scene(SCENE, [f"geometry.algorithm={request.param}"])
    sol = solve_scene(scene, MPI.COMM_SELF, verbose=False)
    try:
        mesh = sol.tagged.mesh
        coords = mesh.geometry.x[:, :2]
        em = edge_mesh(coords, np.asarray(mesh.geometry.dofmaps[0]))
        sigma1 = edge_sigma1(sol.problem, coords, em)
        centre = np.zeros((1, 3))
        sxx0 = sol.problem.point_tensors(["stress"], centre, locate_points(mesh, centre))
    finally:
        sol.problem.destroy()
    mid = em.midpoints()
    exact = principal_max(brazilian_disc_stress(mid[:, 0], mid[:, 1], p=P, radius=R, alpha=ALPHA))
    ends = R * np.array(
        [[sx * math.sin(ALPHA), sy * math.cos(ALPHA)] for sx in (-1, 1) for sy in (-1, 1)]
    )
    d = np.hypot(*(mid[:, None, :] - ends[None, :, :]).transpose(2, 0, 1)).min(axis=1)
    return em, sigma1, exact, d, float(sxx0["stress"][0, 0, 0])


def test_centre_stress(disc):
    """σ_xx at the centre within 1 % of (2p/π)(sin 2α − α) (measured: 0.1-0.4 %)."""
    assert disc[4] == pytest.approx(SIGMA_C, rel=0.01)


def test_interior_edges_away_from_the_ends(disc):
    """Interior edges over 5 mm from a strip's end: mean error ≤ 2 % of σ_c, max ≤ 30 %."""
    em, sigma1, exact, d, _ = disc
    far = ~em.boundary_edges & (d > 5.0)
    error = np.abs(sigma1 - exact)[far] / SIGMA_C
    assert error.mean() <= 0.02 and error.max() <= 0.3, (error.mean(), error.max())


def test_interior_edges_near_the_ends(disc):
    """Interior edges within 3 mm of a strip's end, where the traction jumps from p to 0.

    σ1 within 0.1 p of the exact field (measured ≤ 0.075 p; σ1 there spans about −1.3 p to
    0.14 σ_c), and no tensile σ1 above half the centre's (measured ≤ 0.44 σ_c): the first
    crack cannot start there.
    """
    em, sigma1, exact, d, _ = disc
    near = ~em.boundary_edges & (d < 3.0)
    assert near.sum() > 100
    assert np.abs(sigma1 - exact)[near].max() <= 0.1 * P
    assert sigma1[near].max() <= 0.5 * SIGMA_C


def test_the_largest_sigma1_is_on_the_loaded_diameter_near_the_centre(disc):
    em, sigma1, _, _, _ = disc
    x, y = em.midpoints()[np.argmax(sigma1)]
    assert abs(x) <= 2.0 and math.hypot(x, y) <= 0.5 * R


@pytest.mark.xfail(
    strict=True,
    reason="RGNT's recovered σ1 on the free rim next to a strip's end is tensile "
    "(0.3-0.9 σ_c on the three meshers; exact 0): the stress next to a load's end",
)
def test_rim_edges_next_to_a_strip_end_are_not_in_tension(disc):
    """Boundary edges outside the strips within 3 mm of an end: exact σ1 = 0 (free rim)."""
    em, sigma1, exact, d, _ = disc
    mid = em.midpoints()
    rim = em.boundary_edges & (d < 3.0) & (np.abs(mid[:, 0]) > R * math.sin(ALPHA))
    assert rim.sum() >= 8
    np.testing.assert_allclose(exact[rim], 0.0, atol=1e-3 * SIGMA_C)  # chord midpoints
    assert sigma1[rim].max() <= 0.1 * SIGMA_C
