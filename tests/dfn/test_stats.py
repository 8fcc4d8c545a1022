"""Statistics helpers against known values (geofrac.dfn.stats)."""

import itertools
import math

import numpy as np
import pytest

from geofrac.dfn.errors import DfnError
from geofrac.dfn.stats import (
    axial_deviation_deg,
    axial_mean_deg,
    chi2_cdf,
    chi2_quantile,
    fold_axial_deg,
    ks_pvalue,
    ks_statistic,
    mean_ci,
    normal_quantile,
    orientation_summary,
    t_quantile,
    variance_ci,
)


def kolmogorov_q(lam: float, n: int = 10_000) -> float:
    """ks_pvalue at the Kolmogorov argument lam (undoing Stephens' correction)."""
    sn = math.sqrt(n)
    return ks_pvalue(lam / (sn + 0.12 + 0.11 / sn), n)


@pytest.mark.parametrize(
    ("p", "z"),
    [
        (0.995, 2.5758293035489),
        (0.975, 1.959963984540054),
        (0.5, 0.0),
        (0.8413447460685429, 1.0),  # Φ(1)
        (0.01, -2.326347874040841),
        (1e-10, -6.361340902404056),
    ],
)
def test_normal_quantile_known_values(p, z):
    assert normal_quantile(p) == pytest.approx(z, abs=1e-12)


def test_normal_quantile_is_antisymmetric_and_inverts_erfc():
    for p in (1e-300, 1e-20, 0.001, 0.02425, 0.1, 0.3, 0.49):
        z = normal_quantile(p)
        if p > 1e-6:  # 1 - p must still be distinguishable from 1
            assert normal_quantile(1 - p) == pytest.approx(-z, rel=1e-9)
        assert 0.5 * math.erfc(-z / math.sqrt(2)) == pytest.approx(p, rel=1e-12)


@pytest.mark.parametrize("p", [0.0, 1.0, -0.1, 1.5])
def test_normal_quantile_rejects_bad_probabilities(p):
    with pytest.raises(DfnError, match="probability must be in"):
        normal_quantile(p)


@pytest.mark.parametrize(
    ("p", "dof", "x"),
    [
        (0.95, 1, 3.841458820694124),
        (0.99, 5, 15.08627246938899),
        (0.05, 10, 3.940299136),
        (0.975, 100, 129.5611971685),
        (0.025, 100, 74.22192747),
        (0.5, 2, 2.0 * math.log(2.0)),
    ],
)
def test_chi2_quantile_tabulated(p, dof, x):
    # documented accuracy ~1e-12; the tabulated values carry 10 digits
    assert chi2_quantile(p, dof) == pytest.approx(x, rel=1e-9)


def test_chi2_quantile_inverts_the_cdf_and_is_near_wilson_hilferty():
    for dof in (1, 2, 7.5, 100, 2999, 10**5):
        for p in (0.001, 0.005, 0.3, 0.5, 0.9, 0.995):
            x = chi2_quantile(p, dof)
            assert chi2_cdf(x, dof) == pytest.approx(p, rel=1e-10)
            if dof >= 100:
                z, h = normal_quantile(p), 2.0 / (9.0 * dof)
                assert x == pytest.approx(dof * (1 - h + z * math.sqrt(h)) ** 3, rel=1e-3)


def test_chi2_cdf_closed_form_for_two_dof():
    for x in (0.01, 1.0, 5.0, 40.0):
        assert chi2_cdf(x, 2) == pytest.approx(1.0 - math.exp(-x / 2.0), rel=1e-13)
    assert chi2_cdf(-1.0, 3) == 0.0


@pytest.mark.parametrize(
    ("p", "dof", "t"),
    [
        (0.975, 10, 2.228138851986),
        (0.995, 10, 3.169272672617),
        (0.975, 30, 2.042272456301),
        (0.995, 30, 2.749995653567),
        (0.005, 100, -2.6258905214),
        (0.975, 3, 3.182446305284),
    ],
)
def test_t_quantile_tabulated(p, dof, t):
    assert t_quantile(p, dof) == pytest.approx(t, rel=1e-10)


def test_t_quantile_closed_forms_for_one_and_two_dof():
    for p in (1e-8, 0.01, 0.3, 0.6, 0.995):
        assert t_quantile(p, 1) == pytest.approx(-1.0 / math.tan(math.pi * p), rel=1e-11)
        assert t_quantile(p, 2) == pytest.approx(
            (2 * p - 1) / math.sqrt(2 * p * (1 - p)), rel=1e-11
        )
    assert t_quantile(0.995, 10**6) == pytest.approx(normal_quantile(0.995), rel=1e-5)


def test_ks_statistic_by_hand():
    # uniform CDF at 0.1, 0.5, 0.9: D = max(1/3 - 0.1, 0.9 - 2/3) = 0.2333...
    d = ks_statistic([0.9, 0.1, 0.5], lambda x: x)
    assert d == pytest.approx(0.7 / 3.0, abs=1e-15)
    assert ks_statistic([0.5], lambda x: x) == pytest.approx(0.5)


def test_ks_statistic_rejects_a_cdf_of_the_wrong_shape():
    with pytest.raises(DfnError, match="cdf returned shape"):
        ks_statistic([0.1, 0.2], lambda x: np.array(0.5))


