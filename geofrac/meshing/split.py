"""Split a mesh along joints: the joint's nodes get one copy per side (pure numpy).

A joint is a set of mesh facets (edges of triangles in 2D, triangular faces of tetrahedra
in 3D) across which the displacement may jump. The continuous field cannot jump, so the
mesh is cut along the joint: for each vertex on a joint, its incident cells are grouped
into *sectors*, cells joined through a non-joint facet at that vertex being in one sector
(the joint facets separate sectors); the first sector keeps the vertex and every further
sector gets its own copy. So

- a vertex inside a through-going joint has 2 sectors (doubled), as has a joint vertex
  on the domain's boundary (the joint cuts the boundary there);
- a joint's tip inside the rock (in 3D: a vertex on a fracture's free edge) has 1 sector
  (not split: the jump is zero at a tip);
- a T junction (in 3D: a vertex on the line where one fracture ends on another) has 3
  sectors, an X crossing (the line where two fractures cross) 4.

Second-order triangles (2D only; 3D cuts need first-order tetrahedra): the midpoint of a
joint edge gets a copy in the second of its two cells where the edge's end vertices
differ between them after the split (an edge whose two ends stayed shared, a one-edge
joint with both ends tips, stays whole). Cells keep their number, order and shape; only
their node numbers change.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["split_along", "split_along_faces", "split_model"]

#: local vertices of a triangle's edges 01, 12, 20 (gmsh and VTK order; the midpoints of
#: a 6-node triangle follow in the same order).
EDGES = np.array([[0, 1], [1, 2], [2, 0]])
#: local vertices of a tetrahedron's faces, face i opposite vertex i
FACES = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
#: local vertices of a tetrahedron's six edges
TET_EDGES = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
#: gmsh element types of the 3- and 6-node triangle
TRIANGLES = (2, 9)
#: gmsh element type of the 4-node tetrahedron (the only 3D cell cut)
TETRAHEDRA = (4,)
#: gmsh element type of the 10-node tetrahedron (refused: 3D cuts need first-order cells)
TET10 = 11
#: (cell dimension, element dimension) -> local vertices of the cell's sub-entities
SUBSETS = {(2, 1): EDGES, (3, 2): FACES, (3, 1): TET_EDGES}


def _ids(rows: np.ndarray, base: int) -> np.ndarray:
    """One integer per node set, equal for equal sets (whatever the order), shape=(k,).

    Args:
        rows: the sets, node ids in [0, base), shape=(k, q).
        base: more than the largest id.
    """
    rows = np.sort(rows, axis=1)
    if base ** rows.shape[1] < 2**63:  # min * base + max for an edge
        key = np.zeros(len(rows), dtype=np.int64)
        for column in rows.T:
            key = key * base + column
        return key
    return np.unique(rows, axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)


def _shared_facets(keys: np.ndarray, noun: str) -> tuple[np.ndarray, np.ndarray]:
    """The (cell, local facet) pairs that are one facet.

    Args:
        keys: one integer per (cell, local facet), shape=(n, f).
        noun: the facet in the message ("an edge", "a face").

    Returns:
        first and second (cell * f + local facet) of each shared facet, shape=(s,) each.

    Raises:
        ValueError: a facet shared by more than two cells.
    """
    flat = keys.ravel()
    order = np.argsort(flat, kind="stable")
    same = flat[order][1:] == flat[order][:-1]
    if np.any(same[1:] & same[:-1]):
        raise ValueError(f"{noun} is shared by more than two cells (a non-manifold mesh)")
    i = np.flatnonzero(same)
    return order[i], order[i + 1]


def _sectors(
    verts: np.ndarray, table: np.ndarray, joint: np.ndarray, one: np.ndarray, two: np.ndarray
) -> np.ndarray:
    """Component label of each corner (cell * v + local vertex), shape=(v n,).

    Two corners of the same vertex are joined where their cells share a non-joint facet.

    Args:
        verts: the cells' vertices, shape=(n, v).
        table: local vertices of each facet of a cell, shape=(f, v - 1).
        joint: whether each (cell, local facet) is on a joint, shape=(n, f).
        one: the first (cell * f + local facet) of each shared facet, shape=(s,).
        two: the second, shape=(s,) (:func:`_shared_facets`).
    """
    n, v = verts.shape
    f = len(table)
    keep = ~joint.ravel()[one]
    c1, f1 = np.divmod(one[keep], f)
    c2 = two[keep] // f
    rows, cols = [], []
    for end in range(table.shape[1]):
        l1 = table[f1, end]
        l2 = np.argmax(verts[c2] == verts[c1, l1][:, None], axis=1)
        rows.append(v * c1 + l1)
        cols.append(v * c2 + l2)
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(v * n, v * n))
    return connected_components(graph, directed=False)[1]


def _split(
    cells: np.ndarray, facets: np.ndarray, table: np.ndarray, *, first_new: int | None
) -> tuple[np.ndarray, np.ndarray]:
    """Cut simplices along joint facets (:func:`split_along`, :func:`split_along_faces`).

    Args:
        cells: the cells' nodes, the vertices first, shape=(n, p), p >= v.
        facets: the joint facets by their vertices, shape=(m, v - 1).
        table: local vertices of each facet of a cell, shape=(f, v - 1).
        first_new: id of the first new node (None: the largest id + 1).

    Returns:
        (the cells with the split nodes, shape=(n, p); the original node of each new
        node, shape=(q,)).
    """
    n, (f, q) = len(cells), table.shape
    v = q + 1
    base = int(max(cells.max(), facets.max())) + 1
    first = base if first_new is None else int(first_new)
    ends = cells[:, table]  # (n, f, q)
    ids = _ids(np.concatenate([ends.reshape(-1, q), facets]), base)
    keys = ids[: n * f].reshape(n, f)
    joint = np.isin(keys, ids[n * f :])
    one, two = _shared_facets(keys, "an edge" if q == 2 else "a face")
    labels = _sectors(cells[:, :v], table, joint, one, two)
    # the corners on joints: a sector per label; the first (lowest corner) keeps the vertex
    on_joint = np.isin(cells[:, :v], np.unique(ends[joint])).ravel()
    corners = np.flatnonzero(on_joint)
    out = cells.copy()
    if len(corners) == 0:  # no joint facet is a facet of a cell
        return out, np.zeros(0, dtype=np.int64)
    vertex = cells[:, :v].ravel()[corners]
    ulab, at = np.unique(labels[corners], return_index=True)
    order = np.lexsort((corners[at], vertex[at]))
    lab_sorted, vert_sorted = ulab[order], vertex[at][order]
    fresh = np.ones(len(order), dtype=bool)
    fresh[0] = False
    fresh[1:] = vert_sorted[1:] == vert_sorted[:-1]
    node_of_label = vert_sorted.copy()
    node_of_label[fresh] = first + np.arange(np.count_nonzero(fresh))
    source = [vert_sorted[fresh]]
    verts = out[:, :v].ravel()
    node_map = np.zeros(int(labels.max()) + 1, dtype=np.int64)
    node_map[lab_sorted] = node_of_label
    verts[corners] = node_map[labels[corners]]
    out[:, :v] = verts.reshape(-1, v)
    if q == 2 and cells.shape[1] == 6:
        source.append(_split_midpoints(out, joint, one, two, first + len(source[0])))
    return out, np.concatenate(source).astype(np.int64)


def split_along(
    cells: np.ndarray, joint_edges: np.ndarray, *, first_new: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Cut a triangle mesh along joint edges.

    Args:
        cells: the triangles' nodes, the 3 vertices first (then, for 6-node triangles, the
            midpoints of the edges 01, 12, 20), non-negative ids, shape=(n, 3) or (n, 6).
        joint_edges: the joints' edges by their two end vertices, shape=(m, 2). Edges
            that are no edge of a cell are ignored.
        first_new: id of the first new node (default: the largest id in ``cells`` + 1).

    Returns:
        (the cells with the split nodes, shape=(n, 3) or (n, 6); the original node of each
        new node, new node ``first_new + i`` copying ``source[i]``, shape=(q,)).

    Raises:
        ValueError: cells not triangles, or a non-manifold mesh.
    """
    cells = np.asarray(cells, dtype=np.int64)
    joint_edges = np.asarray(joint_edges, dtype=np.int64).reshape(-1, 2)
    if cells.ndim != 2 or cells.shape[1] not in (3, 6):
        raise ValueError(f"split_along takes 3- or 6-node triangles, got cells {cells.shape}")
    if len(cells) == 0 or len(joint_edges) == 0:
        return cells.copy(), np.zeros(0, dtype=np.int64)
    return _split(cells, joint_edges, EDGES, first_new=first_new)


