"""The points a block set is made of, named by what they stand on (pure numpy).

A block point is always one of: a mesh vertex, an edge midpoint, the inner point of a
face (a triangle's incentre or centroid), or a tetrahedron's centroid. Naming each by
(kind, key), where the key comes from the global ids of the mesh vertices it stands
on, lets every rank compute the same point with the same coordinates, bit for bit,
whatever the partition: midpoints and centroids sum each coordinate's values in
increasing order (:func:`geofrac.blocks.dual3d.centroids`), whichever cell computes them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["PointTable", "edge_keys", "face_keys"]

#: Largest global vertex count for which a face key (a*N + b)*N + c fits in int64.
MAX_VERTICES = 2_097_151


def edge_keys(a: np.ndarray, b: np.ndarray, n: int) -> np.ndarray:
    """Key of the edges (a, b) with a < b, shape like ``a``, from global ids < ``n``."""
    return a.astype(np.int64) * n + b


def face_keys(a: np.ndarray, b: np.ndarray, c: np.ndarray, n: int) -> np.ndarray:
    """Key of the triangles (a, b, c) with a < b < c, shape like ``a``.

    Raises:
        ValueError: ``n`` above :data:`MAX_VERTICES` (the key would overflow).
    """
    if n > MAX_VERTICES:
        raise ValueError(f"{n} vertices: face keys need at most {MAX_VERTICES}")
    return (a.astype(np.int64) * n + b) * n + c


def _unique(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sorted unique keys, the position of one occurrence of each, and each key's index.

    ``np.unique`` with ``return_index`` sorts stably (merge sort) to return the first
    occurrence; any occurrence will do here, so an unstable sort is used (about twice
    as fast).
    """
    order = np.argsort(keys)
    ordered = keys[order]
    starts = np.ones(len(keys), dtype=bool)
    starts[1:] = ordered[1:] != ordered[:-1]
    inverse = np.empty(len(keys), dtype=np.int64)
    inverse[order] = np.cumsum(starts) - 1
    return ordered[starts], order[starts], inverse


class PointTable:
    """Points of several kinds, each kind a sorted array of unique keys with coordinates.

    A point's index in the table is ``offset(kind) + position of its key``; the table's
    :attr:`x` has shape=(num_points, gdim) in that order.
    """

    def __init__(self, keys: Sequence[np.ndarray], coords: Sequence[np.ndarray]) -> None:
        """Build from per-kind keys, shape=(n_k,) each, with coordinates, shape=(n_k, gdim).

        Keys may repeat (the same point seen from several cells, computed with the same
        bits); the coordinates of one of them are kept. :attr:`given` holds, per kind,
        the index of each given key's point (the refs of the construction keys, same
        shapes).
        """
        self.keys: list[np.ndarray] = []
        self.given: list[np.ndarray] = []
        xs = []
        for k, x in zip(keys, coords, strict=True):
            unique, first, inverse = _unique(np.ravel(k))
            self.keys.append(unique)
            self.given.append(inverse.reshape(np.shape(k)))
            xs.append(x[first])
        self.x = np.concatenate(xs) if xs else np.empty((0, 3))
        self._offsets()
        self.given = [g + o for g, o in zip(self.given, self.offsets, strict=False)]

    def _offsets(self) -> None:
        sizes = [len(k) for k in self.keys]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)

    def refs(self, kind: int, keys: np.ndarray) -> np.ndarray:
        """Indices of the points ``keys`` (all present) of ``kind``, shape like ``keys``."""
        return self.offsets[kind] + np.searchsorted(self.keys[kind], keys)

    def describe(self, refs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(kind, key, coordinates) of the points ``refs``, shapes (n,), (n,), (n, gdim)."""
        refs = np.asarray(refs, dtype=np.int64)
        kind = np.searchsorted(self.offsets, refs, side="right") - 1
        key = np.empty(len(refs), dtype=np.int64)
        for k, keys in enumerate(self.keys):
            mine = kind == k
            key[mine] = keys[refs[mine] - self.offsets[k]]
        return kind, key, self.x[refs]

    def merge_remap(
        self, kind: np.ndarray, key: np.ndarray, x: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Add the points (kind, key, x) not yet present (ours are kept where both have one).

        Returns:
            The refs of the given points, shape=(n,), and where each old point went,
            shape=(old_num_points,): refs issued before the merge must be remapped.
        """
        old_offsets = self.offsets.copy()
        old_x = self.x
        new_keys, new_x, old_pos = [], [], []
        for k, keys in enumerate(self.keys):
            mine = kind == k
            merged = np.union1d(keys, key[mine])
            new_keys.append(merged)
            old_pos.append(np.searchsorted(merged, keys))
            coords = np.empty((len(merged), old_x.shape[1]))
            coords[np.searchsorted(merged, key[mine])] = x[mine]
            coords[old_pos[-1]] = old_x[old_offsets[k] : old_offsets[k + 1]]  # keep ours
            new_x.append(coords)
        self.keys = new_keys
        self.x = np.concatenate(new_x) if new_x else old_x
        self._offsets()
        old_to_new = np.concatenate(
            [self.offsets[k] + p for k, p in enumerate(old_pos)] or [np.empty(0, np.int64)]
        )
        refs = np.empty(len(key), dtype=np.int64)
        for k in range(len(self.keys)):
            mine = kind == k
            refs[mine] = self.refs(k, key[mine])
        return refs, old_to_new
