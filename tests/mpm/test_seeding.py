"""Particles from cells and the geostatic initial stress (geofrac.mpm.seeding)."""

import numpy as np
import pytest

from geofrac.mpm.boundaries import boundary_rows, scene_grid
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, time_step
from geofrac.mpm.seeding import from_cells, geostatic


def test_one_particle_per_triangle_carries_its_area_and_centroid():
    points = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    cells = np.array([[0, 1, 2], [0, 2, 3]])
    p = from_cells(points, cells, np.array([1.0, 3.0]))
    assert p.volume.sum() == pytest.approx(2.0)
    np.testing.assert_allclose(p.x[0], [4 / 3, 1 / 3])
    np.testing.assert_allclose(p.mass, [1.0, 3.0])
    np.testing.assert_allclose(p.lp0, 0.5)  # a square of area 1 has half-width 1/2


def test_a_degenerate_cell_is_refused():
    points = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    with pytest.raises(ValueError, match="degenerate"):
        from_cells(points, np.array([[0, 1, 2]]), np.ones(1))


@pytest.mark.parametrize("dim", [2, 3])
def test_geostatic_stress_is_the_weight_above(dim):
    counts = [4, 10] if dim == 2 else [4, 2, 6]
    p = lattice([0.0] * dim, counts, 0.5, density=2000.0)
    g = np.zeros(dim)
    g[-1] = -10.0
    geostatic(p, g, 0.25, width=1.0)
    top = counts[-1] * 0.5
    sigma_v = -2000.0 * 10.0 * (top - p.x[:, -1])
    np.testing.assert_allclose(p.stress[:, -1, -1], sigma_v, rtol=1e-12)
    np.testing.assert_allclose(p.stress[:, 0, 0], sigma_v / 3, rtol=1e-12)  # K0 = 1/3
    if dim == 2:
        np.testing.assert_allclose(p.stress_zz, sigma_v / 3, rtol=1e-12)


def test_gravity_must_be_vertical_for_geostatic():
    p = lattice([0.0, 0.0], [2, 2], 0.5, density=1.0)
    with pytest.raises(ValueError, match="gravity along"):
        geostatic(p, np.array([1.0, -10.0]), 0.25, width=1.0)


def _settle(initial: bool) -> float:
    """Largest particle speed of elastic ground in a box (rollers, fixed floor), 200 steps."""
    g = scene_grid((0.0, 0.0), (8.0, 8.0), 1.0, padding=2)
    p = lattice([0.0, 0.0], [16, 8], 0.5, density=1000.0)
    mat = Elastic(1e6, 0.3)
    gravity = np.array([0.0, -10.0])
    if initial:
        geostatic(p, gravity, mat.nu, width=1.0)
    walls = {"x_min": "roller", "x_max": "roller", "y_min": "fixed"}
    fixed = boundary_rows(g, (0.0, 0.0), (8.0, 8.0), walls=walls, bed=())[0]
    s = StepSettings(
        "musl", "ugimp", time_step(0.2, 1.0, mat, density=1000.0, dim=2), gravity, fixed
    )
    for _ in range(200):
        step(g, p, mat, settings=s)
    return float(np.max(np.linalg.norm(p.v, axis=1)))


def test_confined_ground_with_its_geostatic_stress_stays_at_rest():
    """Stress-free, the ground settles and rings; with its at-rest stress it barely moves."""
    at_rest, falling = _settle(True), _settle(False)
    assert falling > 1e-3
    assert at_rest < 0.05 * falling
