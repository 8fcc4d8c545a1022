"""Named cell regions of a DFN rock mass (openings, excavation stages): polygons and layout.

Pure numpy. A region is a simple polygon inside the domain (the top heading of a tunnel,
its bench); its outline becomes mesh lines and the cells inside it a physical group of
its name (:mod:`geofrac.meshing.dfn`). A circle and a horseshoe are conveniences that
give polygons (:func:`circle_polygon`, :func:`horseshoe_polygon`), and a convex polygon
can be cut by a horizontal line into the part above or below it (:func:`cut_polygon`):
the top heading and the bench of one tunnel are the same polygon cut at the same level,
so they share the cut edge exactly.

:func:`layout_regions` puts the regions together: it merges their common vertices,
splits each outline edge at the other regions' vertices on it (so two regions touching
along a line share the same edges), checks that no two regions overlap, that they keep
clear of the domain's boundary and that their vertices keep the cleaning tolerance
apart, and returns the outline graph with each region's boundary loop and the loops of
the holes the regions cut into the rest of the rock.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from geofrac.dfn.clean import box_pairs
from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import (
    as_polygon,
    nearest_boundary_point,
    point_segment_distance,
)

__all__ = [
    "Region",
    "RegionLayout",
    "circle_polygon",
    "cut_polygon",
    "horseshoe_polygon",
    "layout_regions",
    "strictly_inside",
]

#: Relative size (times the layout's scale) below which two outline points are the same.
SAME_RTOL = 1e-9


@dataclass(frozen=True)
class Region:
    """A named region.

    Attributes:
        name: physical group name of its cells (its outline is ``<name>_outline``).
        polygon: vertices, counter-clockwise, shape=(m, 2).
        mesh_size: element size along its outline, or None for the fractures' size.
    """

    name: str
    polygon: np.ndarray
    mesh_size: float | None = None


@dataclass(frozen=True)
class RegionLayout:
    """The outlines of all regions as one planar graph.

    Attributes:
        regions: the regions, in the order given.
        vertices: outline vertices, shape=(num_vertices, 2).
        edges: vertex numbers of each outline edge, shape=(num_edges, 2); edges of two
            touching regions are stored once.
        loops: per region, its boundary counter-clockwise as (edge numbers, shape=(k,);
            forward, shape=(k,) bool: the loop runs from ``edges[e, 0]`` to ``edges[e, 1]``).
        holes: the outer boundaries of the unions of touching regions, counter-clockwise,
            in the same form: the holes the regions cut into the rest of the rock.
    """

    regions: tuple[Region, ...]
    vertices: np.ndarray
    edges: np.ndarray
    loops: tuple[tuple[np.ndarray, np.ndarray], ...]
    holes: tuple[tuple[np.ndarray, np.ndarray], ...]

    @property
    def segments(self) -> np.ndarray:
        """Edge endpoints, shape=(num_edges, 2, 2)."""
        return self.vertices[self.edges].reshape(-1, 2, 2)

    @property
    def names(self) -> tuple[str, ...]:
        """Region names."""
        return tuple(r.name for r in self.regions)


def _arc(n: int, a0: float, a1: float) -> np.ndarray:
    """Unit vectors at n + 1 angles evenly from a0 to a1, shape=(n + 1, 2)."""
    angle = np.linspace(a0, a1, n + 1)
    unit = np.column_stack([np.cos(angle), np.sin(angle)])
    unit[np.abs(unit) < 1e-15] = 0.0  # the quarter points exactly on the axes
    return unit


def _cut_angle(level: float | None, centre: Sequence[float], radius: float) -> float | None:
    """Angle in (-π/2, π/2) where the line y = level meets the circle's right half."""
    if level is None:
        return None
    s = (level - float(centre[1])) / radius
    if not -1.0 < s < 1.0:
        raise DfnError(f"the line y = {level:g} misses the circle (radius {radius:g})")
    return float(np.arcsin(s))


def _pieces(total: int, spans: Sequence[float]) -> list[int]:
    """Split ``total`` segments over arcs in proportion to their spans, at least 1 each."""
    return [max(1, round(total * a / sum(spans))) for a in spans]


