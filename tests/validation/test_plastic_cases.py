"""The plasticity chapter's closed form (geofrac/validation/cases.py, salencon_ring).

Written there independently of geofrac/analytic_plastic.py (the yield condition of the
elastic zone solved for its radial stress, the flow rule integrated by Gauss-Legendre
quadrature instead of the closed-form primitive); the two must agree.
"""

import math

import pytest

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.validation.cases import CASES, salencon_ring


@pytest.mark.parametrize("b", [10.0, 3.0, math.inf])
@pytest.mark.parametrize("psi", [0.0, 15.0, 30.0])
@pytest.mark.parametrize("pi", [0.0, 1.0, 5.0])
def test_salencon_ring_equals_the_analytic_module(b: float, psi: float, pi: float) -> None:
    """ρ and u_r(a) to 1e-12 (measured <= 3e-14) on plastic and elastic (pi = 5) cases."""
    rho, u = salencon_ring(1.0, b, p0=10.0, pi=pi, E=1e4, nu=0.3, c=1.0, phi=30.0, psi=psi)
    other = MohrCoulombOpening(
        a=1.0,
        b=b,
        p0=10.0,
        pi=pi,
        E=1e4,
        nu=0.3,
        cohesion=1.0,
        friction_angle=30.0,
        dilatancy_angle=psi,
    )
    assert rho == pytest.approx(other.plastic_radius, rel=1e-12)
    assert u == pytest.approx(other.wall_displacement, rel=1e-12)


def test_salencon_hand_values() -> None:
    """Infinite medium, φ = 30° (K_p = 3, A = √3): ρ = a [2(p0 + A)/(4 (pi + A))]^(1/2).

    pi = 5 > p_cr = (2 p0 − σ_c)/(1 + K_p) = (20 − 2√3)/4: elastic, u_r(a) = −(1 + ν)(p0 − pi) a/E.
    """
    rho, _ = salencon_ring(1.0, math.inf, p0=10.0, pi=1.0, E=1e4, nu=0.3, c=1.0, phi=30.0, psi=0.0)
    A = math.sqrt(3.0)
    assert rho == pytest.approx(math.sqrt(2 * (10 + A) / (4 * (1 + A))), rel=1e-12)
    rho, u = salencon_ring(1.0, math.inf, p0=10.0, pi=5.0, E=1e4, nu=0.3, c=1.0, phi=30.0, psi=0.0)
    assert rho == 1.0 and u == pytest.approx(-1.3 * 5.0 / 1e4, rel=1e-12)


def test_plasticity_chapter_cases() -> None:
    """The chapter's cases: the opening within 2 % (CI), the slope's FoS 1.4 within 3 % (full)."""
    by_name = {c.name: c for c in CASES if c.chapter == "Plasticity and factor of safety"}
    assert {"opening_plastic_radius", "opening_wall_displacement", "slope_fos"} <= set(by_name)
    assert by_name["opening_plastic_radius"].reference.value == pytest.approx(1.4733, rel=1e-4)
    assert by_name["opening_wall_displacement"].reference.value == pytest.approx(
        -1.8749e-3, rel=1e-4
    )
    assert by_name["opening_wall_displacement"].reference.rtol == 0.02
    slope = by_name["slope_fos"]
    assert (slope.reference.value, slope.reference.rtol, slope.quick) == (1.4, 0.03, False)


def test_planar_sliding_reference_by_hand() -> None:
    """Without cohesion tan φ / tan ψ whatever the block; c > 0 adds c A / (W sin ψ)."""
    import math

    from geofrac.validation.cases import planar_sliding_fos

    kw = {"psi_deg": 30.0, "alpha_deg": 60.0, "height": 8.0, "gamma": 26.0}
    assert planar_sliding_fos(0.0, 35.0, **kw) == pytest.approx(
        math.tan(math.radians(35.0)) / math.tan(math.radians(30.0)), rel=1e-14
    )
    weight = 0.5 * 26.0 * 64.0 * (math.sqrt(3) - 1 / math.sqrt(3))  # 960.71 kN/m
    extra = 10.0 * 16.0 / (weight * 0.5)
    assert planar_sliding_fos(10.0, 35.0, **kw) == pytest.approx(
        math.tan(math.radians(35.0)) / math.tan(math.radians(30.0)) + extra, rel=1e-14
    )
