"""Blocks of a distributed DOLFINx mesh: each rank builds the blocks of the vertices it owns.

Each rank works on the cells it owns (:func:`~geofrac.blocks.dual3d.tet_corners`,
:func:`~geofrac.blocks.dual2d.tri_corners`). A vertex on the partition boundary has
cells on several ranks; DOLFINx 0.11 ghosts cells only across facets (there is no
``shared_vertex`` ghost mode), so the ghost layer does not hold a vertex's whole
neighbourhood. Instead, the faces and pieces a rank computes for a vertex it does not
own are sent to the vertex's owner, with the (kind, key, coordinates) of their points,
and merged there. Points are computed from their vertices in increasing global-id
order (the mesh's input node index), so the same point has the same coordinates on
every rank, and the block set does not depend on the number of ranks.

This is the only module of :mod:`geofrac.blocks` that imports DOLFINx and MPI.
"""

from __future__ import annotations

from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from dolfinx.mesh import CellType, Mesh, exterior_facet_indices
from mpi4py import MPI

from geofrac.blocks.dual2d import rings, tri_corners
from geofrac.blocks.dual3d import Corners, assemble, tet_corners
from geofrac.blocks.model import Blocks

__all__ = ["build_blocks", "exchange", "gather_blocks", "mesh_cells", "owned_measure"]


def mesh_cells(mesh: Mesh) -> dict[str, Any]:
    """This rank's owned simplices, with what the block builders need.

    Returns:
        ``x`` vertex coordinates per cell, shape=(num_owned_cells, nv, gdim);
        ``gid`` global (input) vertex ids, shape=(num_owned_cells, nv);
        ``cell_key`` input cell indices, shape=(num_owned_cells,);
        ``boundary`` facet k (opposite vertex k) on the domain boundary,
        shape=(num_owned_cells, nv); ``owner`` the rank owning each cell vertex,
        shape=(num_owned_cells, nv); ``owned_ids`` the global ids of the vertices this
        rank owns, sorted, shape=(num_owned_vertices,); ``num_vertices`` an upper bound
        of the global ids.

    Raises:
        ValueError: the mesh is not made of linear triangles or tetrahedra.
    """
    topology, geometry = mesh.topology, mesh.geometry
    tdim = topology.dim
    if topology.cell_type not in (CellType.triangle, CellType.tetrahedron):
        raise ValueError(f"blocks need triangles or tetrahedra, not {topology.cell_type.name}")
    nv = tdim + 1
    dofmap = geometry.dofmaps[0]
    if dofmap.shape[1] != nv:
        raise ValueError("blocks need a linear (straight-sided) mesh")
    num_cells = topology.index_map(tdim).size_local
    c2v = topology.connectivity(tdim, 0).array.reshape(-1, nv)[:num_cells]
    nodes = dofmap[:num_cells]
    gdim = geometry.x.shape[1] if tdim == 3 else 2
    x = geometry.x[nodes][:, :, :gdim]
    inputs = np.asarray(geometry.input_global_indices, dtype=np.int64)
    gid = inputs[nodes]
    vmap = topology.index_map(0)
    owners = np.concatenate([np.full(vmap.size_local, mesh.comm.rank, dtype=np.int32), vmap.owners])
    topology.create_connectivity(tdim - 1, tdim)
    topology.create_connectivity(tdim, tdim - 1)
    exterior = np.zeros(
        topology.index_map(tdim - 1).size_local + topology.index_map(tdim - 1).num_ghosts,
        dtype=bool,
    )
    exterior[exterior_facet_indices(topology)] = True
    c2f = topology.connectivity(tdim, tdim - 1).array.reshape(-1, nv)[:num_cells]
    mine = c2v < vmap.size_local
    owned_ids = np.unique(gid[mine])
    num_vertices = mesh.comm.allreduce(int(inputs.max(initial=-1)) + 1, op=MPI.MAX)
    return {
        "x": x,
        "gid": gid,
        "cell_key": np.asarray(topology.original_cell_index[:num_cells], dtype=np.int64),
        "boundary": exterior[c2f],
        "owner": owners[c2v],
        "owned_ids": owned_ids,
        "num_vertices": num_vertices,
    }


def owned_measure(mesh: Mesh) -> float:
    """Volume (area in 2D) of this rank's owned cells of a linear simplex mesh.

    Read off the geometry alone (no connectivity): the domain volume the block volumes
    must sum to, once summed over the ranks.
    """
    tdim = mesh.topology.dim
    nodes = mesh.geometry.dofmaps[0][: mesh.topology.index_map(tdim).size_local]
    x = mesh.geometry.x[nodes]
    d = x[:, 1:] - x[:, :1]
    if tdim == 3:
        return float(np.abs(np.einsum("ij,ij->i", d[:, 0], np.cross(d[:, 1], d[:, 2]))).sum() / 6)
    return float(np.abs(d[:, 0, 0] * d[:, 1, 1] - d[:, 0, 1] * d[:, 1, 0]).sum() / 2)


