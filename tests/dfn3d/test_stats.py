"""Fisher estimates and bands, radius KS tests, P32 bounds and summaries (geofrac.dfn3d.stats).

The bands are checked by coverage over 20 seeds (a 99 % band must hold the estimate in
at least 17: the chance of 4 or more misses out of 20 at 1 % each is 4e-5) and against
chi-square quantiles from tables; a wrong estimator (2N/(N − R), twice κ̂) lies outside
the κ̂ band for every seed. Seeds are fixed, so outcomes are deterministic.
"""

import json
import math

import numpy as np
import pytest

from geofrac.dfn.errors import DfnError
from geofrac.dfn3d.network import canonical_normals, pole_to_normal
from geofrac.dfn3d.sampling import DiscSet, fisher_poles, power_law_radii, sample_network
from geofrac.dfn3d.stats import (
    fisher_cone_deg,
    fisher_estimate,
    kappa_band,
    kappa_ci,
    mean_pole_band_deg,
    network_summary,
    p32_bounds,
    pole_angle_deg,
    power_law_radius_moment,
    radius_ks,
)

KAPPA, N, SEEDS = 20.0, 2000, range(100, 120)
MEAN = pole_to_normal(30.0, 60.0)[0]


def axial_sample(seed: int, mean=MEAN, kappa=KAPPA, n=N) -> np.ndarray:
    """Fisher poles with the sign rule of stored networks (canonical normals)."""
    return canonical_normals(fisher_poles(np.random.default_rng(seed), n, mean=mean, kappa=kappa))


# ----------------------------------------------------------------------------- Fisher


def test_kappa_and_mean_pole_are_within_their_bands_over_seeds():
    lo, hi = kappa_band(KAPPA, N)
    alpha = mean_pole_band_deg(KAPPA, N)
    kappa_in = mean_in = wrong_in = 0
    for seed in SEEDS:
        est = fisher_estimate(axial_sample(seed))
        kappa_in += lo <= est.kappa <= hi
        mean_in += pole_angle_deg(est.mean, MEAN) <= alpha
        wrong = 2.0 * N / (N - est.resultant)  # a wrong estimator, ~2κ
        wrong_in += lo <= wrong <= hi
    assert kappa_in >= 17
    assert mean_in >= 17
    assert wrong_in == 0


def test_kappa_ci_holds_the_true_kappa():
    hits = 0
    for seed in SEEDS:
        est = fisher_estimate(axial_sample(seed, n=200), mean=MEAN)
        lo, hi = kappa_ci(est.kappa, 200)
        hits += lo <= KAPPA <= hi
    assert hits >= 17


def test_kappa_band_against_chi_square_tables():
    # N = 11: 2(N − 1) = 20 degrees of freedom; χ²(0.025, 20) = 9.591, χ²(0.975, 20) = 34.170
    lo, hi = kappa_band(10.0, 11, level=0.95)
    assert lo == pytest.approx(2 * 10 * 10 / 34.170, rel=1e-4)
    assert hi == pytest.approx(2 * 10 * 10 / 9.591, rel=1e-4)
    lo, hi = kappa_ci(10.0, 11, level=0.95)
    assert (lo, hi) == pytest.approx((10 * 9.591 / 20, 10 * 34.170 / 20), rel=1e-4)
    assert kappa_band(math.inf, 5) == (math.inf, math.inf)


def test_fisher_cone_worked_example():
    # N = 10, R = 9.5, 95 %: cos α = 1 − (0.5/9.5)(20^(1/9) − 1) = 0.9792131, α = 11.7027°
    assert fisher_cone_deg(10, 9.5, level=0.95) == pytest.approx(11.7027, abs=1e-4)
    assert fisher_cone_deg(10, 10.0) == 0.0
    # the band for a true κ is the cone at R = N − (N − 1)/κ
    assert mean_pole_band_deg(20.0, 10, level=0.95) == pytest.approx(
        fisher_cone_deg(10, 10 - 9 / 20, level=0.95), rel=1e-14
    )
    assert mean_pole_band_deg(math.inf, 10) == 0.0
    with pytest.raises(DfnError, match="too small"):
        mean_pole_band_deg(0.5, 10)


def test_estimate_of_identical_poles():
    poles = np.tile(pole_to_normal(30.0, 60.0), (5, 1))
    poles[1] *= -1.0  # axes: the sign does not matter
    est = fisher_estimate(poles)
    assert est.kappa == math.inf and est.resultant == 5.0
    assert est.trend == pytest.approx(30.0, abs=1e-9)
    assert est.plunge == pytest.approx(60.0, abs=1e-9)


def test_horizontal_mean_pole_is_found_from_axial_data():
    # canonical normals of a horizontal set fall on both sides of the equator's sign
    # rule; the orientation tensor still finds the mean
    mean = pole_to_normal(120.0, 0.0)[0]
    poles = axial_sample(3, mean=mean, kappa=KAPPA)
    assert np.any(poles @ mean < 0)  # mixed signs
    est = fisher_estimate(poles)
    lo, hi = kappa_band(KAPPA, N)
    assert lo <= est.kappa <= hi
    assert pole_angle_deg(est.mean, mean) <= mean_pole_band_deg(KAPPA, N)
    assert est.plunge == pytest.approx(0.0, abs=1.0)
    assert est.trend % 180.0 == pytest.approx(120.0, abs=1.0)
    # given the mean as the reference: the same estimate
    again = fisher_estimate(poles, mean=-mean)
    assert again.kappa == pytest.approx(est.kappa, rel=1e-12)


