"""Mohr-Coulomb with a tension cut-off: strain paths to the analytic points, every return.

The reference points are closed forms written here from c, φ, ψ, T, E and ν: Hooke's
law, the flow vector of the active plane and the yield condition, solved for the
multiplier (which enters linearly along these fixed-axis paths).
"""

import numpy as np
import pytest

from geofrac.plasticity import MohrCoulomb
from geofrac.plasticity.elasticity import energy_density
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
from tests.plasticity.drivers import hooke, on_surface, strain_path, symmetric

E, NU, C, PHI = 1000.0, 0.2, 1.0, 20.0
LAM, MU = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))


def mc(stress: np.ndarray, phi: float = PHI, c: float = C, T: float | None = None) -> np.ndarray:
    """The test's own yield function: max(main plane, σ₁ − T), shape=(n, 3, 3) → (n,)."""
    p = np.linalg.eigvalsh(stress)[:, ::-1]
    s, co = np.sin(np.radians(phi)), np.cos(np.radians(phi))
    f = (p[:, 0] - p[:, 2]) + (p[:, 0] + p[:, 2]) * s - 2 * c * co
    return f if T is None else np.maximum(f, p[:, 0] - T)


@pytest.mark.parametrize("psi", [0.0, 10.0, 20.0])
def test_uniaxial_strain_compression_follows_the_compression_edge(psi):
    """Oedometer: yield at ε_y = −c cos φ/(G − (λ + G) sin φ), then on the edge σ_y = σ_z."""
    law = MohrCoulomb(E, NU, PHI, C, psi)
    sf, sp = np.sin(np.radians(PHI)), np.sin(np.radians(psi))
    ey = -C * np.cos(np.radians(PHI)) / (MU - (LAM + MU) * sf)
    steps = np.linspace(0.0, 6.03 * ey, 61)[1:]  # no step exactly at ε_y
    strains = np.zeros((len(steps), 3, 3))
    strains[:, 0, 0] = steps
    stress, kinds = strain_path(law, strains)
    elastic = steps / ey < 1
    np.testing.assert_allclose(stress[elastic], hooke(strains[elastic], E, NU), rtol=1e-12)
    assert np.all(kinds[elastic] == ELASTIC)
    assert np.all(kinds[~elastic] == EDGE_COMPRESSION)
    # plastic flow of the edge: (1 + sin ψ) on each lateral axis, −2(1 − sin ψ) axially
    flow = np.diag([-2 * (1 - sp), 1 + sp, 1 + sp])
    for eps, got in zip(strains[~elastic], stress[~elastic], strict=True):
        want = on_surface(eps, flow, mc, E=E, nu=NU)
        np.testing.assert_allclose(got, want, atol=1e-10 * C)
    np.testing.assert_allclose(mc(stress[~elastic]), 0.0, atol=1e-10 * C)


@pytest.mark.parametrize("psi", [0.0, 15.0])
def test_pure_shear_lands_at_the_analytic_point(psi):
    """ψ = 0: τ = c cos φ and no pressure; ψ > 0: dilatancy builds pressure (closed form)."""
    law = MohrCoulomb(E, NU, PHI, C, psi)
    gam = np.linspace(0.0, 8 * C / MU, 41)[1:]
    strains = np.zeros((len(gam), 3, 3))
    strains[:, 0, 1] = strains[:, 1, 0] = gam / 2
    stress, kinds = strain_path(law, strains)
    yielded = kinds != ELASTIC
    assert np.all(kinds[yielded] == SMOOTH) and yielded.sum() > 30
    if psi == 0:
        np.testing.assert_allclose(stress[yielded, 0, 1], C * np.cos(np.radians(PHI)), rtol=1e-12)
        np.testing.assert_allclose(np.trace(stress[yielded], axis1=1, axis2=2), 0.0, atol=1e-12)
    sp = np.sin(np.radians(psi))
    e1, e3 = np.array([1.0, 1.0, 0.0]) / np.sqrt(2), np.array([1.0, -1.0, 0.0]) / np.sqrt(2)
    flow = (1 + sp) * np.outer(e1, e1) - (1 - sp) * np.outer(e3, e3)
    for eps, got in zip(strains[yielded], stress[yielded], strict=True):
        np.testing.assert_allclose(got, on_surface(eps, flow, mc, E=E, nu=NU), atol=1e-10 * C)


def test_uniaxial_tension_stops_at_the_cut_off():
    """σ_x = T and σ_y = σ_z = λT/(λ + 2G) (Rankine flow along x) after the cut-off."""
    T = 0.2
    law = MohrCoulomb(E, NU, PHI, C, 10.0, tension=T)
    steps = np.linspace(0.0, 5 * T / (LAM + 2 * MU), 26)[1:]
    strains = np.zeros((len(steps), 3, 3))
    strains[:, 0, 0] = steps
    stress, kinds = strain_path(law, strains)
    cut = kinds != ELASTIC
    assert np.all(kinds[cut] == TENSION) and cut.sum() > 15
    want = np.diag([T, LAM * T / (LAM + 2 * MU), LAM * T / (LAM + 2 * MU)])
    assert mc(want[None])[0] < 0  # the shear planes stay inactive
    np.testing.assert_allclose(stress[cut], np.broadcast_to(want, stress[cut].shape), atol=1e-12)


