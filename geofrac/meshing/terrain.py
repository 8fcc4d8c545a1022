"""Landslide terrain of Edo (2016), §5.4: a moving layer of tets over an immobile part.

One process, no MPI, no DOLFINx (:mod:`geofrac.meshing.distribute` hands the mesh on).
The ground surface is eq. 5.1, ``z = b exp((x² + y²) / a) + c`` (a hill for
``a < 0``). The moving layer occupies an elliptic footprint in x-y; its top is the ground
and its bottom the slip surface, the ground lowered by a depth that is largest inside the
footprint (a deep-seated slide) and ``rim_depth > 0`` on its boundary, so side walls join
top and bottom along the footprint boundary. The immobile part is the box
``[x0, x1] x [y0, y1]`` from ``base_z`` up to the ground outside the footprint and up to
the slip surface inside it (a pit with side walls); it is one block, returned as its
closed triangulated surface patch.

The procedure follows Fig. 5.23, with gmsh in place of Triangle and TetGen:

1. mesh the footprint in 2D (gmsh, with the size of :func:`mesh_size` evaluated on the
   ground and on the slip surface above each point), Fig. 5.23(a);
2. lift its triangles to the ground (top) and to the slip surface (bottom), join their
   boundary loops by side walls subdivided vertically so their triangles stay well
   shaped, and hand this closed surface to gmsh as three discrete surfaces (the thesis's
   TetGen "poly" surface patch, Fig. 5.12(b));
3. mesh the volume with linear tets following the same size field, Fig. 5.23(f);
4. build the immobile part's surface patch: the pit is the layer's slip surface and side
   walls (the same points and triangles, reversed), the ground outside the footprint, the
   four box walls and the bottom are meshed with ``h_immobile``, Fig. 5.23(e).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Literal

import numpy as np

__all__ = [
    "ALGORITHMS_3D",
    "HETEROGENEOUS_ZONES",
    "TerrainBuilder",
    "TerrainSpec",
    "footprint_radius",
    "ground",
    "immobile_volume",
    "mesh_size",
    "slip_surface",
    "tet_volumes",
]

#: gmsh 3D algorithms by name (``Mesh.Algorithm3D``).
ALGORITHMS_3D = {"hxt": 10, "delaunay": 1}

#: A size zone: (centre (x, y, z), radius, size inside).
Zone = tuple[tuple[float, float, float], float, float]

#: Two fine and two coarse balls at mid-depth of the default layer (Edo (2016), Fig. 5.5(b),
#: 5.25(b)): near the head scarp, near the toe, and two coarse patches between.
HETEROGENEOUS_ZONES: tuple[Zone, ...] = (
    ((119.5, 59.7, 153.1), 25.0, 1.2),
    ((273.8, 86.6, 74.2), 20.0, 1.4),
    ((247.0, 162.6, 69.3), 35.0, 4.0),
    ((200.0, 55.3, 113.5), 30.0, 3.5),
)


@dataclass(frozen=True)
class TerrainSpec:
    """Geometry and mesh sizes of the landslide terrain (Edo (2016), §5.4, Fig. 5.23).

    Lengths in metres. The defaults are a hill 200 m high on a 1 km square (eq. 5.1 with
    ``a = -1e5``, ``b = 200``, ``c = 0``) with a slide 300 m long, 180 m wide and 8 to 40 m
    deep on its flank; ``h = 1.95`` gives a homogeneous layer of 100,643 vertices (the
    thesis's Fig. 5.25(a) had 100,824 blocks) and ``h = 1.98`` with
    :data:`HETEROGENEOUS_ZONES` a heterogeneous one of 100,298 (Fig. 5.25(b): 100,996).

    Attributes:
        extent: ``(x0, x1, y0, y1)`` of the box.
        base_z: bottom of the box, below the lowest slip point.
        a: eq. 5.1 coefficient (< 0: a hill; its width is about ``sqrt(-a)``).
        b: eq. 5.1 coefficient (height of the hill above ``c``).
        c: eq. 5.1 coefficient (ground level far from the hill).
        footprint_centre: ``(x, y)`` centre of the elliptic footprint.
        footprint_axes: its semi-axes ``(along, across)``.
        footprint_rotation: angle of the first axis from the x axis (degrees).
        max_depth: slip-surface depth below the ground at the footprint centre.
        rim_depth: depth on the footprint boundary (> 0: the height of the side walls).
        h: target edge length of the moving layer's tets.
        zones: balls ``((x, y, z), radius, size)`` where the target size is ``size``
            instead of ``h`` (finer or coarser; empty: a homogeneous layer, Edo (2016), Fig.
            5.25(a)); the size blends linearly to ``h`` over ``zone_transition * radius``
            outside each ball. Where fine and coarse zones overlap the sizes add up
            relative to ``h`` (see :func:`mesh_size`).
        zone_transition: thickness of the blending shell, relative to the ball radius.
        h_immobile: triangle size of the immobile surface patch away from the footprint.
        algorithm_3d: a key of :data:`ALGORITHMS_3D`. HXT (the default) meshes the
            default 540,000-tet layer in 2.0 s on one thread, gmsh's Delaunay in 19.7 s,
            from the same closed surface; neither changes it (checked after meshing).
        threads: gmsh threads for the 3D step (0: all cores). One by default: HXT's mesh
            is then reproducible (with 2 threads the default layer has
            100,396 vertices instead of 100,643), and under MPI the other ranks
            busy-wait in the broadcast of :func:`~geofrac.meshing.distribute.build_mesh`
            anyway.
        optimize: run gmsh's tet optimisation after the 3D step (``Mesh.Optimize``).
    """

    extent: tuple[float, float, float, float] = (-500.0, 500.0, -500.0, 500.0)
    base_z: float = -100.0
    a: float = -1.0e5
    b: float = 200.0
    c: float = 0.0
    footprint_centre: tuple[float, float] = (200.0, 100.0)
    footprint_axes: tuple[float, float] = (150.0, 90.0)
    footprint_rotation: float = 26.57
    max_depth: float = 40.0
    rim_depth: float = 8.0
    h: float = 1.95
    zones: tuple[Zone, ...] = ()
    zone_transition: float = 0.5
    h_immobile: float = 50.0
    algorithm_3d: Literal["hxt", "delaunay"] = "hxt"
    threads: int = 1
    optimize: bool = True

    def __post_init__(self) -> None:
        """Check the values.

        Raises:
            ValueError: an inconsistent value, or a footprint outside the extent.
        """
        x0, x1, y0, y1 = self.extent
        if not (x0 < x1 and y0 < y1):
            raise ValueError(f"extent {self.extent} must have x0 < x1 and y0 < y1")
        if not 0 < self.rim_depth <= self.max_depth:
            raise ValueError("need 0 < rim_depth <= max_depth")
        if min(*self.footprint_axes, self.h, self.h_immobile, self.zone_transition) <= 0:
            raise ValueError("footprint axes, h, h_immobile and zone_transition must be > 0")
        if self.algorithm_3d not in ALGORITHMS_3D:
            raise ValueError(f"algorithm_3d must be one of {sorted(ALGORITHMS_3D)}")
        if self.a == 0:  # eq. 5.1 divides by a
            raise ValueError("a must not be 0 (eq. 5.1 divides by it; < 0 gives a hill)")
        for centre, radius, size in self.zones:
            if len(centre) != 3 or radius <= 0 or size <= 0:
                raise ValueError(f"zone {(centre, radius, size)}: need (x, y, z), r > 0, h > 0")
        # bounding box of the rotated ellipse, with a margin for the walls of the box
        (cx, cy), (p, q) = self.footprint_centre, self.footprint_axes
        t = math.radians(self.footprint_rotation)
        hx = math.hypot(p * math.cos(t), q * math.sin(t))
        hy = math.hypot(p * math.sin(t), q * math.cos(t))
        margin = min(self.h_immobile, 0.05 * min(x1 - x0, y1 - y0))
        if cx - hx < x0 + margin or cx + hx > x1 - margin:
            raise ValueError("the footprint must lie inside the extent (x)")
        if cy - hy < y0 + margin or cy + hy > y1 - margin:
            raise ValueError("the footprint must lie inside the extent (y)")


def ground(x: np.ndarray, y: np.ndarray, spec: TerrainSpec) -> np.ndarray:
    """Ground height, Edo (2016), eq. 5.1: ``z = b exp((x² + y²) / a) + c``.

    Args:
        x: x coordinates, any shape broadcastable with ``y``.
        y: y coordinates.
        spec: the terrain (``a``, ``b``, ``c``).

    Returns:
        z, the broadcast shape of ``x`` and ``y``.
    """
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    return spec.b * np.exp((x * x + y * y) / spec.a) + spec.c


def footprint_radius(x: np.ndarray, y: np.ndarray, spec: TerrainSpec) -> np.ndarray:
    """Normalised elliptic radius ρ of the footprint: < 1 inside, 1 on its boundary.

    Args:
        x: x coordinates, any shape broadcastable with ``y``.
        y: y coordinates.
        spec: the terrain (footprint centre, axes, rotation).

    Returns:
        ρ, the broadcast shape of ``x`` and ``y``.
    """
    (cx, cy), (p, q) = spec.footprint_centre, spec.footprint_axes
    t = math.radians(spec.footprint_rotation)
    dx, dy = np.asarray(x, dtype=float) - cx, np.asarray(y, dtype=float) - cy
    u = dx * math.cos(t) + dy * math.sin(t)
    v = -dx * math.sin(t) + dy * math.cos(t)
    return np.sqrt((u / p) ** 2 + (v / q) ** 2)


def slip_surface(x: np.ndarray, y: np.ndarray, spec: TerrainSpec) -> np.ndarray:
    """Slip surface: the ground lowered by ``rim + (max - rim) (1 - ρ²)`` (Fig. 5.23(e)).

    ρ is :func:`footprint_radius`; the depth is ``max_depth`` at the footprint centre,
    ``rim_depth`` on its boundary, and ``rim_depth`` outside (clipped), so the surface is
    defined everywhere.

    Args:
        x: x coordinates, any shape broadcastable with ``y``.
        y: y coordinates.
        spec: the terrain.

    Returns:
        z, the broadcast shape of ``x`` and ``y``.
    """
    rho2 = footprint_radius(x, y, spec) ** 2
    depth = spec.rim_depth + (spec.max_depth - spec.rim_depth) * np.clip(1.0 - rho2, 0.0, 1.0)
    return ground(x, y, spec) - depth


def mesh_size(points: np.ndarray, spec: TerrainSpec) -> np.ndarray:
    """Target edge length of the moving layer at ``points`` (shape=(n, 3)).

    Each zone ``(centre, r, s)`` gives ``s_i = s`` within distance ``r`` of its centre,
    ``h`` beyond ``r + t`` (``t = zone_transition * r``) and a linear blend between, the
    same as gmsh's ``Ball`` field. Fine zones (``s < h``) combine by their minimum ``F``,
    coarse ones (``s > h``) by their maximum ``C``, and the size is ``F + C - h``: the fine
    size where only fine zones act, the coarse size where only coarse ones do.

    Returns:
        sizes, shape=(n,).
    """
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    fine = np.full(len(points), spec.h)
    coarse = np.full(len(points), spec.h)
    for centre, radius, size in spec.zones:
        d = np.linalg.norm(points - np.asarray(centre, dtype=float), axis=1)
        w = np.clip((d - radius) / (spec.zone_transition * radius), 0.0, 1.0)
        s = size + (spec.h - size) * w
        if size < spec.h:
            fine = np.minimum(fine, s)
        else:
            coarse = np.maximum(coarse, s)
    return fine + coarse - spec.h


def _column_size(x: float, y: float, spec: TerrainSpec) -> float:
    """:func:`mesh_size` at the ground and the slip point above ``(x, y)``, the smaller.

    The scalar version for gmsh's size callback of the footprint's 2D mesh, whose
    triangles become both surfaces.
    """
    zg = spec.b * math.exp((x * x + y * y) / spec.a) + spec.c
    (cx, cy), (p, q) = spec.footprint_centre, spec.footprint_axes
    t = math.radians(spec.footprint_rotation)
    u = (x - cx) * math.cos(t) + (y - cy) * math.sin(t)
    v = -(x - cx) * math.sin(t) + (y - cy) * math.cos(t)
    rho2 = (u / p) ** 2 + (v / q) ** 2
    zs = zg - spec.rim_depth - (spec.max_depth - spec.rim_depth) * min(max(1.0 - rho2, 0.0), 1.0)
    best = math.inf
    for z in (zg, zs):
        fine = coarse = spec.h
        for (px, py, pz), radius, size in spec.zones:
            d = math.sqrt((x - px) ** 2 + (y - py) ** 2 + (z - pz) ** 2)
            w = min(max((d - radius) / (spec.zone_transition * radius), 0.0), 1.0)
            s = size + (spec.h - size) * w
            if size < spec.h:
                fine = min(fine, s)
            else:
                coarse = max(coarse, s)
        best = min(best, fine + coarse - spec.h)
    return best


def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Signed volumes of tets (shape=(m, 4) indices into ``points``, shape=(n, 3)).

    Returns:
        volumes, shape=(m,).
    """
    p = points[tets]
    return (
        np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) / 6
    )


