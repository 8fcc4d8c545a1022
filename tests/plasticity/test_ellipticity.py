"""Loss of ellipticity (the acoustic tensor) and Davis's associated equivalent.

References written here: the elastic acoustic determinant μ (λ + 2μ) for every direction,
and Davis's (1968) factor β = cos φ cos ψ / (1 − sin φ sin ψ) evaluated by hand
(φ = 30°, ψ = 0: β = √3/2, tan φ* = 1/2).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from geofrac.plasticity import DruckerPrager, MohrCoulomb
from geofrac.plasticity.davis import Davis, davis_factor
from geofrac.plasticity.ellipticity import acoustic_determinant, directions, lost_ellipticity
from geofrac.plasticity.strength_reduction import reduce_strength
from tests.plasticity.drivers import symmetric

E, NU = 100.0, 0.3
MU = E / (2 * (1 + NU))
LAM = E * NU / ((1 + NU) * (1 - 2 * NU))


def _plastic_trials(law, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Trial stresses about a confining pressure 2 pushed past the surface, and their returns."""
    trial = -2.0 * np.eye(3) + symmetric(n, 1.5, seed=7)
    trial[:, 2, :2] = trial[:, :2, 2] = 0.0  # plane strain: z a principal direction
    ret = law.return_map(trial, tangent=True)
    return ret.tangent, ret.kind


@pytest.mark.parametrize("dim", [2, 3])
def test_elastic_acoustic_determinant_is_mu_lambda_plus_two_mu(dim: int) -> None:
    law = MohrCoulomb(E, NU, 30.0, cohesion=1e9)
    ret = law.return_map(symmetric(20, 1.0, seed=3), tangent=True)
    assert not ret.kind.any()  # all elastic
    det = acoustic_determinant(ret.tangent, directions(dim, 90))
    expected = MU * (LAM + 2 * MU) if dim == 2 else MU**2 * (LAM + 2 * MU)
    np.testing.assert_allclose(det, expected, rtol=1e-12)
    assert not lost_ellipticity(ret.tangent, shear_modulus=MU, dim=dim).any()


@pytest.mark.parametrize(
    "law",
    [MohrCoulomb(E, NU, 30.0, 1.0, 30.0), DruckerPrager(E, NU, 30.0, 1.0, 30.0)],
    ids=["mohr_coulomb", "drucker_prager"],
)
@pytest.mark.parametrize("dim", [2, 3])
def test_associated_flow_stays_on_the_border(law, dim: int) -> None:
    tangent, kind = _plastic_trials(law)
    plastic = kind > 0
    assert plastic.sum() > 100
    det = acoustic_determinant(tangent[plastic], directions(dim, 720 if dim == 2 else 4000))
    assert np.all(det.min(axis=1) > -1e-6 * MU**dim)
    assert not lost_ellipticity(tangent[plastic], shear_modulus=MU, dim=dim).any()


def test_zero_dilatancy_loses_ellipticity() -> None:
    """Zero dilatancy puts plastic points past the border.

    Mohr-Coulomb, ψ = 0: at every plastic point in 3D, and in the plane where the plastic
    shear is in-plane (σ_zz intermediate); Drucker-Prager, ψ = 0: where the Lode angle
    puts Rudnicki and Rice's critical hardening modulus above 0 (not everywhere).
    """
    tangent, kind = _plastic_trials(MohrCoulomb(E, NU, 30.0, 1.0, 0.0))
    plastic = kind > 0
    assert plastic.sum() > 100
    assert lost_ellipticity(tangent[plastic], shear_modulus=MU, dim=3).all()
    trial = -2.0 * np.eye(3) + symmetric(400, 1.5, seed=7)
    trial[:, 2, :2] = trial[:, :2, 2] = 0.0
    p = np.linalg.eigvalsh(trial[:, :2, :2])
    in_plane = (trial[:, 2, 2] > p[:, 0]) & (trial[:, 2, 2] < p[:, 1]) & (kind == 1)
    assert in_plane.sum() > 30
    assert lost_ellipticity(tangent[in_plane], shear_modulus=MU, dim=2).all()
    assert not lost_ellipticity(tangent[kind == 0], shear_modulus=MU, dim=3).any()
    tangent, kind = _plastic_trials(DruckerPrager(E, NU, 30.0, 1.0, 0.0))
    lost = lost_ellipticity(tangent[kind == 1], shear_modulus=MU, dim=3)
    assert 0.25 < lost.mean() < 1.0


def test_davis_factor_by_hand() -> None:
    assert davis_factor(30.0, 30.0) == pytest.approx(1.0, abs=1e-15)
    assert davis_factor(30.0, 0.0) == pytest.approx(math.sqrt(3) / 2, rel=1e-14)
    law = Davis(E, NU, 30.0, 2.0, 0.0).equivalent()
    assert law.cohesion == pytest.approx(math.sqrt(3), rel=1e-14)
    assert law.friction_angle == pytest.approx(math.degrees(math.atan(0.5)), rel=1e-14)
    assert law.dilatancy_angle == law.friction_angle  # associated


def test_davis_with_associated_flow_is_the_material_itself() -> None:
    trial = -2.0 * np.eye(3) + symmetric(200, 1.5, seed=9)
    given = MohrCoulomb(E, NU, 25.0, 1.0, 25.0, tension=0.5)
    davis = Davis(E, NU, 25.0, 1.0, 25.0, tension=0.5)
    a, b = given.return_map(trial, tangent=True), davis.return_map(trial, tangent=True)
    np.testing.assert_allclose(b.stress, a.stress, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.tangent, a.tangent, rtol=0, atol=1e-9 * E)


def test_davis_under_strength_reduction_uses_the_factored_angles() -> None:
    """Approach B: β from atan(tan φ/F) and atan(tan ψ/F), not from the given angles."""
    F = 1.5
    reduced = reduce_strength(Davis(E, NU, 30.0, 3.0, 10.0), F)
    phi_f = math.atan(math.tan(math.radians(30.0)) / F)
    psi_f = math.atan(math.tan(math.radians(10.0)) / F)
    beta = math.cos(phi_f) * math.cos(psi_f) / (1 - math.sin(phi_f) * math.sin(psi_f))
    law = reduced.equivalent()
    assert law.cohesion == pytest.approx(beta * 3.0 / F, rel=1e-13)
    assert math.tan(math.radians(law.friction_angle)) == pytest.approx(
        beta * math.tan(phi_f), rel=1e-13
    )


def test_davis_equivalent_of_zero_dilatancy_is_elliptic() -> None:
    tangent, kind = _plastic_trials(Davis(E, NU, 30.0, 1.0, 0.0))
    assert (kind > 0).sum() > 100
    assert not lost_ellipticity(tangent[kind > 0], shear_modulus=MU, dim=3).any()


def test_davis_refuses_bad_parameters() -> None:
    with pytest.raises(ValueError, match="law"):
        Davis(E, NU, 30.0, 1.0, 0.0, law="tresca")
    with pytest.raises(ValueError, match="dilatancy"):
        Davis(E, NU, 30.0, 1.0, 35.0)
    with pytest.raises(ValueError, match="tension"):
        Davis(E, NU, 30.0, 1.0, 0.0, law="drucker_prager", tension=0.1)
