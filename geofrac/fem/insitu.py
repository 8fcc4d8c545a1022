"""The initial stress and the live cells of a staged elastic problem as DOLFINx fields.

The initial stress σ0 is evaluated by the pure :mod:`geofrac.geometry.insitu` at the
interpolation points of a discontinuous Lagrange tensor space, region by region (the
cell groups), and stored as a 3×3 field (2D: σzz0 from
:func:`~geofrac.geometry.insitu.out_of_plane`). Its degree is that of the cell geometry
(at least 1), so a field linear in the coordinates (constant, or geostatic under a level
surface with one density per layer whose interfaces follow cell edges) is held exactly
and its equilibrium residual is round-off. ``alive`` is a DG0 indicator: 1 on the cells
that are still there, 0 on the excavated ones; it multiplies the stiffness, the
internal forces and the density.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.walls import live_cells
from geofrac.geometry.insitu import (
    StressField,
    column_weight,
    evaluate,
    out_of_plane,
    surface_height,
)
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import InitialStress, Scene

__all__ = [
    "InsituFields",
    "cell_dofs",
    "group_cells",
    "in_plane",
    "insitu_fields",
    "stress_field",
    "untouched_blocks",
]


@dataclass
class InsituFields:
    """The fields a staged problem carries.

    Attributes:
        alive: DG0, 1 on live cells and 0 on removed ones.
        sigma0: the initial stress, 3×3 discontinuous Lagrange (zero without one).
        density: the density as UFL: ``rho`` times ``alive``.
        rho: DG0 density per cell (per cell group with an initial stress, else
            ``material.density`` or 0; an added group's own).
        lam, mu: DG0 Lamé constants per cell (the scene's material; an added group's own).
        u_ref: the displacement at installation of added cells (0 elsewhere), in
            discontinuous Lagrange of the displacement's degree (per cell, so groups
            installed at different stages keep their own): their stress is
            C ε(u − u_ref), zero when they are installed.
    """

    alive: dolfinx.fem.Function
    sigma0: dolfinx.fem.Function
    density: Any
    rho: dolfinx.fem.Function
    lam: dolfinx.fem.Function
    mu: dolfinx.fem.Function
    u_ref: dolfinx.fem.Function


def stress_field(spec: InitialStress, tagged: TaggedMesh) -> StressField:
    """The pure :class:`StressField` of ``spec`` with the groups' cell tags as region ids."""
    tag = {name: t for name, (d, t) in tagged.groups.items()}
    return StressField(
        dim=tagged.mesh.geometry.dim,
        kind=spec.kind,
        stress=spec.stress,
        surface=spec.surface,
        gravity=spec.gravity,
        density=spec.density,
        densities={tag[g]: v for g, v in spec.densities.items()},
        k0=spec.k0,
        k0s={tag[g]: v for g, v in spec.k0s.items()},
        tectonic=spec.tectonic,
    )


def _cell_regions(tagged: TaggedMesh) -> np.ndarray:
    """The cell group tag of every local cell, shape=(num_local_cells,); -1 if none."""
    mesh = tagged.mesh
    tdim = mesh.topology.dim
    imap = mesh.topology.index_map(tdim)
    regions = np.full(imap.size_local + imap.num_ghosts, -1, dtype=np.int64)
    tags = tagged.tags.get(tdim)
    if tags is not None:
        regions[tags.indices] = tags.values
    return regions


def _triangles(tagged: TaggedMesh, field: StressField) -> tuple[np.ndarray, np.ndarray]:
    """Every rank's owned triangles, shape=(m, 3, 2), and their densities, shape=(m,)."""
    mesh = tagged.mesh
    num_owned = mesh.topology.index_map(2).size_local
    cells = np.arange(num_owned, dtype=np.int32)
    nodes = dolfinx.mesh.entities_to_geometry(mesh, 2, cells)[:, :3]
    corners = mesh.geometry.x[nodes][:, :, :2]
    regions = _cell_regions(tagged)[:num_owned]
    rho = np.full(num_owned, field.density)
    for region, value in field.densities.items():
        rho[regions == region] = value
    corners_all = mesh.comm.allgather(corners)
    rho_all = mesh.comm.allgather(rho)
    return np.concatenate(corners_all), np.concatenate(rho_all)


def _sigma0(tagged: TaggedMesh, scene: Scene) -> dolfinx.fem.Function:
    """The initial stress as a 3×3 DG field of the geometry's degree (collective)."""
    mesh = tagged.mesh
    gdim = mesh.geometry.dim
    degree = max(1, mesh.geometry.cmaps[0].degree)
    space = dolfinx.fem.functionspace(mesh, ("DG", degree, (3, 3)))
    sigma0 = dolfinx.fem.Function(space, name="initial_stress")
    spec = scene.initial_stress
    if spec is None:
        return sigma0
    material = scene.material
    assert material is not None  # a fem scene has one
    field = stress_field(spec, tagged)
    triangles = _triangles(tagged, field) if field.kind == "geostatic" and field.layered else None
    regions = _cell_regions(tagged)
    failure = ""
    for region in np.unique(regions):
        cells = np.flatnonzero(regions == region).astype(np.int32)

        def values(x: np.ndarray, region: int = int(region)) -> np.ndarray:
            points = x[:gdim].T  # shape=(n, gdim)
            column = None
            if triangles is not None:
                top = surface_height(field, points[:, 0])
                column = column_weight(
                    points, triangles[0], triangles[1], surface=top, above=field.density
                )
            voigt = evaluate(field, points, np.full(len(points), region), column=column)
            return _as_3x3(voigt, gdim, nu=material.nu, plane=material.plane)

        try:
            sigma0.interpolate(values, cells0=cells)
        except ValueError as exc:
            failure = str(exc)
    failure = mesh.comm.allreduce(failure, op=MPI.MAX)
    if failure:
        raise RunError(f"initial_stress.surface: {failure}")
    sigma0.x.scatter_forward()
    return sigma0