def immobile_volume(points: np.ndarray, triangles: np.ndarray) -> float:
    """Volume enclosed by a closed, outward-oriented triangle patch (divergence theorem).

    Args:
        points: shape=(n, 3).
        triangles: shape=(m, 3), counter-clockwise seen from outside.

    Returns:
        the volume (negative when the triangles point inwards).
    """
    p = np.asarray(points, dtype=float)
    p = p - p.mean(axis=0)  # less cancellation for a patch far from the origin
    t = p[np.asarray(triangles)]
    return float(np.einsum("ij,ij->", t[:, 0], np.cross(t[:, 1], t[:, 2])) / 6)


def _orient_up(xy: np.ndarray, tris: np.ndarray, up: bool = True) -> np.ndarray:
    """Triangles (shape=(m, 3)) flipped so their x-y signed area is > 0 (``up``) or < 0."""
    p = xy[tris]
    area = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (
        p[:, 2, 0] - p[:, 0, 0]
    )
    flip = (area < 0) if up else (area > 0)
    out = tris.copy()
    out[flip] = out[flip][:, ::-1]
    return out


def _boundary_loop(tris: np.ndarray) -> np.ndarray:
    """Boundary loop of a disk triangulation.

    Args:
        tris: counter-clockwise triangles, shape=(m, 3).

    Returns:
        the boundary vertices in counter-clockwise order, shape=(k,).

    Raises:
        RuntimeError: the boundary is not one loop.
    """
    edges = np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])
    key = np.minimum(edges[:, 0], edges[:, 1]) * (tris.max() + 1) + np.maximum(*edges.T)
    _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
    boundary = edges[counts[inverse] == 1]
    following = dict(zip(boundary[:, 0].tolist(), boundary[:, 1].tolist(), strict=True))
    start = int(boundary[0, 0])
    loop = [start]
    while (nxt := following[loop[-1]]) != start:
        loop.append(nxt)
        if len(loop) > len(boundary):
            break
    if len(loop) != len(boundary):
        raise RuntimeError("the footprint mesh boundary is not a single loop")
    return np.asarray(loop, dtype=np.int64)


