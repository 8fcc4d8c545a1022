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
