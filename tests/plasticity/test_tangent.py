"""The consistent tangent: central differences of the return, and Newton's quadratic rate.

For each return of each law the tangent ``return_map(trial, tangent=True).tangent``
equals the central difference of the returned stress in the strain (relative 1e-6 of
the elastic stiffness); a single-point strain-driven Newton solve with mixed conditions
(strains prescribed, zero stress on the free normal components) converges with
r_{k+1} <= r_k² / s (s the stress scale), the rate a wrong tangent does not reach.
"""

import itertools

import numpy as np
import pytest

from geofrac.plasticity import DruckerPrager, MohrCoulomb
from geofrac.plasticity.elasticity import VOIGT, elastic_tangent, to_voigt
from geofrac.plasticity.returns import (
    APEX,
    EDGE_COMPRESSION,
    EDGE_EXTENSION,
    ELASTIC,
    NAMES,
    SMOOTH,
    TENSION,
    TENSION_APEX,
    TENSION_CORNER,
    TENSION_EDGE,
    TENSION_SHEAR,
)
from tests.plasticity.drivers import fd_tangent, mixed_newton, symmetric

E, NU, C = 1000.0, 0.25, 1.0

SHEAR = {ELASTIC, SMOOTH, EDGE_COMPRESSION, EDGE_EXTENSION}
CUT = SHEAR | {TENSION, TENSION_EDGE, TENSION_SHEAR, TENSION_CORNER, TENSION_APEX}
CASES = {
    "DP plane strain, psi 10": (DruckerPrager(E, NU, 30.0, C, 10.0), {ELASTIC, SMOOTH, APEX}),
    "DP outer, associated": (
        DruckerPrager(E, NU, 30.0, C, 30.0, match="outer"),
        {ELASTIC, SMOOTH, APEX},
    ),
    "MC psi 10": (MohrCoulomb(E, NU, 30.0, C, 10.0), SHEAR | {APEX}),
    "MC cut-off, psi 0": (MohrCoulomb(E, NU, 30.0, C, 0.0, tension=0.5), CUT),
    "MC cut-off, associated": (MohrCoulomb(E, NU, 30.0, C, 30.0, tension=1.0), CUT),
    "Tresca": (MohrCoulomb(E, NU, 0.0, C), SHEAR),
}


