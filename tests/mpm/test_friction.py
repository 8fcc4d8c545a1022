"""Coulomb friction on boundary nodes (seed eqs. 4.44-4.47)."""

import numpy as np
import pytest

from geofrac.mpm.friction import apply_friction, friction
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import SCHEMES, Elastic, StepSettings, step, time_step


def test_contact_slip_stick_and_separation_on_single_nodes():
    fr = friction(np.arange(4), np.tile([0.0, -2.0], (4, 1)), mu=0.5)  # normal normalised
    v = np.array(
        [
            [1.0, 0.5],  # moving away from the floor: free
            [2.0, -1.0],  # into it, fast slip: tangential 2 - 0.5 * 1
            [0.3, -1.0],  # into it, slow: sticks (0.3 < 0.5 * 1)
            [-2.0, -0.2],  # slip to the left: -2 + 0.1
        ]
    )
    out = apply_friction(v.copy(), fr)
    np.testing.assert_allclose(out, [[1.0, 0.5], [1.5, 0.0], [0.0, 0.0], [-1.9, 0.0]])
    # without friction only the approach is removed
    out = apply_friction(v.copy(), fr, sliding_only=True)
    np.testing.assert_allclose(out, [[1.0, 0.5], [2.0, 0.0], [0.3, 0.0], [-2.0, 0.0]])
    with pytest.raises(ValueError, match="mu"):
        friction([0], [[0.0, 1.0]], -0.1)


def sliding_block(shape: str, scheme: str, mu: float, t_end: float = 0.8):
    """A 2D block (4 x 2, ρ = 1000, E = 1e6) sliding at 1.5 on a floor under g = 10.

    Returns (distance travelled by the centre of mass, its final velocity).
    """
    cell, h, g0, v0 = 0.25, 0.125, 10.0, 1.5
    p = lattice([1.0, 1.0], [16, 8], h, 1000.0)
    p.v[:, 0] = v0
    g = grid([0.0, 0.0], cell, [24, 12])
    X = g.nodes()
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[X[:, 1] < 1.0 - 1e-9] = True  # the ground below the floor
    floor = np.flatnonzero(np.isclose(X[:, 1], 1.0))
    fr = friction(floor, np.tile([0.0, -1.0], (len(floor), 1)), mu)
    mat = Elastic(1e6, 0.3)
    dt = time_step(0.2, cell, mat, 1000.0, 2)
    s = StepSettings(scheme, shape, dt, np.array([0.0, -g0]), fixed, friction=fr)
    x0 = p.x[:, 0] @ p.mass
    for _ in range(round(t_end / dt)):
        step(g, p, mat, s)
    m = p.mass.sum()
    return (p.x[:, 0] @ p.mass - x0) / m, (p.v[:, 0] @ p.mass) / m


@pytest.mark.parametrize("scheme", SCHEMES)
@pytest.mark.parametrize("shape", ["mpm", "cpgimp"])
def test_block_sliding_on_a_floor_stops_where_coulomb_says(shape, scheme):
    """Deceleration μg: the block stops after v₀²/(2μg) = 0.375 (within 5 %) and rests."""
    distance, v = sliding_block(shape, scheme, mu=0.3)
    assert distance == pytest.approx(1.5**2 / (2 * 0.3 * 10.0), rel=0.05)
    assert abs(v) < 0.05


def test_frictionless_floor_lets_the_block_slide_on():
    distance, v = sliding_block("cpgimp", "musl", mu=0.0, t_end=0.4)
    assert v == pytest.approx(1.5, rel=1e-3)
    assert distance == pytest.approx(1.5 * 0.4, rel=1e-2)
