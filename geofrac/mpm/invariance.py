"""Rank invariance over long runs: one set-up stepped serially and decomposed, compared.

Two long-running set-ups, each run twice on every rank of a communicator: serially (the
whole grid, this rank alone) and decomposed over the communicator
(:mod:`~geofrac.mpm.parallel`). Every ``every`` steps rank 0 gathers the decomposed
particles in id order and records the largest difference from the serial ones, relative
to the field's largest entry, and the difference of the energies (kinetic, strain),
relative to the initial total:

- ``translating``: the translating bar of Edo (2016), sec. 4.5.3 (E = 500, ρ = 1, length
  5, v₀ = 2, cell 0.5, Courant number 0.1, walls at x = 0 and 50; the same set-up as
  :func:`geofrac.bench.mpm.translating_bar`), to t = 100. On 2 ranks the slabs meet at
  x = 25, the bar's centre at the start: the bar crosses the rank boundary at every
  pass between the walls.
- ``sliding``: a 2D elastic block of 8 × 4 particles thrown at 2 m/s along a frictional
  floor (μ = 0.3) under gravity, between two walls, across the rank boundary.

With nodal sums that depend on the particle order, the two runs drift apart from the
last bit on (the translating bar from t ≈ 15); with the exact sums of
:mod:`~geofrac.mpm.fixedpoint` they stay equal, to the last bit.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from geofrac.mpm import shapes
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.grid import Grid, grid
from geofrac.mpm.particles import Particles, lattice
from geofrac.mpm.schemes import StepSettings, particle_strain_energy, step, time_step

__all__ = ["CASES", "Divergence", "compare_ranks"]

#: The set-ups of :func:`compare_ranks`.
CASES = ("translating", "sliding")

#: The fields compared.
FIELDS = ("x", "v", "stress", "volume", "F", "lp")


@dataclass(frozen=True)
class Divergence:
    """Serial against decomposed, sampled along a run (rank 0's view).

    Attributes:
        case: the set-up (one of :data:`CASES`).
        shape: the shape functions.
        scheme: the update scheme.
        ranks: ranks of the decomposed run.
        steps: steps taken.
        t: the sample times, shape=(k,).
        fields: per sample, the largest |decomposed − serial| over the particles and
            :data:`FIELDS`, each relative to the serial field's largest entry,
            shape=(k,).
        energy: per sample, the largest |decomposed − serial| of the kinetic and the
            strain energy, relative to the initial total, shape=(k,).
        crossed: particles that changed rank at least once.
        seconds: wall seconds of the serial and the decomposed steps (this rank).
    """

    case: str
    shape: str
    scheme: str
    ranks: int
    steps: int
    t: np.ndarray
    fields: np.ndarray
    energy: np.ndarray
    crossed: int
    seconds: tuple[float, float]

    def first_above(self, tol: float) -> float | None:
        """The first sample time where a field or energy differs by more than ``tol``."""
        above = np.flatnonzero((self.fields > tol) | (self.energy > tol))
        return float(self.t[above[0]]) if len(above) else None

    @property
    def worst(self) -> float:
        """The largest relative difference of any field or energy over the run."""
        return float(max(self.fields.max(initial=0.0), self.energy.max(initial=0.0)))


def _translating(shape: str, scheme: str) -> tuple[Grid, Particles, Elastic, Any]:
    """The translating bar of sec. 4.5.3 (as :func:`geofrac.bench.mpm.translating_bar`)."""
    E, rho, length, v0, cell, ppc = 500.0, 1.0, 5.0, 2.0, 0.5, 2
    n = round(length / cell) * ppc
    p = lattice([25.0 - length / 2], [n], length / n, density=rho)
    p.v[:] = v0
    g = grid([-2 * cell], cell, [round(50.0 / cell) + 4])
    mat = Elastic(E)
    dt = time_step(0.1, cell, mat, density=rho, dim=1)

    def settings(local: Grid, domain: Any) -> StepSettings:
        X = local.nodes()[:, 0]
        fixed = ((X <= 0.0) | (X >= 50.0)).reshape(-1, 1)
        return StepSettings(scheme, shapes.get(shape), dt, np.zeros(1), fixed, domain=domain)

    return g, p, mat, settings


def _sliding(shape: str, scheme: str) -> tuple[Grid, Particles, Elastic, Any]:
    """A block sliding on a frictional floor into a wall, gravity on, across the slabs."""
    from geofrac.mpm.friction import friction

    g = grid([0.0, 0.0], 0.25, [16, 8])
    rho = 1000.0
    p = lattice([1.0, 0.5], [8, 4], 0.125, density=rho)
    p.v[:, 0] = 2.0
    mat = Elastic(1e5, 0.3)
    dt = time_step(0.2, g.spacing, mat, density=rho, dim=2)

    def settings(local: Grid, domain: Any) -> StepSettings:
        X = local.nodes()
        fixed = np.zeros((local.num_nodes, 2), dtype=bool)
        fixed[X[:, 1] < 0.5 - 1e-9] = True  # the ground
        fixed[(X[:, 0] < 0.5 - 1e-9) | (X[:, 0] > 3.5 + 1e-9), 0] = True  # the walls
        floor = np.flatnonzero(np.isclose(X[:, 1], 0.5))
        fr = friction(floor, np.tile([0.0, -1.0], (len(floor), 1)), 0.3)
        gravity = np.array([0.0, -9.81])
        return StepSettings(
            scheme, shapes.get(shape), dt, gravity, fixed, friction=fr, domain=domain
        )

    return g, p, mat, settings


def _energies(p: Particles, mat: Elastic, comm: Any) -> np.ndarray:
    """(kinetic, strain) of the particles over ``comm``'s ranks, exact sums."""
    from geofrac.mpm.fixedpoint import exact_sums

    per = np.stack([0.5 * p.mass * np.sum(p.v**2, axis=1), particle_strain_energy(p, mat)], 1)
    return exact_sums(per, comm)


def compare_ranks(
    comm: Any,
    case: str,
    shape: str = "ugimp",
    *,
    scheme: str = "musl",
    steps: int | None = None,
    samples: int = 200,
    t_end: float | None = None,
) -> Divergence | None:
    """Run ``case`` serially and decomposed over ``comm`` (every rank calls this).

    Args:
        comm: the MPI communicator of the decomposed run.
        case: one of :data:`CASES`.
        shape: the shape functions.
        scheme: the update scheme.
        steps: steps to take; None: the translating bar to ``t_end``, the sliding block
            1e5 steps.
        samples: about this many comparisons along the run.
        t_end: the translating bar's end time when ``steps`` is None (None: 100).

    Returns:
        The comparison on rank 0, None on the others.
    """
    from mpi4py import MPI

    from geofrac.mpm.parallel import decompose

    if case not in CASES:
        raise ValueError(f"case {case!r} is not one of {', '.join(CASES)}")
    g, whole, mat, settings = (_translating if case == "translating" else _sliding)(shape, scheme)
    s = settings(g, None)
    if steps is None:
        steps = int(np.ceil((t_end or 100.0) / s.dt)) if case == "translating" else 100_000
    dom = decompose(g, comm)
    serial, mine = copy.deepcopy(whole), dom.distribute(whole)
    sd = settings(dom.local, dom)
    start_owner = dom.owner(whole.x)
    e0 = float(np.sum(_energies(serial, mat, MPI.COMM_SELF)))
    every = max(1, steps // samples)
    t, diff, denergy, crossed = [], [], [], set()
    spent = [0.0, 0.0]
    for k in range(1, steps + 1):
        t0 = time.perf_counter()
        step(g, serial, mat, settings=s)
        t1 = time.perf_counter()
        step(dom.local, mine, mat, settings=sd)
        spent[0] += t1 - t0
        spent[1] += time.perf_counter() - t1
        crossed.update(mine.ids[start_owner[mine.ids] != comm.rank].tolist())
        if k % every and k != steps:
            continue
        e_dec = _energies(mine, mat, comm)
        e_ser = _energies(serial, mat, MPI.COMM_SELF)
        gathered = dom.gather(mine)
        if comm.rank == 0:
            worst = 0.0
            for name in FIELDS:
                a, b = getattr(serial, name), getattr(gathered, name)
                scale = max(float(np.abs(a).max()), 1e-300)
                worst = max(worst, float(np.abs(b - a).max()) / scale)
            t.append(k * s.dt)
            diff.append(worst)
            denergy.append(float(np.abs(e_dec - e_ser).max()) / max(e0, 1e-300))
    n_crossed = int(comm.allreduce(len(crossed)))
    if comm.rank != 0:
        return None
    return Divergence(
        case, shape, scheme, int(comm.size), steps, np.array(t), np.array(diff),
        np.array(denergy), n_crossed, (spent[0], spent[1]),
    )  # fmt: skip
