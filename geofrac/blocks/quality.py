"""Geometry and validity checks of block sets (numpy and numba; pyvista only for the validator).

A block set as large as Edo (2016)'s (10^5 polyhedra of ~70 quadrilateral faces, ~7·10^6
faces) is never walked with a Python loop. The 3D per-block checks and the face pairing
run in compiled loops (:mod:`geofrac.blocks.kernels`: one block or face at a time, with
small local arrays, where numpy would sort all 3·10^7 face corners together); 2D block
sets, which are far smaller, use whole-array numpy. On the 100k terrain the checks below
take about 3 s on one core (they took 28 s as numpy sorts).

- ``block_volumes``, ``block_centroids``, ``piece_volumes``: exact for planar faces
  (shoelace in 2D; divergence theorem over the faces split into triangles in 3D).
- ``check_closed``, ``euler_characteristic``, ``face_planarity``: per block or per face
  topology and shape.
- ``check_pairing``: faces match across blocks (with the volumes this rules out overlaps
  and gaps; see its docstring).
- ``overlap_samples``: how many blocks contain each sample point (via the convex pieces).
- ``validate_cells``: VTK's cell validator (``pyvista.DataSet.cell_validator``) on the
  blocks as ``VTK_POLYHEDRON`` / ``VTK_POLYGON`` cells.
- ``block_checks``: the checks that look at each block alone (ranks can share them out).
- ``summarize``: a JSON-ready report of all of the above.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from geofrac.blocks.model import HEX_FACES, Blocks, block_ranges

__all__ = [
    "BLOCK_CHECKS",
    "HEX_FACES",
    "LARGE_BLOCK_FACES",
    "SUMMARY_PHASES",
    "VALIDATOR_CHUNK",
    "VALIDATOR_FAILURES",
    "block_centroids",
    "block_checks",
    "block_points",
    "block_volumes",
    "check_closed",
    "check_pairing",
    "equivalent_diameters",
    "euler_characteristic",
    "face_planarity",
    "overlap_samples",
    "piece_volumes",
    "self_intersections",
    "summarize",
    "validate_cells",
]

#: Blocks per validator chunk: about 7 s of VTK's checks on terrain blocks (progress).
VALIDATOR_CHUNK = 1000

#: Blocks with more faces skip VTK's (quadratic) validator for the exact tests alone.
LARGE_BLOCK_FACES = 5000

VALIDATOR_FAILURES = (
    "WRONG_NUMBER_OF_POINTS",
    "INTERSECTING_EDGES",
    "INTERSECTING_FACES",
    "NON_CONTIGUOUS_EDGES",
    "INVERTED_FACES",
    "NON_PLANAR_FACES",
    "DEGENERATE_FACES",
    "COINCIDENT_POINTS",
    "INVALID_POINT_REFERENCES",
    "ZERO_SIZE",
    "NEGATIVE_SIZE",
)
"""The ``pyvista.CellStatus`` bits that make a block invalid (all but ``NON_CONVEX``)."""

_CHUNK = 1 << 18  # faces per chunk: bounds the (chunk, 4, 3) temporaries to ~25 MB


def _chunks(n: int, size: int = _CHUNK) -> Iterator[slice]:
    for start in range(0, n, size):
        yield slice(start, min(start + size, n))


def _ring_next(blocks: Blocks) -> np.ndarray:
    """2D: the ring entry after each ring entry (wrapping per block), shape=(num_faces,)."""
    off = np.asarray(blocks.face_offsets, dtype=np.int64)
    nxt = np.arange(1, off[-1] + 1, dtype=np.int64)
    full = off[1:] > off[:-1]
    nxt[off[1:][full] - 1] = off[:-1][full]
    return nxt


def _edges(blocks: Blocks) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2D: the directed ring edges (start, end) and their block, each shape=(num_edges,).

    One per ring entry, from the ring point to the next.
    """
    ring = np.asarray(blocks.faces, dtype=np.int64)[:, 0]
    return ring, ring[_ring_next(blocks)], block_ranges(blocks.face_offsets)


def _group_starts(*keys: np.ndarray) -> np.ndarray:
    """For arrays sorted together: True where a new group of equal keys starts."""
    n = len(keys[0])
    new = np.zeros(n, dtype=bool)
    if n:
        new[0] = True
    for key in keys:
        new[1:] |= key[1:] != key[:-1]
    return new


def _pair_order(owner: np.ndarray, key: np.ndarray) -> np.ndarray:
    """The permutation sorting (owner, key) pairs of non-negative integers."""
    if not len(owner):
        return np.zeros(0, dtype=np.int64)
    span = int(key.max()) + 1
    if (int(owner.max()) + 1) * span < 2**62:  # one int64 key sorts much faster
        return np.argsort(owner.astype(np.int64) * span + key, kind="stable")
    return np.lexsort((key, owner))


def _count_unique_per_block(owner: np.ndarray, key: np.ndarray, num_blocks: int) -> np.ndarray:
    """Number of distinct ``key`` values per block, shape=(num_blocks,)."""
    order = _pair_order(owner, key)
    new = _group_starts(owner[order], key[order])
    return np.bincount(owner[order][new], minlength=num_blocks)


