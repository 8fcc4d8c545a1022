"""The face-pair operators of geofrac.fracture.contact against closed forms (pure numpy).

Two linear MLS fits on either side of an inclined edge. For a displacement that is linear
on each side, u = A x + a on the +n side and u = A x on the −n side, the jump of the fits
at any point is a, so g = a · n and s = a · t, and the faces' stress is σ = D ε(A) with
p = −n · σ n and τ = t · σ n (Cauchy's formula).
"""

from __future__ import annotations

import numpy as np
import pytest

from geofrac.fracture.contact import edge_tractions, pair_operator, shear_factors
from geofrac.materials import d_matrix
from geofrac.mls.shape import linear_fit

RNG = np.random.default_rng(29)
#: The edge's direction: 35° to the x axis; n = (−t_y, t_x).
ANGLE = np.radians(35.0)
T = np.array([np.cos(ANGLE), np.sin(ANGLE)])
N = np.array([-T[1], T[0]])
D = d_matrix(200.0, 0.3, 2, plane="strain")
#: A displacement gradient (not symmetric: the rotation must not stress the faces).
GRAD = np.array([[1e-3, -4e-4], [2.5e-3, -2e-3]])
#: The plus face's rigid shift [u] (opening and slip).
SHIFT = np.array([3e-4, -7e-4])


def _side(sign: float, first: int) -> tuple:
    """A fit on 9 random nodes on the ``sign`` side of the edge through the origin."""
    along = RNG.uniform(-1.0, 1.0, 9)
    across = sign * RNG.uniform(0.05, 1.0, 9)
    coords = along[:, None] * T + across[:, None] * N
    nodes = np.arange(first, first + 9)
    fit = linear_fit(sign * 0.3 * N, 2.5, nodes, coords=coords)
    assert fit is not None
    return fit, coords


def test_pair_operator_gives_the_jump_and_cauchy_tractions_of_linear_fields():
    plus, xp = _side(1.0, 0)
    minus, xm = _side(-1.0, 9)
    op = pair_operator(plus, minus, np.zeros(2), tangent=T, normal=N, D=D)
    u = np.zeros((18, 2))
    u[:9] = xp @ GRAD.T + SHIFT
    u[9:] = xm @ GRAD.T
    jump = op.weights @ u[op.nodes]
    assert jump @ N == pytest.approx(SHIFT @ N, rel=1e-10)
    assert jump @ T == pytest.approx(SHIFT @ T, rel=1e-10)
    eps = np.array([GRAD[0, 0], GRAD[1, 1], GRAD[0, 1] + GRAD[1, 0]])
    sx, sy, sxy = D @ eps
    sigma = np.array([[sx, sxy], [sxy, sy]])
    p, tau = op.traction @ u[op.nodes].ravel()
    assert p == pytest.approx(-N @ sigma @ N, rel=1e-10)
    assert tau == pytest.approx(T @ sigma @ N, rel=1e-10)
    sn, tau2 = edge_tractions(np.array([[sx, sy, sxy]]), T[None], N[None])
    assert (-sn[0], tau2[0]) == pytest.approx((p, tau), rel=1e-10)


def test_shear_factor_reaches_the_mohr_coulomb_envelope():
    """The factor r solves r (|τ| + σn tan φ) = c; compression raises r; no drive: inf."""
    sn = np.array([-1.0, 0.5, -10.0])
    tau = np.array([2.0, -1.0, 1.0])
    r = shear_factors(sn, tau, 3.0, friction_angle=30.0)
    t = np.tan(np.radians(30.0))
    assert r[0] == pytest.approx(3.0 / (2.0 - t))
    assert r[1] == pytest.approx(3.0 / (1.0 + 0.5 * t))
    assert r[2] == np.inf
    assert r[0] * (abs(tau[0]) + sn[0] * t) == pytest.approx(3.0)
