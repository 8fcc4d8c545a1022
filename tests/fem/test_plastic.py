"""The elasto-plastic finite-element solver (geofrac/fem/plastic.py) on the Mohr-Coulomb opening.

Reference: the closed form of geofrac/analytic_plastic.py (Salençon (1969), Carranza-Torres
and Fairhurst (1999), for the finite ring with the outer pressure held). Quarter ring
a = 1, b = 10 (meshes/quarter_ring.geo), p0 = 10, pi = 1, E = 1e4, nu = 0.3, c = 1,
phi = 30 degrees. Measured (docs/plasticity.md, h the wall mesh size, 5 load steps):

| h | psi | wall u error | rho error (yielded area) |
|---|---|---|---|
| 0.2 | 0 | -0.28 % | +1.2 % |
| 0.14 | 0 | -0.004 % | -0.5 % |
| 0.1 | 0 | +0.04 % | +0.55 % |
| 0.2 | 30 | -1.24 % | +1.8 % |
| 0.14 | 30 | -0.99 % | +0.3 % |
| 0.1 | 30 | -0.43 % | +1.0 % |
| 0.05 | 30 | -0.08 % | +0.28 % |
"""

from __future__ import annotations

from dataclasses import replace

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.errors import RunError
from geofrac.fem.plastic import PlasticProblem, solve_plastic
from geofrac.plasticity import DruckerPrager, MohrCoulomb
from geofrac.solvers import LinearSolver, assemble_matrix, assemble_vector, set_bc
from tests.fem.plastic_ring import (
    plastic_radius_from_area,
    ring_mesh,
    ring_problem,
    wall_displacement,
)

A, B, P0, PI, E, NU, C, PHI = 1.0, 10.0, 10.0, 1.0, 1e4, 0.3, 1.0, 30.0


def _law(psi: float, cohesion: float = C) -> MohrCoulomb:
    return MohrCoulomb(E=E, nu=NU, cohesion=cohesion, friction_angle=PHI, dilatancy_angle=psi)


@pytest.mark.parametrize(("psi", "h"), [(0.0, 0.2), (30.0, 0.14)])
def test_opening_against_salencon(psi: float, h: float) -> None:
    """Wall displacement and plastic radius within 2 % of the closed form."""
    exact = MohrCoulombOpening(
        a=A, b=B, p0=P0, pi=PI, E=E, nu=NU, cohesion=C, friction_angle=PHI, dilatancy_angle=psi
    )
    problem = ring_problem(ring_mesh(MPI.COMM_WORLD, a=A, b=B, h=h), _law(psi), p0=P0, pi=PI)
    try:
        result = problem.solve_steps(5)
        assert result.converged and result.end_reason == "converged"
        assert all(s.report.converged for s in result.steps if s.accepted)
        u_wall = wall_displacement(problem.u, A)
        rho = plastic_radius_from_area(problem, A)
    finally:
        problem.destroy()
    assert exact.plastic_radius > 1.3  # a plastic zone several elements thick
    assert u_wall == pytest.approx(exact.wall_displacement, rel=0.02)
    assert rho == pytest.approx(exact.plastic_radius, rel=0.02)


@pytest.mark.slow
def test_opening_fine_mesh_dilatant() -> None:
    """The dilatant case psi = phi on the fine mesh h = 0.05 (3014 cells, 10 s).

    u(a) and rho within 0.5 % (measured -0.08 % and +0.28 %; the coarse rows of the module
    docstring converge towards it).
    """
    exact = MohrCoulombOpening(
        a=A, b=B, p0=P0, pi=PI, E=E, nu=NU, cohesion=C, friction_angle=PHI, dilatancy_angle=PHI
    )
    problem = ring_problem(ring_mesh(MPI.COMM_WORLD, a=A, b=B, h=0.05), _law(PHI), p0=P0, pi=PI)
    try:
        assert problem.solve_steps(5).converged
        u_wall = wall_displacement(problem.u, A)
        rho = plastic_radius_from_area(problem, A)
    finally:
        problem.destroy()
    assert u_wall == pytest.approx(exact.wall_displacement, rel=0.005)
    assert rho == pytest.approx(exact.plastic_radius, rel=0.005)


