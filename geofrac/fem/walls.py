"""Loads on an opening's wall: facets inside the mesh with one live side (docs/insitu.md).

A ``traction`` or ``pressure`` is integrated with ``ds``, over exterior facets. An
opening's wall is an interior curve of the mesh (between the rock and the opening's
cells) until a stage removes the opening's cells. A load on a facet group with facets
inside the mesh is accepted when it has ``from = STAGE`` and each of its facets has
exactly one live cell in every step the load acts in (the same cell throughout): it is
integrated on that cell's side, as an exterior-facet integral over explicit (cell, local
facet) pairs, so ``ufl.FacetNormal`` is the outward normal of the live region and a
pressure pushes into the rock. Each pair is listed by the rank owning its live cell, so
every facet is integrated once on any number of ranks (with or without ghost cells).

When a scene has such a load, the problem's ``ds`` lists explicit entities for every
facet group too (each group's exterior facets, as DOLFINx computes them from the facet
tags), since a form takes one subdomain data per integral type; otherwise ``ds`` is the
usual measure of the facet tags, unchanged.
"""

from __future__ import annotations

from collections.abc import Sequence

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Scene, Stage, acts

__all__ = ["facet_measure", "live_cells", "wall_entities"]


def live_cells(tagged: TaggedMesh, stages: Sequence[Stage], step: int) -> np.ndarray:
    """Which local cells (owned and ghost) are live in ``step``, shape=(n_cells,), bool.

    Step 0 is the initial state: every cell but those of a group that a stage adds
    before any stage removed it (absent until added); step k is the state after stage
    k's ``remove`` and ``add``.
    """
    tdim = tagged.mesh.topology.dim
    imap = tagged.mesh.topology.index_map(tdim)
    live = np.ones(imap.size_local + imap.num_ghosts, dtype=bool)
    seen: set[str] = set()
    for stage in stages:
        seen.update(stage.remove)
        for group in stage.add:
            if group not in seen:
                live[tagged.entities(group)[1]] = False
            seen.add(group)
    for stage in stages[:step]:
        for group in stage.remove:
            live[tagged.entities(group)[1]] = False
        for group in stage.add:
            live[tagged.entities(group)[1]] = True
    return live


def _facet_sum(tagged: TaggedMesh, values: np.ndarray) -> np.ndarray:
    """Per local facet, the sum over ranks of ``values``, shape=(n_facets,) (collective).

    ``values``: per local facet (owned and ghost), shape=(n_facets,); each rank's
    contribution is added to the owner's and the total sent back to every rank.
    """
    fdim = tagged.mesh.topology.dim - 1
    vector = dolfinx.la.vector(tagged.mesh.topology.index_map(fdim), 1)
    vector.array[:] = values
    vector.scatter_reverse(dolfinx.la.InsertMode.add)
    vector.scatter_forward()
    return vector.array.copy()


def _cell_facets(tagged: TaggedMesh) -> np.ndarray:
    """The local facets of every owned cell, shape=(n_owned, facets per cell)."""
    top = tagged.mesh.topology
    tdim = top.dim
    top.create_connectivity(tdim, tdim - 1)
    top.create_connectivity(tdim - 1, tdim)
    n_owned = top.index_map(tdim).size_local
    c2f = top.connectivity(tdim, tdim - 1)
    return c2f.array[: c2f.offsets[n_owned]].reshape(n_owned, -1)


def _counts(tagged: TaggedMesh, cells: np.ndarray) -> np.ndarray:
    """Per local facet, the number of cells beside it on all ranks, shape=(n_facets,).

    ``cells``: which owned cells count, bool, shape=(n_owned,) (collective).
    """
    fdim = tagged.mesh.topology.dim - 1
    imap = tagged.mesh.topology.index_map(fdim)
    local = np.zeros(imap.size_local + imap.num_ghosts)
    np.add.at(local, _cell_facets(tagged)[cells].ravel(), 1.0)
    return np.rint(_facet_sum(tagged, local)).astype(np.int64)