def block_points(blocks: Blocks, *, with_pieces: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The distinct points of each block, in increasing index order (CSR).

    Args:
        blocks: the block set.
        with_pieces: also include points used only by the block's convex pieces (in 3D the
            mesh vertex inside an interior block).

    Returns:
        ``(offsets, ids)``: offsets shape=(num_blocks + 1,), point indices shape=(offsets[-1],).
    """
    faces = np.asarray(blocks.faces)
    if not with_pieces:
        from geofrac.blocks.kernels import unique_segments

        return unique_segments(faces.ravel(), np.asarray(blocks.face_offsets) * faces.shape[1])
    faces = faces.astype(np.int64)
    pieces = np.asarray(blocks.pieces, dtype=np.int64)
    owner = np.concatenate(
        [
            np.repeat(block_ranges(blocks.face_offsets), faces.shape[1]),
            np.repeat(blocks.piece_block, pieces.shape[1]),
        ]
    )
    ids = np.concatenate([faces.ravel(), pieces.ravel()])
    return _unique_per_owner(owner, ids, blocks.num_blocks)


def _unique_per_owner(
    owner: np.ndarray, ids: np.ndarray, num: int
) -> tuple[np.ndarray, np.ndarray]:
    """The distinct ``ids`` of each owner, sorted, as CSR (offsets, ids)."""
    order = _pair_order(owner, ids)
    owner, ids = owner[order], ids[order]
    new = _group_starts(owner, ids)
    owner, ids = owner[new], ids[new]
    counts = np.bincount(owner, minlength=num)
    return np.concatenate([[0], np.cumsum(counts)]).astype(np.int64), ids


def _reference_points(blocks: Blocks) -> np.ndarray:
    """A point near each block (mean of its face points), shape=(num_blocks, dim).

    Integrating relative to it keeps the volume sums free of cancellation far from the
    origin.
    """
    faces = np.asarray(blocks.faces)
    owner = np.repeat(block_ranges(blocks.face_offsets), faces.shape[1])
    x = np.asarray(blocks.points, dtype=float)[faces.ravel()]
    count = np.maximum(np.bincount(owner, minlength=blocks.num_blocks), 1)
    return np.column_stack(
        [np.bincount(owner, x[:, i], blocks.num_blocks) / count for i in range(blocks.dim)]
    )


def _quad_six_volumes(q: np.ndarray) -> np.ndarray:
    """6 x the signed volumes of the tets (0, a, b, c) + (0, a, c, d), shape=(n,).

    ``q``: quadrilaterals (a, b, c, d) relative to a reference point, shape=(n, 4, 3).
    """
    a, b, c, d = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.einsum("ij,ij->i", a, np.cross(b, c)) + np.einsum("ij,ij->i", a, np.cross(c, d))


def _integrate(blocks: Blocks, moments: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """Volumes shape=(num_blocks,) and, on request, centroids shape=(num_blocks, dim)."""
    if blocks.dim == 3:
        from geofrac.blocks.kernels import block_integrals

        vol, centroids = block_integrals(blocks.points, blocks.faces, blocks.face_offsets)
        return vol, centroids if moments else None
    n = blocks.num_blocks
    x = np.asarray(blocks.points, dtype=float)
    faces = np.asarray(blocks.faces, dtype=np.int64)
    owner = block_ranges(blocks.face_offsets)
    ref = _reference_points(blocks)
    vol = np.zeros(n)
    mom = np.zeros((n, 2)) if moments else None
    nxt = _ring_next(blocks)
    for s in _chunks(len(faces)):
        p = x[faces[s, 0]] - ref[owner[s]]
        q = x[faces[nxt[s], 0]] - ref[owner[s]]
        cross = p[:, 0] * q[:, 1] - q[:, 0] * p[:, 1]
        vol += np.bincount(owner[s], cross, n) / 2.0
        if mom is not None:
            for i in range(2):
                mom[:, i] += np.bincount(owner[s], (p[:, i] + q[:, i]) * cross, n) / 6.0
    if mom is None:
        return vol, None
    with np.errstate(divide="ignore", invalid="ignore"):
        centroids = ref + mom / vol[:, None]
    centroids[vol == 0] = np.nan
    return vol, centroids


def block_volumes(blocks: Blocks) -> np.ndarray:
    """Signed block volumes (areas in 2D), shape=(num_blocks,).

    2D: the shoelace formula over the ring (positive for a counter-clockwise ring). 3D: the
    divergence theorem, each quadrilateral split into the triangles (a, b, c), (a, c, d);
    exact for planar faces, positive for outward faces.
    """
    return _integrate(blocks, moments=False)[0]


def block_centroids(blocks: Blocks) -> np.ndarray:
    """Exact centroids of the polygons / polyhedra (planar faces), shape=(num_blocks, dim).

    A block of zero volume gets NaN.
    """
    centroids = _integrate(blocks, moments=True)[1]
    assert centroids is not None  # asked for
    return centroids


def piece_volumes(blocks: Blocks) -> np.ndarray:
    """Signed volumes (areas in 2D) of the convex pieces, shape=(num_pieces,).

    Positive for counter-clockwise quadrilaterals (2D) and VTK-ordered hexahedra (3D).
    """
    x = np.asarray(blocks.points, dtype=float)
    pieces = np.asarray(blocks.pieces, dtype=np.int64)
    out = np.empty(len(pieces))
    for s in _chunks(len(pieces), _CHUNK // 8):
        p = x[pieces[s]]
        p = p - p.mean(axis=1, keepdims=True)
        if blocks.dim == 2:
            q = np.roll(p, -1, axis=1)
            out[s] = 0.5 * np.sum(p[..., 0] * q[..., 1] - q[..., 0] * p[..., 1], axis=1)
        else:
            quads = p[:, HEX_FACES]  # shape=(m, 6, 4, 3)
            six_vol = _quad_six_volumes(quads.reshape(-1, 4, 3))
            out[s] = six_vol.reshape(-1, 6).sum(axis=1) / 6.0
    return out


def _segments_cross(
    p1: np.ndarray, p2: np.ndarray, q1: np.ndarray, q2: np.ndarray, tol: np.ndarray
) -> np.ndarray:
    """Whether segments p1p2 and q1q2 touch or cross (2D), shape=(...,); tol in area units.

    The end points have shape=(..., 2).
    """

    def orient(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
        o = (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (
            c[..., 0] - a[..., 0]
        )
        return np.where(np.abs(o) <= tol, 0.0, np.sign(o))

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    boxes = np.all(
        (np.minimum(p1, p2) <= np.maximum(q1, q2)) & (np.minimum(q1, q2) <= np.maximum(p1, p2)),
        axis=-1,
    )
    return (d1 * d2 <= 0) & (d3 * d4 <= 0) & boxes


def _rings_simple(blocks: Blocks) -> np.ndarray:
    """2D: rings of >= 3 distinct points, no zero-length edge, no fold-back, no crossing."""
    n = blocks.num_blocks
    off = np.asarray(blocks.face_offsets, dtype=np.int64)
    sizes = np.diff(off)
    ring = np.asarray(blocks.faces, dtype=np.int64)[:, 0]
    owner = block_ranges(off)
    x = np.asarray(blocks.points, dtype=float)
    distinct = _count_unique_per_block(owner, ring, n)
    ok = (sizes >= 3) & (distinct == sizes)
    scale = np.ptp(x, axis=0).max() if len(x) else 1.0
    eps = 1e-12 * scale
    for size in np.unique(sizes[ok]):
        which = np.flatnonzero(ok & (sizes == size))
        idx = off[which, None] + np.arange(size)
        p = x[ring[idx]]  # shape=(m, size, 2)
        q = np.roll(p, -1, axis=1)
        e = q - p
        length = np.hypot(e[..., 0], e[..., 1])
        good = np.all(length > eps, axis=1)
        # adjacent edges must not fold back onto each other
        e_next = np.roll(e, -1, axis=1)
        cross = e[..., 0] * e_next[..., 1] - e[..., 1] * e_next[..., 0]
        dot = np.einsum("mki,mki->mk", e, e_next)
        tol_a = 1e-12 * length * np.roll(length, -1, axis=1)
        good &= ~np.any((np.abs(cross) <= tol_a) & (dot < 0), axis=1)
        i, j = np.triu_indices(size, k=2)
        keep = ~((i == 0) & (j == size - 1))
        i, j = i[keep], j[keep]
        if len(i):
            hit = _segments_cross(
                p[:, i], q[:, i], p[:, j], q[:, j], 1e-12 * scale * scale * np.ones(1)
            )
            good &= ~np.any(hit, axis=1)
        ok[which] = good
    return ok


def check_closed(blocks: Blocks) -> np.ndarray:
    """Whether each block's boundary is closed, consistently oriented and manifold.

    3D: every directed edge of the block's faces appears exactly once and its reverse
    exactly once, in the same block (a face flipped, missing or duplicated breaks this),
    and no face repeats a point. 2D: the ring is a simple closed ring of >= 3 distinct
    points (no repeated point, no zero-length edge, no edge folding back onto the previous
    one, no two edges touching or crossing); its orientation shows in the sign of
    ``block_volumes``.

    Returns:
        shape=(num_blocks,) bool.
    """
    if blocks.dim == 2:
        return _rings_simple(blocks)
    return _surface_topology(blocks)[0]


def _surface_topology(blocks: Blocks) -> tuple[np.ndarray, np.ndarray]:
    """3D: ``check_closed`` and ``euler_characteristic`` from one pass over the faces."""
    from geofrac.blocks.kernels import edge_groups

    num_points = max(int(np.asarray(blocks.points).shape[0]), 1)
    closed, e, v = edge_groups(blocks.faces, blocks.face_offsets, num_points)
    return closed, (v - e + np.diff(blocks.face_offsets)).astype(np.int64)


def euler_characteristic(blocks: Blocks) -> np.ndarray:
    """V - E + F of each block's boundary, shape=(num_blocks,) int.

    3D: distinct points, distinct (undirected) edges and faces of the block's surface;
    2 for a block bounded by one sphere-like surface. 2D: the ring as a polygon with one
    face, 1 for a simple ring.
    """
    if blocks.dim == 3:
        return _surface_topology(blocks)[1]
    n = blocks.num_blocks
    start, end, owner = _edges(blocks)
    num_points = int(np.asarray(blocks.points).shape[0])
    v = _count_unique_per_block(owner, start, n)
    e = _count_unique_per_block(
        owner, np.minimum(start, end) * num_points + np.maximum(start, end), n
    )
    return (v - e + (np.diff(blocks.face_offsets) > 0)).astype(np.int64)


def face_planarity(blocks: Blocks) -> np.ndarray:
    """Out-of-plane distortion of each face: largest distance from its plane / diameter.

    The plane of a quadrilateral (a, b, c, d) is the one through its centroid parallel to
    both diagonals; all four points are at the same distance h / 2 from it, where h is the
    distance between the diagonals' lines, and no plane has a smaller largest distance. The
    diameter is the largest distance between two of the points. 0 for a planar face. In 2D
    the faces are ring points and this is 0.

    Returns:
        shape=(num_faces,).
    """
    if blocks.dim == 2:
        return np.zeros(len(blocks.faces))
    from geofrac.blocks import kernels

    return kernels.face_planarity(blocks.points, blocks.faces)


def _box_boundary(points: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """Predicate: all points of a face lie on one plane of the points' bounding box."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    tol = 1e-9 * max(float(np.max(hi - lo)), 1e-300)

    def on_boundary(face_points: np.ndarray) -> np.ndarray:
        on_lo = np.all(np.abs(face_points - lo) <= tol, axis=1)
        on_hi = np.all(np.abs(face_points - hi) <= tol, axis=1)
        return np.any(on_lo | on_hi, axis=1)

    return on_boundary


