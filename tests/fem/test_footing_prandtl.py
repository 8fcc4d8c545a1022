"""Prandtl's strip footing (jobs/footing_prandtl.toml): collapse pressure (2 + π) c.

A rigid smooth strip footing of width B = 2 pushed into weightless Tresca soil (φ = ψ =
0, c = 100) by a prescribed settlement ramped with the load factor (displacement
control). The reference is Prandtl's (1920) closed form q = (2 + π) c, written here;
the measured pressure is the footing's reaction over the half-width B/2. Also the
ramped Dirichlet values themselves, against uniaxial plane strain in closed form.
"""

from __future__ import annotations

import math
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.fem.plastic import PlasticProblem
from geofrac.plasticity import MohrCoulomb
from tests.fem.helpers import solve_job

#: cohesion of the job, and the half-width B/2 the reaction acts over.
COHESION = 100.0
HALF_WIDTH = 1.0
#: Prandtl (1920): the collapse pressure of a strip footing on weightless φ = 0 soil.
PRANDTL = (2.0 + math.pi) * COHESION
#: the coarse mesh of the test (the job is finer: h = 0.25, hf = 0.025).
COARSE = ("geometry.parameters.h=0.5", "geometry.parameters.hf=0.05")
#: the settlement the job prescribes on the footing.
SETTLEMENT = -0.05


def _curve(results: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """(load factors, footing pressures) of the accepted steps, shape=(n,) each."""
    steps = [s for s in results["plasticity"]["steps"] if s["accepted"]]
    factors = np.array([s["factor"] for s in steps])
    pressure = np.array([-s["reactions"]["footing"][1] / HALF_WIDTH for s in steps])
    return factors, pressure


@pytest.fixture(scope="module")
def coarse() -> dict[str, Any]:
    """The job on the coarse mesh (frontal-Delaunay, 403 cells: 8-14 s)."""
    solution = solve_job("footing_prandtl", *COARSE)
    try:
        return solution.results
    finally:
        solution.problem.destroy()


def test_collapse_pressure_within_3_percent(coarse: dict[str, Any]) -> None:
    """The plateau of the load-settlement curve is (2 + π) c within 3 % (measured +1.46 %).

    The plateau: over the last fifth of the settlement (the last five accepted steps)
    the pressure changes by less than 0.2 % (perfect plasticity at collapse: measured
    0.02 %).
    """
    plastic = coarse["plasticity"]
    assert plastic["converged"] and plastic["factor"] == 1.0
    _, q = _curve(coarse)
    assert len(q) >= 5
    assert abs(q[-1] - q[-5]) <= 2e-3 * q[-1]
    assert q[-1] == pytest.approx(PRANDTL, rel=0.03)
    assert q[0] < 0.5 * PRANDTL  # the curve rises to the plateau: not a wrong scale


def test_p3_passes_where_p2_overshoots() -> None:
    """P3 on the coarsest mesh (h = 1, hf = 0.2: 100 cells, about 13 s): within 3 %.

    Measured +2.03 % (P2 on the same mesh: +5.10 %, the overshoot that refinement
    removes, docs/plasticity.md); the plateau flat to 0.2 %.
    """
    solution = solve_job(
        "footing_prandtl",
        "geometry.parameters.h=1.0",
        "geometry.parameters.hf=0.2",
        "discretization.element=p3",
    )
    try:
        results = solution.results
    finally:
        solution.problem.destroy()
    assert results["plasticity"]["converged"]
    _, q = _curve(results)
    assert abs(q[-1] - q[-5]) <= 2e-3 * q[-1]
    assert q[-1] == pytest.approx(PRANDTL, rel=0.03)


def test_reactions_balance_and_footing_settles(coarse: dict[str, Any]) -> None:
    """Weightless and unloaded: the supports' vertical reactions sum to zero.

    To 1e-8 of the footing's (at every accepted step); the footing's centre ends at the
    prescribed settlement.
    """
    for s in coarse["plasticity"]["steps"]:
        if not s["accepted"]:
            continue
        r = s["reactions"]
        assert abs(sum(v[1] for v in r.values())) <= 1e-8 * abs(r["footing"][1])
    assert coarse["probes"]["centre"][1] == pytest.approx(SETTLEMENT, rel=1e-10)


def _column(comm: MPI.Comm, steps: int) -> tuple[list[Any], float, float]:
    """Elastic square column on rollers, top pushed down by δ ramped: (observed, g after, δ)."""
    mesh = dolfinx.mesh.create_unit_square(comm, 3, 3)
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))
    delta = -0.01

    def dofs(axis: int, where: float, comp: int) -> np.ndarray:
        facets = dolfinx.mesh.locate_entities_boundary(
            mesh, 1, lambda x: np.isclose(x[axis], where)
        )
        return dolfinx.fem.locate_dofs_topological(V.sub(comp), 1, facets)

    top = dofs(1, 1.0, 1)
    bcs = [
        dolfinx.fem.dirichletbc(np.float64(0.0), dofs(0, 0.0, 0), V.sub(0)),
        dolfinx.fem.dirichletbc(np.float64(0.0), dofs(1, 0.0, 1), V.sub(1)),
        dolfinx.fem.dirichletbc(np.float64(delta), top, V.sub(1)),
    ]
    law = MohrCoulomb(E=1000.0, nu=0.3, cohesion=1e8, friction_angle=0.0)

    def external(factor: Any, v: Any) -> Any:
        return ufl.inner(ufl.as_vector([0.0, 0.0]), v) * ufl.dx(domain=mesh)

    owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs

    def observe(p: PlasticProblem) -> tuple[float, float, float]:
        mine = top[top < owned]
        r = comm.allreduce(float(np.sum(p.residual()[mine])), op=MPI.SUM)
        lo = comm.allreduce(float(p.u.x.array[mine].min(initial=np.inf)), op=MPI.MIN)
        hi = comm.allreduce(float(p.u.x.array[mine].max(initial=-np.inf)), op=MPI.MAX)
        return r, lo, hi

    problem = PlasticProblem(V, law, external, bcs=bcs)
    try:
        result = problem.solve_steps(steps, observe=observe)
    finally:
        problem.destroy()
    assert result.converged
    return [(s.factor, *s.observed) for s in result.steps], float(bcs[2].g.value), delta


