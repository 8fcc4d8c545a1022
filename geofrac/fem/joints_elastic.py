"""Elastic rock with Coulomb joints: Newton on the element's own unknowns (P2 or RGNQ).

The springs of :mod:`geofrac.fem.joints` act on the P2 displacement u. An element whose
unknowns are u itself (P2) or vertex DOFs w with u = T w (RGNQ: three rotations per
vertex, Edo (2016), eq. 2.5; :mod:`geofrac.elements.gradient`) is solved here in its
unknowns: with K the element's stiffness on them (:meth:`ElasticProblem.stiffness`:
Tᵀ A T plus its zero-mode penalty) and b its load vector, the residual and Jacobian are

    R(w) = K w − λ b + Tᵀ f(T w),        J = K + Tᵀ K_f T,

f and K_f the springs' forces and tangent on u (T the identity for P2). The loads and the
prescribed displacements are ramped with λ in equal steps; each step is a full Newton
iteration from the last converged state (a new LU factorisation per iteration, MUMPS via
:class:`~geofrac.solvers.LinearSolver` under the prefix ``geofrac_joints_``) with the
Dirichlet rows and columns eliminated (the increment is zero there). A step converges
at the round-off of its residual (:meth:`_Newton.step`); it is not cut: a step that
does not converge in ``max_iterations`` ends the run with a ``NOT CONVERGED`` result.
The rock is elastic (the ``plasticity`` effect's solver has the elasto-plastic rock, on
P2 only).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.joints import JointGeometry, JointInterface
from geofrac.plasticity.interface import JointStrength
from geofrac.solvers import LinearSolver, coo_matrix, function_vector, zero_rows_columns
from geofrac.solvers.matrices import add_matrix

__all__ = ["PREFIX", "run_elastic_joints"]

#: PETSc options prefix of the joints' Newton solves.
PREFIX = "geofrac_joints_"
#: Relative and absolute (on the problem's scale) residual tolerances of a step.
#: Round-off of R's terms (relative to ‖K w‖), and where a stalled Newton counts as converged.
ROUND_OFF, RTOL = 1e-14, 1e-9


class _Unknowns:
    """The map between the element's unknowns w and the P2 displacement u = T w."""

    def __init__(self, problem: Any) -> None:
        self.problem = problem
        element = problem.element
        self.T = element.prolongation() if hasattr(element, "prolongation") else None
        self.w = problem.unknown()
        self.u = problem.uh

    def field(self) -> None:
        """Set u = T w (ghosts updated)."""
        self.w.x.scatter_forward()
        self.problem.to_field()
        self.u.x.scatter_forward()

    def restrict(self, f: dolfinx.fem.Function) -> Any:
        """Tᵀ f as a new vector on the unknowns."""
        fv = function_vector(f)
        if self.T is None:
            return fv.copy()
        out = self.T.createVecRight()
        self.T.multTranspose(fv, out)
        return out

    def restrict_matrix(self, K: Any) -> Any:
        """Tᵀ K T as a new matrix on the unknowns (K itself for P2)."""
        return K if self.T is None else K.ptap(self.T)


def _bc_rows(problem: Any) -> list[np.ndarray]:
    """Per scene ``[[bc]]`` the owned global rows of the unknowns it holds.

    Vertex-DOF elements keep one (rows, values) pair per condition (then the implied
    ones); a DOLFINx space keeps one DirichletBC per held component (one for an
    ``exact`` condition), in the scene's order.
    """
    out: list[np.ndarray] = []
    if problem.bcs and isinstance(problem.bcs[0], tuple):
        return [np.asarray(r, dtype=np.int64) for r, _ in problem.bcs[: len(problem.scene.bcs)]]
    V = problem.element.space
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    start, k = imap.local_range[0] * bs, 0
    for bc in problem.scene.bcs:
        count = 1 if bc.value == "exact" else len(bc.components)
        rows = []
        for dirichlet in problem.bcs[k : k + count]:
            local = np.asarray(dirichlet.dof_indices()[0], dtype=np.int64)
            rows.append(local[local < imap.size_local * bs] + start)
        k += count
        out.append(np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64))
    return out


