"""A scene's loads as right-hand-side terms: UFL linear forms and point forces.

Distributed loads become linear forms (:mod:`geofrac_forms.elasticity`), each multiplied
by the thickness t in 2D (1 in 3D):

- ``traction`` t̄ (force per area) on a facet group: t ∫ t̄·v ds;
- ``pressure`` p on a facet group: the traction -p n with n the outward unit normal
  (``ufl.FacetNormal``), so p > 0 pushes into the body;
- a traction or pressure on facets inside the mesh (an opening's wall) acts from the
  stage that removes the cells on one side, on the live side (:mod:`geofrac.fem.walls`);
- ``body_force`` b (force per volume): t ∫ b·v dx.

A component given as an expression text (:mod:`geofrac.model.expr`) is translated node by
node into UFL of ``ufl.SpatialCoordinate``: the form evaluates the expression itself at
every quadrature point, with no interpolation error and no extra function space, and
UFL's degree estimate (the polynomial degree, +2 for a transcendental function) picks
the quadrature, exact for a polynomial such as a hydrostatic ``1000*(10 - y)``.

A ``point`` load F is not a form: it is added to the assembled load vector of the
element's displacement space at the DOFs of the mesh vertex of its physical point,
F·v(x_p), which is the consistent load of a Dirac force for every element here: a
Lagrange basis function (P1, P2, P3; the CST load of EFMM, Edo (2016), eq. 3.4c) is 1 at its
own vertex and 0 at the others; for RGNT, GNT and RGNQ the displacement is the P2 field
T w, so the force added at the P2 vertex node and then multiplied by Tᵀ
(:meth:`~geofrac.fem.elastic.GradientDofProblem.load_vector`) is F·(T w)(x_p). Only the
rank owning a DOF adds to it, so a point is counted once on any number of ranks. In 2D
the value is a force per unit thickness (as the traction, it is multiplied by t: the
total force on the specimen is t F); in 3D it is a force.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model import expr
from geofrac.model.scene import Load
from geofrac.solvers import SCALAR, Vector
from geofrac_forms import elasticity as forms

__all__ = [
    "PointForces",
    "expression_ufl",
    "has_expressions",
    "load_form",
    "point_forces",
    "require_finite",
    "value_ufl",
]

#: UFL function of each function an expression may call (:data:`expr.FUNCTIONS`).
_UFL_FUNCTIONS: dict[str, Callable[..., Any]] = {
    "sin": ufl.sin,
    "cos": ufl.cos,
    "tan": ufl.tan,
    "exp": ufl.exp,
    "log": ufl.ln,
    "sqrt": ufl.sqrt,
    "abs": abs,
    "min": ufl.min_value,
    "max": ufl.max_value,
}


def expression_ufl(text: str, mesh: dolfinx.mesh.Mesh) -> Any:
    """The expression ``text`` of x, y[, z] as a UFL scalar of ``SpatialCoordinate(mesh)``.

    Raises:
        ExpressionError: ``text`` is not an expression :func:`expr.parse` accepts (the
            scene loader has already checked it).
    """
    gdim = mesh.geometry.dim
    names = ("x", "y", "z")[:gdim]
    tree = expr.parse(text, names).tree
    x = ufl.SpatialCoordinate(mesh)
    coordinates = {name: x[i] for i, name in enumerate(names)}
    return ufl.as_ufl(expr.fold(tree, coordinates, _UFL_FUNCTIONS, lift=lambda v: v))


def value_ufl(value: Sequence[float | str], mesh: dolfinx.mesh.Mesh) -> Any:
    """A load value as UFL: a DOLFINx constant when every entry is a number.

    Args:
        value: numbers or expression texts, shape=(gdim,) or shape=(1,) (pressure).
        mesh: the mesh (constants and ``SpatialCoordinate``).

    Returns:
        a vector of shape=(len(value),), or a scalar for one entry.
    """
    if all(not isinstance(c, str) for c in value):
        array = np.asarray(value, dtype=SCALAR)
        return dolfinx.fem.Constant(mesh, array[0] if len(array) == 1 else array)
    parts = [expression_ufl(c, mesh) if isinstance(c, str) else ufl.as_ufl(c) for c in value]
    return parts[0] if len(parts) == 1 else ufl.as_vector(parts)


def load_form(
    load: Load,
    v: Any,
    tagged: TaggedMesh,
    *,
    ds: ufl.Measure,
    dx: ufl.Measure,
    thickness: Any,
    value: Any = None,
    subdomain: int | None = None,
) -> ufl.Form:
    """The linear form of a traction, pressure or body-force load.

    Args:
        load: the scene's load (not ``point``).
        v: test function of the displacement space.
        tagged: the mesh with its physical groups (the facet group of the load).
        ds: the problem's exterior facet measure (:func:`geofrac.fem.walls.facet_measure`).
        dx: cell measure.
        thickness: t in 2D, 1 in 3D.
        value: the load's value as UFL when it is not ``load.value`` (``"exact"``).
        subdomain: the id of ``ds`` for a load on facets inside the mesh (an opening's
            wall, integrated on its live side, :mod:`geofrac.fem.walls`); None: the
            group's tag.
    """
    if value is None:
        value = value_ufl(load.value, tagged.mesh)
    if load.type == "body_force":
        return forms.body_force_form(v, value, thickness, dx)
    assert load.group is not None  # a facet load names its group
    tag = tagged.groups[load.group][1] if subdomain is None else subdomain
    if load.type == "pressure":
        value = -value * ufl.FacetNormal(tagged.mesh)
    return forms.traction_form(v, value, thickness, ds(tag))


@dataclass(frozen=True)
class PointForces:
    """Point loads as entries of the load vector.

    Attributes:
        rows: owned local indices into the unrolled load vector, shape=(m,).
        values: force added at each, shape=(m,).
    """

    rows: np.ndarray
    values: np.ndarray

    def add_to(self, b: Vector) -> None:
        """Add the forces to the owned entries of an assembled load vector ``b``."""
        if len(self.rows):
            with b.localForm() as local:
                np.add.at(local.array_w, self.rows, self.values)


def point_forces(
    tagged: TaggedMesh, V: dolfinx.fem.FunctionSpace, loads: Sequence[Load], *, thickness: float
) -> PointForces:
    """The scene's point loads on the displacement space ``V`` (collective).

    Each point load's physical point must be exactly one mesh vertex; its force times
    ``thickness`` goes to the DOFs of ``V`` at that vertex, on the rank that owns them.

    Raises:
        RunError: collectively, when a point group has no mesh vertex or several.
    """
    mesh = tagged.mesh
    comm = mesh.comm
    gdim = mesh.geometry.dim
    owned_size = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    num_vertices = mesh.topology.index_map(0).size_local
    rows, values = [], []
    for i, load in enumerate(loads):
        if load.type != "point":
            continue
        dim, vertices = tagged.entities(load.group)  # type: ignore[arg-type]
        count = comm.allreduce(len(np.unique(vertices[vertices < num_vertices])), op=MPI.SUM)
        if count != 1:
            raise RunError(
                f"load[{i}].group: physical point group '{load.group}' has {count} mesh "
                "vertices; a point load needs exactly one (one gmsh Point of the mesh)"
            )
        for c in range(gdim):
            dofs = dolfinx.fem.locate_dofs_topological(V.sub(c), dim, vertices)
            dofs = np.unique(dofs[dofs < owned_size])
            rows.append(dofs)
            values.append(np.full(len(dofs), thickness * float(load.value[c])))
    if not rows:
        return PointForces(np.empty(0, dtype=np.int32), np.empty(0))
    return PointForces(np.concatenate(rows).astype(np.int32), np.concatenate(values))


def has_expressions(loads: Sequence[Load]) -> bool:
    """Whether a load has a component given as an expression text."""
    return any(
        load.value != "exact" and any(isinstance(c, str) for c in load.value) for load in loads
    )


def require_finite(b: Vector, comm: MPI.Comm) -> None:
    """Refuse a load vector with an inf or NaN entry (collective).

    Raises:
        RunError: on every rank, when an expression load is not finite at some
            quadrature point (for example ``1/x`` on a group touching x = 0).
    """
    bad = comm.allreduce(int(not np.all(np.isfinite(b.array_r))), op=MPI.SUM)
    if bad:
        raise RunError(
            "load: an expression load is not finite somewhere on its group or domain "
            "(the load vector has inf or NaN entries)"
        )