def _mesh_footprint(gmsh: ModuleType, spec: TerrainSpec) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate the footprint ellipse in x-y with the size of :func:`_column_size`.

    Returns:
        xy shape=(n, 2), triangles shape=(m, 3) counter-clockwise.
    """
    (cx, cy), (p, q) = spec.footprint_centre, spec.footprint_axes
    t = math.radians(spec.footprint_rotation)
    e1, e2 = np.array([math.cos(t), math.sin(t)]), np.array([-math.sin(t), math.cos(t)])
    geo = gmsh.model.geo
    centre = geo.addPoint(cx, cy, 0.0)
    tips = [
        geo.addPoint(*(np.array([cx, cy]) + v), 0.0) for v in (p * e1, q * e2, -p * e1, -q * e2)
    ]
    major = tips[0] if p >= q else tips[1]
    arcs = [geo.addEllipseArc(tips[k], centre, major, tips[(k + 1) % 4]) for k in range(4)]
    geo.addPlaneSurface([geo.addCurveLoop(arcs)])
    geo.synchronize()
    gmsh.model.mesh.setSizeCallback(lambda dim, tag, x, y, z, lc: _column_size(x, y, spec))
    gmsh.model.mesh.generate(2)
    gmsh.model.mesh.removeSizeCallback()
    return _extract_planar(gmsh)


def _extract_planar(gmsh: ModuleType) -> tuple[np.ndarray, np.ndarray]:
    """The current model's 2D mesh, renumbered from 0.

    Returns:
        node x-y shape=(n, 2), counter-clockwise triangles shape=(m, 3).
    """
    tags, coords, _ = gmsh.model.mesh.getNodes()
    _, nodes = gmsh.model.mesh.getElementsByType(2)
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    tris = index[nodes.astype(np.int64).reshape(-1, 3)]
    used = np.unique(tris)
    renumber = np.full(len(tags), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    xy = coords.reshape(-1, 3)[used, :2]
    return xy, _orient_up(xy, renumber[tris])


def _mesh_planar(
    gmsh: ModuleType, loops: list[np.ndarray], sizes: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate a planar domain whose boundary points are given and kept.

    Args:
        gmsh: the gmsh module (a temporary model is added and removed).
        loops: closed polylines, the outer one first, each shape=(k_i, 2) (the last
            point is not repeated); every point is a mesh node and every segment a
            mesh edge.
        sizes: target mesh size at each loop point, shapes (k_i,); gmsh interpolates
            them inside (``Mesh.MeshSizeExtendFromBoundary``).

    Returns:
        interior points shape=(p, 2); triangles shape=(m, 3) indexing the loop points
        (concatenated in the given order) then the interior points, orientation as gmsh
        made it.
    """
    model = gmsh.model
    model.add("terrain-planar")
    geo = model.geo
    point_tags: list[int] = []
    curve_loops = []
    for loop, size in zip(loops, sizes, strict=True):
        tags = [
            geo.addPoint(float(u), float(v), 0.0, float(s))
            for (u, v), s in zip(loop, size, strict=True)
        ]
        lines = [geo.addLine(tags[k], tags[(k + 1) % len(tags)]) for k in range(len(tags))]
        for line in lines:
            geo.mesh.setTransfiniteCurve(line, 2)
        curve_loops.append(geo.addCurveLoop(lines))
        point_tags += tags
    geo.addPlaneSurface(curve_loops)
    geo.synchronize()
    option = gmsh.option
    # sizes from the boundary points, interpolated inside, capped by the largest
    wanted = {
        "Mesh.MeshSizeFromPoints": 1.0,
        "Mesh.MeshSizeExtendFromBoundary": 1.0,
        "Mesh.MeshSizeMax": float(max(s.max() for s in sizes)),
    }
    saved = {name: option.getNumber(name) for name in wanted}
    for name, value in wanted.items():
        option.setNumber(name, value)
    try:
        model.mesh.generate(2)
    finally:
        for name, value in saved.items():
            option.setNumber(name, value)
    boundary_node = np.array(
        [model.mesh.getNodes(0, tag)[0][0] for tag in point_tags], dtype=np.int64
    )
    inner_tags, inner_coords, _ = model.mesh.getNodes(2, -1)
    all_tags = np.concatenate([boundary_node, inner_tags.astype(np.int64)])
    index = np.full(int(all_tags.max()) + 1, -1, dtype=np.int64)
    index[all_tags] = np.arange(len(all_tags))
    _, nodes = model.mesh.getElementsByType(2)
    tris = index[nodes.astype(np.int64).reshape(-1, 3)]
    model.remove()
    if np.any(tris < 0):
        raise RuntimeError("a planar face mesh used a node off its boundary and interior")
    return inner_coords.reshape(-1, 3)[:, :2], tris


