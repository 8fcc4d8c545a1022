"""Drucker-Prager (Edo (2016), eq. 4.39-4.43): the matches, strain paths, every return.

The reference points are closed forms written here from c, φ, ψ, E and ν (Hooke's law,
the flow direction β_ψ I + s/(2√J₂) along a fixed-axis path and f = 0).
"""

import numpy as np
import pytest

from geofrac.plasticity import DruckerPrager
from geofrac.plasticity.elasticity import energy_density
from geofrac.plasticity.returns import APEX, ELASTIC, SMOOTH
from tests.plasticity.drivers import hooke, on_surface, strain_path, symmetric

E, NU, C, PHI = 1000.0, 0.25, 1.0, 30.0
K, G = E / (3 * (1 - 2 * NU)), E / (2 * (1 + NU))


def plane_strain(angle: float, c: float = C) -> tuple[float, float]:
    """β and k of eq. 4.42-4.43."""
    t = np.tan(np.radians(angle))
    return t / np.sqrt(9 + 12 * t * t), 3 * c / np.sqrt(9 + 12 * t * t)


def dp(stress: np.ndarray, beta: float, k: float) -> np.ndarray:
    """The test's own f = β I₁ + √J₂ − k, shape=(n, 3, 3) → (n,)."""
    i1 = np.trace(stress, axis1=1, axis2=2)
    s = stress - i1[:, None, None] / 3 * np.eye(3)
    return beta * i1 + np.sqrt(0.5 * np.sum(s * s, axis=(1, 2))) - k


def test_the_matches_meet_mohr_coulomb_where_they_should():
    """The three matches of Mohr-Coulomb's c and φ.

    Plane strain: eq. 4.42-4.43; outer: the uniaxial compressive strength
    2c cos φ/(1 − sin φ); inner: the uniaxial tensile strength 2c cos φ/(1 + sin φ).
    """
    s, co = np.sin(np.radians(PHI)), np.cos(np.radians(PHI))
    law = DruckerPrager(E, NU, PHI, C)
    assert (law.beta, law.k) == pytest.approx(plane_strain(PHI), rel=1e-14)
    outer = DruckerPrager(E, NU, PHI, C, match="outer")
    inner = DruckerPrager(E, NU, PHI, C, match="inner")
    compression = np.diag([-2 * C * co / (1 - s), 0.0, 0.0])[None]
    tension = np.diag([2 * C * co / (1 + s), 0.0, 0.0])[None]
    assert dp(compression, outer.beta, outer.k)[0] == pytest.approx(0.0, abs=1e-13)
    assert dp(tension, inner.beta, inner.k)[0] == pytest.approx(0.0, abs=1e-13)


@pytest.mark.parametrize("psi", [0.0, 10.0, 30.0])
def test_uniaxial_strain_compression_lands_on_the_cone(psi):
    """Oedometer: yield at ε_y = −k/(2G/√3 − 3Kβ), then σ = Hooke(ε − γ m) on f = 0."""
    law = DruckerPrager(E, NU, 15.0, C, min(psi, 15.0))
    beta, k = plane_strain(15.0)
    beta_psi, _ = plane_strain(min(psi, 15.0))
    ey = -k / (2 * G / np.sqrt(3) - 3 * K * beta)
    steps = np.linspace(0.0, 6.03 * ey, 61)[1:]
    strains = np.zeros((len(steps), 3, 3))
    strains[:, 0, 0] = steps
    stress, kinds = strain_path(law, strains)
    elastic = steps / ey < 1
    np.testing.assert_allclose(stress[elastic], hooke(strains[elastic], E, NU), rtol=1e-12)
    assert np.all(kinds[elastic] == ELASTIC) and np.all(kinds[~elastic] == SMOOTH)
    # flow β_ψ I + s/(2√J₂); s/(2√J₂) = diag(−2, 1, 1)/(2√3) for an axially compressed σ
    flow = beta_psi * np.eye(3) + np.diag([-2.0, 1.0, 1.0]) / (2 * np.sqrt(3))
    f = lambda s: dp(s, beta, k)  # noqa: E731
    for eps, got in zip(strains[~elastic], stress[~elastic], strict=True):
        np.testing.assert_allclose(got, on_surface(eps, flow, f, E=E, nu=NU), atol=1e-10 * C)


