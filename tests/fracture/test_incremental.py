"""The ``update`` solver (one factorisation, exact corrections) against dense numpy solves."""

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.fracture.incremental import MAX_RESIDUAL, Gather, IncrementalSolver, Stale
from geofrac.solvers import LinearSolver, Vector, ghosted_vector
from tests.petsc_matrices import aij_from_dense

N = 40


def _spd(n: int = N) -> np.ndarray:
    """A symmetric positive definite banded matrix (a 1D stiffness with springs to ground)."""
    return np.diag(np.full(n, 2.2)) - np.diag(np.ones(n - 1), 1) - np.diag(np.ones(n - 1), -1)


def _solver(comm: MPI.Comm, A: np.ndarray, b: np.ndarray) -> tuple[IncrementalSolver, Vector]:
    n = len(A)
    M = aij_from_dense(comm, A)
    r0, r1 = M.getOwnershipRange()
    bv = M.createVecLeft()
    bv.array[:] = b[r0:r1]
    x = ghosted_vector(comm, (r1 - r0, n))
    none = np.zeros(n, dtype=bool)
    solver = LinearSolver(M, "test_update_", "direct", options={}, num_dofs=n)
    inc = IncrementalSolver(
        M,
        bv,
        fixed=none,
        bc_mask=none,
        bc_values=np.zeros(n),
        solver=solver,
        x=x,
        gather=Gather(x),
        capacity=20,
    )
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


def _spoil_correction(monkeypatch, inc, spoil: float, refinement: float) -> None:
    """Spoil the correction on T to a residual of norm ``spoil``.

    Every refinement step's correction becomes ``refinement`` on each DOF of T.
    """
    lu = inc.update
    exact_correction = lu.correction

    def correction(y_t, atol=0.0, steps=3):
        g = exact_correction(y_t, atol, steps)
        # g + δ gives the residual −E (I + ΔC S) δ: δ on T's first DOF, scaled so that the
        # residual's norm is `spoil`
        g[0] += spoil / np.linalg.norm((np.eye(lu.m) + lu.dC @ lu.S)[:, 0])
        return g

    monkeypatch.setattr(lu, "correction", correction)
    monkeypatch.setattr(lu, "homogeneous_correction", lambda w_t: refinement * np.ones(len(w_t)))


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
        spoil = 4e-11 * np.linalg.norm(b)
        _spoil_correction(monkeypatch, inc, spoil, refinement=1e-3)
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


def _weakly_held_chain(ground: float = 1e-6) -> np.ndarray:
    """A chain held by one weak spring at its end: condition number ~1.6e8 for 1e-6."""
    A = 2.0 * np.eye(N) - np.eye(N, k=1) - np.eye(N, k=-1)
    A[0, 0], A[-1, -1] = 1.0 + ground, 1.0
    return A


def test_ill_conditioned_reference_accepts_corrections_as_accurate_as_a_fresh_solve():
    """A corrected solution as accurate as a fresh factorisation passes.

    On an ill-conditioned reference the factorisation's own residual ρ₀ exceeds
    MAX_RESIDUAL; refusing such corrections refactorised at every event, to no better
    residual. One spoiled to ten times ρ₀ is still refused (the next test).
    """
    A, b = _weakly_held_chain(), np.linspace(-1.0, 2.0, N)
    dofs, k = _change()
    A1 = A.copy()
    A1[np.ix_(dofs, dofs)] += k
    fresh, xf = _solver(MPI.COMM_SELF, A1, b)
    fresh_residual = np.linalg.norm(b - A1 @ fresh.y) / np.linalg.norm(b)
    fresh.destroy()
    xf.destroy()
    assert fresh_residual > MAX_RESIDUAL  # the case this is about
    inc, x = _solver(MPI.COMM_SELF, A, b)
    try:
        floor = np.sqrt(inc.floor2)
        assert floor > MAX_RESIDUAL
        inc.apply([(dofs, k)], np.zeros(0, dtype=np.int64), np.zeros(0))
        u = inc.solve(x)
        residual = np.linalg.norm(b - A1 @ u) / np.linalg.norm(b)
        assert residual <= 2.0 * floor
        assert residual <= 4.0 * fresh_residual
        # the solution itself: as close to the exact one as the fresh solve is
        exact = np.linalg.solve(A1, b)
        err = np.linalg.norm(u - exact) / np.linalg.norm(exact)
        assert err < 1e-6
    finally:
        inc.destroy()
        x.destroy()


def test_ill_conditioned_reference_still_refuses_a_spoiled_correction(monkeypatch):
    A, b = _weakly_held_chain(), np.linspace(-1.0, 2.0, N)
    inc, x = _solver(MPI.COMM_SELF, A, b)
    try:
        dofs, k = _change()
        inc.apply([(dofs, k)], np.zeros(0, dtype=np.int64), np.zeros(0))
        _spoil_correction(monkeypatch, inc, 10.0 * np.sqrt(inc.floor2) * np.linalg.norm(b), 0.0)
        with pytest.raises(Stale) as info:
            inc.solve(x)
        assert info.value.kind == "residual"
    finally:
        inc.destroy()
        x.destroy()
