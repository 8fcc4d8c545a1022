"""MLS smoothing of strain increments (Edo (2016), eqs. 4.50-4.58)."""

from pathlib import Path

import numpy as np
import pytest

from geofrac.mpm import smoothing
from geofrac.mpm.smoothing import (
    MARGIN,
    basis,
    cubic_spline,
    neighbour_pairs,
    neighbour_stats,
    smooth,
    smooth_particles,
)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_linear_strain_increments_are_reproduced_exactly(dim):
    rng = np.random.default_rng(dim)
    x = rng.uniform(0.0, 3.0, size=(250 * dim, dim))
    values = np.stack(
        [1.0 + x @ np.arange(1.0, dim + 1), 2.0 - 0.5 * x[:, 0], np.full(len(x), 3.0)], 1
    )
    out, done = smooth(x, values, 0.6 if dim < 3 else 0.9)
    assert done.mean() > 0.9  # most particles have enough neighbours
    np.testing.assert_allclose(out[done], values[done], atol=1e-11)
    np.testing.assert_array_equal(out[~done], values[~done])


def test_cubic_field_is_reproduced_in_1d_and_noise_is_reduced():
    rng = np.random.default_rng(5)
    x = np.sort(rng.uniform(0.0, 5.0, size=(80, 1)), axis=0)
    cubic = x**3 - 2 * x
    out, done = smooth(x, cubic, 1.0)
    np.testing.assert_allclose(out[done], cubic[done], atol=1e-10)
    noise = rng.normal(size=(80, 1))
    out, done = smooth(x, cubic + noise, 1.0)
    assert np.std((out - cubic)[done]) < 0.9 * np.std(noise[done])


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_too_few_neighbours_or_a_singular_fit_keep_their_own_value(backend):
    # 1D cubic needs 4 neighbours (self included): three particles are not smoothed
    x = np.array([[0.0], [0.3], [0.6]])
    v = np.array([[1.0], [5.0], [2.0]])
    out, done = smooth(x, v, 1.0, backend=backend)
    assert not done.any()
    np.testing.assert_array_equal(out, v)
    # 2D particles on a line: the cubic moment matrix is singular
    t = np.linspace(0.0, 1.0, 30)
    x2 = np.stack([t, 2 * t], axis=1)
    values = np.stack([t**2, t, 1 + t], axis=1)
    out, done = smooth(x2, values, 0.5, backend=backend)
    assert not done.any()
    np.testing.assert_array_equal(out, values)
    # almost on a line (1e-7 off it): A is regular but κ₂ is ~1e20, far beyond 1e12
    x3 = x2 + 1e-7 * np.random.default_rng(3).normal(size=x2.shape)
    out, done = smooth(x3, values, 0.5, backend=backend)
    assert not done.any()


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_conditioning_bound_accepts_a_spread_cloud_and_brackets_cond2(backend):
    """tr(A) tr(A⁻¹) lies in [κ₂, m² κ₂]; a cloud in a disc is well conditioned."""
    rng = np.random.default_rng(11)
    x = rng.uniform(0.0, 1.0, size=(60, 2))
    x[0] = 0.5
    h = 0.45
    p, q = neighbour_pairs(x, h)
    mine = q[p == 0]
    F = basis((x[mine] - x[0]) / h)
    w = cubic_spline(np.linalg.norm(x[mine] - x[0], axis=1) / h)
    A = (w[:, None] * F).T @ F
    lam = np.linalg.eigvalsh(A)
    kappa_T = np.trace(A) * np.sum(1 / lam)
    m = A.shape[0]
    assert lam[-1] / lam[0] <= kappa_T <= m * m * lam[-1] / lam[0]
    assert kappa_T < smoothing.COND_MAX
    done = smooth(x, rng.normal(size=(60, 3)), h, backend=backend)[1]
    assert done[0]


def _cloud(n_side: int = 24, seed: int = 4):
    """A jittered 2D lattice with values and shuffled storage (ids not the rows)."""
    rng = np.random.default_rng(seed)
    g = (np.arange(n_side) + 0.5) * 0.25
    x = np.stack([a.ravel() for a in np.meshgrid(g, g, indexing="ij")], 1)
    x += rng.uniform(-0.05, 0.05, size=x.shape)
    values = rng.normal(size=(len(x), 3))
    ids = rng.permutation(len(x)).astype(np.int64)
    return x, values, ids


