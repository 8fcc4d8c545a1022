"""Mesh a geometry with gmsh on rank 0 and distribute it as a DOLFINx mesh with tags."""

from __future__ import annotations

import time
from contextlib import ExitStack
from types import ModuleType
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from dolfinx.io import gmsh as gmshio
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.meshing.geo import failure_message, gmsh_session, meshed_model
from geofrac.meshing.split import split_model
from geofrac.model.scene import Geometry

__all__ = ["TaggedMesh", "build_mesh", "check_fracture_cover", "renumber_model"]


class TaggedMesh:
    """A distributed mesh with its physical groups.

    Attributes:
        mesh: the DOLFINx mesh.
        groups: physical group name -> (dimension, tag).
        tags: dimension -> ``dolfinx.mesh.MeshTags`` for that dimension (or None). Where
            physical groups of one dimension overlap (``left`` inside ``boundary``), an
            entity appears once per group: ``tags[d].find(tag)`` and ``ds(tag)`` see each
            group whole.
        report: what the geometry builder reported (JSON-ready; empty for a file).
        fractures: the builder's payload, the same on every rank (the ``dfn`` effect's
            :class:`~geofrac.dfn.clean.CleanNetwork`), or None.
        split: the curve groups the mesh was cut along before distribution
            (:attr:`~geofrac.model.scene.Geometry.split`).
    """

    def __init__(
        self,
        data: gmshio.MeshData,
        report: dict[str, Any] | None = None,
        fractures: Any = None,
        *,
        tags: dict[int, Any] | None = None,
        split: tuple[str, ...] = (),
    ) -> None:
        self.mesh = data.mesh
        self.split = split
        self.report = report or {}
        self.fractures = fractures
        self.groups = {name: (g.dim, g.tag) for name, g in data.physical_groups.items()}
        tdim = self.mesh.topology.dim
        by_codim = [data.cell_tags, data.facet_tags, data.ridge_tags, data.peak_tags]
        self.tags = {tdim - c: t for c, t in enumerate(by_codim) if tdim - c >= 0}
        self.tags.update(tags or {})

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


def _overlaps(model: Any, tdim: int) -> tuple[str | None, dict[int, int]]:
    """Overlapping physical groups of ``model`` (rank 0).

    Returns:
        (a message when cell groups overlap, which DOLFINx cannot mesh, else None;
        dimension < tdim with overlapping groups -> nodes per element of its groups,
        or 0 when they mix element types and cannot be retagged).
    """
    owners: dict[tuple[int, int], str] = {}
    dims: dict[int, int] = {}
    for d, tag in model.getPhysicalGroups():
        name = model.getPhysicalName(d, tag)
        for entity in model.getEntitiesForPhysicalGroup(d, tag):
            other = owners.setdefault((d, int(entity)), name)
            if other == name:
                continue
            if d == tdim:
                return (
                    f"physical groups '{other}' and '{name}' share the {d}D entity {entity}; "
                    "DOLFINx gives each cell one group, so cell groups must not overlap",
                    {},
                )
            dims[d] = 0
    for d in dims:
        types = {
            int(t)
            for _, tag in model.getPhysicalGroups(d)
            for e in model.getEntitiesForPhysicalGroup(d, tag)
            for t in model.mesh.getElements(d, e)[0]
        }
        if len(types) == 1:
            dims[d] = int(model.mesh.getElementProperties(types.pop())[3])
    return None, dims


