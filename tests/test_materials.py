import numpy as np
import pytest

from geofrac.materials import d_matrix, lame


def test_plane_stress_d_matrix_is_the_textbook_one():
    E, nu = 97.0, 0.25
    expected = E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    np.testing.assert_allclose(d_matrix(E, nu, 2, plane="stress"), expected, rtol=1e-14)


def test_plane_strain_d_matrix_is_the_textbook_one():
    E, nu = 38000.0, 0.2
    c = E / ((1 + nu) * (1 - 2 * nu))
    expected = c * np.array([[1 - nu, nu, 0], [nu, 1 - nu, 0], [0, 0, (1 - 2 * nu) / 2]])
    np.testing.assert_allclose(d_matrix(E, nu, 2, plane="strain"), expected, rtol=1e-14)


def test_3d_d_matrix_inverts_to_the_compliance():
    E, nu = 1.34e6, 0.45
    D = d_matrix(E, nu, 3)
    C = np.linalg.inv(D)
    assert C[0, 0] == pytest.approx(1 / E)
    assert C[0, 1] == pytest.approx(-nu / E)
    assert C[5, 5] == pytest.approx(2 * (1 + nu) / E)


def test_near_incompressible_constants_stay_finite():
    lam, mu = lame(1.0, 0.4999999, 2, plane="strain")
    assert np.isfinite(lam) and lam > 1e5 * mu
    lam_s, _ = lame(1.0, 0.4999999, 2, plane="stress")
    assert lam_s == pytest.approx(0.4999999 / (1 - 0.4999999**2))
