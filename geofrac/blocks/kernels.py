"""Compiled (numba) loops of the block checks and writers, imported only when needed.

Each loop visits one block (or face) at a time with small local arrays, where the numpy
versions sort all 10^7 face corners of a large set together. Compiled on first use and
cached on disk (``cache=True``); :func:`warm_up` compiles (or loads) them all, so that a
caller can time that apart from the work.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numba
import numpy as np

from geofrac.blocks.model import HEX_FACES

__all__ = [
    "block_integrals",
    "edge_groups",
    "face_planarity",
    "face_status",
    "face_stream",
    "overlapping_pairs",
    "reach",
    "unique_segments",
    "warm_up",
]


def _index_array(values: np.ndarray) -> np.ndarray:
    """Indices as a contiguous int32 or int64 array, copied only when it must be.

    The kernels are compiled for both widths; the block builders store int32.
    """
    v = np.asarray(values)
    if v.dtype not in (np.int32, np.int64):
        v = v.astype(np.int64)
    return np.ascontiguousarray(v)


def _require_quads(faces: np.ndarray) -> None:
    shape = np.shape(faces)
    if len(shape) != 2 or shape[1] != 4:
        raise ValueError(f"faces must be quadrilaterals, shape=(n, 4), not {shape}")


#: Faces sharing a smallest point are sorted by insertion up to this many, else merge sort.
_SMALL_BUCKET = 32


@numba.njit(cache=True)
def _pairs(lo: np.ndarray, hi: np.ndarray, tri: np.ndarray, order: np.ndarray) -> np.ndarray:
    out = np.empty((max(16, 4 * len(order)), 2), dtype=np.int64)
    n = 0
    for a in range(len(order)):
        i = order[a]
        for b in range(a + 1, len(order)):
            j = order[b]
            if lo[j, 0] > hi[i, 0]:
                break
            if lo[j, 1] > hi[i, 1] or hi[j, 1] < lo[i, 1]:
                continue
            if lo[j, 2] > hi[i, 2] or hi[j, 2] < lo[i, 2]:
                continue
            shared = False
            for s in range(3):
                for t in range(3):
                    if tri[i, s] == tri[j, t]:
                        shared = True
            if shared:
                continue
            if n == out.shape[0]:
                grown = np.empty((2 * n, 2), dtype=np.int64)
                grown[:n] = out
                out = grown
            out[n, 0] = i
            out[n, 1] = j
            n += 1
    return out[:n]


def overlapping_pairs(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Pairs of triangles that share no point and whose bounding boxes overlap.

    Sweep and prune along x.

    Args:
        points: coordinates, shape=(num_points, 3).
        tri: point indices, shape=(num_triangles, 3).

    Returns:
        shape=(num_pairs, 2), each pair once.
    """
    corners = points[tri]
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    order = np.argsort(lo[:, 0], kind="stable")
    return _pairs(lo, hi, np.ascontiguousarray(tri, dtype=np.int64), order)


