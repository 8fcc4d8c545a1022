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

from collections.abc import Callable

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from geofrac.errors import RunError
from geofrac.solvers.vectors import update_ghosts

__all__ = [
    "AUTO_DIRECT_MAX_DOFS",
    "MAX_RELATIVE_RESIDUAL",
    "LinearSolver",
    "PreconditionedCG",
    "preset_options",
]

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
        *,
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
        update_ghosts(x)
        if not np.isfinite(x.norm()):
            raise RunError(f"linear solver '{self.prefix}' returned a non-finite solution")
        self.residual = self._relative_residual(b, x)
        if self.residual > self.max_residual:
            raise RunError(
                f"linear solver '{self.prefix}': relative residual {self.residual:.2e} exceeds "
                f"{self.max_residual:.0e}; the system is singular or badly conditioned"
            )
        return int(self.ksp.getIterationNumber())

    def apply(self, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """Set x = A⁻¹ b with the factorisation/preconditioner as it is, unchecked.

        For repeated solves with a direct solver whose set-up and first solve were
        checked by :meth:`solve` (iterative refinement, preconditioning); ghosts are not
        updated.
        """
        self.ksp.solve(b, x)

    def factor(self) -> PETSc.Mat:
        """The factor matrix of a direct solver (MUMPS), for :mod:`geofrac.solvers.mumps`.

        A new reference to it: the caller destroys it (the factor itself lives as long
        as this solver).
        """
        return self.ksp.getPC().getFactorMatrix()

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


class _ApplySolver:
    """PCSHELL context: apply a :class:`LinearSolver` (its factorisation) as the PC."""

    def __init__(self, solver: LinearSolver) -> None:
        self.solver = solver

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.solver.apply(x, y)


class PreconditionedCG:
    """CG preconditioned by another solver's factorisation (an older, nearby matrix).

    The KSP is set up once (own options prefix, user options read then); each
    :meth:`solve` may have a new operator.

    Args:
        comm: the communicator of the operators.
        prefix: PETSc options prefix, e.g. ``"geofrac_crack_cg_"``.
        preconditioner: the solver applied as the preconditioner (not owned).
        max_it: the most iterations before CG gives up; CG stops at rtol 1e-10.
    """

    def __init__(
        self, comm: MPI.Comm, prefix: str, preconditioner: LinearSolver, *, max_it: int
    ) -> None:
        self.ksp = PETSc.KSP().create(comm)
        self.ksp.setOptionsPrefix(prefix)
        self.ksp.setType("cg")
        pc = self.ksp.getPC()
        pc.setType("python")
        pc.setPythonContext(_ApplySolver(preconditioner))
        self.ksp.setTolerances(rtol=1e-10, atol=0.0, max_it=max_it)
        self.ksp.setInitialGuessNonzero(True)
        self.ksp.setFromOptions()

    def solve(self, A: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> int | None:
        """Solve A x = b from the initial guess x; the iteration count, or None on failure.

        Failure: CG did not converge within ``max_it`` or the solution is not finite.
        """
        self.ksp.setOperators(A)
        self.ksp.solve(b, x)
        if self.ksp.getConvergedReason() > 0 and np.isfinite(x.norm()):
            return int(self.ksp.getIterationNumber())
        return None

    def destroy(self) -> None:
        """Free the KSP."""
        self.ksp.destroy()