def _plastic_step_residuals(**kw: object) -> list[float]:
    """SNES residual norms of the first load step past the elastic ones.

    psi = 0, h = 0.2, converged or not.
    """
    problem = ring_problem(
        ring_mesh(MPI.COMM_WORLD, a=A, b=B, h=0.2), _law(0.0), p0=P0, pi=PI, **kw
    )
    try:
        result = problem.solve_steps(5, max_cuts=0)
    finally:
        problem.destroy()
    plastic = [s for s in result.steps if s.report.iterations > 1]  # elastic steps take 1
    assert plastic, "no plastic step"
    return plastic[0].report.residuals


def test_newton_converges_quadratically() -> None:
    """The consistent tangent: e_{k+1} <= 10 e_k² (e = r/r0).

    On the last two iterations above the round-off floor (e > 1e-12; measured e = 1,
    0.56, 0.21, 2.2e-2, 1.1e-4, 1.7e-9, 7.7e-14: ratios 0.23, 0.15), and converged in
    at most 10 iterations.
    """
    r = np.array(_plastic_step_residuals())
    e = r / r[0]
    assert e[-1] < 1e-10
    assert len(e) <= 11
    above = e[1:] > 1e-12
    ratios = (e[1:] / e[:-1] ** 2)[above]
    assert len(ratios) >= 2 and np.all(ratios[-2:] <= 10.0), (e, ratios)


def test_non_convergent_step_is_reported() -> None:
    """An inner tension above the apex c cot(phi) has no equilibrium.

    The run ends with converged = False at the last converged factor, each failed step
    with its reason.
    """
    tagged = ring_mesh(MPI.COMM_WORLD, a=A, b=B, h=0.3)
    problem = ring_problem(tagged, _law(0.0), p0=P0, pi=-5.0, max_it=15)
    try:
        result = problem.solve_steps(4, max_cuts=2)
    finally:
        problem.destroy()
    assert not result.converged and result.end_reason == "step_too_small"
    assert result.factor < 1.0
    accepted = [s for s in result.steps if s.accepted]
    assert accepted[-1].factor == result.factor
    failed = result.steps[-3:]
    assert all(not s.accepted and s.report.reason < 0 for s in failed)
    assert all(s.report.reason_name.startswith("DIVERGED") for s in failed)
    lost, plastic = result.ellipticity  # psi = 0 < phi: yielding points past the border
    assert 0 < lost <= plastic  # (not those at the apex, where D = 0)


def _linear_elastic(tagged, V, bcs, *, p0: float, pi: float) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The linear elastic solve of the same ring.

    geofrac_forms' stiffness, geofrac's direct LinearSolver, the same quadrature degree
    2: K u = f(pi) − f(p0), the load change from the uniform state.
    """
    from geofrac.materials import lame
    from geofrac_forms import elasticity as forms

    mesh = tagged.mesh
    lam, mu = lame(E, NU, 2, plane="strain")
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 2})  # the solver's rule
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tagged.tags[1])
    n = ufl.FacetNormal(mesh)
    one = dolfinx.fem.Constant(mesh, 1.0)
    a = dolfinx.fem.form(forms.stiffness_form(u, v, lam, mu, one, dx))
    L = dolfinx.fem.form(ufl.inner(-(pi - p0) * n, v) * ds(tagged.groups["wall"][1]))
    Amat = assemble_matrix(a, bcs)
    b = assemble_vector(L, (a, bcs))
    set_bc(b, bcs)
    uh = dolfinx.fem.Function(V)
    solver = LinearSolver(
        Amat,
        "test_plastic_elastic_",
        "direct",
        options={},
        num_dofs=V.dofmap.index_map.size_global * 2,
    )
    try:
        solver.solve(b, uh.x.petsc_vec)
    finally:
        solver.destroy()
        Amat.destroy()
        b.destroy()
    uh.x.scatter_forward()
    return uh.x.array.copy()


@pytest.mark.parametrize("law", ["mohr_coulomb", "drucker_prager"])
def test_huge_cohesion_equals_linear_elastic(law: str) -> None:
    """C = 1e8: no point yields and u equals the linear elastic solver's to 1e-10."""
    tagged = ring_mesh(MPI.COMM_WORLD, a=A, b=B, h=0.3)
    strong = (
        _law(0.0, cohesion=1e8)
        if law == "mohr_coulomb"
        else DruckerPrager(E=E, nu=NU, cohesion=1e8, friction_angle=PHI, dilatancy_angle=0.0)
    )
    problem = ring_problem(tagged, strong, p0=P0, pi=PI)
    try:
        result = problem.solve_steps(2)
        assert result.converged and all(s.plastic_points == 0 for s in result.steps)
        u_plastic = problem.u.x.array.copy()
        u_elastic = _linear_elastic(tagged, problem.V, problem.newton.bcs, p0=P0, pi=PI)
    finally:
        problem.destroy()
    scale = MPI.COMM_WORLD.allreduce(np.abs(u_elastic).max(), op=MPI.MAX)
    diff = MPI.COMM_WORLD.allreduce(np.abs(u_plastic - u_elastic).max(), op=MPI.MAX)
    assert diff <= 1e-10 * scale


