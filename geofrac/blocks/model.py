"""Block sets: the containers the block builders return and the writers read (pure numpy).

A block set is a list of polygons (2D) or closed polyhedra (3D) that share one point
array. Every block also carries its decomposition into convex pieces, one per sub-cell
of the mesh it was built from (Edo (2016), §5.2.2: a quadrilateral per triangle corner in 2D,
a hexahedron per tetrahedron corner in 3D), for the DEM/DDA codes that need convex
blocks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["HEX_FACES", "Blocks", "block_ranges", "join", "weld"]

HEX_FACES = np.array(
    [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
)
"""The faces of a VTK hexahedron, counter-clockwise seen from outside, shape=(6, 4)."""


@dataclass
class Blocks:
    """Polygonal (``dim == 2``) or polyhedral (``dim == 3``) blocks.

    2D: block ``b``'s boundary is the ring ``faces[face_offsets[b]:face_offsets[b + 1], 0]``
    (its points in counter-clockwise order); ``faces`` has shape=(num_ring_points, 1).

    3D: block ``b``'s faces are the rows ``faces[face_offsets[b]:face_offsets[b + 1]]``,
    each a planar quadrilateral (Edo (2016), §5.2.2(b): every block face has 4 points) whose points
    run counter-clockwise seen from outside the block; ``faces`` has shape=(num_faces, 4).
    A face two blocks share is stored once in each, in opposite orders.

    Attributes:
        dim: 2 or 3.
        points: point coordinates, shape=(num_points, dim); a few may be used by no
            block (points of faces another rank builds).
        faces: point indices, shape=(num_faces, 1) in 2D or (num_faces, 4) in 3D.
        face_offsets: where each block's faces start, shape=(num_blocks + 1,).
        pieces: the convex pieces' point indices, shape=(num_pieces, 4) in 2D (a
            counter-clockwise quadrilateral) or (num_pieces, 8) in 3D (a hexahedron in VTK's
            order: bottom quad, then the top quad above it).
        piece_block: the block of each piece, shape=(num_pieces,); pieces are in any
            order (the builders leave them in cell order).
        ids: an id per block, unique across ranks (the global index of the mesh vertex it
            surrounds; -1 for an immobile block), shape=(num_blocks,).
        seeds: the point each block surrounds (the mesh vertex; for an immobile block its
            centroid), shape=(num_blocks, dim).
        kind: per block, 0 for a block of the moving layer (one per mesh vertex), 1 for an
            immobile block, shape=(num_blocks,).
    """

    dim: int
    points: np.ndarray
    faces: np.ndarray
    face_offsets: np.ndarray
    pieces: np.ndarray
    piece_block: np.ndarray
    ids: np.ndarray
    seeds: np.ndarray
    kind: np.ndarray = field(default=None)  # type: ignore[arg-type]  # None: set by __post_init__

    def __post_init__(self) -> None:
        """Default ``kind``: every block of the moving layer."""
        if self.kind is None:
            self.kind = np.zeros(len(self.ids), dtype=np.int8)

    @property
    def num_blocks(self) -> int:
        """Number of blocks."""
        return len(self.face_offsets) - 1


def block_ranges(offsets: np.ndarray) -> np.ndarray:
    """The block of each entry of a CSR list, shape=(offsets[-1],).

    ``offsets`` has shape=(num_blocks + 1,).
    """
    counts = np.diff(offsets)
    return np.repeat(np.arange(len(counts), dtype=np.int64), counts)


def join(first: Blocks, second: Blocks) -> Blocks:
    """The blocks of ``first`` then those of ``second``, in one set (same ``dim``)."""
    if first.dim != second.dim:
        raise ValueError(f"cannot join {first.dim}D and {second.dim}D blocks")
    if first.faces.shape[1] != second.faces.shape[1]:
        raise ValueError("cannot join blocks whose faces have different widths")
    shift = len(first.points)
    index = np.int64 if len(first.points) + len(second.points) >= 2**31 else np.int32
    return Blocks(
        dim=first.dim,
        points=np.concatenate([first.points, second.points]),
        faces=np.concatenate([first.faces, second.faces + shift]).astype(index),
        face_offsets=np.concatenate(
            [first.face_offsets, first.face_offsets[-1] + second.face_offsets[1:]]
        ),
        pieces=np.concatenate([first.pieces, second.pieces + shift]).astype(index),
        piece_block=np.concatenate([first.piece_block, second.piece_block + first.num_blocks]),
        ids=np.concatenate([first.ids, second.ids]),
        seeds=np.concatenate([first.seeds, second.seeds]),
        kind=np.concatenate([first.kind, second.kind]),
    )


def weld(blocks: Blocks) -> Blocks:
    """The same blocks with exactly coincident points merged into one.

    Block sets built apart (on different ranks, or a moving layer and its immobile
    part) compute their shared points with the same bits (see
    :func:`geofrac.blocks.dual3d.centroids`); welding them lets a face two blocks share
    be recognised by its point indices.
    """
    p = blocks.points
    order = _lexicographic_order(p)
    ordered = p[order]
    starts = np.ones(len(p), dtype=bool)
    starts[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    inverse = np.empty(len(p), dtype=blocks.faces.dtype)
    inverse[order] = np.cumsum(starts) - 1
    points = ordered[starts]
    return Blocks(
        dim=blocks.dim,
        points=points,
        faces=inverse[blocks.faces],
        face_offsets=blocks.face_offsets,
        pieces=inverse[blocks.pieces],
        piece_block=blocks.piece_block,
        ids=blocks.ids,
        seeds=blocks.seeds,
        kind=blocks.kind,
    )


def _lexicographic_order(points: np.ndarray) -> np.ndarray:
    """The permutation sorting the rows of ``points`` shape=(n, dim) lexicographically.

    As ``np.lexsort(points.T[::-1])``, but the full sort runs on the first coordinate
    alone; the other coordinates only order the rows whose first coordinates tie.
    """
    order = np.argsort(points[:, 0], kind="stable")
    first = points[order, 0]
    same = first[1:] == first[:-1]
    if not same.any():
        return order
    tied = np.zeros(len(order), dtype=bool)
    tied[1:] |= same
    tied[:-1] |= same
    run = np.cumsum(np.concatenate([[True], ~same]))[tied]
    sub = order[tied]
    rest = [points[sub, c] for c in range(points.shape[1] - 1, 0, -1)]
    order[tied] = sub[np.lexsort([*rest, run])]
    return order