@pytest.mark.parametrize(
    ("lam", "q"),
    [(0.5, 0.9639452436648751), (1.0, 0.2699996716773546), (1.36, 0.0494858767), (1.63, 0.0098)],
)
def test_ks_pvalue_known_values(lam, q):
    assert kolmogorov_q(lam) == pytest.approx(q, abs=1e-4)


def test_ks_pvalue_monotone_bounded_and_continuous_at_the_switch():
    ps = [ks_pvalue(d, 500) for d in np.linspace(0.0, 0.2, 401)]
    assert ps[0] == 1.0
    assert all(0.0 <= p <= 1.0 for p in ps)
    assert all(b <= a for a, b in itertools.pairwise(ps))
    assert kolmogorov_q(1.18 - 1e-9) == pytest.approx(kolmogorov_q(1.18 + 1e-9), abs=1e-8)


def test_ks_test_accepts_the_true_law_and_rejects_a_wrong_one():
    x = np.random.default_rng(3).random(2000)
    d_true = ks_statistic(x, lambda v: v)
    d_wrong = ks_statistic(x, lambda v: v**1.3)
    assert ks_pvalue(d_true, len(x)) > 0.01
    assert ks_pvalue(d_wrong, len(x)) < 1e-6


def test_fold_and_axial_deviation():
    assert fold_axial_deg([-10.0, 180.0, 190.0, 359.9, -1e-18]).tolist() == pytest.approx(
        [170.0, 0.0, 10.0, 179.9, 0.0]
    )
    assert np.all(fold_axial_deg(np.array([-1e-18])) < 180.0)
    dev = axial_deviation_deg([1.0, 179.0, 90.0, 45.0], 0.0)
    assert dev.tolist() == pytest.approx([1.0, -1.0, -90.0, 45.0])
    assert axial_deviation_deg(1.0, 179.0) == pytest.approx(2.0)
    assert axial_deviation_deg(179.0, 1.0) == pytest.approx(-2.0)


def test_axial_mean_wraps_around_180():
    m = axial_mean_deg([179.0, 1.0])
    assert 0.0 <= m < 180.0
    assert axial_deviation_deg(m, 0.0) == pytest.approx(0.0, abs=1e-12)
    assert axial_mean_deg([170.0, 176.0, 4.0]) == pytest.approx(176.6666, abs=0.01)
    assert axial_mean_deg([89.0, 91.0]) == pytest.approx(90.0)
    assert axial_mean_deg([30.0, 210.0]) == pytest.approx(30.0)
    with pytest.raises(DfnError, match="no mean direction"):
        axial_mean_deg([0.0, 90.0])


def test_orientation_summary_of_a_wrapped_sample():
    rng = np.random.default_rng(5)
    a = fold_axial_deg(175.0 + 6.0 * rng.standard_normal(5000))
    s = orientation_summary(a)
    assert s["n"] == 5000
    assert axial_deviation_deg(s["mean"], 175.0) == pytest.approx(0.0, abs=0.3)
    assert s["std"] == pytest.approx(6.0, rel=0.03)
    # the naive statistics of the folded angles are badly wrong
    assert abs(np.mean(a) - 175.0) > 20.0


def test_intervals_cover_at_their_level():
    rng = np.random.default_rng(8)
    reps, n, level = 2000, 40, 0.9
    x = 3.0 + 2.0 * rng.standard_normal((reps, n))
    mean_hits = sum(lo <= 3.0 <= hi for lo, hi in (mean_ci(row, level) for row in x))
    var_hits = sum(lo <= 4.0 <= hi for lo, hi in (variance_ci(row, level) for row in x))
    # binomial standard deviation of the coverage: sqrt(0.9 * 0.1 / 2000) = 0.0067
    assert mean_hits / reps == pytest.approx(level, abs=0.025)
    assert var_hits / reps == pytest.approx(level, abs=0.025)


def test_intervals_by_formula():
    x = np.array([1.0, 2.0, 4.0, 7.0])
    lo, hi = mean_ci(x, 0.95)
    assert 0.5 * (lo + hi) == pytest.approx(3.5)
    assert hi - lo == pytest.approx(2 * 3.182446305284 * np.std(x, ddof=1) / 2.0)  # t, 3 dof
    vlo, vhi = variance_ci(x, 0.95)
    ss = 3 * np.var(x, ddof=1)
    assert vlo == pytest.approx(ss / chi2_quantile(0.975, 3))
    assert vhi == pytest.approx(ss / chi2_quantile(0.025, 3))


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: mean_ci([1.0]), "at least 2 samples"),
        (lambda: variance_ci([1.0, 2.0], 1.0), "confidence level"),
        (lambda: mean_ci([1.0, np.nan]), "finite"),
        (lambda: chi2_quantile(0.5, 0), "dof must be"),
        (lambda: ks_pvalue(-0.1, 10), "d must be"),
        (lambda: ks_pvalue(0.1, 0), "n must be"),
        (lambda: t_quantile(0.9, 0.0), "dof must be"),
    ],
)
def test_stats_errors(call, match):
    with pytest.raises(DfnError, match=match):
        call()
