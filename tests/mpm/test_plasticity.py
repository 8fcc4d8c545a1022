"""Drucker-Prager return mapping and the Jaumann rate (Edo (2016), eqs. 4.39-4.43, D.30-D.31)."""

import numpy as np
import pytest

from geofrac.mpm.plasticity import DruckerPrager, yield_function
from geofrac.mpm.rotation import rotate_stress


def _random_stresses(n: int, scale: float, seed: int = 0) -> np.ndarray:
    a = np.random.default_rng(seed).normal(scale=scale, size=(n, 3, 3))
    return 0.5 * (a + np.swapaxes(a, 1, 2))


def test_constants_of_eqs_4_42_and_4_43():
    m = DruckerPrager(E=1.0, nu=0.3, friction_angle=30.0, cohesion=2.0)
    # tan 30° = 1/√3: √(9 + 12/3) = √13
    assert m.beta == pytest.approx((1 / np.sqrt(3)) / np.sqrt(13))
    assert m.k == pytest.approx(6 / np.sqrt(13))
    assert DruckerPrager(1.0, 0.3, 30.0).beta_psi == 0.0


def test_elastic_steps_are_left_alone():
    m = DruckerPrager(E=100.0, nu=0.25, friction_angle=25.0, cohesion=5.0)
    deps = _random_stresses(50, 1e-4)
    new, dlam = m.update(np.zeros((50, 3, 3)), deps)
    K, G = m.moduli()
    tr = np.trace(deps, axis1=1, axis2=2)[:, None, None]
    np.testing.assert_allclose(new, K * tr * np.eye(3) + 2 * G * (deps - tr / 3 * np.eye(3)))
    assert np.all(dlam == 0)


@pytest.mark.parametrize("psi", [0.0, 12.0, 25.0])
def test_return_lands_on_the_cone_and_keeps_the_deviator_direction(psi):
    m = DruckerPrager(E=100.0, nu=0.25, friction_angle=25.0, cohesion=1.0, dilatancy_angle=psi)
    start = -20.0 * np.eye(3)[None].repeat(400, axis=0)  # confined
    deps = _random_stresses(400, 0.05, seed=1)
    new, dlam = m.update(start, deps)
    trial, _ = DruckerPrager(100.0, 0.25, 89.0, 1e12).update(start, deps)  # never yields
    f = yield_function(new, m.beta, m.k)
    plastic = dlam > 0
    assert plastic.sum() > 50
    assert np.all(f <= 1e-9 * np.abs(trial).max())
    on_cone = plastic & (np.abs(np.einsum("nii->n", new) - m.k / m.beta) > 1e-9)
    np.testing.assert_allclose(f[on_cone], 0.0, atol=1e-9 * np.abs(trial).max())
    dev = lambda s: s - np.einsum("nii->n", s)[:, None, None] / 3 * np.eye(3)  # noqa: E731
    dn, dt_ = dev(new[on_cone]), dev(trial[on_cone])
    cos = np.sum(dn * dt_, axis=(1, 2)) / (
        np.linalg.norm(dn, axis=(1, 2)) * np.linalg.norm(dt_, axis=(1, 2))
    )
    np.testing.assert_allclose(cos, 1.0, atol=1e-12)
    # plastic volume change 3K β_ψ Δλ per unit: zero without dilatancy
    K, _ = m.moduli()
    di1 = np.einsum("nii->n", trial[on_cone]) - np.einsum("nii->n", new[on_cone])
    np.testing.assert_allclose(di1, 9 * K * m.beta_psi * dlam[on_cone], rtol=1e-9, atol=1e-9)


def test_cohesionless_soil_in_tension_returns_to_zero_stress():
    m = DruckerPrager(E=1.34e6, nu=0.45, friction_angle=12.0, cohesion=0.0)
    deps = np.diag([1e-3, 2e-4, 0.0])[None]  # stretched: tension
    new, dlam = m.update(np.zeros((1, 3, 3)), deps)
    assert dlam[0] > 0
    np.testing.assert_allclose(new, 0.0, atol=1e-12)


def _spin_to_quarter_turn(steps: int) -> np.ndarray:
    """σ₀ carried through a rigid rotation by 90° about z in ``steps`` Jaumann updates."""
    s = np.array([[[3.0, 1.0, 0.0], [1.0, -2.0, 0.0], [0.0, 0.0, 0.5]]])
    w = (np.pi / 2) / steps
    # v = ω × x: ∂v_x/∂y = −w Δt, ∂v_y/∂x = w Δt per step; the Δω of Edo (2016) (D.31)
    dw = np.array([[[0.0, w, 0.0], [-w, 0.0, 0.0], [0.0, 0.0, 0.0]]])
    for _ in range(steps):
        s = rotate_stress(s, dw)
    return s[0]


