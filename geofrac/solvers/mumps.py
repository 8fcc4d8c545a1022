"""MUMPS factorisations beyond a plain solve: selected inverse entries, sparse solves.

Both take the factor matrix of a direct :class:`~geofrac.solvers.linear.LinearSolver`
(:meth:`~geofrac.solvers.linear.LinearSolver.factor`) and hand MUMPS its sparse
right-hand sides on rank 0, as it wants them. The ICNTL controls each call changes are
restored afterwards, so the factor solves as before.
"""

from __future__ import annotations

import ctypes
import functools
from pathlib import Path

import dolfinx_solver  # orders MPI before the DOLFINx bindings; its lib/ holds libpetsc

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from geofrac.errors import RunError

__all__ = ["mumps_inverse_entries", "mumps_sparse_solve"]


@functools.cache
def _petsc_library() -> ctypes.CDLL:
    """The PETSc shared library petsc4py is linked to (for calls petsc4py does not wrap)."""
    libs = sorted(Path(dolfinx_solver.__path__[0], "lib").glob("libpetsc.so*"))
    if not libs:
        raise RunError("libpetsc not found next to dolfinx_solver; reinstall the venv")
    lib = ctypes.CDLL(str(libs[0]))
    lib.MatMumpsGetInverse.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    lib.MatMumpsGetInverse.restype = ctypes.c_int
    return lib


def _rank0_aij(
    pcomm: PETSc.Comm,
    shape: tuple[int, int],
    indptr: np.ndarray,
    *,
    indices: np.ndarray,
    values: np.ndarray,
) -> PETSc.Mat:
    """An assembled AIJ matrix held, rows and columns, wholly on rank 0 (from its CSR).

    The layout MUMPS wants for sparse right-hand sides: PETSc hands it rank 0's
    diagonal block only, so rank 0 must own every column too. Other ranks' CSR
    arguments are ignored.

    Args:
        pcomm: the PETSc communicator.
        shape: global (rows, columns).
        indptr: CSR row pointers, shape=(rows + 1,).
        indices: CSR column indices, shape=(nnz,).
        values: CSR values, shape=(nnz,).
    """
    nrows, ncols = shape
    rank0 = pcomm.tompi4py().rank == 0
    A = PETSc.Mat().create(pcomm)
    A.setSizes(((nrows if rank0 else 0, nrows), (ncols if rank0 else 0, ncols)))
    A.setType(PETSc.Mat.Type.AIJ)
    if rank0:
        ip, ix = indptr.astype(PETSc.IntType), indices.astype(PETSc.IntType)
        A.setPreallocationCSR((ip, ix))
        A.setValuesCSR(ip, ix, np.asarray(values, dtype=float))
    else:
        A.setPreallocationCSR((np.zeros(1, dtype=PETSc.IntType), np.zeros(0, dtype=PETSc.IntType)))
    A.assemble()
    return A


def mumps_inverse_entries(F: PETSc.Mat, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """Entries (A⁻¹)[rows, cols] from a MUMPS factor of A (collective), shape=(nr, nc).

    MUMPS computes selected entries of the inverse from sparse right-hand sides
    (ICNTL(30)), pruning its elimination tree to the requested rows and columns, which
    is far cheaper than full solves for a few columns (``MatMumpsGetInverse``; petsc4py
    does not wrap it, so it is called through ctypes). The request is built on rank 0,
    as MUMPS wants it; the result is broadcast to every rank. The solve controls the
    call changes (ICNTL 20, 21, 30) are restored, so ``F`` solves as before.

    Args:
        F: the MUMPS factor (:meth:`LinearSolver.factor`), on its communicator.
        rows: global row indices, the same on every rank, shape=(nr,).
        cols: global column indices, the same on every rank, shape=(nc,).
    """
    pcomm = F.getComm()
    comm = pcomm.tompi4py()
    n = F.getSize()[0]
    rows = np.asarray(rows, dtype=np.int64)
    cols = np.asarray(cols, dtype=np.int64)
    r_order, c_order = np.argsort(rows), np.argsort(cols)
    r_sorted, c_sorted = rows[r_order], cols[c_order]
    # Bt: row j lists the rows i of the requested A⁻¹(i, j)
    count = np.zeros(n, dtype=np.int64)
    count[c_sorted] = len(rows)
    indptr = np.concatenate([[0], np.cumsum(count)])
    indices = np.tile(r_sorted, len(cols))
    Bt = _rank0_aij(pcomm, (n, n), indptr, indices=indices, values=np.zeros(len(indices)))
    spRHS = PETSc.Mat().createTranspose(Bt)
    saved = {i: F.getMumpsIcntl(i) for i in (20, 21, 30)}
    try:
        err = _petsc_library().MatMumpsGetInverse(F.handle, spRHS.handle)
        values = Bt.getValuesCSR()[2] if comm.rank == 0 else None
    finally:
        for i, v in saved.items():
            F.setMumpsIcntl(i, v)
        spRHS.destroy()
        Bt.destroy()
    if comm.allreduce(err, op=MPI.MAX):
        raise RunError(f"MatMumpsGetInverse failed (PETSc error {err})")
    block = comm.bcast(values)
    out = np.empty((len(rows), len(cols)))
    out[np.ix_(r_order, c_order)] = block.reshape(len(cols), len(rows)).T
    return out


def mumps_sparse_solve(
    F: PETSc.Mat, rows: np.ndarray, values: np.ndarray, *, out: PETSc.Vec
) -> None:
    """Solve A out = b for a right-hand side b with few nonzeros (collective).

    MUMPS prunes the forward elimination to the subtrees that hold b's nonzeros when it
    gets b as a sparse right-hand side (ICNTL(20) = 1, through ``MatMatSolve`` with a
    transposed AIJ matrix); the backward pass stays full, as the solution is dense. For a
    few hundred nonzeros in a 2D system of 10^5 DOFs this is cheaper than a dense-vector
    solve. The right-hand side is handed to MUMPS on rank 0, as it wants it.

    Args:
        F: the MUMPS factor (:meth:`LinearSolver.factor`), on its communicator.
        rows: global indices of b's nonzeros, the same on every rank, shape=(k,).
        values: b at ``rows``, the same on every rank, shape=(k,).
        out: the solution, laid out as the factor's rows (ghosts are not updated).
    """
    pcomm = F.getComm()
    n = F.getSize()[0]
    n_local = out.getLocalSize()
    order = np.argsort(rows)
    indptr = np.array([0, len(rows)])
    Bt = _rank0_aij(
        pcomm, (1, n), indptr, indices=np.asarray(rows)[order], values=np.asarray(values)[order]
    )
    B = PETSc.Mat().createTranspose(Bt)
    X = PETSc.Mat().createDense(((n_local, n), (None, 1)), comm=pcomm)
    X.setUp()
    saved = F.getMumpsIcntl(20)
    try:
        F.matSolve(B, X)
        out.array[:] = X.getDenseArray()[:, 0]
    finally:
        F.setMumpsIcntl(20, saved)
        for obj in (X, B, Bt):
            obj.destroy()