def circle_polygon(
    centre: Sequence[float], radius: float, segments: int, *, level: float | None = None
) -> np.ndarray:
    """Polygon inscribed in a circle.

    Args:
        centre: (x, y).
        radius: circumradius (> 0).
        segments: number of sides (>= 3).
        level: a height y at which the polygon will be cut (:func:`cut_polygon`): the two
            points where the line y = level meets the circle are then vertices (with y =
            level exactly), and each of the two arcs between them gets its share of the
            sides, so the parts above and below have no short sides at the cut.

    Returns:
        Vertices counter-clockwise, shape=(k, 2) (k = ``segments`` without ``level``,
        starting at ``centre + (radius, 0)``, its area ``k / 2 · radius² · sin(2π / k)``;
        about ``segments`` with it). Vertices at multiples of 90° lie exactly on the axes
        through ``centre``.
    """
    if not (np.isfinite(radius) and radius > 0):
        raise DfnError(f"radius must be > 0, got {radius!r}")
    if segments < 3:
        raise DfnError(f"segments must be >= 3, got {segments}")
    beta = _cut_angle(level, centre, radius)
    if beta is None:
        return _arc(segments, 0.0, 2.0 * np.pi)[:-1] * radius + np.asarray(centre, float)
    top, bottom = _pieces(segments, [np.pi - 2 * beta, np.pi + 2 * beta])
    unit = np.vstack(
        [_arc(top, beta, np.pi - beta)[:-1], _arc(bottom, np.pi - beta, 2 * np.pi + beta)[:-1]]
    )
    poly = unit * radius + np.asarray(centre, float)
    poly[[0, top], 1] = level
    return poly


def horseshoe_polygon(
    centre: Sequence[float],
    width: float,
    wall_height: float,
    *,
    segments: int,
    level: float | None = None,
) -> np.ndarray:
    """A semicircular roof on vertical walls with a flat invert.

    Args:
        centre: (x, y) of the roof's centre, on the springline (the tops of the walls).
        width: span between the walls (the roof's radius is width / 2).
        wall_height: height of the vertical walls below the springline (> 0).
        segments: sides of the polygonal roof (>= 2).
        level: a height y at which the polygon will be cut: inside the roof, the points
            where the line meets it are vertices (as in :func:`circle_polygon`); at or
            below the springline the walls are cut where they are.

    Returns:
        Vertices counter-clockwise from the invert's right end, shape=(k, 2): the right
        wall's foot, the roof from angle 0 to π, the left wall's foot. Without ``level``
        k = segments + 3 and the area is ``segments / 2 · R² · sin(π / segments) + width ·
        wall_height``, R = width / 2.
    """
    if not (np.isfinite(width) and width > 0):
        raise DfnError(f"width must be > 0, got {width!r}")
    if not (np.isfinite(wall_height) and wall_height > 0):
        raise DfnError(f"wall_height must be > 0, got {wall_height!r}")
    if segments < 2:
        raise DfnError(f"segments must be >= 2, got {segments}")
    r = 0.5 * width
    in_roof = level is not None and level > float(centre[1])
    beta = _cut_angle(level, centre, r) if in_roof else None
    if beta is None:
        roof = _arc(segments, 0.0, np.pi)
    else:
        side, middle, _ = _pieces(segments, [beta, np.pi - 2 * beta, beta])
        roof = np.vstack(
            [
                _arc(side, 0.0, beta)[:-1],
                _arc(middle, beta, np.pi - beta)[:-1],
                _arc(side, np.pi - beta, np.pi),
            ]
        )
    feet = np.array([[r, -wall_height], [-r, -wall_height]])
    poly = np.vstack([feet[:1], roof * r, feet[1:]]) + np.asarray(centre, float)
    if beta is not None:
        poly[[1 + side, 1 + side + middle], 1] = level
    return poly


