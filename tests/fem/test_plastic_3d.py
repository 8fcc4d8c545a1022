"""The elasto-plastic solver in 3D: the opening's slab in plane strain, homogeneous limits.

References (closed forms, not geofrac's): Salençon's opening (the finite ring of
:mod:`geofrac.analytic_plastic`, cross-checked in tests/plasticity/test_analytic_opening.py)
and Mohr-Coulomb's triaxial compression strength
q_f = (p_c (1 + sin φ) + 2 c cos φ) / (1 − sin φ) (σ₁ = σ₂ = −p_c, σ₃ = −q_f on the
compression edge; p_c = 0: the uniaxial strength 2 c cos φ / (1 − sin φ)).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.fem.plastic import PlasticProblem
from geofrac.meshing.distribute import build_mesh
from geofrac.meshing.geo import inspect_geometry
from geofrac.model.scene import Geometry
from geofrac.plasticity import MohrCoulomb
from tests.fem.helpers import solve_job
from tests.fem.plastic_ring import ring_problem

GEO = Path(__file__).resolve().parents[2] / "meshes" / "quarter_ring_slab.geo"
A, B, P0, PI, E, NU, C, PHI = 1.0, 10.0, 10.0, 1.0, 1e4, 0.3, 1.0, 30.0


def _slab(comm: MPI.Comm, psi: float, *, h: float, t: float) -> tuple[PlasticProblem, Any]:
    params = {"a": A, "b": B, "h": h, "t": t}
    info = inspect_geometry(GEO, params)
    tagged = build_mesh(Geometry(GEO, params, None, 3, info.groups, order=info.order), comm)
    law = MohrCoulomb(E=E, nu=NU, cohesion=C, friction_angle=PHI, dilatancy_angle=psi)
    return ring_problem(tagged, law, p0=P0, pi=PI), tagged.mesh


def _radial_wall(u: dolfinx.fem.Function, mesh: Any) -> float:
    """u_x at (a, 0, t/2) (the radial wall displacement), the same on every rank."""
    z = mesh.geometry.x[:, 2].max()
    z = mesh.comm.allreduce(z, op=MPI.MAX)
    point = np.array([[A, 0.0, 0.5 * z]])
    tree = dolfinx.geometry.bb_tree(mesh, 3)
    cells = dolfinx.geometry.compute_colliding_cells(
        mesh, dolfinx.geometry.compute_collisions_points(tree, point), point
    ).links(0)
    owned = cells[cells < mesh.topology.index_map(3).size_local]
    value, count = (float(u.eval(point, owned[:1])[0]), 1) if len(owned) else (0.0, 0)
    return mesh.comm.allreduce(value, op=MPI.SUM) / mesh.comm.allreduce(count, op=MPI.SUM)


def test_scene_in_3d_is_salencon() -> None:
    """The 3D scene gives the plane-strain wall displacement.

    jobs/opening_mohr_coulomb_3d.toml (ψ = 0, h = t = 0.3, 402 tetrahedra): within 2 % of
    the closed form (measured +0.18 %).
    """
    exact = MohrCoulombOpening(
        a=A, b=B, p0=P0, pi=PI, E=E, nu=NU, cohesion=C, friction_angle=PHI, dilatancy_angle=0.0
    )
    solution = solve_job("opening_mohr_coulomb_3d")
    try:
        results = solution.results
    finally:
        solution.problem.destroy()
    assert results["plasticity"]["converged"] and results["plasticity"]["plastic_points"] > 0
    assert results["probes"]["wall"][0] == pytest.approx(exact.wall_displacement, rel=0.02)


@pytest.mark.slow
@pytest.mark.parametrize(("psi", "h"), [(30.0, 0.2)])
def test_slab_in_plane_strain_is_salencon(psi: float, h: float) -> None:
    """u_z = 0 on both faces: the 3D solve gives the plane-strain wall displacement.

    Within 2 % of the closed form on a coarse slab of thickness t = h, with plastic flow
    over several steps (measured: ψ = 0, h = 0.3, 402 tetrahedra: +0.18 %; ψ = 30°,
    h = 0.2, 781 tetrahedra: +0.47 %; ψ = 30° at h = 0.3: +2.5 %).
    """
    exact = MohrCoulombOpening(
        a=A, b=B, p0=P0, pi=PI, E=E, nu=NU, cohesion=C, friction_angle=PHI, dilatancy_angle=psi
    )
    problem, mesh = _slab(MPI.COMM_WORLD, psi, h=h, t=h)
    try:
        result = problem.solve_steps(4)
        assert result.converged
        assert problem.plastic_points() > 0
        u_wall = _radial_wall(problem.u, mesh)
    finally:
        problem.destroy()
    assert u_wall == pytest.approx(exact.wall_displacement, rel=0.02)


def _cube_limit(load: float, *, confinement: float, law: MohrCoulomb) -> tuple[bool, float]:
    """(converged, σ_zz at the end) of a unit cube loaded to ``load`` axially.

    Rollers on x = 0, y = 0, z = 0; the lateral faces x = 1, y = 1 under the confinement
    held, the top z = 1 under the axial pressure confinement + λ (load − confinement).
    Starts from σ0 = −confinement I.
    """
    mesh = dolfinx.mesh.create_unit_cube(
        MPI.COMM_WORLD, 2, 2, 2, cell_type=dolfinx.mesh.CellType.tetrahedron
    )
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (3,)))
    fdim = 2
    markers = {1: lambda x: np.isclose(x[0], 1.0), 2: lambda x: np.isclose(x[1], 1.0)}
    markers[3] = lambda x: np.isclose(x[2], 1.0)
    facets, values = [], []
    for tag, where in markers.items():
        f = dolfinx.mesh.locate_entities_boundary(mesh, fdim, where)
        facets.append(f)
        values.append(np.full(len(f), tag, dtype=np.int32))
    order = np.argsort(np.concatenate(facets))
    tags = dolfinx.mesh.meshtags(
        mesh, fdim, np.concatenate(facets)[order], np.concatenate(values)[order]
    )
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    n = ufl.FacetNormal(mesh)

    def external(factor: Any, v: Any) -> Any:
        axial = confinement + factor * (load - confinement)
        return ufl.inner(-confinement * n, v) * (ds(1) + ds(2)) + ufl.inner(-axial * n, v) * ds(3)

    bcs = []
    for comp in range(3):
        dofs = dolfinx.fem.locate_dofs_geometrical(
            (V.sub(comp), V.sub(comp).collapse()[0]), lambda x, c=comp: np.isclose(x[c], 0.0)
        )
        bcs.append(dolfinx.fem.dirichletbc(0.0, dofs[0], V.sub(comp)))
    problem = PlasticProblem(
        V, law, external, bcs=bcs, initial_stress=-confinement * np.eye(3), max_it=10
    )
    try:
        result = problem.solve_steps(2, max_cuts=1)
        szz = float(problem.sig.x.array.reshape(-1, 6)[:, 2].mean())
    finally:
        problem.destroy()
    return result.converged, float(mesh.comm.allreduce(szz, op=MPI.SUM) / mesh.comm.size)


@pytest.mark.parametrize("confinement", [0.0, 2.0])
def test_cube_carries_the_triaxial_strength_and_not_more(confinement: float) -> None:
    """Load control: 0.99 q_f holds, 1.01 q_f does not.

    At 0.99 q_f σ_zz = −0.99 q_f everywhere; at 1.01 q_f there is no equilibrium (the run
    stops short, not converged).
    """
    law = MohrCoulomb(E=100.0, nu=0.25, cohesion=1.0, friction_angle=30.0, dilatancy_angle=10.0)
    s = math.sin(math.radians(30.0))
    q_f = (confinement * (1 + s) + 2.0 * math.cos(math.radians(30.0))) / (1 - s)
    ok, szz = _cube_limit(0.99 * q_f, confinement=confinement, law=law)
    assert ok and szz == pytest.approx(-0.99 * q_f, rel=1e-9)
    ok, _ = _cube_limit(1.01 * q_f, confinement=confinement, law=law)
    assert not ok


def test_refuses_p1_and_a_surface_mesh_in_3d() -> None:
    from geofrac.errors import RunError

    cube = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    V1 = dolfinx.fem.functionspace(cube, ("Lagrange", 1, (3,)))
    law = MohrCoulomb(E=E, nu=NU, cohesion=C, friction_angle=PHI)
    zero = lambda f, v: ufl.inner(f * ufl.as_vector([0.0, 0.0, 0.0]), v) * ufl.ds  # noqa: E731
    with pytest.raises(RunError, match="degree >= 2"):
        PlasticProblem(V1, law, zero)
