"""Cell matrices of the crack driver against DOLFINx's assembly of the UFL forms."""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.fracture.cells import fe_matrices, principal_max
from geofrac.fracture.driver import gather_mesh
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
        _, mu = lame(mat.E, mat.nu, 2, mat.plane)
        space = p._unknown().function_space
        gm = gather_mesh(sol.tagged.mesh, space)
        bs = space.dofmap.index_map_bs
        K = fe_matrices(
            element,
            gm.coords[gm.cells],
            d_matrix(mat.E, mat.nu, 2, mat.plane),
            mat.thickness,
            sol.scene.discretization.zero_mode_penalty * mu,
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
