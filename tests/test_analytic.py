"""Exact solutions checked against elasticity itself, not against their own code.

Strains by finite differences, Hooke's law, equilibrium and the end-load resultant.
"""

import numpy as np
import pytest

from geofrac.analytic import make_exact
from geofrac.materials import d_matrix

E, NU = 100.0, 0.2
H = 1e-5


def _strain_fd(sol, x, y):
    def u(px, py):
        return np.array(sol.displacement(px, py), dtype=float)

    dudx = (u(x + H, y) - u(x - H, y)) / (2 * H)
    dudy = (u(x, y + H) - u(x, y - H)) / (2 * H)
    return np.array([dudx[0], dudy[1], dudy[0] + dudx[1]])


@pytest.mark.parametrize("plane", ["stress", "strain"])
def test_timoshenko_satisfies_hooke_and_equilibrium(plane):
    sol = make_exact(
        "timoshenko_cantilever", {"P": 1.0, "L": 10.0, "D": 1.0}, E=E, nu=NU, plane=plane
    )
    D = d_matrix(E, NU, 2, plane=plane)
    rng = np.random.default_rng(0)
    for x, y in zip(rng.uniform(0, 10, 20), rng.uniform(-0.5, 0.5, 20), strict=True):
        s = sol.stress(x, y)
        voigt = np.array([s[0][0], s[1][1], s[0][1]], dtype=float)
        np.testing.assert_allclose(D @ _strain_fd(sol, x, y), voigt, rtol=1e-6, atol=1e-6)

        def sig(px, py):
            t = sol.stress(px, py)
            return np.array([[t[0][0], t[0][1]], [t[1][0], t[1][1]]], dtype=float)

        div = (sig(x + H, y) - sig(x - H, y))[:, 0] / (2 * H) + (sig(x, y + H) - sig(x, y - H))[
            :, 1
        ] / (2 * H)
        np.testing.assert_allclose(div, 0.0, atol=1e-5)


def test_timoshenko_boundary_conditions_and_tip():
    sol = make_exact(
        "timoshenko_cantilever", {"P": 2.0, "L": 8.0, "D": 2.0}, E=1000.0, nu=0.2, plane="stress"
    )
    y = np.linspace(-1.0, 1.0, 2001)
    # free top and bottom faces: σy = τxy = 0 at y = ±D/2
    for yy in (-1.0, 1.0):
        s = sol.stress(3.0, yy)
        assert abs(s[0][1]) < 1e-12 and abs(s[1][1]) < 1e-12
    # end shear resultant equals P (trapezoidal rule on a fine grid)
    ty = np.array([sol.stress(8.0, yy)[0][1] for yy in y])
    assert np.trapezoid(ty, y) == pytest.approx(2.0, rel=1e-6)
    # no resultant axial force or moment at the loaded end
    sx = np.array([sol.stress(8.0, yy)[0][0] for yy in y])
    assert abs(np.trapezoid(sx, y)) < 1e-12
    # tip deflection of beam theory plus the shear term of Timoshenko & Goodier
    inertia = 2.0**3 / 12
    expected = 2.0 * 8.0**3 / (3 * 1000.0 * inertia) + (4 + 5 * 0.2) * 2.0 * 2.0**2 * 8.0 / (
        24 * 1000.0 * inertia
    )
    assert sol.tip_deflection() == pytest.approx(expected, rel=1e-14)


def test_uniform_strain_stress_is_hooke():
    sol = make_exact(
        "uniform_strain", {"exx": 0.002, "eyy": -0.0006, "gxy": 0.001}, E=E, nu=NU, plane="stress"
    )
    s = sol.stress(np.array([1.0, 2.0]), np.array([0.0, 3.0]))
    voigt = np.array([s[0][0], s[1][1], s[0][1]])
    expected = d_matrix(E, NU, 2, plane="stress") @ np.array([0.002, -0.0006, 0.001])
    np.testing.assert_allclose(voigt, np.repeat(expected[:, None], 2, axis=1), rtol=1e-14)
    np.testing.assert_allclose(_strain_fd(sol, 1.3, 0.4), [0.002, -0.0006, 0.001], atol=1e-10)
