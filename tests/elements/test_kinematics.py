"""The vertex-gradient-DOF fields of RGNT, GNT and RGNQ as P2 maps (pure numpy)."""

import basix
import numpy as np
import pytest

from geofrac.elements.kinematics import (
    KINDS,
    dofs_from_gradient,
    local_prolongation,
    vertex_field,
)

EDGES = {
    2: np.array(basix.topology(basix.CellType.triangle)[1]),
    3: np.array(basix.topology(basix.CellType.tetrahedron)[1]),
}


def _cell(gdim, seed):
    rng = np.random.default_rng(seed)
    ref = np.vstack([np.zeros(gdim), np.eye(gdim)])
    return ref @ (np.eye(gdim) + 0.3 * rng.standard_normal((gdim, gdim))) + rng.standard_normal(
        gdim
    )


def _p2_nodes(coords, edges):
    return np.vstack([coords, 0.5 * (coords[edges[:, 0]] + coords[edges[:, 1]])])


@pytest.mark.parametrize("name", ["rgnt", "gnt", "rgnq"])
def test_local_map_equals_the_thesis_field_at_the_p2_nodes(name):
    """T_loc w gives eq. (2.1)/(2.29)/(2.5) evaluated directly, at every P2 node."""
    kind = KINDS[name]
    gdim, edges = kind.gdim, EDGES[kind.gdim]
    coords = _cell(gdim, 1)
    dofs = np.random.default_rng(2).standard_normal((gdim + 1, kind.block_size))
    T = local_prolongation(kind, coords[None], edges)[0]
    mapped = np.einsum("nrid,id->nr", T, dofs)
    direct = vertex_field(kind, coords, dofs, points=_p2_nodes(coords, edges))
    np.testing.assert_allclose(mapped, direct, atol=1e-13)


@pytest.mark.parametrize("name", ["rgnt", "gnt", "rgnq"])
def test_constant_extra_dofs_move_no_node(name):
    """The spurious zero-energy modes the penalty must remove."""
    kind = KINDS[name]
    coords = _cell(kind.gdim, 3)
    dofs = np.zeros((kind.gdim + 1, kind.block_size))
    dofs[:, kind.gdim :] = np.random.default_rng(4).standard_normal(len(kind.names))
    T = local_prolongation(kind, coords[None], EDGES[kind.gdim])[0]
    assert np.abs(np.einsum("nrid,id->nr", T, dofs)).max() < 1e-15


def test_gnt_reproduces_every_quadratic_with_half_gradients():
    kind = KINDS["gnt"]
    rng = np.random.default_rng(5)
    A, B, c = rng.standard_normal((2, 2, 2)), rng.standard_normal((2, 2)), rng.standard_normal(2)
    A = 0.5 * (A + A.transpose(0, 2, 1))

    def u(x):  # u_r = x·A_r·x + B_r·x + c_r
        return np.einsum("ni,rij,nj->nr", x, A, x) + x @ B.T + c

    def grad(x):
        return 2.0 * np.einsum("rij,nj->nri", A, x) + B

    coords = _cell(2, 6)
    dofs = np.hstack([u(coords), dofs_from_gradient(kind, grad(coords))])
    points = _p2_nodes(coords, EDGES[2])
    np.testing.assert_allclose(
        vertex_field(kind, coords, dofs, points=points), u(points), atol=1e-13
    )
    # whereas the full nodal gradient (not halved) does not reproduce it
    full = np.hstack([u(coords), 2.0 * dofs_from_gradient(kind, grad(coords))])
    assert np.abs(vertex_field(kind, coords, full, points=points) - u(points)).max() > 1e-3


@pytest.mark.parametrize("name", ["rgnt", "rgnq"])
def test_rotational_elements_reproduce_their_quadratic_family(name):
    """The field (k·x)(e × x) with θ = (k·x) e (e = e_z in 2D) lies in the RGNT/RGNQ space."""
    kind = KINDS[name]
    gdim = kind.gdim
    k = np.array([0.7, -1.3, 0.4])[:gdim]
    axes = [np.array([0.0, 0.0, 1.0])] if gdim == 2 else list(np.eye(3))
    coords = _cell(gdim, 7)
    points = _p2_nodes(coords, EDGES[gdim])
    for a, e in enumerate(axes):

        def u(x, e=e):
            x3 = np.hstack([x, np.zeros((len(x), 3 - gdim))])
            return (x @ k)[:, None] * np.cross(e, x3)[:, :gdim]

        dofs = np.zeros((gdim + 1, kind.block_size))
        dofs[:, :gdim] = u(coords)
        dofs[:, gdim + a] = coords @ k
        np.testing.assert_allclose(
            vertex_field(kind, coords, dofs, points=points), u(points), atol=1e-13
        )


def test_dofs_of_a_rigid_rotation_are_half_the_rotation():
    grad2 = np.array([[[0.0, -0.4], [0.4, 0.0]]])  # u = 0.4 (-y, x): ω = 0.4
    assert dofs_from_gradient(KINDS["rgnt"], grad2)[0] == pytest.approx([0.2])
    assert dofs_from_gradient(KINDS["gnt"], grad2)[0] == pytest.approx([0.2, 0.0, 0.0, 0.0])
    w = np.array([0.1, -0.2, 0.3])
    grad3 = np.cross(w, np.eye(3)).T[None]  # ∇(w × x)
    assert dofs_from_gradient(KINDS["rgnq"], grad3)[0] == pytest.approx(0.5 * w)
