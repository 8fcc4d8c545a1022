"""Distorted cantilever meshes with a prescribed minimum angle (gmsh on one process).

The Timoshenko cantilever 0 ≤ x ≤ L, -D/2 ≤ y ≤ D/2 is meshed by gmsh as in
``meshes/cantilever.geo`` (nx × ny squares of side h, each split into two
right-isosceles triangles, minimum angle 45°). Every node then moves by
``amplitude × h × r``, where ``r`` is a seeded random field, uniform in [-1, 1]², whose
component normal to the boundary is zero (nodes on x = 0 and x = L keep their x, nodes
on y = ±D/2 keep their y, corners stay put): the physical groups stay exact. The
amplitude is found by bisection so that the mesh's minimum interior angle equals the
target; a triangle that inverts or degenerates counts as angle 0, so the result never
inverts one.

The numpy functions (angles, areas, the field, the bisection) take and return arrays and
need no gmsh; :func:`build_distorted_cantilever` runs them on the gmsh mesh and writes
an MSH 4.1 file that a scene reads through ``geometry.file``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from geofrac.meshing.geo import gmsh_session

__all__ = [
    "GROUPS",
    "DistortedMesh",
    "build_distorted_cantilever",
    "distort_to_angle",
    "min_angle",
    "perturbation_field",
    "signed_areas",
    "triangle_angles",
]

#: Physical groups, as in ``meshes/cantilever.geo``.
GROUPS = ("domain", "fixed", "tip", "top", "bottom")


@dataclass(frozen=True)
class DistortedMesh:
    """A distorted cantilever mesh written to disk.

    Attributes:
        path: the ``.msh`` file.
        target: requested minimum angle [degrees].
        min_angle: measured minimum angle of the written mesh [degrees].
        max_angle: measured maximum angle of the written mesh [degrees].
        amplitude: node displacement bound, in units of the cell size h.
        nodes: number of nodes.
        cells: number of triangles.
    """

    path: Path
    target: float
    min_angle: float
    max_angle: float
    amplitude: float
    nodes: int
    cells: int


def triangle_angles(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Interior angles of every triangle, at each of its vertices, in degrees.

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices per triangle, shape=(num_triangles, 3).

    Returns:
        angles at vertices 0, 1, 2, shape=(num_triangles, 3); a degenerate triangle
        (two coincident nodes) gets angle 0 at the third vertex.
    """
    p = np.asarray(points, dtype=float)[np.asarray(triangles)]  # shape=(m, 3, 2)
    angles = np.empty(p.shape[:2])
    for i in range(3):
        a = p[:, (i + 1) % 3] - p[:, i]
        b = p[:, (i + 2) % 3] - p[:, i]
        cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
        dot = np.einsum("ij,ij->i", a, b)
        angles[:, i] = np.degrees(np.arctan2(np.abs(cross), dot))
    return angles


