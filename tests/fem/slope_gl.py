"""The slope of Griffiths and Lane (1999), example 1, as an elasto-plastic problem.

meshes/slope_griffiths_lane.geo: H = 10, 2:1, firm base at the toe (D = 1); the base
fixed, the back on rollers; gravity γ = 20 ramped with the load factor from a
stress-free start. Shared by tests/fem/test_strength_reduction.py.
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
from geofrac.fem.strength_reduction import point_monitor
from geofrac.meshing.distribute import TaggedMesh, build_mesh
from geofrac.meshing.geo import inspect_geometry
from geofrac.model.scene import Geometry
from geofrac.plasticity import MohrCoulomb

GEO = Path(__file__).resolve().parents[2] / "meshes" / "slope_griffiths_lane.geo"
#: Griffiths and Lane (1999), example 1: H, γ, c, φ, ψ, E, ν.
H, GAMMA, C, PHI, PSI, E, NU = 10.0, 20.0, 10.0, 20.0, 0.0, 1e5, 0.3


def slope_law() -> MohrCoulomb:
    """Their soil: c/(γH) = 0.05, φ = 20°, ψ = 0."""
    return MohrCoulomb(E=E, nu=NU, cohesion=C, friction_angle=PHI, dilatancy_angle=PSI)


def slope_mesh(comm: MPI.Comm, *, h: float, algorithm: int = 6, behind: float = 12.0) -> TaggedMesh:
    """The meshed slope (mesh size h, gmsh 2D algorithm, level ground ``behind`` the crest)."""
    params = {"H": H, "n": 2.0, "L": behind, "h": h, "algorithm": algorithm}
    info = inspect_geometry(GEO, params)
    geometry = Geometry(GEO, params, None, 2, info.groups, order=info.order)
    return build_mesh(geometry, comm)


def slope_problem(tagged: TaggedMesh, law: Law, **kw: Any) -> PlasticProblem:
    """Gravity λ γ (downwards) for λ 0 → 1; base fixed, back x-fixed (P2)."""
    mesh = tagged.mesh
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (2,)))

    def external(factor: Any, v: Any) -> Any:
        return ufl.inner(factor * ufl.as_vector([0.0, -GAMMA]), v) * ufl.dx(domain=mesh)

    bcs = []
    dim, ents = tagged.entities("base")
    dofs = dolfinx.fem.locate_dofs_topological(V, dim, ents)
    bcs.append(dolfinx.fem.dirichletbc(np.zeros(2), dofs, V))
    dim, ents = tagged.entities("back")
    dofs = dolfinx.fem.locate_dofs_topological(V.sub(0), dim, ents)
    bcs.append(dolfinx.fem.dirichletbc(0.0, dofs, V.sub(0)))
    return PlasticProblem(V, law, external, bcs=bcs, **kw)


#: u at the crest's edge (2H, H), shape=(2,), the same on every rank.
crest_monitor = point_monitor((2.0 * H, H))