def _trials(n: int, seed: int) -> np.ndarray:
    """Trial stresses spread over every region of the surface (shear, tension, apex)."""
    rng = np.random.default_rng(seed)
    return symmetric(n, 3 * C, seed) + rng.normal(scale=2 * C, size=n)[:, None, None] * np.eye(3)


LAWS = {
    "no cut-off, psi 0": (MohrCoulomb(E, NU, PHI, C, 0.0), None),
    "no cut-off, psi 10": (MohrCoulomb(E, NU, PHI, C, 10.0), None),
    "cut-off, psi 0": (MohrCoulomb(E, NU, PHI, C, 0.0, tension=0.5), 0.5),
    "cut-off, associated": (MohrCoulomb(E, NU, PHI, C, PHI, tension=1.2), 1.2),
    "Tresca": (MohrCoulomb(E, NU, 0.0, C), None),
}
KINDS = {
    None: {ELASTIC, SMOOTH, EDGE_COMPRESSION, EDGE_EXTENSION, APEX},
    "cut": {
        ELASTIC,
        SMOOTH,
        EDGE_COMPRESSION,
        EDGE_EXTENSION,
        TENSION,
        TENSION_EDGE,
        TENSION_SHEAR,
        TENSION_CORNER,
        TENSION_APEX,
    },
}


@pytest.mark.parametrize("name", list(LAWS))
def test_every_return_lands_on_the_surface(name):
    """f(σ) = 0 after every plastic return, edges, apex, corners and cut-off (1e-10 of c)."""
    law, T = LAWS[name]
    trial = _trials(6000, seed=3)
    ret = law.return_map(trial)
    phi = law.friction_angle
    kinds = set(np.unique(ret.kind).tolist())
    want = KINDS["cut" if T is not None else None] - ({APEX} if phi == 0 else set())
    assert kinds == want, {NAMES[k] for k in kinds ^ want}
    plastic = ret.kind != ELASTIC
    f = mc(ret.stress, phi=phi, T=T)
    np.testing.assert_allclose(f[plastic], 0.0, atol=1e-10 * C)
    assert np.all(mc(trial, phi=phi, T=T)[plastic] > 0)
    assert np.all(mc(trial, phi=phi, T=T)[~plastic] <= 0)
    np.testing.assert_array_equal(ret.stress[~plastic], trial[~plastic])
    # Δεᵖ = C⁻¹:(σ* − σ): Hooke of the plastic strain gives back the stress drop
    np.testing.assert_allclose(hooke(ret.plastic_strain, E, NU), trial - ret.stress, atol=1e-12)
    assert np.all(ret.multipliers >= -1e-15)
    # away from the fixed points the plastic strain is the flow rule: Σⱼ Δγⱼ nⱼ in the
    # trial's principal frame (the flow vectors written here, sorted order)
    sp = np.sin(np.radians(law.dilatancy_angle))
    flows = np.array(
        [[1 + sp, 0, -(1 - sp)], [1 + sp, -(1 - sp), 0], [0, 1 + sp, -(1 - sp)], *np.eye(3)]
    )
    _, V = np.linalg.eigh(trial)
    V = V[:, :, ::-1]
    flowing = plastic & ~np.isin(ret.kind, [APEX, TENSION_CORNER, TENSION_APEX])
    principal = ret.multipliers[flowing] @ flows
    want = np.einsum("nik,nk,njk->nij", V[flowing], principal, V[flowing])
    np.testing.assert_allclose(ret.plastic_strain[flowing], want, atol=1e-14 * C)


@pytest.mark.parametrize("name", list(LAWS))
def test_the_return_never_raises_the_stored_energy(name):
    law, _ = LAWS[name]
    K, G = law.moduli()
    trial = _trials(6000, seed=4)
    ret = law.return_map(trial)
    before, after = energy_density(trial, K, G), energy_density(ret.stress, K, G)
    assert np.all(after <= before * (1 + 1e-12) + 1e-15 * C**2 / E)
    assert np.all(after[ret.kind != ELASTIC] < before[ret.kind != ELASTIC])


def test_no_dilatancy_keeps_the_plastic_volume_on_planes_and_edges():
    """ψ = 0: tr Δεᵖ = 0 on the main plane and the edges (the apex and cut-off change volume)."""
    ret = MohrCoulomb(E, NU, PHI, C, 0.0).return_map(_trials(4000, seed=5))
    shear = np.isin(ret.kind, [SMOOTH, EDGE_COMPRESSION, EDGE_EXTENSION])
    assert shear.sum() > 1000
    vol = np.trace(ret.plastic_strain[shear], axis1=1, axis2=2)
    scale = np.abs(ret.plastic_strain[shear]).max()
    np.testing.assert_allclose(vol, 0.0, atol=1e-12 * scale)
    dil = MohrCoulomb(E, NU, PHI, C, 10.0).return_map(_trials(4000, seed=5))
    assert np.all(np.trace(dil.plastic_strain[dil.kind == SMOOTH], axis1=1, axis2=2) > 0)


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError, match="tension"):
        MohrCoulomb(E, NU, 30.0, 1.0, tension=2.0)  # c cot φ = 1.73
    with pytest.raises(ValueError, match="dilatancy"):
        MohrCoulomb(E, NU, 10.0, 1.0, 20.0)
    with pytest.raises(ValueError, match="cohesion"):
        MohrCoulomb(E, NU, 10.0, -1.0)