class _Points:
    """A growing point array (shape=(n, 3)) that hands out the indices of added rows."""

    def __init__(self) -> None:
        self.blocks: list[np.ndarray] = []
        self.count = 0

    def add(self, xyz: np.ndarray) -> np.ndarray:
        """Append rows (shape=(k, 3)); return their indices, shape=(k,)."""
        xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
        self.blocks.append(xyz)
        self.count += len(xyz)
        return np.arange(self.count - len(xyz), self.count, dtype=np.int64)

    def array(self) -> np.ndarray:
        """All points, shape=(n, 3)."""
        return np.concatenate(self.blocks) if self.blocks else np.empty((0, 3))


def _orient_along(points: np.ndarray, tris: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """Triangles (shape=(m, 3)) flipped so their normals point along ``outward`` (3,)."""
    p = points[tris]
    flip = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]) @ outward < 0
    out = tris.copy()
    out[flip] = out[flip][:, ::-1]
    return out


def _edge_nodes(start: float, stop: float, size: float) -> np.ndarray:
    """Equally spaced values from ``start`` to ``stop`` (excluded), at most ``size`` apart."""
    n = max(1, math.ceil(abs(stop - start) / size - 1e-9))
    return start + (stop - start) * np.arange(n) / n


def _immobile_patch(
    gmsh: ModuleType,
    spec: TerrainSpec,
    pts: _Points,
    rim_top: np.ndarray,
    pit: np.ndarray,
    rim_size: np.ndarray,
) -> np.ndarray:
    """Triangles of the immobile part's outer ground, box walls and bottom (Fig. 5.23(e)).

    Args:
        gmsh: the gmsh module (temporary models for the planar faces).
        spec: the terrain.
        pts: the patch's points so far (the pit's); new points are added to it.
        rim_top: indices in ``pts`` of the footprint boundary on the ground, shape=(k,),
            counter-clockwise seen from above.
        pit: the pit's triangles, shape=(m, 3), already oriented outwards (upwards).
        rim_size: mesh size at the rim points, shape=(k,).

    Returns:
        all triangles of the patch (pit included), shape=(t, 3), outward.
    """
    x0, x1, y0, y1 = spec.extent
    hi, base = spec.h_immobile, spec.base_z
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    # the rectangle's boundary, counter-clockwise from (x0, y0): its ground ring and base ring
    ring_xy, edge_rows = [], []
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        s = _edge_nodes(0.0, 1.0, hi / float(np.linalg.norm(b - a)))
        edge_rows.append(len(ring_xy) + np.arange(len(s) + 1))
        ring_xy += [a + t * (b - a) for t in s]
    ring_xy = np.array(ring_xy)
    nr = len(ring_xy)
    edge_rows = [rows % nr for rows in edge_rows]  # each edge's ring rows, both corners
    top_ring = pts.add(np.column_stack([ring_xy, ground(*ring_xy.T, spec)]))
    bottom_ring = pts.add(np.column_stack([ring_xy, np.full(nr, base)]))
    tris = [pit]

    # ground outside the footprint: the rectangle with the footprint as a hole
    all_xy = pts.array()[:, :2]
    rim_xy = all_xy[rim_top]
    inner, t = _mesh_planar(gmsh, [ring_xy, rim_xy], [np.full(nr, hi), rim_size])
    ids = np.concatenate(
        [top_ring, rim_top, pts.add(np.column_stack([inner, ground(*inner.T, spec)]))]
    )
    xy = np.concatenate([ring_xy, rim_xy, inner])
    tris.append(ids[_orient_up(xy, t, up=True)])

    # vertical box edges at the corners (interior points only)
    verticals = []
    for corner in corners:
        z = _edge_nodes(float(ground(*corner, spec)), base, hi)[1:]  # top down, ends excluded
        verticals.append(pts.add(np.column_stack([np.repeat(corner[None], len(z), 0), z])))

    # the four walls, each meshed in its own (distance along, z) plane
    points = pts.array()
    for k in range(4):
        rows = edge_rows[k]
        a, b = corners[k], corners[(k + 1) % 4]
        direction = (b - a) / np.linalg.norm(b - a)
        loop_ids = np.concatenate(
            [
                bottom_ring[rows],
                verticals[(k + 1) % 4][::-1],
                top_ring[rows][::-1],
                verticals[k],
            ]
        )
        loop_pts = points[loop_ids]
        loop_uv = np.column_stack([(loop_pts[:, :2] - a) @ direction, loop_pts[:, 2]])
        inner, t = _mesh_planar(gmsh, [loop_uv], [np.full(len(loop_uv), hi)])
        inner_xyz = np.column_stack(
            [a[0] + inner[:, 0] * direction[0], a[1] + inner[:, 0] * direction[1], inner[:, 1]]
        )
        ids = np.concatenate([loop_ids, pts.add(inner_xyz)])
        points = pts.array()
        outward = np.array([direction[1], -direction[0], 0.0])
        tris.append(_orient_along(points, ids[t], outward))

    # the bottom
    inner, t = _mesh_planar(gmsh, [ring_xy], [np.full(nr, hi)])
    ids = np.concatenate(
        [bottom_ring, pts.add(np.column_stack([inner, np.full(len(inner), base)]))]
    )
    tris.append(ids[_orient_up(np.concatenate([ring_xy, inner]), t, up=False)])
    return np.concatenate(tris)


