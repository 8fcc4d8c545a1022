"""Newton's method through PETSc SNES for a residual and Jacobian given as DOLFINx forms.

The caller supplies the compiled residual form F(u; v) and Jacobian form J(u; du, v),
the unknown u (a :class:`dolfinx.fem.Function`) and an ``update`` callback run each time
u changes, before F or J is assembled (the return mapping at quadrature points of an
elasto-plastic solve). Dirichlet conditions are imposed on the increment (residual
entries u − g, rows of J replaced by the identity). Defaults: ``newtonls`` with the
secant line search on ||F||² (``l2``; ``bt`` stops at the first iteration of a plastic
step started from a converged state on the yield surface, measured
DIVERGED_LINE_SEARCH), ``preonly`` + LU from MUMPS (the tangent of a non-associated law
is not symmetric), under the solver's own options prefix; user
options are applied after and then removed from the global database. Every residual norm
is recorded (the SNES monitor) and the converged reason is returned with its name; the
caller decides what a negative reason means (never a silent result).

With ``watchdog`` (the joint springs' solves), a stalled line search is not the end of a
solve (:meth:`NewtonSolver.solve`). The residual of joint springs is piecewise smooth:
at a kink (a spring on the edge of slipping or of opening) the Newton direction of the
branch the law picks can fail to decrease ||F|| for any step length, and the monotone
line search gives up (DIVERGED_LINE_SEARCH) although the equilibrium is near (measured
on the DFN slope: the same five spring states switched back and forth for 14 line-search
trials, ||F|| stuck at 7.1 while the other round-off of another machine converged). The
solver then takes one full Newton step, which changes the springs' states, and resumes
the monotone search from there (a watchdog step, as in non-monotone semismooth Newton
methods), within the same iteration budget. It does so only while each stall is at a
smaller ||F|| than the one before, so a true loss of equilibrium still ends in
DIVERGED_LINE_SEARCH, after one more step.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import dolfinx.fem.petsc
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from geofrac.errors import RunError
from geofrac.solvers.matrices import widened

__all__ = ["ExtraTerms", "NewtonReport", "NewtonSolver", "snes_reason_name"]


class ExtraTerms(Protocol):
    """Terms added to the assembled residual and Jacobian, by global index (e.g. joint springs).

    Each rank gives only rows it owns (global scalar DOF indices); Dirichlet rows and
    columns are the caller's to leave out of the Jacobian.
    """

    def residual_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, values), shape=(k,) each."""
        ...

    def jacobian_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rows, cols, values), shape=(k,) each (summed where repeated)."""
        ...

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of every entry :meth:`jacobian_entries` may give, shape=(k,) each."""
        ...


def _add_entries(A: PETSc.Mat, rows: np.ndarray, cols: np.ndarray, values: np.ndarray) -> None:
    """Add values at (rows, cols) by global index, summed where repeated (none: nothing)."""
    if not len(rows):
        return
    order = np.argsort(rows, kind="stable")  # one setValues per row, O(k log k)
    rows, cols, values = rows[order], cols[order].astype(PETSc.IntType), values[order]
    starts = np.flatnonzero(np.r_[True, rows[1:] != rows[:-1]])
    for a, b in zip(starts, np.r_[starts[1:], len(rows)], strict=True):
        A.setValues([int(rows[a])], cols[a:b], values[a:b], PETSc.InsertMode.ADD)


def snes_reason_name(reason: int) -> str:
    """PETSc's name of a ``SNESConvergedReason`` code (e.g. ``DIVERGED_MAX_IT``)."""
    for name in dir(PETSc.SNES.ConvergedReason):
        if not name.startswith("_") and getattr(PETSc.SNES.ConvergedReason, name) == reason:
            return str(name)
    return str(reason)


@dataclass
class NewtonReport:
    """What one Newton solve did.

    Attributes:
        reason: the ``SNESConvergedReason`` (> 0 converged, < 0 diverged).
        reason_name: its PETSc name.
        iterations: Newton iterations taken.
        residuals: ||F|| before each iteration and at the end (the SNES monitor),
            shape=(iterations + 1,).
        watchdog_steps: full Newton steps taken after a stalled line search (counted
            in ``iterations``; :meth:`NewtonSolver.solve`).
    """

    reason: int
    reason_name: str
    iterations: int
    residuals: list[float] = field(default_factory=list)
    watchdog_steps: int = 0

    @property
    def converged(self) -> bool:
        """Whether SNES reported convergence."""
        return self.reason > 0


