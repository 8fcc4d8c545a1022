"""The critical factor λ under a constant plus a scaled stress (geofrac.fracture.nonprop).

Closed forms: a zero constant stress gives exactly the proportional factor f_t/σ1(σ_v);
a hydrostatic constant stress −p shifts it to (f_t + p)/σ1(σ_v); a variable stress in
compression never cracks (inf); a constant stress over the strength gives λ = 0 with
the overstress ratio. The general case (Newton's method) is checked against bisection
on the definition.
"""

import numpy as np
import pytest

from geofrac.fracture.contact import shear_factors
from geofrac.fracture.nonprop import principal_factors, shear_factors_affine, traction_factors

FT = 3.0


def sigma1(s: np.ndarray) -> np.ndarray:
    """Largest principal stress of (σ_xx, σ_yy, σ_xy), shape=(..., 3)."""
    return 0.5 * (s[..., 0] + s[..., 1]) + np.hypot(0.5 * (s[..., 0] - s[..., 1]), s[..., 2])


def mean_s1(sc, sv, w, lam):
    return np.sum(w * sigma1(sc + lam[:, None, None] * sv), axis=1)


def bisect(sc, sv, w, ft):
    """Least λ with mean σ1 = f_t by bracketing and bisection (inf if none below 1e8)."""
    lo, hi = np.zeros(len(sc)), np.ones(len(sc))
    for _ in range(60):
        low = mean_s1(sc, sv, w, hi) < ft
        hi[low] *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        below = mean_s1(sc, sv, w, mid) < ft
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return np.where(hi > 1e17, np.inf, hi)


def two_cells(rng, k):
    sv = rng.normal(size=(k, 2, 3))
    w = np.tile([0.5, 0.5], (k, 1))
    w[::3] = [1.0, 0.0]  # boundary-like sites: one cell
    return sv, w


def test_zero_constant_stress_gives_the_proportional_factor_exactly():
    rng = np.random.default_rng(1)
    sv, w = two_cells(rng, 200)
    lam, drive, ratio = principal_factors(np.zeros_like(sv), sv, w, tensile_strength=FT)
    d_v = np.sum(w * sigma1(sv), axis=1)
    pos = d_v > 0
    np.testing.assert_array_equal(drive[pos], d_v[pos])  # bit for bit
    np.testing.assert_array_equal(lam[pos], FT / d_v[pos])
    assert np.all(np.isinf(lam[~pos])) and np.all(drive[~pos] == 0.0)
    np.testing.assert_array_equal(ratio, 0.0)


def test_hydrostatic_constant_stress_shifts_the_factor():
    rng = np.random.default_rng(2)
    sv, w = two_cells(rng, 200)
    p = 1.7
    sc = np.zeros_like(sv)
    sc[..., 0] = sc[..., 1] = -p
    lam, drive, ratio = principal_factors(sc, sv, w, tensile_strength=FT)
    d_v = np.sum(w * sigma1(sv), axis=1)
    pos = d_v > 0
    np.testing.assert_allclose(lam[pos], (FT + p) / d_v[pos], rtol=1e-14)
    np.testing.assert_allclose(drive[pos], FT / lam[pos], rtol=1e-14)
    np.testing.assert_allclose(ratio, -p / FT, rtol=1e-14)
    assert np.all(np.isinf(lam[~pos]))


def test_compressive_variable_stress_never_cracks():
    sv = np.array([[[-1.0, -2.0, 0.1], [-1.5, -0.5, 0.0]]])
    sc = np.array([[[0.5, -1.0, 0.3], [0.2, 0.1, 0.0]]])
    lam, drive, _ = principal_factors(sc, sv, np.array([[0.5, 0.5]]), tensile_strength=FT)
    assert np.isinf(lam[0]) and drive[0] == 0.0
    # a variable drive at round-off is no drive
    sv = np.array([[[1e-20, 0.0, 0.0], [1e-20, 0.0, 0.0]]])
    lam, _, _ = principal_factors(
        np.zeros_like(sv), sv, np.array([[0.5, 0.5]]), tensile_strength=FT, floor=1e-12
    )
    assert np.isinf(lam[0])


