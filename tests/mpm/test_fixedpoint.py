"""Exact sums (geofrac.mpm.fixedpoint) and the step's nodal sums built on them."""

import math
from fractions import Fraction

import numpy as np
import pytest

from geofrac.mpm.fixedpoint import accumulate, exact_sums, scales, to_float
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import MASS_FLOOR
from geofrac.mpm.shapes import HAT, REGISTRY, Shape, compiled_weights, get, weights


def test_sum_is_exact_where_floats_cancel():
    """1e16 + 1 − 1e16 is 1 (a float sum in this order gives 0), in any order."""
    values = np.array([[1e16], [1.0], [-1e16], [3.0], [-2.5]])
    assert float(np.sum(values[:3])) == 0.0
    assert exact_sums(values)[0] == 1.5
    assert exact_sums(values[::-1])[0] == 1.5


def test_sum_is_the_rounded_exact_sum_in_any_order():
    rng = np.random.default_rng(3)
    values = rng.normal(size=(5000, 3)) * np.exp(rng.uniform(-30, 5, size=(5000, 1)))
    got = exact_sums(values)
    for c in range(3):
        exact = sum(Fraction(v) for v in values[:, c])
        # the terms are on a grid of 2^(e − 102), 2^e above the largest
        grid_step = 2.0 ** (math.frexp(np.abs(values[:, c]).max())[1] + 1 - 102)
        assert abs(Fraction(got[c]) - exact) <= Fraction(math.ulp(got[c])) + 5000 * Fraction(
            grid_step
        )
    for seed in range(3):
        shuffled = values[np.random.default_rng(seed).permutation(len(values))]
        np.testing.assert_array_equal(exact_sums(shuffled), got)


def test_non_finite_column_turns_nan():
    values = np.array([[1.0, np.inf], [2.0, 1.0]])
    with np.errstate(invalid="ignore"):
        got = exact_sums(values)
    assert got[0] == 3.0 and np.isnan(got[1])


def _nodal(dim, shape, order):
    """Nodal mass and momentum pairs of a jittered block, the particles in ``order``."""
    rng = np.random.default_rng(dim)
    p = lattice([1.0] * dim, [6] * dim, 0.25, density=2.0)
    p.x += rng.uniform(-0.05, 0.05, p.x.shape)
    p.v = rng.normal(size=p.x.shape)
    p.x, p.v, p.mass, p.lp = p.x[order], p.v[order], p.mass[order], p.lp[order]
    g = grid(np.zeros(dim), 0.5, [6] * dim)
    w = weights(g, p.x, get(shape), lp=p.lp)
    return g, p, w


@pytest.mark.parametrize("shape", REGISTRY)
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_compiled_nodal_sums_are_the_reference_integers_in_any_order(dim, shape):
    from geofrac.mpm import kernels

    n = 6**dim
    g, p, w = _nodal(dim, shape, np.arange(n))
    terms = np.concatenate(
        [
            (w.phi * p.mass[:, None])[:, :, None],
            w.phi[:, :, None] * (p.mass[:, None] * p.v)[:, None],
        ],
        axis=2,
    )
    bound = np.abs(terms).max(axis=(0, 1))
    ref = accumulate(w.nodes, terms, scales(bound), num=g.num_nodes)
    for seed in range(3):
        order = np.random.default_rng(seed).permutation(n)
        _, q, wq = _nodal(dim, shape, order)
        acc = np.zeros((g.num_nodes, 1 + dim, 2), np.int64)
        kernels.mass_momentum(wq.nodes, wq.phi, q.mass, q.v, scales(bound), acc)
        np.testing.assert_array_equal(acc, ref)
    # the float of the pairs is the sum of the terms, to round-off
    mass = to_float(ref, bound)[:, 0]
    assert mass.sum() == pytest.approx(p.mass.sum(), rel=1e-14)


def test_light_nodes_keep_their_digits():
    """Nodes 1e-13 of the heaviest (below the mass floor): relative error 1e-16."""
    rng = np.random.default_rng(5)
    heavy = lattice([1.0, 1.0], [8, 8], 0.25, density=2.0)
    x = np.concatenate([heavy.x, [[4.3, 3.1], [4.6, 3.35]]])  # two far from the block
    mass = np.concatenate([heavy.mass * rng.uniform(0.5, 2.0, heavy.n), [1e-13, 3e-14]])
    g = grid(np.zeros(2), 0.5, [10, 10])
    w = weights(g, x, HAT)
    terms = (w.phi * mass[:, None])[:, :, None]
    bound = np.abs(terms).max(axis=(0, 1))
    got = to_float(accumulate(w.nodes, terms, scales(bound), num=g.num_nodes), bound)[:, 0]
    exact = [Fraction(0)] * g.num_nodes
    for i in range(len(x)):
        for c in range(w.nodes.shape[1]):
            exact[w.nodes[i, c]] += Fraction(float(terms[i, c, 0]))
    light = [j for j in range(g.num_nodes) if 0 < exact[j] < MASS_FLOOR * got.max()]
    assert len(light) >= 4
    for j in range(g.num_nodes):
        assert abs(Fraction(got[j]) - exact[j]) <= Fraction(1e-16) * exact[j]


@pytest.mark.parametrize("shape", REGISTRY.values(), ids=str)
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_weights_stay_within_the_bounds_the_step_scales_by(dim, shape: Shape):
    """0 <= φ <= phi_bound and |∂φ/∂x| <= grad_bound/L, the bounds the step scales by.

    Every registered shape, numpy and compiled weights: the hat and GIMP (eqs. 4.29,
    4.31, half-widths up to L/2) have 1 and 1/L; the quadratic B-spline N <= 3/4 and
    |N'| <= 1/L (its largest slope, at |r| = L/2), so a tensor product's gradient is at
    most 1/L.
    """
    rng = np.random.default_rng(dim)
    g = grid(np.zeros(dim), 0.5, [8] * dim)
    x = rng.uniform(1.0, 3.0, size=(3000, dim))
    lp = rng.uniform(0.01, 0.25, size=x.shape) if shape.boxes else None
    spline = shape.name == "bspline2"
    for w in (weights(g, x, shape, lp=lp), compiled_weights(g, x, shape, lp=lp)):
        assert w.phi.min() >= 0.0 and w.phi.max() <= shape.phi_bound
        assert np.abs(w.grad).max() <= shape.grad_bound / g.spacing * (1 + 1e-15)
        if spline:  # nearly reached: N'(L/2) = 1/L times N = 3/4 across, per other axis
            assert np.abs(w.grad).max() > 0.9 * 0.75 ** (dim - 1) / g.spacing
