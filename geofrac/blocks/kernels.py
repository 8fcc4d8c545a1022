"""Compiled (numba) loops of the block checks, imported only when a check needs them."""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["overlapping_pairs"]


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