def test_fits_do_not_depend_on_storage_order():
    """Neighbours are summed by global id: a permuted storage gives the same bits."""
    x, values, ids = _cloud()
    h = 0.6
    out, done = smooth(x, values, h, backend="numba", ids=ids)
    perm = np.random.default_rng(9).permutation(len(x))
    out2, done2 = smooth(x[perm], values[perm], h, backend="numba", ids=ids[perm])
    np.testing.assert_array_equal(done2, done[perm])
    np.testing.assert_array_equal(out2, out[perm])
    ref, ref_done = smooth(x, values, h, backend="numpy", ids=ids)
    np.testing.assert_array_equal(done, ref_done)
    np.testing.assert_allclose(out, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("move", [0.4, 0.9, 3.0])
def test_reused_neighbour_lists_give_the_fresh_fits(move):
    """Moves below margin·h/2 reuse the lists, above rebuild them; the bits are a fresh fit's.

    ``move`` is the largest displacement in units of margin·h/2.
    """
    x, values, ids = _cloud()
    h = 0.6
    smoothing._SERIAL[0] = None
    smooth_particles(x, ids, values, h=h)
    before = neighbour_stats()["builds"]
    rng = np.random.default_rng(5)
    step = rng.normal(size=x.shape)
    step *= move * 0.5 * MARGIN * h / np.linalg.norm(step, axis=1).max()
    moved = x + step
    got = smooth_particles(moved, ids, values, h=h)
    rebuilt = neighbour_stats()["builds"] - before
    assert rebuilt == (1 if move > 1 else 0)
    fresh, _ = smooth(moved, values, h, backend="numba", ids=ids)
    np.testing.assert_array_equal(got, fresh)
    # some pairs crossed r = h (else the test could not tell a stale list)
    r0 = np.linalg.norm(x[:, None] - x[None], axis=2)
    r1 = np.linalg.norm(moved[:, None] - moved[None], axis=2)
    assert np.sum((r0 < h) != (r1 < h)) > 0


def test_generated_kernels_are_current():
    """geofrac/mpm/mls_kernels.py is what mls_codegen writes (never edited by hand)."""
    from geofrac.mpm import mls_codegen

    path = Path(mls_codegen.__file__).with_name("mls_kernels.py")
    assert path.read_text(encoding="utf-8") == mls_codegen.module_source()


@pytest.mark.mpi(min_size=2)
def test_fits_on_two_ranks_equal_the_serial_ones_bit_for_bit():
    """A block straddling the slab boundary: the decomposed fits are the serial bits."""
    from mpi4py import MPI

    from geofrac.mpm.grid import grid
    from geofrac.mpm.parallel import decompose
    from geofrac.mpm.particles import particles

    comm = MPI.COMM_WORLD
    x, values, ids = _cloud()
    h = 0.6
    g = grid([0.0, 0.0], 0.25, [26, 26])
    p = particles(x, np.full(len(x), 0.0625), 1.0, lp0=np.full(x.shape, 0.125))
    p.ids = ids
    dom = decompose(g, comm, halo=3)
    mine = dom.distribute(p)
    by_id = np.empty_like(values)
    by_id[ids] = values
    for rep in range(2):  # a build, then a reuse after a small move
        shift = rep * 0.2 * MARGIN * h
        serial = np.empty_like(values)
        serial[ids] = smooth(x + shift, values, h, backend="numba", ids=ids)[0]
        got = smooth_particles(mine.x + shift, mine.ids, by_id[mine.ids], h=h, domain=dom)
        all_ids, all_fits = dom.allgather_rows(mine.ids, got)
        assert comm.allreduce(len(mine.ids), op=MPI.MIN) > 50  # both ranks hold particles
        np.testing.assert_array_equal(np.sort(all_ids), np.arange(len(x)))
        np.testing.assert_array_equal(all_fits[np.argsort(all_ids)], serial)


def test_neighbour_pairs_match_brute_force():
    rng = np.random.default_rng(2)
    x = rng.uniform(0.0, 2.0, size=(300, 2))
    p, q = neighbour_pairs(x, 0.27)
    close = np.linalg.norm(x[:, None] - x[None], axis=2) < 0.27
    assert len(p) == close.sum()
    assert np.all(close[p, q])
    assert np.all(np.diff(p) >= 0)


def test_cubic_spline_weight_is_smooth_and_compact():
    s = np.linspace(0.0, 1.2, 1201)
    w = cubic_spline(s)
    assert w[0] == pytest.approx(2 / 3)
    assert np.all(w[s >= 1.0] == 0.0)
    assert np.all(np.diff(w) <= 1e-15)  # decreasing
    assert np.max(np.abs(np.diff(w))) < 2e-3  # continuous (no jump at s = 1/2)
    assert basis(np.zeros((1, 2))).shape == (1, 10)
