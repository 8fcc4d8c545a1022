"""The 3D Coulomb joint law (geofrac/plasticity/interface.py, coulomb_joint_3d).

Closed forms written here from kₙ, kₛ, c, μ: under a normal pressure p a joint sheared in
any direction of its plane sticks with τ = kₛ δₛ until |τ| = c + μ p, then slips at that
shear in the trial's direction; an open joint carries no normal traction and at most c in
shear; the law does not depend on the tangent frame (rotating δₛ and s rotates τ and s);
the tangent is the derivative of the return (central differences).
"""

from __future__ import annotations

import numpy as np
import pytest

from geofrac.plasticity.interface import CLOSED, OPEN, SLIP, coulomb_joint_3d

KN, KS, C, MU = 2.0e4, 1.5e4, 3.0, 0.6


def _rotation(angle: float) -> np.ndarray:
    return np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


@pytest.mark.parametrize("direction", [0.0, 0.7, 2.1, -2.9])
def test_shear_in_any_direction_sticks_then_slips_at_c_plus_mu_p(direction: float) -> None:
    """|τ| = min(kₛ |δₛ|, c + μ p) along δₛ; the slip is δₛ − τ/kₛ, along δₛ too."""
    p = 5.0
    size = np.linspace(0.0, 1e-3, 37)  # no size at the slip onset 4e-4 itself
    e = np.array([np.cos(direction), np.sin(direction)])
    ds = size[:, None] * e
    dn = np.full(len(size), -p / KN)
    r = coulomb_joint_3d(dn, ds, np.zeros_like(ds), kn=KN, ks=KS, cohesion=C, friction=MU)
    limit = C + MU * p
    expected = np.minimum(KS * size, limit)[:, None] * e
    assert np.allclose(r.normal, -p, rtol=0, atol=1e-12)
    assert np.allclose(r.shear, expected, rtol=0, atol=1e-12)
    slipping = KS * size > limit
    assert np.array_equal(r.state == SLIP, slipping)
    assert np.all(r.state[~slipping] == CLOSED)
    assert np.allclose(r.slip, np.where(slipping[:, None], ds - expected / KS, 0.0), atol=1e-15)


def test_the_law_does_not_depend_on_the_tangent_frame() -> None:
    """Rotating δₛ and the slip by an angle rotates τ and the new slip by it."""
    rng = np.random.default_rng(7)
    dn = rng.uniform(-4e-4, 1e-4, 50)
    ds = rng.uniform(-1e-3, 1e-3, (50, 2))
    slip = rng.uniform(-2e-4, 2e-4, (50, 2))
    dn[:5], ds[:5], slip[:5] = 1e-4, 1e-5, 0.0  # open and sticking (|τ| < c)
    Q = _rotation(0.83)
    a = coulomb_joint_3d(dn, ds, slip, kn=KN, ks=KS, cohesion=C, friction=MU)
    b = coulomb_joint_3d(dn, ds @ Q.T, slip @ Q.T, kn=KN, ks=KS, cohesion=C, friction=MU)
    assert np.array_equal(a.state, b.state)
    assert np.allclose(b.shear, a.shear @ Q.T, rtol=0, atol=1e-10)
    assert np.allclose(b.slip, a.slip @ Q.T, rtol=0, atol=1e-15)
    assert len(set(a.state.tolist())) == 3  # closed, slipping and open pairs were all tried


def test_open_joint_has_no_tensile_strength() -> None:
    """δₙ > 0: σₙ = 0; shear up to c; cohesionless: no traction at all."""
    dn = np.full(3, 1e-4)
    ds = np.array([[1e-4, 0.0], [6e-4, 8e-4], [0.0, -1e-3]])
    r = coulomb_joint_3d(dn, ds, np.zeros((3, 2)), kn=KN, ks=KS, cohesion=C, friction=MU)
    assert np.all(r.normal == 0.0)
    assert np.allclose(r.shear, [[KS * 1e-4, 0.0], [0.6 * C, 0.8 * C], [0.0, -C]], atol=1e-12)
    assert list(r.state) == [OPEN, SLIP, SLIP]
    r0 = coulomb_joint_3d(dn, ds, np.zeros((3, 2)), kn=KN, ks=KS, cohesion=0.0, friction=MU)
    assert np.all(r0.normal == 0.0) and np.all(r0.shear == 0.0)
    assert list(r0.state) == [OPEN, OPEN, OPEN]  # nothing to slip against
    assert np.allclose(r0.slip, ds, rtol=0, atol=1e-18)  # the slip follows the sliding


@pytest.mark.parametrize(
    ("dn", "ds", "state"),
    [
        (-2e-4, (1e-4, -5e-5), CLOSED),
        (-2e-4, (6e-4, 2e-4), SLIP),
        (-2e-4, (-3e-4, -5e-4), SLIP),
        (1e-4, (1e-4, 0.0), OPEN),
        (1e-4, (5e-4, -1e-4), SLIP),
    ],
)
def test_tangent_is_the_derivative(dn: float, ds: tuple[float, float], state: int) -> None:
    """d(σₙ, τ₁, τ₂)/d(δₙ, δₛ₁, δₛ₂) equals a central difference (1e-7 of kₙ)."""
    slip = np.array([[1e-5, -2e-5]])

    def traction(x: np.ndarray) -> np.ndarray:
        r = coulomb_joint_3d(x[:1], x[None, 1:], slip, kn=KN, ks=KS, cohesion=C, friction=MU)
        return np.array([r.normal[0], *r.shear[0]])

    x = np.array([dn, *ds])
    r = coulomb_joint_3d(x[:1], x[None, 1:], slip, kn=KN, ks=KS, cohesion=C, friction=MU)
    assert r.state[0] == state
    h = 1e-9
    fd = np.column_stack([(traction(x + h * e) - traction(x - h * e)) / (2 * h) for e in np.eye(3)])
    assert np.allclose(r.tangent[0], fd, rtol=0, atol=1e-7 * KN)