def _group_tags(model: Any, data: gmshio.MeshData, dims: dict[int, int]) -> dict[int, Any]:
    """Mesh tags in which each physical group of the dimensions ``dims`` has all its entities.

    ``model_to_mesh`` keeps one tag per entity, so of two overlapping groups one loses the
    shared entities. Here each group is distributed and located on its own, and the tags
    of one dimension hold an (entity, group tag) pair per membership, sorted by entity.
    Collective.

    Args:
        model: the gmsh model on rank 0, None elsewhere.
        data: what ``model_to_mesh`` made of it.
        dims: dimension -> nodes per element (from :func:`_overlaps`, the same on every
            rank); dimensions with 0 are left as ``model_to_mesh`` tagged them.
    """
    from dolfinx.graph import adjacencylist
    from dolfinx.io.utils import distribute_entity_data
    from dolfinx.mesh import meshtags, meshtags_from_entities

    mesh = data.mesh
    tdim = mesh.topology.dim
    out = {}
    groups = sorted((g.dim, g.tag) for g in data.physical_groups.values())
    for d, nodes in sorted(dims.items()):
        if nodes == 0:
            continue
        mesh.topology.create_connectivity(d, tdim)
        indices, values = [], []
        for gd, tag in groups:
            if gd != d:
                continue
            marked = np.empty((0, nodes), dtype=np.int64)
            if model is not None:
                blocks = [
                    conn.reshape(-1, nodes).astype(np.int64) - 1
                    for e in model.getEntitiesForPhysicalGroup(d, tag)
                    for conn in model.mesh.getElements(d, e)[2]
                ]
                marked = np.concatenate(blocks) if blocks else marked
            local, local_values = distribute_entity_data(
                mesh, d, marked, np.full(len(marked), tag, dtype=np.int32)
            )
            group = meshtags_from_entities(
                mesh, d, adjacencylist(local), local_values.astype(np.int32, copy=False)
            )
            indices.append(group.indices)
            values.append(group.values)
        index, value = np.concatenate(indices), np.concatenate(values)
        order = np.lexsort((value, index))
        tags = meshtags(mesh, d, index[order].astype(np.int32), value[order].astype(np.int32))
        tags.name = f"dim{d}_tags"
        out[d] = tags
    return out


def _idle_until_rank0(comm: MPI.Comm, poll: float = 0.005) -> None:
    """Wait for rank 0's meshing without spinning a core.

    MPICH's blocking collectives poll flat out; waiting in one slowed gmsh on rank 0 by up
    to 1.7x on a 2-core machine.
    """
    request = comm.Ibarrier()
    while not request.Test():
        time.sleep(poll)


def _failure(source: str, geometry: Geometry, exc: BaseException, gmsh: ModuleType | None) -> str:
    """One line saying what failed, never an empty message."""
    from geofrac.meshing.geo import GmshTimeout, MeshingFailed

    if isinstance(exc, GmshTimeout | MeshingFailed):
        return str(exc)
    detail = failure_message(exc, gmsh)
    if detail:
        return f"meshing {source} failed: {detail}"
    if geometry.builder is not None:
        return f"meshing {source} failed ({type(exc).__name__} with no message)"
    return (
        f"meshing {source} with parameters {geometry.parameters} failed (gmsh gave no "
        f"message; run gmsh {geometry.file} -{geometry.dim} to see its log)"
    )


def renumber_model(gmsh: ModuleType, seed: int) -> None:
    """Number the meshed model's nodes and order each entity's elements at random (seeded).

    The same mesh, numbered otherwise: DOLFINx takes the nodes in tag order and the
    cells in the order gmsh stores them, so the distributed mesh's input numbering, the
    crack driver's node, edge and cell ids and the solver's DOF order all change, while
    every node and cell stays where it was. A result that changes with ``seed`` depends
    on the numbering (a tie broken by id, a sum in another order): the scenes' key
    ``discretization.renumber`` (docs/scenes.md).

    Args:
        gmsh: the gmsh module with the meshed model current.
        seed: seed of ``numpy.random.default_rng``.
    """
    rng = np.random.default_rng(seed)
    dim = gmsh.model.getDimension()
    # the cells' nodes trade tags among themselves; a node of no cell (the centre point of
    # a hole's arcs) keeps its tag, as DOLFINx needs such nodes where gmsh put them
    used = np.unique(np.concatenate([*gmsh.model.mesh.getElements(dim)[2], np.zeros(0)]))
    used = used.astype(np.uint64)
    gmsh.model.mesh.renumberNodes(used, used[rng.permutation(len(used))])
    for dim, tag in gmsh.model.getEntities():
        types, elements, _ = gmsh.model.mesh.getElements(dim, tag)
        for kind, ids in zip(types, elements, strict=True):
            if len(ids) > 1:
                gmsh.model.mesh.reorderElements(kind, tag, rng.permutation(len(ids)))