def test_prescribed_displacement_ramped_with_the_factor() -> None:
    """Displacement control: the top is at λ δ at each step, its reaction λ δ E/(1 − ν²).

    Uniaxial plane strain with σ_xx = 0 (free side), closed form; to 1e-9. After the
    run the Dirichlet value is δ again (restored: a shared condition is left as found).
    """
    observed, after, delta = _column(MPI.COMM_WORLD, 4)
    assert len(observed) == 4
    stiffness = 1000.0 / (1.0 - 0.3**2)
    for factor, reaction, lo, hi in observed:
        assert lo == pytest.approx(factor * delta, rel=1e-12)
        assert hi == pytest.approx(factor * delta, rel=1e-12)
        assert reaction == pytest.approx(factor * delta * stiffness, rel=1e-9)
    assert after == delta


@pytest.mark.mpi(min_size=2)
def test_two_ranks_same_footing_curve() -> None:
    """The distributed footing's curve equals each rank's serial one (to 100 Newton rtol)."""
    world = MPI.COMM_WORLD
    curves = []
    for comm in (world, MPI.COMM_SELF):
        solution = solve_job(
            "footing_prandtl",
            "geometry.parameters.h=1.0",
            "geometry.parameters.hf=0.2",
            "plasticity.load_steps=8",
            comm=comm,
        )
        try:
            curves.append(_curve(solution.results))
        finally:
            solution.problem.destroy()
    (f2, q2), (f1, q1) = curves
    same = f2.shape == f1.shape and np.array_equal(f2, f1)
    gap = float(np.abs(q2 - q1).max() / np.abs(q1).max()) if same else math.inf
    assert world.allreduce(int(not same), op=MPI.SUM) == 0
    # each run stops Newton once ||F|| <= 1e-9 ||F0|| (geofrac/solvers/snes.py): two
    # converged iterates differ by up to that tolerance times the problem's amplification
    # (measured 2.0e-9 on one venv, below 1e-9 on another: a bound at 1e-9 was the
    # tolerance itself and flipped); stale ghost displacements (the scatter left out)
    # change the accepted steps themselves
    assert world.allreduce(gap, op=MPI.MAX) <= 100 * 1e-9