def test_large_kappa_estimate_keeps_precision():
    poles = axial_sample(4, kappa=1e8, n=500)
    lo, hi = kappa_band(1e8, 500)
    assert lo <= fisher_estimate(poles).kappa <= hi


def test_pole_angle():
    assert pole_angle_deg([0, 0, 1], [0, 0, -1]) == 0.0
    assert pole_angle_deg([1, 0, 0], [0, 1, 0]) == pytest.approx(90.0)
    assert pole_angle_deg([1, 0, 0], [1, 1e-9, 0]) == pytest.approx(math.degrees(1e-9), rel=1e-6)


def test_fisher_estimate_rejects_bad_input():
    with pytest.raises(DfnError, match="at least 2 poles"):
        fisher_estimate([[0, 0, 1]])
    with pytest.raises(DfnError, match="finite and nonzero"):
        fisher_estimate([[0, 0, 1], [0, 0, 0]])
    with pytest.raises(DfnError, match="zero resultant"):
        fisher_estimate([[1, 0, 0], [-1, 0, 0]], mean=[0, 1, 0])
    with pytest.raises(DfnError, match="confidence level"):
        kappa_band(10.0, 5, level=1.0)
    with pytest.raises(DfnError, match="n must be an integer >= 2"):
        kappa_band(10.0, 1)


# ------------------------------------------------------------------------------ radii


def test_radius_ks_accepts_the_law_and_rejects_another():
    r = power_law_radii(np.random.default_rng(31), 2000, rmin=0.5, rmax=10.0, alpha=2.5)
    d, p = radius_ks(r, rmin=0.5, rmax=10.0, alpha=2.5)
    assert 0 < d < 0.05 and p > 0.01
    _, p_wrong = radius_ks(r, rmin=0.5, rmax=10.0, alpha=1.5)
    assert p_wrong < 1e-6
    assert radius_ks([2.0, 2.0], rmin=2.0, rmax=2.0, alpha=1.0) == (0.0, 1.0)
    assert radius_ks([2.0, 2.5], rmin=2.0, rmax=2.0, alpha=1.0) == (1.0, 0.0)


@pytest.mark.parametrize(("k", "alpha"), [(1, 2.5), (2, 2.5), (2, 2.0), (3, 1.2)])
def test_radius_moments_against_quadrature(k, alpha):
    rmin, rmax = 0.5, 10.0
    # midpoint rule in log r of ∫ r^k α r^(−α−1) dr / (rmin^−α − rmax^−α)
    t = np.linspace(math.log(rmin), math.log(rmax), 200_001)
    tm = 0.5 * (t[1:] + t[:-1])
    r = np.exp(tm)
    integral = np.sum(r**k * alpha * r**-alpha) * (t[1] - t[0])
    want = integral / (rmin**-alpha - rmax**-alpha)
    assert power_law_radius_moment(k, rmin=rmin, rmax=rmax, alpha=alpha) == pytest.approx(
        want, rel=1e-9
    )
    assert power_law_radius_moment(2, rmin=3.0, rmax=3.0, alpha=1.0) == 9.0


# ------------------------------------------------------------------------ P32, summary


BOX = (0.0, 0.0, 0.0, 20.0, 10.0, 10.0)
SETS = [
    DiscSet("steep", 30.0, 60.0, 20.0, 0.5, 3.0, 2.5, p32=0.3),
    DiscSet("flat", 200.0, 85.0, 10.0, 1.0, 1.0, 1.0, count=300),
    DiscSet("fixed", 90.0, 0.0, math.inf, 0.5, 2.0, 2.0, count=20),
]


@pytest.fixture(scope="module")
def summary() -> dict:
    net = sample_network(SETS, box=BOX, seed=41)
    return network_summary(net, BOX, SETS)


def test_p32_bounds():
    assert p32_bounds(0.3, volume=2000.0, rmax=3.0) == (0.3, 0.3 + math.pi * 9 / 2000)
    assert p32_bounds(0.0, volume=1.0, rmax=1.0) == (0.0, 0.0)
    with pytest.raises(DfnError, match="volume must be finite and > 0"):
        p32_bounds(0.3, volume=0.0, rmax=1.0)


def test_summary_is_json_and_consistent(summary):
    text = json.dumps(summary, allow_nan=False)  # JSON-ready: no inf, NaN or arrays
    assert json.loads(text) == summary
    assert list(summary) == ["steep", "flat", "fixed"]
    steep, flat, fixed = summary["steep"], summary["flat"], summary["fixed"]
    lo, hi = steep["p32_bounds"]
    assert lo * (1 - 1e-12) <= steep["p32"] < hi
    assert flat["count"] == 300 and flat["count_target"] == 300 and flat["p32_bounds"] is None
    assert flat["radius_ks_p"] == 1.0  # constant radius
    for s in (steep, flat):
        assert s["kappa_in_band"] and s["mean_in_band"]
        assert s["radius_ks_p"] > 0.01
        assert s["mean_angle_deg"] <= s["mean_band_deg"]
    assert fixed["kappa"] is None and fixed["kappa_hat"] is None  # κ = inf
    assert fixed["kappa_in_band"] and fixed["mean_angle_deg"] == pytest.approx(0.0, abs=1e-6)


def test_summary_of_sets_not_in_the_network():
    net = sample_network(SETS[1:2], box=BOX, seed=1)
    out = network_summary(net, BOX, [SETS[0]])
    assert out["steep"]["count"] == 0 and out["steep"]["p32"] == 0.0
    assert out["flat"]["count"] == 300 and "kappa_band" not in out["flat"]  # no target
