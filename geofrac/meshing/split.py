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

from collections.abc import Sequence
from types import ModuleType
from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["split_along", "split_model"]

#: local vertices of a triangle's edges 01, 12, 20 (gmsh and VTK order; the midpoints of
#: a 6-node triangle follow in the same order).
EDGES = np.array([[0, 1], [1, 2], [2, 0]])
#: gmsh element types of the 3- and 6-node triangle
TRIANGLES = (2, 9)


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


def _cells(model: Any) -> tuple[list[tuple[int, int, np.ndarray, int]], np.ndarray]:
    """The model's triangles (rank 0).

    Returns:
        (blocks: (surface, element type, element tags, first row), the cells' node tags,
        shape=(n, 3) or (n, 6)).

    Raises:
        ValueError: the model is not 2D, or its cells are not all 3- or all 6-node triangles.
    """
    if model.getDimension() != 2:
        raise ValueError("splitting joints needs a 2D mesh (3D joints are not split)")
    blocks, rows = [], []
    count = 0
    for _, s in model.getEntities(2):
        types, tags, nodes = model.mesh.getElements(2, s)
        for kind, et, nt in zip(types, tags, nodes, strict=True):
            if int(kind) not in TRIANGLES:
                name = model.mesh.getElementProperties(kind)[0]
                raise ValueError(f"splitting joints needs triangles, the mesh has {name}")
            blocks.append((int(s), int(kind), np.asarray(et), count))
            rows.append(np.asarray(nt, dtype=np.int64).reshape(len(et), -1))
            count += len(et)
    if len({r.shape[1] for r in rows}) > 1:
        raise ValueError("splitting joints needs cells of one order (all 3- or all 6-node)")
    return blocks, np.concatenate(rows)


def _edge_cells(cells: np.ndarray) -> dict[tuple[int, int], list[int]]:
    """Vertex edge (sorted node pair) -> the cells holding it."""
    out: dict[tuple[int, int], list[int]] = {}
    for c, row in enumerate(cells[:, :3].tolist()):
        for i, j in EDGES.tolist():
            a, b = row[i], row[j]
            out.setdefault((min(a, b), max(a, b)), []).append(c)
    return out


def _remap_curves(model: Any, cells: np.ndarray, out: np.ndarray, joints: set[int]) -> None:
    """Renumber every curve element after the cells (rank 0, in place).

    A curve element takes the nodes of its cell after the split; an element of a joint
    curve cut in two becomes two, one per side (the second with a new element tag).
    """
    edges = _edge_cells(cells)
    next_tag = int(model.mesh.getMaxElementTag()) + 1
    for _, e in model.getEntities(1):
        types, tags, nodes = model.mesh.getElements(1, e)
        for kind, et, nt in zip(types, tags, nodes, strict=True):
            rows = np.asarray(nt, dtype=np.int64).reshape(len(et), -1)
            new_tags, new_rows = [], []
            for tag, row in zip(np.asarray(et).tolist(), rows.tolist(), strict=True):
                held = edges.get((min(row[:2]), max(row[:2])), [])
                sides = []
                for c in held:
                    where = [int(np.flatnonzero(cells[c] == n)[0]) for n in row]
                    sides.append(out[c, where].tolist())
                if not sides:
                    sides = [row]
                if len(sides) == 2 and (e not in joints or sides[0] == sides[1]):
                    sides = sides[:1]
                for k, side in enumerate(sides):
                    new_tags.append(tag if k == 0 else next_tag)
                    next_tag += k
                    new_rows.append(side)
            if new_rows == rows.tolist():
                continue
            model.mesh.removeElements(1, e, et)
            model.mesh.addElementsByType(e, kind, new_tags, np.ravel(new_rows))


def split_model(gmsh: ModuleType, groups: Sequence[str]) -> int:
    """Cut the meshed 2D gmsh model along the curve groups ``groups`` (rank 0, in place).

    The cells' nodes are split by :func:`split_along`; the new nodes are added to the
    model (classified on its first surface), the cells renumbered, and every curve
    element follows its cell, a joint's element becoming one per side, so a joint's
    physical group holds the facets of both faces once DOLFINx has the mesh.

    Returns:
        the number of nodes added.

    Raises:
        ValueError: a group is not a curve group of the model, or the mesh is not one of
            2D triangles of one order.
    """
    model = gmsh.model
    names = {model.getPhysicalName(d, t): (d, t) for d, t in model.getPhysicalGroups()}
    entities: set[int] = set()
    for group in groups:
        if group not in names or names[group][0] != 1:
            raise ValueError(f"no curve group '{group}' to split in the mesh")
        entities.update(int(e) for e in model.getEntitiesForPhysicalGroup(*names[group]))
    blocks, cells = _cells(model)
    joint = [
        np.asarray(nt, dtype=np.int64).reshape(len(et), -1)[:, :2]
        for e in sorted(entities)
        for et, nt in zip(*model.mesh.getElements(1, e)[1:], strict=True)
    ]
    tags, coords, _ = model.mesh.getNodes()
    # the next tag after the nodes there are (getMaxNodeTag may count removed nodes, and
    # DOLFINx wants the tags 1 ... N without gaps)
    first = int(np.max(tags)) + 1
    edges = np.concatenate(joint) if joint else np.zeros((0, 2), dtype=np.int64)
    out, source = split_along(cells, edges, first_new=first)
    if len(source) == 0:
        return 0
    coords = np.asarray(coords).reshape(-1, 3)
    order = np.argsort(tags)
    where = order[np.searchsorted(np.asarray(tags)[order], source)]
    model.mesh.addNodes(2, blocks[0][0], first + np.arange(len(source)), coords[where].ravel())
    for surface, kind, et, start in blocks:
        model.mesh.removeElements(2, surface, et)
        model.mesh.addElementsByType(surface, kind, et, out[start : start + len(et)].ravel())
    _remap_curves(model, cells, out, entities)
    return len(source)
