"""The ``update`` solver (one factorisation, exact corrections) against dense numpy solves."""

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI
from petsc4py import PETSc

from geofrac.fracture.incremental import MAX_RESIDUAL, Gather, IncrementalSolver
from geofrac.solvers import LinearSolver
from tests.petsc_matrices import aij_from_dense

N = 40


def _spd(n: int = N) -> np.ndarray:
    """A symmetric positive definite banded matrix (a 1D stiffness with springs to ground)."""
    return np.diag(np.full(n, 2.2)) - np.diag(np.ones(n - 1), 1) - np.diag(np.ones(n - 1), -1)


def _solver(comm: MPI.Comm, A: np.ndarray, b: np.ndarray) -> tuple[IncrementalSolver, PETSc.Vec]:
    n = len(A)
    M = aij_from_dense(comm, A)
    r0, r1 = M.getOwnershipRange()
    bv = M.createVecLeft()
    bv.array[:] = b[r0:r1]
    x = PETSc.Vec().createGhost([], (r1 - r0, n), comm=comm)
    none = np.zeros(n, dtype=bool)
    solver = LinearSolver(M, "test_update_", "direct", {}, n)
    inc = IncrementalSolver(M, bv, none, none, np.zeros(n), solver, x, Gather(x), capacity=20)
    return inc, x


def _change() -> tuple[np.ndarray, np.ndarray]:
    """A cell-like symmetric change on four DOFs (a stiffer spring between 7 and 30, ...)."""
    dofs = np.array([7, 30, 12, 13])
    k = np.array([[3.0, -3.0, 0, 0], [-3.0, 3.0, 0, 0], [0, 0, -0.5, 0.5], [0, 0, 0.5, -0.5]])
    return dofs, k


@pytest.mark.parametrize(
    "comm",
    [
        pytest.param(MPI.COMM_SELF, id="self"),
        pytest.param(MPI.COMM_WORLD, id="world", marks=pytest.mark.mpi(min_size=2)),
    ],
)
def test_corrected_solution_is_the_changed_systems(comm):
    A, b = _spd(), np.linspace(-1.0, 2.0, N)
    inc, x = _solver(comm, A, b)
    try:
        assert inc.floor2 < 1e-28  # a well-conditioned reference solves to round-off
        dofs, k = _change()
        inc.apply([(dofs, k)], np.zeros(0, dtype=np.int64), np.zeros(0))
        u = inc.solve(x)
        A1 = A.copy()
        A1[np.ix_(dofs, dofs)] += k
        np.testing.assert_allclose(u, np.linalg.solve(A1, b), rtol=0, atol=1e-12)
        assert inc.refinements == 0
    finally:
        inc.destroy()
        x.destroy()


def test_refinement_step_that_does_not_help_is_undone(monkeypatch):
    """A refinement step that raises the residual is dropped; the solution before it stays.

    The correction on T is spoiled a little (relative residual between REFINE_ABOVE and
    MAX_RESIDUAL, so one refinement step is taken) and the refinement's own correction a
    lot (the step makes things worse): the solver must return the first solution, not
    the worse one, and must not go stale.
    """
    A, b = _spd(), np.linspace(-1.0, 2.0, N)
    inc, x = _solver(MPI.COMM_WORLD, A, b)
    try:
        dofs, k = _change()
        inc.apply([(dofs, k)], np.zeros(0, dtype=np.int64), np.zeros(0))
        lu = inc.update
        exact_correction = lu.correction
        spoil = 4e-11 * np.linalg.norm(b)

        def correction(y_t, atol=0.0, steps=3):
            g = exact_correction(y_t, atol, steps)
            # g + δ gives the residual −E (I + ΔC S) δ: δ on T's first DOF, scaled so
            # that the residual's norm is `spoil`
            g[0] += spoil / np.linalg.norm((np.eye(lu.m) + lu.dC @ lu.S)[:, 0])
            return g

        monkeypatch.setattr(lu, "correction", correction)
        monkeypatch.setattr(lu, "homogeneous_correction", lambda w_t: 1e-3 * np.ones(len(w_t)))
        u = inc.solve(x)
        assert inc.refinements == 1
        A1 = A.copy()
        A1[np.ix_(dofs, dofs)] += k
        r = b - A1 @ u
        assert np.linalg.norm(r) == pytest.approx(spoil, rel=1e-3)
        assert np.linalg.norm(r) <= MAX_RESIDUAL * np.linalg.norm(b)
    finally:
        inc.destroy()
        x.destroy()