def signed_areas(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Signed areas (positive for counter-clockwise vertices).

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices per triangle, shape=(num_triangles, 3).

    Returns:
        areas, shape=(num_triangles,).
    """
    p = np.asarray(points, dtype=float)[np.asarray(triangles)]
    a, b = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    return 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])


def min_angle(points: np.ndarray, triangles: np.ndarray) -> float:
    """Smallest interior angle of a triangle mesh, in degrees.

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices per triangle, shape=(num_triangles, 3).
    """
    return float(triangle_angles(points, triangles).min())


def perturbation_field(
    points: np.ndarray, box: tuple[float, float, float, float], seed: int = 0
) -> np.ndarray:
    """Seeded random node directions, uniform in [-1, 1]², tangential on the boundary.

    The random vectors are assigned in lexicographic (x, y) order of the nodes, so the
    field does not depend on how the mesher numbered them.

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        box: (xmin, xmax, ymin, ymax) of the rectangular domain.
        seed: seed of ``numpy.random.default_rng``.

    Returns:
        directions, shape=(num_nodes, 2); the x component is 0 on x = xmin, xmax and the
        y component 0 on y = ymin, ymax (both at the corners).
    """
    pts = np.asarray(points, dtype=float)
    xmin, xmax, ymin, ymax = box
    scale = max(xmax - xmin, ymax - ymin)
    key = np.round(pts / scale, 9)  # round-off of the mesher must not change the order
    order = np.lexsort((key[:, 1], key[:, 0]))
    field = np.empty_like(pts)
    field[order] = np.random.default_rng(seed).uniform(-1.0, 1.0, size=pts.shape)
    tol = 1e-9 * scale
    on_x = (np.abs(pts[:, 0] - xmin) <= tol) | (np.abs(pts[:, 0] - xmax) <= tol)
    on_y = (np.abs(pts[:, 1] - ymin) <= tol) | (np.abs(pts[:, 1] - ymax) <= tol)
    field[on_x, 0] = 0.0
    field[on_y, 1] = 0.0
    return field


def _valid_min_angle(points: np.ndarray, triangles: np.ndarray, orientation: np.ndarray) -> float:
    """Minimum angle, or 0 if any triangle changed orientation or degenerated."""
    if np.any(signed_areas(points, triangles) * orientation <= 0.0):
        return 0.0
    return min_angle(points, triangles)


def distort_to_angle(
    points: np.ndarray,
    triangles: np.ndarray,
    directions: np.ndarray,
    *,
    target: float,
    tol: float = 1e-3,
    max_amplitude: float = 1.0,
) -> tuple[np.ndarray, float]:
    """Move nodes by ``amplitude × directions`` so that the minimum angle is ``target``.

    Bisection on the amplitude in [0, ``max_amplitude``]; the minimum angle counts as 0
    once a triangle inverts or degenerates, and is continuous in the amplitude, so the
    result meets the target to ``tol`` with no triangle inverted.

    Args:
        points: node coordinates, shape=(num_nodes, 2).
        triangles: node indices per triangle, shape=(num_triangles, 3).
        directions: node displacement per unit amplitude, shape=(num_nodes, 2).
        target: minimum angle wanted [degrees], at most the undistorted mesh's.
        tol: accepted |measured - target| [degrees].
        max_amplitude: upper end of the search.

    Returns:
        (moved points, shape=(num_nodes, 2), amplitude).

    Raises:
        ValueError: the target exceeds the undistorted minimum angle, or is not reached
            within ``max_amplitude``.
    """
    pts = np.asarray(points, dtype=float)
    dirs = np.asarray(directions, dtype=float)
    orientation = np.sign(signed_areas(pts, triangles))
    if np.any(orientation == 0.0):
        raise ValueError("the undistorted mesh has a degenerate triangle")
    start = min_angle(pts, triangles)
    if target > start + tol:
        raise ValueError(f"target {target}° exceeds the undistorted minimum angle {start:.4g}°")
    if target >= start - tol:
        return pts.copy(), 0.0
    lo, hi = 0.0, max_amplitude
    if _valid_min_angle(pts + hi * dirs, triangles, orientation) > target:
        raise ValueError(f"minimum angle {target}° not reached with amplitude {max_amplitude}")
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        measured = _valid_min_angle(pts + mid * dirs, triangles, orientation)
        if abs(measured - target) <= tol:
            return pts + mid * dirs, mid
        if measured > target:
            lo = mid
        else:
            hi = mid
    raise ValueError(f"bisection for minimum angle {target}° did not converge")  # pragma: no cover


def build_distorted_cantilever(
    path: Path,
    ny: int,
    target: float,
    *,
    length: float = 10.0,
    depth: float = 1.0,
    seed: int = 0,
) -> DistortedMesh:
    """Mesh the cantilever with gmsh, distort it to minimum angle ``target``, write ``path``.

    Runs gmsh on the calling process only (call it on rank 0). The mesh has
    nx = round(length / depth × ny) by ny squares of side h = depth / ny, split as
    ``meshes/cantilever.geo`` splits them, and the physical groups ``domain``, ``fixed``
    (x = 0), ``tip`` (x = length), ``top`` and ``bottom``.

    Args:
        path: output ``.msh`` file (MSH 4.1); its directory is created.
        ny: squares across the depth.
        target: minimum angle [degrees], in (0, 45]; 45 gives the undistorted mesh.
        length: beam length L.
        depth: beam depth D.
        seed: seed of the random node field (:func:`perturbation_field`).

    Raises:
        ValueError: the target cannot be met (see :func:`distort_to_angle`).
    """
    nx = round(length / depth * ny)
    h = depth / ny
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with gmsh_session(None, {}) as gmsh:
        gmsh.model.add("distorted_cantilever")
        geo = gmsh.model.geo
        corners = [
            geo.addPoint(0.0, -depth / 2, 0.0),
            geo.addPoint(length, -depth / 2, 0.0),
            geo.addPoint(length, depth / 2, 0.0),
            geo.addPoint(0.0, depth / 2, 0.0),
        ]
        lines = [geo.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
        surface = geo.addPlaneSurface([geo.addCurveLoop(lines)])
        for line, n in zip(lines, (nx, ny, nx, ny), strict=True):
            geo.mesh.setTransfiniteCurve(line, n + 1)
        geo.mesh.setTransfiniteSurface(surface, "Right", corners)
        geo.synchronize()
        gmsh.model.addPhysicalGroup(2, [surface], name="domain")
        for name, line in zip(("bottom", "tip", "top", "fixed"), lines, strict=True):
            gmsh.model.addPhysicalGroup(1, [line], name=name)
        gmsh.model.mesh.generate(2)

        tags, coords, _ = gmsh.model.mesh.getNodes()
        points = coords.reshape(-1, 3)[:, :2]
        index = np.empty(int(tags.max()) + 1, dtype=np.int64)
        index[tags] = np.arange(len(tags))
        _, tri_nodes = gmsh.model.mesh.getElementsByType(2)
        triangles = index[tri_nodes.reshape(-1, 3)]
        directions = h * perturbation_field(points, (0.0, length, -depth / 2, depth / 2), seed)
        moved, amplitude = distort_to_angle(points, triangles, directions, target=target)
        for tag, (x, y) in zip(tags, moved, strict=True):
            gmsh.model.mesh.setNode(int(tag), [float(x), float(y), 0.0], [])

        tags_w, coords, _ = gmsh.model.mesh.getNodes()  # what is written, not what was computed
        written = np.empty_like(points)
        written[index[tags_w]] = coords.reshape(-1, 3)[:, :2]
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(path))
    angles = triangle_angles(written, triangles)
    return DistortedMesh(
        path=path,
        target=float(target),
        min_angle=float(angles.min()),
        max_angle=float(angles.max()),
        amplitude=float(amplitude),
        nodes=len(tags),
        cells=len(triangles),
    )
