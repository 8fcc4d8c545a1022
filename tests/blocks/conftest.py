"""Median-dual block sets of structured simplex meshes of the unit square and cube.

Hand-built references for the block quality checks and writers (the production builder
lives elsewhere): the block of mesh vertex v is the union of the sub-cells at v of the
triangles (2D: quad v, mid(v, w1), centroid, mid(v, w2)) or tetrahedra (3D: hexahedron
v, three edge midpoints, three face centroids, tet centroid) that contain v.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from geofrac.blocks.model import Blocks


def square_mesh(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Points shape=((n+1)^2, 2) and CCW triangles shape=(2 n^2, 3) of the unit square."""
    g = np.linspace(0.0, 1.0, n + 1)
    x, y = np.meshgrid(g, g, indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel()])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    p00, p10 = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    p01, p11 = idx[:-1, 1:].ravel(), idx[1:, 1:].ravel()
    tris = np.concatenate([np.column_stack([p00, p10, p11]), np.column_stack([p00, p11, p01])])
    return points, tris


def cube_mesh(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Points shape=((n+1)^3, 3) and positively oriented tets shape=(6 n^3, 4) (Kuhn split)."""
    g = np.linspace(0.0, 1.0, n + 1)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    idx = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)
    base = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    tets = []
    for perm in itertools.permutations(range(3)):
        corner = base.copy()
        chain = [idx[tuple(corner.T)]]
        for axis in perm:
            corner[:, axis] += 1
            chain.append(idx[tuple(corner.T)])
        tets.append(np.column_stack(chain))
    tets = np.concatenate(tets)
    p = points[tets]
    det = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    tets[det < 0] = tets[det < 0][:, [0, 2, 1, 3]]
    return points, tets


def _unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique sorted tuples and the index of each row into them."""
    uniq, inverse = np.unique(np.sort(rows, axis=1), axis=0, return_inverse=True)
    return uniq, inverse.ravel()


def _sort_by_block(rows: np.ndarray, owner: np.ndarray, num: int):
    order = np.argsort(owner, kind="stable")
    offsets = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=num))])
    return rows[order], owner[order], offsets


def median_dual_2d(n: int) -> Blocks:
    """Median-dual blocks of the ``n`` x ``n`` right-triangle mesh of the unit square."""
    verts, tris = square_mesh(n)
    nv, nt = len(verts), len(tris)
    corners = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]])  # v, w1, w2 (CCW)
    v, w1, w2 = (tris[:, corners[:, k]].ravel() for k in range(3))
    tri = np.repeat(np.arange(nt), 3)
    edges, inv = _unique_rows(np.column_stack([np.concatenate([v, v]), np.concatenate([w1, w2])]))
    m1, m2 = inv[: len(v)] + nv, inv[len(v) :] + nv
    c = tri + nv + len(edges)
    points = np.concatenate([verts, verts[edges].mean(axis=1), verts[tris].mean(axis=1)])
    pieces = np.column_stack([v, m1, c, m2])
    # directed boundary segments of each block: the interfaces m1 -> c -> m2, and on
    # domain-boundary edges v -> m1 and m2 -> v
    counts = np.bincount(inv, minlength=len(edges))
    seg = [np.column_stack([m1, c]), np.column_stack([c, m2])]
    owner = [v, v]
    b1, b2 = counts[inv[: len(v)]] == 2, counts[inv[len(v) :]] == 2  # 4 if interior
    seg += [np.column_stack([v, m1])[b1], np.column_stack([m2, v])[b2]]
    owner += [v[b1], v[b2]]
    seg, owner = np.concatenate(seg), np.concatenate(owner)
    # chain the segments of each block into its ring by following start -> end
    order = np.lexsort((seg[:, 0], owner))
    seg, owner = seg[order], owner[order]
    key = owner * len(points) + seg[:, 0]
    nxt = np.searchsorted(key, owner * len(points) + seg[:, 1])
    offsets = np.concatenate([[0], np.cumsum(np.bincount(owner, minlength=nv))])
    ring = np.empty(len(seg), dtype=np.int64)
    cur = offsets[:-1].copy()
    sizes = np.diff(offsets)
    for step in range(sizes.max()):
        live = step < sizes
        ring[offsets[:-1][live] + step] = seg[cur[live], 0]
        cur = nxt[cur]
    pieces, piece_block, _ = _sort_by_block(pieces, v, nv)
    return Blocks(
        dim=2,
        points=points,
        faces=ring[:, None],
        face_offsets=offsets,
        pieces=pieces,
        piece_block=piece_block,
        ids=np.arange(nv),
        seeds=verts.copy(),
    )


