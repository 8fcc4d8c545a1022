"""MLS smoothing of strain increments (seed eqs. 4.50-4.58)."""

import numpy as np
import pytest

from geofrac.mpm.smoothing import basis, cubic_spline, neighbour_pairs, smooth


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


def test_too_few_neighbours_or_a_singular_fit_keep_their_own_value():
    # 1D cubic needs 4 neighbours (self included): three particles are not smoothed
    x = np.array([[0.0], [0.3], [0.6]])
    v = np.array([[1.0], [5.0], [2.0]])
    out, done = smooth(x, v, 1.0)
    assert not done.any()
    np.testing.assert_array_equal(out, v)
    # 2D particles on a line: the cubic moment matrix is singular
    t = np.linspace(0.0, 1.0, 30)
    x2 = np.stack([t, 2 * t], axis=1)
    out, done = smooth(x2, t[:, None] ** 2, 0.5)
    assert not done.any()
    assert np.all(np.isfinite(out))


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