def _trials(n: int, seed: int) -> np.ndarray:
    """Shear, tension and apex trials (a tenth of them in strong hydrostatic tension)."""
    rng = np.random.default_rng(seed)
    mean = rng.normal(scale=2 * C, size=n)
    mean[: n // 10] = 5 * C
    return symmetric(n, 3 * C, seed) + mean[:, None, None] * np.eye(3)


def _separated(trial: np.ndarray, gap: float) -> np.ndarray:
    """Trials whose principal stresses are ``gap`` apart (away from coincident axes)."""
    w = np.linalg.eigvalsh(trial)
    return np.min(np.diff(w, axis=1), axis=1) > gap


@pytest.mark.parametrize("name", list(CASES))
def test_the_tangent_is_the_derivative_of_the_return_for_every_return(name):
    law, kinds = CASES[name]
    trial = _trials(3000, seed=11)
    ret = law.return_map(trial, tangent=True)
    fd, same = fd_tangent(law, trial, h=1e-6 * C / E)
    use = same & _separated(trial, 0.05 * C)
    scale = np.abs(elastic_tangent(*law.moduli())).max()
    for kind in kinds:
        pick = use & (ret.kind == kind)
        assert pick.sum() >= 3, f"{NAMES[kind]}: {pick.sum()} samples"
        err = np.abs(ret.tangent[pick] - fd[pick]).max() / scale
        assert err < 1e-6, f"{NAMES[kind]}: relative error {err:.2e}"


def test_the_difference_check_sees_a_wrong_tangent():
    """The elastic stiffness in place of the consistent tangent fails the check above."""
    law = MohrCoulomb(E, NU, 30.0, C, 10.0)
    trial = _trials(500, seed=12)
    ret = law.return_map(trial)
    fd, same = fd_tangent(law, trial, h=1e-6 * C / E)
    pick = same & (ret.kind == SMOOTH)
    C4 = elastic_tangent(*law.moduli())
    assert np.abs(fd[pick] - C4).max() / np.abs(C4).max() > 1e-2


def test_voigt_form_is_the_d_matrix_of_elasticity():
    from geofrac.materials import d_matrix

    law = DruckerPrager(E, NU, 30.0, C)
    ret = law.return_map(np.zeros((1, 3, 3)), tangent=True)
    np.testing.assert_allclose(to_voigt(ret.tangent)[0], d_matrix(E, NU, 3), rtol=1e-14)
    assert VOIGT[5] == (0, 1)


@pytest.mark.parametrize(
    "law",
    [DruckerPrager(E, NU, 30.0, C, 10.0), MohrCoulomb(E, NU, 30.0, C, 10.0, tension=0.5)],
    ids=["drucker_prager", "mohr_coulomb"],
)
def test_a_mixed_strain_driven_newton_solve_converges_quadratically(law):
    """ε_xx and ε_xy prescribed, σ_yy = σ_zz = 0: one big plastic step, principal axes turn."""
    eps = np.zeros((3, 3))
    eps[0, 0] = -5 * C / E
    eps[0, 1] = eps[1, 0] = 5 * C / E
    stress, _, history, kind = mixed_newton(law, eps, free=[(1, 1), (2, 2)], target=np.zeros(2))
    assert kind == SMOOTH and history[-1] <= 1e-12 and len(history) <= 8
    rho = np.array(history) / C
    pairs = [(a, b) for a, b in itertools.pairwise(rho) if a < 0.5 and b > 1e-13]
    assert len(pairs) >= 2, rho  # the rate is seen on at least two steps
    for a, b in pairs:
        assert b <= a * a, rho  # quadratic: r_{k+1} <= r_k² (a linear rate fails this)
    np.testing.assert_allclose(stress[1:, 1:].diagonal(), 0.0, atol=1e-12)
    assert abs(law.yield_function(stress[None])[0]) < 1e-10 * C


@pytest.mark.parametrize(
    "law",
    [
        MohrCoulomb(E, NU, 30.0, C, 10.0),
        DruckerPrager(E, NU, 30.0, C, 10.0, match="outer"),
    ],
    ids=["mohr_coulomb", "drucker_prager_outer"],
)
def test_uniaxial_compression_stops_at_the_compressive_strength(law):
    """σ_yy = σ_zz = 0: σ_xx = −2c cos φ/(1 − sin φ) once yielded (the outer cone's match)."""
    s, co = np.sin(np.radians(30.0)), np.cos(np.radians(30.0))
    eps = np.zeros((3, 3))
    eps[0, 0] = -10 * C / E
    stress, _, history, kind = mixed_newton(law, eps, free=[(1, 1), (2, 2)], target=np.zeros(2))
    assert kind != ELASTIC and history[-1] <= 1e-12
    np.testing.assert_allclose(stress[0, 0], -2 * C * co / (1 - s), rtol=1e-12)


def test_a_wrong_tangent_loses_the_rate():
    """Newton with the elastic stiffness (a modified Newton) converges linearly at best."""
    law = DruckerPrager(E, NU, 30.0, C, 10.0)
    eps = np.zeros((3, 3))
    eps[0, 0] = -5 * C / E
    eps[0, 1] = eps[1, 0] = 5 * C / E
    _, _, history, _ = mixed_newton(
        law, eps, free=[(1, 1), (2, 2)], target=np.zeros(2), elastic_jacobian=True
    )
    rho = np.array(history) / C
    assert any(b > a * a for a, b in itertools.pairwise(rho) if a < 0.5 and b > 1e-13)
