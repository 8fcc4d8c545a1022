"""Exact solves of a locally changed system with one fixed factorisation (pure numpy).

Between two crack events the stiffness changes only on the DOFs of the cells whose field
changed. Let A₀ x₀ = b₀ be the system at the last factorisation and T the set of DOFs
touched since then, E the n×m matrix selecting T. The current system is

    (A₀ + E ΔC Eᵀ) x = b₀ + E Δb,                 ΔC shape=(m, m), Δb shape=(m,).

With y = A₀⁻¹ b₀ and S = (A₀⁻¹)_TT (the TT block of the inverse), x = y + A₀⁻¹ E g with

    g = Δb − ΔC x_T,      N x_T = y_T + S Δb,      N = I + S ΔC

(Woodbury's identity without inverting ΔC, which is singular in general). Per event this
needs the new rows and columns of S (entries of A₀⁻¹, which MUMPS computes from sparse
right-hand sides without a full solve: :func:`geofrac.solvers.mumps_inverse_entries`),
and one solve with A₀ for x. N⁻¹ is kept explicitly and updated in O(m² p) per event
instead of refactorised in O(m³):

- new DOFs enter T with zero rows and columns of ΔC, so N gains the block row
  [S_nT ΔC, I] and N⁻¹ the block row [−S_nT ΔC N⁻¹, I] (block lower triangular);
- an event's change δ of ΔC on the positions P changes the columns P of N by S_{:P} δ,
  a rank-|P| update: N⁻¹ ← N⁻¹ − X (I + δ X_P)⁻¹ δ N⁻¹_P with X = N⁻¹ S_{:P}.

:class:`LocalUpdate` keeps T, S, ΔC, Δb and N⁻¹; the driver owns the PETSc side. Under MPI
the rows of S, ΔC and N⁻¹ are shared among the ranks (position i of T on rank i mod size),
so that each rank does 1/size of the dense work; every product is completed by gathering
the rows (:class:`RowShare`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["LocalUpdate", "RowShare"]


class RowShare:
    """Rows of T's dense matrices shared cyclically among the ranks of a communicator.

    Position i of T lives on rank i mod size, at local row i // size. Without a
    communicator (or on one rank) every row is local and nothing is communicated.

    Args:
        comm: an mpi4py communicator, or None.
    """

    def __init__(self, comm: Any = None) -> None:
        self.comm = comm
        self.size = 1 if comm is None else int(comm.size)
        self.rank = 0 if comm is None else int(comm.rank)

    def rows(self, m: int) -> np.ndarray:
        """This rank's positions among the first m, shape=(ceil((m - rank) / size),)."""
        return np.arange(self.rank, m, self.size)

    def local(self, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(which of ``positions`` are this rank's, their local rows), shapes=(k,), (j,)."""
        mine = positions % self.size == self.rank
        return mine, positions[mine] // self.size

    def gather(self, part: np.ndarray, m: int) -> np.ndarray:
        """The rows of every rank assembled in position order, shape=(m, ...).

        ``part`` holds this rank's rows of the first m positions, in order.
        """
        if self.size == 1:
            return part
        parts = self.comm.allgather(part)
        out = np.empty((m, *part.shape[1:]), dtype=part.dtype)
        for r, p in enumerate(parts):
            out[r :: self.size] = p
        return out

    def gather_at(self, positions: np.ndarray, local: np.ndarray) -> np.ndarray:
        """Rows at ``positions`` (any order) from their owners, shape=(len(positions), ...).

        ``local`` holds this rank's rows at its positions among ``positions``, in their
        order (:meth:`local`).
        """
        if self.size == 1:
            return local
        parts = self.comm.allgather(local)
        out = np.empty((len(positions), *local.shape[1:]), dtype=local.dtype)
        owner = positions % self.size
        for r, p in enumerate(parts):
            out[owner == r] = p
        return out

    def sum(self, partial: np.ndarray) -> np.ndarray:
        """Σ over the ranks of ``partial`` (same shape on every rank)."""
        if self.size == 1:
            return partial
        from mpi4py import MPI

        out = np.empty_like(partial)
        self.comm.Allreduce(np.ascontiguousarray(partial), out, op=MPI.SUM)
        return out


class LocalUpdate:
    """The changed block of a system on a growing DOF set T.

    T and Δb are the same on every rank; the rows of S, ΔC and N⁻¹ are shared among
    the ranks of ``comm`` (:class:`RowShare`), and every result is the same on every rank.

    Args:
        n: number of DOFs of the whole system.
        capacity: largest size of T kept (the driver refactorises beyond it).
        comm: an mpi4py communicator whose ranks share the rows of S, ΔC and N⁻¹
            (collective methods then), or None: all rows here.

    Attributes:
        dofs: global ids of T in insertion order, shape=(m,).
    """

    def __init__(self, n: int, capacity: int, *, comm: Any = None) -> None:
        self.capacity = capacity
        self.share = RowShare(comm)
        rows = -(-capacity // self.share.size)  # this rank's rows at most
        self._pos = np.full(n, -1, dtype=np.int64)
        self._dofs = np.zeros(capacity, dtype=np.int64)
        # this rank's rows of S, ΔC and N⁻¹ (local row i // size: position i)
        self._S = np.zeros((rows, capacity))
        self._dC = np.zeros((rows, capacity))
        self._Ninv = np.zeros((rows, capacity))
        self._db = np.zeros(capacity)
        #: changes of ΔC not yet folded into N⁻¹: (positions, matrix) pairs.
        self._pending: list[tuple[np.ndarray, np.ndarray]] = []
        self.m = 0

    @property
    def dofs(self) -> np.ndarray:
        """Global ids of T, shape=(m,)."""
        return self._dofs[: self.m]

    def _loc(self, a: np.ndarray) -> np.ndarray:
        """This rank's rows of a local matrix over the first m columns."""
        return a[: len(self.share.rows(self.m)), : self.m]

    @property
    def S(self) -> np.ndarray:
        """(A₀⁻¹)_TT, shape=(m, m) (gathered: for checks, not for the event loop)."""
        return self.share.gather(self._loc(self._S), self.m)

    @property
    def dC(self) -> np.ndarray:
        """ΔC, shape=(m, m) (gathered: for checks, not for the event loop)."""
        return self.share.gather(self._loc(self._dC), self.m)

    @property
    def Ninv(self) -> np.ndarray:
        """(I + S ΔC)⁻¹ for the ΔC folded in so far, shape=(m, m) (gathered: for checks)."""
        return self.share.gather(self._loc(self._Ninv), self.m)

    def _product(self, a: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(a's full m×m matrix) @ v from this rank's rows, on every rank, shape=(m,)."""
        return self.share.gather(self._loc(a) @ v, self.m)

    def dC_matvec(self, v: np.ndarray) -> np.ndarray:
        """ΔC v for v shape=(m,), shape=(m,) (collective)."""
        return self._product(self._dC, v)

    @property
    def db(self) -> np.ndarray:
        """Δb, shape=(m,)."""
        return self._db[: self.m]

    def positions(self, dofs: np.ndarray) -> np.ndarray:
        """Positions in T of global DOFs (-1 where not in T), same shape."""
        return self._pos[dofs]

    def missing(self, dofs: np.ndarray) -> np.ndarray:
        """The DOFs of ``dofs`` not yet in T, unique and sorted, shape=(k,)."""
        d = np.unique(np.asarray(dofs, dtype=np.int64))
        return d[self._pos[d] < 0]

    def grow(self, new: np.ndarray, block: np.ndarray, rows: np.ndarray | None = None) -> None:
        """Append DOFs ``new`` to T with their entries of A₀⁻¹.

        Args:
            new: DOFs not in T, shape=(k,).
            block: (A₀⁻¹)[T ∪ new, new] with rows in the order (old T, new), shape=(m + k, k).
            rows: (A₀⁻¹)[new, old T], shape=(k, m); None when A₀ is symmetric (the new
                rows are then the transposed new columns).

        Raises:
            ValueError: T would exceed ``capacity`` or a DOF is already in T.
        """
        k, m = len(new), self.m
        if m + k > self.capacity:
            raise ValueError(f"T would hold {m + k} DOFs, capacity {self.capacity}")
        if np.any(self._pos[new] >= 0):
            raise ValueError("a DOF is already in T")
        share = self.share
        self._pos[new] = np.arange(m, m + k)
        self._dofs[m : m + k] = new
        S_nT = block[:m].T if rows is None else rows
        old_rows = share.rows(m)
        # N⁻¹ gains the block row [-S_nT ΔC N⁻¹, I] (ΔC is zero on the new DOFs): both
        # products sum over T's positions, each rank over its rows
        dC_loc, Ninv_loc = self._loc(self._dC), self._loc(self._Ninv)
        nT_dC = share.sum(S_nT[:, old_rows] @ dC_loc)  # shape=(k, m)
        border = -share.sum(nT_dC[:, old_rows] @ Ninv_loc)  # shape=(k, m)
        self.m = m + k
        pos = share.rows(m + k)  # this rank's positions among the m + k
        at = pos // share.size  # their local rows
        self._S[at, m : m + k] = block[pos]
        new_mine = pos >= m
        self._S[at[new_mine], :m] = S_nT[pos[new_mine] - m]
        self._Ninv[at, m : m + k] = 0.0
        self._Ninv[at[new_mine], :m] = border[pos[new_mine] - m]
        self._Ninv[at[new_mine], pos[new_mine]] = 1.0

    def add(self, dofs: np.ndarray, matrix: np.ndarray) -> None:
        """ΔC[dofs, dofs] += matrix for DOFs already in T.

        Args:
            dofs: global ids, all in T, shape=(p,).
            matrix: shape=(p, p).
        """
        p = self._pos[dofs]
        if np.any(p < 0):
            raise ValueError("add: a DOF is not in T")
        self._pending.append((p, np.asarray(matrix, dtype=float)))

    def add_rhs(self, dofs: np.ndarray, values: np.ndarray) -> None:
        """Δb[dofs] += values (DOFs in T), shape=(p,)."""
        p = self._pos[dofs]
        if np.any(p < 0):
            raise ValueError("add_rhs: a DOF is not in T")
        np.add.at(self._db, p, values)

    def _fold(self) -> None:
        """Fold the pending changes of ΔC into ΔC and N⁻¹ (rank-|P| Woodbury update)."""
        if not self._pending:
            return
        P = np.unique(np.concatenate([p for p, _ in self._pending]))
        delta = np.zeros((len(P), len(P)))
        for p, k in self._pending:
            q = np.searchsorted(P, p)
            np.add.at(delta, (q[:, None], q[None, :]), k)
        self._pending = []
        share, m = self.share, self.m
        S_loc, Ninv_loc = self._loc(self._S), self._loc(self._Ninv)
        mine, at = share.local(P)
        S_cols = share.gather(S_loc[:, P], m)  # S[:, P], shape=(m, p)
        X = Ninv_loc @ S_cols  # this rank's rows of N⁻¹ S_{:P}, shape=(rows, p)
        X_P = share.gather_at(P, X[at])  # shape=(p, p)
        Ninv_P = share.gather_at(P, Ninv_loc[at])  # N⁻¹[P], shape=(p, m)
        C = delta @ X_P
        C[np.diag_indices(len(P))] += 1.0
        Ninv_loc -= X @ np.linalg.solve(C, delta @ Ninv_P)
        self._dC[np.ix_(at, P)] += delta[mine]

    def correction(self, y_t: np.ndarray, atol: float = 0.0, steps: int = 3) -> np.ndarray:
        """The correction g = Δb − ΔC x_T with N x_T = y_T + S Δb, shape=(m,).

        g solves (I + ΔC S) g = Δb − ΔC y_T. The explicitly updated N⁻¹ loses digits
        after many events on an ill-conditioned system, so g is refined on T: with the
        residual ρ = Δb − ΔC y_T − (I + ΔC S) g, g += (I − ΔC N⁻¹ S) ρ (the inverse of
        I + ΔC S by the push-through identity), while ‖ρ‖ > ``atol``, at most ``steps``
        times. ρ is E's part of the residual of the whole system for x = y + A₀⁻¹ E g, so
        this refinement costs O(m²) instead of solves with A₀.

        Args:
            y_t: A₀⁻¹ b₀ on T, shape=(m,).
            atol: the residual norm on T that needs no refinement.
            steps: most refinement steps.

        Raises:
            numpy.linalg.LinAlgError: the changed system is singular.
        """
        if self.m == 0:
            return np.zeros(0)
        self._fold()
        S, dC, Ninv, mul = self._S, self._dC, self._Ninv, self._product
        rhs = self.db - mul(dC, y_t)
        g = self.db - mul(dC, mul(Ninv, y_t + mul(S, self.db)))
        for _ in range(steps):
            rho = rhs - g - mul(dC, mul(S, g))
            if not np.all(np.isfinite(rho)):
                break
            if np.linalg.norm(rho) <= atol:
                break
            g += rho - mul(dC, mul(Ninv, mul(S, rho)))
        if not np.all(np.isfinite(g)):
            raise np.linalg.LinAlgError("non-finite correction")
        return g

    def homogeneous_correction(self, w_t: np.ndarray) -> np.ndarray:
        """The correction g = −ΔC N⁻¹ w_T for a right-hand side f with A₀⁻¹ f = w.

        Then A⁻¹ f = A₀⁻¹ (f + E g) (iterative refinement of a corrected solution).
        """
        self._fold()
        return -self._product(self._dC, self._product(self._Ninv, w_t))