def _faces_and_owner(blocks: Blocks) -> tuple[np.ndarray, np.ndarray]:
    """The faces as point rows (2D: ring edges, shape=(n, 2)) and their blocks."""
    if blocks.dim == 3:
        return np.asarray(blocks.faces), block_ranges(blocks.face_offsets)
    start, end, owner = _edges(blocks)  # in the faces' integer type, as the kernels' warm-up
    return np.column_stack([start, end]).astype(np.asarray(blocks.faces).dtype), owner


def _pairing_status(
    blocks: Blocks, on_boundary: Callable[[np.ndarray], np.ndarray] | None
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Per face: a status code (see ``check_pairing``), the owner, and boundary closure.

    Faces are grouped by their point cycle in either direction
    (:func:`geofrac.blocks.kernels.face_status`): 3D faces as stored, 2D faces as the
    ring edges (start, end).
    """
    from geofrac.blocks.kernels import face_status

    faces, owner = _faces_and_owner(blocks)
    num_points = max(int(np.asarray(blocks.points).shape[0]), 1)
    status = face_status(faces, owner, num_points)
    single = np.flatnonzero(status == 1)
    if len(single):
        if on_boundary is None:
            on_boundary = _box_boundary(np.asarray(blocks.points, dtype=float))
        pts = np.asarray(blocks.points, dtype=float)[faces[single]]
        status[single[~np.asarray(on_boundary(pts), dtype=bool)]] = 2
    return status, owner, _singles_closed(blocks, faces[(status == 1) | (status == 2)])


def _singles_closed(blocks: Blocks, faces: np.ndarray) -> bool:
    """Whether the unpaired ``faces`` shape=(n, k) form a closed, oriented chain."""
    if blocks.dim == 2:
        return _chain_closed(blocks, faces[:, 0], faces[:, 1])
    faces = faces.astype(np.int64)
    k = faces.shape[1]
    return _chain_closed(blocks, faces.ravel(), faces[:, np.r_[1:k, 0]].ravel())


def _chain_closed(blocks: Blocks, start: np.ndarray, end: np.ndarray) -> bool:
    """2D: in-degree = out-degree at every point; 3D: every directed edge has its reverse."""
    if blocks.dim == 2:
        num = int(np.asarray(blocks.points).shape[0])
        return bool(
            np.array_equal(np.bincount(start, minlength=num), np.bincount(end, minlength=num))
        )
    num_points = max(int(np.asarray(blocks.points).shape[0]), 1)
    edge = np.minimum(start, end) * num_points + np.maximum(start, end)
    fwd = start < end
    order = np.argsort(edge, kind="stable")
    new = _group_starts(edge[order])
    first = np.flatnonzero(new)
    if not len(first):
        return True
    n_fwd = np.add.reduceat(fwd[order].astype(np.int64), first)
    n_all = np.diff(np.append(first, len(order)))
    return bool(np.all(2 * n_fwd == n_all))


def check_pairing(
    blocks: Blocks, on_boundary: Callable[[np.ndarray], np.ndarray] | None = None
) -> dict:
    """Whether the faces match across blocks.

    Each face (a ring edge in 2D, a quadrilateral in 3D) must either appear, reversed, in
    exactly one other block, or lie on the domain boundary. Why this (with the volumes)
    rules out overlaps and gaps: let w_b(x) be the winding number of block b's oriented
    boundary around x (1 inside, 0 outside for a closed, non-self-intersecting block).
    When every interior face is stored twice with opposite orientations, those faces cancel
    in the sum of all block boundaries, which is then the oriented domain boundary, so
    sum_b w_b(x) = 1 at every x inside the domain. With every block closed and simple
    (``check_closed``, ``validate_cells``: no intersecting faces), each w_b is 0 or 1, so
    every point of the domain lies in exactly one block: no overlap, no gap. The sum of
    the signed block volumes is the integral of sum_b w_b, so it equals the domain volume
    exactly when the unmatched faces are precisely the domain boundary; a mismatch means
    missing boundary faces or a boundary that encloses more (or less) than the domain.

    Args:
        blocks: the block set.
        on_boundary: predicate on face points shape=(n, k, dim) (k = 2 in 2D, 4 in 3D)
            returning shape=(n,) bool: True for faces on the domain boundary. Default: the
            face lies on one plane of the bounding box of all points (box domains). For
            other domains pass e.g. ``lambda p: np.ones(len(p), bool)`` and read
            ``boundary_closed`` and the volume sum instead.

    Returns:
        Counts of faces: ``faces``, ``matched`` (reversed partner in another block),
        ``boundary``, ``unmatched_interior`` (no partner, not on the boundary),
        ``same_orientation`` (the partner has the same orientation: a flipped face or two
        overlapping blocks), ``same_block`` (both copies in one block), ``more_than_two``
        (faces whose point set appears more than twice); ``bad_blocks`` (blocks with a
        face in the last four classes), ``boundary_closed`` (the faces without a partner
        form a closed, consistently oriented surface / set of rings, as the boundary of a
        union of blocks must) and ``ok`` (no bad face and the boundary closed).
    """
    status, owner, closed = _pairing_status(blocks, on_boundary)
    counts = np.bincount(status, minlength=6)
    bad = np.unique(owner[status >= 2])
    return {
        "faces": len(status),
        "matched": int(counts[0]),
        "boundary": int(counts[1]),
        "unmatched_interior": int(counts[2]),
        "same_orientation": int(counts[3]),
        "same_block": int(counts[4]),
        "more_than_two": int(counts[5]),
        "bad_blocks": len(bad),
        "boundary_closed": closed,
        "ok": bool(len(bad) == 0 and closed),
    }


def _piece_boxes(blocks: Blocks) -> tuple[np.ndarray, np.ndarray]:
    """Bounding boxes of the pieces, lo and hi each shape=(num_pieces, dim)."""
    x = np.asarray(blocks.points, dtype=float)
    pieces = np.asarray(blocks.pieces, dtype=np.int64)
    lo = np.empty((len(pieces), blocks.dim))
    hi = np.empty_like(lo)
    for s in _chunks(len(pieces), _CHUNK // 2):
        p = x[pieces[s]]
        lo[s], hi[s] = p.min(axis=1), p.max(axis=1)
    return lo, hi


def _candidate_pairs(
    lo: np.ndarray, hi: np.ndarray, samples: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(sample, piece) pairs whose piece box contains the sample.

    A loose hierarchical grid: a piece of extent e goes to level L = ceil(log2(e / h0))
    (h0 the median extent), into the cell (size h0 2^L) of its box's lower corner; a sample
    looks in its own cell and the 2^dim - 1 cells below it on each level.
    """
    dim = lo.shape[1]
    extent = (hi - lo).max(axis=1)
    h0 = float(np.median(extent)) if len(extent) else 1.0
    h0 = h0 if h0 > 0 else 1.0
    level = np.maximum(np.ceil(np.log2(np.maximum(extent, h0) / h0)), 0).astype(np.int64)
    origin = np.minimum(lo.min(axis=0), samples.min(axis=0)) - h0
    top = np.maximum(hi.max(axis=0), samples.max(axis=0)) + h0
    shifts = np.array(np.meshgrid(*[[0, -1]] * dim, indexing="ij")).reshape(dim, -1).T
    out_s, out_p = [], []
    for lev in np.unique(level):
        which = np.flatnonzero(level == lev)
        h = h0 * 2.0**lev
        shape = np.floor((top - origin) / h).astype(np.int64) + 2
        cell = np.floor((lo[which] - origin) / h).astype(np.int64)
        key = np.ravel_multi_index(cell.T, shape)
        order = np.argsort(key, kind="stable")
        key, which = key[order], which[order]
        base = np.floor((samples - origin) / h).astype(np.int64)
        for shift in shifts:
            c = base + shift
            inside = np.all((c >= 0) & (c < shape), axis=1)
            sid = np.flatnonzero(inside)
            k = np.ravel_multi_index(c[inside].T, shape)
            a, b = np.searchsorted(key, k, "left"), np.searchsorted(key, k, "right")
            count = b - a
            rep_s = np.repeat(sid, count)
            pos = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
            rep_p = which[np.repeat(a, count) + pos]
            hit = np.all((samples[rep_s] >= lo[rep_p]) & (samples[rep_s] <= hi[rep_p]), axis=1)
            out_s.append(rep_s[hit])
            out_p.append(rep_p[hit])
    if not out_s:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(out_s), np.concatenate(out_p)


def overlap_samples(blocks: Blocks, points: np.ndarray) -> np.ndarray:
    """How many blocks contain each sample point, shape=(n,) int.

    A block contains a point when one of its convex pieces does: the point is on the inner
    side of (or on) every edge (2D, counter-clockwise quadrilaterals) or every face plane
    (3D, VTK hexahedra; the plane through a face's centroid normal to its diagonals'
    cross product). Pieces are first filtered by their bounding boxes on a hierarchical
    grid, so a few thousand samples on 10^5 blocks cost about as much as reading the
    pieces. A point inside the domain must give exactly 1 (0: a gap, 2: an overlap);
    points exactly on a block face count in both blocks.

    Args:
        blocks: the block set.
        points: sample points, shape=(n, dim).
    """
    samples = np.asarray(points, dtype=float).reshape(-1, blocks.dim)
    count = np.zeros(len(samples), dtype=np.int64)
    if not len(samples) or not len(blocks.pieces):
        return count
    lo, hi = _piece_boxes(blocks)
    s_idx, p_idx = _candidate_pairs(lo, hi, samples)
    x = np.asarray(blocks.points, dtype=float)
    pieces = np.asarray(blocks.pieces, dtype=np.int64)
    inside = np.empty(len(s_idx), dtype=bool)
    for s in _chunks(len(s_idx), _CHUNK // 8):
        p = x[pieces[p_idx[s]]]
        y = samples[s_idx[s]]
        if blocks.dim == 2:
            e = np.roll(p, -1, axis=1) - p
            r = y[:, None, :] - p
            cross = e[..., 0] * r[..., 1] - e[..., 1] * r[..., 0]
            inside[s] = np.all(cross >= 0, axis=1)
        else:
            q = p[:, HEX_FACES]  # shape=(m, 6, 4, 3)
            normal = np.cross(q[:, :, 2] - q[:, :, 0], q[:, :, 3] - q[:, :, 1])
            r = y[:, None, :] - q.mean(axis=2)
            inside[s] = np.all(np.einsum("mfi,mfi->mf", r, normal) <= 0, axis=1)
    s_in = s_idx[inside]
    b_in = np.asarray(blocks.piece_block, dtype=np.int64)[p_idx[inside]]
    pairs = np.unique(np.column_stack([s_in, b_in]), axis=0) if len(s_in) else np.zeros((0, 2))
    return np.bincount(pairs[:, 0].astype(np.int64), minlength=len(samples))


def _vtk_grid(blocks: Blocks, which: np.ndarray) -> Any:
    """The blocks ``which`` shape=(m,) as a pyvista UnstructuredGrid of m polyhedra / polygons.

    Every cell gets its own copies of its points, centred on the cell's bounding box:
    vtkCellValidator triangulates faces into float32 points, and far from the origin that
    rounding breaks the coplanarity of neighbouring faces and makes it report
    intersecting faces that do not intersect.
    """
    import pyvista as pv
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonCore import VTK_ID_TYPE, VTK_UNSIGNED_CHAR
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkUnstructuredGrid

    def vtk_ids(values: np.ndarray) -> Any:
        return numpy_to_vtk(
            np.ascontiguousarray(values, np.int64), deep=True, array_type=VTK_ID_TYPE
        )

    def cell_array(offsets: np.ndarray, conn: np.ndarray) -> vtkCellArray:
        arr = vtkCellArray()
        arr.SetData(vtk_ids(offsets), vtk_ids(conn))
        return arr

    off = np.asarray(blocks.face_offsets, dtype=np.int64)
    counts = np.diff(off)[which]
    faces = np.asarray(blocks.faces, dtype=np.int64)[_positions(off[which], counts)]
    k = faces.shape[1]
    owner = np.repeat(np.arange(len(which)), counts * k)
    pt_off, pt_ids = _unique_per_owner(owner, faces.ravel(), len(which))
    num_points = max(int(np.asarray(blocks.points).shape[0]), 1)
    key = np.repeat(np.arange(len(which)), np.diff(pt_off)) * num_points + pt_ids
    local = np.searchsorted(key, owner * num_points + faces.ravel())  # this cell's copy
    x = np.zeros((len(pt_ids), 3))
    x[:, : blocks.dim] = np.asarray(blocks.points, dtype=float)[pt_ids]
    full = np.diff(pt_off) > 0
    starts = pt_off[:-1][full]
    centre = np.zeros((len(which), 3))
    if len(starts):
        lo, hi = np.minimum.reduceat(x, starts), np.maximum.reduceat(x, starts)
        centre[full] = (lo + hi) / 2
    x -= np.repeat(centre, np.diff(pt_off), axis=0)
    cell_offsets = np.concatenate([[0], np.cumsum(counts)])
    grid = vtkUnstructuredGrid()
    grid.SetPoints(pv.vtk_points(x, deep=True))
    if blocks.dim == 2:
        types = np.full(len(which), pv.CellType.POLYGON, dtype=np.uint8)
        grid.SetCells(
            numpy_to_vtk(types, deep=True, array_type=VTK_UNSIGNED_CHAR),
            cell_array(cell_offsets, local),
        )
        return pv.wrap(grid)
    types = np.full(len(which), pv.CellType.POLYHEDRON, dtype=np.uint8)
    grid.SetPolyhedralCells(
        numpy_to_vtk(types, deep=True, array_type=VTK_UNSIGNED_CHAR),
        cell_array(pt_off, np.arange(len(pt_ids))),
        cell_array(cell_offsets, np.arange(len(faces))),
        cell_array(np.arange(len(faces) + 1) * k, local),
    )
    return pv.wrap(grid)


def _positions(start: np.ndarray, count: np.ndarray) -> np.ndarray:
    """start[i] + 0 .. count[i] - 1 for every i, concatenated, shape=(count.sum(),)."""
    return np.repeat(start - (np.cumsum(count) - count), count) + np.arange(int(count.sum()))


def _validator_states(blocks: Blocks, which: np.ndarray, planarity_tolerance: float) -> np.ndarray:
    """The pyvista ``validity_state`` bit fields of the blocks ``which``, shape=(len(which),)."""
    grid = _vtk_grid(blocks, which)
    if grid.n_cells == 0:
        return np.zeros(0, dtype=np.int64)
    diag = float(np.linalg.norm(np.ptp(np.asarray(grid.points), axis=0)))
    tol = float(np.finfo(np.float32).eps) * max(diag, 1e-30)
    checked = grid.cell_validator(
        tolerance=tol,
        planarity_tolerance=planarity_tolerance,
        size_tolerance=float(np.finfo(float).eps) * max(diag, 1e-30) ** blocks.dim,
    )
    return np.asarray(checked.cell_data["validity_state"], dtype=np.int64)


def _failure_mask() -> int:
    import pyvista as pv

    mask = 0
    for name in VALIDATOR_FAILURES:
        mask |= int(pv.CellStatus[name].value)
    return mask


def validate_cells(
    blocks: Blocks,
    sample: int | None = None,
    seed: int = 0,
    *,
    planarity_tolerance: float = 0.1,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """VTK's cell validator on the blocks as ``VTK_POLYHEDRON`` (3D) / ``VTK_POLYGON`` cells.

    ``pyvista.DataSet.cell_validator`` runs ``vtkCellValidator`` and pyvista's own checks
    and returns the mesh with a cell array ``validity_state``: a bit field of
    ``pyvista.CellStatus`` values (0 valid; WRONG_NUMBER_OF_POINTS 0x1, INTERSECTING_EDGES
    0x2, INTERSECTING_FACES 0x4, NON_CONTIGUOUS_EDGES 0x8, NON_CONVEX 0x10, INVERTED_FACES
    0x20, NON_PLANAR_FACES 0x40, DEGENERATE_FACES 0x80, COINCIDENT_POINTS 0x100,
    INVALID_POINT_REFERENCES 0x10000, ZERO_SIZE 0x20000, NEGATIVE_SIZE 0x100000), plus a
    field array of cell ids per status. Blocks are generally not convex, so NON_CONVEX is
    counted but is not a failure; every other bit is (``VALIDATOR_FAILURES``), except
    INVERTED_FACES on a non-convex cell: VTK tests that each face normal points away from
    the centroid of the cell's points, which a correctly oriented non-convex block can
    fail. Those cells are counted (``inverted_faces_non_convex``); their orientation is
    checked exactly by :func:`check_closed` and a positive :func:`block_volumes`.

    Each cell gets its own copy of its points, centred on its bounding box (VTK
    triangulates faces in float32, and far from the origin the rounding makes touching
    faces look intersecting); the tolerances scale with the largest cell diagonal d:
    coincidence/intersection float32 eps x d, size float64 eps x d^dim. pyvista's
    ZERO_SIZE / NEGATIVE_SIZE use VTK's cell size, which for a non-convex polyhedron is
    its convex hull's volume (never negative): ``block_volumes`` is the exact check. VTK
    9.7 reports NON_PLANAR_FACES only for convex polyhedra (a non-convex one gets just
    NON_CONVEX): ``face_planarity`` is the check for the blocks.

    Cost (VTK 9.7, pyvista 0.49, one shared core): 6.5 s per 1000 polyhedra of 64 faces
    on average, 7.6 s per 1000 of 72 faces (the face-intersection test is quadratic in
    the faces); 10^5 blocks take ~12 min, so ``sample`` a few thousand of large sets.

    Args:
        blocks: the block set.
        sample: check only this many blocks, drawn without replacement with ``seed``
            (None: all).
        seed: random seed of the sample.
        planarity_tolerance: VTK's allowed face distance from its plane relative to the
            largest face-centre-to-corner distance (polyhedra only).
        progress: called as ``progress(chunks_done, chunks)`` before the first and after
            each chunk of :data:`VALIDATOR_CHUNK` blocks, or None.

    Returns:
        ``blocks`` (total), ``checked``, ``large_exact`` (blocks of more than
        :data:`LARGE_BLOCK_FACES` faces, checked by :func:`self_intersections` instead of
        VTK; with :func:`check_closed`, :func:`face_planarity` and a positive volume in
        :func:`summarize`), ``passed`` and ``failed`` (any failure bit; ``checked`` =
        ``passed`` + ``failed``), ``no_flags`` (VTK set no bit at all, not even the
        informational NON_CONVEX: most blocks pass with NON_CONVEX set), ``non_convex``,
        ``states`` (name -> count of checked cells with that bit, for every
        ``pyvista.CellStatus`` but VALID), ``failed_blocks`` (indices of up to 20 failed
        blocks), ``seconds``.
    """
    report, failed = _validate(blocks, sample, seed, planarity_tolerance, progress)
    report["failed_blocks"] = [int(b) for b in failed[:20]]
    return report


def _validate(
    blocks: Blocks,
    sample: int | None,
    seed: int,
    planarity_tolerance: float,
    progress: Callable[[int, int], None] | None = None,
    chunk: int | None = None,
) -> tuple[dict, np.ndarray]:
    """``validate_cells`` without the block list, and all failed block indices."""
    import pyvista as pv

    t0 = time.perf_counter()
    n = blocks.num_blocks
    if sample is not None and sample < n:
        which = np.sort(np.random.default_rng(seed).choice(n, size=sample, replace=False))
    else:
        which = np.arange(n)
    # VTK's face-intersection test is quadratic in a cell's faces: a block of many faces
    # (the immobile part: tens of thousands) would take hours, so such blocks get the
    # exact test alone (self_intersections, sweep and prune) instead of VTK's
    sizes = np.diff(np.asarray(blocks.face_offsets))[which]
    large = which[sizes > LARGE_BLOCK_FACES] if blocks.dim == 3 else which[:0]
    large_failed = np.array(
        [b for b in large.tolist() if self_intersections(blocks, b) > 0], dtype=np.int64
    )
    which = which[~np.isin(which, large)]
    chunk = chunk or VALIDATOR_CHUNK
    chunks = [which[i : i + chunk] for i in range(0, len(which), chunk)] or [which]
    states_list = []
    if progress is not None:
        progress(0, len(chunks))
    for done, part in enumerate(chunks, 1):
        states_list.append(_validator_states(blocks, part, planarity_tolerance))
        if progress is not None:
            progress(done, len(chunks))
    state = np.concatenate(states_list)
    inverted = int(pv.CellStatus.INVERTED_FACES.value)
    others = _failure_mask() & ~inverted
    convex = (state & int(pv.CellStatus.NON_CONVEX.value)) == 0
    # VTK's INVERTED_FACES asks every face normal to point away from the cell's point
    # centroid (vtkCellValidator::FacesAreOrientedCorrectly): right for convex cells,
    # wrong for many non-convex ones. There the exact test is check_closed (consistent
    # orientation) with a positive block volume (outward), which summarize applies.
    failed = ((state & others) != 0) | (((state & inverted) != 0) & convex)
    # VTK tests face intersections on faces triangulated in float32, which flags faces
    # that only come close on large blocks (the immobile part, ~1 km across); such a
    # block is re-tested exactly (float64 segment-triangle test) and cleared if it passes
    crossing = int(pv.CellStatus.INTERSECTING_FACES.value)
    recheck = failed & ((state & (others & ~crossing)) == 0) & ((state & crossing) != 0)
    cleared = 0
    for i in np.flatnonzero(recheck):
        if blocks.dim == 3 and self_intersections(blocks, int(which[i])) == 0:
            failed[i] = False
            cleared += 1
    states = {
        s.name: int(np.count_nonzero(state & int(s.value)))
        for s in pv.CellStatus
        if s != pv.CellStatus.VALID
    }
    report = {
        "blocks": n,
        "checked": len(which) + len(large),
        "large_exact": len(large),
        "passed": len(which) + len(large) - int(np.count_nonzero(failed)) - len(large_failed),
        "failed": int(np.count_nonzero(failed)) + len(large_failed),
        "no_flags": int(np.count_nonzero(state == 0)),
        "non_convex": states["NON_CONVEX"],
        "inverted_faces_non_convex": int(np.count_nonzero(((state & inverted) != 0) & ~convex)),
        "intersecting_faces_cleared": cleared,
        "states": states,
        "seconds": time.perf_counter() - t0,
    }
    return report, np.concatenate([which[failed], large_failed])


def self_intersections(blocks: Blocks, b: int, chunk: int = 1 << 20) -> int:
    """Exact count of a 3D block's face edges that cross one of its faces elsewhere.

    The quads are split into triangles. Pairs of triangles that share no point and whose
    bounding boxes overlap (sweep and prune, :func:`geofrac.blocks.kernels.overlapping_pairs`)
    are tested edge against triangle (Möller-Trumbore, float64), both ways; touching counts.
    A closed block whose faces neither cross nor touch away from shared points has none.
    An edge lying in a triangle's plane is not tested (coplanar overlaps of faces that
    share no point are not detected).

    Args:
        blocks: the block set (3D).
        b: the block.
        chunk: triangle pairs tested at a time.
    """
    from geofrac.blocks.kernels import overlapping_pairs

    quads = np.asarray(blocks.faces[blocks.face_offsets[b] : blocks.face_offsets[b + 1]])
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]]).astype(np.int64)
    p = np.asarray(blocks.points, dtype=float)
    pairs = overlapping_pairs(p, tris)
    hits = 0
    for start in range(0, len(pairs), chunk):
        part = pairs[start : start + chunk]
        for first, second in ((0, 1), (1, 0)):
            edge_tri, t = tris[part[:, first]], tris[part[:, second]]
            for c in range(3):
                hits += _edge_crossings(p, edge_tri[:, c], edge_tri[:, (c + 1) % 3], t)
    return hits


