"""Fracture sets, samplers and network generation (geofrac.dfn.sampling).

The statistical tests are the acceptance criterion of the DFN generator: with the sets of
Table 2.1 of Edo (2016) (3000 fractures each, power law n = 3.1 on 10-50 mm, 200 × 100 mm),
the lengths pass a KS test against the truncated power law of Edo (2016), eq. (2.28) and the
orientations' mean and variance are within their 99 % confidence intervals, while
deliberately wrong laws are rejected. Seeds are fixed, so the outcome is deterministic.
"""

import math

import numpy as np
import pytest

from geofrac.dfn import sampling
from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import clip_segments, points_in_polygon, rectangle
from geofrac.dfn.sampling import (
    FractureSet,
    Network,
    generate_network,
    network_p21,
    power_law_ccdf,
    power_law_cdf,
    power_law_lengths,
    sample_angles,
    uniform_points,
)
from geofrac.dfn.stats import (
    axial_deviation_deg,
    ks_pvalue,
    ks_statistic,
    mean_ci,
    orientation_summary,
    variance_ci,
)

DOMAIN = rectangle((0.0, 0.0), (200.0, 100.0))
# Edo (2016), Table 2.1: (name, mean angle in degrees, variance in deg²)
TABLE_2_1 = [("set1", 47.473, 60.74), ("set2", 102.753, 57.16), ("set3", 162.830, 57.48)]
LMIN, LMAX, N_EXP = 10.0, 50.0, 3.1
COUNT = 3000
SEED = 2024


def table_sets(count: int = COUNT) -> list[FractureSet]:
    return [
        FractureSet(name, mean, math.sqrt(var), LMIN, LMAX, N_EXP, count=count)
        for name, mean, var in TABLE_2_1
    ]


@pytest.fixture(scope="module")
def table_network() -> Network:
    return generate_network(table_sets(), DOMAIN, seed=SEED)


def bessel_i(order: int, x: float) -> float:
    """Modified Bessel function of the first kind by its power series."""
    return sum(
        (x / 2.0) ** (2 * k + order) / (math.factorial(k) * math.factorial(k + order))
        for k in range(80)
    )


# ------------------------------------------------------------------------ FractureSet


def fset(**kw) -> FractureSet:
    args = {
        "name": "s",
        "mean_deg": 30.0,
        "spread": 5.0,
        "lmin": 10.0,
        "lmax": 50.0,
        "exponent": 3.1,
        "count": 10,
    }
    args.update(kw)
    return FractureSet(**args)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"lmin": 60.0}, r"lmin > lmax \(lmin = 60.0, lmax = 50.0\)"),
        ({"lmin": 0.0}, "lmin must be > 0"),
        ({"lmin": -1.0}, "lmin must be > 0"),
        ({"exponent": 0.0}, "exponent must be > 0"),
        ({"exponent": -3.1}, "exponent must be > 0"),
        ({"lmax": math.inf}, "lmax must be finite"),
        ({"mean_deg": math.nan}, "mean_deg must be finite"),
        ({"spread": "5"}, "spread must be a number"),
        ({"spread": -1.0}, "spread must be >= 0"),
        ({"distribution": "von_mises", "spread": 0.0}, "concentration"),
        ({"distribution": "fisher"}, "unknown distribution 'fisher'"),
        ({"count": None}, "exactly one of count and p21"),
        ({"p21": 0.1}, "exactly one of count and p21"),
        ({"count": -1}, "count must be >= 0"),
        ({"count": 2.5}, "count must be an integer"),
        ({"count": True}, "count must be an integer"),
        ({"count": None, "p21": -0.1}, "negative density"),
        ({"count": None, "p21": math.inf}, "p21 must be finite"),
        ({"name": ""}, "non-empty string"),
        ({"name": "a,b"}, "must not contain commas"),
        ({"name": 3}, "non-empty string"),
    ],
)
def test_fracture_set_errors(kw, match):
    with pytest.raises(DfnError, match=match):
        fset(**kw)


def test_fracture_set_error_names_the_set():
    with pytest.raises(DfnError, match="fracture set 'joints': lmin > lmax"):
        fset(name="joints", lmin=51.0)


def test_fracture_set_accepts_valid_fields():
    s = fset(count=np.int64(5), lmin=20.0, lmax=20.0, spread=0.0)
    assert s.count == 5
    assert fset(count=None, p21=0.0).p21 == 0.0
    assert fset(distribution="von_mises", spread=4.0).distribution == "von_mises"


# ------------------------------------------------------------------------- power law


