"""The bar benchmarks of Edo (2016): quasi-static bar (4.5.1), translating bar (4.5.3)."""

import numpy as np
import pytest

from geofrac.bench.mpm import translating_bar
from geofrac.mpm.bar import impact_bar, quasi_static_bar, self_weight_stress
from geofrac.mpm.schemes import SCHEMES
from geofrac.mpm.shapes import REGISTRY

# The quadratic B-spline (not a shape of Edo (2016)) misses the 2 % at the fixed base: RMS 0.030
# (MUSL), the error sits in the particles within 1.5 cells of the base (−27 % of ρ₀|b|L₀
# at the second one; 0.013 RMS without the three particles at each end), where the
# spline's support crosses the held nodes with no boundary-modified spline. Measured on
# mpm-energy before the merge; strict, so a fix shows.
_BASE = pytest.mark.xfail(strict=True, reason="bspline2 has no boundary-modified splines")


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize(
    "shape", [pytest.param(s, marks=_BASE) if s == "bspline2" else s for s in REGISTRY]
)
def test_quasi_static_bar_matches_eq_4_73_at_W_1000(shape, scheme):
    """Edo (2016), §4.5.1 (Fig. 4.13): RMS stress error over ρ₀|b|L₀ below 2% for every variant."""
    res = quasi_static_bar(shape, scheme, W=1000.0)
    assert res.steps == 500
    assert res.error < 0.02


def test_self_weight_stress_is_in_equilibrium():
    """Eq. 4.73 satisfies dσ/dx = ρ b with ρ = ρ₀/λ, λ = 1 + σ/E; zero at the top Δ."""
    E, rho0, b, L0 = 1e6, 1.0, 2000.0, 50.0
    delta = L0 - rho0 * b * L0**2 / (2 * E)
    x = np.linspace(0.0, delta, 201)
    s = self_weight_stress(x, E=E, rho0=rho0, b=b, L0=L0)
    assert s[-1] == pytest.approx(0.0, abs=1e-9)
    rho = rho0 / (1 + s / E)
    np.testing.assert_allclose(np.gradient(s, x, edge_order=2), rho * b, rtol=1e-6)


def test_translating_bar_stays_finite_over_1e5_steps():
    """Edo (2016), §4.5.3, 1e5 steps (about 224 time units, 9 wall hits): no NaN.

    Point-particle MPM with MLS smoothing: the variant whose energy drifts most.
    """
    res = translating_bar("mpm", "musl", smoothing=2.0, steps=100_000, samples=200)
    assert res.steps == 100_000
    assert res.finite
    assert np.all(np.isfinite(res.total))
    assert res.t[-1] > 200.0


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("shape", REGISTRY)
def test_impact_bar_carries_the_stress_of_eq_4_75_behind_the_wave(shape, scheme):
    """Edo (2016), §4.5.2: behind the front the mean stress is −E v₀/c (within 3 %), ahead ~0."""
    res = impact_bar(shape, scheme)
    behind, ahead = res.x0 < 35.0, res.x0 > 45.0
    assert np.mean(res.stress[behind]) == pytest.approx(1.0, abs=0.03)
    assert np.max(np.abs(res.stress[ahead])) < 0.05
    assert res.overshoot < 1.4  # the dispersive overshoot at the front stays bounded
