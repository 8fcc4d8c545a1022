"""Simple polygons in the plane: validation, area, point location, segment clipping.

Pure numpy. A polygon is an array of its ``m`` vertices, shape=(m, 2), without the
closing repeat of the first vertex; :func:`as_polygon` checks it and returns it
counter-clockwise. Points on the boundary (within ``1e-12`` times the polygon's size, the
diagonal of its bounding box) count as inside, in :func:`points_in_polygon` and in
:func:`clip_segments` alike.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from geofrac.dfn.errors import DfnError

__all__ = [
    "as_polygon",
    "boundary_tolerance",
    "clip_segments",
    "nearest_boundary_point",
    "point_segment_distance",
    "points_in_polygon",
    "polygon_area",
    "rectangle",
]

#: Relative tolerance of the on-boundary test, times the polygon's size.
BOUNDARY_RTOL = 1e-12


def _signed_area(poly: np.ndarray) -> float:
    """Shoelace area, positive for counter-clockwise vertices; poly shape=(m, 2)."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _size(poly: np.ndarray) -> float:
    """Diagonal of the bounding box of poly, shape=(m, 2)."""
    return float(np.hypot(*(poly.max(axis=0) - poly.min(axis=0))))


def boundary_tolerance(poly: np.ndarray) -> float:
    """Distance below which a point counts as on the boundary of ``poly``.

    Args:
        poly: polygon vertices, shape=(m, 2).

    Returns:
        ``BOUNDARY_RTOL`` times the diagonal of the bounding box.
    """
    return BOUNDARY_RTOL * _size(np.asarray(poly, dtype=float))


