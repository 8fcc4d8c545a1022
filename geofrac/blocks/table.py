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


def face_keys(a: np.ndarray, b: np.ndarray, c: np.ndarray, *, n: int) -> np.ndarray:
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
    """Points of several kinds, each named by a key unique within its kind.

    The points are stored in segments: the construction's points, kind by kind with their
    keys sorted, then points appended later (:meth:`append`), again sorted by kind and
    key within each append. :attr:`x` has shape=(num_points, gdim); :attr:`kind` and
    :attr:`key` give each point's kind and key, shape=(num_points,).
    """

    def __init__(self, keys: Sequence[np.ndarray], coords: Sequence[np.ndarray]) -> None:
        """Build from per-kind keys, shape=(n_k,) each, with coordinates, shape=(n_k, gdim).

        Keys may repeat (the same point seen from several cells, computed with the same
        bits); the coordinates of one of them are kept. :attr:`given` holds, per kind,
        the index of each given key's point (the refs of the construction keys, same
        shapes).
        """
        self.num_kinds = len(keys)
        self.segments: list[list[tuple[np.ndarray, int]]] = [[] for _ in keys]
        self.given: list[np.ndarray] = []
        xs, kinds, all_keys = [], [], []
        start = 0
        for k, (raw, x) in enumerate(zip(keys, coords, strict=True)):
            unique, first, inverse = _unique(np.ravel(raw))
            self.segments[k].append((unique, start))
            self.given.append(start + inverse.reshape(np.shape(raw)))
            xs.append(x[first])
            kinds.append(np.full(len(unique), k, dtype=np.int8))
            all_keys.append(unique)
            start += len(unique)
        self.x = np.concatenate(xs) if xs else np.empty((0, 3))
        self.kind = np.concatenate(kinds) if kinds else np.empty(0, np.int8)
        self.key = np.concatenate(all_keys) if all_keys else np.empty(0, np.int64)

    def find(self, kind: int, keys: np.ndarray) -> np.ndarray:
        """Indices of the points ``keys`` of ``kind``, -1 where absent, shape like ``keys``."""
        keys = np.asarray(keys, dtype=np.int64)
        out = np.full(keys.shape, -1, dtype=np.int64)
        for sorted_keys, start in self.segments[kind]:
            if not len(sorted_keys):
                continue
            pos = np.minimum(np.searchsorted(sorted_keys, keys), len(sorted_keys) - 1)
            hit = (sorted_keys[pos] == keys) & (out < 0)
            out[hit] = start + pos[hit]
        return out

    def refs(self, kind: int, keys: np.ndarray) -> np.ndarray:
        """Indices of the points ``keys`` of ``kind``, all present, shape like ``keys``.

        Raises:
            KeyError: a key is not in the table.
        """
        out = self.find(kind, keys)
        if np.any(out < 0):
            raise KeyError(f"{int(np.count_nonzero(out < 0))} point(s) of kind {kind} missing")
        return out

    def describe(self, refs: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(kind, key, coordinates) of the points ``refs``, shapes (n,), (n,), (n, gdim)."""
        refs = np.asarray(refs, dtype=np.int64)
        return self.kind[refs].astype(np.int64), self.key[refs], self.x[refs]

    def append(self, kind: np.ndarray, key: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Add the points (kind, key, x) not yet present; earlier refs stay valid.

        Args:
            kind: the points' kinds, shape=(n,).
            key: their keys, shape=(n,).
            x: their coordinates, shape=(n, gdim).

        Returns:
            The refs of the given points, shape=(n,).
        """
        kind = np.asarray(kind)
        refs = np.empty(len(key), dtype=np.int64)
        xs, kinds, keys = [self.x], [self.kind], [self.key]
        start = len(self.x)
        for k in range(self.num_kinds):
            mine = np.flatnonzero(kind == k)
            found = self.find(k, key[mine])
            refs[mine[found >= 0]] = found[found >= 0]
            missing = mine[found < 0]
            if not len(missing):
                continue
            unique, first, inverse = _unique(key[missing])
            self.segments[k].append((unique, start))
            refs[missing] = start + inverse
            xs.append(x[missing[first]])
            kinds.append(np.full(len(unique), k, dtype=np.int8))
            keys.append(unique)
            start += len(unique)
        self.x, self.kind, self.key = (
            np.concatenate(xs),
            np.concatenate(kinds),
            np.concatenate(keys),
        )
        return refs
