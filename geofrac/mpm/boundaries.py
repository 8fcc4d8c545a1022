"""Grid, walls and bed of an MPM scene: which nodal velocity components are held.

Pure numpy. The scene's box ``[lower, upper]`` is padded by ``padding`` cells on every
side (GIMP supports reach past a wall). A wall on a box side holds the nodes on or
beyond that side: ``fixed`` all velocity components, ``roller`` the normal one. The
``bed`` (2D) is the immobile ground as a polyline y(x): nodes on or below it are held,
or, when the ``friction`` effect names it, frictional (eqs. 4.44-4.47) with the normal
pointing out of the material into the bed.

A frictional boundary gives one row (node, normal, plane offset) per node on or beyond
it: the padding nodes beyond a wall and the nodes below the bed too, since GIMP
supports reach them; each row's plane x·n = d is the boundary itself, so the touch
check of :mod:`~geofrac.mpm.friction` measures how far the material is from the
boundary, not from the node. A node on several boundaries keeps a row for each
frictional one (a corner); a node with held components keeps its frictional rows with
the normals projected onto its free components (a roller wall meeting a frictional
floor: the wall holds x, the floor still stops y; before, such a node lost its friction
row and material fell through the corner). Only a node held in every component drops
its rows.

``mpm.bed_representation`` says which bed nodes are frictional: all those on or below
the polyline (``"plane"``), or only the surface of the staircase they form, the deeper
ones held (``"staircase"``, the grid boundary of Edo (2016), 4.3.3); see :func:`bed_nodes`.
"""

from __future__ import annotations

import numpy as np

from geofrac.model.scene import BED_REPRESENTATIONS
from geofrac.mpm.grid import Grid, grid

__all__ = [
    "TOL",
    "bed_nodes",
    "boundary_rows",
    "scene_grid",
    "wall_nodes",
]

#: Tolerance (relative to the cell size L) of the grid's geometry: a node within
#: TOL × L of a box side is on it, within TOL × L of the bed polyline (above it, or
#: beyond its x-range) is on the bed, and a box side within TOL × L of a node plane
#: ends the grid there. The node coordinates (origin + k L) and the polyline carry
#: round-off of a few ulps of the coordinates, so a node meant to lie on a boundary
#: (a side at x = 1.5 is the node at 1.5000000000000002) belongs to it on every
#: machine; a node a cell away is far outside.
TOL = 1e-9


def scene_grid(
    lower: tuple[float, ...], upper: tuple[float, ...], spacing: float, *, padding: int
) -> Grid:
    """The background grid covering the box plus ``padding`` cells on every side."""
    lo, up = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    cells = np.ceil((up - lo) / spacing - TOL).astype(int) + 2 * padding
    return grid(lo - padding * spacing, spacing, tuple(int(c) for c in cells))


def wall_nodes(
    nodes: np.ndarray, lower: np.ndarray, upper: np.ndarray, *, side: str, spacing: float
) -> tuple[np.ndarray, int, float]:
    """Nodes on or beyond a box side.

    Args:
        nodes: node coordinates, shape=(N, dim).
        lower: the box's lowest corner, shape=(dim,).
        upper: its highest corner, shape=(dim,).
        side: ``x_min`` ... ``z_max``.
        spacing: cell size (for the tolerance).

    Returns:
        (mask shape=(N,), axis, outward sign ±1).
    """
    axis = "xyz".index(side[0])
    tol = TOL * spacing
    if side.endswith("min"):
        return nodes[:, axis] <= lower[axis] + tol, axis, -1.0
    return nodes[:, axis] >= upper[axis] - tol, axis, 1.0


def _below(x: np.ndarray, y: np.ndarray, bed: np.ndarray, tol: float) -> tuple[np.ndarray, ...]:
    """Which points lie on or below the polyline within its x-range, shape=(N,).

    ``tol``: a point within it above the polyline, or beyond its x-range, is on it.

    Returns:
        (below shape=(N,) bool, the segment under each point shape=(N,), its slope
        f' shape=(N,), the bed height f(x) shape=(N,)).
    """
    inside = (x >= bed[0, 0] - tol) & (x <= bed[-1, 0] + tol)
    seg = np.clip(np.searchsorted(bed[:, 0], x, side="right") - 1, 0, len(bed) - 2)
    x0, y0 = bed[seg, 0], bed[seg, 1]
    slope = (bed[seg + 1, 1] - y0) / (bed[seg + 1, 0] - x0)
    yb = y0 + slope * (x - x0)
    return inside & (y <= yb + tol), seg, slope, yb


