"""2D polygonal blocks from a triangle mesh, one per vertex (Edo (2016), §5.2.2(a), Fig. 5.6-5.8).

In each triangle ijk a point p is chosen inside the incircle: the incentre (Fig. 5.6),
or a seeded random point of the disc of radius ``radius`` x r around it (Fig. 5.7(b):
the "movable region"; ``radius = 1`` is the whole incircle, Fig. 5.7(a)). The triangle
is cut into three quadrilateral pieces, one per corner: (i, m_ij, p, m_ik), with m the
edge midpoints. The block of a vertex is the union of its pieces; a vertex on the
boundary keeps its boundary pieces, so it and the midpoints of its boundary edges are
points of its block (Fig. 5.6(c)).

Convexity. With the incentre every piece is convex: the incircle's radius r is less than
half of every height of the triangle (r = 2A/(a + b + c) < 2A/(2a)), so the incentre lies
beyond each of the three midlines m_ij m_ik, on the far side from i, and the piece's angle
at p is below 180°. A random point of the incircle can cross a midline (the disc reaches
2r from a side, and 2r can exceed half a height): the piece of that corner is then
concave at p (a dart), and so may be the block. ``convex=True`` keeps every piece
convex: a random point outside the medial triangle (the triangle of the three midpoints)
is pulled back toward the incentre to 0.99 of the way to the medial triangle's edge.
Blocks are unions of convex pieces; they are not convex in general either way.

The random point of a triangle depends only on the seed and the global ids of its
vertices, so the blocks are the same on any number of ranks.
"""

from __future__ import annotations

import numpy as np

from geofrac.blocks.dual3d import Corners, assemble, on_boundary, sort_cells
from geofrac.blocks.model import Blocks
from geofrac.blocks.table import PointTable, edge_keys, face_keys
from geofrac.geometry.triangles import inner_points

__all__ = ["blocks_2d", "rings", "tri_corners"]

VERTEX, EDGE, FACE = 0, 1, 2
#: Local edges of a triangle; edge k is opposite vertex k (DOLFINx/Basix numbering).
EDGES = np.array([(1, 2), (0, 2), (0, 1)])


def tri_corners(
    x: np.ndarray,
    gid: np.ndarray,
    boundary: np.ndarray | None,
    *,
    num_vertices: int,
    inner: str = "incentre",
    radius: float = 1.0,
    convex: bool = False,
    seed: int = 0,
) -> Corners:
    """Block chains and convex pieces contributed by a set of triangles.

    A chain is the part of a block's ring inside one triangle, (m_ij, p, m_ik) in
    counter-clockwise order around i; :func:`rings` joins them after grouping.
    ``Corners.extra`` carries per chain the keys of edges ij and ik, and whether those
    edges lie on the boundary, shape=(num_chains, 4).

    Args:
        x: vertex coordinates per triangle, shape=(num_cells, 3, 2).
        gid: global vertex ids per triangle, shape=(num_cells, 3).
        boundary: whether the edge opposite each local vertex is on the domain boundary,
            shape=(num_cells, 3); None to find it from these cells (the whole mesh).
        num_vertices: an upper bound of the global vertex ids.
        inner: the inner point, see :func:`inner_points`.
        radius: the movable region, see :func:`inner_points`.
        convex: keep pieces convex, see :func:`inner_points`.
        seed: the random seed, see :func:`inner_points`.
    """
    order, gid, x = sort_cells(np.asarray(x, dtype=float)[:, :, :2], gid)
    n = num_vertices
    ekey = edge_keys(gid[:, EDGES[:, 0]], gid[:, EDGES[:, 1]], n)
    emid = (x[:, EDGES[:, 0]] + x[:, EDGES[:, 1]]) * 0.5
    tkey = face_keys(gid[:, 0], gid[:, 1], gid[:, 2], n=n)
    p = inner_points(x, tkey, inner, radius=radius, convex=convex, seed=seed)
    boundary = on_boundary(ekey, boundary, order)
    table = PointTable(
        [gid.ravel(), ekey.ravel(), tkey], [x.reshape(-1, 2), emid.reshape(-1, 2), p]
    )
    vref = table.refs(VERTEX, gid)
    eref = table.refs(EDGE, ekey)
    pref = table.refs(FACE, tkey)
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    ccw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0
    chains, extra, block, pieces = [], [], [], []
    for i in range(3):
        j, k = [(1, 2), (2, 0), (0, 1)][i]  # counter-clockwise after i when ccw
        jj, kk = np.where(ccw, j, k), np.where(ccw, k, j)
        rows = np.arange(len(gid))
        eij, eik = 3 - (i + jj), 3 - (i + kk)  # the edge opposite the third vertex
        chains.append(np.stack([eref[rows, eij], pref, eref[rows, eik]], axis=1))
        extra.append(
            np.stack(
                [ekey[rows, eij], ekey[rows, eik], boundary[rows, eij], boundary[rows, eik]],
                axis=1,
            )
        )
        pieces.append(np.stack([vref[:, i], eref[rows, eij], pref, eref[rows, eik]], axis=1))
        block.append(gid[:, i])
    block_ids = np.concatenate(block)
    return Corners(
        table=table,
        face_block=block_ids,
        faces=np.concatenate(chains),
        piece_block=block_ids,
        pieces=np.concatenate(pieces),
        extra=np.concatenate(extra).astype(np.int64),
    )


