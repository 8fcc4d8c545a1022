"""One MUMPS factorisation serving many crack events exactly (the ``update`` solver).

The PETSc side of :mod:`geofrac.fracture.woodbury`: the reference system A₀ x = b₀ (the
stiffness at the last factorisation, Dirichlet and held DOFs applied), its MUMPS factor,
y = A₀⁻¹ b₀, and the changed block on the touched DOFs T. Each event costs

- the entries of A₀⁻¹ on (T, new DOFs of T), from MUMPS's selected-inverse solve
  (:func:`geofrac.solvers.mumps_inverse_entries`);
- the dense m×m correction solve (m = |T|, its rows shared among the ranks);
- one solve with the factor, x = y + A₀⁻¹ E g (E g handed to MUMPS as a sparse right-hand
  side, :func:`geofrac.solvers.mumps_sparse_solve`), and a residual check against the current
  system ‖b − A x‖ ≤ max(:data:`MAX_RESIDUAL`, 2 ρ₀) ‖b‖, ρ₀ the reference solution's own
  relative residual (with iterative refinement when needed).

The solver is *stale* (the driver then assembles and factorises afresh) when T would
exceed its capacity, when a change touches a DOF held at the reference (held DOFs may
not come back without a new factorisation), when the corrected system is singular or the
residual check fails (a fragment cut free: the fresh factorisation finds and holds it).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.woodbury import LocalUpdate
from geofrac.solvers import (
    Gather,
    LinearSolver,
    Matrix,
    Vector,
    add_values,
    mumps_inverse_entries,
    mumps_sparse_solve,
    update_ghosts,
)

__all__ = [
    "MAX_RESIDUAL",
    "REFINEMENTS",
    "REFINE_ABOVE",
    "Gather",
    "IncrementalSolver",
    "Stale",
]

#: Largest relative residual of a corrected solution; above it the solver is stale. On an
#: ill-conditioned reference whose own solution misses it (relative residual ρ₀ > 1e-10:
#: near-null modes of small element islands), a corrected solution within 2 ρ₀ passes:
#: a fresh factorisation of a system so close to the reference reaches no better, and
#: refusing it would refactorise at every event for nothing.
MAX_RESIDUAL = 1e-10

#: A corrected solution with a larger relative residual is refined (or above twice the
#: reference solution's own residual, when that is larger: refinement cannot go below
#: the accuracy of the factorisation it uses) ...
REFINE_ABOVE = 1e-11

#: ... by at most this many steps of iterative refinement.
REFINEMENTS = 2


class Stale(Exception):
    """The reference factorisation can no longer serve the current system.

    Args:
        kind: ``held`` (a change touches a held DOF), ``capacity``, ``singular`` or
            ``residual``: counted per run in the results (``refactor_reasons``).
        detail: the message.
    """

    def __init__(self, kind: str, detail: str) -> None:
        super().__init__(detail)
        self.kind = kind


class IncrementalSolver:
    """A reference factorisation and the exact correction for later local changes.

    Args:
        A: the reference matrix with Dirichlet and held DOFs applied (owned by this
            object from now on).
        b: the matching right-hand side (owned from now on).
        fixed: Dirichlet and held DOFs of the reference, shape=(n_global,) bool.
        bc_mask: Dirichlet DOFs, shape=(n_global,) bool.
        bc_values: prescribed values on Dirichlet DOFs (0 elsewhere), shape=(n_global,).
        solver: a factorisation of ``A`` (MUMPS; owned from now on).
        x: a vector of A's layout to solve into (ghosted DOLFINx vector).
        gather: copies vectors of x's layout to every rank (the caller's; not owned).
        capacity: the largest |T|.
        parts: seconds per part of the work (``inverse_entries``, ``dense_update``,
            ``substitution``, ``residual``) are added here (the driver's
            :attr:`~geofrac.fracture.linear.Timing.parts`); None: not measured.
        transposed: when A is unsymmetric (friction on slipping crack faces), makes a
            factorisation of Aᵀ: the new rows of A⁻¹ on T are its columns. Called when
            first needed (collective), so a reference that is replaced before it grows T
            twice never factorises Aᵀ; the factorisation is owned from then on.

    Raises:
        geofrac.errors.RunError: the reference solve failed (singular system).
    """

    def __init__(
        self,
        A: Matrix,
        b: Vector,
        *,
        fixed: np.ndarray,
        bc_mask: np.ndarray,
        bc_values: np.ndarray,
        solver: LinearSolver,
        x: Vector,
        gather: Gather,
        capacity: int,
        transposed: Callable[[], LinearSolver] | None = None,
        parts: dict[str, float] | None = None,
    ) -> None:
        self.parts: dict[str, float] = {} if parts is None else parts
        self.A, self.b, self.solver = A, b, solver
        self._transposed = transposed
        self.solver_t: LinearSolver | None = None
        self.fixed, self.bc_mask, self.bc_values = fixed, bc_mask, bc_values
        self.comm = A.getComm().tompi4py()
        self.row0, self.row1 = A.getOwnershipRange()
        self.update = LocalUpdate(A.getSize()[0], capacity, comm=self.comm)
        self.held = np.zeros_like(fixed)
        self.solver.solve(b, x)
        self.y_vec = x.copy()
        self.gather = gather
        self.y = self.gather(x)
        self.b_full = self.gather(b)
        self._b_norm2 = float(self.b_full @ self.b_full)
        self.factor = solver.factor()
        self.factor_t: Matrix | None = None
        #: refinement steps with solves by A₀ taken so far (after the refinement on T)
        self.refinements = 0
        e = b.duplicate()
        try:
            A.mult(self.y_vec, e)
            e.aypx(-1.0, b)
            #: ‖b₀ − A₀ y‖² / ‖b₀‖²: the factorisation's own accuracy on this system
            self.floor2 = float(e.norm() ** 2) / max(self._b_norm2, 1e-300)
        finally:
            e.destroy()

    def apply(
        self, blocks: list[tuple[np.ndarray, np.ndarray]], hold: np.ndarray, hold_values: np.ndarray
    ) -> None:
        """Add changed cell matrices and hold DOFs that lost all stiffness.

        Args:
            blocks: (global DOFs, shape=(p,); signed matrix, shape=(p, p)) per change: the
                new contribution of a cell with +, its old one with −.
            hold: DOFs that no longer carry stiffness, shape=(h,).
            hold_values: their values, shape=(h,).

        Raises:
            Stale: a change needs a new factorisation.
        """
        lu, bc = self.update, self.bc_mask
        touched = np.concatenate([d for d, _ in blocks] + [hold]).astype(np.int64)
        if np.any(self.fixed[touched] & ~bc[touched]):
            raise Stale("held", "a change touches a DOF held at the reference")
        new = lu.missing(touched[~bc[touched]])
        if lu.m + len(new) > lu.capacity:
            raise Stale("capacity", f"{lu.m + len(new)} changed DOFs exceed the update capacity")
        t = time.perf_counter()
        if len(new):
            rows = np.concatenate([lu.dofs, new])
            transposed = None
            if self._transposed is not None and lu.m:
                if self.factor_t is None:
                    try:
                        self.solver_t = self._transposed()
                    except RunError as exc:
                        raise Stale("singular", f"the transposed system: {exc}") from None
                    self.factor_t = self.solver_t.factor()
                transposed = mumps_inverse_entries(self.factor_t, lu.dofs, new).T
            block = mumps_inverse_entries(self.factor, rows, new)
            t = self._lap("inverse_entries", t)
            lu.grow(new, block, transposed)
        for dofs, k in blocks:
            free = ~bc[dofs]
            lu.add(dofs[free], k[np.ix_(free, free)])
            if not free.all():
                lu.add_rhs(dofs[free], -k[np.ix_(free, ~free)] @ self.bc_values[dofs[~free]])
        for j, v in zip(hold.tolist(), hold_values.tolist(), strict=True):
            # its row and column are zero now (every cell that used it changed): make
            # them the identity with the held value on the right
            p = int(lu.positions(np.array([j]))[0])
            lu.add(np.array([j]), np.ones((1, 1)))
            lu.add_rhs(np.array([j]), np.array([v - self.b_full[j] - lu.db[p]]))
            self.held[j] = True
        self._lap("dense_update", t)

    def solve(self, x: Vector) -> np.ndarray:
        """Solve the current system into ``x``; return the solution on every rank.

        The corrected solution is refined (at most :data:`REFINEMENTS` steps of iterative
        refinement with the same correction) while its relative residual exceeds
        :data:`REFINE_ABOVE`: after an event that leaves the system ill-conditioned, the
        explicitly updated N⁻¹ can lose digits that a fresh factorisation would keep. The
        refinement stops early at twice the reference solution's own relative residual
        (on an ill-conditioned system MUMPS's solves have a floor above
        :data:`REFINE_ABOVE`, and steps below it only repeat two solves) and when a step
        does not reduce the residual. The solution is accepted within :data:`MAX_RESIDUAL`,
        or within twice the reference solution's own residual when that is larger.

        Raises:
            Stale: the corrected system is singular or misses the residual check.
        """
        lu = self.update
        if lu.m == 0:
            self.y_vec.copy(x)
            return self.y.copy()
        b_t = self.b_full[lu.dofs]
        b2 = max(self._b_norm2 + float(np.sum((b_t + lu.db) ** 2 - b_t**2)), 1e-300)
        t = time.perf_counter()
        try:
            g = lu.correction(self.y[lu.dofs], atol=0.1 * REFINE_ABOVE * np.sqrt(b2))
        except np.linalg.LinAlgError as exc:
            raise Stale("singular", f"the changed system is singular ({exc})") from None
        t = self._lap("dense_update", t)
        target2 = max(REFINE_ABOVE**2, 4.0 * self.floor2) * b2
        accept2 = max(MAX_RESIDUAL**2, 4.0 * self.floor2) * b2
        e, w, last = self.b.duplicate(), self.b.duplicate(), self.b.duplicate()
        try:
            self._solve_with(g, x)
            x.axpy(1.0, self.y_vec)
            t = self._lap("substitution", t)
            r2_last, u_last = math.inf, None
            for step in range(REFINEMENTS + 1):
                update_ghosts(x)
                u = self.gather(x)
                if not np.all(np.isfinite(u)):
                    raise Stale("singular", "non-finite corrected solution")
                r2 = self._residual(x, u, e)
                if r2 >= r2_last:  # the step did not help: keep the solution before it
                    last.copy(x)
                    update_ghosts(x)
                    r2, u = r2_last, u_last
                    break
                if r2 <= target2 or step == REFINEMENTS:
                    break
                r2_last, u_last = r2, u
                x.copy(last)
                self.refinements += 1
                # x += A⁻¹ r = A₀⁻¹ (r + E g_r), g_r = −ΔC N⁻¹ (A₀⁻¹ r)_T
                self.solver.apply(e, w)
                g_r = lu.homogeneous_correction(self.gather(w)[lu.dofs])
                x.axpy(1.0, w)
                self._solve_with(g_r, w)
                x.axpy(1.0, w)
        finally:
            for vec in (e, w, last):
                vec.destroy()
            self._lap("residual", t)
        if not r2 <= accept2:
            raise Stale("residual", f"relative residual {np.sqrt(r2 / b2):.1e}")
        return u

    def solve_rhs(self, f: Vector, x: Vector) -> np.ndarray:
        """Solve the current system for another right-hand side ``f``; on every rank.

        ``f`` is the current system's right-hand side of another load (assembled on
        the current crack state: Dirichlet values lifted, held DOFs at their values).
        With w = A₀⁻¹ f, A⁻¹ f = A₀⁻¹ (f + E g), g = −ΔC N⁻¹ w_T
        (:meth:`~geofrac.fracture.woodbury.LocalUpdate.homogeneous_correction`); the
        residual ‖f − A x‖ is checked as in :meth:`solve`, with up to
        :data:`REFINEMENTS` steps of the same refinement.

        Raises:
            Stale: the corrected solution is not finite or misses the residual check.
        """
        lu = self.update
        f_norm2 = max(float(f.norm() ** 2), 1e-300)
        target2 = max(REFINE_ABOVE**2, 4.0 * self.floor2) * f_norm2
        accept2 = max(MAX_RESIDUAL**2, 4.0 * self.floor2) * f_norm2
        e, w = f.duplicate(), f.duplicate()
        try:
            f.copy(e)
            x.set(0.0)
            r2 = math.inf
            for step in range(REFINEMENTS + 1):
                # x += A⁻¹ e = A₀⁻¹ (e + E g_e), g_e = −ΔC N⁻¹ (A₀⁻¹ e)_T
                self.solver.apply(e, w)
                x.axpy(1.0, w)
                if lu.m:
                    g_e = lu.homogeneous_correction(self.gather(w)[lu.dofs])
                    self._solve_with(g_e, w)
                    x.axpy(1.0, w)
                update_ghosts(x)
                u = self.gather(x)
                if not np.all(np.isfinite(u)):
                    raise Stale("singular", "non-finite corrected solution")
                self.A.mult(x, e)
                e.aypx(-1.0, f)
                if lu.m:
                    corr = -lu.dC_matvec(u[lu.dofs])
                    mine = (lu.dofs >= self.row0) & (lu.dofs < self.row1)
                    add_values(e, lu.dofs[mine], corr[mine])
                r2 = float(e.norm() ** 2)
                if r2 <= target2:
                    break
                if step < REFINEMENTS:
                    self.refinements += 1
        finally:
            e.destroy()
            w.destroy()
        if not r2 <= accept2:
            raise Stale("residual", f"relative residual {np.sqrt(r2 / f_norm2):.1e}")
        return u

    def _lap(self, name: str, t0: float) -> float:
        """Add the seconds since ``t0`` to the part ``name``; returns now."""
        t1 = time.perf_counter()
        self.parts[name] = self.parts.get(name, 0.0) + t1 - t0
        return t1

    def _solve_with(self, g: np.ndarray, out: Vector) -> None:
        """Solve A₀ out = E g; E g has nonzeros on T only (a sparse right-hand side)."""
        mumps_sparse_solve(self.factor, self.update.dofs, g, out=out)

    def _residual(self, x: Vector, u: np.ndarray, e: Vector) -> float:
        """Residual b₀ + E Δb − A₀ x − E ΔC x_T of the current system into e; ‖e‖²."""
        lu = self.update
        mine = (lu.dofs >= self.row0) & (lu.dofs < self.row1)
        self.A.mult(x, e)
        e.aypx(-1.0, self.b)
        corr = lu.db - lu.dC_matvec(u[lu.dofs])
        add_values(e, lu.dofs[mine], corr[mine])
        return float(e.norm() ** 2)

    def destroy(self) -> None:
        """Free the reference matrix, vectors and factorisation."""
        # the factor's Python wrapper holds a PETSc reference of its own
        for obj in (self.factor, self.solver, self.A, self.b, self.y_vec):
            obj.destroy()
        if self.solver_t is not None:
            assert self.factor_t is not None
            self.factor_t.destroy()
            self.solver_t.destroy()
