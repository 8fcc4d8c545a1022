"""The regular background grid of the MPM (the Euler grid of Edo (2016), Fig. 4.1)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Grid", "grid"]


@dataclass(frozen=True)
class Grid:
    """Square (cubic) cells of one size on a box.

    Attributes:
        origin: the lowest corner, shape=(dim,).
        spacing: the cell size L (eq. 4.28).
        cells: cells per direction, shape=(dim,).
    """

    origin: np.ndarray
    spacing: float
    cells: tuple[int, ...]

    @property
    def dim(self) -> int:
        """Spatial dimension (1, 2 or 3)."""
        return len(self.cells)

    @property
    def shape(self) -> tuple[int, ...]:
        """Nodes per direction."""
        return tuple(c + 1 for c in self.cells)

    @property
    def num_nodes(self) -> int:
        """Number of grid nodes."""
        return int(np.prod(self.shape))

    @property
    def upper(self) -> np.ndarray:
        """The highest corner, shape=(dim,)."""
        return self.origin + self.spacing * np.asarray(self.cells)

    def nodes(self) -> np.ndarray:
        """Node coordinates in flat (C) order, shape=(num_nodes, dim)."""
        axes = [self.origin[a] + self.spacing * np.arange(n) for a, n in enumerate(self.shape)]
        mesh = np.meshgrid(*axes, indexing="ij")
        return np.stack([m.ravel() for m in mesh], axis=1)

    def flat(self, index: np.ndarray) -> np.ndarray:
        """Flat node ids of per-direction node indices, shape=index.shape[:-1]."""
        return np.ravel_multi_index(tuple(np.moveaxis(index, -1, 0)), self.shape)

    def outside(self, x: np.ndarray, margin: np.ndarray | float = 0.0) -> np.ndarray:
        """Which points (with a half-width ``margin``) reach beyond the grid, shape=(n,).

        Args:
            x: points, shape=(n, dim).
            margin: half-width of each point's support, shape=(n, dim) or a number.
        """
        lo = np.any(x - margin < self.origin, axis=1)
        hi = np.any(x + margin > self.upper, axis=1)
        return lo | hi


def grid(
    origin: np.ndarray | list[float], spacing: float, cells: tuple[int, ...] | list[int]
) -> Grid:
    """A grid from its lowest corner, cell size and cells per direction."""
    o = np.asarray(origin, dtype=float).reshape(-1)
    c = tuple(int(n) for n in cells)
    if len(c) != len(o) or not 1 <= len(c) <= 3:
        raise ValueError(
            f"grid: origin {o.tolist()} and cells {list(c)} must both have 1-3 entries"
        )
    if not spacing > 0 or min(c) < 1:
        raise ValueError(f"grid: spacing {spacing} must be > 0 and every cell count >= 1")
    return Grid(o, float(spacing), c)
