"""MUMPS helpers against dense numpy solves, on 1 rank and on all ranks."""

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from geofrac.solvers import LinearSolver, mumps_inverse_entries, mumps_sparse_solve
from tests.petsc_matrices import aij_from_dense

N = 60


def _dense(n: int = N) -> np.ndarray:
    """A nonsymmetric, well-conditioned matrix with a banded and a random part."""
    rng = np.random.default_rng(3)
    A = np.diag(np.full(n, 4.0)) - np.diag(np.ones(n - 1), 1) - np.diag(np.ones(n - 2), -2)
    return A + 0.05 * rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.1)


def _factor(comm: MPI.Comm, A: np.ndarray) -> tuple[PETSc.Mat, LinearSolver]:
    M = aij_from_dense(comm, A)
    return M, LinearSolver(M, "test_mumps_", "direct", {}, len(A))


@pytest.mark.parametrize(
    "comm",
    [
        pytest.param(MPI.COMM_SELF, id="self"),
        pytest.param(MPI.COMM_WORLD, id="world", marks=pytest.mark.mpi(min_size=2)),
    ],
)
def test_sparse_rhs_solve_and_inverse_entries_match_numpy(comm):
    A = _dense()
    inv = np.linalg.inv(A)
    M, solver = _factor(comm, A)
    out, dense = M.createVecRight(), M.createVecRight()
    try:
        F = solver.ksp.getPC().getFactorMatrix()
        r0, r1 = out.getOwnershipRange()
        rows = np.array([41, 3, 17, 5])  # unsorted on purpose
        values = np.array([1.0, -2.0, 0.5, 3.0])
        mumps_sparse_solve(F, rows, values, out)
        b = np.zeros(N)
        b[rows] = values
        np.testing.assert_allclose(out.array, (inv @ b)[r0:r1], rtol=0, atol=1e-12)
        # the factor still solves dense right-hand sides afterwards
        rhs = M.createVecLeft()
        rhs.array[:] = np.arange(r0, r1, dtype=float)
        solver.ksp.solve(rhs, dense)
        np.testing.assert_allclose(dense.array, (inv @ np.arange(N))[r0:r1], atol=1e-11)
        rhs.destroy()
        want_r, want_c = np.array([7, 2, 50, 33]), np.array([33, 0, 2])
        entries = mumps_inverse_entries(F, want_r, want_c)
        np.testing.assert_allclose(entries, inv[np.ix_(want_r, want_c)], atol=1e-13)
    finally:
        for obj in (out, dense, M):
            obj.destroy()
        solver.destroy()
