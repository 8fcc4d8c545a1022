"""EFMM numpy reference (Edo (2016), §3.2): domains tile the mesh, patch test, rigid modes."""

import numpy as np
import pytest

from geofrac.elements.efmm_numpy import integration_domains, node_stiffness, stiffness
from geofrac.materials import d_matrix
from tests.blocks.conftest import square_mesh


def _distorted(n=6, seed=1, amount=0.3):
    points, tris = square_mesh(n)
    inside = np.all((points > 0) & (points < 1), axis=1)
    points[inside] += np.random.default_rng(seed).uniform(-amount, amount, (inside.sum(), 2)) / n
    return points, tris, inside


D = d_matrix(1000.0, 0.2, 2, plane="stress")


@pytest.mark.parametrize("q_rand", [0.0, 0.5])
def test_domains_tile_the_mesh(q_rand):
    points, tris, _ = _distorted()
    tris[::2] = tris[::2][:, [0, 2, 1]]  # clockwise cells are reoriented
    domains = integration_domains(points, tris, q_rand, seed=3)
    c = domains.corners
    area = 0.5 * (
        (c[:, 1, 0] - c[:, 0, 0]) * (c[:, 2, 1] - c[:, 0, 1])
        - (c[:, 2, 0] - c[:, 0, 0]) * (c[:, 1, 1] - c[:, 0, 1])
    )
    assert area.min() > 0  # every sub-triangle counter-clockwise, none degenerate
    assert abs(area.sum() - 1.0) < 1e-14
    per_node = np.bincount(domains.node, weights=area, minlength=len(points))
    assert per_node.min() > 0 and domains.clamped == 0


@pytest.mark.parametrize("q_rand", [0.0, 0.5])
def test_constant_strain_patch_test_is_exact_on_a_distorted_mesh(q_rand):
    points, tris, inside = _distorted()
    K = stiffness(points, tris, D, q_rand=q_rand, seed=3)
    exact = np.zeros(2 * len(points))
    exact[0::2] = 0.002 * points[:, 0] + 0.0005 * points[:, 1]
    exact[1::2] = -0.0006 * points[:, 1] + 0.0002 * points[:, 0]
    fixed = np.flatnonzero(np.repeat(~inside, 2))
    free = np.flatnonzero(np.repeat(inside, 2))
    u = exact.copy()
    u[free] = np.linalg.solve(K[np.ix_(free, free)], -K[np.ix_(free, fixed)] @ exact[fixed])
    assert np.abs(u - exact).max() < 1e-10 * np.abs(exact).max()


def test_a_free_mesh_has_exactly_three_rigid_modes():
    points, tris, _ = _distorted(5, seed=2)
    K = stiffness(points, tris, D, q_rand=0.5, seed=4)
    assert np.abs(K - K.T).max() < 1e-10 * np.abs(K).max()
    eig = np.linalg.eigvalsh(0.5 * (K + K.T))
    assert np.count_nonzero(np.abs(eig) < 1e-9 * eig.max()) == 3
    assert eig.min() > -1e-9 * eig.max()
    # the rigid modes are in the null space
    x, y = points[:, 0], points[:, 1]
    modes = np.zeros((2 * len(points), 3))
    modes[0::2, 0], modes[1::2, 1] = 1.0, 1.0
    modes[0::2, 2], modes[1::2, 2] = -y, x
    assert np.abs(K @ modes).max() < 1e-9 * np.abs(K).max()


def test_a_node_stiffness_acts_on_its_patch_only():
    points, tris, inside = _distorted(4, seed=5)
    domains = integration_domains(points, tris)
    node = int(np.flatnonzero(inside)[0])
    K, dofs = node_stiffness(points, tris, D, domains=domains, node=node)
    patch = np.unique(tris[np.any(tris == node, axis=1)])
    np.testing.assert_array_equal(np.unique(dofs // 2), patch)
    assert K.shape == (len(dofs), len(dofs))
    assert np.linalg.matrix_rank(K) <= 9  # at most the 9 stress coefficients
