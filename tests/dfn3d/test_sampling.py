"""Disc sets, Fisher poles, power-law radii, clipped areas and networks (geofrac.dfn3d.sampling).

The samplers are checked against closed forms: the Fisher law's mean cos θ = coth κ − 1/κ
and CDF P(cos θ <= c) = (e^{κc} − e^{−κ})/(e^κ − e^{−κ}), the truncated power law's CDF
and mean, uniform azimuths and centres; the clipped areas against the areas of discs cut
by planes through and off their centres. Seeds are fixed, so outcomes are deterministic.
"""

import math

import numpy as np
import pytest

from geofrac.dfn.errors import DfnError
from geofrac.dfn.stats import ks_pvalue, ks_statistic
from geofrac.dfn3d import sampling
from geofrac.dfn3d.network import DiscNetwork, pole_to_normal
from geofrac.dfn3d.sampling import (
    DiscSet,
    clipped_area,
    fisher_poles,
    network_p32,
    polygon_area_error,
    power_law_radii,
    power_law_radius_cdf,
    sample_network,
    set_p32,
)

BOX = (0.0, 0.0, 0.0, 10.0, 10.0, 10.0)
ERR = 1.0 - math.sin(2.0 * math.pi / 720) * 720 / (2.0 * math.pi)  # inscribed 720-gon


def dset(**kw) -> DiscSet:
    args = {
        "name": "s",
        "trend": 30.0,
        "plunge": 60.0,
        "kappa": 20.0,
        "radius_min": 0.5,
        "radius_max": 5.0,
        "alpha": 2.5,
        "count": 10,
    }
    args.update(kw)
    return DiscSet(**args)


def fisher_mean_cos(kappa: float) -> float:
    """E[cos θ] = coth κ − 1/κ (Fisher 1953)."""
    return 1.0 / math.tanh(kappa) - 1.0 / kappa


def fisher_cos_cdf(c: np.ndarray, kappa: float) -> np.ndarray:
    """P(cos θ <= c) = (e^{κc} − e^{−κ})/(e^κ − e^{−κ}), without overflow for large κ."""
    return (np.exp(kappa * (c - 1.0)) - math.exp(-2.0 * kappa)) / (1.0 - math.exp(-2.0 * kappa))


def tpl_mean(rmin: float, rmax: float, alpha: float, k: int = 1) -> float:
    """E[R^k] of the pdf α r^(−α−1)/(rmin^−α − rmax^−α) on [rmin, rmax] (k != α)."""
    c = alpha / (rmin**-alpha - rmax**-alpha)
    return c * (rmax ** (k - alpha) - rmin ** (k - alpha)) / (k - alpha)


def one(centre, normal, radius, box=BOX, **kw) -> float:
    return float(
        clipped_area(
            (np.array([centre], float), np.array([normal], float), np.array([radius], float)),
            box,
            **kw,
        )[0]
    )


# --------------------------------------------------------------------------- DiscSet


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"radius_min": 6.0}, r"radius_min > radius_max \(6.0 > 5.0\)"),
        ({"radius_min": 0.0}, "radius_min must be > 0"),
        ({"radius_max": math.inf}, "radius_max must be finite"),
        ({"alpha": 0.0}, "alpha must be > 0"),
        ({"alpha": "2"}, "alpha must be a number"),
        ({"kappa": 0.0}, "kappa must be > 0"),
        ({"kappa": -math.inf}, "kappa must be finite"),
        ({"kappa": math.nan}, "kappa must be finite"),
        ({"trend": math.nan}, "trend must be finite"),
        ({"plunge": 91.0}, r"plunge must be in \[-90, 90\]"),
        ({"count": None}, "exactly one of p32 and count"),
        ({"p32": 0.1}, "exactly one of p32 and count"),
        ({"count": -1}, "count must be >= 0"),
        ({"count": 1.5}, "count must be an integer"),
        ({"count": True}, "count must be an integer"),
        ({"count": None, "p32": -0.1}, "p32 must be >= 0"),
        ({"count": None, "p32": math.inf}, "p32 must be finite"),
        ({"region": (0, 0, 0, 1, 1)}, "region: must be six numbers"),
        ({"region": (0, 0, 0, 1, 0, 1)}, "region: needs min < max"),
        ({"region": (0, 0, 0, 1, math.nan, 1)}, "region: coordinates must be finite"),
        ({"name": ""}, "non-empty string"),
        ({"name": "a,b"}, "must not contain commas"),
    ],
)
def test_disc_set_errors_name_the_field(kw, match):
    with pytest.raises(DfnError, match=match):
        dset(**kw)


