"""Triangle mesh quality figures (pure numpy)."""

from __future__ import annotations

import numpy as np

__all__ = ["triangle_quality"]


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