def point_segment_distance(
    p: np.ndarray, a: np.ndarray, b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Distance from points p to the closed segments [a, b], broadcast over leading axes.

    Args:
        p: points, shape=(..., 2).
        a: segment starts, shape=(..., 2).
        b: segment ends, shape=(..., 2).

    Returns:
        (distances, t), both of the broadcast leading shape; the closest point is
        a + t (b − a) with t in [0, 1].
    """
    ab = b - a
    ap = p - a
    den = np.sum(ab * ab, axis=-1)
    t = np.sum(ap * ab, axis=-1) / np.where(den > 0.0, den, 1.0)
    t = np.clip(t, 0.0, 1.0)
    d = ap - t[..., None] * ab
    return np.hypot(d[..., 0], d[..., 1]), t


def nearest_boundary_point(
    points: np.ndarray, poly: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Closest point of the boundary of ``poly`` to each point.

    Args:
        points: shape=(n, 2).
        poly: polygon vertices, shape=(m, 2); side k runs from vertex k to vertex k + 1.

    Returns:
        (distance shape=(n,), side shape=(n,), t shape=(n,) the parameter along that
        side, closest point shape=(n, 2)).
    """
    a, b = poly, np.roll(poly, -1, axis=0)
    d, t = point_segment_distance(points[:, None, :], a[None], b[None])
    side = np.argmin(d, axis=1)
    rows = np.arange(len(points))
    ts = t[rows, side]
    closest = a[side] + ts[:, None] * (b[side] - a[side])
    return d[rows, side], side, ts, closest


def as_polygon(points: ArrayLike) -> np.ndarray:
    """Check a simple polygon and return its vertices counter-clockwise.

    Args:
        points: vertices in order, shape=(m, 2), ``m >= 3``, without repeating the first
            vertex at the end.

    Returns:
        Float copy of the vertices, shape=(m, 2), counter-clockwise (reversed if the input
        was clockwise).

    Raises:
        DfnError: not an (m, 2) array of finite numbers, fewer than 3 vertices, two
            consecutive vertices equal (also last and first), zero area, or the boundary
            intersects or touches itself.
    """
    try:
        poly = np.array(points, dtype=float)
    except (TypeError, ValueError) as exc:
        raise DfnError(f"polygon: vertices are not an (m, 2) array of numbers ({exc})") from None
    if poly.ndim != 2 or poly.shape[1] != 2:
        raise DfnError(f"polygon: vertices must have shape (m, 2), got {poly.shape}")
    m = len(poly)
    if m < 3:
        raise DfnError(f"polygon: needs at least 3 vertices, got {m}")
    if not np.all(np.isfinite(poly)):
        bad = int(np.nonzero(~np.all(np.isfinite(poly), axis=1))[0][0])
        raise DfnError(f"polygon: vertex {bad} is not finite: {poly[bad].tolist()}")
    nxt = np.roll(poly, -1, axis=0)
    same = np.all(poly == nxt, axis=1)
    if np.any(same):
        i = int(np.nonzero(same)[0][0])
        j = (i + 1) % m
        hint = " (do not repeat the first vertex at the end)" if j == 0 else ""
        raise DfnError(f"polygon: vertices {i} and {j} are the same point {poly[i].tolist()}{hint}")
    size = _size(poly)
    area = _signed_area(poly)
    if abs(area) <= BOUNDARY_RTOL * size * size:
        raise DfnError(f"polygon: zero area (vertices {poly.tolist()})")
    tol = BOUNDARY_RTOL * size
    a, b = poly, nxt
    first, second = np.triu_indices(m, k=1)  # edge pairs first < second
    adjacent = (second == first + 1) | ((first == 0) & (second == m - 1))
    # non-adjacent edges must not meet at all: a proper crossing, or an endpoint of one
    # edge on the other (touching, a repeated vertex, a collinear overlap)
    ni, nj = first[~adjacent], second[~adjacent]
    if len(ni):
        ai, bi, aj, bj = a[ni], b[ni], a[nj], b[nj]

        def orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
            return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (
                r[:, 0] - p[:, 0]
            )

        o1, o2 = orient(ai, bi, aj), orient(ai, bi, bj)
        o3, o4 = orient(aj, bj, ai), orient(aj, bj, bi)
        crossing = (np.sign(o1) * np.sign(o2) < 0) & (np.sign(o3) * np.sign(o4) < 0)
        touching = (
            (point_segment_distance(aj, ai, bi)[0] <= tol)
            | (point_segment_distance(bj, ai, bi)[0] <= tol)
            | (point_segment_distance(ai, aj, bj)[0] <= tol)
            | (point_segment_distance(bi, aj, bj)[0] <= tol)
        )
        hit = crossing | touching
        if np.any(hit):
            k = int(np.nonzero(hit)[0][0])
            raise DfnError(
                f"polygon: not simple, edge {ni[k]} ({ni[k]}->{(ni[k] + 1) % m}) meets "
                f"edge {nj[k]} ({nj[k]}->{(nj[k] + 1) % m})"
            )
    # adjacent edges share one vertex; they overlap when the boundary folds back on itself
    prev = np.roll(poly, 1, axis=0)
    spike = (point_segment_distance(prev, poly, nxt)[0] <= tol) | (
        point_segment_distance(nxt, prev, poly)[0] <= tol
    )
    if np.any(spike):
        k = int(np.nonzero(spike)[0][0])
        raise DfnError(f"polygon: not simple, the boundary folds back at vertex {k}")
    return poly if area > 0 else poly[::-1].copy()


def rectangle(lower: tuple[float, float], upper: tuple[float, float]) -> np.ndarray:
    """Axis-aligned rectangle ``[x0, x1] × [y0, y1]``.

    Args:
        lower: the corner ``(x0, y0)``.
        upper: the corner ``(x1, y1)``.

    Returns:
        Vertices counter-clockwise from ``(x0, y0)``, shape=(4, 2).

    Raises:
        DfnError: ``x1 <= x0`` or ``y1 <= y0``, or a coordinate is not finite.
    """
    (x0, y0), (x1, y1) = lower, upper
    vals = np.array([x0, y0, x1, y1], dtype=float)
    if not np.all(np.isfinite(vals)):
        raise DfnError(f"rectangle: coordinates must be finite, got {vals.tolist()}")
    if x1 <= x0:
        raise DfnError(f"rectangle: x1 = {x1} must be greater than x0 = {x0}")
    if y1 <= y0:
        raise DfnError(f"rectangle: y1 = {y1} must be greater than y0 = {y0}")
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)


def polygon_area(poly: ArrayLike) -> float:
    """Area of a polygon (positive whatever the orientation).

    Args:
        poly: vertices, shape=(m, 2); checked by :func:`as_polygon`.
    """
    return abs(_signed_area(as_polygon(poly)))