def median_dual_3d(n: int) -> Blocks:
    """Median-dual blocks of the Kuhn tetrahedral mesh (``n``^3 cubes) of the unit cube."""
    verts, tets = cube_mesh(n)
    nv, nt = len(verts), len(tets)
    pairs = np.array(list(itertools.combinations(range(4), 2)))  # 6 tet edges
    triples = np.array(list(itertools.combinations(range(4), 3)))  # 4 tet faces
    edges, e_inv = _unique_rows(tets[:, pairs].reshape(-1, 2))
    faces, f_inv = _unique_rows(tets[:, triples].reshape(-1, 3))
    e_of = e_inv.reshape(nt, 6) + nv  # point index of each tet edge midpoint
    f_of = f_inv.reshape(nt, 4) + nv + len(edges)
    c_of = np.arange(nt) + nv + len(edges) + len(faces)
    points = np.concatenate(
        [verts, verts[edges].mean(axis=1), verts[faces].mean(axis=1), verts[tets].mean(axis=1)]
    )
    edge_slot = {tuple(p): k for k, p in enumerate(pairs)}
    face_slot = {tuple(t): k for k, t in enumerate(triples)}

    def mid(i: int, j: int) -> np.ndarray:
        return e_of[:, edge_slot[tuple(sorted((i, j)))]]

    def fc(i: int, j: int, k: int) -> np.ndarray:
        return f_of[:, face_slot[tuple(sorted((i, j, k)))]]

    hexes, hex_block, quads, quad_block = [], [], [], []
    for i in range(4):
        j, k, m = (a for a in range(4) if a != i)
        bottom = [tets[:, i], mid(i, j), fc(i, j, k), mid(i, k)]
        top = [mid(i, m), fc(i, j, m), c_of, fc(i, k, m)]  # above bottom, point by point
        hexes.append(np.column_stack([*bottom, *top]))
        hex_block.append(tets[:, i])
        for w in (j, k, m):
            a, b = (x for x in range(4) if x not in (i, w))
            quads.append(np.column_stack([mid(i, w), fc(i, w, a), c_of, fc(i, w, b)]))
            quad_block.append(tets[:, i])
            # orientation: outward of block i means the normal points from i to w
            q, dirn = points[quads[-1]], verts[tets[:, w]] - verts[tets[:, i]]
            normal = np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1])
            flip = np.einsum("ij,ij->i", normal, dirn) < 0
            quads[-1][flip] = quads[-1][flip][:, ::-1]
    hexes = np.concatenate(hexes)
    p = points[hexes]
    det = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 3] - p[:, 0]), p[:, 4] - p[:, 0])
    swap = det < 0  # bottom quad must turn counter-clockwise seen from the top
    hexes[swap] = hexes[swap][:, [0, 3, 2, 1, 4, 7, 6, 5]]
    # boundary triangles: the sub-quads (v, mid, face centroid, mid), outward
    counts = np.bincount(f_inv, minlength=len(faces))
    for t, tri in enumerate(triples):
        on_bnd = counts[f_inv.reshape(nt, 4)[:, t]] == 1
        centre = points[c_of[on_bnd]]
        for i in tri:
            j, k = (a for a in tri if a != i)
            quad = np.column_stack([tets[:, i], mid(i, j), fc(*tri), mid(i, k)])[on_bnd]
            q = points[quad]
            normal = np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1])
            flip = np.einsum("ij,ij->i", normal, q[:, 2] - centre) < 0
            quad[flip] = quad[flip][:, ::-1]
            quads.append(quad)
            quad_block.append(tets[on_bnd, i])
    faces_b, _, offsets = _sort_by_block(np.concatenate(quads), np.concatenate(quad_block), nv)
    pieces, piece_block, _ = _sort_by_block(hexes, np.concatenate(hex_block), nv)
    return Blocks(
        dim=3,
        points=points,
        faces=faces_b,
        face_offsets=offsets,
        pieces=pieces,
        piece_block=piece_block,
        ids=np.arange(nv),
        seeds=verts.copy(),
    )


def take_blocks(blocks: Blocks, which: np.ndarray) -> Blocks:
    """The blocks ``which`` (repeats allowed: duplicated blocks), same points."""
    which = np.asarray(which)
    f_off = blocks.face_offsets
    p_off = np.searchsorted(blocks.piece_block, np.arange(blocks.num_blocks + 1))
    f_idx = np.concatenate([np.arange(f_off[b], f_off[b + 1]) for b in which]).astype(int)
    p_idx = np.concatenate([np.arange(p_off[b], p_off[b + 1]) for b in which]).astype(int)
    nf, npc = np.diff(f_off)[which], np.diff(p_off)[which]
    return Blocks(
        dim=blocks.dim,
        points=blocks.points,
        faces=blocks.faces[f_idx],
        face_offsets=np.concatenate([[0], np.cumsum(nf)]),
        pieces=blocks.pieces[p_idx],
        piece_block=np.repeat(np.arange(len(which)), npc),
        ids=blocks.ids[which],
        seeds=blocks.seeds[which],
        kind=blocks.kind[which],
    )


def pieces_as_blocks(blocks: Blocks) -> Blocks:
    """3D: every convex hexahedral piece as a block of its own (6 outward quads)."""
    from geofrac.blocks.quality import HEX_FACES

    n = len(blocks.pieces)
    return Blocks(
        dim=3,
        points=blocks.points,
        faces=blocks.pieces[:, HEX_FACES].reshape(-1, 4),
        face_offsets=np.arange(n + 1) * 6,
        pieces=blocks.pieces,
        piece_block=np.arange(n),
        ids=np.arange(n),
        seeds=blocks.points[blocks.pieces].mean(axis=1),
    )


@pytest.fixture(scope="module")
def dual2d() -> Blocks:
    """Median-dual blocks of a 4 x 4 square mesh (25 blocks)."""
    return median_dual_2d(4)


@pytest.fixture(scope="module")
def dual3d() -> Blocks:
    """Median-dual blocks of a 3 x 3 x 3 Kuhn cube mesh (64 blocks)."""
    return median_dual_3d(3)
