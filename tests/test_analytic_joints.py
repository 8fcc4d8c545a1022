"""Joint slip around a circular opening (geofrac/analytic_joints.py) against hand derivations.

The references are derived here from elasticity and Coulomb's criterion, not taken from
the module: Kirsch's wall stresses (3 − K and 3K − 1 times σ_v at the sidewall and the
crown), equilibrium in polar coordinates by finite differences, and, for K = 1 (σ_v = p),
the wall state σ_rr = (1 − α) p, σ_θθ = (1 + α) p, σ_rθ = 0: a joint at the angle β to
the wall's tangent carries σn = p (1 − α cos 2β), |τ| = α p |sin 2β| and slips at
α* = (c/p + μ) cos φ / sin(2|β| + φ), least (c cos φ / p + sin φ) at |β| = 45° − φ/2
(Brady and Brown (2004), planes of weakness around openings; Jaeger, Cook and Zimmerman
(2007), §4.7).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from geofrac.analytic_joints import JointedOpening

P, A = 10.0, 2.0
PHI = 30.0
MU = math.tan(math.radians(PHI))


def opening(**kw) -> JointedOpening:
    args = {"sigma_v": P, "k": 1.0, "radius": A, "dip": 0.0, "cohesion": 0.0, "friction": MU}
    return JointedOpening(**(args | kw))


def beta_to_tangent(theta: np.ndarray, dip: float) -> np.ndarray:
    """Angle of the joint trace to the wall's tangent at θ, in (−90°, 90°] (degrees)."""
    b = np.mod(dip - (np.asarray(theta) + 90.0), 180.0)
    return np.where(b > 90.0, b - 180.0, b)


@pytest.mark.parametrize("k", [0.5, 1.0, 2.0])
def test_kirsch_wall_stresses_are_the_textbook_values(k):
    o = opening(k=k)
    srr, stt, srt = o.kirsch(A, [0.0, 90.0, 180.0, 270.0])
    np.testing.assert_allclose(srr, 0.0, atol=1e-12 * P)
    np.testing.assert_allclose(srt, 0.0, atol=1e-12 * P)
    np.testing.assert_allclose(stt, [(3 - k) * P, (3 * k - 1) * P] * 2, rtol=1e-12)


@pytest.mark.parametrize("k", [0.5, 2.0])
def test_kirsch_satisfies_equilibrium_and_the_far_field(k):
    """∂σrr/∂r + (1/r) ∂σrθ/∂θ + (σrr − σθθ)/r = 0 and (1/r) ∂σθθ/∂θ + ∂σrθ/∂r + 2σrθ/r = 0."""
    o = opening(k=k)
    h, hd = 1e-5, 1e-4  # steps in r and in θ (degrees)
    for r, th in [(1.3 * A, 20.0), (2.0 * A, 110.0), (5.0 * A, 250.0)]:
        srr, stt, srt = (float(v) for v in o.kirsch(r, th))
        d_r = [
            (float(p) - float(m)) / (2 * h)
            for p, m in zip(o.kirsch(r + h, th), o.kirsch(r - h, th), strict=True)
        ]
        d_t = [
            (float(p) - float(m)) / (2 * math.radians(hd))
            for p, m in zip(o.kirsch(r, th + hd), o.kirsch(r, th - hd), strict=True)
        ]
        assert d_r[0] + d_t[2] / r + (srr - stt) / r == pytest.approx(0.0, abs=1e-6 * P / A)
        assert d_t[1] / r + d_r[2] + 2 * srt / r == pytest.approx(0.0, abs=1e-6 * P / A)
    sxx, syy, sxy = o.stress(1e4 * A, [15.0, 75.0], 1.0)
    np.testing.assert_allclose(sxx, k * P, rtol=1e-6)
    np.testing.assert_allclose(syy, P, rtol=1e-6)
    np.testing.assert_allclose(sxy, 0.0, atol=1e-6 * P)


def test_no_relaxation_is_the_in_situ_state_everywhere():
    o = opening(k=0.4, dip=35.0)
    sxx, syy, sxy = o.stress([A, 1.5 * A, 3 * A], [10.0, 100.0, 200.0], 0.0)
    np.testing.assert_allclose(sxx, 0.4 * P, rtol=1e-14)
    np.testing.assert_allclose(syy, P, rtol=1e-14)
    np.testing.assert_allclose(sxy, 0.0, atol=1e-14 * P)
    sn, tau = o.tractions(A, 10.0, 0.0)
    d = math.radians(35.0)  # uniform field on the joint: the stress transformation
    assert float(sn) == pytest.approx(0.4 * P * math.sin(d) ** 2 + P * math.cos(d) ** 2)
    assert float(tau) == pytest.approx((P - 0.4 * P) * math.sin(d) * math.cos(d))