def _edge_crossings(p: np.ndarray, e0: np.ndarray, e1: np.ndarray, t: np.ndarray) -> int:
    """How many segments p[e0] p[e1] meet the (closed) triangles p[t]."""
    o, d = p[e0], p[e1] - p[e0]
    a = p[t[:, 0]]
    u1, u2 = p[t[:, 1]] - a, p[t[:, 2]] - a
    h = np.cross(d, u2)
    det = np.einsum("ij,ij->i", u1, h)
    scale = np.linalg.norm(d, axis=1) * np.linalg.norm(u1, axis=1) * np.linalg.norm(u2, axis=1)
    ok = np.abs(det) > 1e-12 * scale  # an edge parallel to the triangle cannot cross it
    inv = 1.0 / np.where(ok, det, 1.0)
    s = o - a
    u = inv * np.einsum("ij,ij->i", s, h)
    q = np.cross(s, u1)
    v = inv * np.einsum("ij,ij->i", d, q)
    w = inv * np.einsum("ij,ij->i", u2, q)
    eps = 1e-12  # touching counts: faces that share no point must not meet at all
    hit = ok & (u >= -eps) & (v >= -eps) & (u + v <= 1 + eps) & (w >= -eps) & (w <= 1 + eps)
    return int(np.count_nonzero(hit))