def test_jaumann_rotates_a_stress_with_a_rigid_spin():
    """R σ₀ Rᵀ after a quarter turn, to first order in the step; the trace is kept."""
    s0 = np.array([[3.0, 1.0, 0.0], [1.0, -2.0, 0.0], [0.0, 0.0, 0.5]])
    R = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    exact = R @ s0 @ R.T
    errors = [np.abs(_spin_to_quarter_turn(n) - exact).max() for n in (1000, 2000, 4000)]
    assert errors[-1] < 5e-3
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.05)  # first order
    assert errors[1] / errors[2] == pytest.approx(2.0, rel=0.05)
    assert np.trace(_spin_to_quarter_turn(1000)) == pytest.approx(np.trace(s0), abs=1e-12)


def test_bad_parameters_are_refused():
    with pytest.raises(ValueError, match="dilatancy"):
        DruckerPrager(1.0, 0.3, 10.0, dilatancy_angle=20.0)
    with pytest.raises(ValueError, match="cohesion"):
        DruckerPrager(1.0, 0.3, 10.0, cohesion=-1.0)


def _column(material, t_end: float = 0.6):
    """A 2 m × 2 m 2D block (cpGIMP, MUSL) dropped on a fixed floor under gravity."""
    from geofrac.mpm.grid import grid
    from geofrac.mpm.particles import lattice
    from geofrac.mpm.schemes import StepSettings, step, time_step

    cell, h = 0.25, 0.125
    p = lattice([2.0, 1.0], [16, 16], h, density=2000.0)
    g = grid([0.0, 0.0], cell, [48, 16])
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[g.nodes()[:, 1] <= 1.0] = True
    dt = time_step(0.2, cell, material, density=2000.0, dim=2)
    s = StepSettings("musl", "cpgimp", dt, np.array([0.0, -9.81]), fixed)
    top = p.x[:, 1].max()
    for _ in range(round(t_end / dt)):
        step(g, p, material, settings=s)
    return p, top - p.x[:, 1].max()


def test_cohesionless_block_slumps_and_stays_on_the_cone():
    """A cohesionless block (φ = 20°) cannot stand with vertical faces.

    It slumps: the top drops more than ten times as far as the elastic block settles,
    and every stress ends on or inside the cone. A very strong Drucker-Prager block
    settles like the elastic one (the rest is the Jaumann rotation of a vibrating block).
    """
    from geofrac.mpm.elastic import Elastic

    _, elastic_drop = _column(Elastic(1e6, 0.3))
    soil = DruckerPrager(1e6, 0.3, friction_angle=20.0, cohesion=0.0)
    p, drop = _column(soil)
    assert drop > 10 * elastic_drop
    assert np.all(p.plastic > 0)
    full = np.zeros((p.n, 3, 3))
    full[:, :2, :2] = p.stress
    full[:, 2, 2] = p.stress_zz
    assert yield_function(full, soil.beta, soil.k).max() <= 1e-9 * np.abs(full).max()
    _, strong_drop = _column(DruckerPrager(1e6, 0.3, friction_angle=20.0, cohesion=1e9))
    assert strong_drop == pytest.approx(elastic_drop, rel=0.03)


def test_plasticity_is_refused_in_1d():
    from geofrac.mpm.grid import grid
    from geofrac.mpm.particles import particles
    from geofrac.mpm.schemes import StepSettings, step

    p = particles(np.array([[1.0]]), np.ones(1), 1.0, lp0=np.full((1, 1), 0.25))
    g = grid([0.0], 1.0, [4])
    s = StepSettings("musl", "mpm", 1e-3, np.zeros(1), np.zeros((g.num_nodes, 1), bool))
    with pytest.raises(ValueError, match="2D or 3D"):
        step(g, p, DruckerPrager(1.0, 0.3, 20.0), settings=s)


# --- pure shear beyond the cone: the closed-form return (Edo (2016), eqs. 4.39-4.43) ----

PHI, COHESION, E_DP, NU_DP = 30.0, 10.0, 1000.0, 0.25


def _pure_shear_return(p_trial: float, tau_trial: float, psi: float) -> tuple[float, float]:
    """The return of σ* = p* I + τ* (e_x ⊗ e_y + e_y ⊗ e_x), by hand.

    For this σ*, I₁ = 3p* and √J₂ = |τ*| (s : s = 2τ*²), so the yield function (4.39) is
    f* = 3β p* + |τ*| − k. The flow rule's potential β_ψ I₁ + √J₂ gives the plastic
    strain increment Δλ (β_ψ I + s/(2√J₂)); elastically that is Δp = −3K β_ψ Δλ and
    Δτ = −G Δλ sign τ*. f = 0 afterwards: Δλ = f* / (9K β β_ψ + G). So

    - ψ = 0: p = p*, |τ| = k − 3β p* (the deviator scales radially to the cone at the
      same mean stress);
    - ψ = φ (associated): Δλ = f* / (9K β² + G), p = p* − 3K β Δλ, |τ| = |τ*| − G Δλ.

    (de Souza Neto, Perić & Owen 2008, box 8.9, with η = 3β, η̄ = 3β_ψ, ξ c = k.)
    """
    t = np.tan(np.radians(PHI))
    beta, k = t / np.sqrt(9 + 12 * t * t), 3 * COHESION / np.sqrt(9 + 12 * t * t)
    tp = np.tan(np.radians(psi))
    beta_psi = tp / np.sqrt(9 + 12 * tp * tp)
    K, G = E_DP / (3 * (1 - 2 * NU_DP)), E_DP / (2 * (1 + NU_DP))
    f = 3 * beta * p_trial + abs(tau_trial) - k
    if f <= 0:
        return p_trial, tau_trial
    dlam = f / (9 * K * beta * beta_psi + G)
    assert abs(tau_trial) - G * dlam > 0  # on the cone, not at the apex
    return p_trial - 3 * K * beta_psi * dlam, np.sign(tau_trial) * (abs(tau_trial) - G * dlam)