def bed_nodes(
    nodes: np.ndarray, bed: np.ndarray, spacing: float, *, representation: str = "plane"
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Nodes on or below the bed polyline within its x-range, with normals into the bed.

    ``representation`` says which of them carry a frictional row:

    - ``"plane"``: every one; its row's plane is the polyline's segment over the node, so
      a node a cell or more below the bed still lets the material slide along the bed
      (only the approach into the bed is stopped).
    - ``"staircase"`` (the immobile ground as the grid's boundary, Edo (2016), 4.3.3):
      the nodes below the bed form the fixed region, a staircase of cells. Only its
      surface nodes, those sharing a cell with a node above the bed (or beyond the
      polyline's x-range), carry a row (normal and plane of the segment over the node);
      the deeper ones are held in every component.

    Args:
        nodes: node coordinates, shape=(N, 2).
        bed: the polyline, shape=(k, 2), x increasing.
        spacing: cell size (for the tolerance and the neighbours).
        representation: ``"plane"`` or ``"staircase"``.

    Returns:
        (node ids of the rows shape=(m,), unit normals out of the material into the bed
        shape=(m, 2): (f', −1)/√(1 + f'²) of the segment under the node, the plane
        offsets d = n·(x, f(x)) of that segment shape=(m,), ids of the nodes held in
        every component shape=(j,) (empty for ``"plane"``)).
    """
    if representation not in BED_REPRESENTATIONS:
        raise ValueError(
            f"bed_nodes: representation must be one of {BED_REPRESENTATIONS}, "
            f"got {representation!r}"
        )
    x, y = nodes[:, 0], nodes[:, 1]
    tol = TOL * spacing
    below, _, slope, yb = _below(x, y, bed, tol)
    deep = np.zeros_like(below)
    if representation == "staircase":
        # a node is deep when all 8 nodes it shares a cell with are below the bed too
        # (tested by coordinates, not grid indices: the same answer on every rank's slab)
        deep = below.copy()
        for dx in (-spacing, 0.0, spacing):
            for dy in (-spacing, 0.0, spacing):
                if dx or dy:
                    deep &= _below(x + dx, y + dy, bed, tol)[0]
    ids = np.flatnonzero(below & ~deep)
    n = np.column_stack([slope[ids], -np.ones(len(ids))])
    n /= np.linalg.norm(n, axis=1)[:, None]
    return ids, n, n[:, 0] * x[ids] + n[:, 1] * yb[ids], np.flatnonzero(deep)


def boundary_rows(
    g: Grid,
    lower: tuple[float, ...],
    upper: tuple[float, ...],
    *,
    walls: dict[str, str],
    bed: tuple[tuple[float, float], ...],
    frictional: tuple[str, ...] = (),
    bed_representation: str = "plane",
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Held components and frictional rows of grid ``g``.

    Args:
        g: the (local) grid.
        lower: the scene's box, lowest corner, shape=(dim,).
        upper: its highest corner, shape=(dim,).
        walls: side -> ``"fixed"`` or ``"roller"``.
        bed: the bed polyline (2D), or empty.
        frictional: boundaries (sides, ``"bed"``) whose nodes are frictional instead of
            held.
        bed_representation: ``"plane"`` or ``"staircase"`` (:func:`bed_nodes`).

    Returns:
        (held components shape=(N, dim) bool, frictional node ids shape=(m,) (a corner
        node once per boundary), their unit normals out of the material, projected on
        the node's free components, shape=(m, dim), their boundary planes' offsets
        x·n = d shape=(m,), the index into ``frictional`` of each row's boundary
        shape=(m,)).
    """
    nodes = g.nodes()
    lo, up = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    fixed = np.zeros((g.num_nodes, g.dim), dtype=bool)
    rows: list[tuple[np.ndarray, np.ndarray, np.ndarray, int]] = []
    for side, kind in walls.items():
        mask, axis, sign = wall_nodes(nodes, lo, up, side=side, spacing=g.spacing)
        if side in frictional:
            ids = np.flatnonzero(mask)
            normal = np.zeros((len(ids), g.dim))
            normal[:, axis] = sign
            plane = sign * (lo[axis] if sign < 0 else up[axis])
            rows.append((ids, normal, np.full(len(ids), plane), frictional.index(side)))
        elif kind == "fixed":
            fixed[mask] = True
        else:
            fixed[mask, axis] = True
    if bed:
        ids, normals, planes, deep = bed_nodes(
            nodes, np.asarray(bed, dtype=float), g.spacing, representation=bed_representation
        )
        fixed[deep] = True
        if "bed" in frictional:
            rows.append((ids, normals, planes, frictional.index("bed")))
        else:
            fixed[ids] = True
    if not rows:
        empty = np.zeros(0, dtype=np.int64)
        return fixed, empty, np.zeros((0, g.dim)), np.zeros(0), empty
    ids = np.concatenate([r[0] for r in rows])
    normals = np.concatenate([r[1] for r in rows])
    planes = np.concatenate([r[2] for r in rows])
    which = np.concatenate([np.full(len(r[0]), r[3], dtype=np.int64) for r in rows])
    from geofrac.mpm.friction import free_normals

    keep, free = free_normals(normals, fixed[ids])
    # a projected normal keeps its plane through the boundary point nearest the node
    planes = planes[keep] - np.einsum("ka,ka->k", nodes[ids[keep]], normals[keep])
    planes += np.einsum("ka,ka->k", nodes[ids[keep]], free)
    return fixed, ids[keep], free, planes, which[keep]