class NewtonSolver:
    """A SNES on the residual form ``F`` and Jacobian form ``J`` of the unknown ``u``.

    Args:
        F: compiled residual form (rank 1).
        J: compiled Jacobian form (rank 2).
        u: the unknown; its values are the initial guess and the result.
        bcs: Dirichlet conditions (their values are the target of u).
        update: called with u updated (ghosts included) before each F or J assembly.
        prefix: PETSc options prefix, e.g. ``"geofrac_plastic_"``.
        options: user options (without prefix), applied after the defaults.
        atol: absolute tolerance on ||F||.
        rtol: relative tolerance on ||F|| / ||F₀||.
        max_it: the most Newton iterations.
        extra: terms added to F and J after their assembly (None: none).
        watchdog: after a stalled line search, take a full step and go on (module
            docstring); False: the stall ends the solve.
    """

    def __init__(
        self,
        F: dolfinx.fem.Form,
        J: dolfinx.fem.Form,
        u: dolfinx.fem.Function,
        *,
        bcs: Sequence[dolfinx.fem.DirichletBC],
        update: Callable[[], None],
        prefix: str,
        options: dict[str, str] | None = None,
        atol: float = 1e-10,
        rtol: float = 1e-9,
        max_it: int = 25,
        extra: ExtraTerms | None = None,
        watchdog: bool = False,
    ) -> None:
        self.extra, self.watchdog = extra, watchdog
        self.F, self.J, self.u, self.bcs, self.update = F, J, u, list(bcs), update
        self.prefix = prefix
        self.options = {
            "snes_type": "newtonls",
            "snes_linesearch_type": "l2",
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
        }
        self.options.update(options or {})
        self.residuals: list[float] = []
        self._last: np.ndarray | None = None
        if extra is None:
            self.A = dolfinx.fem.petsc.create_matrix(J)
        else:  # its entries couple DOFs of no common cell: preallocated with the form's
            self.A = widened(J, *extra.jacobian_pattern())
        self.b = dolfinx.fem.petsc.create_vector(u.function_space)
        self.x = dolfinx.fem.petsc.create_vector(u.function_space)
        self.snes = PETSc.SNES().create(u.function_space.mesh.comm)
        self.snes.setOptionsPrefix(prefix)
        self.snes.setFunction(self._residual, self.b)
        self.snes.setJacobian(self._jacobian, self.A)
        self.snes.setTolerances(atol=atol, rtol=rtol, stol=0.0, max_it=max_it)
        self.snes.setMonitor(lambda _snes, _it, norm: self.residuals.append(float(norm)))
        db = PETSc.Options()
        for k, v in self.options.items():
            db[f"{prefix}{k}"] = v
        try:
            self.snes.setFromOptions()
        except PETSc.Error as exc:
            raise RunError(f"Newton solver '{prefix}' set-up failed ({exc})") from None
        finally:
            for k in self.options:
                db.delValue(f"{prefix}{k}")

    def _set_u(self, x: PETSc.Vec) -> None:
        """Copy x into u and run ``update`` unless u already holds x."""
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        local = x.getArray(readonly=True)
        same = self._last is not None and np.array_equal(local, self._last)
        if self.u.function_space.mesh.comm.allreduce(same, op=MPI.LAND):
            return
        self.u.x.array[: local.size] = local
        self.u.x.scatter_forward()
        self.update()
        self._last = np.array(local, copy=True)

    def _residual(self, _snes: PETSc.SNES, x: PETSc.Vec, b: PETSc.Vec) -> None:
        self._set_u(x)
        with b.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.F)
        dolfinx.fem.petsc.apply_lifting(b, [self.J], [self.bcs], x0=[x], alpha=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        if self.extra is not None:
            rows, values = self.extra.residual_entries()
            start = b.getOwnershipRange()[0]
            with b.localForm() as local:
                np.add.at(local.array, rows - start, values)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)

    def _jacobian(self, _snes: PETSc.SNES, x: PETSc.Vec, A: PETSc.Mat, _P: PETSc.Mat) -> None:
        self._set_u(x)
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(A, self.J, bcs=self.bcs)
        if self.extra is not None:
            A.assemble(PETSc.Mat.AssemblyType.FLUSH)  # the Dirichlet diagonal was inserted
            _add_entries(A, *self.extra.jacobian_entries())
        A.assemble()

    def solve(self) -> NewtonReport:
        """Newton from the current u; u holds the last iterate whatever the reason.

        With ``watchdog``, a stalled line search is followed by a full step and a restart
        (module docstring), counted in the iterations and in :attr:`watchdog_steps`; the restart
        keeps the first solve's relative criterion (rtol of its first ||F||).

        Raises:
            RunError: PETSc raised (e.g. a singular factorisation).
        """
        self.residuals = []
        self._last = None
        self.watchdog_steps = 0
        owned = self.x.getLocalSize()
        self.x.array[:] = self.u.x.array[:owned]
        rtol, atol, _stol, max_it = self.snes.getTolerances()
        iterations, stalled_at = 0, np.inf
        try:
            while True:
                self.snes.setTolerances(max_it=max_it - iterations)
                first_solve = not self.residuals
                self.snes.solve(None, self.x)
                if first_solve:  # a restart keeps this criterion: rtol of the first ||F||
                    first = self.residuals[0] if self.residuals else 0.0
                    self.snes.setTolerances(atol=max(atol, rtol * first), rtol=0.0)
                iterations += int(self.snes.getIterationNumber())
                reason = int(self.snes.getConvergedReason())
                stall = self.residuals[-1] if self.residuals else np.inf
                if (
                    not self.watchdog
                    or reason != PETSc.SNES.ConvergedReason.DIVERGED_LINE_SEARCH
                    or iterations >= max_it
                    or not stall < stalled_at
                ):
                    break
                stalled_at = stall
                if not self._full_step():
                    break
                iterations += 1
                self.watchdog_steps += 1
        except PETSc.Error as exc:
            raise RunError(f"Newton solver '{self.prefix}' failed ({exc})") from None
        finally:
            self.snes.setTolerances(atol=atol, rtol=rtol, max_it=max_it)
        self._set_u(self.x)
        ksp = self.snes.getKSP()
        self.linear_failure = ""
        if reason == PETSc.SNES.ConvergedReason.DIVERGED_LINEAR_SOLVE:
            pc = ksp.getPC()
            self.linear_failure = (
                f"KSP reason {ksp.getConvergedReason()}, PC {pc.getFailedReason()}"
            )
            if pc.getType() == "lu" and pc.getFactorSolverType() == "mumps":
                factor = pc.getFactorMatrix()
                self.linear_failure += f", MUMPS INFOG(1) {factor.getMumpsInfog(1)}"
            pc.reset()  # a failed factorisation is not reused by the next solve
        if reason > 0 and not np.isfinite(self.x.norm()):
            reason = int(PETSc.SNES.ConvergedReason.DIVERGED_FNORM_NAN)
        return NewtonReport(
            reason, snes_reason_name(reason), iterations, self.residuals, self.watchdog_steps
        )

    def _full_step(self) -> bool:
        """One full Newton step x ← x − J(x)⁻¹ F(x), no line search.

        The new ||F|| is the restart's first monitored norm. Returns False, x unchanged,
        when the linear solve fails.
        """
        ksp = self.snes.getKSP()
        dx = self.x.duplicate()
        try:
            self._residual(self.snes, self.x, self.b)
            self._jacobian(self.snes, self.x, self.A, self.A)
            ksp.setOperators(self.A)
            ksp.solve(self.b, dx)
            if ksp.getConvergedReason() < 0:
                return False
            self.x.axpy(-1.0, dx)
            return True
        finally:
            dx.destroy()

    def describe(self) -> dict[str, object]:
        """Prefix, SNES, line search, KSP and PC types (for summary.json)."""
        ksp = self.snes.getKSP()
        return {
            "prefix": self.prefix,
            "snes_type": self.snes.getType(),
            "linesearch": self.snes.getLineSearch().getType(),
            "ksp_type": ksp.getType(),
            "pc_type": ksp.getPC().getType(),
            "options": dict(self.options),
        }

    def destroy(self) -> None:
        """Free the SNES, matrix and vectors.

        These are the only PETSc objects the solver makes: u is read and written through
        its DOLFINx array, never its wrapped PETSc vector, which Python's garbage
        collector would free at a different moment on each rank (u's owner sits in a
        reference cycle through ``update``); freeing the last PETSc object of a
        communicator on one rank only makes the next solver's creation call MPI_Comm_dup
        on that rank alone, and the ranks deadlock (strength reduction builds one
        solver per trial).
        """
        self.snes.destroy()
        self.A.destroy()
        self.b.destroy()
        self.x.destroy()
