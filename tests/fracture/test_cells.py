"""Cell matrices of the crack driver against DOLFINx's assembly of the UFL forms."""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac import elements
from geofrac.fracture.cells import MlsTable, fe_matrices, principal_max
from geofrac.fracture.context import gather_mesh
from geofrac.materials import d_matrix, lame
from tests.fem.helpers import solve_job


@pytest.mark.parametrize("element", ["cst", "rgnt", "gnt"])
def test_fe_matrices_match_dolfinx(element):
    """Σ cell matrices (numpy) = the reduced UFL stiffness, before Dirichlet rows."""
    from petsc4py import PETSc

    sol = solve_job(
        "patch_test",
        f"discretization.element={element}",
        "geometry.parameters.h=1.0",
        comm=MPI.COMM_SELF,
    )
    p = sol.problem
    try:
        mat = sol.scene.material
        _, mu = lame(mat.E, mat.nu, 2, plane=mat.plane)
        space = p.unknown().function_space
        gm = gather_mesh(sol.tagged.mesh, space)
        bs = space.dofmap.index_map_bs
        K = fe_matrices(
            elements.get(element),
            gm.coords[gm.cells],
            d_matrix(mat.E, mat.nu, 2, plane=mat.plane),
            thickness=mat.thickness,
            penalty=sol.scene.discretization.zero_mode_penalty * mu,
        )
        n = len(gm.coords) * bs
        dofs = (gm.node_block[gm.cells][:, :, None] * bs + np.arange(bs)).reshape(len(gm.cells), -1)
        dense = np.zeros((n, n))
        for c in range(len(gm.cells)):
            dense[np.ix_(dofs[c], dofs[c])] += K[c]
        rows, _ = p.dirichlet()
        free = np.setdiff1d(np.arange(n), rows)
        ref = p.A.convert("dense").getDenseArray()  # Dirichlet rows/cols replaced by identity
        scale = np.abs(dense).max()
        np.testing.assert_allclose(
            dense[np.ix_(free, free)], ref[np.ix_(free, free)], atol=1e-11 * scale
        )
        assert isinstance(p.A, PETSc.Mat)
    finally:
        p.destroy()


def test_principal_max():
    s = np.array([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 1.0], [-1.0, -3.0, 0.0]])
    np.testing.assert_allclose(principal_max(s), [1.0, 2.0, 1.0, -1.0])


def test_mls_table_strains_match_each_cell():
    """Padded rows give each cell's B u; removed rows give zero and are reused."""
    rng = np.random.default_rng(5)
    n = 50
    u = rng.normal(size=n)
    table = MlsTable(n)
    cells = {}
    for c, p in [(3, 4), (8, 10), (11, 6), (20, 24)]:  # the 24-DOF cell widens the table
        dofs = rng.choice(n, size=p, replace=False)
        B = rng.normal(size=(3, p))
        table.set(c, dofs, B, weight=1.0)
        cells[c] = (dofs, B)
    table.remove(8)
    dofs, B = rng.choice(n, size=8, replace=False), rng.normal(size=(3, 8))
    table.set(30, dofs, B, weight=2.0)  # takes the freed row
    cells[30] = (dofs, B)
    del cells[8]
    eps = table.strains(np.append(u, 0.0))
    assert len(table.cells) == 16 and sorted(table.row) == sorted(cells)
    for c, (dofs, B) in cells.items():
        np.testing.assert_allclose(eps[table.row[c]], B @ u[dofs], rtol=1e-13)
    free = table.cells < 0
    np.testing.assert_array_equal(eps[free], 0.0)
    assert table.weight[table.row[30]] == 2.0


@pytest.mark.parametrize("element", ["cst", "rgnt"])
def test_cell_stresses_of_a_uniform_strain(element):
    """A linear field u = ε x: σ = D ε at every midpoint, energy = ½ t A εᵀ D ε per cell."""
    from geofrac.elements.kinematics import KINDS, dofs_from_gradient
    from geofrac.fracture.cells import MIDPOINTS, strain_operator
    from geofrac.fracture.units import cell_stresses, cell_stresses_numpy

    spec = elements.get(element)
    rng = np.random.default_rng(3)
    x = np.array([[[0.0, 0.0], [2.0, 0.1], [0.3, 1.5]], [[1.0, 1.0], [1.5, 2.5], [0.2, 1.8]]])
    D, t = d_matrix(30.0, 0.2, 2, plane="strain"), 0.5
    grad = rng.normal(size=(2, 2))
    eps = np.array([grad[0, 0], grad[1, 1], grad[0, 1] + grad[1, 0]])  # engineering shear
    bs = (
        2
        if spec.kinematics is None
        else 2 + len(dofs_from_gradient(KINDS[spec.kinematics], grad[None])[0])
    )
    nodal = []
    for cell in x:
        per_node = [grad @ p for p in cell]
        if spec.kinematics is not None:
            extra = dofs_from_gradient(KINDS[spec.kinematics], grad[None])[0]
            per_node = [np.concatenate([v, extra]) for v in per_node]
        nodal.append(np.concatenate(per_node))
    u = np.concatenate(nodal)
    dofs = np.arange(len(u)).reshape(2, 3 * bs)
    S = np.einsum("ij,cqjp->cqip", D, strain_operator(spec, x, MIDPOINTS)).reshape(2, 9, -1)
    K = fe_matrices(spec, x, D, thickness=t, penalty=0.0)
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    sigma = D @ eps
    s1_exact = principal_max(sigma)
    use = np.array([True, True])
    for f in (cell_stresses_numpy, cell_stresses):
        s1, sig, energy = f(S, K, dofs, u=u, use=use)
        np.testing.assert_allclose(sig, np.tile(sigma, (2, 3)), rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(s1, s1_exact, rtol=1e-12)
        assert energy == pytest.approx(0.5 * t * area.sum() * eps @ sigma, rel=1e-12)
    s1, sig, energy = cell_stresses(S, K, dofs, u=u, use=np.array([False, True]))
    assert not s1[0].any() and not sig[0].any()  # a cell not used is left alone
    assert energy == pytest.approx(0.5 * t * area[1] * eps @ sigma, rel=1e-12)


def test_cell_stresses_kernel_matches_numpy_on_random_cells():
    """The compiled pass agrees with the numpy reference on arbitrary operators."""
    from geofrac.fracture.units import cell_stresses, cell_stresses_numpy

    rng = np.random.default_rng(5)
    nc, nd, n = 200, 9, 500
    S, K = rng.normal(size=(nc, 9, nd)), rng.normal(size=(nc, nd, nd))
    dofs, u = rng.integers(0, n, size=(nc, nd)), rng.normal(size=n)
    use = rng.random(nc) < 0.7
    ref, got = (
        cell_stresses_numpy(S, K, dofs, u=u, use=use),
        cell_stresses(S, K, dofs, u=u, use=use),
    )
    np.testing.assert_allclose(got[0], ref[0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(got[1], ref[1], rtol=1e-12, atol=1e-12)
    assert got[2] == pytest.approx(ref[2], rel=1e-12)