@pytest.mark.parametrize("psi", [0.0, 20.0])
def test_pure_shear_lands_at_the_analytic_point(psi):
    """ψ = 0: σ_xy = k and no pressure; ψ > 0: Hooke(ε − γ m) on f = 0."""
    law = DruckerPrager(E, NU, PHI, C, psi)
    beta, k = plane_strain(PHI)
    beta_psi, _ = plane_strain(psi)
    gam = np.linspace(0.0, 8 * C / G, 41)[1:]
    strains = np.zeros((len(gam), 3, 3))
    strains[:, 0, 1] = strains[:, 1, 0] = gam / 2
    stress, kinds = strain_path(law, strains)
    yielded = kinds != ELASTIC
    assert np.all(kinds[yielded] == SMOOTH) and yielded.sum() > 30
    if psi == 0:
        np.testing.assert_allclose(stress[yielded, 0, 1], k, rtol=1e-12)
        np.testing.assert_allclose(np.trace(stress[yielded], axis1=1, axis2=2), 0.0, atol=1e-12)
    shear = np.zeros((3, 3))
    shear[0, 1] = shear[1, 0] = 0.5  # s/(2√J₂) for σ_xy > 0
    flow = beta_psi * np.eye(3) + shear
    f = lambda s: dp(s, beta, k)  # noqa: E731
    for eps, got in zip(strains[yielded], stress[yielded], strict=True):
        np.testing.assert_allclose(got, on_surface(eps, flow, f, E=E, nu=NU), atol=1e-10 * C)


def _trials(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return symmetric(n, 3 * C, seed) + rng.normal(scale=2 * C, size=n)[:, None, None] * np.eye(3)


@pytest.mark.parametrize("match", ["plane_strain", "outer", "inner"])
@pytest.mark.parametrize("psi", [0.0, 15.0])
def test_every_return_lands_on_the_cone_or_its_apex(match, psi):
    law = DruckerPrager(E, NU, PHI, C, psi, match=match)
    trial = _trials(4000, seed=7)
    ret = law.return_map(trial)
    assert set(np.unique(ret.kind).tolist()) == {ELASTIC, SMOOTH, APEX}
    plastic = ret.kind != ELASTIC
    f = dp(ret.stress, law.beta, law.k)
    np.testing.assert_allclose(f[plastic], 0.0, atol=1e-10 * C)
    assert np.all(dp(trial, law.beta, law.k)[plastic] > 0)
    np.testing.assert_array_equal(ret.stress[~plastic], trial[~plastic])
    apex = ret.kind == APEX
    np.testing.assert_allclose(
        ret.stress[apex],
        np.broadcast_to(law.k / (3 * law.beta) * np.eye(3), ret.stress[apex].shape),
        rtol=1e-14,
    )
    np.testing.assert_allclose(hooke(ret.plastic_strain, E, NU), trial - ret.stress, atol=1e-12)
    # energy: the return never raises the stored elastic energy
    before, after = energy_density(trial, K, G), energy_density(ret.stress, K, G)
    assert np.all(after[plastic] < before[plastic])
    np.testing.assert_array_equal(after[~plastic], before[~plastic])


def test_no_dilatancy_keeps_the_plastic_volume_on_the_cone():
    ret = DruckerPrager(E, NU, PHI, C, 0.0).return_map(_trials(4000, seed=8))
    cone = ret.kind == SMOOTH
    vol = np.trace(ret.plastic_strain[cone], axis1=1, axis2=2)
    np.testing.assert_allclose(vol, 0.0, atol=1e-12 * np.abs(ret.plastic_strain[cone]).max())
    dil = DruckerPrager(E, NU, PHI, C, 10.0).return_map(_trials(4000, seed=8))
    assert np.all(np.trace(dil.plastic_strain[dil.kind == SMOOTH], axis1=1, axis2=2) > 0)


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError, match="match"):
        DruckerPrager(E, NU, PHI, C, match="middle")
    with pytest.raises(ValueError, match="dilatancy"):
        DruckerPrager(E, NU, 10.0, C, 20.0)