def wall_entities(tagged: TaggedMesh, scene: Scene, index: int) -> np.ndarray | None:
    """The (live cell, local facet) pairs of ``scene.loads[index]`` on this rank (collective).

    Returns None when the load's facet group lies on the mesh's boundary (the ordinary
    ``ds(tag)``); else the pairs, flat, shape=(2 m,), int32, each listed by the rank
    owning the live cell.

    Raises:
        RunError: collectively, naming ``load[index].group``: the group has facets inside
            the mesh and the load has no ``from``, or in a step it acts in one of its
            facets has live cells on both sides, none, or another one than at ``from``.
    """
    load = scene.loads[index]
    assert load.group is not None
    top, comm = tagged.mesh.topology, tagged.mesh.comm
    fdim = top.dim - 1
    n_owned = top.index_map(top.dim).size_local
    n_facets = top.index_map(fdim).size_local
    marked = np.zeros(top.index_map(fdim).size_local + top.index_map(fdim).num_ghosts)
    marked[tagged.entities(load.group)[1]] = 1.0
    member = _facet_sum(tagged, marked) > 0.5  # every rank sees the group's facets whole
    cells = _counts(tagged, np.ones(n_owned, dtype=bool))
    owned = member[:n_facets]
    inside = comm.allreduce(int(np.count_nonzero(cells[:n_facets][owned] == 2)), op=MPI.SUM)
    if not inside:
        return None
    key = f"load[{index}].group"
    where = f"{inside} facets of group '{load.group}' lie inside the mesh (between two cells)"
    if load.switch_on is None:
        raise RunError(
            f"{key}: {where} and the load has no 'from': a traction or pressure acts on such "
            "facets only once a stage has removed the cells on one side (an opening's wall: "
            "give the load from = the stage that excavates it), or put it on a boundary group"
        )
    names = [stage.name for stage in scene.stages]
    first: np.ndarray | None = None
    for step in range(len(scene.stages) + 1):
        if not acts(load, step, names):
            continue
        live = live_cells(tagged, scene.stages, step)[:n_owned]
        count = _counts(tagged, live)[:n_facets][owned]
        both = comm.allreduce(int(np.count_nonzero(count > 1)), op=MPI.SUM)
        none = comm.allreduce(int(np.count_nonzero(count == 0)), op=MPI.SUM)
        if both or none:
            why = f"{both} have live cells on both sides" if both else ""
            why += " and " if both and none else ""
            why += f"{none} have no live cell (both sides removed)" if none else ""
            raise RunError(
                f"{key}: at stage '{names[step - 1]}', of the facets of group "
                f"'{load.group}', {why}: a traction or pressure on facets inside the mesh "
                "needs exactly one live cell beside each facet in every stage it acts in "
                "(from the stage that removes the cells on one side, until a stage adds "
                "them back or removes the other side)"
            )
        pairs = _pairs(tagged, live, member)
        if first is None:
            first = pairs
        moved = int(len(pairs) != len(first) or not np.array_equal(pairs, first))
        if comm.allreduce(moved, op=MPI.SUM):
            raise RunError(
                f"{key}: at stage '{names[step - 1]}' the live side of group "
                f"'{load.group}' changes (its cells on the other side are live now): a "
                "traction or pressure on facets inside the mesh keeps one side; switch it "
                "off there (until) and give a new load"
            )
    assert first is not None  # a load with from acts in its stage
    return first


def _pairs(tagged: TaggedMesh, live: np.ndarray, member: np.ndarray) -> np.ndarray:
    """The (owned live cell, local facet) pairs on the group's facets, flat, int32.

    ``live``: owned cells, shape=(n_owned,); ``member``: local facets, shape=(n_facets,).
    """
    facets = _cell_facets(tagged)
    cell, local = np.nonzero(member[facets] & live[:, None])
    return np.column_stack([cell, local]).ravel().astype(np.int32)


def facet_measure(tagged: TaggedMesh, scene: Scene) -> tuple[ufl.Measure, dict[int, int]]:
    """The problem's ``ds`` and, per load on facets inside the mesh, its subdomain id.

    Without such a load, ``ds`` is the measure of the facet tags (unchanged); with one,
    explicit entities: each facet tag's exterior facets under its own id (what DOLFINx
    computes from the tags) and each wall load's pairs (:func:`wall_entities`) under a
    new id (collective).

    Raises:
        RunError: collectively, from :func:`wall_entities`.
    """
    mesh = tagged.mesh
    fdim = mesh.topology.dim - 1
    tags = tagged.tags.get(fdim)
    walls: dict[int, np.ndarray] = {}
    for i, load in enumerate(scene.loads):
        if load.type in ("traction", "pressure"):
            entities = wall_entities(tagged, scene, i)
            if entities is not None:
                walls[i] = entities
    if not walls:
        return ufl.Measure("ds", domain=mesh, subdomain_data=tags), {}
    assert tags is not None  # a wall load names a facet group
    ids = sorted({t for d, t in tagged.groups.values() if d == fdim})
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    kind = dolfinx.fem.IntegralType.exterior_facet
    data = [
        (
            tag,
            dolfinx.fem.compute_integration_domains(
                kind, mesh.topology, np.intersect1d(tags.find(tag), exterior)
            ),
        )
        for tag in ids
    ]
    start = max(ids, default=0) + 1
    numbers = {i: start + n for n, i in enumerate(walls)}
    data += [(numbers[i], entities) for i, entities in walls.items()]
    return ufl.Measure("ds", domain=mesh, subdomain_data=data), numbers
