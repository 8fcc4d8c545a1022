"""Mesh a geometry with gmsh on rank 0 and distribute it as a DOLFINx mesh with tags."""

from __future__ import annotations

import time
from contextlib import ExitStack
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.meshing.geo import gmsh_session
from geofrac.scene.model import Geometry

__all__ = ["TaggedMesh", "build_mesh", "check_fracture_cover"]


class TaggedMesh:
    """A distributed mesh with its physical groups.

    Attributes:
        mesh: the DOLFINx mesh.
        groups: physical group name -> (dimension, tag).
        tags: dimension -> ``dolfinx.mesh.MeshTags`` for that dimension (or None).
        report: what the geometry builder reported (JSON-ready; empty for a file).
        fractures: the builder's payload, the same on every rank (the ``dfn`` effect's
            :class:`~geofrac.dfn.clean.CleanNetwork`), or None.
    """

    def __init__(
        self, data: gmshio.MeshData, report: dict[str, Any] | None = None, fractures: Any = None
    ) -> None:
        self.mesh = data.mesh
        self.report = report or {}
        self.fractures = fractures
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

    def owned(self, dim: int, entities: np.ndarray) -> np.ndarray:
        """The entities of ``entities`` (local indices, shape=(n,)) this rank owns."""
        self.mesh.topology.create_entities(dim)
        return entities[entities < self.mesh.topology.index_map(dim).size_local]

    def vertex_coordinates(self, dim: int, entities: np.ndarray) -> np.ndarray:
        """Coordinates of the vertices of entities, shape=(n, num_vertices, 3)."""
        from dolfinx.mesh import entities_to_geometry

        nodes = entities_to_geometry(self.mesh, dim, entities.astype(np.int32))
        return self.mesh.geometry.x[nodes]

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


def _idle_until_rank0(comm: MPI.Comm, poll: float = 0.005) -> None:
    """Wait for rank 0's meshing without spinning a core.

    MPICH's blocking collectives poll flat out; waiting in one slowed gmsh on rank 0 by up
    to 1.7x on a 2-core machine.
    """
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(poll)


def build_mesh(geometry: Geometry, comm: MPI.Comm, verbose: bool = False) -> TaggedMesh:
    """Mesh ``geometry`` with gmsh on rank 0 and distribute the mesh over ``comm``.

    A ``geometry.builder`` creates and meshes the model itself; its report and payload
    reach every rank (:attr:`TaggedMesh.report`, :attr:`TaggedMesh.fractures`).

    Raises:
        RunError: gmsh (or the builder) failed (raised on every rank).
    """
    if comm.rank != 0:
        _idle_until_rank0(comm)
        message, report, payload = comm.bcast(None, root=0)
        if message is not None:
            raise RunError(message)
        data = gmshio.model_to_mesh(None, comm, 0, gdim=geometry.dim)
        return TaggedMesh(data, report, payload)
    builder = geometry.builder
    with ExitStack() as stack:
        message, report, payload = None, None, None
        try:
            gmsh = stack.enter_context(
                gmsh_session(
                    None if builder else geometry.file,
                    geometry.parameters,
                    geometry.mesh_size,
                    verbose,
                )
            )
            if builder is not None:
                report, payload = builder.build(gmsh)
            elif geometry.file.suffix == ".geo":  # type: ignore[union-attr]  # .msh: as it is
                gmsh.model.mesh.generate(geometry.dim)  # type: ignore[attr-defined]
            if len(gmsh.model.mesh.getNodes()[0]) == 0:  # type: ignore[attr-defined]
                raise RuntimeError("gmsh produced no nodes")
            _check_groups_on_cells(gmsh.model, geometry.dim)  # type: ignore[attr-defined]
        except Exception as exc:  # gmsh raises bare Exceptions
            source = builder.name if builder else geometry.file.name  # type: ignore[union-attr]
            message = f"meshing {source} failed: {exc}"
        comm.Ibarrier().Wait()  # releases the ranks idling in _idle_until_rank0
        comm.bcast((message, report, payload), root=0)
        if message is not None:
            raise RunError(message)
        data = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=geometry.dim)  # type: ignore[attr-defined]
        return TaggedMesh(data, report, payload)


def check_fracture_cover(tagged: TaggedMesh, group: str = "fractures") -> dict[str, Any]:
    """Check that the facets tagged ``group`` cover the network exactly (collective).

    Each rank matches the facets it owns to the network edges
    (:func:`geofrac.dfn.check.match_facets`); lengths are summed over ranks. Every
    tagged facet must lie on a network edge and every fracture's tagged length must
    equal its length in the cleaned network within 1e-9 relative.

    Returns:
        ``fracture_facets`` (global count), ``max_length_error`` (relative, over
        fractures), ``fractures_covered``.

    Raises:
        RunError: a facet off the network or a fracture not covered (on every rank).
    """
    from geofrac.dfn.check import covered_length, match_facets

    clean = tagged.fractures
    comm = tagged.mesh.comm
    if group in tagged.groups:
        dim, facets = tagged.entities(group)
        facets = tagged.owned(dim, facets)
    else:
        facets = np.empty(0, dtype=np.int32)
        dim = tagged.mesh.topology.dim - 1
    xy = tagged.vertex_coordinates(dim, facets)[:, :, :2]
    off = int(np.count_nonzero(match_facets(xy, clean) < 0))
    covered = comm.allreduce(covered_length(xy, clean), op=MPI.SUM)
    count = comm.allreduce(len(facets), op=MPI.SUM)
    off = comm.allreduce(off, op=MPI.SUM)
    expected = clean.length
    present = expected > 0
    error = np.abs(covered - expected)[present] / expected[present]
    worst = float(error.max(initial=0.0))
    if off or worst > 1e-9 or np.any(covered[~present] > 0):
        raise RunError(
            f"the mesh does not follow the fracture network: {off} tagged facet(s) off the "
            f"network, largest relative length error {worst:.2e}"
        )
    return {
        "fracture_facets": int(count),
        "max_length_error": worst,
        "fractures_covered": int(np.count_nonzero(present)),
    }