def test_disc_set_error_names_the_set():
    with pytest.raises(DfnError, match="disc set 'joints': alpha must be > 0"):
        dset(name="joints", alpha=-1.0)


def test_disc_set_accepts_valid_fields():
    s = dset(
        kappa=math.inf, radius_min=2.0, radius_max=2.0, count=np.int64(3), region=[0] * 3 + [1] * 3
    )
    assert s.region == (0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
    assert dset(count=None, p32=0.0).p32 == 0.0


@pytest.mark.parametrize(
    ("trend", "plunge", "pole"),
    [
        (0.0, 0.0, (0, 1, 0)),
        (90.0, 0.0, (1, 0, 0)),
        (0.0, 90.0, (0, 0, -1)),
        (180.0, 45.0, (0, -1, -1)),
    ],
)
def test_mean_pole_follows_the_conventions(trend, plunge, pole):
    # trend clockwise from north (+y), plunge down (−z)
    want = np.array(pole, float) / np.linalg.norm(pole)
    np.testing.assert_allclose(dset(trend=trend, plunge=plunge).mean_pole, want, atol=1e-15)


# ---------------------------------------------------------------------- Fisher poles


def test_fisher_mean_cos_matches_closed_form():
    kappa, n = 20.0, 2000
    mean = pole_to_normal(30.0, 60.0)[0]
    poles = fisher_poles(np.random.default_rng(11), n, mean=mean, kappa=kappa)
    np.testing.assert_allclose(np.linalg.norm(poles, axis=1), 1.0, atol=1e-15)
    cos = poles @ mean
    a = fisher_mean_cos(kappa)
    # Var(cos θ) = E[cos²θ] − A² with E[cos²θ] = 1 − 2A/κ
    se = math.sqrt((1.0 - 2.0 * a / kappa - a * a) / n)
    assert abs(cos.mean() - a) < 3.3 * se  # 99.9 %
    # and the whole law of cos θ
    d = ks_statistic(cos, lambda c: fisher_cos_cdf(c, kappa))
    assert ks_pvalue(d, n) > 0.01


def test_fisher_azimuth_is_uniform_about_the_mean():
    mean = pole_to_normal(250.0, 15.0)[0]
    poles = fisher_poles(np.random.default_rng(12), 4000, mean=mean, kappa=5.0)
    # azimuths in a basis of our own choosing
    e1 = np.cross(mean, [0.0, 0.0, 1.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(mean, e1)
    az = np.mod(np.arctan2(poles @ e2, poles @ e1), 2 * np.pi)
    d = ks_statistic(az, lambda x: x / (2 * np.pi))
    assert ks_pvalue(d, len(az)) > 0.01


@pytest.mark.parametrize("kappa", [1e6, 1e9, 1e15])
def test_fisher_large_kappa_keeps_precision(kappa):
    # 1 − cos θ ~ Exp(κ) for large κ: mean 1/κ, sd 1/κ
    mean = np.array([0.0, 0.6, -0.8])
    poles = fisher_poles(np.random.default_rng(13), 10_000, mean=mean, kappa=kappa)
    assert np.all(np.isfinite(poles))
    one_minus_cos = 0.5 * np.sum((poles - mean) ** 2, axis=1)
    assert abs(kappa * one_minus_cos.mean() - 1.0) < 4.0 / math.sqrt(10_000)


def test_fisher_infinite_kappa_and_small_kappa():
    mean = np.array([1.0, 1.0, 0.0])
    rng = np.random.default_rng(14)
    poles = fisher_poles(rng, 5, mean=mean, kappa=math.inf)
    np.testing.assert_allclose(poles, np.tile(mean / math.sqrt(2), (5, 1)), atol=1e-15)
    # κ → 0: uniform on the sphere, E[cos θ] = κ/3 → 0, cos θ uniform on [−1, 1]
    cos = fisher_poles(rng, 4000, mean=mean, kappa=1e-9) @ (mean / math.sqrt(2))
    d = ks_statistic(cos, lambda c: (c + 1.0) / 2.0)
    assert ks_pvalue(d, len(cos)) > 0.01


def test_fisher_rejects_bad_arguments():
    rng = np.random.default_rng(0)
    with pytest.raises(DfnError, match="mean: must be a finite nonzero 3-vector"):
        fisher_poles(rng, 3, mean=[0, 0, 0], kappa=1.0)
    with pytest.raises(DfnError, match="kappa must be > 0"):
        fisher_poles(rng, 3, mean=[0, 0, 1], kappa=0.0)


# ----------------------------------------------------------------------- power law


def test_power_law_radii_follow_the_law():
    rmin, rmax, alpha, n = 0.5, 20.0, 2.5, 5000
    r = power_law_radii(np.random.default_rng(21), n, rmin=rmin, rmax=rmax, alpha=alpha)
    assert r.min() >= rmin and r.max() <= rmax

    def cdf(x):  # 1 − (x^−α − rmax^−α)/(rmin^−α − rmax^−α)
        return 1.0 - (x**-alpha - rmax**-alpha) / (rmin**-alpha - rmax**-alpha)

    d = ks_statistic(r, cdf)
    assert ks_pvalue(d, n) > 0.01
    mean = tpl_mean(rmin, rmax, alpha)
    se = math.sqrt((tpl_mean(rmin, rmax, alpha, 2) - mean**2) / n)
    assert abs(r.mean() - mean) < 3.3 * se
    # a wrong exponent is told apart
    d_wrong = ks_statistic(r, lambda x: 1.0 - (x**-2.0 - rmax**-2.0) / (rmin**-2.0 - rmax**-2.0))
    assert ks_pvalue(d_wrong, n) < 1e-6


def test_power_law_radius_cdf_closed_form():
    r = np.array([0.1, 1.0, 2.0, 4.0, 9.0])
    got = power_law_radius_cdf(r, rmin=1.0, rmax=4.0, alpha=2.0)
    # (1 − r^−2)/(1 − 1/16) on [1, 4]
    want = [0.0, 0.0, (1 - 0.25) / (15 / 16), 1.0, 1.0]
    np.testing.assert_allclose(got, want, atol=1e-15)


def test_constant_radius():
    r = power_law_radii(np.random.default_rng(0), 7, rmin=2.5, rmax=2.5, alpha=3.0)
    assert r.tolist() == [2.5] * 7


def test_power_law_rejects_bad_laws():
    with pytest.raises(DfnError, match="radius_min > radius_max"):
        power_law_radii(np.random.default_rng(0), 3, rmin=2.0, rmax=1.0, alpha=1.0)


# ---------------------------------------------------------------------- clipped area


def test_polygon_error_formula():
    assert polygon_area_error() == pytest.approx(ERR, rel=1e-12)
    assert 1.26e-5 < ERR < 1.28e-5


def test_disc_inside_has_the_polygon_area():
    assert one((5, 5, 5), (0.3, -0.2, 0.9), 2.0) == pytest.approx(
        math.pi * 4.0 * (1 - ERR), rel=1e-13
    )
    # a regular 12-gon inscribed in a circle of radius r has area 3r²
    assert one((5, 5, 5), (0, 0, 1), 2.0, sides=12) == pytest.approx(12.0, rel=1e-13)


@pytest.mark.parametrize("seed", range(4))
def test_disc_centred_on_a_face_normal_to_it_is_halved(seed):
    # centred on the face x = 0, its normal in the face: any such cut is through the centre
    t = np.random.default_rng(seed).uniform(0, np.pi)
    normal = (0.0, math.cos(t), math.sin(t))
    half = math.pi * 1.5**2 / 2
    assert one((0, 5, 5), normal, 1.5) == pytest.approx(half * (1 - ERR), rel=1e-12)
    assert one((10, 5, 5), normal, 1.5) == pytest.approx(half * (1 - ERR), rel=1e-12)


def test_disc_centred_on_an_edge_normal_to_it_is_quartered():
    quarter = math.pi / 4
    assert one((0, 0, 5), (0, 0, 1), 1.0) == pytest.approx(quarter * (1 - ERR), rel=1e-12)
    assert one((10, 5, 0), (0, 1, 0), 1.0) == pytest.approx(quarter * (1 - ERR), rel=1e-12)


def test_disc_through_an_edge_at_an_angle_gets_the_wedge():
    # plane x + y + z = 5 through (0, 0, 5): x >= 0, y >= 0 is a 60° wedge (the lines
    # x = 0 and y = 0 in it have directions (0, 1, −1) and (1, 0, −1))
    disc = math.pi / 6
    got = one((0, 0, 5), (1, 1, 1), 1.0)
    assert disc - ERR * math.pi <= got <= disc


@pytest.mark.parametrize("h", [0.0, 0.3, 0.9, -0.6])
def test_disc_cut_off_centre_by_a_face(h):
    # centre at distance h inside the face x = 0: area inside is π − segment beyond h
    # for h >= 0, the segment r²acos(h/r) − h√(r² − h²) itself for h < 0
    r = 1.0
    a = abs(h)
    segment = r * r * math.acos(a / r) - a * math.sqrt(r * r - a * a)
    disc = math.pi - segment if h >= 0 else segment
    got = one((h, 5, 5), (0, 0, 1), r)
    assert disc - ERR * math.pi <= got <= disc


def test_large_discs_give_the_box_cross_section():
    assert one((5, 5, 5), (0, 0, 1), 100.0) == pytest.approx(100.0, rel=1e-13)
    # the plane x + z = 10 cuts the box in a 10 × 10√2 rectangle
    assert one((5, 5, 5), (1, 0, 1), 100.0) == pytest.approx(100.0 * math.sqrt(2), rel=1e-13)


def test_disc_outside_has_no_area():
    assert one((-2, 5, 5), (0, 0, 1), 1.0) == 0.0
    assert one((5, 5, 11.5), (0.1, 0, 1), 1.0) == 0.0
    # its extent overlaps the box on every axis but the disc misses the corner
    assert one((-0.8, -0.8, 5), (0, 0, 1), 1.0) == 0.0


def test_clipped_area_is_per_disc_and_takes_a_network():
    rng = np.random.default_rng(5)
    n = sampling.CLIP_CHUNK + 40  # more than one chunk
    centre = rng.uniform(-2, 12, (n, 3))
    normal = rng.normal(size=(n, 3))
    radius = rng.uniform(0.5, 4.0, n)
    together = clipped_area((centre, normal, radius), BOX)
    alone = [one(c, v, r) for c, v, r in zip(centre[:50], normal[:50], radius[:50], strict=True)]
    assert together[:50].tolist() == alone  # bit for bit, whatever the neighbours
    assert np.all(together >= 0) and np.all(together <= np.pi * radius**2)
    net = DiscNetwork(
        centre,
        normal / np.linalg.norm(normal, axis=1)[:, None],
        radius,
        np.zeros(n, dtype=np.intp),
        ("a",),
    )
    np.testing.assert_allclose(clipped_area(net, BOX), together, rtol=1e-12, atol=1e-12)


def test_clipped_area_rejects_bad_input():
    with pytest.raises(DfnError, match="sides must be an integer >= 3"):
        one((5, 5, 5), (0, 0, 1), 1.0, sides=2)
    with pytest.raises(DfnError, match="box: needs min < max"):
        one((5, 5, 5), (0, 0, 1), 1.0, box=(0, 0, 0, 1, 1, 0))
    with pytest.raises(DfnError, match="radii must be > 0"):
        one((5, 5, 5), (0, 0, 1), 0.0)
    with pytest.raises(DfnError, match="nonzero"):
        one((5, 5, 5), (0, 0, 0), 1.0)


# -------------------------------------------------------------------------- networks


SETS = [
    dset(name="a", count=None, p32=0.4, trend=30.0, plunge=60.0, radius_max=3.0),
    dset(name="b", count=None, p32=0.2, trend=120.0, plunge=5.0, kappa=8.0),
    dset(name="c", count=150, trend=0.0, plunge=90.0, region=(2, 2, 2, 8, 8, 8)),
]


@pytest.fixture(scope="module")
def network() -> DiscNetwork:
    return sample_network(SETS, box=BOX, seed=7)


def test_p32_mode_stops_at_the_first_disc_reaching_the_target(network):
    volume = 1000.0
    got = set_p32(network, BOX)
    for i, s in enumerate(SETS[:2]):
        # the exact bound: P32 in [target, target + one disc's clipped area / V)
        mask = network.set_index == i
        area = clipped_area(network.subset(mask), BOX)
        assert s.p32 * (1 - 1e-12) <= got[i] < s.p32 + area[-1] / volume
        assert area[-1] <= math.pi * s.radius_max**2 * (1 - ERR) * (1 + 1e-12)
        assert area[:-1].sum() / volume < s.p32  # without the last disc it is not reached
    assert network_p32(network, BOX) == pytest.approx(got.sum(), rel=1e-12)


def test_count_mode_and_layout(network):
    assert network.set_names == ("a", "b", "c")
    counts = np.bincount(network.set_index, minlength=3)
    assert counts[2] == 150
    c = network.centre[network.set_index == 2]
    assert np.all((c >= 2) & (c <= 8))
    assert np.all(np.diff(network.set_index) >= 0)  # ordered by set
    assert np.all(network.normal[:, 2] >= 0)  # canonical normals
    np.testing.assert_allclose(np.linalg.norm(network.normal, axis=1), 1.0, atol=1e-15)
    r = network.radius[network.set_index == 0]
    assert r.min() >= 0.5 and r.max() <= 3.0


def test_centres_are_uniform_in_the_region():
    net = sample_network([dset(count=3000, region=(-1, 2, 0, 3, 4, 10))], box=BOX, seed=3)
    for axis, (lo, hi) in enumerate([(-1, 3), (2, 4), (0, 10)]):
        x = net.centre[:, axis]
        d = ks_statistic(x, lambda v, lo=lo, hi=hi: (v - lo) / (hi - lo))
        assert ks_pvalue(d, len(x)) > 0.01


def test_same_seed_same_network_other_seed_other(network):
    again = sample_network(SETS, box=BOX, seed=7)
    for field in ("centre", "normal", "radius", "set_index"):
        assert getattr(again, field).tobytes() == getattr(network, field).tobytes()
    other = sample_network(SETS, box=BOX, seed=8)
    assert other.size != network.size or not np.array_equal(other.centre, network.centre)
    assert not np.array_equal(other.radius[:10], network.radius[:10])


def test_sets_draw_from_their_own_streams(network):
    # adding set "c" after "a" and "b" leaves them unchanged; a P32 set is a prefix of
    # the same set drawn by count
    b = network.set_index == 1
    pair = sample_network([SETS[0], SETS[1]], box=BOX, seed=7)
    assert pair.centre[pair.set_index == 1].tobytes() == network.centre[b].tobytes()
    k = int(b.sum())
    by_count = sample_network(
        [SETS[0], dset(**{**_fields(SETS[1]), "p32": None, "count": k + 5})], box=BOX, seed=7
    )
    sel = by_count.set_index == 1
    assert by_count.centre[sel][:k].tobytes() == network.centre[b].tobytes()
    assert by_count.radius[sel][:k].tobytes() == network.radius[b].tobytes()


def _fields(s: DiscSet) -> dict:
    return {f: getattr(s, f) for f in s.__dataclass_fields__}


def test_zero_targets_give_empty_sets():
    net = sample_network([dset(count=0), dset(name="t", count=None, p32=0.0)], box=BOX, seed=1)
    assert net.size == 0 and net.set_names == ("s", "t")
    assert network_p32(net, BOX) == 0.0


def test_unreachable_p32_is_refused_at_once():
    far = dset(count=None, p32=0.1, radius_max=1.0, region=(20, 20, 20, 30, 30, 30))
    with pytest.raises(DfnError, match=r"disc set 's': p32 = 0.1 cannot be reached"):
        sample_network([far], box=BOX, seed=1)


def test_p32_cap(monkeypatch):
    monkeypatch.setattr(sampling, "MAX_P32_FRACTURES", 2 * sampling.BATCH)
    # centres barely reach the box: area comes in slowly
    s = dset(
        name="thin",
        count=None,
        p32=5.0,
        radius_min=0.5,
        radius_max=0.5,
        region=(10.4, 0, 0, 20, 10, 10),
    )
    with pytest.raises(
        DfnError,
        match=r"disc set 'thin': p32 = 5.0 \(area 5000 in the box\) "
        r"not reached with 2048 fractures",
    ):
        sample_network([s], box=BOX, seed=1)


@pytest.mark.parametrize(
    ("sets", "kw", "match"),
    [
        ([dset()], {"seed": -1}, "seed must be a non-negative integer"),
        ([dset()], {"seed": 1.5}, "seed must be a non-negative integer"),
        ([dset(), dset()], {"seed": 1}, r"set names must be distinct, repeated: \['s'\]"),
        (["s"], {"seed": 1}, r"sets\[0\] is not a DiscSet"),
    ],
)
def test_sample_network_rejects_bad_requests(sets, kw, match):
    with pytest.raises(DfnError, match=match):
        sample_network(sets, box=BOX, **kw)
