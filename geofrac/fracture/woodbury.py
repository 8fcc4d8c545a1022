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

:class:`LocalUpdate` keeps T, S, ΔC, Δb and N⁻¹; the driver owns the PETSc side.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LocalUpdate"]


class LocalUpdate:
    """The changed block of a system on a growing DOF set T (replicated on every rank).

    Args:
        n: number of DOFs of the whole system.
        capacity: largest size of T kept (the driver refactorises beyond it).

    Attributes:
        dofs: global ids of T in insertion order, shape=(m,).
    """

    def __init__(self, n: int, capacity: int) -> None:
        self.capacity = capacity
        self._pos = np.full(n, -1, dtype=np.int64)
        self._dofs = np.zeros(capacity, dtype=np.int64)
        self._S = np.zeros((capacity, capacity))
        self._dC = np.zeros((capacity, capacity))
        self._Ninv = np.zeros((capacity, capacity))
        self._db = np.zeros(capacity)
        #: changes of ΔC not yet folded into N⁻¹: (positions, matrix) pairs.
        self._pending: list[tuple[np.ndarray, np.ndarray]] = []
        self.m = 0

    @property
    def dofs(self) -> np.ndarray:
        """Global ids of T, shape=(m,)."""
        return self._dofs[: self.m]

    @property
    def S(self) -> np.ndarray:
        """(A₀⁻¹)_TT, shape=(m, m)."""
        return self._S[: self.m, : self.m]

    @property
    def dC(self) -> np.ndarray:
        """ΔC, shape=(m, m)."""
        return self._dC[: self.m, : self.m]

    @property
    def Ninv(self) -> np.ndarray:
        """(I + S ΔC)⁻¹ for the ΔC folded in so far, shape=(m, m)."""
        return self._Ninv[: self.m, : self.m]

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
        self._pos[new] = np.arange(m, m + k)
        self._dofs[m : m + k] = new
        S_nT = block[:m].T if rows is None else rows
        self._S[: m + k, m : m + k] = block
        self._S[m : m + k, :m] = S_nT
        # N⁻¹ gains the block row [-S_nT ΔC N⁻¹, I] (ΔC is zero on the new DOFs)
        self._Ninv[m : m + k, :m] = -((S_nT @ self.dC) @ self.Ninv)
        self._Ninv[: m + k, m : m + k] = 0.0
        self._Ninv[np.arange(m, m + k), np.arange(m, m + k)] = 1.0
        self.m = m + k

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
        m = self.m
        Ninv = self._Ninv[:m, :m]
        X = Ninv @ self._S[:m, P]  # shape=(m, p)
        C = delta @ X[P]
        C[np.diag_indices(len(P))] += 1.0
        Ninv -= X @ np.linalg.solve(C, delta @ Ninv[P])
        self._dC[np.ix_(P, P)] += delta

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
        S, dC, Ninv = self.S, self.dC, self.Ninv
        rhs = self.db - dC @ y_t
        g = self.db - dC @ (Ninv @ (y_t + S @ self.db))
        for _ in range(steps):
            rho = rhs - g - dC @ (S @ g)
            if not np.all(np.isfinite(rho)):
                break
            if np.linalg.norm(rho) <= atol:
                break
            g += rho - dC @ (Ninv @ (S @ rho))
        if not np.all(np.isfinite(g)):
            raise np.linalg.LinAlgError("non-finite correction")
        return g

    def homogeneous_correction(self, w_t: np.ndarray) -> np.ndarray:
        """The correction g = −ΔC N⁻¹ w_T for a right-hand side f with A₀⁻¹ f = w.

        Then A⁻¹ f = A₀⁻¹ (f + E g) (iterative refinement of a corrected solution).
        """
        self._fold()
        return -(self.dC @ (self.Ninv @ w_t))