class _Newton:
    """The joints' Newton solve on the unknowns of one elastic problem."""

    def __init__(self, problem: Any, springs: JointInterface, *, max_iterations: int) -> None:
        self.problem, self.springs, self.max_iterations = problem, springs, max_iterations
        if problem.changes_basis:
            raise RunError(
                "joints: the element's boundary DOFs use a per-vertex basis here "
                "(discretization.gradient_bc = 'consistent' on a curved or oblique group); "
                "set gradient_bc = 'fixed' or 'free' to run with joints"
            )
        self.map = _Unknowns(problem)
        self.K = problem.stiffness()
        self.b = problem.load_vector()
        self.rows, self.values = problem.dirichlet()
        self.f = dolfinx.fem.Function(problem.element.space)
        #: the Newton increment (ghosted: the linear solver updates its ghosts)
        self.dw = dolfinx.fem.Function(self.map.w.function_space)
        bs = problem.element.space.dofmap.index_map_bs
        self._start = problem.element.space.dofmap.index_map.local_range[0] * bs
        self.comm = problem.mesh.comm
        #: per ``[[bc]]`` group the reaction by component at the last converged step
        self.reactions: dict[str, list[float]] = {}

    def residual(self, factor: float) -> tuple[Any, float]:
        """R = K w − λ b + Tᵀ f(T w) (unconstrained, a new vector) and ‖K w‖.

        The springs are updated at u = T w.
        """
        self.map.field()
        self.springs.update(self.map.u)
        rows, values = self.springs.residual_entries()
        self.f.x.array[:] = 0.0
        np.add.at(self.f.x.array, rows - self._start, values)
        w = function_vector(self.map.w)
        R = self.K.createVecLeft()
        self.K.mult(w, R)
        internal = R.norm()
        R.axpy(-factor, self.b)
        spring = self.map.restrict(self.f)
        R.axpy(1.0, spring)
        spring.destroy()
        return R, internal

    def jacobian(self) -> Any:
        """J = K + Tᵀ K_f T (a new matrix, the Dirichlet rows not yet eliminated)."""
        V = self.problem.element.space
        imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
        sizes = (imap.size_local * bs, imap.size_global * bs)
        Kf = coo_matrix(self.comm, sizes, self.springs.jacobian_entries())
        try:
            J = self.K.copy()
            reduced = self.map.restrict_matrix(Kf)
            add_matrix(J, reduced)
            J.assemble()
            if reduced is not Kf:
                reduced.destroy()
        finally:
            Kf.destroy()
        return J

    def step(self, factor: float) -> tuple[bool, int, float]:
        """Newton at the load factor: (converged, iterations, final ‖R‖); :attr:`reactions`.

        Converged at ‖R‖ <= 1e-14 ‖K w‖ (round-off in R's terms), or once ‖R‖ <= 1e-9
        of the step's first residual has stopped falling tenfold an iteration (Newton is
        at round-off there): the solves of 1 and N ranks then agree to round-off.
        """
        w = function_vector(self.map.w)
        owned = self.rows - w.getOwnershipRange()[0]
        w.array[owned] = factor * self.values
        w.ghostUpdate()
        first, previous = None, math.inf
        for k in range(self.max_iterations + 1):
            R, internal = self.residual(factor)
            held = R.array[owned].copy()  # the reactions' rows
            R.array[owned] = 0.0
            norm = R.norm()
            first = norm if first is None else first
            stalled = norm <= RTOL * first and norm > 0.1 * previous
            if norm <= ROUND_OFF * internal or stalled:
                R.array[owned] = held
                self.reactions = self._reactions(R)
                R.destroy()
                return True, k, norm
            if k == self.max_iterations or not np.isfinite(norm):
                R.destroy()
                return False, k, norm
            previous = norm
            J = self.jacobian()
            dw = function_vector(self.dw)
            solver = None
            try:
                zero_rows_columns(J, self.rows, np.zeros(len(self.rows)), b=R)
                R.scale(-1.0)
                solver = LinearSolver(J, PREFIX, "direct", options={}, num_dofs=int(J.getSize()[0]))
                solver.solve(R, dw)
                w.axpy(1.0, dw)
                w.ghostUpdate()
            finally:
                for obj in (solver, J, R):
                    if obj is not None:
                        obj.destroy()
        return False, self.max_iterations, float("nan")

    def _reactions(self, R: Any) -> dict[str, list[float]]:
        """Per ``[[bc]]`` group the sum of R = K w − λ b + Tᵀ f over its rows, by component."""
        gdim = self.problem.mesh.geometry.dim
        bs = self.map.w.function_space.dofmap.index_map_bs
        lo = R.getOwnershipRange()[0]
        out: dict[str, list[float]] = {}
        for bc, rows in zip(self.problem.scene.bcs, _bc_rows(self.problem), strict=True):
            sums = np.array([np.sum(R.array[rows[rows % bs == c] - lo]) for c in range(gdim)])
            total = self.comm.allreduce(sums, op=MPI.SUM)
            out[bc.group] = [float(v) for v in total]
        return out

    def destroy(self) -> None:
        """Free the stiffness and load vector."""
        self.K.destroy()
        self.b.destroy()


