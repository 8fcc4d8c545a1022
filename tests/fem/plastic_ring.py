"""The quarter ring a <= r <= b of meshes/quarter_ring.geo as an elasto-plastic problem.

Outer pressure p0 held, inner pressure lowered from p0 to pi with the load factor,
starting from the uniform stress -p0 I; symmetry on x = 0 and y = 0. Shared by
tests/fem/test_plastic.py and the validation case.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.fem.plastic import Law, PlasticProblem
from geofrac.meshing.distribute import TaggedMesh, build_mesh
from geofrac.meshing.geo import inspect_geometry
from geofrac.model.scene import Geometry

GEO = Path(__file__).resolve().parents[2] / "meshes" / "quarter_ring.geo"


def ring_mesh(comm: MPI.Comm, *, a: float, b: float, h: float) -> TaggedMesh:
    """The meshed quarter ring."""
    info = inspect_geometry(GEO, {"a": a, "b": b, "h": h})
    geometry = Geometry(GEO, {"a": a, "b": b, "h": h}, None, 2, info.groups, order=info.order)
    return build_mesh(geometry, comm)


def ring_problem(
    tagged: TaggedMesh, law: Law, *, p0: float, pi: float, degree: int = 2, **kw: Any
) -> PlasticProblem:
    """The elasto-plastic ring (P``degree`` displacements).

    In 3D (the slab of meshes/quarter_ring_slab.geo) also u_z = 0 on its faces ``back``
    and ``front``: the plane-strain ring.
    """
    mesh = tagged.mesh
    gdim = mesh.geometry.dim
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", degree, (gdim,)))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tagged.tags[gdim - 1])
    n = ufl.FacetNormal(mesh)
    wall, outer = tagged.groups["wall"][1], tagged.groups["outer"][1]

    def external(factor: Any, v: Any) -> Any:
        p_in = p0 + factor * (pi - p0)
        return ufl.inner(-p_in * n, v) * ds(wall) + ufl.inner(-p0 * n, v) * ds(outer)

    bcs = []
    held = [("bottom", 1), ("left", 0)] + ([("back", 2), ("front", 2)] if gdim == 3 else [])
    for group, comp in held:
        dim, ents = tagged.entities(group)
        dofs = dolfinx.fem.locate_dofs_topological(V.sub(comp), dim, ents)
        bcs.append(dolfinx.fem.dirichletbc(0.0, dofs, V.sub(comp)))
    return PlasticProblem(V, law, external, bcs=bcs, initial_stress=-p0 * np.eye(3), **kw)


def wall_displacement(u: dolfinx.fem.Function, a: float) -> float:
    """u_x at (a, 0) (the radial wall displacement), the same on every rank."""
    mesh = u.function_space.mesh
    point = np.array([[a, 0.0, 0.0]])
    tree = dolfinx.geometry.bb_tree(mesh, mesh.topology.dim)
    cand = dolfinx.geometry.compute_collisions_points(tree, point)
    cells = dolfinx.geometry.compute_colliding_cells(mesh, cand, point)
    local = cells.links(0)
    owned = local[local < mesh.topology.index_map(2).size_local]
    value, count = 0.0, 0
    if len(owned):
        value, count = float(u.eval(point, owned[:1])[0]), 1
    total = mesh.comm.allreduce(value, op=MPI.SUM)
    return total / mesh.comm.allreduce(count, op=MPI.SUM)


def plastic_radius(problem: PlasticProblem) -> float:
    """The largest radius of a yielded quadrature point (all ranks).

    From the accumulated plastic strain.
    """
    Q = problem.eps.function_space
    x = Q.tabulate_dof_coordinates()
    r = np.hypot(x[:, 0], x[:, 1])
    owned = Q.dofmap.index_map.size_local
    yielded = problem.plastic_shear_strain()[:owned] > 0.0
    local = float(r[:owned][yielded].max()) if yielded.any() else 0.0
    return float(problem.comm.allreduce(local, op=MPI.MAX))


def plastic_radius_from_area(problem: PlasticProblem, a: float) -> float:
    """ρ from the yielded area of the quarter ring, π/4 (ρ² − a²) (all ranks)."""
    return float(np.sqrt(a * a + 4.0 * problem.yielded_area() / np.pi))