def rings(corners: Corners, block_ids: np.ndarray) -> Blocks:
    """Join each block's chains into its ring (counter-clockwise), then :func:`assemble`.

    Args:
        corners: the chains and pieces of the blocks (this rank's and those received).
        block_ids: the blocks to build, sorted, shape=(num_blocks,).

    Raises:
        ValueError: a vertex whose triangles do not form one fan (a non-manifold vertex).
    """
    block_ids = np.asarray(block_ids, dtype=np.int64)
    b = np.searchsorted(block_ids, corners.face_block)
    assert corners.extra is not None  # the 2D builders keep their columns
    first_edge, last_edge = corners.extra[:, 0], corners.extra[:, 1]
    first_on = corners.extra[:, 2].astype(bool)
    nb, nc = len(block_ids), len(b)
    # the chain that follows each chain: same block, starting at the edge this one ends at
    by_start = np.lexsort((first_edge, b))
    start_sorted = (b[by_start], first_edge[by_start])
    pos = _find(start_sorted, b, last_edge)
    follows = np.where(pos >= 0, by_start[np.maximum(pos, 0)], -1)
    # the ring starts at a chain that no chain leads to: one beginning on the boundary
    led_to = np.zeros(nc, dtype=bool)
    led_to[follows[follows >= 0]] = True
    opening = np.flatnonzero(~led_to)
    count_open = np.bincount(b[opening], minlength=nb)
    if np.any(count_open > 1) or np.any(~first_on[opening]):
        bad = block_ids[np.flatnonzero(count_open > 1)[:1]]
        raise ValueError(
            f"the triangles at vertex {bad.tolist() or '?'} do not form one fan "
            "(a non-manifold vertex); mesh the domain without such vertices"
        )
    start = np.full(nb, -1, dtype=np.int64)
    start[b[opening]] = opening
    closed = start < 0  # interior vertices: start at the chain with the smallest key
    if np.any(closed):
        lowest = np.lexsort((first_edge, b))
        first_of = np.full(nb, -1, dtype=np.int64)
        first_of[b[lowest[::-1]]] = lowest[::-1]  # the smallest wins (written last)
        start[closed] = first_of[closed]
    # walk: the step of each chain along its block's ring
    step = np.full(nc, -1, dtype=np.int64)
    current = start.copy()
    for s in range(nc + 1):
        alive = current >= 0
        if not np.any(alive):
            break
        step[current[alive]] = s
        nxt = follows[current[alive]]
        nxt[nxt >= 0] = np.where(step[nxt[nxt >= 0]] >= 0, -1, nxt[nxt >= 0])
        current[alive] = nxt
    if np.any(step < 0):
        raise ValueError("the chains of a block do not join into one ring")
    # ring entries: (vertex if open), then per chain its first midpoint and inner point,
    # then (the last chain's closing midpoint if open)
    chains = corners.faces
    open_block = ~closed
    vref = corners.table.refs(VERTEX, block_ids[open_block])
    last = np.full(nb, -1, dtype=np.int64)
    np.maximum.at(last, b, step)
    is_last = step == last[b]
    entry_block = np.concatenate([np.flatnonzero(open_block), b, b, b[is_last & open_block[b]]])
    entry_key = np.concatenate(
        [
            np.full(open_block.sum(), -1),
            2 * step,
            2 * step + 1,
            2 * step[is_last & open_block[b]] + 2,
        ]
    )
    entry_ref = np.concatenate(
        [vref, chains[:, 0], chains[:, 1], chains[is_last & open_block[b], 2]]
    )
    order = np.lexsort((entry_key, entry_block))
    ring_corners = Corners(
        table=corners.table,
        face_block=block_ids[entry_block[order]],
        faces=entry_ref[order][:, None],
        piece_block=corners.piece_block,
        pieces=corners.pieces,
    )
    return assemble(ring_corners, block_ids, 2)


def _find(sorted_pairs: tuple[np.ndarray, np.ndarray], a: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Positions of the pairs (a, k) in lexicographically sorted pairs, -1 if absent."""
    sa, sk = sorted_pairs
    span = int(max(sk.max(initial=0), k.max(initial=0))) + 1
    key_sorted = sa * span + sk
    key = a * span + k  # pairs as one sortable key
    pos = np.searchsorted(key_sorted, key)
    pos = np.minimum(pos, len(key_sorted) - 1)
    found = len(key_sorted) > 0
    ok = found & (key_sorted[pos] == key) if found else np.zeros(len(a), dtype=bool)
    return np.where(ok, pos, -1)


def blocks_2d(
    points: np.ndarray,
    triangles: np.ndarray,
    inner: str = "incentre",
    *,
    radius: float = 1.0,
    convex: bool = False,
    seed: int = 0,
) -> Blocks:
    """The blocks of a whole triangle mesh, one per vertex used by a triangle.

    Args:
        points: vertex coordinates, shape=(num_vertices, 2) (or 3, z ignored).
        triangles: vertex indices per triangle, shape=(num_cells, 3).
        inner: the inner point, see :func:`inner_points`.
        radius: the movable region, see :func:`inner_points`.
        convex: keep pieces convex, see :func:`inner_points`.
        seed: the random seed, see :func:`inner_points`.
    """
    triangles = np.asarray(triangles, dtype=np.int64)
    points = np.asarray(points, dtype=float)[:, :2]
    corners = tri_corners(
        points[triangles],
        triangles,
        None,
        num_vertices=len(points),
        inner=inner,
        radius=radius,
        convex=convex,
        seed=seed,
    )
    return rings(corners, np.unique(triangles))
