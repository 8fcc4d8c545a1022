"""MUMPS helpers against dense numpy solves, on 1 rank and on all ranks."""

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.solvers import (
    Gather,
    LinearSolver,
    Matrix,
    PreconditionedCG,
    add_matrix,
    add_values,
    coo_matrix,
    dense_submatrix,
    diagonal_norm1,
    ghosted_vector,
    mumps_inverse_entries,
    mumps_sparse_solve,
    transposed,
    zero_rows_columns,
)
from tests.petsc_matrices import aij_from_dense

N = 60


def _dense(n: int = N) -> np.ndarray:
    """A nonsymmetric, well-conditioned matrix with a banded and a random part."""
    rng = np.random.default_rng(3)
    A = np.diag(np.full(n, 4.0)) - np.diag(np.ones(n - 1), 1) - np.diag(np.ones(n - 2), -2)
    return A + 0.05 * rng.normal(size=(n, n)) * (rng.random((n, n)) < 0.1)


def _factor(comm: MPI.Comm, A: np.ndarray) -> tuple[Matrix, LinearSolver]:
    M = aij_from_dense(comm, A)
    return M, LinearSolver(M, "test_mumps_", "direct", options={}, num_dofs=len(A))


@pytest.mark.parametrize(
    "comm",
    [
        pytest.param(MPI.COMM_SELF, id="self"),
        pytest.param(MPI.COMM_WORLD, id="world", marks=pytest.mark.mpi(min_size=2)),
    ],
)
def test_sparse_rhs_solve_and_inverse_entries_match_numpy(comm):
    A = _dense()
    inv = np.linalg.inv(A)
    M, solver = _factor(comm, A)
    out, dense = M.createVecRight(), M.createVecRight()
    F = solver.factor()
    try:
        r0, r1 = out.getOwnershipRange()
        rows = np.array([41, 3, 17, 5])  # unsorted on purpose
        values = np.array([1.0, -2.0, 0.5, 3.0])
        mumps_sparse_solve(F, rows, values, out=out)
        b = np.zeros(N)
        b[rows] = values
        np.testing.assert_allclose(out.array, (inv @ b)[r0:r1], rtol=0, atol=1e-12)
        # the factor still solves dense right-hand sides afterwards
        rhs = M.createVecLeft()
        rhs.array[:] = np.arange(r0, r1, dtype=float)
        solver.apply(rhs, dense)
        np.testing.assert_allclose(dense.array, (inv @ np.arange(N))[r0:r1], atol=1e-11)
        rhs.destroy()
        want_r, want_c = np.array([7, 2, 50, 33]), np.array([33, 0, 2])
        entries = mumps_inverse_entries(F, want_r, want_c)
        np.testing.assert_allclose(entries, inv[np.ix_(want_r, want_c)], atol=1e-13)
    finally:
        for obj in (out, dense, M, F):
            obj.destroy()
        solver.destroy()


COMMS = [
    pytest.param(MPI.COMM_SELF, id="self"),
    pytest.param(MPI.COMM_WORLD, id="world", marks=pytest.mark.mpi(min_size=2)),
]


def _coo(comm: MPI.Comm, A: np.ndarray) -> Matrix:
    """A from COO entries, each rank adding half of its own rows twice (summed)."""
    n = len(A)
    r0, r1 = comm.rank * n // comm.size, (comm.rank + 1) * n // comm.size
    rows, cols = np.nonzero(A[r0:r1])
    rows = rows + r0
    vals = A[rows, cols]
    half = 0.5 * vals
    entries = (np.r_[rows, rows], np.r_[cols, cols], np.r_[half, half])
    return coo_matrix(comm, (r1 - r0, n), entries)


@pytest.mark.parametrize("comm", COMMS)
def test_matrix_helpers_match_numpy(comm):
    A = _dense()
    M = _coo(comm, A)
    Mt = transposed(M)
    try:
        dofs = np.array([9, 2, 40])
        np.testing.assert_array_equal(dense_submatrix(M, dofs), A[np.ix_(dofs, dofs)])
        np.testing.assert_array_equal(dense_submatrix(Mt, dofs), A.T[np.ix_(dofs, dofs)])
        assert diagonal_norm1(M) == pytest.approx(np.abs(np.diag(A)).sum(), rel=1e-14)
        add_matrix(Mt, M)
        Mt.assemble()
        np.testing.assert_allclose(dense_submatrix(Mt, dofs), (A + A.T)[np.ix_(dofs, dofs)])
        # x[fixed] = values by symmetric elimination: the rest solves the reduced system
        fixed, values = np.array([0, 31]), np.array([1.5, -2.0])
        b = M.createVecLeft()
        r0, r1 = b.getOwnershipRange()
        b.array[:] = 1.0
        mine = (fixed >= r0) & (fixed < r1)
        zero_rows_columns(M, fixed[mine], values[mine], b=b)
        x = ghosted_vector(comm, (r1 - r0, len(A)))  # a solve updates the ghosts
        solver = LinearSolver(M, "test_zero_", "direct", options={}, num_dofs=len(A))
        solver.solve(b, x)
        gather = Gather(x)
        u = gather(x)
        free = np.setdiff1d(np.arange(len(A)), fixed)
        want = np.zeros(len(A))
        want[fixed] = values
        rhs = np.ones(len(A)) - A[:, fixed] @ values
        want[free] = np.linalg.solve(A[np.ix_(free, free)], rhs[free])
        np.testing.assert_allclose(u, want, atol=1e-12)
        for obj in (gather, solver, x, b):
            obj.destroy()
    finally:
        M.destroy()
        Mt.destroy()