@pytest.mark.parametrize("dip", [0.0, 30.0, 72.0])
@pytest.mark.parametrize("c", [0.0, 1.0])
def test_hydrostatic_wall_slip_fraction_is_the_hand_formula(dip, c):
    o = opening(dip=dip, cohesion=c)
    theta = np.linspace(0.0, 359.5, 720)
    beta = np.radians(beta_to_tangent(theta, dip))
    s = np.sin(2 * np.abs(beta) + math.radians(PHI))
    with np.errstate(divide="ignore"):
        hand = np.where(s > 0, (c / P + MU) * math.cos(math.radians(PHI)) / s, np.inf)
    got = o.slip_fraction(A, theta)
    edge = np.abs(hand - 1.0) < 1e-9  # slips exactly at α = 1: round-off decides
    hand[hand > 1.0] = np.inf
    assert np.count_nonzero(np.isfinite(hand[~edge])) > 100
    np.testing.assert_allclose(got[~edge], hand[~edge], rtol=1e-10)


@pytest.mark.parametrize("dip", [0.0, 30.0, 72.0])
@pytest.mark.parametrize("c", [0.0, 1.0])
def test_hydrostatic_first_slip_is_where_the_joint_makes_45_minus_half_phi(dip, c):
    fs = opening(dip=dip, cohesion=c).first_slip()
    phi = math.radians(PHI)
    assert fs.alpha == pytest.approx(c * math.cos(phi) / P + math.sin(phi), rel=1e-10)
    b = 45.0 - PHI / 2
    hand = np.sort(np.mod([dip - 90.0 - s * b + t for s in (1, -1) for t in (0, 180)], 360.0))
    assert len(fs.theta) == 4
    np.testing.assert_allclose(fs.theta, hand, atol=1e-5)


def test_full_excavation_sidewall_is_jaegers_uniaxial_plane_of_weakness():
    """α = 1 at θ = 0: σr = 0, σθ = (3 − K) p along y; a joint at β to the tangent."""
    k, dip, c = 0.5, 20.0, 1.5
    o = opening(k=k, dip=dip, cohesion=c)
    s1 = (3 - k) * P
    beta = math.radians(dip - 90.0)  # the tangent at θ = 0 is vertical
    hand = abs(s1 * math.sin(beta) * math.cos(beta)) - MU * s1 * math.sin(beta) ** 2 - c
    assert float(o.margin(A, 0.0, 1.0)) == pytest.approx(hand, rel=1e-12)


def test_in_situ_failure_slips_at_zero_and_strong_joints_never_slip():
    weak = opening(k=0.2, dip=45.0, friction=0.3)  # τ = 0.4 p > 0.3 · 0.6 p far away
    fs = weak.first_slip()
    assert fs.alpha == 0.0 and len(fs.theta) == 3600
    strong = opening(k=0.5, dip=20.0, cohesion=100.0 * P)
    fs = strong.first_slip()
    assert math.isinf(fs.alpha) and len(fs.theta) == 0


def test_anisotropic_first_slip_is_the_least_over_the_wall():
    o = opening(k=0.5, dip=30.0, cohesion=0.5, friction=0.6)
    fs = o.first_slip()
    fine = np.linspace(0.0, 360.0, 720001)
    assert fs.alpha == pytest.approx(float(o.slip_fraction(A, fine).min()), rel=1e-7)
    assert len(fs.theta) == 2  # point symmetry: θ and θ + 180°
    assert fs.theta[1] - fs.theta[0] == pytest.approx(180.0, abs=1e-5)
    np.testing.assert_allclose(o.margin(A, fs.theta, fs.alpha), 0.0, atol=1e-9 * P)


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="radius"):
        opening(radius=0.0)
    with pytest.raises(ValueError, match="cohesion"):
        opening(cohesion=-1.0)
    with pytest.raises(ValueError, match="inside the opening"):
        opening().kirsch(0.5 * A, 0.0)
