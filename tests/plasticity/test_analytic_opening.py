"""The closed form of the Mohr-Coulomb opening (geofrac/analytic_plastic.py) on its own."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geofrac.analytic import LameCylinder
from geofrac.analytic_plastic import MohrCoulombOpening

BASE = dict(a=1.0, p0=10.0, E=1e4, nu=0.3, cohesion=1.0, friction_angle=30.0)


def test_elastic_limit_is_lame() -> None:
    """pᵢ ≥ p_cr: no plastic zone, u_r is Lamé's ring minus the uniform state."""
    op = MohrCoulombOpening(b=20.0, pi=8.0, **BASE)
    assert op.plastic_radius == 1.0
    lame = LameCylinder(a=1.0, b=20.0, p=8.0, p_outer=10.0, E=1e4, nu=0.3)
    uniform = -(1 + 0.3) * (1 - 2 * 0.3) * 10.0 / 1e4  # u_r/r under σ = −p₀ I
    for r in (1.0, 2.0, 7.0, 20.0):
        assert op.radial_displacement(r) == pytest.approx(
            lame.radial_displacement(r) - uniform * r, rel=1e-12
        )


def test_critical_pressure_and_salencon_radius() -> None:
    """B → ∞: yield starts at p_cr = (2p₀ − σ_c)/(1 + K_p); ρ is Salençon's formula."""
    kp = 3.0  # φ = 30°
    sc = 2 * math.cos(math.pi / 6) / (1 - 0.5)
    pcr = (2 * 10.0 - sc) / (1 + kp)
    assert MohrCoulombOpening(b=math.inf, pi=pcr * 1.0001, **BASE).plastic_radius == 1.0
    assert MohrCoulombOpening(b=math.inf, pi=pcr * 0.999, **BASE).plastic_radius > 1.0
    A = 1.0 / math.tan(math.pi / 6)
    op = MohrCoulombOpening(b=math.inf, pi=1.0, **BASE)
    assert op.plastic_radius == pytest.approx((2 * (10 + A) / (4 * (1 + A))) ** 0.5, rel=1e-12)
    # the finite ring tends to it as b grows (the elastic zone's Lamé correction ~ (ρ/b)²)
    far = MohrCoulombOpening(b=1e4, pi=1.0, **BASE)
    assert far.plastic_radius == pytest.approx(op.plastic_radius, rel=1e-6)
    assert far.wall_displacement == pytest.approx(op.wall_displacement, rel=1e-6)


@pytest.mark.parametrize("psi", [0.0, 30.0])
def test_fields_solve_equilibrium_yield_and_flow(psi: float) -> None:
    """Stresses in equilibrium, at yield inside ρ, continuous at ρ; u obeys the flow rule."""
    op = MohrCoulombOpening(b=20.0, pi=1.0, dilatancy_angle=psi, **BASE)
    rho = op.plastic_radius
    r = np.linspace(1.0, 19.0, 2001)
    sr, st = op.stresses(r)
    dsr = np.gradient(sr, r)
    inside = (np.abs(r - rho) > 0.05) & (r > 1.02) & (r < 18.9)
    assert np.allclose(dsr[inside], ((st - sr) / r)[inside], atol=1e-3 * 10)
    assert np.allclose(st[r < rho], 3.0 * sr[r < rho] + op.sigma_c, atol=1e-12 * 10)
    assert op.stresses(np.array([20.0]))[0][0] == pytest.approx(10.0, rel=1e-12)
    # continuity of u at ρ and the flow rule εᵖ_r + K_ψ εᵖ_θ = 0 in the plastic zone
    h = 1e-6
    assert op.radial_displacement(rho - h) == pytest.approx(
        op.radial_displacement(rho + h), rel=1e-5
    )
    E, nu = 1e4, 0.3
    for s in (1.2, 0.5 * (1 + rho)):
        du = (op.radial_displacement(s + h) - op.radial_displacement(s - h)) / (2 * h)
        u = op.radial_displacement(s)
        (srs,), (sts,) = op.stresses(np.array([s]))
        dr, dt = -(srs - 10.0), -(sts - 10.0)  # tension-positive stress changes
        er = (1 + nu) / E * ((1 - nu) * dr - nu * dt)
        et = (1 + nu) / E * ((1 - nu) * dt - nu * dr)
        assert (du - er) + op.kpsi * (u / s - et) == pytest.approx(0.0, abs=1e-7 * abs(u))
    assert op.wall_displacement < 0.0


def test_dilatancy_increases_convergence() -> None:
    """ψ = φ converges more than ψ = 0 (more plastic volume)."""
    u0 = MohrCoulombOpening(b=20.0, pi=1.0, dilatancy_angle=0.0, **BASE).wall_displacement
    u30 = MohrCoulombOpening(b=20.0, pi=1.0, dilatancy_angle=30.0, **BASE).wall_displacement
    assert u30 < u0 < 0.0
