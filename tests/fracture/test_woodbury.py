"""The exact low-rank correction of a locally changed system (pure numpy)."""

import numpy as np
import pytest

from geofrac.fracture.woodbury import LocalUpdate


def _system(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A0, b0, A0⁻¹): a chain Laplacian plus a random SPD coupling, like a stiffness."""
    A = np.diag(np.full(n, 4.0)) - np.diag(np.ones(n - 1), 1) - np.diag(np.ones(n - 1), -1)
    R = rng.normal(size=(n, 3))
    A = A + 0.1 * R @ R.T
    return A, rng.normal(size=n), np.linalg.inv(A)


def _cell_change(rng: np.random.Generator, p: int) -> np.ndarray:
    """A symmetric change: a rank-2 softening plus a rank-1 stiffening."""
    U = rng.normal(size=(p, 3))
    return -0.3 * U[:, :2] @ U[:, :2].T + 0.2 * np.outer(U[:, 2], U[:, 2])


def _events(lu: LocalUpdate, rng: np.random.Generator, n: int = 60, events: int = 10):
    """Run random cell changes through ``lu``; the corrected solutions and exact ones."""
    A0, b0, inv = _system(n, rng)
    y = inv @ b0
    A, b = A0.copy(), b0.copy()
    got, exact = [], []
    for _event in range(events):
        dofs = np.sort(rng.choice(n, size=5, replace=False))
        new = lu.missing(dofs)
        if len(new):
            rows = np.concatenate([lu.dofs, new])
            lu.grow(new, inv[np.ix_(rows, new)])
        k = _cell_change(rng, len(dofs))
        lu.add(dofs, k)
        A[np.ix_(dofs, dofs)] += k
        f = rng.normal(size=len(dofs))
        lu.add_rhs(dofs, f)
        b[dofs] += f
        e = np.zeros(n)
        e[lu.dofs] = lu.correction(y[lu.dofs])
        got.append(y + inv @ e)
        exact.append(np.linalg.solve(A, b))
    return np.array(got), np.array(exact)


def test_corrected_solution_equals_the_direct_solve_over_many_events():
    lu = LocalUpdate(60, capacity=40)
    got, exact = _events(lu, np.random.default_rng(7), events=8)
    np.testing.assert_allclose(got, exact, rtol=1e-9, atol=1e-10)
    assert lu.m <= 40
    # N⁻¹ kept by updates equals the inverse formed afresh
    N = np.eye(lu.m) + lu.S @ lu.dC
    np.testing.assert_allclose(lu.Ninv @ N, np.eye(lu.m), atol=1e-9)


def _unsymmetric_events(rows_given: bool) -> float:
    """Largest relative error of the corrected solutions of an unsymmetric A₀.

    Friction on slipping crack faces makes A₀ and its changes unsymmetric (a block
    −μ sgn BₜᵀBₙ); the new rows of S are then (A₀⁻¹)[new, T], which the ``update`` solver
    takes from its factorisation of A₀ᵀ, or not (``rows_given``).
    """
    rng = np.random.default_rng(5)
    n = 50
    A0, b0, _ = _system(n, rng)
    A0 = A0 + 0.4 * np.outer(rng.normal(size=n), rng.normal(size=n)) / n
    inv = np.linalg.inv(A0)
    y = inv @ b0
    lu = LocalUpdate(n, capacity=n)
    A, b = A0.copy(), b0.copy()
    worst = 0.0
    for _event in range(6):
        dofs = np.sort(rng.choice(n, size=4, replace=False))
        new = lu.missing(dofs)
        if len(new):
            old = lu.dofs.copy()
            rows = inv[np.ix_(new, old)] if rows_given else None
            lu.grow(new, inv[np.ix_(np.concatenate([old, new]), new)], rows)
        Bn, Bt = rng.normal(size=len(dofs)), rng.normal(size=len(dofs))
        k = 0.5 * (np.outer(Bn, Bn) - 0.6 * np.outer(Bt, Bn))
        lu.add(dofs, k)
        A[np.ix_(dofs, dofs)] += k
        e = np.zeros(n)
        e[lu.dofs] = lu.correction(y[lu.dofs])
        x, exact = y + inv @ e, np.linalg.solve(A, b)
        worst = max(worst, float(np.max(np.abs(x - exact)) / np.max(np.abs(exact))))
    return worst


def test_unsymmetric_system_needs_the_rows_of_the_inverse():
    assert _unsymmetric_events(rows_given=True) < 1e-10
    # the columns transposed in their place (a symmetric A₀ assumed) are wrong here
    assert _unsymmetric_events(rows_given=False) > 1e-6


def test_refinement_on_t_recovers_digits_lost_by_n_inverse():
    """A perturbed N⁻¹ (as after many ill-conditioned updates) is corrected on T alone."""
    rng = np.random.default_rng(11)
    n = 40
    A0, b0, inv = _system(n, rng)
    y = inv @ b0
    lu = LocalUpdate(n, capacity=n)
    dofs = np.sort(rng.choice(n, size=12, replace=False))
    lu.grow(dofs, inv[np.ix_(dofs, dofs)])
    k = _cell_change(rng, len(dofs))
    lu.add(dofs, k)
    A = A0.copy()
    A[np.ix_(dofs, dofs)] += k
    exact = np.linalg.solve(A, b0)
    lu.correction(y[lu.dofs])  # fold the change into N⁻¹
    lu._Ninv[: lu.m, : lu.m] += 1e-5 * rng.normal(size=(lu.m, lu.m))

    def error(steps: int) -> float:
        e = np.zeros(n)
        e[lu.dofs] = lu.correction(y[lu.dofs], atol=0.0, steps=steps)
        return float(np.linalg.norm(y + inv @ e - exact) / np.linalg.norm(exact))

    assert error(0) > 1e-7
    assert error(3) < 1e-12


def test_a_row_made_identity_holds_its_value():
    """Removing every coupling of a DOF and adding 1 on its diagonal holds it at Δb's value."""
    rng = np.random.default_rng(3)
    n = 20
    A0, b0, inv = _system(n, rng)
    lu = LocalUpdate(n, capacity=n)
    j = 7
    dofs = np.flatnonzero(A0[j] != 0)
    lu.grow(dofs, inv[np.ix_(dofs, dofs)])
    k = np.zeros((len(dofs), len(dofs)))
    q = int(np.flatnonzero(dofs == j)[0])
    k[q, :] -= A0[j, dofs]
    k[:, q] -= A0[dofs, j]
    k[q, q] += A0[j, j] + 1.0
    lu.add(dofs, k)
    lu.add_rhs(np.array([j]), np.array([0.25 - b0[j]]))
    g = lu.correction((inv @ b0)[lu.dofs])
    e = np.zeros(n)
    e[lu.dofs] = g
    x = inv @ b0 + inv @ e
    assert x[j] == pytest.approx(0.25, abs=1e-12)