def gather_blocks(blocks: Blocks, comm: MPI.Comm) -> Blocks | None:
    """The whole block set on rank 0 (None elsewhere), shared points welded (collective).

    Welding (:func:`geofrac.blocks.model.weld`) merges the points the ranks computed
    apart, so a face two ranks' blocks share is recognised by its point indices.
    """
    from geofrac.blocks.model import join, weld

    parts = comm.gather(blocks, root=0)
    if comm.rank != 0:
        return None
    assert parts is not None  # rank 0
    whole = parts[0]
    for part in parts[1:]:
        whole = join(whole, part)
    return weld(whole)


def exchange(corners: Corners, ids: np.ndarray, ranks: np.ndarray, *, comm: MPI.Comm) -> Corners:
    """Send each face and piece to the rank owning its block; merge what arrives.

    Args:
        corners: this rank's contributions.
        ids: global vertex ids, sorted, covering every block id in ``corners``,
            shape=(n,).
        ranks: the rank owning each of ``ids``, shape=(n,).
        comm: the communicator.

    Returns:
        The faces and pieces of this rank's blocks, from every rank.
    """
    if comm.size == 1:
        return corners

    def dest(block: np.ndarray) -> np.ndarray:
        return ranks[np.searchsorted(ids, block)]

    table = corners.table
    face_dest, piece_dest = dest(corners.face_block), dest(corners.piece_block)
    outgoing: list[tuple[object, ...] | None] = []
    for r in range(comm.size):
        if r == comm.rank:
            outgoing.append(None)
            continue
        f = np.flatnonzero(face_dest == r)
        p = np.flatnonzero(piece_dest == r)
        refs = np.concatenate([corners.faces[f].ravel(), corners.pieces[p].ravel()])
        kind, key, x = table.describe(refs)
        extra = None if corners.extra is None else corners.extra[f]
        outgoing.append(
            (
                corners.face_block[f],
                corners.faces.shape[1],
                extra,
                corners.piece_block[p],
                corners.pieces.shape[1],
                kind,
                key,
                x,
            )
        )
    incoming = comm.alltoall(outgoing)
    keep_f, keep_p = face_dest == comm.rank, piece_dest == comm.rank
    parts = [m for m in incoming if m is not None]
    kinds = np.concatenate([m[5] for m in parts] or [np.empty(0, np.int64)])
    keys = np.concatenate([m[6] for m in parts] or [np.empty(0, np.int64)])
    xs = np.concatenate([m[7] for m in parts] or [np.empty((0, table.x.shape[1]))])
    refs = table.append(kinds, keys, xs)
    face_block = [corners.face_block[keep_f]]
    faces = [corners.faces[keep_f]]
    extras = [] if corners.extra is None else [corners.extra[keep_f]]
    piece_block = [corners.piece_block[keep_p]]
    pieces = [corners.pieces[keep_p]]
    start = 0
    for fb, fw, fx, pb, pw, *_ in parts:
        n_face = len(fb) * fw
        faces.append(refs[start : start + n_face].reshape(-1, fw))
        start += n_face
        n_piece = len(pb) * pw
        pieces.append(refs[start : start + n_piece].reshape(-1, pw))
        start += n_piece
        face_block.append(fb)
        piece_block.append(pb)
        if fx is not None:
            extras.append(fx)
    return Corners(
        table=table,
        face_block=np.concatenate(face_block),
        faces=np.concatenate(faces),
        piece_block=np.concatenate(piece_block),
        pieces=np.concatenate(pieces),
        extra=np.concatenate(extras) if extras else None,
    )


def build_blocks(
    mesh: Mesh,
    inner: str = "incentre",
    radius: float = 1.0,
    *,
    convex: bool = False,
    seed: int = 0,
) -> Blocks:
    """The blocks of the vertices this rank owns (collective).

    Args:
        mesh: a distributed mesh of linear triangles or tetrahedra.
        inner: 2D, the triangles' inner point (:func:`~geofrac.geometry.triangles.inner_points`).
        radius: 2D, the movable region's relative radius.
        convex: 2D, keep pieces convex.
        seed: 2D, the random seed.
    """
    cells = mesh_cells(mesh)
    tdim = mesh.topology.dim
    if tdim == 3:
        corners = tet_corners(
            cells["x"],
            cells["gid"],
            cells["cell_key"],
            boundary=cells["boundary"],
            num_vertices=cells["num_vertices"],
        )
    else:
        corners = tri_corners(
            cells["x"],
            cells["gid"],
            cells["boundary"],
            num_vertices=cells["num_vertices"],
            inner=inner,
            radius=radius,
            convex=convex,
            seed=seed,
        )
    if mesh.comm.size > 1:
        ids, first = np.unique(cells["gid"].ravel(), return_index=True)
        corners = exchange(corners, ids, cells["owner"].ravel()[first], comm=mesh.comm)
    if tdim == 3:
        return assemble(corners, cells["owned_ids"], 3)
    return rings(corners, cells["owned_ids"])