def _size_field(gmsh: ModuleType, spec: TerrainSpec) -> int:
    """Background size field equal to :func:`mesh_size` (``Ball`` fields, ``F + C - h``)."""
    field = gmsh.model.mesh.field
    fine, coarse = [], []
    for (px, py, pz), radius, size in spec.zones:
        f = field.add("Ball")
        values = {
            "XCenter": px,
            "YCenter": py,
            "ZCenter": pz,
            "Radius": radius,
            "Thickness": spec.zone_transition * radius,
            "VIn": size,
            "VOut": spec.h,
        }
        for key, value in values.items():
            field.setNumber(f, key, float(value))
        (fine if size < spec.h else coarse).append(f)
    if not fine and not coarse:
        f = field.add("MathEval")
        field.setString(f, "F", repr(float(spec.h)))
        return f
    parts = []
    for name, group in (("Min", fine), ("Max", coarse)):
        if group:
            f = field.add(name)
            field.setNumbers(f, "FieldsList", group)
            parts.append(f)
    if len(parts) == 1:
        return parts[0]
    f = field.add("MathEval")
    field.setString(f, "F", f"F{parts[0]} + F{parts[1]} - {float(spec.h)!r}")
    return f


class TerrainBuilder:
    """Geometry builder of the landslide terrain (Edo (2016), §5.4, Fig. 5.23).

    Used as ``Geometry(builder=TerrainBuilder(spec), dim=3, groups={"layer": 3, "top": 2,
    "slip": 2, "side": 2})``; :func:`geofrac.meshing.distribute.build_mesh` calls
    :meth:`build` on rank 0 inside an empty gmsh session.

    Attributes:
        name: ``"terrain"``.
        spec: the terrain.
    """

    name = "terrain"

    def __init__(self, spec: TerrainSpec | None = None) -> None:
        self.spec = spec or TerrainSpec()

    def build(self, gmsh: ModuleType) -> tuple[dict[str, Any], tuple[np.ndarray, np.ndarray]]:
        """Mesh the moving layer in the current gmsh model; build the immobile patch.

        The model gets the volume group ``layer`` (linear tets) and the surface groups
        ``top``, ``slip`` and ``side``.

        Returns:
            report: JSON-ready numbers: ``vertices``, ``tets``, ``layer_volume`` (sum of
            the tet volumes), ``surface_triangles``, ``immobile_triangles``,
            ``immobile_volume``, ``wall_levels``, and seconds ``time_2d_s`` (footprint),
            ``time_surface_s`` (surfaces and immobile patch), ``time_3d_s``.
            payload: the immobile part's closed surface ``(points, triangles)``,
            shape=(n, 3) float64 and shape=(m, 3) int64, outward; its pit is the layer's
            ``slip`` and ``side`` triangles (same coordinates, reversed).

        Raises:
            RuntimeError: the slip surface reaches the base, or gmsh changed the surface.
        """
        spec = self.spec
        model = gmsh.model
        option = gmsh.option
        for name in ("Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
            option.setNumber(name, 0)
        option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
        option.setNumber("Mesh.Algorithm", 6)
        option.setNumber("General.NumThreads", 1)
        timer = time.perf_counter()

        # 1. the footprint in 2D (Fig. 5.23(a))
        model.add("terrain-footprint")
        xy, tris = _mesh_footprint(gmsh, spec)
        model.remove()
        t_2d = time.perf_counter() - timer

        # 2. top, slip and side surfaces of the layer (Fig. 5.12(b))
        timer = time.perf_counter()
        n = len(xy)
        z_top, z_slip = ground(*xy.T, spec), slip_surface(*xy.T, spec)
        if z_slip.min() <= spec.base_z:
            raise RuntimeError(f"the slip surface reaches base_z = {spec.base_z}")
        loop = _boundary_loop(tris)
        m = len(loop)
        widths = np.linalg.norm(xy[np.roll(loop, -1)] - xy[loop], axis=1)
        levels = max(1, round(spec.rim_depth / (0.87 * float(np.median(widths)))))
        frac = np.arange(1, levels)[:, None] / levels  # shape=(levels - 1, 1)
        wall_z = z_slip[loop] + frac * (z_top[loop] - z_slip[loop])  # shape=(levels - 1, m)
        wall_xyz = np.column_stack([np.tile(xy[loop], (levels - 1, 1)), wall_z.ravel()])
        surface = np.concatenate(
            [np.column_stack([xy, z_top]), np.column_stack([xy, z_slip]), wall_xyz]
        )
        # wall node of rim point j at level l: slip (l = 0), intermediate, top (l = levels)
        grid = np.vstack([n + loop, 2 * n + np.arange((levels - 1) * m).reshape(-1, m), loop])
        lo, up = grid[:-1], grid[1:]
        lo_next, up_next = np.roll(lo, -1, axis=1), np.roll(up, -1, axis=1)
        # outward (away from the footprint) for a counter-clockwise loop
        side = np.concatenate(
            [
                np.stack([lo, lo_next, up_next], axis=-1).reshape(-1, 3),
                np.stack([lo, up_next, up], axis=-1).reshape(-1, 3),
            ]
        )
        top, slip = tris, tris[:, ::-1] + n

        # the immobile patch: pit = slip and side reversed, then the rest (Fig. 5.23(e))
        pts = _Points()
        pts.add(surface)
        pit = np.concatenate([slip[:, ::-1], side[:, ::-1]])
        rim_size = np.array([_column_size(x, y, spec) for x, y in xy[loop]])
        rim_size = np.minimum(rim_size, np.maximum(widths, np.roll(widths, 1)))
        patch = _immobile_patch(gmsh, spec, pts, loop, pit, rim_size)
        patch_points = pts.array()
        used = np.unique(patch)
        renumber = np.full(len(patch_points), -1, dtype=np.int64)
        renumber[used] = np.arange(len(used))
        immobile = (np.ascontiguousarray(patch_points[used]), renumber[patch].astype(np.int64))
        t_surface = time.perf_counter() - timer

        # 3. the volume (Fig. 5.23(f))
        timer = time.perf_counter()
        model.add("terrain")
        node_tags = np.arange(1, len(surface) + 1, dtype=np.uint64)
        entities = {}
        for name, rows, elems in (
            ("top", np.arange(n), top),
            ("slip", np.arange(n, 2 * n), slip),
            ("side", np.arange(2 * n, len(surface)), side),
        ):
            tag = model.addDiscreteEntity(2)
            if len(rows):
                model.mesh.addNodes(2, tag, node_tags[rows], surface[rows].ravel())
            model.mesh.addElementsByType(tag, 2, [], (elems.ravel() + 1).astype(np.uint64))
            entities[name] = (tag, len(elems))
        shell = model.geo.addSurfaceLoop([tag for tag, _ in entities.values()])
        volume = model.geo.addVolume([shell])
        model.geo.synchronize()
        option.setNumber("Mesh.Algorithm3D", ALGORITHMS_3D[spec.algorithm_3d])
        option.setNumber("Mesh.Optimize", 1 if spec.optimize else 0)
        option.setNumber("General.NumThreads", spec.threads)
        model.mesh.field.setAsBackgroundMesh(_size_field(gmsh, spec))
        model.mesh.generate(3)
        for name, (tag, count) in entities.items():
            if len(model.mesh.getElementsByType(2, tag)[0]) != count:
                raise RuntimeError(f"gmsh changed the {name} surface while meshing the volume")
        model.addPhysicalGroup(3, [volume], name="layer")
        for name, (tag, _) in entities.items():
            model.addPhysicalGroup(2, [tag], name=name)
        t_3d = time.perf_counter() - timer

        tags, coords, _ = model.mesh.getNodes()
        _, tet_nodes = model.mesh.getElementsByType(4)
        index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
        index[tags.astype(np.int64)] = np.arange(len(tags))
        tets = index[tet_nodes.astype(np.int64).reshape(-1, 4)]
        vols = tet_volumes(coords.reshape(-1, 3), tets)
        report = {
            "vertices": len(np.unique(tets)),
            "tets": len(tets),
            "layer_volume": float(np.abs(vols).sum()),
            "surface_triangles": len(top) + len(slip) + len(side),
            "wall_levels": levels,
            "immobile_triangles": len(immobile[1]),
            "immobile_volume": immobile_volume(*immobile),
            "time_2d_s": t_2d,
            "time_surface_s": t_surface,
            "time_3d_s": t_3d,
        }
        return report, immobile