def test_power_law_ccdf_formula_and_limits():
    l = np.array([5.0, 10.0, 20.0, 50.0, 80.0])  # noqa: E741
    ccdf = power_law_ccdf(l, 10.0, 50.0, exponent=3.1)
    expected_20 = (20.0**-3.1 - 50.0**-3.1) / (10.0**-3.1 - 50.0**-3.1)
    assert ccdf.tolist() == pytest.approx([1.0, 1.0, expected_20, 0.0, 0.0], abs=1e-15)
    assert np.all(np.diff(ccdf) <= 0)
    np.testing.assert_allclose(power_law_cdf(l, 10.0, 50.0, exponent=3.1) + ccdf, 1.0, atol=1e-15)


def test_power_law_with_equal_bounds_is_a_step():
    assert power_law_ccdf([9.9, 10.0, 10.1], 10.0, 10.0, exponent=3.1).tolist() == [1.0, 0.0, 0.0]
    rng = np.random.default_rng(0)
    assert power_law_lengths(rng, 4, 10.0, lmax=10.0, exponent=3.1).tolist() == [10.0] * 4


def test_power_law_lengths_bounds_and_median():
    x = power_law_lengths(np.random.default_rng(1), 20000, 10.0, lmax=50.0, exponent=3.1)
    assert x.shape == (20000,)
    assert x.min() >= 10.0 and x.max() <= 50.0
    # the median solves ccdf = 1/2
    r = 5.0**-3.1
    median = 10.0 * (r + 0.5 * (1.0 - r)) ** (-1.0 / 3.1)
    assert np.median(x) == pytest.approx(median, rel=0.01)


def test_power_law_rejects_bad_parameters():
    with pytest.raises(DfnError, match="lmin > lmax"):
        power_law_ccdf(1.0, 5.0, 2.0, exponent=3.1)


# -------------------------------------------- acceptance: Edo (2016), Table 2.1 statistics


@pytest.mark.parametrize("i", range(3))
def test_lengths_pass_ks_against_the_truncated_power_law(table_network, i):
    lengths = table_network.lengths[table_network.set_index == i]
    assert len(lengths) == COUNT
    d = ks_statistic(lengths, lambda x: power_law_cdf(x, LMIN, LMAX, exponent=N_EXP))
    assert ks_pvalue(d, len(lengths)) > 0.01
    # a deliberately wrong law is rejected
    d_wrong = ks_statistic(lengths, lambda x: power_law_cdf(x, LMIN, LMAX, exponent=2.0))
    assert ks_pvalue(d_wrong, len(lengths)) < 1e-6


@pytest.mark.parametrize(("i", "row"), list(enumerate(TABLE_2_1)))
def test_orientations_match_table_2_1(table_network, i, row):
    _, mean, var = row
    angles = table_network.angles_deg[table_network.set_index == i]
    assert np.all((angles >= 0.0) & (angles < 180.0))
    # deviations from the true mean, folded (set 3 wraps past 180°)
    dev = axial_deviation_deg(angles, mean)
    lo, hi = mean_ci(dev, 0.99)
    assert lo <= 0.0 <= hi, (lo, hi)
    vlo, vhi = variance_ci(dev, 0.99)
    assert vlo <= var <= vhi, (vlo, vhi)
    # a mean shifted by 2° and a variance 20 % off are rejected
    dev_shifted = axial_deviation_deg(angles, mean + 2.0)
    lo, hi = mean_ci(dev_shifted, 0.99)
    assert not lo <= 0.0 <= hi
    assert not vlo <= 1.2 * var <= vhi
    assert not vlo <= 0.8 * var <= vhi


def test_orientation_summary_of_the_table_sets(table_network):
    for i, (_, mean, var) in enumerate(TABLE_2_1):
        s = orientation_summary(table_network.angles_deg[table_network.set_index == i])
        assert s["n"] == COUNT
        assert axial_deviation_deg(s["mean"], mean) == pytest.approx(0.0, abs=0.5)
        assert s["std"] == pytest.approx(math.sqrt(var), rel=0.05)


@pytest.mark.parametrize(("mean", "kappa"), [(150.0, 8.0), (20.0, 2.5)])
def test_von_mises_axial_mean_and_resultant(mean, kappa):
    vm = FractureSet("vm", mean, kappa, LMIN, LMAX, N_EXP, distribution="von_mises", count=COUNT)
    angles = generate_network([vm], DOMAIN, seed=SEED).angles_deg
    assert np.all((angles >= 0.0) & (angles < 180.0))
    lo, hi = mean_ci(axial_deviation_deg(angles, mean), 0.99)
    assert lo <= 0.0 <= hi
    lo, hi = mean_ci(axial_deviation_deg(angles, mean + 2.0), 0.99)
    assert not lo <= 0.0 <= hi
    # mean resultant length of the doubled angles: A(κ) = I1(κ)/I0(κ)
    a = bessel_i(1, kappa) / bessel_i(0, kappa)
    assert bessel_i(0, kappa) == pytest.approx(float(np.i0(kappa)), rel=1e-12)
    two = np.radians(2.0 * angles)
    r = math.hypot(np.mean(np.cos(two)), np.mean(np.sin(two)))
    # standard deviation of R̄ about A: sqrt((1 + I2/I0)/2 - A²) / sqrt(n) < 0.008
    assert r == pytest.approx(a, abs=0.02)
    assert orientation_summary(angles)["resultant"] == pytest.approx(r)