def cut_polygon(poly: np.ndarray, level: float, *, keep: str) -> np.ndarray:
    """Part of a convex polygon above or below the line y = level.

    The cut points are computed from each crossing edge's lower endpoint, so cutting one
    polygon at one level gives bitwise the same points for ``above`` and ``below``: the two
    parts share their cut edge exactly. Vertices on the line belong to both parts.

    Args:
        poly: convex polygon, counter-clockwise, shape=(m, 2).
        level: y of the cut.
        keep: ``"above"`` (y >= level) or ``"below"`` (y <= level).

    Returns:
        The part, counter-clockwise, shape=(k, 2).

    Raises:
        DfnError: the line leaves less than a polygon of positive area on that side.
    """
    if keep not in ("above", "below"):
        raise DfnError(f"keep must be 'above' or 'below', got {keep!r}")
    sign = 1.0 if keep == "above" else -1.0
    out: list[np.ndarray] = []
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        if sign * (a[1] - level) >= 0.0:
            out.append(a)
        if (a[1] - level) * (b[1] - level) < 0.0:
            lo, hi = (a, b) if a[1] < b[1] else (b, a)
            x = lo[0] + (level - lo[1]) * (hi[0] - lo[0]) / (hi[1] - lo[1])
            out.append(np.array([x, level]))
    part = np.array(out).reshape(-1, 2)
    if len(part) < 3 or _area(part) <= 1e-12 * float(np.ptp(poly, axis=0).max()) ** 2:
        raise DfnError(f"the line y = {level:g} leaves nothing of the shape {keep} it")
    return part


def _area(poly: np.ndarray) -> float:
    """Shoelace area, positive counter-clockwise; poly shape=(m, 2)."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def strictly_inside(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd ray casting without a boundary tolerance; points shape=(n, 2) -> (n,).

    For points at a known distance from the boundary (the tests' cell centroids, the
    overlap probes of :func:`layout_regions`); a point on the boundary may go either way.
    """
    px, py = points[:, 0], points[:, 1]
    inside = np.zeros(len(points), dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for (ax, ay), (bx, by) in zip(poly, np.roll(poly, -1, axis=0), strict=True):
            if ay == by:
                continue
            straddles = (ay > py) != (by > py)
            inside ^= straddles & (px < ax + (py - ay) * (bx - ax) / (by - ay))
    return inside


def _merge_points(polygons: Sequence[np.ndarray], eps: float) -> tuple[np.ndarray, list[list[int]]]:
    """Common vertex numbers: points within eps of an earlier point are that point."""
    points = np.vstack(polygons)
    rep = np.arange(len(points))
    i, j = box_pairs(np.hstack([points, points]), pad=eps)  # i < j
    close = np.hypot(*(points[i] - points[j]).T) <= eps
    np.minimum.at(rep, j[close], i[close])
    while np.any(rep[rep] != rep):  # chains: follow to the first point
        rep = rep[rep]
    first, number = np.unique(rep, return_inverse=True)
    ids = np.split(number, np.cumsum([len(p) for p in polygons])[:-1])
    return points[first], [row.tolist() for row in ids]


def _split_loops(
    vertices: np.ndarray, ids: list[list[int]], eps: float
) -> list[list[tuple[int, int]]]:
    """Each region's directed edges, split at every other vertex lying on them."""
    loops = []
    for row in ids:
        u_all = np.array(row)
        v_all = np.roll(u_all, -1)
        segs = np.stack([vertices[u_all], vertices[v_all]], axis=1)
        e, k = box_pairs(_boxes(segs), np.hstack([vertices, vertices]), pad=eps)
        d, t = point_segment_distance(vertices[k], segs[e, 0], segs[e, 1])
        on = (d <= eps) & (t > 0.0) & (t < 1.0) & (k != u_all[e]) & (k != v_all[e])
        e, k, t = e[on], k[on], t[on]
        order = np.lexsort((t, e))
        inner = np.split(k[order], np.searchsorted(e[order], np.arange(1, len(row))))
        directed: list[tuple[int, int]] = []
        for u, v, mid in zip(u_all.tolist(), v_all.tolist(), inner, strict=True):
            directed += list(itertools.pairwise([u, *mid.tolist(), v]))
        loops.append(directed)
    return loops


def _boxes(segments: np.ndarray) -> np.ndarray:
    """Bounding boxes of segments shape=(n, 2, 2) -> shape=(n, 4)."""
    return np.hstack([segments.min(axis=1), segments.max(axis=1)])


def _check_crossings(layout_segments: np.ndarray, owner: np.ndarray, names: Sequence[str]) -> None:
    """No outline edge properly crosses another region's (after the splits)."""
    i, j = box_pairs(_boxes(layout_segments))
    keep = owner[i] != owner[j]
    i, j = i[keep], j[keep]
    a0, b0 = layout_segments[i, 0], layout_segments[j, 0]
    r, s = layout_segments[i, 1] - a0, layout_segments[j, 1] - b0
    den = r[:, 0] * s[:, 1] - r[:, 1] * s[:, 0]
    w = b0 - a0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[:, 0] * s[:, 1] - w[:, 1] * s[:, 0]) / den
        u = (w[:, 0] * r[:, 1] - w[:, 1] * r[:, 0]) / den
    eps = 1e-9
    hit = np.flatnonzero((den != 0) & (t > eps) & (t < 1 - eps) & (u > eps) & (u < 1 - eps))
    if len(hit):
        k = int(hit[0])
        p = a0[k] + t[k] * r[k]
        raise DfnError(
            f"regions '{names[owner[i[k]]]}' and '{names[owner[j[k]]]}' overlap: their "
            f"outlines cross at ({p[0]:.6g}, {p[1]:.6g})"
        )