def test_capacity_and_membership_are_checked():
    lu = LocalUpdate(10, capacity=2)
    with pytest.raises(ValueError, match="capacity"):
        lu.grow(np.array([0, 1, 2]), np.zeros((3, 3)))
    lu.grow(np.array([4]), np.ones((1, 1)))
    with pytest.raises(ValueError, match="already"):
        lu.grow(np.array([4]), np.ones((1, 1)))
    with pytest.raises(ValueError, match="not in T"):
        lu.add(np.array([5]), np.ones((1, 1)))


def test_singular_change_is_reported():
    """Removing all stiffness of a 1-DOF system makes the corrected system singular."""
    lu = LocalUpdate(1, capacity=1)
    lu.grow(np.array([0]), np.array([[0.5]]))  # A0 = [2]
    lu.add(np.array([0]), np.array([[-2.0]]))
    with pytest.raises(np.linalg.LinAlgError):
        lu.correction(np.array([1.0]))


@pytest.mark.mpi(min_size=2)
def test_rows_shared_among_ranks_give_the_serial_correction():
    """S, ΔC and N⁻¹ split by rows over the ranks correct as the whole matrices do."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    shared = LocalUpdate(60, capacity=50, comm=comm)
    got, exact = _events(shared, np.random.default_rng(13))
    serial, _ = _events(LocalUpdate(60, capacity=50), np.random.default_rng(13))
    np.testing.assert_allclose(got, exact, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(got, serial, rtol=1e-12, atol=1e-13)
    # each rank holds its rows only, and the gathered matrices are the serial ones
    assert shared._loc(shared._Ninv).shape[0] == len(range(comm.rank, shared.m, comm.size))
    N = np.eye(shared.m) + shared.S @ shared.dC
    np.testing.assert_allclose(shared.Ninv @ N, np.eye(shared.m), atol=1e-9)
    g = shared.homogeneous_correction(np.ones(shared.m))
    assert np.allclose(comm.allgather(g)[0], g)  # the same on every rank
