"""A 2D elastic block settling on a fixed floor: the throughput case of ``bench mpm``.

A square block of particles (two by two per cell, plane strain, E = 1e7, ν = 0.3,
ρ = 2000) stands on grid nodes held fixed at its base and is loaded by gravity; the
step is Courant number 0.1. It measures particle-steps per second of a scheme and
shape at a realistic particle count (``bench mpm`` defaults to 100k), not an accuracy. With a
communicator of more than one rank the grid is decomposed into slabs
(:mod:`~geofrac.mpm.parallel`) and every rank steps its own particles.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from geofrac.mpm import shapes
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, time_step

__all__ = ["Throughput", "gravity_block"]


@dataclass(frozen=True)
class Throughput:
    """A timed run.

    Attributes:
        particles: particles of the block (all ranks).
        steps: steps timed.
        seconds: wall seconds of the timed steps (the slowest rank).
        particle_steps_per_s: particles × steps / seconds.
        ranks: MPI ranks.
        warmup_seconds: the untimed first step (numba's compilation or cache load, the
            slowest rank).
        per_rank: each rank's own particle-steps per second of the wall time,
            shape=(ranks,).
        neighbour_builds: MLS neighbour-list builds within the timed steps (the most
            of any rank; the warm-up step's first build is not counted).
        neighbour_build_seconds: their wall seconds (the slowest rank), part of
            ``seconds``.
    """

    particles: int
    steps: int
    seconds: float
    particle_steps_per_s: float
    ranks: int = 1
    warmup_seconds: float = 0.0
    per_rank: tuple[float, ...] = ()
    neighbour_builds: int = 0
    neighbour_build_seconds: float = 0.0


def gravity_block(
    n_particles: int,
    scheme: str = "musl",
    shape: str = "mpm",
    *,
    smoothing: float | None = None,
    steps: int = 5,
    comm: Any = None,
    backend: str = "numba",
) -> Throughput:
    """Time ``steps`` steps (after one untimed step) of a block of about ``n_particles``.

    Args:
        n_particles: the block's particles (rounded to an even square).
        scheme: the update scheme.
        shape: the shape functions.
        smoothing: MLS radius in cells, or None.
        steps: steps timed.
        comm: an MPI communicator to decompose over (all its ranks call this), or None.
        backend: ``numba`` or ``numpy``.
    """
    side = max(2, 2 * round(np.sqrt(n_particles) / 2))
    h, cell, rho = 0.5, 1.0, 2000.0
    p = lattice([2.0, 2.0], [side, side], h, density=rho)
    n_total = p.n
    cells = side // 2 + 6
    g = grid([0.0, 0.0], cell, [cells, cells])
    dom = None
    if comm is not None and comm.size > 1:
        from geofrac.mpm.parallel import decompose

        dom = decompose(g, comm)
        g, p = dom.local, dom.distribute(p)
    mat = Elastic(1e7, 0.3)
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[g.nodes()[:, 1] <= 2.0] = True
    dt = time_step(0.1, cell, mat, density=rho, dim=2)
    s = StepSettings(
        scheme,
        shapes.get(shape),
        dt,
        np.array([0.0, -9.81]),
        fixed,
        smoothing,
        backend=backend,
        domain=dom,
    )
    t0 = time.perf_counter()
    step(g, p, mat, settings=s)
    warmup = time.perf_counter() - t0
    if dom is not None:
        comm.Barrier()
    if smoothing is not None:
        from geofrac.mpm.smoothing import neighbour_stats

        neighbour_stats(reset=True)
    done = 0
    t0 = time.perf_counter()
    for _ in range(steps):
        done += p.n
        step(g, p, mat, settings=s)
    if dom is not None:
        comm.Barrier()
    seconds = time.perf_counter() - t0
    builds, build_seconds = 0, 0.0
    if smoothing is not None:
        stats = neighbour_stats()
        builds, build_seconds = int(stats["builds"]), float(stats["build_seconds"])
    if dom is None:
        rate = n_total * steps / seconds
        return Throughput(n_total, steps, seconds, rate, 1, warmup, (rate,), builds, build_seconds)
    seconds, warmup = dom.allmax(seconds), dom.allmax(warmup)
    builds, build_seconds = int(dom.allmax(builds)), dom.allmax(build_seconds)
    per_rank = tuple(float(d) / seconds for d in comm.allgather(done))
    return Throughput(
        n_total, steps, seconds, n_total * steps / seconds, comm.size, warmup, per_rank,
        builds, build_seconds,
    )  # fmt: skip