def _on_boundary(points: np.ndarray, poly: np.ndarray, tol: float) -> np.ndarray:
    """Whether points lie within tol of an edge; points shape=(n, 2) -> shape=(n,)."""
    on = np.zeros(len(points), dtype=bool)
    px, py = np.ascontiguousarray(points[:, 0]), np.ascontiguousarray(points[:, 1])
    nxt = np.roll(poly, -1, axis=0)
    for a, b in zip(poly, nxt, strict=True):
        (x0, y0), (x1, y1) = np.minimum(a, b) - tol, np.maximum(a, b) + tol
        near = np.nonzero((px >= x0) & (px <= x1) & (py >= y0) & (py <= y1))[0]
        on[near] |= point_segment_distance(points[near], a, b)[0] <= tol
    return on


def _inside(points: np.ndarray, poly: np.ndarray, tol: float) -> np.ndarray:
    """Even-odd ray casting plus the on-boundary test; points shape=(n, 2) -> shape=(n,)."""
    px, py = points[:, 0], points[:, 1]
    inside = np.zeros(len(points), dtype=bool)
    nxt = np.roll(poly, -1, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        for (ax, ay), (bx, by) in zip(poly, nxt, strict=True):
            straddles = (ay > py) != (by > py)
            if ay == by:
                continue  # a horizontal edge never straddles the ray's height
            x_cross = ax + (py - ay) * (bx - ax) / (by - ay)
            inside ^= straddles & (px < x_cross)
    return inside | _on_boundary(points, poly, tol)


def points_in_polygon(points: ArrayLike, poly: ArrayLike) -> np.ndarray:
    """Which points lie inside the polygon (even-odd rule; the boundary counts as inside).

    Args:
        points: query points, shape=(n, 2).
        poly: polygon vertices, shape=(m, 2); checked by :func:`as_polygon`.

    Returns:
        Boolean mask, shape=(n,). Points within :func:`boundary_tolerance` of an edge are
        inside.
    """
    poly = as_polygon(poly)
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise DfnError(f"points must have shape (n, 2), got {pts.shape}")
    return _inside(pts, poly, boundary_tolerance(poly))


def _fill_null(status: np.ndarray) -> np.ndarray:
    """Replace -1 entries by the nearest earlier valid entry of the row, else a later one.

    Args:
        status: shape=(n, k) of -1 (null), 0 (outside), 1 (inside).

    Returns:
        shape=(n, k); rows with no valid entry stay -1.
    """
    n, k = status.shape
    rows = np.arange(n)[:, None]
    cols = np.arange(k)
    valid = status >= 0
    last = np.maximum.accumulate(np.where(valid, cols, -1), axis=1)
    out = np.where(last >= 0, status[rows, np.maximum(last, 0)], -1)
    first = np.minimum.accumulate(np.where(valid, cols, k)[:, ::-1], axis=1)[:, ::-1]
    return np.where(out >= 0, out, np.where(first < k, status[rows, np.minimum(first, k - 1)], -1))


def clip_segments(segments: ArrayLike, poly: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Parts of segments inside a (possibly non-convex) polygon.

    Each segment is split at the parameters ``t`` in [0, 1] where it crosses a polygon
    edge or passes over a polygon vertex; the sub-pieces whose midpoint is inside (the
    boundary counts as inside, so a segment along an edge is kept) are kept, and
    consecutive kept sub-pieces of one segment are joined, so a segment touching the
    boundary from inside (at a vertex or along an edge) stays one piece. Sub-pieces shorter
    than :func:`boundary_tolerance` (repeated crossings at a vertex) count as zero length
    and never split or form a piece; no other length filter is applied. Pieces keep their
    segment's direction, and an endpoint inside the polygon is returned exactly, so a
    segment entirely inside comes back unchanged.

    Args:
        segments: segments as two endpoints each, shape=(n, 2, 2) (segment, endpoint, xy).
        poly: polygon vertices, shape=(m, 2); checked by :func:`as_polygon`.

    Returns:
        ``(pieces, parent)``: pieces, shape=(k, 2, 2), ordered by parent then along it;
        parent, shape=(k,) int, the index of each piece's input segment.

    Raises:
        DfnError: segments of the wrong shape or not finite; an invalid polygon.
    """
    poly = as_polygon(poly)
    segs = np.asarray(segments, dtype=float)
    if segs.size == 0:
        segs = segs.reshape(0, 2, 2)
    if segs.ndim != 3 or segs.shape[1:] != (2, 2):
        raise DfnError(f"segments must have shape (n, 2, 2), got {segs.shape}")
    if not np.all(np.isfinite(segs)):
        bad = int(np.nonzero(~np.all(np.isfinite(segs), axis=(1, 2)))[0][0])
        raise DfnError(f"segment {bad} is not finite: {segs[bad].tolist()}")
    n = len(segs)
    if n == 0:
        return np.zeros((0, 2, 2)), np.zeros(0, dtype=np.intp)
    tol = boundary_tolerance(poly)
    p, q = segs[:, 0], segs[:, 1]
    r = q - p
    rr = np.sum(r * r, axis=1)
    length = np.sqrt(rr)
    xlo, ylo = np.minimum(p, q).T.copy()
    xhi, yhi = np.maximum(p, q).T.copy()
    hit_rows: list[np.ndarray] = [np.arange(n), np.arange(n)]
    hit_ts: list[np.ndarray] = [np.zeros(n), np.ones(n)]
    nxt = np.roll(poly, -1, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        for a, b in zip(poly, nxt, strict=True):
            # only segments whose bounding box meets the edge's can cross it or touch a
            (x0, y0), (x1, y1) = np.minimum(a, b) - tol, np.maximum(a, b) + tol
            near = np.nonzero((xhi >= x0) & (xlo <= x1) & (yhi >= y0) & (ylo <= y1))[0]
            pn, qn, rn, rrn = p[near], q[near], r[near], rr[near]
            s = b - a
            w = a - pn
            denom = rn[:, 0] * s[1] - rn[:, 1] * s[0]
            t = (w[:, 0] * s[1] - w[:, 1] * s[0]) / denom
            u = (w[:, 0] * rn[:, 1] - w[:, 1] * rn[:, 0]) / denom
            cross = (denom != 0.0) & (t >= 0.0) & (t <= 1.0) & (u >= 0.0) & (u <= 1.0)
            hit_rows.append(near[cross])
            hit_ts.append(t[cross])
            # the vertex a lying on the segment (this also covers collinear overlaps)
            on = (point_segment_distance(a, pn, qn)[0] <= tol) & (rrn > 0.0)
            tv = (w[on, 0] * rn[on, 0] + w[on, 1] * rn[on, 1]) / rrn[on]
            hit_rows.append(near[on])
            hit_ts.append(np.clip(tv, 0.0, 1.0))
    # T: the sorted split parameters of each segment, shape=(n, k), padded with 1.0
    rows = np.concatenate(hit_rows)
    tvals = np.concatenate(hit_ts)
    order = np.lexsort((tvals, rows))
    rows, tvals = rows[order], tvals[order]
    counts = np.bincount(rows, minlength=n)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    T = np.ones((n, int(counts.max())))
    T[rows, np.arange(len(rows)) - first[rows]] = tvals
    lo, hi = T[:, :-1], T[:, 1:]
    real = (hi - lo) * length[:, None] > tol
    status = np.full(lo.shape, -1, dtype=np.int8)
    ri, ci = np.nonzero(real)
    tm = 0.5 * (lo[ri, ci] + hi[ri, ci])
    mid = (1.0 - tm)[:, None] * p[ri] + tm[:, None] * q[ri]
    status[ri, ci] = _inside(mid, poly, tol)
    inside = _fill_null(status) == 1
    before = np.zeros_like(inside)
    before[:, 1:] = inside[:, :-1]
    after = np.zeros_like(inside)
    after[:, :-1] = inside[:, 1:]
    sr, sc = np.nonzero(inside & ~before)
    er, ec = np.nonzero(inside & ~after)
    t0 = T[sr, sc]
    t1 = T[er, ec + 1]
    start = (1.0 - t0)[:, None] * p[sr] + t0[:, None] * q[sr]
    end = (1.0 - t1)[:, None] * p[er] + t1[:, None] * q[er]
    pieces = np.stack([start, end], axis=1)
    keep = np.any(start != end, axis=1)
    return pieces[keep], sr[keep].astype(np.intp)
