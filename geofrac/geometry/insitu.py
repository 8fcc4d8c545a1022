"""Initial (in-situ) stress at points: a constant tensor or a geostatic field (numpy only).

Sign convention: **tension positive, compression negative** (as everywhere in geofrac); a
rock mass at depth has negative normal stresses. Stresses are in Voigt order: 2D
``(xx, yy, xy)``, 3D ``(xx, yy, zz, xy, yz, xz)`` (the order of
:func:`geofrac.model.fields.tensor_components` without the 2D ``zz``).

Kinds (docs/insitu.md):

- ``constant``: one tensor everywhere;
- ``geostatic``: the vertical stress of the overburden's weight, σv = −g ∫ ρ dz from the
  point up to the ground surface (σv = −ρ g d for one density, d the depth below the
  surface), and the horizontal stresses σh = K0 σv, K0 per region; the vertical axis is
  y in 2D and z in 3D, gravity acts along it downwards. The surface is a level (2D and
  3D) or, in 2D, a polyline y(x). Points above the surface carry no stress. With a
  density per region (2D), the column above a point is integrated exactly through the
  triangles of the mesh (:func:`column_weight`), the part above the mesh up to the
  surface with the default density.

A ``tectonic`` tensor, if given, is added to either kind.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "ROUND_OFF",
    "StressField",
    "column_weight",
    "evaluate",
    "out_of_plane",
    "surface_height",
    "voigt_size",
]


#: The step, relative to the mesh's width, to which :func:`column_weight` rounds x
#: coordinates (points pushed forward to interpolation points are off by round-off).
ROUND_OFF = 1e-9


def voigt_size(dim: int) -> int:
    """Number of Voigt components in dimension ``dim``: 3 (2D) or 6 (3D)."""
    return 3 if dim == 2 else 6


@dataclass(frozen=True)
class StressField:
    """An initial stress field, its regions given by integer ids (the cell tags).

    Attributes:
        dim: 2 or 3.
        kind: ``"constant"`` or ``"geostatic"``.
        stress: constant: the tensor in Voigt order, shape=(voigt_size(dim),).
        surface: geostatic: the ground level (y in 2D, z in 3D), or in 2D a polyline of
            [x, y] points, shape=(k, 2), x strictly increasing.
        gravity: g > 0, the magnitude of the gravitational acceleration.
        density: default mass density (regions not in ``densities``).
        densities: region id -> density.
        k0: default K0 (regions not in ``k0s``).
        k0s: region id -> K0.
        tectonic: a tensor added everywhere, shape=(voigt_size(dim),), or None.
    """

    dim: int
    kind: str
    stress: tuple[float, ...] = ()
    surface: float | tuple[tuple[float, float], ...] = 0.0
    gravity: float = 9.81
    density: float = 0.0
    densities: Mapping[int, float] = field(default_factory=dict)
    k0: float = 0.0
    k0s: Mapping[int, float] = field(default_factory=dict)
    tectonic: tuple[float, ...] | None = None

    @property
    def layered(self) -> bool:
        """Whether the density differs between regions (geostatic)."""
        return any(v != self.density for v in self.densities.values())


def surface_height(field_: StressField, x: np.ndarray) -> np.ndarray:
    """The ground surface's height above each horizontal position.

    Args:
        field_: a geostatic field.
        x: horizontal coordinates, shape=(n,) in 2D (x) or shape=(n, 2) in 3D (x, y).

    Returns:
        heights, shape=(n,).

    Raises:
        ValueError: a 2D point lies outside the polyline's x range (by more than
            :data:`ROUND_OFF` of it).
    """
    n = len(x)
    if isinstance(field_.surface, int | float):
        return np.full(n, float(field_.surface))
    line = np.asarray(field_.surface, dtype=float)
    slack = ROUND_OFF * (line[-1, 0] - line[0, 0])  # round-off of pushed-forward points
    outside = (x < line[0, 0] - slack) | (x > line[-1, 0] + slack)
    if np.any(outside):
        i = int(np.flatnonzero(outside)[0])
        raise ValueError(
            f"x = {x[i]:.6g} lies outside the surface polyline's range "
            f"[{line[0, 0]:.6g}, {line[-1, 0]:.6g}]"
        )
    return np.interp(x, line[:, 0], line[:, 1])


def column_weight(
    points: np.ndarray,
    triangles: np.ndarray,
    densities: np.ndarray,
    *,
    surface: np.ndarray,
    above: float,
) -> np.ndarray:
    """∫ ρ dy from each point up to the surface through a 2D triangulation (exact).

    The vertical line through a point crosses each triangle in a segment; the part of
    that segment between the point and the surface, times the triangle's density, is
    summed. Between the top of the mesh over the point and the surface the density is
    ``above``. A line along a vertical edge would meet the triangles on both sides of
    it: the column is taken as the limit from the right (triangles with x in [xmin,
    xmax)), or from the left where no triangle lies to the right of the point (the
    mesh's right side). The x coordinates of points and corners are first rounded to
    :data:`ROUND_OFF` of the mesh's width, so a point or corner that round-off moved off
    a vertical edge (a pushed-forward interpolation point) is on it again.

    Args:
        points: shape=(n, 2).
        triangles: corner coordinates, shape=(m, 3, 2).
        densities: density of each triangle, shape=(m,).
        surface: the surface's height over each point, shape=(n,).
        above: density between the mesh's top and the surface.

    Returns:
        shape=(n,): the mass per unit area of the column above each point (0 above the
        surface).
    """
    x = triangles[:, :, 0]
    step = ROUND_OFF * max(float(x.max() - x.min()), 1e-300) if len(x) else 1.0
    points = points.copy()
    points[:, 0] = np.round(points[:, 0] / step) * step
    triangles = triangles.copy()
    triangles[:, :, 0] = np.round(x / step) * step
    right, covered = _column(points, triangles, densities, surface=surface, above=above, right=True)
    left, _ = _column(points, triangles, densities, surface=surface, above=above, right=False)
    return np.where(covered, right, left)


def _column(
    points: np.ndarray,
    triangles: np.ndarray,
    densities: np.ndarray,
    *,
    surface: np.ndarray,
    above: float,
    right: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """One side's limit of :func:`column_weight`, and whether a triangle holds each point.

    ``right``: triangles with x in [xmin, xmax); else (xmin, xmax]. Both shape=(n,).
    """
    n = len(points)
    px, py = points[:, 0], points[:, 1]
    order = np.argsort(px, kind="stable")
    xs = px[order]
    total = np.zeros(n)
    covered = np.zeros(n, dtype=bool)
    top = np.full(n, -np.inf)  # highest mesh point over each point's x
    xmin, xmax = triangles[:, :, 0].min(axis=1), triangles[:, :, 0].max(axis=1)
    lo = np.searchsorted(xs, xmin, side="left" if right else "right")
    hi = np.searchsorted(xs, xmax, side="left" if right else "right")
    for t in np.flatnonzero(hi > lo):
        idx = order[lo[t] : hi[t]]
        bottom, upper = _vertical_span(triangles[t], px[idx])
        top[idx] = np.maximum(top[idx], upper)
        covered[idx] |= (bottom <= py[idx]) & (py[idx] <= upper)
        a = np.maximum(bottom, py[idx])
        b = np.minimum(upper, surface[idx])
        total[idx] += densities[t] * np.maximum(b - a, 0.0)
    cover = np.maximum(surface - np.maximum(top, py), 0.0)
    total += above * np.where(np.isfinite(top), cover, np.maximum(surface - py, 0.0))
    return total, covered


def _vertical_span(corners: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lowest, highest) y of a triangle, shape=(3, 2), on the vertical lines at ``x``."""
    lows = np.full(len(x), np.inf)
    highs = np.full(len(x), -np.inf)
    for i in range(3):
        (x0, y0), (x1, y1) = corners[i], corners[(i + 1) % 3]
        if x0 == x1:  # a vertical edge: its two ends, where x is on it
            on = x == x0
            lows[on] = np.minimum(lows[on], min(y0, y1))
            highs[on] = np.maximum(highs[on], max(y0, y1))
            continue
        s = (x - x0) / (x1 - x0)
        on = (s >= 0.0) & (s <= 1.0)
        y = y0 + np.clip(s, 0.0, 1.0) * (y1 - y0)
        lows = np.where(on, np.minimum(lows, y), lows)
        highs = np.where(on, np.maximum(highs, y), highs)
    empty = highs < lows
    lows[empty] = highs[empty] = 0.0
    return lows, highs


def evaluate(
    field_: StressField,
    points: np.ndarray,
    regions: np.ndarray,
    *,
    column: np.ndarray | None = None,
) -> np.ndarray:
    """The initial stress at points (tension positive).

    Args:
        field_: the field.
        points: coordinates, shape=(n, dim) (or (n, 3) with a zero z in 2D).
        regions: region id of each point, shape=(n,).
        column: geostatic with layered densities: ∫ ρ dz above each point, shape=(n,)
            (:func:`column_weight`); None: the region-independent density
            ``field_.density`` times the depth.

    Returns:
        Voigt stresses, shape=(n, 3) in 2D, shape=(n, 6) in 3D.

    Raises:
        ValueError: a point outside a polyline surface's range.
    """
    dim = field_.dim
    n = len(points)
    size = voigt_size(dim)
    out = np.zeros((n, size))
    if field_.kind == "constant":
        out[:] = np.asarray(field_.stress, dtype=float)
    else:
        vertical = dim - 1
        horizontal = points[:, 0] if dim == 2 else points[:, :2]
        depth = surface_height(field_, horizontal) - points[:, vertical]
        if column is None:
            column = field_.density * np.maximum(depth, 0.0)
        sv = -field_.gravity * column
        k0 = np.full(n, field_.k0)
        for region, value in field_.k0s.items():
            k0[regions == region] = value
        out[:, vertical] = sv
        for axis in range(dim - 1):
            out[:, axis] = k0 * sv
    if field_.tectonic is not None:
        out += np.asarray(field_.tectonic, dtype=float)
    return out


def out_of_plane(voigt: np.ndarray, *, nu: float, plane: str) -> np.ndarray:
    """The 2D initial stress's σzz: ν (σxx + σyy) in plane strain, 0 in plane stress.

    ν (σxx + σyy) is the out-of-plane stress that keeps εzz = 0 for an elastic initial
    state; for a geostatic field with the default K0 = ν/(1 − ν) it is K0 σv.

    Args:
        voigt: shape=(n, 3).
        nu: Poisson's ratio.
        plane: ``"strain"`` or ``"stress"``.

    Returns:
        shape=(n,).
    """
    if plane == "stress":
        return np.zeros(len(voigt))
    return nu * (voigt[:, 0] + voigt[:, 1])
