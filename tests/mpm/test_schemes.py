"""MPM steps: conservation in the transfers, rigid motion, the quasi-static bar (eq. 4.73)."""

import numpy as np
import pytest

from geofrac.mpm.elastic import Elastic
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice, particles
from geofrac.mpm.schemes import (
    SCHEMES,
    ParticlesLeftGrid,
    StepSettings,
    _nodal_velocity,
    _to_grid,
    step,
    strain_energy,
    time_step,
)
from geofrac.mpm.shapes import REGISTRY, get, weights


def _block(dim: int, n_side: int = 6, h: float = 0.25):
    """Particles filling a cube of side n_side·h at 1.0, two per cell of size 2h."""
    return lattice([1.0] * dim, [n_side] * dim, h, density=2.0)


@pytest.mark.parametrize("shape", REGISTRY)
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_transfers_conserve_mass_and_momentum(dim, shape):
    rng = np.random.default_rng(dim)
    p = _block(dim)
    p.x += rng.uniform(-0.05, 0.05, p.x.shape)
    p.v = rng.normal(size=p.x.shape)
    g = grid(np.zeros(dim), 0.5, [6] * dim)
    w = weights(g, p.x, get(shape), lp=p.lp)
    mass = _to_grid(w, p.mass[:, None], g.num_nodes)[:, 0]
    assert mass.sum() == pytest.approx(p.mass.sum(), rel=1e-14)
    active = mass > 0
    v = _nodal_velocity(w, p, mass, active, np.zeros((g.num_nodes, dim), bool))
    np.testing.assert_allclose(mass @ v, p.momentum(), rtol=1e-13, atol=1e-13)


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("shape", REGISTRY)
@pytest.mark.parametrize("dim", [2, 3])
def test_uniformly_moving_block_stays_stress_free(dim, shape, scheme):
    """A block translating through cells: no stress, no change of velocity, 400 steps."""
    p = _block(dim)
    v0 = np.array([0.7, -0.4, 0.3][:dim])
    p.v[:] = v0
    mat = Elastic(E=1000.0, nu=0.3)
    g = grid(np.zeros(dim), 0.5, [8] * dim)
    dt = time_step(0.2, g.spacing, mat, density=2.0, dim=dim)
    s = StepSettings(scheme, shape, dt, np.zeros(dim), np.zeros((g.num_nodes, dim), bool))
    x0 = p.x.copy()
    for _ in range(400):
        step(g, p, mat, settings=s)
    assert np.abs(p.stress).max() < 1e-9 * mat.E
    np.testing.assert_allclose(p.v, np.broadcast_to(v0, p.v.shape), atol=1e-12)
    np.testing.assert_allclose(p.x, x0 + 400 * dt * v0, atol=1e-10)
    # it crossed more than one cell
    assert np.abs(400 * dt * v0).max() > g.spacing


def test_particle_leaving_the_grid_is_reported_and_nothing_changes():
    p = particles(np.array([[0.5], [3.8]]), np.ones(2), 1.0, lp0=np.full((2, 1), 0.25))
    p.v[1] = 5.0
    g = grid([0.0], 1.0, [4])
    mat = Elastic(100.0)
    s = StepSettings("musl", "ugimp", 0.01, np.zeros(1), np.zeros((g.num_nodes, 1), bool))
    with pytest.raises(ParticlesLeftGrid, match="1 particle") as info:
        step(g, p, mat, settings=s)
    assert info.value.ids.tolist() == [1]
    np.testing.assert_array_equal(p.x[:, 0], [0.5, 3.8])


def test_strain_energy_matches_half_sigma_epsilon():
    """½ σ:ε V for a known plane-strain state and a 1D bar."""
    mat = Elastic(E=200.0, nu=0.25)
    p = _block(2, n_side=1)
    eps = np.array([[1e-3, 2e-4], [2e-4, -5e-4]])
    p.stress[0] = mat.increment(eps[None])[0]
    p.stress_zz[0] = mat.lame()[0] * np.trace(eps)  # plane strain: ε_zz = 0
    assert strain_energy(p, mat) == pytest.approx(0.5 * np.sum(p.stress[0] * eps) * p.volume[0])
    # a 2D elastic step stores that σ_zz itself
    g = grid([0.0, 0.0], 0.5, [6, 6])
    q = _block(2)
    q.v[:, 0] = 0.1 * (q.x[:, 0] - 1.75)  # a uniform stretching in x
    fixed = np.zeros((g.num_nodes, 2), bool)
    step(g, q, mat, settings=StepSettings("usf", "mpm", 1e-3, np.zeros(2), fixed))
    np.testing.assert_allclose(q.stress_zz, mat.nu * np.trace(q.stress, axis1=1, axis2=2))
    bar = _block(1, n_side=1)
    bar.stress[0, 0, 0] = 3.0
    assert strain_energy(bar, mat) == pytest.approx(0.5 * 9.0 / 200.0 * bar.volume[0])


def test_bad_settings_are_refused():
    fixed = np.zeros((2, 1), bool)
    with pytest.raises(ValueError, match="scheme 'usl'"):
        StepSettings("usl", "mpm", 0.1, np.zeros(1), fixed)
    with pytest.raises(ValueError, match="shape 'gimp'"):
        StepSettings("musl", "gimp", 0.1, np.zeros(1), fixed)
    with pytest.raises(ValueError, match="Courant"):
        time_step(1.2, 1.0, Elastic(1.0), density=1.0, dim=1)


def test_smoothing_code_is_not_loaded_unless_asked():
    """Ask 3 at the engine level: a step without smoothing never imports its module."""
    import subprocess
    import sys

    probe = (
        "import sys, numpy as np\n"
        "from geofrac.bench.mpm import translating_bar\n"
        "translating_bar('mpm', steps=5)\n"
        "print('geofrac.mpm.smoothing' in sys.modules)\n"
        "translating_bar('mpm', smoothing=2.0, steps=5)\n"
        "print('geofrac.mpm.smoothing' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


def test_unstable_step_raises_instead_of_carrying_nan():
    """A time step far above the Courant limit blows up; the step says so, no NaN goes on."""
    from geofrac.errors import RunError

    h = 0.25
    p = particles(
        (1000.0 + (np.arange(8) + 0.5) * h)[:, None], np.full(8, h), 2.0, lp0=np.full((8, 1), h / 2)
    )
    p.v[:, 0] = np.linspace(-1.0, 1.0, p.n)
    mat = Elastic(E=1e4)
    g = grid([0.0], 0.5, [4000])  # far from the grid's ends: the particles cannot leave it
    dt = 50 * g.spacing / mat.wave_speed(2.0, 1)  # Courant number 50
    s = StepSettings("musl", "mpm", dt, np.zeros(1), np.zeros((g.num_nodes, 1), bool))
    with pytest.raises(RunError, match="non-positive volume") as info:
        for _ in range(20):
            step(g, p, mat, settings=s)
    assert not isinstance(info.value, ParticlesLeftGrid)
