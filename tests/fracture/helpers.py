"""Helpers shared by the fracture tests."""

import numpy as np


def grid_mesh(n: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Structured triangles on [0, n]^2: coordinates shape=(nodes, 2), cells shape=(cells, 3)."""
    x, y = np.meshgrid(np.arange(n + 1.0), np.arange(n + 1.0))
    coords = np.column_stack([x.ravel(), y.ravel()])
    cells = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            cells += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return coords, np.array(cells)
