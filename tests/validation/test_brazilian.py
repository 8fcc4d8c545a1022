"""The Brazilian disc's closed form against the literature's formulas.

References written out here: Hondros (1959)'s stresses along the two diameters (as
quoted e.g. by Fairhurst (1964) and in the ISRM literature), the point-load solution of
the disc (Timoshenko and Goodier, Theory of Elasticity (1970), §41) as the strips shrink
with the load fixed, and the boundary tractions (p on the strips, free elsewhere).
"""

import math

import numpy as np
import pytest

from geofrac.validation.brazilian import (
    brazilian_centre_stress,
    brazilian_disc_stress,
    splitting_tensile_strength,
    strip_resultant,
)

R, P_STRIP, ALPHA = 25.0, 2.0, math.radians(5.0)


def hondros_loaded(rho: np.ndarray, p: float, a: float) -> tuple[np.ndarray, np.ndarray]:
    """(σ_xx, σ_yy) on the loaded diameter x = 0 at y = ρR (Hondros 1959)."""
    f = (1 - rho**2) * math.sin(2 * a) / (1 - 2 * rho**2 * math.cos(2 * a) + rho**4)
    g = np.arctan((1 + rho**2) / (1 - rho**2) * math.tan(a))
    return 2 * p / math.pi * (f - g), -2 * p / math.pi * (f + g)


def hondros_horizontal(rho: np.ndarray, p: float, a: float) -> tuple[np.ndarray, np.ndarray]:
    """(σ_xx, σ_yy) on the horizontal diameter y = 0 at x = ρR (Hondros 1959)."""
    f = (1 - rho**2) * math.sin(2 * a) / (1 + 2 * rho**2 * math.cos(2 * a) + rho**4)
    g = np.arctan((1 - rho**2) / (1 + rho**2) * math.tan(a))
    return 2 * p / math.pi * (f - g), -2 * p / math.pi * (f + g)


def point_load(x: float, y: float, P: float, t: float) -> tuple[float, float, float]:
    """Disc under two opposed point loads P at (0, ±R) (Timoshenko and Goodier, §41)."""
    r1, r2 = x**2 + (R - y) ** 2, x**2 + (R + y) ** 2
    k = 2 * P / (math.pi * t)
    sxx = -k * (x**2 * (R - y) / r1**2 + x**2 * (R + y) / r2**2 - 1 / (2 * R))
    syy = -k * ((R - y) ** 3 / r1**2 + (R + y) ** 3 / r2**2 - 1 / (2 * R))
    sxy = k * (x * (R - y) ** 2 / r1**2 - x * (R + y) ** 2 / r2**2)
    return sxx, syy, sxy


@pytest.mark.parametrize("deg", [2.0, 10.0, 30.0])
def test_diameters_are_hondros(deg):
    a = math.radians(deg / 2)
    rho = np.linspace(0.0, 0.99, 23)
    on_y = brazilian_disc_stress(0 * rho, rho * R, p=P_STRIP, radius=R, alpha=a)
    on_x = brazilian_disc_stress(rho * R, 0 * rho, p=P_STRIP, radius=R, alpha=a)
    for s, (sxx, syy) in (
        (on_y, hondros_loaded(rho, P_STRIP, a)),
        (on_x, hondros_horizontal(rho, P_STRIP, a)),
    ):
        np.testing.assert_allclose(s[:, 0], sxx, rtol=1e-10, atol=1e-13)
        np.testing.assert_allclose(s[:, 1], syy, rtol=1e-10, atol=1e-13)
        np.testing.assert_allclose(s[:, 2], 0.0, atol=1e-13)


def test_centre():
    sxx, syy = brazilian_centre_stress(P_STRIP, ALPHA)
    s = brazilian_disc_stress(np.zeros(1), np.zeros(1), p=P_STRIP, radius=R, alpha=ALPHA)[0]
    assert s == pytest.approx([sxx, syy, 0.0], abs=1e-14)
    assert sxx / P_STRIP == pytest.approx(2 / math.pi * (math.sin(2 * ALPHA) - ALPHA), rel=1e-14)
    assert sxx / P_STRIP == pytest.approx(0.054992, rel=1e-5)


@pytest.mark.parametrize("xy", [(7.0, 13.0), (-10.0, 3.0), (3.0, -20.0), (20.0, 1.0), (-4.0, 23.0)])
def test_narrow_strips_give_the_point_load_field(xy):
    a, P, t = 1e-5, 3.0, 2.0
    p = P / strip_resultant(1.0, radius=R, alpha=a, thickness=t)
    s = brazilian_disc_stress(np.array(xy[0]), np.array(xy[1]), p=p, radius=R, alpha=a)
    np.testing.assert_allclose(s, point_load(*xy, P, t), rtol=1e-6, atol=1e-9 * P / R)


def test_rim_tractions():
    """On ρ → 1: σ_rr = σ_θθ = −p on the strips, 0 on the free rim; σ_rθ = 0."""
    deg = np.array([0.0, 20.0, 60.0, 84.0, 86.0, 90.0, 94.0, 96.0, 180.0, 267.0, 276.0, 300.0])
    th = np.radians(deg)
    r = R * (1 - 1e-11)
    s = brazilian_disc_stress(r * np.cos(th), r * np.sin(th), p=P_STRIP, radius=R, alpha=ALPHA)
    c, sn = np.cos(th), np.sin(th)
    srr = s[:, 0] * c * c + s[:, 1] * sn * sn + 2 * s[:, 2] * sn * c
    stt = s[:, 0] * sn * sn + s[:, 1] * c * c - 2 * s[:, 2] * sn * c
    srt = (s[:, 1] - s[:, 0]) * sn * c + s[:, 2] * (c * c - sn * sn)
    loaded = np.abs(np.abs(deg - 180.0) - 90.0) < 5.0
    np.testing.assert_allclose(srr, np.where(loaded, -P_STRIP, 0.0), atol=1e-8)
    np.testing.assert_allclose(stt, srr, atol=1e-8)
    np.testing.assert_allclose(srt, 0.0, atol=1e-8)


def test_field_is_doubly_symmetric():
    x, y = np.array([3.0, 11.0]), np.array([17.0, 5.0])
    s = brazilian_disc_stress(x, y, p=P_STRIP, radius=R, alpha=ALPHA)
    for sx, sy in ((-1, 1), (1, -1), (-1, -1)):
        m = brazilian_disc_stress(sx * x, sy * y, p=P_STRIP, radius=R, alpha=ALPHA)
        np.testing.assert_allclose(m[:, :2], s[:, :2], rtol=1e-12)
        np.testing.assert_allclose(m[:, 2], sx * sy * s[:, 2], rtol=1e-12)


def test_splitting_strength():
    D, t, ft = 50.0, 25.0, 3.0
    P = math.pi * D * t * ft / 2  # ISRM: σ_t = 2P / (π D t)
    assert splitting_tensile_strength(P, diameter=D, thickness=t) == pytest.approx(ft, rel=1e-14)
    # with the strip: the load at which the exact centre stress reaches f_t
    p = ft / brazilian_centre_stress(1.0, ALPHA)[0]
    P = strip_resultant(p, radius=D / 2, alpha=ALPHA, thickness=t)
    assert splitting_tensile_strength(P, diameter=D, thickness=t, alpha=ALPHA) == pytest.approx(
        ft, rel=1e-12
    )
