"""3D polyhedral blocks from a tetrahedral mesh, one per vertex (Edo (2016), §5.2.2(b), Fig. 5.9).

Each tetrahedron abcd is cut into four hexahedral sub-cells, one per corner: the
sub-cell of a has the corners a, the edge midpoints m_ab, m_ac, m_ad, the face centroids
f_abc, f_abd, f_acd and the tetrahedron's centroid c. It is the set of points whose
largest barycentric coordinate is a's, so it is convex, its faces are planar and its
volume is a quarter of the tetrahedron's. The block of a vertex is the union of its
sub-cells: the faces that sub-cells of the same vertex share are dropped ("the faces
that neighbouring blocks share are removed", Edo (2016), §5.2.2(b)), which leaves

- per tetrahedron and edge ij, the quadrilateral (m_ij, f_ijk, c, f_ijl) between the
  sub-cells of i and j (a face of both blocks, in opposite orders), and
- per boundary triangle ijl and corner i, the quadrilateral (i, m_ij, f_ijl, m_il).

Every face has four points, as in Edo (2016), and is planar: f_ijk - m_ij and f_ijl - m_ij
span it and c - m_ij = 3/4 (f_ijk - m_ij) + 3/4 (f_ijl - m_ij). A vertex inside the
domain is not a point of its block; a vertex on the boundary is.

:func:`tet_corners` does the per-tetrahedron work on any subset of the cells (a rank's);
:func:`assemble` groups what belongs to each block; :func:`blocks_3d` does both for a
whole mesh held in numpy arrays.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from geofrac.blocks.model import Blocks
from geofrac.blocks.table import PointTable, edge_keys, face_keys

__all__ = [
    "Corners",
    "assemble",
    "blocks_3d",
    "centroids",
    "on_boundary",
    "sort_cells",
    "tet_corners",
]

VERTEX, EDGE, FACE, CELL = 0, 1, 2, 3
#: Local edges of a tetrahedron, (i, j) with i < j.
EDGES = np.array([(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)])
#: The two local vertices not on each edge.
EDGE_OTHERS = np.array([(2, 3), (1, 3), (1, 2), (0, 3), (0, 2), (0, 1)])
#: Local faces: face k is opposite vertex k (the DOLFINx/Basix facet numbering).
FACES = np.array([(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)])
#: Sign of each permutation of (0, 1, 2, 3), indexed by the permuted tuple.
_PARITY = np.zeros((4, 4, 4, 4), dtype=np.int8)
for _p in itertools.permutations(range(4)):
    _PARITY[_p] = 1 - 2 * (sum(a > b for i, a in enumerate(_p) for b in _p[i + 1 :]) % 2)
_EDGE_INDEX = np.full((4, 4), -1)
for _e, (_i, _j) in enumerate(EDGES):
    _EDGE_INDEX[_i, _j] = _EDGE_INDEX[_j, _i] = _e


@dataclass
class Corners:
    """What a set of cells contributes to the blocks of their vertices, not yet grouped.

    Attributes:
        table: the points.
        face_block: global id of the block each face belongs to, shape=(num_faces,).
        faces: point refs into ``table``, outward order, shape=(num_faces, 4) (3D) or
            (num_chains, 3) chains in 2D (see :mod:`geofrac.blocks.dual2d`).
        piece_block: global id of each piece's block, shape=(num_pieces,).
        pieces: point refs of the convex pieces, shape=(num_pieces, 8) or (num_pieces, 4).
        extra: per-face integer columns a builder needs after grouping (2D: the keys of
            a chain's first and last edge), shape=(num_faces, k), or None.
    """

    table: PointTable
    face_block: np.ndarray
    faces: np.ndarray
    piece_block: np.ndarray
    pieces: np.ndarray
    extra: np.ndarray | None = None


#: Sorting networks for 2, 3 and 4 values (pairs to compare and swap, in order).
_NETWORKS = {
    2: ((0, 1),),
    3: ((0, 1), (1, 2), (0, 1)),
    4: ((0, 1), (2, 3), (0, 2), (1, 3), (1, 2)),
}


def sort_cells(x: np.ndarray, gid: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each cell's vertices in increasing global id (so a point comes out the same bits).

    Args:
        x: vertex coordinates per cell, shape=(num_cells, nv, gdim).
        gid: global vertex ids per cell, shape=(num_cells, nv).

    Returns:
        The order applied, the sorted ids and the sorted coordinates (same shapes).
    """
    gid = np.asarray(gid, dtype=np.int64)
    order = np.argsort(gid, axis=1, kind="stable")
    return (
        order,
        np.take_along_axis(gid, order, axis=1),
        np.take_along_axis(np.asarray(x, dtype=float), order[:, :, None], axis=1),
    )


def on_boundary(facet_keys: np.ndarray, given: np.ndarray | None, order: np.ndarray) -> np.ndarray:
    """Whether each cell's facet k (opposite its vertex k, after sorting) is on the boundary.

    Args:
        facet_keys: key of each facet of each (sorted) cell, shape=(num_cells, nv).
        given: the flags in the cells' original vertex order, shape=(num_cells, nv), or
            None to find them from ``facet_keys`` (a facet of one cell only: the cells
            must be the whole mesh).
        order: the vertex order :func:`sort_cells` applied, shape=(num_cells, nv).
    """
    if given is None:
        _, inverse, counts = np.unique(facet_keys, return_inverse=True, return_counts=True)
        return (counts[inverse] == 1).reshape(facet_keys.shape)
    return np.take_along_axis(np.asarray(given, dtype=bool), order, axis=1)


def centroids(x: np.ndarray) -> np.ndarray:
    """Centroids of point groups, the same bits whatever the order of their points.

    Each coordinate's values are summed in increasing order, so a face computed from two
    tetrahedra (or from a surface patch) gets exactly the same point.

    Args:
        x: points, shape=(..., k, dim).

    Returns:
        shape=(..., dim).
    """
    k = x.shape[-2]
    v = [x[..., i, :] for i in range(k)]
    for i, j in _NETWORKS.get(k, ()):  # a sorting network: elementwise min/max swaps
        v[i], v[j] = np.minimum(v[i], v[j]), np.maximum(v[i], v[j])
    if k not in _NETWORKS:
        s = np.sort(x, axis=-2)
        v = [s[..., i, :] for i in range(k)]
    total = v[0]
    for i in range(1, k):
        total = total + v[i]
    return total / k


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.einsum("ij,ij->i", a, b)


def tet_corners(
    x: np.ndarray,
    gid: np.ndarray,
    cell_key: np.ndarray,
    *,
    boundary: np.ndarray | None,
    num_vertices: int,
) -> Corners:
    """Block faces and convex pieces contributed by a set of tetrahedra.

    Args:
        x: vertex coordinates per cell, shape=(num_cells, 4, 3).
        gid: global vertex ids per cell (the same on any number of ranks),
            shape=(num_cells, 4).
        cell_key: a global id per cell, shape=(num_cells,).
        boundary: whether the face opposite each local vertex lies on the domain
            boundary, shape=(num_cells, 4); None to find it from these cells (when they
            are the whole mesh).
        num_vertices: an upper bound of the global vertex ids.

    Returns:
        The faces (grouped later by :func:`assemble`) and the hexahedral pieces.
    """
    order, gid, x = sort_cells(x, gid)
    n = num_vertices
    ekey = edge_keys(gid[:, EDGES[:, 0]], gid[:, EDGES[:, 1]], n)
    emid = (x[:, EDGES[:, 0]] + x[:, EDGES[:, 1]]) * 0.5
    fkey = face_keys(gid[:, FACES[:, 0]], gid[:, FACES[:, 1]], gid[:, FACES[:, 2]], n=n)
    fmid = centroids(x[:, FACES])
    centre = ((x[:, 0] + x[:, 1]) + (x[:, 2] + x[:, 3])) * 0.25  # one cell computes it
    boundary = on_boundary(fkey, boundary, order)
    table = PointTable(
        [gid.ravel(), ekey.ravel(), fkey.ravel(), np.asarray(cell_key, dtype=np.int64)],
        [x.reshape(-1, 3), emid.reshape(-1, 3), fmid.reshape(-1, 3), centre],
    )
    vref, eref, fref, cref = (
        g.reshape(shape)
        for g, shape in zip(
            table.given, (gid.shape, ekey.shape, fkey.shape, (len(gid),)), strict=True
        )
    )

    d1, d2, d3 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]
    negative = _dot(d1, np.cross(d2, d3)) < 0  # the cell's orientation, once per cell
    index = np.int32 if len(table.x) < 2**31 else np.int64
    vref, eref, fref, cref = (r.astype(index) for r in (vref, eref, fref, cref))

    blocks, faces = [], []
    for e, (i, j) in enumerate(EDGES):  # the face between the sub-cells of i and j
        k, m = EDGE_OTHERS[e]
        # (m_ij, f_ijk, c, f_ijm) turns about j - i as det(j - i, k - i, m - i) does (its
        # normal is (c - m_ij) x (f_ijm - f_ijk) = (k - m_ij) x (m - m_ij) / 6): the sign
        # of the permutation (i, j, k, m) times the cell's orientation
        flip = negative ^ (_PARITY[i, j, k, m] < 0)
        fa = np.where(flip, fref[:, k], fref[:, m])
        fb = np.where(flip, fref[:, m], fref[:, k])
        blocks += [gid[:, i], gid[:, j]]
        faces += [
            np.stack([eref[:, e], fa, cref, fb], axis=1),
            np.stack([eref[:, e], fb, cref, fa], axis=1),
        ]
    for k in range(4):  # boundary triangles: one quad per corner
        on = np.flatnonzero(boundary[:, k])
        if len(on) == 0:
            continue
        outward = fmid[on, k] - x[on, k]
        tri = FACES[k]
        for c in range(3):
            i, j, m = tri[c], tri[(c + 1) % 3], tri[(c + 2) % 3]
            eij, eim = _EDGE_INDEX[i, j], _EDGE_INDEX[i, m]
            normal = np.cross(fmid[on, k] - x[on, i], emid[on, eim] - emid[on, eij])
            flip = _dot(normal, outward) < 0
            first = np.where(flip, eref[on, eim], eref[on, eij])
            last = np.where(flip, eref[on, eij], eref[on, eim])
            blocks.append(gid[on, i])
            faces.append(np.stack([vref[on, i], first, fref[on, k], last], axis=1))

    pieces, piece_block = [], []
    for a in range(4):  # the hexahedral sub-cell of corner a, right-handed
        b, c, d = (v for v in range(4) if v != a)
        swap = negative ^ (_PARITY[a, b, c, d] < 0)  # det(b - a, c - a, d - a) < 0
        bb, cc = np.where(swap, c, b), np.where(swap, b, c)
        rows = np.arange(len(gid))

        def edge(p: int, q: np.ndarray | int, rows: np.ndarray = rows) -> np.ndarray:
            return eref[rows, _EDGE_INDEX[p, q]]

        def face(
            p: int, q: np.ndarray | int, r: np.ndarray | int, *, rows: np.ndarray = rows
        ) -> np.ndarray:
            return fref[rows, 6 - (p + q + r)]  # face pqr is opposite the fourth vertex

        # VTK order: bottom (a, m_ab, f_abc, m_ac), then above it (m_ad, f_abd, c, f_acd)
        hexa = np.stack(
            [
                vref[:, a],
                edge(a, bb),
                face(a, bb, cc),
                edge(a, cc),
                edge(a, d),
                face(a, bb, d),
                cref,
                face(a, cc, d),
            ],
            axis=1,
        )
        pieces.append(hexa)
        piece_block.append(gid[:, a])
    return Corners(
        table=table,
        face_block=np.concatenate(blocks),
        faces=np.concatenate(faces),
        piece_block=np.concatenate(piece_block),
        pieces=np.concatenate(pieces),
    )


