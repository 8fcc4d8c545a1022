"""PETSc linear solvers: presets, one options prefix per solver, clear failures.

Presets (``[solver] preset``):

- ``direct``: ``preonly`` + LU from MUMPS. Robust; memory grows fast in 3D.
- ``iterative``: CG + GAMG with the rigid body modes as near-nullspace, rtol 1e-10.
- ``auto``: ``direct`` up to :data:`AUTO_DIRECT_MAX_DOFS` DOFs, ``iterative`` above.

User options from ``[solver.options]`` are applied under the same prefix, after the
preset, so they win. They are removed from the global PETSc options database once the
solver has read them, so one solver's options never leak into the next.
"""

from __future__ import annotations

import ctypes
import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

import dolfinx_solver  # orders MPI before the DOLFINx bindings; its lib/ holds libpetsc

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from geofrac.errors import RunError

__all__ = [
    "AUTO_DIRECT_MAX_DOFS",
    "MAX_RELATIVE_RESIDUAL",
    "LinearSolver",
    "Matrix",
    "Vector",
    "block_diagonal",
    "mumps_inverse_entries",
    "mumps_sparse_solve",
    "orthonormal_nullspace",
    "preset_options",
    "rigid_body_modes",
]

#: The distributed matrix and vector types the rest of geofrac passes around (and annotates
#: with) without importing petsc4py.
Matrix = PETSc.Mat
Vector = PETSc.Vec

#: A solution whose relative residual ||b - Ax|| / ||b|| exceeds this is rejected.
MAX_RELATIVE_RESIDUAL = 1e-6

#: Largest problem the ``auto`` preset solves with a direct factorisation.
AUTO_DIRECT_MAX_DOFS = 300_000


def preset_options(preset: str, num_dofs: int) -> tuple[str, dict[str, str]]:
    """Return (resolved preset, PETSc options without prefix) for ``preset``."""
    if preset == "auto":
        preset = "direct" if num_dofs <= AUTO_DIRECT_MAX_DOFS else "iterative"
    if preset == "direct":
        return preset, {
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
            "mat_mumps_icntl_24": "1",  # detect null pivots: a singular system is an error
        }
    return preset, {
        "ksp_type": "cg",
        "ksp_rtol": "1e-10",
        "ksp_max_it": "2000",
        "pc_type": "gamg",
        "pc_gamg_type": "agg",
        "pc_gamg_coarse_eq_limit": "1000",
        "mg_levels_ksp_type": "chebyshev",
        "mg_levels_pc_type": "jacobi",
    }


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
    nrows: int,
    ncols: int,
    indptr: np.ndarray,
    indices: np.ndarray,
    values: np.ndarray,
) -> PETSc.Mat:
    """An assembled AIJ matrix held, rows and columns, wholly on rank 0 (from its CSR).

    The layout MUMPS wants for sparse right-hand sides: PETSc hands it rank 0's
    diagonal block only, so rank 0 must own every column too. Other ranks' CSR
    arguments are ignored.
    """
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
        F: the MUMPS factor (``pc.getFactorMatrix()``), on its communicator.
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
    Bt = _rank0_aij(pcomm, n, n, indptr, indices, np.zeros(len(indices)))
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


def mumps_sparse_solve(F: PETSc.Mat, rows: np.ndarray, values: np.ndarray, out: PETSc.Vec) -> None:
    """Solve A out = b for a right-hand side b with few nonzeros (collective).

    MUMPS prunes the forward elimination to the subtrees that hold b's nonzeros when it
    gets b as a sparse right-hand side (ICNTL(20) = 1, through ``MatMatSolve`` with a
    transposed AIJ matrix); the backward pass stays full, as the solution is dense. For a
    few hundred nonzeros in a 2D system of 10^5 DOFs this is cheaper than a dense-vector
    solve. The right-hand side is handed to MUMPS on rank 0, as it wants it.

    Args:
        F: the MUMPS factor (``pc.getFactorMatrix()``), on its communicator.
        rows: global indices of b's nonzeros, the same on every rank, shape=(k,).
        values: b at ``rows``, the same on every rank, shape=(k,).
        out: the solution, laid out as the factor's rows (ghosts are not updated).
    """
    pcomm = F.getComm()
    n = F.getSize()[0]
    n_local = out.getLocalSize()
    order = np.argsort(rows)
    indptr = np.array([0, len(rows)])
    Bt = _rank0_aij(pcomm, 1, n, indptr, np.asarray(rows)[order], np.asarray(values)[order])
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


def rigid_body_modes(space: object) -> PETSc.NullSpace:
    """Orthonormalised rigid body modes of a vector space (3 in 2D, 6 in 3D)."""
    dofmap = space.dofmap  # type: ignore[attr-defined]
    bs = dofmap.index_map_bs
    n_local = dofmap.index_map.size_local
    x = space.tabulate_dof_coordinates()[:n_local]  # type: ignore[attr-defined]
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


def orthonormal_nullspace(modes: list[np.ndarray], comm: object) -> PETSc.NullSpace:
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
    return PETSc.NullSpace().create(vectors=vecs, comm=comm)


