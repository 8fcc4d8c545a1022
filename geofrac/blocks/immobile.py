"""The immobile part as one block, from its closed surface patch.

Edo (2016), §5.3.2, Fig. 5.19-5.21.

A block face always has four points (§5.2.2(b)), so each triangle ijk of the surface
patch gives three faces, one per corner: (i, m_ij, p, m_ik), with m the edge midpoints and
p a point inside the triangle (its centroid here). The block has three times as many
faces as the patch has triangles (§5.5). It has no convex pieces: DEM and DDA codes
hold the immobile part fixed and need only its surface.
"""

from __future__ import annotations

import numpy as np

from geofrac.blocks.dual3d import centroids
from geofrac.blocks.model import Blocks

__all__ = ["surface_block"]


def surface_block(points: np.ndarray, triangles: np.ndarray) -> Blocks:
    """One block bounded by a closed, outward-oriented triangle surface.

    Args:
        points: surface vertices, shape=(num_points, 3).
        triangles: vertex indices, counter-clockwise seen from outside,
            shape=(num_triangles, 3).

    Returns:
        A single block (``ids`` -1, ``kind`` 1) of 3 x num_triangles quadrilateral faces.
    """
    points = np.asarray(points, dtype=float)
    tri = np.asarray(triangles, dtype=np.int64)
    n, m = len(points), len(tri)
    pairs = np.stack([tri, np.roll(tri, -1, axis=1)], axis=2).reshape(-1, 2)  # edge i -> i+1
    lo, hi = pairs.min(axis=1), pairs.max(axis=1)
    edges, edge_of = np.unique(lo * n + hi, return_inverse=True)
    a, b = edges // n, edges % n
    mids = (points[a] + points[b]) * 0.5
    centroid = centroids(points[tri])  # bit-equal to the moving layer's face centroids
    edge_of = edge_of.reshape(m, 3)  # edge c of a triangle runs from corner c to c + 1
    all_points = np.concatenate([points, mids, centroid])
    mid_ref = n + edge_of
    tri_ref = n + len(edges) + np.arange(m)
    faces = np.concatenate(
        [
            np.stack([tri[:, c], mid_ref[:, c], tri_ref, mid_ref[:, (c + 2) % 3]], axis=1)
            for c in range(3)
        ]
    )
    used = np.zeros(len(all_points), dtype=bool)
    used[faces.ravel()] = True
    new = np.cumsum(used) - 1
    p = points[tri]  # the volume centroid, by cones from the origin
    cone = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])) / 6.0
    seed = (cone[:, None] * p.sum(axis=1) / 4.0).sum(axis=0) / cone.sum()
    return Blocks(
        dim=3,
        points=all_points[used],
        faces=new[faces].astype(np.int32),
        face_offsets=np.array([0, len(faces)], dtype=np.int64),
        pieces=np.empty((0, 8), dtype=np.int32),
        piece_block=np.empty(0, dtype=np.int64),
        ids=np.array([-1], dtype=np.int64),
        seeds=seed[None, :],
        kind=np.array([1], dtype=np.int8),
    )