def equivalent_diameters(volumes: np.ndarray, dim: int) -> np.ndarray:
    """Diameter of the circle (2D) / sphere (3D) of the same area / volume, shape=(n,)."""
    v = np.maximum(np.asarray(volumes, dtype=float), 0.0)
    return np.sqrt(4.0 * v / np.pi) if dim == 2 else np.cbrt(6.0 * v / np.pi)


def _circum_diameters(blocks: Blocks, centroids: np.ndarray) -> np.ndarray:
    """Twice the largest distance from each centroid to the block's points, shape=(n,)."""
    from geofrac.blocks.kernels import reach

    return 2.0 * reach(blocks.points, blocks.faces, blocks.face_offsets, centres=centroids)


def _stats(values: np.ndarray) -> dict:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if not len(v):
        return {"min": None, "mean": None, "max": None}
    return {"min": float(v.min()), "mean": float(v.mean()), "max": float(v.max())}


#: The checks of :func:`block_checks`, in the order they report progress.
BLOCK_CHECKS = ("volumes", "aspect ratios", "closure and Euler", "planarity")

#: The checks of :func:`summarize` that report progress, in order.
SUMMARY_PHASES = (*BLOCK_CHECKS, "pairing")


def block_checks(
    blocks: Blocks, progress: Callable[[str], None] | None = None
) -> dict[str, np.ndarray]:
    """The checks that look at each block alone, each shape=(num_blocks,).

    They need no other block, so ranks can check their own blocks: the results of
    several block sets, concatenated, are those of the sets joined in that order
    (:func:`geofrac.blocks.model.join`, which ``gather_blocks`` uses).

    Aspect ratio: twice the largest distance from the block's centroid to its points,
    divided by its equivalent diameter (``equivalent_diameters``); 1 for a disc / ball,
    1.25 for a square, 1.40 for a cube, larger for elongated or flat blocks.

    Args:
        blocks: the block set.
        progress: called with what was just checked after each of the
            :data:`BLOCK_CHECKS`, or None.

    Returns:
        ``volume`` (signed, ``block_volumes``), ``aspect_ratio``, ``closed``
        (``check_closed``), ``euler`` (``euler_characteristic``) and ``planarity`` (the
        largest ``face_planarity`` of the block's faces; 0 without faces).
    """
    say = progress or (lambda what: None)
    vol, centroids = _integrate(blocks, moments=True)
    assert centroids is not None  # asked for
    say("volumes and centroids")
    with np.errstate(divide="ignore", invalid="ignore"):
        aspect = _circum_diameters(blocks, np.nan_to_num(centroids)) / equivalent_diameters(
            vol, blocks.dim
        )
    say("aspect ratios")
    if blocks.dim == 3:
        closed, euler = _surface_topology(blocks)
    else:
        closed, euler = check_closed(blocks), euler_characteristic(blocks)
    wrong = np.count_nonzero(euler != (2 if blocks.dim == 3 else 1))
    say(f"closure: {np.count_nonzero(~closed)} not closed, Euler characteristic: {wrong} wrong")
    faces = face_planarity(blocks)
    planarity = np.zeros(blocks.num_blocks)
    off = np.asarray(blocks.face_offsets)
    full = off[1:] > off[:-1]
    if full.any():
        planarity[full] = np.maximum.reduceat(faces, off[:-1][full])
    say(f"face planarity: largest {planarity.max(initial=0.0):.2g}")
    return {
        "volume": vol,
        "aspect_ratio": aspect,
        "closed": closed,
        "euler": euler,
        "planarity": planarity,
    }


