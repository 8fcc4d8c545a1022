"""MLS field of a cracked cell (Edo (2016), eqs. 2.10-2.19)."""

import numpy as np
import pytest

from geofrac.mls.shape import linear_fit, quartic_spline, strain_matrix


def test_quartic_spline_values():
    h = 2.0
    w = quartic_spline(np.array([0.0, 1.0, 2.0, 3.0]), h)
    s = 0.5
    assert w[0] == pytest.approx(5 / (np.pi * h * h))
    assert w[1] == pytest.approx(5 / (np.pi * h * h) * (1 - 6 * s**2 + 8 * s**3 - 3 * s**4))
    assert w[2] == pytest.approx(0.0, abs=1e-15)  # C1 at r = h
    assert w[3] == 0.0


def _cloud(n=12, seed=3):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1.0, 1.0, size=(n, 2))


def test_reproduces_linear_fields_and_sums_to_one():
    pts = _cloud()
    fit = linear_fit(np.array([0.1, -0.05]), 2.0, np.arange(len(pts)), coords=pts)
    assert fit is not None
    x = np.array([[0.0, 0.0], [0.3, -0.2], [-0.4, 0.1]])
    phi = fit.shape_functions(x)
    np.testing.assert_allclose(phi.sum(axis=1), 1.0, atol=1e-13)
    f = 0.7 - 1.3 * pts[:, 0] + 2.1 * pts[:, 1]
    np.testing.assert_allclose(phi @ f, 0.7 - 1.3 * x[:, 0] + 2.1 * x[:, 1], atol=1e-13)
    np.testing.assert_allclose(fit.gradients() @ f, [-1.3, 2.1], atol=1e-12)
    np.testing.assert_allclose(fit.gradients().sum(axis=1), 0.0, atol=1e-12)


def test_strain_matrix_of_uniform_strain():
    pts = _cloud(10, 5)
    fit = linear_fit(np.zeros(2), 2.5, np.arange(10), coords=pts)
    u = np.column_stack([0.002 * pts[:, 0], -0.0006 * pts[:, 1] + 0.001 * pts[:, 0]])
    np.testing.assert_allclose(strain_matrix(fit) @ u.ravel(), [0.002, -0.0006, 0.001], atol=1e-14)


def test_too_few_or_collinear_nodes_give_no_fit():
    pts = np.array([[0.1, 0.0], [0.5, 0.0]])
    assert linear_fit(np.zeros(2), 1.0, np.arange(2), coords=pts) is None
    line = np.column_stack([np.linspace(-0.5, 0.5, 6), np.zeros(6)])
    assert linear_fit(np.zeros(2), 1.0, np.arange(6), coords=line) is None
    outside = np.array([[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [0.1, 0.1]])
    assert linear_fit(np.zeros(2), 1.0, np.arange(4), coords=outside) is None  # one node weighs
