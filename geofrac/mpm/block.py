"""A 2D elastic block settling on a fixed floor: the throughput case of ``bench mpm``.

A square block of particles (two by two per cell, plane strain, E = 1e7, ν = 0.3,
ρ = 2000) stands on grid nodes held fixed at its base and is loaded by gravity; the
step is Courant number 0.1. It measures particle-steps per second of a scheme and
shape at a realistic particle count (the issue's 100k), not an accuracy.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import Elastic, StepSettings, step, time_step

__all__ = ["Throughput", "gravity_block"]


@dataclass(frozen=True)
class Throughput:
    """Attributes: particles, steps timed, wall seconds, particle-steps per second."""

    particles: int
    steps: int
    seconds: float
    particle_steps_per_s: float


def gravity_block(
    n_particles: int,
    scheme: str = "musl",
    shape: str = "mpm",
    smoothing: float | None = None,
    steps: int = 5,
) -> Throughput:
    """Time ``steps`` steps (after one untimed step) of a block of about ``n_particles``."""
    side = max(2, 2 * round(np.sqrt(n_particles) / 2))
    h, cell, rho = 0.5, 1.0, 2000.0
    p = lattice([2.0, 2.0], [side, side], h, rho)
    cells = side // 2 + 6
    g = grid([0.0, 0.0], cell, [cells, cells])
    mat = Elastic(1e7, 0.3)
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[g.nodes()[:, 1] <= 2.0] = True
    dt = time_step(0.1, cell, mat, rho, 2)
    s = StepSettings(scheme, shape, dt, np.array([0.0, -9.81]), fixed, smoothing)
    step(g, p, mat, s)
    t0 = time.perf_counter()
    for _ in range(steps):
        step(g, p, mat, s)
    seconds = time.perf_counter() - t0
    return Throughput(p.n, steps, seconds, p.n * steps / seconds)