@pytest.mark.parametrize("psi", [0.0, PHI])
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_pure_shear_returns_to_the_analytic_point_on_the_cone(psi, sign):
    """A pure shear increment from a hydrostatic stress: the return of eqs. 4.39-4.43.

    Numbers (φ = 30°, c = 10, E = 1000, ν = 0.25, p₀ = −20): β = 1/√39, k = 30/√13,
    the cone at p₀ is at τ = k − 3β p₀ = 17.93; the trial τ* = 30.
    """
    m = DruckerPrager(E_DP, NU_DP, friction_angle=PHI, cohesion=COHESION, dilatancy_angle=psi)
    p0, tau_star = -20.0, 30.0 * sign
    _, G = m.moduli()
    deps = np.zeros((1, 3, 3))
    deps[0, 0, 1] = deps[0, 1, 0] = tau_star / (2 * G)
    new, dlam = m.update(p0 * np.eye(3)[None], deps)
    p, tau = _pure_shear_return(p0, tau_star, psi)
    if psi == 0:
        assert p == p0
        assert abs(tau) == pytest.approx(30 / np.sqrt(13) + 60 / np.sqrt(39), rel=1e-12)
    expected = p * np.eye(3)
    expected[0, 1] = expected[1, 0] = tau
    np.testing.assert_allclose(new[0], expected, rtol=1e-12, atol=1e-12)
    assert dlam[0] > 0
    assert yield_function(new, m.beta, m.k)[0] == pytest.approx(0.0, abs=1e-12)


def _pure_shear_step(scheme: str, psi: float):
    """One 2D plane-strain step of a prestressed block in pure shear.

    The block starts at σ = −20 I (σ_zz too) with the velocity v = γ̇ (y − y_c, x − x_c):
    a pure shear, no spin; ρ = 1e4 makes the free faces' unloading negligible in a step.

    Returns the stresses (3 × 3 with σ_zz) of the particles two cells or more inside
    the block, whose nodes see the exact linear field, and the strain increment Δε_xy.
    """
    from geofrac.mpm.grid import grid
    from geofrac.mpm.particles import lattice
    from geofrac.mpm.schemes import StepSettings, step

    centre = np.array([8.0, 8.0])
    p = lattice(centre - 4.0, [16, 16], 0.5, density=1.0e4)
    p.stress[:] = -20.0 * np.eye(2)
    p.stress_zz[:] = -20.0
    rate, dt = 37.5, 1e-3  # Δε_xy = 0.0375: τ* = 2G Δε_xy = 30 (USAVG: twice 15)
    p.v = rate * (p.x - centre)[:, ::-1]
    inner = np.all(np.abs(p.x - centre) < 2.0, axis=1)
    g = grid([0.0, 0.0], 1.0, [16, 16])
    s = StepSettings(
        scheme, "ugimp", dt, np.zeros(2), np.zeros((g.num_nodes, 2), bool), backend="numpy"
    )
    m = DruckerPrager(E_DP, NU_DP, friction_angle=PHI, cohesion=COHESION, dilatancy_angle=psi)
    step(g, p, m, settings=s)
    full = np.zeros((int(inner.sum()), 3, 3))
    full[:, :2, :2] = p.stress[inner]
    full[:, 2, 2] = p.stress_zz[inner]
    return full, rate * dt


@pytest.mark.parametrize("psi", [0.0, PHI])
@pytest.mark.parametrize("scheme", ["musl", "usf", "usavg"])
def test_pure_shear_step_lands_on_the_cone_at_the_analytic_point(scheme, psi):
    """Through one step, the interior particles land on the closed-form point, σ_zz too.

    The trial τ* = 2G Δε_xy = 30 from p₀ = −20 is beyond the cone (τ = 17.93 there).

    USAVG updates the stress twice with half the increment (elastic to τ = 15, then a
    trial of 30 returned); the closed form is applied to each half.
    """
    full, de = _pure_shear_step(scheme, psi)
    _, G = DruckerPrager(E_DP, NU_DP, PHI).moduli()
    if scheme == "usavg":
        p, tau = _pure_shear_return(-20.0, G * de, psi)
        p, tau = _pure_shear_return(p, tau + G * de, psi)
    else:
        p, tau = _pure_shear_return(-20.0, 2 * G * de, psi)
    expected = p * np.eye(3)
    expected[0, 1] = expected[1, 0] = tau
    np.testing.assert_allclose(full, np.broadcast_to(expected, full.shape), rtol=1e-9, atol=1e-9)
    assert abs(tau) < 2 * G * de  # it did yield
