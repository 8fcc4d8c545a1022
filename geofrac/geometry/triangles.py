"""Points of triangles: the inner point of each triangle of a mesh (Edo (2016), 5.2.2(a)).

In each triangle a point p is chosen inside the incircle: the incentre (Fig. 5.6), or a
seeded random point of the disc of radius ``radius`` x r around it (Fig. 5.7(b), the
"movable region"). The 2D blocks (:mod:`geofrac.blocks.dual2d`) cut each triangle at its
point; the EFMM element (:mod:`geofrac.elements.efmm`) joins the points of neighbouring
triangles into its domains. Pure numpy.

The random point of a triangle depends only on the seed and the key of the triangle: a
key given by the caller (the 2D blocks: the triangle's global id), or by default one made
of the triangle's corner coordinates (:func:`coordinate_keys`), so that the point is the
same on any number of ranks and however the mesh numbers its nodes and cells.
"""

from __future__ import annotations

import numpy as np

__all__ = ["INNER_POINTS", "coordinate_keys", "inner_points"]

#: Where a triangle's inner point goes (``blocks.inner_point``).
INNER_POINTS = ("incentre", "random")


def _mix(z: np.ndarray) -> np.ndarray:
    """splitmix64's finaliser of uint64 words, same shape (wraps modulo 2⁶⁴)."""
    with np.errstate(over="ignore"):
        z = z ^ (z >> np.uint64(30))
        z = z * np.uint64(0xBF58476D1CE4E5B9)
        z ^= z >> np.uint64(27)
        z *= np.uint64(0x94D049BB133111EB)
        z ^= z >> np.uint64(31)
    return z


def _uniform(keys: np.ndarray, seed: int, stream: int) -> np.ndarray:
    """Uniform numbers in [0, 1) from splitmix64 of (seed, stream, key), shape like ``keys``."""
    with np.errstate(over="ignore"):
        z = keys.astype(np.uint64) * np.uint64(0x9E3779B97F4A7C15)
        z += np.uint64((seed * 2 + stream) & 0xFFFFFFFFFFFFFFFF) * np.uint64(0xBF58476D1CE4E5B9)
    z = _mix(z)
    return (z >> np.uint64(11)).astype(np.float64) / float(1 << 53)


def coordinate_keys(x: np.ndarray) -> np.ndarray:
    """A key per triangle made of its corners' coordinates alone, shape=(num_cells,) uint64.

    The corners are taken in (x, y) order and the bits of their six coordinates mixed
    with splitmix64: the key does not depend on the order of the corners, on the
    triangle's index, nor on the number of ranks (the coordinates are the mesh file's).

    Args:
        x: vertex coordinates per triangle, any corner order, shape=(num_cells, 3, 2).
    """
    x = np.asarray(x, dtype=np.float64)[:, :, :2] + 0.0  # + 0.0: −0.0 and 0.0 alike
    order = np.lexsort((x[:, :, 1], x[:, :, 0]), axis=-1)
    words = np.ascontiguousarray(np.take_along_axis(x, order[:, :, None], axis=1))
    bits = words.reshape(len(x), 6).view(np.uint64)
    z = np.full(len(x), 0x9E3779B97F4A7C15, dtype=np.uint64)
    for j in range(6):
        z = _mix(z ^ bits[:, j])
    return z


def inner_points(
    x: np.ndarray,
    keys: np.ndarray | None,
    inner: str = "incentre",
    *,
    radius: float = 1.0,
    convex: bool = False,
    seed: int = 0,
) -> np.ndarray:
    """The inner point of each triangle, shape=(num_cells, 2).

    Args:
        x: vertex coordinates per triangle in increasing global-id order,
            shape=(num_cells, 3, 2).
        keys: a global key per triangle (seeds its random point), shape=(num_cells,);
            None: :func:`coordinate_keys` of ``x``.
        inner: ``"incentre"`` or ``"random"`` (a point of the disc of radius
            ``radius`` x r around the incentre, r the inradius).
        radius: the movable region's radius relative to the inradius, in [0, 1].
        convex: pull random points back into the medial triangle (see the module text).
        seed: the random seed.
    """
    side = np.linalg.norm(x[:, [2, 0, 1]] - x[:, [1, 2, 0]], axis=2)  # opposite each vertex
    perimeter = (side[:, 0] + side[:, 1]) + side[:, 2]
    centre = ((side[:, 0:1] * x[:, 0] + side[:, 1:2] * x[:, 1]) + side[:, 2:3] * x[:, 2]) / (
        perimeter[:, None]
    )
    if inner == "incentre":
        return centre
    if inner != "random":
        raise ValueError(f"inner point {inner!r}: expected one of {INNER_POINTS}")
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    r = 2.0 * area / perimeter
    if keys is None:
        keys = coordinate_keys(x)
    u, v = _uniform(keys, seed, 0), _uniform(keys, seed, 1)
    step = (radius * r * np.sqrt(u))[:, None] * np.column_stack(
        [np.cos(2 * np.pi * v), np.sin(2 * np.pi * v)]
    )
    if convex:  # largest t with centre + t step inside the medial triangle, then 0.99 of it
        t = np.ones(len(x))
        for i in range(3):
            j, k = [(1, 2), (0, 2), (0, 1)][i]
            mid_j, mid_k = (x[:, i] + x[:, j]) * 0.5, (x[:, i] + x[:, k]) * 0.5
            normal = np.column_stack([mid_k[:, 1] - mid_j[:, 1], mid_j[:, 0] - mid_k[:, 0]])
            toward_i = np.einsum("ij,ij->i", normal, x[:, i] - mid_j)
            normal *= np.sign(toward_i)[:, None]  # points to i's side of the midline
            gap = np.einsum("ij,ij->i", normal, mid_j - centre)  # > 0: centre is beyond
            rate = np.einsum("ij,ij->i", normal, step)
            hits = rate > gap
            t[hits] = np.minimum(t[hits], 0.99 * gap[hits] / rate[hits])
        step = step * t[:, None]
    return centre + step