def _loop_arrays(
    directed: Sequence[tuple[int, int]], index: dict[tuple[int, int], int]
) -> tuple[np.ndarray, np.ndarray]:
    edges = np.array([index[(min(u, v), max(u, v))] for u, v in directed], dtype=np.int64)
    forward = np.array([u < v for u, v in directed], dtype=bool)
    return edges, forward


def _holes(
    directed: list[list[tuple[int, int]]], vertices: np.ndarray, names: Sequence[str]
) -> list[list[tuple[int, int]]]:
    """The union's boundary: edges of one region only, chained into loops."""
    count: dict[tuple[int, int], int] = {}
    for loop in directed:
        for u, v in loop:
            key = (min(u, v), max(u, v))
            count[key] = count.get(key, 0) + 1
    nxt: dict[int, int] = {}
    for r, loop in enumerate(directed):
        for u, v in loop:
            if count[(min(u, v), max(u, v))] == 1:
                if u in nxt:
                    raise DfnError(
                        f"region '{names[r]}' touches another region at the single point "
                        f"({vertices[u][0]:.6g}, {vertices[u][1]:.6g}); regions must share "
                        "an edge or keep apart"
                    )
                nxt[u] = v
    loops = []
    while nxt:
        start = min(nxt)
        chain = [start]
        while nxt[chain[-1]] != start:
            chain.append(nxt.pop(chain[-1]))
        nxt.pop(chain[-1])
        if _area(vertices[chain]) <= 0.0:
            raise DfnError(
                "regions enclose rock between them (a hole in their union near "
                f"({vertices[start][0]:.6g}, {vertices[start][1]:.6g})); make that part a "
                "region too"
            )
        loops.append(list(itertools.pairwise([*chain, start])))
    return loops


def _check_spacing(
    vertices: np.ndarray, edges: np.ndarray, owner: np.ndarray, names: Sequence[str], tol: float
) -> None:
    """Outline vertices at least tol apart and from outline edges they do not end on."""
    points = np.hstack([vertices, vertices])
    i, j = box_pairs(points, pad=tol)
    d = np.hypot(*(vertices[i] - vertices[j]).T)
    v, e = box_pairs(points, _boxes(vertices[edges]), pad=tol)
    foreign = (edges[e, 0] != v) & (edges[e, 1] != v)
    v, e = v[foreign], e[foreign]
    dist, _ = point_segment_distance(vertices[v], vertices[edges[e, 0]], vertices[edges[e, 1]])
    close_points, close_edge = d.min(initial=np.inf), dist.min(initial=np.inf)
    if min(close_points, close_edge) >= tol:
        return
    if close_points <= close_edge:
        k = int(i[np.argmin(d)])
        edge = int(np.flatnonzero((edges == k).any(axis=1))[0])
    else:
        k, edge = int(v[np.argmin(dist)]), int(e[np.argmin(dist)])
    p = vertices[k]
    raise DfnError(
        f"region '{names[owner[edge]]}': outline points {min(close_points, close_edge):.3g} "
        f"apart near ({p[0]:.6g}, {p[1]:.6g}), closer than the cleaning tolerance {tol:g}; "
        "use fewer segments or a smaller tolerance"
    )