def build_mesh(geometry: Geometry, comm: MPI.Comm, *, verbose: bool = False) -> TaggedMesh:
    """Mesh ``geometry`` with gmsh on rank 0 and distribute the mesh over ``comm``.

    A ``.geo`` file is checked and meshed in a child process under the geometry's time
    limit (:func:`~geofrac.meshing.geo.meshed_model`); a ``geometry.builder`` creates and
    meshes the model itself in-process; its report and payload reach every rank
    (:attr:`TaggedMesh.report`, :attr:`TaggedMesh.fractures`). Physical groups of a
    lower dimension may overlap (each keeps all its entities); cell groups may not.
    With ``geometry.renumber`` the mesh is renumbered first (:func:`renumber_model`);
    with ``geometry.split`` it is then cut along those curve groups
    (:func:`~geofrac.meshing.split.split_model`).

    Raises:
        RunError: gmsh (or the builder) failed or timed out, or cell groups overlap
            (raised on every rank).
    """
    if comm.rank != 0:
        _idle_until_rank0(comm)
        message, report, payload, dims = comm.bcast(None, root=0)
        if message is not None:
            raise RunError(message)
        data = gmshio.model_to_mesh(None, comm, 0, gdim=geometry.dim)
        return TaggedMesh(
            data, report, payload, tags=_group_tags(None, data, dims), split=geometry.split
        )
    builder = geometry.builder
    with ExitStack() as stack:
        message, report, payload, dims = None, None, None, {}
        gmsh: ModuleType | None = None
        try:
            if builder is not None:
                gmsh = stack.enter_context(
                    gmsh_session(None, geometry.parameters, geometry.mesh_size, verbose=verbose)
                )
                report, payload = builder.build(gmsh)
            else:
                assert geometry.file is not None
                gmsh = stack.enter_context(
                    meshed_model(
                        geometry.file,
                        geometry.parameters,
                        geometry.mesh_size,
                        dim=geometry.dim,
                        time_limit=geometry.time_limit,
                        trusted=geometry.trusted,
                        verbose=verbose,
                        algorithm=geometry.algorithm,
                    )
                )
            assert gmsh is not None  # one of the two sessions is open
            if len(gmsh.model.mesh.getNodes()[0]) == 0:
                raise RuntimeError("gmsh produced no nodes")
            if geometry.renumber is not None:
                renumber_model(gmsh, geometry.renumber)
            if geometry.split:
                split_model(gmsh, geometry.split)
            _check_groups_on_cells(gmsh.model, geometry.dim)
            overlap, dims = _overlaps(gmsh.model, geometry.dim)
            if overlap is not None:
                raise RuntimeError(overlap)
        except Exception as exc:  # gmsh raises bare Exceptions
            source = builder.name if builder else geometry.file.name  # type: ignore[union-attr]
            message = _failure(source, geometry, exc, gmsh)
        comm.Ibarrier().Wait()  # releases the ranks idling in _idle_until_rank0
        comm.bcast((message, report, payload, dims), root=0)
        if message is not None:
            raise RunError(message)
        assert gmsh is not None  # no message: the model was made
        data = gmshio.model_to_mesh(gmsh.model, comm, 0, gdim=geometry.dim)
        return TaggedMesh(
            data, report, payload, tags=_group_tags(gmsh.model, data, dims), split=geometry.split
        )


def _upper_face(tagged: TaggedMesh, dim: int, facets: np.ndarray) -> np.ndarray:
    """Which facets (local indices, shape=(n,)) to count once on a cut joint, shape=(n,).

    A facet with two cells (a piece of the joint that stayed whole) counts; of a facet
    with one cell, only the face whose cell lies on the side the facet's upward normal
    (n_y > 0, or n_x > 0 when vertical to 1e-9) points to.
    """
    mesh = tagged.mesh
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(dim, tdim)
    f2c = mesh.topology.connectivity(dim, tdim)
    xy = tagged.vertex_coordinates(dim, facets)[:, :, :2]
    keep = np.ones(len(facets), dtype=bool)
    for k, f in enumerate(facets):
        cells = f2c.links(f)
        if len(cells) != 1:
            continue
        t = xy[k, 1] - xy[k, 0]
        n = np.array([-t[1], t[0]]) / np.linalg.norm(t)
        if n[1] < -1e-9 or (abs(n[1]) <= 1e-9 and n[0] < 0):
            n = -n
        centre = tagged.vertex_coordinates(tdim, cells)[0, :, :2].mean(axis=0)
        keep[k] = float(np.dot(centre - xy[k].mean(axis=0), n)) > 0
    return keep


def check_fracture_cover(tagged: TaggedMesh, group: str = "fractures") -> dict[str, Any]:
    """Check that the facets tagged ``group`` cover the network exactly (collective).

    Each rank matches the facets it owns to the network edges
    (:func:`geofrac.dfn.check.match_facets`); lengths are summed over ranks. When the
    mesh was cut along ``group`` (:attr:`TaggedMesh.split`), one face of each cut facet
    counts. Every
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
    if group in tagged.split:  # a cut joint has a facet per face: count one face
        facets = facets[_upper_face(tagged, dim, facets)]
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
