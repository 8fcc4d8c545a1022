"""Distributed matrices and null spaces: creation, Dirichlet elimination, extraction.

Every matrix returned here is new and assembled; the caller destroys it. Global
indices are converted to :data:`~geofrac.solvers.types.INDEX` here, so callers pass
any integer arrays.
"""

from __future__ import annotations

from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

__all__ = [
    "add_matrix",
    "block_diagonal",
    "coo_matrix",
    "csr_matrix",
    "dense_submatrix",
    "diagonal_norm1",
    "orthonormal_nullspace",
    "rigid_body_modes",
    "transposed",
    "widened",
    "zero_rows_columns",
]


def coo_matrix(
    comm: MPI.Comm,
    sizes: tuple[int, int],
    entries: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> PETSc.Mat:
    """A square AIJ matrix summed from COO entries (entries of other ranks' rows allowed).

    Args:
        comm: the matrix's communicator.
        sizes: (owned rows, global rows); the columns are laid out like the rows.
        entries: (global rows, global columns, values), each shape=(nnz,); repeated
            (row, column) pairs are added.
    """
    rows, cols, vals = entries
    A = PETSc.Mat().create(comm)
    A.setSizes((sizes, sizes))
    A.setType(PETSc.Mat.Type.AIJ)
    A.setPreallocationCOO(rows.astype(PETSc.IntType), cols.astype(PETSc.IntType))
    A.setValuesCOO(vals, addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()
    return A


def csr_matrix(
    comm: MPI.Comm,
    sizes: tuple[tuple[int, int], tuple[int, int]],
    csr: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> PETSc.Mat:
    """An AIJ matrix from the CSR of each rank's owned rows.

    Args:
        comm: the matrix's communicator.
        sizes: ((owned rows, global rows), (owned columns, global columns)).
        csr: (row pointers, shape=(owned rows + 1,); global columns, shape=(nnz,);
            values, shape=(nnz,)).
    """
    indptr, cols, vals = csr
    M = PETSc.Mat().createAIJ(
        size=sizes,
        csr=(indptr.astype(PETSc.IntType), cols.astype(PETSc.IntType), vals),
        comm=comm,
    )
    M.assemble()
    return M


def block_diagonal(blocks: np.ndarray, space: Any) -> PETSc.Mat:
    """A block-diagonal AIJ matrix on ``space`` from owned blocks, shape=(n_owned, bs, bs).

    ``space`` is a blocked DOLFINx function space of block size bs; the caller destroys
    the matrix.
    """
    imap, bs = space.dofmap.index_map, space.dofmap.index_map_bs
    n = imap.size_local
    first = imap.local_range[0] * bs
    cols = first + (np.arange(n)[:, None, None] * bs + np.arange(bs)[None, None, :])
    cols = np.broadcast_to(cols, (n, bs, bs)).reshape(-1)
    indptr = np.arange(n * bs + 1) * bs
    size = (n * bs, imap.size_global * bs)
    return csr_matrix(space.mesh.comm, (size, size), (indptr, cols, blocks.reshape(-1)))


def zero_rows_columns(A: PETSc.Mat, rows: np.ndarray, values: np.ndarray, *, b: PETSc.Vec) -> None:
    """Impose x[rows] = values on A x = b by symmetric elimination, in place.

    ``MatZeroRowsColumns`` with lifting: the rows and columns become those of the
    identity and b takes the columns' share of the values (b -= A[:, rows] values,
    b[rows] = values).

    Args:
        A: assembled square matrix.
        rows: owned global indices, shape=(p,).
        values: their values, shape=(p,).
        b: the right-hand side.
    """
    rows = rows.astype(PETSc.IntType)
    g = A.createVecRight()
    try:
        g.setValues(rows, values)
        g.assemble()
        A.zeroRowsColumns(rows, 1.0, g, b)
    finally:
        g.destroy()


def transposed(A: PETSc.Mat) -> PETSc.Mat:
    """Aᵀ as a new matrix (petsc4py's ``transpose()`` without an output works in place)."""
    return A.transpose(PETSc.Mat())


def add_matrix(A: PETSc.Mat, B: PETSc.Mat) -> None:
    """A += B, in place, B with any nonzero pattern (A is not reassembled here)."""
    A.axpy(1.0, B, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)


def dense_submatrix(A: PETSc.Mat, dofs: np.ndarray) -> np.ndarray:
    """A[dofs, dofs] as a dense array on every rank, shape=(k, k) (collective).

    Args:
        A: assembled matrix.
        dofs: global indices, the same on every rank, shape=(k,).
    """
    index = PETSc.IS().createGeneral(dofs.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
    try:
        (sub,) = A.createSubMatrices(index)
        try:
            return sub.convert(PETSc.Mat.Type.DENSE).getDenseArray().copy()
        finally:
            sub.destroy()
    finally:
        index.destroy()


def diagonal_norm1(A: PETSc.Mat) -> float:
    """Σ |A_ii| over the whole diagonal (collective)."""
    diag = A.createVecLeft()
    try:
        A.getDiagonal(diag)
        return diag.norm(PETSc.NormType.NORM_1)
    finally:
        diag.destroy()


def rigid_body_modes(space: Any) -> PETSc.NullSpace:
    """Orthonormalised rigid body modes of a vector space (3 in 2D, 6 in 3D)."""
    dofmap = space.dofmap
    bs = dofmap.index_map_bs
    n_local = dofmap.index_map.size_local
    x = space.tabulate_dof_coordinates()[:n_local]
    gdim = bs
    n_modes = 3 if gdim == 2 else 6
    modes = [np.zeros(n_local * bs) for _ in range(n_modes)]
    for i in range(gdim):
        modes[i][i::bs] = 1.0
    if gdim == 2:
        modes[2][0::bs], modes[2][1::bs] = -x[:, 1], x[:, 0]
    else:
        modes[3][0::bs], modes[3][1::bs] = -x[:, 1], x[:, 0]
        modes[4][1::bs], modes[4][2::bs] = -x[:, 2], x[:, 1]
        modes[5][0::bs], modes[5][2::bs] = x[:, 2], -x[:, 0]
    return orthonormal_nullspace(modes, dofmap.index_map.comm)


def orthonormal_nullspace(modes: list[np.ndarray], comm: MPI.Comm) -> PETSc.NullSpace:
    """A PETSc null space spanned by ``modes``, orthonormalised (modified Gram–Schmidt).

    Args:
        modes: owned entries of each mode, each shape=(num_owned_dofs,).
        comm: MPI communicator of the vectors.
    """
    vecs = []
    for m in modes:
        v = PETSc.Vec().createMPI((len(m), None), comm=comm)
        v.setArray(m)
        vecs.append(v)
    for i, v in enumerate(vecs):
        for w in vecs[:i]:
            v.axpy(-v.dot(w), w)
        v.normalize()
    nullspace = PETSc.NullSpace().create(vectors=vecs, comm=comm)
    for v in vecs:  # the null space holds its own references
        v.destroy()
    return nullspace


def widened(J: Any, rows: np.ndarray, cols: np.ndarray) -> PETSc.Mat:
    """The matrix of the bilinear form J with the entries (rows, cols) added to its pattern.

    A form's matrix refuses entries outside its pattern, and letting PETSc grow it entry
    by entry copies the whole matrix at every row that grows (minutes for a 3D joint's
    pairs). The union of the form's sparsity pattern and the entries is preallocated
    exactly (the form's pattern read from one assembly of it), with the sizes, block size
    and local-to-global map DOLFINx gives the form's matrix, so DOLFINx assembles into it
    as into its own.

    Args:
        J: a compiled DOLFINx bilinear form.
        rows: global scalar rows owned by this rank, shape=(k,).
        cols: global scalar columns, shape=(k,).

    Returns:
        The matrix (zeros in its pattern), assembled.
    """
    import dolfinx.fem.petsc

    A = dolfinx.fem.petsc.create_matrix(J)
    try:
        # the form's pattern: the entries one assembly inserts (zeros included)
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(A, J)
        A.assemble()
        lo, hi = A.getOwnershipRange()
        indptr, indices, _ = A.getValuesCSR()
        local = np.repeat(np.arange(hi - lo, dtype=np.int64), np.diff(indptr))
        r = np.concatenate([local, np.asarray(rows, dtype=np.int64) - lo])
        c = np.concatenate([np.asarray(indices, dtype=np.int64), np.asarray(cols, dtype=np.int64)])
        if len(r) and (r.min() < 0 or r.max() >= hi - lo):
            raise ValueError("widened: a row is not owned by this rank")
        pairs = np.unique(np.stack([r, c], axis=1), axis=0)
        counts = np.bincount(pairs[:, 0], minlength=hi - lo)
        ptr = np.concatenate([[0], np.cumsum(counts)]).astype(PETSc.IntType)
        B = PETSc.Mat().create(comm=A.getComm())
        B.setSizes(A.getSizes(), bsize=A.getBlockSizes())
        B.setType(A.getType())
        B.setPreallocationCSR((ptr, pairs[:, 1].astype(PETSc.IntType)))
        B.setLGMap(*A.getLGMap())
        B.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        B.assemble()
    finally:
        A.destroy()
    return B