def split_along_faces(
    cells: np.ndarray, faces: np.ndarray, *, first_new: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Cut a tetrahedral mesh along joint faces.

    A vertex inside a through-going joint surface (or where it meets the domain's
    boundary) gets 2 sectors, one on a fracture's free edge 1 (not split), one on the
    line where two fractures cross 4, on a T line (a fracture ending on another) 3.

    Args:
        cells: the 4-node tetrahedra's nodes, non-negative ids, shape=(n, 4).
        faces: the joints' triangles by their three vertices (any order), shape=(m, 3).
            Triangles that are no face of a cell are ignored.
        first_new: id of the first new node (default: the largest id in ``cells`` + 1).

    Returns:
        (the cells with the split nodes, shape=(n, 4); the original node of each new node,
        new node ``first_new + i`` copying ``source[i]``, shape=(q,)).

    Raises:
        ValueError: cells not 4-node tetrahedra (10-node ones included: first-order
            geometry is required in 3D), or a face shared by more than two cells.
    """
    cells = np.asarray(cells, dtype=np.int64)
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if cells.ndim == 2 and cells.shape[1] == 10:
        raise ValueError(
            "first-order geometry is required to cut 3D joints: got 10-node tetrahedra "
            "(mesh with element order 1)"
        )
    if cells.ndim != 2 or cells.shape[1] != 4:
        raise ValueError(f"split_along_faces takes 4-node tetrahedra, got cells {cells.shape}")
    if len(cells) == 0 or len(faces) == 0:
        return cells.copy(), np.zeros(0, dtype=np.int64)
    return _split(cells, faces, FACES, first_new=first_new)


def _split_midpoints(
    out: np.ndarray, joint: np.ndarray, one: np.ndarray, two: np.ndarray, first: int
) -> np.ndarray:
    """Give the second cell of each cut joint edge its own midpoint (in place in ``out``).

    Returns:
        the original midpoint of each new node, shape=(q,).
    """
    cut = joint.ravel()[one]
    one, two = one[cut], two[cut]
    c1, e1, c2, e2 = one // 3, one % 3, two // 3, two % 3
    v1 = np.sort(out[c1[:, None], EDGES[e1]], axis=1)
    v2 = np.sort(out[c2[:, None], EDGES[e2]], axis=1)
    apart = np.any(v1 != v2, axis=1)
    c2, e2 = c2[apart], e2[apart]
    source = out[c2, 3 + e2].copy()
    out[c2, 3 + e2] = first + np.arange(len(c2))
    return source


def _cells(model: Any, dim: int) -> tuple[list[tuple[int, int, np.ndarray, int]], np.ndarray]:
    """The model's cells (rank 0): triangles in 2D, 4-node tetrahedra in 3D.

    Returns:
        (blocks: (entity, element type, element tags, first row), the cells' node tags,
        shape=(n, 3) or (n, 6) in 2D, (n, 4) in 3D).

    Raises:
        ValueError: cells of another shape, of two orders (2D), or of the second order (3D).
    """
    allowed, shape = (TRIANGLES, "triangles") if dim == 2 else (TETRAHEDRA, "tetrahedra")
    blocks, rows = [], []
    count = 0
    for _, s in model.getEntities(dim):
        types, tags, nodes = model.mesh.getElements(dim, s)
        for kind, et, nt in zip(types, tags, nodes, strict=True):
            if int(kind) == TET10:
                raise ValueError(
                    "first-order geometry is required to cut 3D joints: the mesh has "
                    "10-node tetrahedra (mesh with element order 1)"
                )
            if int(kind) not in allowed:
                name = model.mesh.getElementProperties(kind)[0]
                raise ValueError(f"splitting joints needs {shape}, the mesh has {name}")
            blocks.append((int(s), int(kind), np.asarray(et), count))
            rows.append(np.asarray(nt, dtype=np.int64).reshape(len(et), -1))
            count += len(et)
    if len({r.shape[1] for r in rows}) > 1:
        raise ValueError("splitting joints needs cells of one order (all 3- or all 6-node)")
    return blocks, np.concatenate(rows)


def _holders(cells: np.ndarray, table: np.ndarray, query: np.ndarray) -> np.ndarray:
    """The cells holding each queried sub-entity, by increasing cell.

    Args:
        cells: the cells' nodes, the vertices first, shape=(n, p).
        table: local vertices of a cell's sub-entities of the queried kind, shape=(k, q).
        query: the sub-entities by their vertices (any order), shape=(m, q).

    Returns:
        (query row, cell) pairs, sorted by query row then cell, shape=(r, 2).
    """
    n, (k, q) = len(cells), table.shape
    base = int(max(cells.max(), query.max(initial=0))) + 1
    ids = _ids(np.concatenate([cells[:, table].reshape(-1, q), query]), base)
    own, asked = ids[: n * k], ids[n * k :]
    order = np.argsort(own, kind="stable")
    lo = np.searchsorted(own[order], asked, side="left")
    counts = np.searchsorted(own[order], asked, side="right") - lo
    row = np.repeat(np.arange(len(query)), counts)
    at = np.arange(int(counts.sum())) + np.repeat(lo - np.cumsum(counts) + counts, counts)
    return np.column_stack([row, order[at] // k])


def _versions(
    rows: np.ndarray, pairs: np.ndarray, cells: np.ndarray, out: np.ndarray, *, every: bool
) -> tuple[np.ndarray, np.ndarray]:
    """The elements ``rows`` with the nodes of their cells after the split.

    Args:
        rows: the elements' nodes, shape=(m, p).
        pairs: (element, cell holding it) pairs by element then cell, shape=(r, 2).
        cells: the cells' nodes before the split, shape=(n, pc).
        out: the cells' nodes after the split, shape=(n, pc).
        every: one element per distinct version (else the first cell's only).

    Returns:
        (the element each new element comes from, ascending, shape=(v,); their nodes,
        shape=(v, p)). An element no cell holds stays as it was.
    """
    element, cell = pairs[:, 0], pairs[:, 1]
    where = np.argmax(cells[cell][:, None, :] == rows[element][:, :, None], axis=2)
    mapped = out[cell[:, None], where].reshape(len(pairs), rows.shape[1])
    if len(pairs) == 0:
        keep = np.zeros(0, dtype=np.int64)
    elif every:
        keep = np.sort(np.unique(np.column_stack([element, mapped]), axis=0, return_index=True)[1])
    else:
        keep = np.flatnonzero(np.r_[True, element[1:] != element[:-1]])
    lonely = np.setdiff1d(np.arange(len(rows)), element)
    owner = np.concatenate([element[keep], lonely])
    order = np.argsort(owner, kind="stable")
    return owner[order], np.concatenate([mapped[keep], rows[lonely]])[order]


def _remap_elements(model: Any, cells: np.ndarray, out: np.ndarray, joints: set[int]) -> None:
    """Renumber every facet (and, in 3D, line) element after the cells (rank 0, in place).

    An element takes the nodes of its cell after the split. An element of a joint cut in
    two becomes two, one per side (the second with a new element tag); a line element in
    3D becomes one per distinct copy of its edge; any other facet element follows its
    first cell. Point elements keep their node (still a node of the first sector's cells).
    """
    tdim = int(model.getDimension())
    next_tag = int(model.mesh.getMaxElementTag()) + 1
    for dim in range(tdim - 1, 0, -1):
        table = SUBSETS[(tdim, dim)]
        blocks = [
            (int(e), kind, np.asarray(et, dtype=np.int64), np.asarray(nt, dtype=np.int64))
            for _, e in model.getEntities(dim)
            for kind, et, nt in zip(*model.mesh.getElements(dim, e), strict=True)
        ]
        if not blocks:
            continue
        rows = [nt.reshape(len(et), -1) for _, _, et, nt in blocks]
        query = np.concatenate([r[:, : table.shape[1]] for r in rows])
        pairs = _holders(cells, table, query)
        start = 0
        for (e, kind, et, _), block in zip(blocks, rows, strict=True):
            stop = start + len(et)
            mine = pairs[(pairs[:, 0] >= start) & (pairs[:, 0] < stop)] - [start, 0]
            start = stop
            every = dim < tdim - 1 or e in joints
            owner, new_rows = _versions(block, mine, cells, out, every=every)
            if np.array_equal(new_rows, block):
                continue
            new_tags = et[owner]
            extra = np.r_[False, owner[1:] == owner[:-1]]
            new_tags[extra] = next_tag + np.arange(np.count_nonzero(extra))
            next_tag += int(np.count_nonzero(extra))
            model.mesh.removeElements(dim, e, et)
            model.mesh.addElementsByType(e, kind, new_tags, new_rows.ravel())


def split_model(gmsh: ModuleType, groups: Sequence[str]) -> int:
    """Cut the meshed gmsh model along the joint groups ``groups`` (rank 0, in place).

    In 2D the joints are curve groups and the cells triangles (3- or 6-node), in 3D the
    joints are surface groups and the cells 4-node tetrahedra. The cells' nodes are split
    by :func:`split_along` or :func:`split_along_faces`; the new nodes are added to the
    model (classified on its first cell entity), the cells renumbered, and every facet
    element (curve elements in 2D, triangles on every surface in 3D) follows its cell, a
    joint's element becoming one per side (same node order: both keep the original's
    orientation), so a joint's physical group holds the facets of both faces once
    DOLFINx has the mesh; boundary facets follow their one cell. In 3D, line elements
    become one per copy of their edge (a curve group on a cut stays whole on every side).
    Point elements keep their node.

    Returns:
        the number of nodes added.

    Raises:
        ValueError: a group is not a curve (2D) or surface (3D) group of the model, the
            cells are not all triangles of one order (2D) or all 4-node tetrahedra (3D),
            or a facet is shared by more than two cells.
    """
    model = gmsh.model
    tdim = int(model.getDimension())
    if tdim not in (2, 3):
        raise ValueError(f"splitting joints needs a 2D or 3D mesh, the model is {tdim}D")
    kind = "curve" if tdim == 2 else "surface"
    names = {model.getPhysicalName(d, t): (d, t) for d, t in model.getPhysicalGroups()}
    entities: set[int] = set()
    for group in groups:
        if group not in names or names[group][0] != tdim - 1:
            raise ValueError(f"no {kind} group '{group}' to split in the mesh")
        entities.update(int(e) for e in model.getEntitiesForPhysicalGroup(*names[group]))
    blocks, cells = _cells(model, tdim)
    joint = [
        np.asarray(nt, dtype=np.int64).reshape(len(et), -1)[:, :tdim]
        for e in sorted(entities)
        for et, nt in zip(*model.mesh.getElements(tdim - 1, e)[1:], strict=True)
    ]
    tags, coords, _ = model.mesh.getNodes()
    # the next tag after the nodes there are (getMaxNodeTag may count removed nodes, and
    # DOLFINx wants the tags 1 ... N without gaps)
    first = int(np.max(tags)) + 1
    facets = np.concatenate(joint) if joint else np.zeros((0, tdim), dtype=np.int64)
    cut = split_along if tdim == 2 else split_along_faces
    out, source = cut(cells, facets, first_new=first)
    if len(source) == 0:
        return 0
    coords = np.asarray(coords).reshape(-1, 3)
    order = np.argsort(tags)
    where = order[np.searchsorted(np.asarray(tags)[order], source)]
    model.mesh.addNodes(tdim, blocks[0][0], first + np.arange(len(source)), coords[where].ravel())
    for entity, etype, et, start in blocks:
        model.mesh.removeElements(tdim, entity, et)
        model.mesh.addElementsByType(entity, etype, et, out[start : start + len(et)].ravel())
    _remap_elements(model, cells, out, entities)
    return len(source)
