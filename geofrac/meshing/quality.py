"""Mesh quality figures (pure numpy): triangles in the plane or in space, tetrahedra."""

from __future__ import annotations

import numpy as np

__all__ = [
    "tetrahedron_aspect_ratio",
    "tetrahedron_dihedral_angles",
    "tetrahedron_quality",
    "triangle_angles",
    "triangle_quality",
]


def triangle_quality(points: np.ndarray, triangles: np.ndarray) -> dict[str, float]:
    """Minimum and mean interior angle, shortest and longest edge of a triangle mesh.

    Args:
        points: node coordinates, shape=(num_nodes, 2) (or (num_nodes, 3); z is ignored).
        triangles: node indices of each triangle, shape=(num_triangles, 3).

    Returns:
        ``min_angle_deg``, ``mean_min_angle_deg`` (mean over triangles of their smallest
        angle), ``max_angle_deg``, ``shortest_edge``, ``longest_edge``.
    """
    xy = np.asarray(points, dtype=float)[:, :2]
    p = xy[np.asarray(triangles)]  # shape=(m, 3, 2)
    e = np.roll(p, -1, axis=1) - p  # edge k from vertex k to k+1, shape=(m, 3, 2)
    length = np.hypot(e[..., 0], e[..., 1])
    a, b = -np.roll(e, 1, axis=1), e  # the two edges leaving vertex k
    cos = np.einsum("mki,mki->mk", a, b) / (np.roll(length, 1, axis=1) * length)
    angles = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    smallest = angles.min(axis=1)
    return {
        "min_angle_deg": float(smallest.min()),
        "mean_min_angle_deg": float(smallest.mean()),
        "max_angle_deg": float(angles.max()),
        "shortest_edge": float(length.min()),
        "longest_edge": float(length.max()),
    }


def triangle_angles(corners: np.ndarray) -> np.ndarray:
    """Interior angles of triangles in the plane or in space, in degrees.

    Args:
        corners: the triangles' corners, shape=(n, 3, 2) or (n, 3, 3).

    Returns:
        the angle at each corner, shape=(n, 3) (nan for a triangle with a zero edge).
    """
    p = np.asarray(corners, dtype=float)
    e = np.roll(p, -1, axis=1) - p  # edge k from corner k to k+1
    length = np.linalg.norm(e, axis=2)
    a, b = -np.roll(e, 1, axis=1), e  # the two edges leaving corner k
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.einsum("mki,mki->mk", a, b) / (np.roll(length, 1, axis=1) * length)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _outward_face_normals(corners: np.ndarray) -> np.ndarray:
    """Area vectors of the faces of tetrahedra, face k opposite corner k, pointing out.

    Args:
        corners: shape=(n, 4, 3).

    Returns:
        shape=(n, 4, 3); each vector's length is twice the face's area.
    """
    p = np.asarray(corners, dtype=float)
    faces = ((1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2))
    out = np.empty_like(p)
    for k, (a, b, c) in enumerate(faces):
        normal = np.cross(p[:, b] - p[:, a], p[:, c] - p[:, a])
        inward = np.einsum("ni,ni->n", normal, p[:, k] - p[:, a]) > 0
        normal[inward] *= -1.0
        out[:, k] = normal
    return out


def tetrahedron_dihedral_angles(corners: np.ndarray) -> np.ndarray:
    """The six dihedral angles of tetrahedra (between the two faces at each edge), degrees.

    The angle at the edge shared by the faces opposite corners i and j is π minus the
    angle between their outward normals; 70.53° for all six of a regular tetrahedron.

    Args:
        corners: the tetrahedra's corners, shape=(n, 4, 3).

    Returns:
        shape=(n, 6), for the face pairs (0,1), (0,2), (0,3), (1,2), (1,3), (2,3)
        (nan for a face of zero area).
    """
    return _dihedral(_outward_face_normals(corners))


def _dihedral(normal: np.ndarray) -> np.ndarray:
    """Dihedral angles (degrees, shape=(n, 6)) from outward face normals, shape=(n, 4, 3)."""
    length = np.sqrt(np.einsum("nki,nki->nk", normal, normal))
    pairs = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
    i, j = np.array(pairs).T
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = -np.einsum("nki,nki->nk", normal[:, i], normal[:, j]) / (length[:, i] * length[:, j])
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def tetrahedron_aspect_ratio(corners: np.ndarray) -> np.ndarray:
    """Circumradius over three times the inradius of tetrahedra: 1 for a regular one.

    Args:
        corners: the tetrahedra's corners, shape=(n, 4, 3).

    Returns:
        R / (3 ρ), >= 1, shape=(n,) (inf for a flat tetrahedron).
    """
    p = np.asarray(corners, dtype=float)
    return _aspect(p, _outward_face_normals(p))


def _aspect(p: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """R / (3 ρ) (shape=(n,)) from corners (n, 4, 3) and outward face normals (n, 4, 3)."""
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    bc, ca, ab = np.cross(b, c), np.cross(c, a), np.cross(a, b)
    triple = np.abs(np.einsum("ni,ni->n", a, bc))  # 6 V
    num = (
        np.einsum("ni,ni->n", a, a)[:, None] * bc
        + np.einsum("ni,ni->n", b, b)[:, None] * ca
        + np.einsum("ni,ni->n", c, c)[:, None] * ab
    )
    area = 0.5 * np.sqrt(np.einsum("nki,nki->nk", normal, normal)).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        circumradius = np.sqrt(np.einsum("ni,ni->n", num, num)) / (2.0 * triple)
        inradius = 0.5 * triple / area  # 3 V / total face area
        ratio = circumradius / (3.0 * inradius)
    return np.where(triple > 0, ratio, np.inf)


def tetrahedron_quality(corners: np.ndarray) -> dict[str, float]:
    """Summary figures of a tetrahedral mesh.

    Args:
        corners: the tetrahedra's corners, shape=(n, 4, 3), n >= 1.

    Returns:
        ``min_dihedral_deg``, ``max_dihedral_deg``, ``max_aspect_ratio``,
        ``mean_aspect_ratio`` (:func:`tetrahedron_aspect_ratio`), ``min_volume``.
    """
    p = np.asarray(corners, dtype=float)
    normal = _outward_face_normals(p)
    angles = _dihedral(normal)
    ratio = _aspect(p, normal)
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    volume = np.abs(np.einsum("ni,ni->n", a, np.cross(b, c))) / 6.0
    return {
        "min_dihedral_deg": float(np.min(angles)),
        "max_dihedral_deg": float(np.max(angles)),
        "max_aspect_ratio": float(np.max(ratio)),
        "mean_aspect_ratio": float(np.mean(ratio)),
        "min_volume": float(np.min(volume)),
    }