@pytest.mark.parametrize("comm", COMMS)
def test_preconditioned_cg_and_add_values(comm):
    A = _dense()
    spd = A @ A.T
    M, solver = _factor(comm, spd)
    near = _coo(comm, spd + np.diag(np.full(len(A), 0.1)))
    r0, r1 = M.getOwnershipRange()
    x = ghosted_vector(comm, (r1 - r0, len(A)))
    b = M.createVecLeft()
    b.set(0.0)
    add_values(b, np.array([3, 44]), np.array([1.0, 2.0]))  # from every rank: summed
    cg = PreconditionedCG(comm, "test_cg_", solver, max_it=50)
    try:
        its = cg.solve(near, b, x)
        assert its is not None and 0 < its < 50
        rhs = np.zeros(len(A))
        rhs[[3, 44]] = [comm.size, 2.0 * comm.size]
        want = np.linalg.solve(spd + np.diag(np.full(len(A), 0.1)), rhs)
        gather = Gather(x)
        np.testing.assert_allclose(gather(x), want, rtol=1e-8, atol=1e-12)
        gather.destroy()
    finally:
        for obj in (cg, x, b, near, M):
            obj.destroy()
        solver.destroy()


@pytest.mark.parametrize(
    "comm",
    [
        pytest.param(MPI.COMM_SELF, id="self"),
        pytest.param(MPI.COMM_WORLD, id="world", marks=pytest.mark.mpi(min_size=2)),
    ],
)
def test_newton_solvers_one_after_another_whatever_the_garbage_collector(comm):
    """A Newton solver makes no PETSc object it does not destroy itself.

    u's wrapped PETSc vector would be freed by Python's garbage collector (u's owner is in a
    reference cycle through ``update``) at a different moment on each rank; freeing the
    last PETSc object of a communicator on one rank only makes the next solver's creation
    duplicate the communicator on that rank alone, and the ranks deadlock. So the
    solver must leave u without one, and a second solver built after the collector ran
    on rank 0 only (as it may between two strength-reduction trials) must solve.
    """
    import gc

    from geofrac.plasticity import MohrCoulomb
    from tests.fem.plastic_ring import ring_mesh, ring_problem

    tagged = ring_mesh(comm, a=1.0, b=10.0, h=0.5)
    law = MohrCoulomb(E=1e4, nu=0.3, cohesion=1.0, friction_angle=30.0, dilatancy_angle=30.0)
    converged = []
    for _ in range(2):
        problem = ring_problem(tagged, law, p0=10.0, pi=1.0)
        converged.append(problem.solve_steps(2).converged)
        problem.destroy()
        assert problem.u.x._petsc_x is None
        del problem
        if comm.rank == 0:
            gc.collect()
    assert converged == [True, True]


def test_newton_keeps_its_tolerances_from_solve_to_solve():
    """Each solve ends with the SNES tolerances it was built with.

    A solve changes them for its restarts (after a watchdog step the relative criterion
    becomes an absolute one, rtol of the first ||F||); a later solve, e.g. the next load
    step, must again stop at its own rtol and atol.
    """
    from geofrac.plasticity import MohrCoulomb
    from tests.fem.plastic_ring import ring_mesh, ring_problem

    tagged = ring_mesh(MPI.COMM_SELF, a=1.0, b=10.0, h=0.5)
    law = MohrCoulomb(E=1e4, nu=0.3, cohesion=1.0, friction_angle=30.0, dilatancy_angle=30.0)
    problem = ring_problem(tagged, law, p0=10.0, pi=1.0, atol=3e-10, rtol=2e-9, max_it=17)
    try:
        given = (2e-9, 3e-10, 0.0, 17)  # PETSc's order: rtol, atol, stol, max_it
        assert problem.solve_steps(1).converged  # one solve
        assert problem.newton.snes.getTolerances() == given
        assert problem.newton.solve().converged  # and the next
        assert problem.newton.snes.getTolerances() == given
    finally:
        problem.destroy()