def run_elastic_joints(
    solution: Any,
    say: Callable[[str], None],
    *,
    joints: Sequence[Any],
    penalty: float,
    steps: int,
    max_iterations: int,
) -> dict[str, Any]:
    """Ramp the loads in ``steps`` with the joints' springs; the results (JSON-ready).

    Args:
        solution: the runner's solution (its elastic problem, mesh and scene).
        say: progress lines (rank 0 prints).
        joints: the effect's joint entries (``name``, ``friction``, ``cohesion``,
            ``normal_stiffness``, ``shear_stiffness``).
        penalty: kₙ = kₛ = penalty · E / ℓ where a joint gives no stiffness.
        steps: equal load increments.
        max_iterations: Newton iterations per increment.

    Returns:
        ``converged``, ``factor`` (the last converged load factor), ``steps`` (per step:
        ``factor``, ``iterations``, ``residual``, ``reactions``), ``joints`` (the springs'
        summary) and ``solver``.
    """
    problem = solution.problem
    scene = solution.scene
    V = problem.element.space
    geometry = JointGeometry.build(V, solution.tagged, [j.name for j in joints], key="joints")
    springs = JointInterface(
        geometry,
        V,
        [JointStrength(j.cohesion, j.friction) for j in joints],
        penalty=penalty,
        E=float(scene.material.E),
        stiffness=[(j.normal_stiffness, j.shear_stiffness) for j in joints],
    )
    newton = _Newton(problem, springs, max_iterations=max_iterations)
    rows: list[dict[str, Any]] = []
    converged, factor = True, 0.0
    try:
        for k in range(1, steps + 1):
            trial = k / steps
            ok, its, norm = newton.step(trial)
            if not ok:
                say(
                    f"joints: factor {trial:.4f} NOT CONVERGED after {its} iterations "
                    f"(|R| {norm:.3g}); the fields are those of the last iterate"
                )
                converged = False
                break
            # the reactions and states of the converged iterate, before its slips are
            # committed (after, each slipping pair's trial sits on its limit to round-off)
            reactions = newton.reactions
            summary = springs.summary()
            springs.commit()
            factor = trial
            rows.append(
                {"factor": trial, "iterations": its, "residual": norm, "reactions": reactions}
            )
            say(
                f"joints: factor {trial:.4f} converged ({its} its, |R| {norm:.2e}), "
                f"{summary['slipping']} slipping, {summary['open']} open"
            )
    finally:
        newton.destroy()
    newton.map.field()
    return {
        "converged": converged,
        "factor": factor,
        "steps": rows,
        "joints": springs.summary(),
        "solver": {"prefix": PREFIX, "newton": "full, LU (MUMPS) per iteration"},
        "springs": springs,
    }
