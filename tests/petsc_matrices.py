"""PETSc matrices from dense numpy arrays for solver tests (each rank fills its rows)."""

import dolfinx_solver  # noqa: F401

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

__all__ = ["aij_from_dense"]


def aij_from_dense(comm: MPI.Comm, A: np.ndarray) -> PETSc.Mat:
    """An assembled AIJ matrix on ``comm`` with the nonzeros of A, shape=(n, n)."""
    n = len(A)
    M = PETSc.Mat().createAIJ((n, n), comm=comm)
    M.setUp()
    r0, r1 = M.getOwnershipRange()
    for i in range(r0, r1):
        cols = np.flatnonzero(A[i]).astype(PETSc.IntType)
        M.setValues(i, cols, A[i, cols])
    M.assemble()
    return M
