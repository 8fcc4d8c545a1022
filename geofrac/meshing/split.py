"""Split a triangle mesh along joints: the joint's nodes get one copy per side (pure numpy).

A joint is a chain of mesh edges across which the displacement may jump. The continuous
field cannot jump, so the mesh is cut along the joint: for each vertex on a joint, its
incident cells are grouped into *sectors*, cells joined through a non-joint edge at that
vertex being in one sector (the joint edges separate sectors); the first sector keeps
the vertex and every further sector gets its own copy. So

- a vertex inside a through-going joint has 2 sectors (doubled), as has a joint vertex
  on the domain's boundary (the joint cuts the boundary there);
- a joint's tip inside the rock has 1 sector (not split: the jump is zero at a tip);
- a T junction has 3 sectors, an X crossing 4.

Second-order cells: the midpoint of a joint edge gets a copy in the second of its two
cells where the edge's end vertices differ between them after the split (an edge whose
two ends stayed shared, a one-edge joint with both ends tips, stays whole). Cells keep
their number, order and shape; only their node numbers change.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["split_along"]

#: local vertices of a triangle's edges 01, 12, 20 (gmsh and VTK order; the midpoints of
#: a 6-node triangle follow in the same order).
EDGES = np.array([[0, 1], [1, 2], [2, 0]])


def _shared_edges(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The (cell, local edge) pairs that are one edge.

    Args:
        keys: one integer per (cell, local edge), shape=(n, 3).

    Returns:
        first and second (cell * 3 + local edge) of each shared edge, shape=(s,) each.

    Raises:
        ValueError: an edge shared by more than two cells.
    """
    flat = keys.ravel()
    order = np.argsort(flat, kind="stable")
    same = flat[order][1:] == flat[order][:-1]
    if np.any(same[1:] & same[:-1]):
        raise ValueError("an edge is shared by more than two cells (a non-manifold mesh)")
    i = np.flatnonzero(same)
    return order[i], order[i + 1]


def _sectors(
    cells: np.ndarray, ends: np.ndarray, joint: np.ndarray, one: np.ndarray, two: np.ndarray
) -> np.ndarray:
    """Component label of each corner (cell * 3 + local vertex), shape=(3 n,).

    Two corners of the same vertex are joined where their cells share a non-joint edge.
    """
    n = len(cells)
    keep = ~joint.ravel()[one]
    one, two = one[keep], two[keep]
    rows, cols = [], []
    for end in (0, 1):
        c1, e1 = one // 3, one % 3
        c2, e2 = two // 3, two % 3
        vertex = ends[c1, e1, end]
        l1 = EDGES[e1, end]
        l2 = np.where(cells[c2, EDGES[e2, 0]] == vertex, EDGES[e2, 0], EDGES[e2, 1])
        rows.append(3 * c1 + l1)
        cols.append(3 * c2 + l2)
    r, c = np.concatenate(rows), np.concatenate(cols)
    graph = coo_matrix((np.ones(len(r)), (r, c)), shape=(3 * n, 3 * n))
    return connected_components(graph, directed=False)[1]


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
    n = len(cells)
    if n == 0 or len(joint_edges) == 0:
        return cells.copy(), np.zeros(0, dtype=np.int64)
    base = int(max(cells.max(), joint_edges.max())) + 1
    first = base if first_new is None else int(first_new)
    ends = cells[:, EDGES]  # (n, 3, 2)
    keys = ends.min(axis=2) * base + ends.max(axis=2)
    jkeys = np.unique(joint_edges.min(axis=1) * base + joint_edges.max(axis=1))
    joint = np.isin(keys, jkeys)
    one, two = _shared_edges(keys)
    labels = _sectors(cells, ends, joint, one, two)
    # the corners on joints: a sector per label; the first (lowest corner) keeps the vertex
    on_joint = np.isin(cells[:, :3], np.unique(ends[joint])).ravel()
    corners = np.flatnonzero(on_joint)
    vertex = cells[:, :3].ravel()[corners]
    ulab, at = np.unique(labels[corners], return_index=True)
    order = np.lexsort((corners[at], vertex[at]))
    lab_sorted, vert_sorted = ulab[order], vertex[at][order]
    fresh = np.ones(len(order), dtype=bool)
    fresh[0] = False
    fresh[1:] = vert_sorted[1:] == vert_sorted[:-1]
    node_of_label = vert_sorted.copy()
    node_of_label[fresh] = first + np.arange(np.count_nonzero(fresh))
    source = [vert_sorted[fresh]]
    out = cells.copy()
    verts = out[:, :3].ravel()
    node_map = np.zeros(int(labels.max()) + 1, dtype=np.int64)
    node_map[lab_sorted] = node_of_label
    verts[corners] = node_map[labels[corners]]
    out[:, :3] = verts.reshape(-1, 3)
    if cells.shape[1] == 6:
        source.append(_split_midpoints(out, joint, one, two, first + len(source[0])))
    return out, np.concatenate(source).astype(np.int64)


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