def test_sample_angles_fixed_and_folded():
    rng = np.random.default_rng(0)
    angles = sample_angles(rng, 5, fset(mean_deg=200.0, spread=0.0))
    assert angles.tolist() == pytest.approx([20.0] * 5)
    angles = sample_angles(rng, 4000, fset(mean_deg=-1.0, spread=3.0))
    assert np.all((angles >= 0.0) & (angles < 180.0))
    assert np.any(angles > 170.0) and np.any(angles < 10.0)


# --------------------------------------------------------------------------- centres


def test_uniform_points_in_an_l_shape():
    ell = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
    pts = uniform_points(np.random.default_rng(6), 30000, ell)
    assert pts.shape == (30000, 2)
    assert np.all(points_in_polygon(pts, ell))
    # lower arm (y < 1) holds 2/3 of the area; binomial sd = 0.0027
    assert np.mean(pts[:, 1] < 1.0) == pytest.approx(2.0 / 3.0, abs=0.011)
    assert np.mean(pts[:, 0] < 0.5) == pytest.approx(1.0 / 3.0, abs=0.011)
    again = uniform_points(np.random.default_rng(6), 30000, ell)
    assert np.array_equal(pts, again)
    assert uniform_points(np.random.default_rng(6), 0, ell).shape == (0, 2)


def test_centres_lie_in_the_region_uniformly(table_network):
    centres = table_network.centres
    assert np.all(points_in_polygon(centres, DOMAIN))
    for coord, size in ((centres[:, 0], 200.0), (centres[:, 1], 100.0)):
        d = ks_statistic(coord / size, lambda u: u)
        assert ks_pvalue(d, len(coord)) > 0.01
    # fractures are not clipped: some stick out of the region
    assert not np.all(points_in_polygon(table_network.segments.reshape(-1, 2), DOMAIN))


# ------------------------------------------------------------------- generate_network


def test_generation_is_deterministic(table_network):
    again = generate_network(table_sets(), DOMAIN, seed=SEED)
    assert np.array_equal(table_network.segments, again.segments)
    assert np.array_equal(table_network.set_index, again.set_index)
    assert table_network.set_names == ("set1", "set2", "set3")
    other = generate_network(table_sets(), DOMAIN, seed=SEED + 1)
    assert not np.array_equal(table_network.segments, other.segments)


def test_count_is_exact_and_a_smaller_count_gives_a_prefix(table_network):
    assert len(table_network) == 3 * COUNT
    assert np.bincount(table_network.set_index).tolist() == [COUNT] * 3
    small = generate_network(table_sets(count=1500), DOMAIN, seed=SEED)
    assert np.array_equal(small.segments[:1500], table_network.segments[:1500])
    assert len(generate_network(table_sets(count=0), DOMAIN, seed=SEED)) == 0


def test_adding_a_set_keeps_the_earlier_sets(table_network):
    first = generate_network(table_sets()[:1], DOMAIN, seed=SEED)
    assert np.array_equal(first.segments, table_network.segments[:COUNT])
    extra = FractureSet("extra", 10.0, 4.0, 5.0, 20.0, 2.0, count=100)
    more = generate_network([*table_sets(), extra], DOMAIN, seed=SEED)
    assert np.array_equal(more.segments[: 3 * COUNT], table_network.segments)
    assert more.set_names[-1] == "extra"
    assert np.all(more.set_index[3 * COUNT :] == 3)