def assemble(corners: Corners, block_ids: np.ndarray, dim: int) -> Blocks:
    """Group the faces by block; the pieces keep their order, with their block index.

    The points are the table's, all of them: after an exchange a few may be used by no
    block of this rank.

    Args:
        corners: the contributions (of this rank's cells and those received).
        block_ids: the global ids of the blocks to build (this rank's vertices), sorted,
            shape=(num_blocks,). Rows of other blocks are an error.
        dim: 2 or 3.

    Raises:
        ValueError: a face or piece belongs to none of ``block_ids``.
    """
    block_ids = np.asarray(block_ids, dtype=np.int64)
    nb = len(block_ids)
    index_type = np.int32 if len(corners.table.x) < 2**31 else np.int64

    def index_of(owner: np.ndarray) -> np.ndarray:
        index = np.searchsorted(block_ids, owner)
        if len(owner) and (
            index.max() >= nb or np.any(block_ids[np.minimum(index, nb - 1)] != owner)
        ):
            raise ValueError("a face or piece belongs to a block this rank does not build")
        return index

    index = index_of(corners.face_block).astype(np.int32)
    order = np.argsort(index)  # within a block, any order will do
    offsets = np.zeros(nb + 1, dtype=np.int64)
    np.cumsum(np.bincount(index, minlength=nb), out=offsets[1:])
    return Blocks(
        dim=dim,
        points=corners.table.x,
        faces=corners.faces.astype(index_type)[order],
        face_offsets=offsets,
        pieces=corners.pieces.astype(index_type),
        piece_block=index_of(corners.piece_block),
        ids=block_ids,
        seeds=corners.table.x[corners.table.refs(VERTEX, block_ids)],
    )


def blocks_3d(points: np.ndarray, tets: np.ndarray) -> Blocks:
    """The blocks of a whole tetrahedral mesh, one per vertex used by a tetrahedron.

    Args:
        points: vertex coordinates, shape=(num_vertices, 3).
        tets: vertex indices per tetrahedron, shape=(num_cells, 4).
    """
    tets = np.asarray(tets, dtype=np.int64)
    points = np.asarray(points, dtype=float)
    corners = tet_corners(
        points[tets],
        tets,
        np.arange(len(tets), dtype=np.int64),
        boundary=None,
        num_vertices=len(points),
    )
    return assemble(corners, np.unique(tets), 3)