def test_refuses_p1() -> None:
    """P1 (locks under plastic flow) is refused with a reason (3D: tests/fem/test_plastic_3d.py)."""
    mesh = dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 2, 2)
    V1 = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (2,)))
    zero = lambda f, v: ufl.inner(f * ufl.as_vector([0.0, 0.0]), v) * ufl.ds  # noqa: E731
    with pytest.raises(RunError, match="degree >= 2"):
        PlasticProblem(V1, _law(0.0), zero)


@pytest.mark.mpi(min_size=2)
def test_two_ranks_equal_one() -> None:
    """The distributed solve equals each rank's own serial solve (wall u, yielded area)."""
    world = MPI.COMM_WORLD
    values = []
    for comm in (world, MPI.COMM_SELF):
        problem = ring_problem(ring_mesh(comm, a=A, b=B, h=0.3), _law(0.0), p0=P0, pi=PI)
        try:
            assert problem.solve_steps(5).converged
            values.append(
                (wall_displacement(problem.u, A), problem.yielded_area(), problem.plastic_points())
            )
        finally:
            problem.destroy()
    (u2, area2, n2), (u1, area1, n1) = values
    gap_u = world.allreduce(abs(u2 - u1) / abs(u1), op=MPI.MAX)
    gap_area = world.allreduce(abs(area2 - area1) / area1, op=MPI.MAX)
    assert gap_u <= 1e-9 and gap_area <= 1e-9
    assert world.allreduce(int(n2 != n1), op=MPI.SUM) == 0


def test_solve_plastic_for_strength_reduction() -> None:
    """The entry point strength reduction will call.

    The full strength converges with the monitor displacement; c and tan(phi) divided by
    10 cannot hold p0 (the ring's limit outer pressure (pi + A)(b/a)^(K_p - 1) - A = 1.87
    < p0 = 10) and is reported so.
    """
    tagged = ring_mesh(MPI.COMM_WORLD, a=A, b=B, h=0.3)

    def factory(law: MohrCoulomb) -> PlasticProblem:
        return ring_problem(tagged, law, p0=P0, pi=PI, max_it=15)

    def monitor(u: dolfinx.fem.Function) -> np.ndarray:
        return np.array([wall_displacement(u, A)])

    strong = solve_plastic(factory, _law(0.0), steps=5, monitor=monitor)
    assert strong.converged and strong.monitor is not None
    exact = MohrCoulombOpening(
        a=A, b=B, p0=P0, pi=PI, E=E, nu=NU, cohesion=C, friction_angle=PHI
    ).wall_displacement
    assert strong.monitor[0] == pytest.approx(exact, rel=0.05)  # h = 0.3: a coarse mesh
    weak_phi = float(np.degrees(np.arctan(np.tan(np.radians(PHI)) / 10.0)))
    weak = replace(_law(0.0), cohesion=C / 10.0, friction_angle=weak_phi)
    result = solve_plastic(factory, weak, steps=2, monitor=monitor, max_cuts=1)
    assert not result.converged and result.end_reason == "step_too_small"
    assert result.factor < 1.0 and result.monitor is not None