@pytest.mark.parametrize("p21", [0.02, 0.25])
def test_p21_target_reached_within_one_fracture(p21):
    region = rectangle((-40.0, -40.0), (240.0, 140.0))  # centres also outside the domain
    sets = [
        FractureSet("a", 47.0, 8.0, LMIN, LMAX, N_EXP, p21=p21),
        FractureSet("b", 103.0, 8.0, LMIN, LMAX, N_EXP, p21=p21 / 2.0),
    ]
    net = generate_network(sets, region, seed=7, domain=DOMAIN)
    for i, fs in enumerate(sets):
        segs = net.segments[net.set_index == i]
        one = Network(segs, np.zeros(len(segs), dtype=int), ("x",))
        fewer = Network(segs[:-1], np.zeros(len(segs) - 1, dtype=int), ("x",))
        assert network_p21(one, DOMAIN) >= fs.p21
        assert network_p21(fewer, DOMAIN) < fs.p21
    # P21 counts only the clipped length: more fractures are needed than with no clipping
    pieces, _ = clip_segments(net.segments, DOMAIN)
    assert len(pieces) < len(net)
    # and the p21 sequence is the same as the count sequence
    counted = generate_network(
        [FractureSet("a", 47.0, 8.0, LMIN, LMAX, N_EXP, count=10)], region, seed=7
    )
    assert np.array_equal(counted.segments, net.segments[:10])


def test_zero_p21_gives_no_fractures():
    net = generate_network([fset(count=None, p21=0.0)], DOMAIN, seed=0)
    assert len(net) == 0 and net.set_names == ("s",)


def test_unreachable_p21_is_refused(monkeypatch):
    monkeypatch.setattr(sampling, "MAX_P21_FRACTURES", 4 * sampling.BATCH)
    far = rectangle((1000.0, 1000.0), (1100.0, 1100.0))
    with pytest.raises(DfnError, match=r"fracture set 's': p21 = 0.1 not reached"):
        generate_network([fset(count=None, p21=0.1)], far, seed=0, domain=DOMAIN)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"seed": -1}, "seed must be a non-negative integer"),
        ({"seed": 1.5}, "seed must be a non-negative integer"),
        ({"seed": True}, "seed must be a non-negative integer"),
        ({"sets": [fset(), fset()]}, r"set names must be distinct, repeated: \['s'\]"),
        ({"sets": ["s"]}, r"sets\[0\] is not a FractureSet"),
        ({"region": [[0, 0], [1, 1]]}, "polygon: needs at least 3 vertices"),
    ],
)
def test_generate_network_errors(kw, match):
    args = {"sets": [fset()], "region": DOMAIN, "seed": 0}
    args.update(kw)
    with pytest.raises(DfnError, match=match):
        generate_network(**args)


def test_network_p21_by_hand():
    segs = np.array([[[-10.0, 50.0], [210.0, 50.0]], [[10.0, 10.0], [10.0, 30.0]]])
    net = Network(segs, np.array([0, 0]), ("x",))
    assert network_p21(net, DOMAIN) == pytest.approx((200.0 + 20.0) / 20000.0)


# --------------------------------------------------------------------------- Network


def test_network_properties():
    segs = np.array([[[0.0, 0.0], [3.0, 4.0]], [[1.0, 1.0], [-1.0, 1.0]], [[0, 0], [0, -2]]])
    net = Network(segs, [0, 1, 1], ["a", "b"])
    assert len(net) == 3
    assert net.set_names == ("a", "b")
    assert net.lengths.tolist() == pytest.approx([5.0, 2.0, 2.0])
    assert net.angles_deg.tolist() == pytest.approx([math.degrees(math.atan2(4, 3)), 0.0, 90.0])
    assert net.centres.tolist() == [[1.5, 2.0], [0.0, 1.0], [0.0, -1.0]]
    with pytest.raises(ValueError, match="read-only"):
        net.segments[0, 0, 0] = 1.0
    segs[0, 0, 0] = 99.0  # the network holds a copy
    assert net.segments[0, 0, 0] == 0.0


def test_empty_network():
    net = Network(np.zeros((0, 2, 2)), np.zeros(0, dtype=int), ())
    assert len(net) == 0 and net.lengths.shape == (0,) and net.angles_deg.shape == (0,)


@pytest.mark.parametrize(
    ("segments", "index", "names", "match"),
    [
        (np.zeros((2, 2, 3)), [0, 0], ("a",), r"shape \(n, 2, 2\)"),
        ([[[0, 0], [1, np.nan]]], [0], ("a",), "fracture 0 has a non-finite coordinate"),
        ([[[0, 0], [1, 1]]], [0, 0], ("a",), r"set_index must have shape \(1,\)"),
        ([[[0, 0], [1, 1]]], [0.0], ("a",), "set_index must be integers"),
        ([[[0, 0], [1, 1]]], [1], ("a",), r"set index 1, outside \[0, 1\)"),
        ([[[0, 0], [1, 1]]], [0], ("a", "a"), "set names must be distinct"),
        ([[[0, 0], [1, 1]]], [0], ("a\nb",), "line breaks"),
    ],
)
def test_network_errors(segments, index, names, match):
    with pytest.raises(DfnError, match=match):
        Network(np.asarray(segments, dtype=float), np.asarray(index), names)