def test_over_strength_at_zero_is_flagged():
    sc = np.array([[[4.0, 0.0, 0.0], [3.0, 0.0, 1.0]], [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]])
    sv = np.ones_like(sc)
    lam, drive, ratio = principal_factors(
        sc, sv, np.array([[0.5, 0.5], [0.5, 0.5]]), tensile_strength=FT
    )
    assert lam[0] == 0.0 and np.isinf(drive[0])
    assert ratio[0] == pytest.approx((4.0 + 1.5 + np.hypot(1.5, 1.0)) / 2 / FT, rel=1e-15)
    assert ratio[0] > 1.0 and lam[1] > 0.0 and ratio[1] < 1.0


def test_general_case_is_the_least_root():
    """Random deviatoric constant stresses: λ is the least root, by bisection, to 1e-12."""
    rng = np.random.default_rng(3)
    sv, w = two_cells(rng, 500)
    sc = rng.normal(size=sv.shape)
    lam, drive, ratio = principal_factors(sc, sv, w, tensile_strength=FT)
    ok = (ratio < 1.0) & np.isfinite(lam)
    assert ok.sum() > 100
    ref = bisect(sc[ok], sv[ok], w[ok], FT)
    np.testing.assert_allclose(lam[ok], ref, rtol=1e-12)
    np.testing.assert_allclose(mean_s1(sc[ok], sv[ok], w[ok], lam[ok]), FT, rtol=1e-12)
    np.testing.assert_allclose(drive[ok], FT / lam[ok], rtol=1e-15)
    # no root: the asymptotic drive is not positive
    none = (ratio < 1.0) & ~np.isfinite(lam)
    assert np.all(np.sum(w[none] * sigma1(sv[none]), axis=1) <= 0.0)


def test_traction_is_linear():
    tc, tv = np.array([0.0, -1.0, 2.0, 3.5, 1.0]), np.array([2.0, 2.0, 0.5, 1.0, -1.0])
    lam, drive, ratio = traction_factors(tc, tv, tensile_strength=FT)
    assert lam[0] == FT / 2.0 and drive[0] == 2.0
    assert lam[1] == pytest.approx((FT + 1.0) / 2.0, rel=1e-15)
    assert lam[2] == pytest.approx((FT - 2.0) / 0.5, rel=1e-15)
    assert lam[3] == 0.0 and ratio[3] == pytest.approx(3.5 / FT)
    assert np.isinf(lam[4])


def test_shear_closed_forms():
    rng = np.random.default_rng(4)
    sn_v, tau_v = rng.normal(size=300), rng.normal(size=300)
    c, phi = 2.0, 30.0
    zero = np.zeros(300)
    lam, ratio = shear_factors_affine((zero, sn_v), (zero, tau_v), c, friction_angle=phi)
    # without a constant traction: the proportional factor, bit for bit
    np.testing.assert_array_equal(lam, shear_factors(sn_v, tau_v, c, friction_angle=phi))
    sn_c, tau_c = rng.normal(size=300), rng.normal(size=300)
    lam, ratio = shear_factors_affine((sn_c, sn_v), (tau_c, tau_v), c, friction_angle=phi)
    mu = np.tan(np.radians(phi))

    ok = np.isfinite(lam) & (lam > 0)

    def g(x):
        return np.abs(tau_c[ok] + x * tau_v[ok]) + (sn_c[ok] + x * sn_v[ok]) * mu - c

    np.testing.assert_allclose(g(lam[ok]), 0.0, atol=1e-12)
    for frac in (0.25, 0.5, 0.999):  # nothing fails before λ (g is convex, g(0) < 0)
        assert np.all(g(frac * lam[ok]) < 0.0)
    assert np.all((ratio >= 1.0) == (lam == 0.0))
    never = ~np.isfinite(lam)
    assert np.all(np.abs(tau_v[never]) + sn_v[never] * mu <= 0.0)
