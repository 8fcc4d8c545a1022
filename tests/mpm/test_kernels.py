"""The compiled backend (geofrac.mpm.kernels) against the numpy reference."""

import copy
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from geofrac.mpm.elastic import Elastic
from geofrac.mpm.friction import friction
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.plasticity import DruckerPrager
from geofrac.mpm.schemes import SCHEMES, StepSettings, step, time_step
from geofrac.mpm.shapes import REGISTRY, Shape, compiled_weights, weights
from geofrac.mpm.smoothing import neighbour_pairs, smooth

FIELDS = ("x", "v", "stress", "stress_zz", "volume", "F", "lp", "plastic")


def _assert_close(p, q, rtol: float = 1e-12) -> None:
    """Every particle field of q equals p's to rtol (of the field's largest entry)."""
    for name in FIELDS:
        a, b = getattr(p, name), getattr(q, name)
        scale = max(float(np.abs(a).max(initial=0.0)), 1e-300)
        np.testing.assert_allclose(b, a, rtol=rtol, atol=rtol * scale, err_msg=name)


def _scene(dim: int, shape: str, scheme: str, smoothing: float | None):
    """A block thrown at a floor with friction, plastic in 2D/3D, elastic in 1D."""
    p = lattice([1.0] * dim, [6] * dim, 0.25, density=2.0)
    p.v = np.random.default_rng(dim).normal(scale=0.5, size=p.x.shape)
    g = grid(np.zeros(dim), 0.5, [8] * dim)
    mat = Elastic(1000.0, 0.3) if dim == 1 else DruckerPrager(1000.0, 0.3, 20.0, 1.0)
    X = g.nodes()
    fixed = np.zeros((g.num_nodes, dim), dtype=bool)
    fixed[X[:, -1] < 0.75] = True
    fr = None
    if dim > 1:
        floor = np.flatnonzero(np.isclose(X[:, -1], 1.0))
        normal = np.zeros(dim)
        normal[-1] = -1.0
        fr = friction(floor, np.tile(normal, (len(floor), 1)), 0.3)
    gravity = np.zeros(dim)
    gravity[-1] = -9.81
    dt = time_step(0.2, g.spacing, mat, density=2.0, dim=dim)
    s = StepSettings(scheme, shape, dt, gravity, fixed, smoothing, fr, backend="numpy")
    return g, p, mat, s


@pytest.mark.parametrize("smoothing", [None, 2.0])
@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("shape", REGISTRY)
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_numba_steps_equal_the_numpy_reference(dim, shape, scheme, smoothing):
    """20 steps with gravity, walls, friction, plasticity (2D/3D) and MLS: round-off."""
    g, p, mat, s = _scene(dim, shape, scheme, smoothing)
    q = copy.deepcopy(p)
    # a boundary carries its run's contact memory (Friction.held_vn): one per run
    fast = replace(s, backend="numba", friction=copy.deepcopy(s.friction))
    for _ in range(20):
        step(g, p, mat, settings=s)
        step(g, q, mat, settings=fast)
    assert np.abs(p.stress).max() > 0
    if dim > 1:
        assert p.plastic.max() > 0  # the return mapping was exercised
    _assert_close(p, q)


@pytest.mark.parametrize("shape", REGISTRY.values(), ids=str)
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_compiled_weights_equal_the_reference(dim, shape: Shape):
    rng = np.random.default_rng(7)
    g = grid(np.full(dim, -1.0), 0.5, [7] * dim)
    x = rng.uniform(-0.4, 2.0, size=(200, dim))
    x[0] = 0.5  # on a node
    lp = rng.uniform(0.05, 0.3, size=x.shape) if shape.boxes else None
    ref, got = weights(g, x, shape, lp=lp), compiled_weights(g, x, shape, lp=lp)
    np.testing.assert_array_equal(got.nodes, ref.nodes)
    np.testing.assert_allclose(got.phi, ref.phi, rtol=1e-14, atol=1e-15)
    np.testing.assert_allclose(got.grad, ref.grad, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_compiled_neighbour_search_and_fit_equal_the_reference(dim):
    from geofrac.mpm.kernels import bin_neighbours

    rng = np.random.default_rng(dim)
    x = rng.uniform(0.0, 2.0, size=(150 * dim, dim))
    h = 0.5 if dim < 3 else 0.8
    p, q = neighbour_pairs(x, h)
    starts, nbrs = bin_neighbours(x, h)
    np.testing.assert_array_equal(np.repeat(np.arange(len(x)), np.diff(starts)), p)
    np.testing.assert_array_equal(nbrs, q)
    values = rng.normal(size=(len(x), 3))
    ref, ref_done = smooth(x, values, h)
    got, done = smooth(x, values, h, backend="numba")
    np.testing.assert_array_equal(done, ref_done)
    np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-12 * np.abs(ref).max())


def test_numba_is_imported_only_by_a_compiled_step():
    """Nothing undeclared is compiled: importing the engine does not load numba."""
    probe = (
        "import sys\n"
        "import geofrac.mpm.schemes, geofrac.mpm.parallel, geofrac.mpm.bar\n"
        "from geofrac.bench.mpm import translating_bar\n"
        "print('numba' in sys.modules)\n"
        "from geofrac.mpm.schemes import StepSettings\n"
        "translating_bar('mpm', steps=3)\n"
        "print('numba' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


def test_particles_carry_ids():
    p = lattice([0.0, 0.0], [3, 2], 0.5, density=1.0)
    np.testing.assert_array_equal(p.ids, np.arange(6))
    assert p.ids.dtype == np.int64
    with pytest.raises(ValueError, match="backend 'cuda'"):
        replace(_scene(1, "mpm", "musl", None)[3], backend="cuda")