class LinearSolver:
    """A KSP with its own options prefix, built for one assembled operator.

    Args:
        A: assembled operator.
        prefix: PETSc options prefix, e.g. ``"geofrac_elastic_"``.
        preset: ``auto``, ``direct`` or ``iterative``.
        options: user options (without prefix), applied after the preset's.
        num_dofs: global problem size (decides ``auto``).
        near_nullspace: builds the rigid body modes for GAMG (called only when GAMG is
            used); the solver destroys what it returns.
        max_residual: largest accepted relative residual after the solve.
    """

    def __init__(
        self,
        A: PETSc.Mat,
        prefix: str,
        preset: str,
        options: dict[str, str],
        num_dofs: int,
        near_nullspace: Callable[[], PETSc.NullSpace] | None = None,
        max_residual: float = MAX_RELATIVE_RESIDUAL,
    ) -> None:
        self.prefix = prefix
        self.residual = float("nan")
        self.max_residual = max_residual
        self.preset, self.options = preset_options(preset, num_dofs)
        self.options.update(options)
        self._nullspace = None
        if self.options.get("pc_type") == "gamg" and near_nullspace is not None:
            self._nullspace = near_nullspace()
            A.setNearNullSpace(self._nullspace)
        self.ksp = PETSc.KSP().create(A.getComm())
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setOperators(A)
        db = PETSc.Options()
        for k, v in self.options.items():
            db[f"{prefix}{k}"] = v
        try:
            self.ksp.setFromOptions()
            self.ksp.setUp()  # factor-matrix options (mat_mumps_*) are read here
        except PETSc.Error as exc:
            raise RunError(f"linear solver '{prefix}' set-up failed ({exc})") from None
        finally:
            for k in self.options:
                db.delValue(f"{prefix}{k}")

    def solve(self, b: PETSc.Vec, x: PETSc.Vec) -> int:
        """Solve A x = b; return the iteration count.

        Raises:
            RunError: the solver failed (singular matrix, divergence) or produced NaN.
        """
        try:
            self.ksp.solve(b, x)
        except PETSc.Error as exc:
            raise RunError(
                f"linear solver '{self.prefix}' failed ({exc}); the system is probably singular "
                "(a free rigid body motion: check the Dirichlet conditions)"
            ) from None
        reason = self.ksp.getConvergedReason()
        if reason < 0:
            raise RunError(
                f"linear solver '{self.prefix}' did not converge (KSPConvergedReason {reason}, "
                f"{self.ksp.getIterationNumber()} iterations)"
            )
        pc = self.ksp.getPC()
        if pc.getType() in ("lu", "cholesky") and pc.getFactorSolverType() == "mumps":
            null_pivots = pc.getFactorMatrix().getMumpsInfog(28)
            if null_pivots > 0:
                raise RunError(
                    f"linear solver '{self.prefix}': the system is singular ({null_pivots} null "
                    "pivot(s)); a rigid body motion is free, check the Dirichlet conditions"
                )
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        if not np.isfinite(x.norm()):
            raise RunError(f"linear solver '{self.prefix}' returned a non-finite solution")
        self.residual = self._relative_residual(b, x)
        if self.residual > self.max_residual:
            raise RunError(
                f"linear solver '{self.prefix}': relative residual {self.residual:.2e} exceeds "
                f"{self.max_residual:.0e}; the system is singular or badly conditioned"
            )
        return int(self.ksp.getIterationNumber())

    def _relative_residual(self, b: PETSc.Vec, x: PETSc.Vec) -> float:
        """||b - A x|| / ||b|| (or ||A x|| when b = 0)."""
        A = self.ksp.getOperators()[0]
        r = b.duplicate()
        try:
            A.mult(x, r)
            r.aypx(-1.0, b)
            scale = b.norm()
            return float(r.norm() / scale) if scale > 0 else float(r.norm())
        finally:
            r.destroy()

    def describe(self) -> dict[str, object]:
        """Preset, KSP and PC types and the options used (for summary.json)."""
        return {
            "prefix": self.prefix,
            "preset": self.preset,
            "ksp_type": self.ksp.getType(),
            "pc_type": self.ksp.getPC().getType(),
            "options": dict(self.options),
            "relative_residual": self.residual,
        }

    def destroy(self) -> None:
        """Free the KSP and near-nullspace."""
        self.ksp.destroy()
        if self._nullspace is not None:
            self._nullspace.destroy()


def block_diagonal(blocks: np.ndarray, space: Any) -> PETSc.Mat:
    """A block-diagonal AIJ matrix on ``space`` from owned blocks, shape=(n_owned, bs, bs).

    ``space`` is a blocked DOLFINx function space of block size bs; the caller destroys
    the matrix.
    """
    imap, bs = space.dofmap.index_map, space.dofmap.index_map_bs
    n = imap.size_local
    first = imap.local_range[0] * bs
    cols = first + (np.arange(n)[:, None, None] * bs + np.arange(bs)[None, None, :])
    cols = np.broadcast_to(cols, (n, bs, bs)).reshape(-1).astype(PETSc.IntType)
    indptr = (np.arange(n * bs + 1) * bs).astype(PETSc.IntType)
    M = PETSc.Mat().createAIJ(
        size=((n * bs, imap.size_global * bs), (n * bs, imap.size_global * bs)),
        csr=(indptr, cols, blocks.reshape(-1)),
        comm=space.mesh.comm,
    )
    M.assemble()
    return M