@numba.njit(cache=True)
def _unique_segments(values: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    num = len(offsets) - 1
    out = np.empty(len(values), dtype=np.int64)
    out_offsets = np.zeros(num + 1, dtype=np.int64)
    # seen[v] = the last segment in which v was met: distinct values without sorting all
    seen = np.full(values.max() + 1 if len(values) else 0, -1, dtype=np.int64)
    n = 0
    for b in range(num):
        for i in range(offsets[b], offsets[b + 1]):
            if seen[values[i]] != b:
                seen[values[i]] = b
                out[n] = values[i]
                n += 1
        out[out_offsets[b] : n].sort()
        out_offsets[b + 1] = n
    return out_offsets, out[:n].copy()


def unique_segments(values: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct values of each segment ``values[offsets[b]:offsets[b + 1]]``, sorted.

    Args:
        values: integers, shape=(offsets[-1],).
        offsets: segment starts, shape=(num_segments + 1,).

    Returns:
        ``(offsets, values)`` of the distinct values (CSR): shape=(num_segments + 1,) and
        shape=(new_offsets[-1],), int64.
    """
    return _unique_segments(_index_array(values), np.asarray(offsets, dtype=np.int64))


@numba.njit(cache=True)
def _edge_groups(
    faces: np.ndarray, offsets: np.ndarray, num_points: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    num, k = len(offsets) - 1, faces.shape[1]
    closed = np.zeros(num, dtype=np.bool_)
    edges = np.zeros(num, dtype=np.int64)
    vertices = np.zeros(num, dtype=np.int64)
    # per block, the edges leaving each point towards higher indices, as linked lists
    # (head[p], then next[e]); stamps say which block last wrote a point's entries
    vertex_stamp = np.full(num_points, -1, dtype=np.int64)
    head_stamp = np.full(num_points, -1, dtype=np.int64)
    head = np.empty(num_points, dtype=np.int64)
    most = 0
    for b in range(num):
        most = max(most, (offsets[b + 1] - offsets[b]) * k)
    other = np.empty(most, dtype=np.int64)  # the edge's higher point
    nxt = np.empty(most, dtype=np.int64)
    used = np.empty(most, dtype=np.int64)  # how often the block uses the edge
    up = np.empty(most, dtype=np.int64)  # how often towards the higher point
    for b in range(num):
        f0, f1 = offsets[b], offsets[b + 1]
        ok = f1 > f0
        m = 0
        for f in range(f0, f1):
            for j in range(k):
                a = faces[f, j]
                c = faces[f, j + 1] if j + 1 < k else faces[f, 0]
                if vertex_stamp[a] != b:
                    vertex_stamp[a] = b
                    vertices[b] += 1
                if a == c:
                    ok = False
                lo, hi = min(a, c), max(a, c)
                if head_stamp[lo] != b:
                    head_stamp[lo] = b
                    head[lo] = -1
                e = head[lo]
                while e >= 0 and other[e] != hi:
                    e = nxt[e]
                if e < 0:
                    e = m
                    m += 1
                    other[e], used[e], up[e] = hi, 0, 0
                    nxt[e], head[lo] = head[lo], e
                used[e] += 1
                if a < c:
                    up[e] += 1
        for e in range(m):
            if used[e] != 2 or up[e] != 1:
                ok = False
        edges[b] = m
        closed[b] = ok
    return closed, edges, vertices


def edge_groups(
    faces: np.ndarray, offsets: np.ndarray, num_points: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closure, edge and vertex counts of each block bounded by polygonal faces (3D).

    Args:
        faces: point indices of the faces, counter-clockwise from outside,
            shape=(num_faces, k).
        offsets: each block's first face, shape=(num_blocks + 1,).
        num_points: more than the largest point index.

    Returns:
        ``closed`` shape=(num_blocks,) bool: the block has faces, none has an edge from a
        point to itself, and each undirected edge of its faces is used exactly twice, once
        in each direction. ``edges`` and ``vertices`` shape=(num_blocks,): distinct
        undirected edges and distinct points of the block's faces.
    """
    return _edge_groups(
        _index_array(faces),
        np.asarray(offsets, dtype=np.int64),
        int(num_points),
    )


@numba.njit(cache=True)
def _block_integrals(
    points: np.ndarray, faces: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    num, k = len(offsets) - 1, faces.shape[1]
    volume = np.zeros(num)
    centroid = np.full((num, 3), np.nan)
    q = np.zeros((4, 3))
    for b in range(num):
        f0, f1 = offsets[b], offsets[b + 1]
        r0 = r1 = r2 = 0.0
        for f in range(f0, f1):
            for j in range(k):
                r0 += points[faces[f, j], 0]
                r1 += points[faces[f, j], 1]
                r2 += points[faces[f, j], 2]
        count = max((f1 - f0) * k, 1)
        r0, r1, r2 = r0 / count, r1 / count, r2 / count
        six_volume = m0 = m1 = m2 = 0.0
        for f in range(f0, f1):
            for j in range(4):
                q[j, 0] = points[faces[f, j], 0] - r0
                q[j, 1] = points[faces[f, j], 1] - r1
                q[j, 2] = points[faces[f, j], 2] - r2
            # (0, a, b, c) and (0, a, c, d): 6 x volume = a . (b x c), a . (c x d)
            v1 = (
                q[0, 0] * (q[1, 1] * q[2, 2] - q[1, 2] * q[2, 1])
                + q[0, 1] * (q[1, 2] * q[2, 0] - q[1, 0] * q[2, 2])
                + q[0, 2] * (q[1, 0] * q[2, 1] - q[1, 1] * q[2, 0])
            )
            v2 = (
                q[0, 0] * (q[2, 1] * q[3, 2] - q[2, 2] * q[3, 1])
                + q[0, 1] * (q[2, 2] * q[3, 0] - q[2, 0] * q[3, 2])
                + q[0, 2] * (q[2, 0] * q[3, 1] - q[2, 1] * q[3, 0])
            )
            six_volume += v1 + v2
            m0 += v1 * (q[0, 0] + q[1, 0] + q[2, 0]) + v2 * (q[0, 0] + q[2, 0] + q[3, 0])
            m1 += v1 * (q[0, 1] + q[1, 1] + q[2, 1]) + v2 * (q[0, 1] + q[2, 1] + q[3, 1])
            m2 += v1 * (q[0, 2] + q[1, 2] + q[2, 2]) + v2 * (q[0, 2] + q[2, 2] + q[3, 2])
        volume[b] = six_volume / 6.0
        if volume[b] != 0.0:  # first moment / volume: (sum m / 24) / (sum v / 6)
            centroid[b, 0] = r0 + m0 / 24.0 / volume[b]
            centroid[b, 1] = r1 + m1 / 24.0 / volume[b]
            centroid[b, 2] = r2 + m2 / 24.0 / volume[b]
    return volume, centroid


def block_integrals(
    points: np.ndarray, faces: np.ndarray, offsets: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Signed volumes and centroids of polyhedra bounded by quadrilaterals.

    The divergence theorem over each quadrilateral (a, b, c, d) split into the triangles
    (a, b, c), (a, c, d), relative to the mean of the block's face points (no
    cancellation far from the origin): exact for planar faces, positive for outward faces.

    Args:
        points: shape=(num_points, 3).
        faces: shape=(num_faces, 4), counter-clockwise seen from outside.
        offsets: each block's first face, shape=(num_blocks + 1,).

    Returns:
        ``volume`` shape=(num_blocks,) and ``centroid`` shape=(num_blocks, 3) (NaN for a
        block of zero volume).
    """
    _require_quads(faces)
    return _block_integrals(
        np.ascontiguousarray(points, dtype=float),
        _index_array(faces),
        np.asarray(offsets, dtype=np.int64),
    )


@numba.njit(cache=True)
def _reach(
    points: np.ndarray, faces: np.ndarray, offsets: np.ndarray, centres: np.ndarray
) -> np.ndarray:
    num, k, dim = len(offsets) - 1, faces.shape[1], points.shape[1]
    out = np.zeros(num)
    for b in range(num):
        for f in range(offsets[b], offsets[b + 1]):
            for j in range(k):
                s = 0.0
                for i in range(dim):
                    s += (points[faces[f, j], i] - centres[b, i]) ** 2
                out[b] = max(out[b], np.sqrt(s))
    return out


def reach(
    points: np.ndarray, faces: np.ndarray, offsets: np.ndarray, *, centres: np.ndarray
) -> np.ndarray:
    """Largest distance from each block's centre to the points of its faces.

    Args:
        points: shape=(num_points, dim).
        faces: shape=(num_faces, k) (2D rings: k = 1).
        offsets: each block's first face, shape=(num_blocks + 1,).
        centres: shape=(num_blocks, dim).

    Returns:
        shape=(num_blocks,).
    """
    return _reach(
        np.ascontiguousarray(points, dtype=float),
        _index_array(faces),
        np.asarray(offsets, dtype=np.int64),
        np.ascontiguousarray(centres, dtype=float),
    )


@numba.njit(cache=True)
def _face_planarity(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    out = np.zeros(len(faces))
    q = np.zeros((4, 3))
    for f in range(len(faces)):
        for i in range(3):
            mean = 0.0
            for j in range(4):
                q[j, i] = points[faces[f, j], i]
                mean += q[j, i]
            for j in range(4):
                q[j, i] -= mean / 4.0
        u0, u1, u2 = q[2, 0] - q[0, 0], q[2, 1] - q[0, 1], q[2, 2] - q[0, 2]
        v0, v1, v2 = q[3, 0] - q[1, 0], q[3, 1] - q[1, 1], q[3, 2] - q[1, 2]
        n0, n1, n2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0  # diagonals
        norm = np.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        diam = 0.0
        for i in range(4):
            for j in range(i + 1, 4):
                d0, d1, d2 = q[i, 0] - q[j, 0], q[i, 1] - q[j, 1], q[i, 2] - q[j, 2]
                diam = max(diam, np.sqrt(d0 * d0 + d1 * d1 + d2 * d2))
        if norm > 0.0 and diam > 0.0:  # parallel diagonals: the points are coplanar
            h = abs((q[1, 0] - q[0, 0]) * n0 + (q[1, 1] - q[0, 1]) * n1 + (q[1, 2] - q[0, 2]) * n2)
            out[f] = h / norm / 2.0 / diam
    return out


def face_planarity(points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Out-of-plane distortion of quadrilaterals: largest distance from their plane / diameter.

    The plane of (a, b, c, d) passes through its centroid parallel to both diagonals;
    all four points are at the same distance h / 2 from it (h: the distance between the
    diagonals' lines), and no plane has a smaller largest distance.

    Args:
        points: shape=(num_points, 3).
        faces: shape=(num_faces, 4).

    Returns:
        shape=(num_faces,); 0 for a planar face.
    """
    _require_quads(faces)
    return _face_planarity(np.ascontiguousarray(points, dtype=float), _index_array(faces))


@numba.njit(cache=True)
def _less(keys: np.ndarray, i: int, j: int) -> bool:
    for c in range(keys.shape[1]):
        if keys[i, c] != keys[j, c]:
            return keys[i, c] < keys[j, c]
    return False


@numba.njit(cache=True)
def _face_status(faces: np.ndarray, owner: np.ndarray, num_points: int) -> np.ndarray:
    n, k = faces.shape
    # orientation-free keys: rotated to start at the smallest index, read towards the
    # smaller neighbour; sign: that reading is the face's own direction
    keys = np.empty((n, k), dtype=np.int64)
    sign = np.empty(n, dtype=np.bool_)
    for i in range(n):
        first = 0
        for j in range(1, k):
            if faces[i, j] < faces[i, first]:
                first = j
        if k > 2:
            forward = faces[i, (first + 1) % k] < faces[i, (first + k - 1) % k]
        else:  # an edge: its own direction runs towards the higher index
            forward = faces[i, 0] < faces[i, 1]
        sign[i] = forward
        for j in range(k):
            keys[i, j] = faces[i, (first + j) % k] if forward else faces[i, (first - j + k) % k]
    # counting sort on the smallest index, then each bucket by the other indices
    start = np.zeros(num_points + 1, dtype=np.int64)
    for i in range(n):
        start[keys[i, 0] + 1] += 1
    for p in range(num_points):
        start[p + 1] += start[p]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        order[fill[keys[i, 0]]] = i
        fill[keys[i, 0]] += 1
    for p in range(num_points):
        lo, hi = start[p], start[p + 1]
        if hi - lo <= _SMALL_BUCKET:
            for a in range(lo + 1, hi):
                cur = order[a]
                b = a - 1
                while b >= lo and _less(keys, cur, order[b]):
                    order[b + 1] = order[b]
                    b -= 1
                order[b + 1] = cur
        else:
            part = order[lo:hi].copy()
            for c in range(k - 1, 0, -1):  # least significant column first, stable
                part = part[np.argsort(keys[part, c], kind="mergesort")]
            order[lo:hi] = part
    # groups of equal keys: 0 matched, 1 single, 3 same orientation, 4 same block, 5 more
    status = np.empty(n, dtype=np.int8)
    a = 0
    while a < n:
        b = a + 1
        while b < n and not _less(keys, order[a], order[b]):
            b += 1
        size = b - a
        code = 5
        if size == 1:
            code = 1
        elif size == 2:
            i, j = order[a], order[a + 1]
            if owner[i] == owner[j]:
                code = 4
            elif sign[i] != sign[j]:
                code = 0
            else:
                code = 3
        for c in range(a, b):
            status[order[c]] = code
        a = b
    return status


def face_status(faces: np.ndarray, owner: np.ndarray, num_points: int) -> np.ndarray:
    """How each face of a block set pairs with the others (faces as point-index rows).

    Faces with the same point cycle (either direction) form a group; 2D faces are ring
    edges (start, end).

    Args:
        faces: shape=(num_faces, k), k >= 2.
        owner: the block of each face, shape=(num_faces,).
        num_points: more than the largest point index.

    Returns:
        shape=(num_faces,) int8: 0 the face has one partner, in another block and reversed;
        1 it has none; 3 its partner runs the same way; 4 its partner is in the same
        block; 5 more than two faces share its points.
    """
    return _face_status(
        _index_array(faces),
        _index_array(owner),
        int(num_points),
    )


@numba.njit(cache=True)
def _face_stream(faces: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    num, k = len(offsets) - 1, faces.shape[1]
    stream = np.empty(num + len(faces) * (k + 1), dtype=faces.dtype)
    ends = np.empty(num, dtype=np.int64)
    t = 0
    for b in range(num):
        stream[t] = offsets[b + 1] - offsets[b]
        t += 1
        for f in range(offsets[b], offsets[b + 1]):
            stream[t] = k
            t += 1
            for j in range(k):
                stream[t] = faces[f, j]
                t += 1
        ends[b] = t
    return stream, ends


def face_stream(faces: np.ndarray, offsets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """VTK's (legacy) polyhedron face stream: per block [num_faces, k, p1 .. pk, k, ...].

    Args:
        faces: point indices, shape=(num_faces, k).
        offsets: each block's first face, shape=(num_blocks + 1,).

    Returns:
        ``stream`` shape=(num_blocks + num_faces * (k + 1),), of ``faces``' integer type,
        and where each block's part ends, shape=(num_blocks,).
    """
    return _face_stream(_index_array(faces), np.asarray(offsets, dtype=np.int64))


def warm_up(progress: Callable[[str, float], None] | None = None) -> float:
    """Compile (or load from the disk cache) the kernels for the builders' int32 indices.

    Args:
        progress: called as ``progress(kernel, seconds)`` after each kernel is ready (the
            first compilation takes 1-2 s per kernel, a cache load milliseconds), or None.

    Returns:
        The seconds it took.
    """
    t0 = time.perf_counter()
    x = np.array(  # the unit cube, in VTK's hexahedron order
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        dtype=float,
    )
    faces = HEX_FACES.astype(np.int32)
    off = np.array([0, 6], dtype=np.int64)
    centre = x.mean(axis=0, keepdims=True)
    calls: list[tuple[Callable[..., Any], tuple[Any, ...], dict[str, Any]]] = [
        (unique_segments, (faces.ravel(), off * 4), {}),
        (edge_groups, (faces, off, len(x)), {}),
        (block_integrals, (x, faces, off), {}),
        (reach, (x, faces, off), {"centres": centre}),
        (face_planarity, (x, faces), {}),
        (face_status, (faces, np.zeros(6, dtype=np.int64), len(x)), {}),
        (face_stream, (faces, off), {}),
    ]
    for kernel, args, kwargs in calls:
        start = time.perf_counter()
        kernel(*args, **kwargs)
        if progress is not None:
            progress(kernel.__name__, time.perf_counter() - start)
    return time.perf_counter() - t0
