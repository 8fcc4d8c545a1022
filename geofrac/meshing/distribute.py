"""Mesh a geometry with gmsh on rank 0 and distribute it as a DOLFINx mesh with tags."""

from __future__ import annotations

from contextlib import ExitStack

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.meshing.geo import gmsh_session
from geofrac.scene.model import Geometry

__all__ = ["TaggedMesh", "build_mesh"]


class TaggedMesh:
    """A distributed mesh with its physical groups.

    Attributes:
        mesh: the DOLFINx mesh.
        groups: physical group name -> (dimension, tag).
        tags: dimension -> ``dolfinx.mesh.MeshTags`` for that dimension (or None).
    """

    def __init__(self, data: gmshio.MeshData) -> None:
        self.mesh = data.mesh
        self.groups = {name: (g.dim, g.tag) for name, g in data.physical_groups.items()}
        tdim = self.mesh.topology.dim
        by_codim = [data.cell_tags, data.facet_tags, data.ridge_tags, data.peak_tags]
        self.tags = {tdim - c: t for c, t in enumerate(by_codim) if tdim - c >= 0}

    def entities(self, group: str) -> tuple[int, np.ndarray]:
        """Return (dimension, local entity indices, shape=(n,)) of a physical group."""
        dim, tag = self.groups[group]
        tags = self.tags[dim]
        if tags is None:
            return dim, np.empty(0, dtype=np.int32)
        return dim, tags.find(tag)

    def num_global(self, dim: int) -> int:
        """Global number of entities of dimension ``dim``."""
        self.mesh.topology.create_entities(dim)
        return int(self.mesh.topology.index_map(dim).size_global)


def _check_groups_on_cells(model: object, dim: int) -> None:
    """Every node of a lower-dimensional physical group must belong to a meshed cell.

    DOLFINx's ``model_to_mesh`` aborts the whole MPI job ("Invalid rank") on a tagged
    curve or point outside the cells, e.g. a fracture line sticking out of the domain;
    this turns that into an error naming the group.

    Raises:
        RuntimeError: naming the offending physical group.
    """
    cell_nodes = []
    for d, tag in model.getPhysicalGroups(dim):  # type: ignore[attr-defined]
        for entity in model.getEntitiesForPhysicalGroup(d, tag):  # type: ignore[attr-defined]
            _, _, nodes = model.mesh.getElements(d, entity)  # type: ignore[attr-defined]
            cell_nodes += [np.asarray(n) for n in nodes]
    inside = np.unique(np.concatenate(cell_nodes)) if cell_nodes else np.empty(0)
    for d, tag in model.getPhysicalGroups():  # type: ignore[attr-defined]
        if d >= dim:
            continue
        nodes = model.mesh.getNodesForPhysicalGroup(d, tag)[0]  # type: ignore[attr-defined]
        outside = np.setdiff1d(nodes, inside)
        if len(outside):
            name = model.getPhysicalName(d, tag)  # type: ignore[attr-defined]
            raise RuntimeError(
                f"physical group '{name}' has {len(outside)} node(s) outside the meshed domain; "
                "clip it to the domain or embed it in the mesh"
            )


def build_mesh(geometry: Geometry, comm: MPI.Comm, verbose: bool = False) -> TaggedMesh:
    """Mesh ``geometry`` with gmsh on rank 0 and distribute the mesh over ``comm``.

    Raises:
        RunError: gmsh failed to mesh the geometry (raised on every rank).
    """
    if comm.rank != 0:
        message = comm.bcast(None, root=0)
        if message is not None:
            raise RunError(message)
        return TaggedMesh(gmshio.model_to_mesh(None, comm, 0, gdim=geometry.dim))
    with ExitStack() as stack:
        message = None
        try:
            gmsh = stack.enter_context(
                gmsh_session(geometry.file, geometry.parameters, geometry.mesh_size, verbose)
            )
            if geometry.file.suffix == ".geo":  # a .msh file is used as it is, never re-meshed
                gmsh.model.mesh.generate(geometry.dim)  # type: ignore[attr-defined]
            if len(gmsh.model.mesh.getNodes()[0]) == 0:  # type: ignore[attr-defined]
                raise RuntimeError("gmsh produced no nodes")
            _check_groups_on_cells(gmsh.model, geometry.dim)  # type: ignore[attr-defined]
        except Exception as exc:  # gmsh raises bare Exceptions
            message = f"meshing {geometry.file.name} failed: {exc}"
        comm.bcast(message, root=0)
        if message is not None:
            raise RunError(message)
        return TaggedMesh(gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=geometry.dim))  # type: ignore[attr-defined]
