"""Drucker-Prager return mapping and the Jaumann rate (seed 4.39-4.43, D.30-D.31)."""

import numpy as np
import pytest

from geofrac.mpm.plasticity import DruckerPrager, jaumann, yield_function


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
    # v = ω × x: ∂v_x/∂y = −w Δt, ∂v_y/∂x = w Δt per step; the seed's Δω (D.31)
    dw = np.array([[[0.0, w, 0.0], [-w, 0.0, 0.0], [0.0, 0.0, 0.0]]])
    for _ in range(steps):
        s = jaumann(s, dw)
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
    p = lattice([2.0, 1.0], [16, 16], h, 2000.0)
    g = grid([0.0, 0.0], cell, [48, 16])
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[g.nodes()[:, 1] <= 1.0] = True
    dt = time_step(0.2, cell, material, 2000.0, 2)
    s = StepSettings("musl", "cpgimp", dt, np.array([0.0, -9.81]), fixed)
    top = p.x[:, 1].max()
    for _ in range(round(t_end / dt)):
        step(g, p, material, s)
    return p, top - p.x[:, 1].max()


def test_cohesionless_block_slumps_and_stays_on_the_cone():
    """A cohesionless block (φ = 20°) cannot stand with vertical faces.

    It slumps: the top drops more than ten times as far as the elastic block settles,
    and every stress ends on or inside the cone. A very strong Drucker-Prager block
    settles like the elastic one (the rest is the Jaumann rotation of a vibrating block).
    """
    from geofrac.mpm.schemes import Elastic

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

    p = particles(np.array([[1.0]]), np.ones(1), 1.0, np.full((1, 1), 0.25))
    g = grid([0.0], 1.0, [4])
    s = StepSettings("musl", "mpm", 1e-3, np.zeros(1), np.zeros((g.num_nodes, 1), bool))
    with pytest.raises(ValueError, match="2D or 3D"):
        step(g, p, DruckerPrager(1.0, 0.3, 20.0), s)