def _as_3x3(voigt: np.ndarray, gdim: int, *, nu: float, plane: str) -> np.ndarray:
    """Voigt stresses, shape=(n, 3|6), as row-major 3×3 tensors, shape=(9, n)."""
    n = len(voigt)
    out = np.zeros((n, 3, 3))
    if gdim == 2:
        out[:, 0, 0], out[:, 1, 1] = voigt[:, 0], voigt[:, 1]
        out[:, 0, 1] = out[:, 1, 0] = voigt[:, 2]
        out[:, 2, 2] = out_of_plane(voigt, nu=nu, plane=plane)
    else:
        for k, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))):
            out[:, i, j] = out[:, j, i] = voigt[:, k]
    return out.reshape(n, 9).T


def _density(tagged: TaggedMesh, scene: Scene, alive: dolfinx.fem.Function) -> dolfinx.fem.Function:
    """ρ per cell (DG0): per cell group with an initial stress, else ``material.density``."""
    spec = scene.initial_stress
    material = scene.material
    assert material is not None  # a fem scene has one
    rho = dolfinx.fem.Function(alive.function_space, name="density")
    rho.x.array[:] = spec.density if spec is not None else (material.density or 0.0)
    if spec is not None:
        regions = _cell_regions(tagged)
        for group, value in spec.densities.items():
            cells = np.flatnonzero(regions == tagged.groups[group][1])
            rho.x.array[cell_dofs(rho, cells)] = value
    return rho


def group_cells(tagged: TaggedMesh, group: str) -> np.ndarray:
    """The local cells of a cell group, shape=(n,)."""
    return tagged.entities(group)[1]


def cell_dofs(f: dolfinx.fem.Function, cells: np.ndarray) -> np.ndarray:
    """The DOF of each local cell of a DG0 function, shape=(len(cells),)."""
    return f.function_space.dofmap.list[np.asarray(cells, dtype=np.int32), 0]


def insitu_fields(
    tagged: TaggedMesh, scene: Scene, *, lam: float, mu: float, degree: int
) -> InsituFields:
    """The fields of a staged scene (collective).

    ``alive`` is 1 except on groups that a stage adds before any removed them (absent
    until added); ``lam``, ``mu``: the scene's Lamé constants; ``degree``: of the
    displacement space (that of ``u_ref``).
    """
    mesh = tagged.mesh
    dg0 = dolfinx.fem.functionspace(mesh, ("DG", 0))
    alive = dolfinx.fem.Function(dg0, name="alive")
    live = live_cells(tagged, scene.stages, 0)
    alive.x.array[cell_dofs(alive, np.arange(len(live)))] = live
    alive.x.scatter_forward()
    rho = _density(tagged, scene, alive)
    lam_f = dolfinx.fem.Function(dg0, name="lambda")
    lam_f.x.array[:] = lam
    mu_f = dolfinx.fem.Function(dg0, name="mu")
    mu_f.x.array[:] = mu
    gdim = mesh.geometry.dim
    u_ref = dolfinx.fem.Function(
        dolfinx.fem.functionspace(mesh, ("DG", degree, (gdim,))), name="installed_at"
    )
    return InsituFields(alive, _sigma0(tagged, scene), rho * alive, rho, lam_f, mu_f, u_ref)


def in_plane(sigma0: dolfinx.fem.Function, gdim: int) -> Any:
    """The gdim×gdim block of a 3×3 field, as UFL."""
    return ufl.as_matrix([[sigma0[i, j] for j in range(gdim)] for i in range(gdim)])


def untouched_blocks(V: dolfinx.fem.FunctionSpace, alive: dolfinx.fem.Function) -> np.ndarray:
    """The DOF blocks (nodes) that no live cell touches, local with ghosts (collective).

    The elastic and the elasto-plastic stages hold them where they are: with ``alive``
    multiplying the stiffness they have no equation. Shape=(k,), int32, sorted.
    """
    mesh = V.mesh
    cmap = mesh.topology.index_map(mesh.topology.dim)
    cells = np.arange(cmap.size_local + cmap.num_ghosts, dtype=np.int32)
    live = cells[alive.x.array[cell_dofs(alive, cells)] > 0.5]
    touched = dolfinx.la.vector(V.dofmap.index_map, 1)
    np.add.at(touched.array, V.dofmap.list[live].ravel(), 1.0)
    touched.scatter_reverse(dolfinx.la.InsertMode.add)
    touched.scatter_forward()
    return np.flatnonzero(touched.array == 0.0).astype(np.int32)