def layout_regions(
    regions: Sequence[Region], domain: np.ndarray, *, tol: float, margin: float
) -> RegionLayout:
    """Put the regions together into one outline graph and check them.

    Args:
        regions: the regions (polygons counter-clockwise).
        domain: the rock mass, counter-clockwise, shape=(m, 2).
        tol: the cleaning tolerance: outline vertices must keep it apart.
        margin: smallest distance between a region and the domain's boundary.

    Returns:
        The layout.

    Raises:
        DfnError: naming the region: outside the domain or closer than ``margin`` to its
            boundary, overlapping another region, touching one at a single point, enclosing
            rock with others, or with outline points closer than ``tol``.
    """
    names = [r.name for r in regions]
    polygons = [as_polygon(r.polygon) for r in regions]
    for region, poly in zip(regions, polygons, strict=True):
        inside = strictly_inside(poly, domain)
        gap = float(nearest_boundary_point(poly, domain)[0].min())
        corner_gap, _ = point_segment_distance(
            domain[:, None, :], poly[None, :, :], np.roll(poly, -1, axis=0)[None]
        )
        gap = min(gap, float(corner_gap.min()))
        if not inside.all() or gap < margin:
            where = "leaves the domain" if not inside.all() else f"lies {gap:.3g} from its boundary"
            raise DfnError(
                f"region '{region.name}' {where}; keep it at least {margin:g} (the mesh size) "
                "inside"
            )
    scale = float(np.ptp(domain, axis=0).max())
    eps = SAME_RTOL * scale
    vertices, ids = _merge_points(polygons, eps)
    directed = _split_loops(vertices, ids, eps)
    index: dict[tuple[int, int], int] = {}
    owners: dict[tuple[int, int], list[tuple[int, bool]]] = {}
    for r, loop in enumerate(directed):
        for u, v in loop:
            key = (min(u, v), max(u, v))
            index.setdefault(key, len(index))
            owners.setdefault(key, []).append((r, u < v))
    edges = np.array(list(index), dtype=np.int64).reshape(-1, 2)
    owner = np.array([owners[k][0][0] for k in index], dtype=np.int64)
    for own in owners.values():
        if len(own) > 1 and (len(own) > 2 or own[0][1] == own[1][1]):
            a, b = (names[own[0][0]], names[own[1][0]])
            raise DfnError(f"regions '{a}' and '{b}' overlap along their common edge")
    _check_crossings(vertices[edges], owner, names)
    probe = _inward_probes(vertices, directed, 1e-6 * scale)
    for r, pts in enumerate(probe):
        for other, poly in enumerate(polygons):
            if other != r and strictly_inside(pts, poly).any():
                raise DfnError(f"regions '{names[r]}' and '{names[other]}' overlap")
    holes = _holes(directed, vertices, names)
    _check_spacing(vertices, edges, owner, names, tol)
    return RegionLayout(
        regions=tuple(
            Region(r.name, poly, r.mesh_size) for r, poly in zip(regions, polygons, strict=True)
        ),
        vertices=vertices,
        edges=edges,
        loops=tuple(_loop_arrays(loop, index) for loop in directed),
        holes=tuple(_loop_arrays(loop, index) for loop in holes),
    )


def _inward_probes(
    vertices: np.ndarray, directed: list[list[tuple[int, int]]], offset: float
) -> list[np.ndarray]:
    """Per region, points just inside it next to each edge's midpoint, shape=(k, 2) each."""
    out = []
    for loop in directed:
        a = vertices[[u for u, _ in loop]]
        b = vertices[[v for _, v in loop]]
        t = b - a
        normal = np.column_stack([-t[:, 1], t[:, 0]]) / np.hypot(*t.T)[:, None]
        out.append(0.5 * (a + b) + offset * normal)
    return out