def summarize(
    blocks: Blocks,
    domain_volume: float,
    *,
    validate: bool = True,
    sample: int | None = 2000,
    on_boundary: Callable[[np.ndarray], np.ndarray] | None = None,
    planarity_tolerance: float = 1e-6,
    stats_of: np.ndarray | slice = slice(None),
    progress: Callable[[str], None] | None = None,
    checked: dict[str, np.ndarray] | None = None,
) -> dict:
    """A JSON-ready quality report of a block set.

    Args:
        blocks: the block set.
        domain_volume: volume (area in 2D) of the domain the blocks tile.
        validate: run ``validate_cells``.
        sample: number of blocks (seeded draw) for the validator, ~7 s per 1000 blocks
            in 3D (None: all).
        on_boundary: passed to ``check_pairing``.
        planarity_tolerance: a block with a face whose ``face_planarity`` exceeds this
            is invalid.
        stats_of: the blocks the statistics (volume, equivalent diameter, aspect ratio)
            describe, a mask or index (default all; e.g. the moving layer only). The
            checks always cover every block.
        progress: called with what was just checked after each of the
            :data:`SUMMARY_PHASES` checks (those of ``block_checks`` only when it runs
            here), or None.
        checked: ``block_checks`` of these blocks when already computed (e.g. by the
            ranks, each on its own blocks), or None to compute them here.

    Returns:
        ``count``, ``dim``, ``total_volume``, ``volume_rel_error`` ((total - domain) /
        domain), ``volume`` / ``equivalent_diameter`` / ``aspect_ratio`` (each min, mean,
        max), ``not_closed``, ``wrong_euler`` (3D: != 2; 2D: != 1), ``non_positive_volume``,
        ``non_planar`` (blocks with a face beyond ``planarity_tolerance``),
        ``max_face_planarity``, ``validator`` (``validate_cells`` report without the block
        list, or None), ``invalid_blocks`` (blocks failing any of these five checks;
        validator failures counted among the checked blocks), ``pairing``
        (``check_pairing``).

    Raises:
        ValueError: ``checked`` does not have one value per block.
    """
    say = progress or (lambda what: None)
    if checked is None:
        checked = block_checks(blocks, progress)
    wrong_length = [k for k, v in checked.items() if len(v) != blocks.num_blocks]
    if wrong_length:
        raise ValueError(f"checked {wrong_length}: not one value per block")
    vol, closed, planarity = checked["volume"], checked["closed"], checked["planarity"]
    total = float(vol.sum())
    d_eq = equivalent_diameters(vol, blocks.dim)
    wrong_euler = checked["euler"] != (2 if blocks.dim == 3 else 1)
    non_planar = planarity > planarity_tolerance
    invalid = ~closed | wrong_euler | (vol <= 0) | non_planar
    report = None
    if validate and blocks.num_blocks:
        report, failed = _validate(blocks, sample, 0, 0.1)
        invalid[failed] = True
    pairing = check_pairing(blocks, on_boundary)
    say(f"face pairing: {'ok' if pairing['ok'] else 'FAILED'}")
    return {
        "count": blocks.num_blocks,
        "dim": blocks.dim,
        "total_volume": total,
        "domain_volume": float(domain_volume),
        "volume_rel_error": (total - domain_volume) / domain_volume,
        "volume": _stats(vol[stats_of]),
        "equivalent_diameter": _stats(d_eq[stats_of]),
        "aspect_ratio": _stats(checked["aspect_ratio"][stats_of]),
        "statistics_of": int(np.ones(len(vol), bool)[stats_of].sum()),
        "not_closed": int(np.count_nonzero(~closed)),
        "wrong_euler": int(np.count_nonzero(wrong_euler)),
        "non_positive_volume": int(np.count_nonzero(vol <= 0)),
        "non_planar": int(np.count_nonzero(non_planar)),
        "max_face_planarity": float(planarity.max(initial=0.0)),
        "validator": report,
        "invalid_blocks": int(np.count_nonzero(invalid)),
        "pairing": pairing,
    }
