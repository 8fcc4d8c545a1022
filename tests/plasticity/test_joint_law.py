"""The Coulomb joint law of the interface springs (geofrac/plasticity/interface.py).

Closed forms written here from kₙ, kₛ, c, μ: a joint held under a normal pressure p and
sheared sticks with τ = kₛ δₛ until |τ| = c + μ p, then slips at that shear with the slip
δₛ − τ/kₛ; an open joint carries no normal traction and at most c in shear (nothing
when cohesionless); the tangent is the derivative of the return (central differences);
strength reduction divides c and μ.
"""

from __future__ import annotations

import numpy as np
import pytest

from geofrac.plasticity.interface import (
    CLOSED,
    OPEN,
    SLIP,
    JointStrength,
    coulomb_joint,
)

KN, KS, C, MU = 2.0e4, 1.5e4, 3.0, 0.6


def test_shear_under_pressure_sticks_then_slips() -> None:
    """P fixed, δₛ from −1e-3 to 1e-3: τ = kₛ δₛ below c + μ p, ±(c + μ p) above."""
    p = 5.0
    ds = np.linspace(-1e-3, 1e-3, 41)
    dn = np.full_like(ds, -p / KN)
    r = coulomb_joint(dn, ds, np.zeros_like(ds), kn=KN, ks=KS, cohesion=C, friction=MU)
    limit = C + MU * p  # 6.0: reached at |δₛ| = 4e-4
    expected = np.clip(KS * ds, -limit, limit)
    assert np.allclose(r.normal, -p, rtol=0, atol=1e-12)
    assert np.allclose(r.shear, expected, rtol=0, atol=1e-12)
    slipping = np.abs(KS * ds) > limit
    assert np.array_equal(r.state == SLIP, slipping)
    assert np.all(r.state[~slipping] == CLOSED)
    assert np.allclose(r.slip, np.where(slipping, ds - expected / KS, 0.0), rtol=0, atol=1e-15)


def test_slip_history_shifts_the_elastic_branch() -> None:
    """A converged slip s: the trial is kₛ (δₛ − s), unloading from it is elastic."""
    s = np.array([2e-4])
    r = coulomb_joint(np.array([-1e-4]), np.array([3e-4]), s, kn=KN, ks=KS, cohesion=C, friction=MU)
    assert r.shear[0] == pytest.approx(KS * 1e-4, rel=1e-14)
    assert r.state[0] == CLOSED and r.slip[0] == s[0]


def test_open_joint_has_no_tensile_strength() -> None:
    """δₙ > 0: σₙ = 0; shear up to c (the cut-off corner); cohesionless: no traction."""
    dn = np.array([1e-4, 1e-4, 1e-4])
    ds = np.array([1e-4, 1e-3, -1e-3])
    r = coulomb_joint(dn, ds, np.zeros(3), kn=KN, ks=KS, cohesion=C, friction=MU)
    assert np.all(r.normal == 0.0)
    assert r.shear == pytest.approx([KS * 1e-4, C, -C], rel=1e-14)
    assert list(r.state) == [OPEN, SLIP, SLIP]
    r0 = coulomb_joint(dn, ds, np.zeros(3), kn=KN, ks=KS, cohesion=0.0, friction=MU)
    assert np.all(r0.normal == 0.0) and np.all(r0.shear == 0.0)


def test_traction_is_continuous_at_the_opening() -> None:
    """δₙ = ∓ε gives tractions within kₙ ε (μ kₙ ε in shear) of each other."""
    eps = 1e-10
    ds = np.array([1e-3, 1e-3])
    r = coulomb_joint(np.array([-eps, eps]), ds, np.zeros(2), kn=KN, ks=KS, cohesion=C, friction=MU)
    assert abs(r.normal[0] - r.normal[1]) <= KN * eps * 1.0001
    assert abs(r.shear[0] - r.shear[1]) <= MU * KN * eps * 1.0001


@pytest.mark.parametrize(
    ("dn", "ds", "state"),
    [
        (-2e-4, 1e-4, CLOSED),
        (-2e-4, 6e-4, SLIP),
        (-2e-4, -6e-4, SLIP),
        (1e-4, 1e-4, OPEN),
        (1e-4, 5e-4, SLIP),
    ],
)
def test_tangent_is_the_derivative(dn: float, ds: float, state: int) -> None:
    """d(σₙ, τ)/d(δₙ, δₛ) equals a central difference (relative 1e-7 of kₙ)."""
    slip = np.array([1e-5])

    def traction(x: np.ndarray) -> np.ndarray:
        r = coulomb_joint(x[:1], x[1:], slip, kn=KN, ks=KS, cohesion=C, friction=MU)
        return np.array([r.normal[0], r.shear[0]])

    x = np.array([dn, ds])
    r = coulomb_joint(x[:1], x[1:], slip, kn=KN, ks=KS, cohesion=C, friction=MU)
    assert r.state[0] == state
    h = 1e-9
    fd = np.column_stack([(traction(x + h * e) - traction(x - h * e)) / (2 * h) for e in np.eye(2)])
    assert np.allclose(r.tangent[0], fd, rtol=0, atol=1e-7 * KN)


def test_strength_reduction_divides_c_and_mu() -> None:
    """c/F and μ/F; negative or non-finite strengths and F <= 0 refused."""
    s = JointStrength(10.0, 0.7).reduced(1.6)
    assert s.cohesion == pytest.approx(10.0 / 1.6, rel=1e-15)
    assert s.friction == pytest.approx(0.7 / 1.6, rel=1e-15)
    with pytest.raises(ValueError, match="> 0"):
        JointStrength(1.0, 0.5).reduced(0.0)
    with pytest.raises(ValueError, match="cohesion"):
        JointStrength(-1.0, 0.5)
    with pytest.raises(ValueError, match="friction"):
        JointStrength(1.0, float("nan"))
