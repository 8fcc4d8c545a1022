"""MLS displacement field of a cracked triangle, Edo (2016), eqs. (2.10)-(2.19) and App. B.

The field of a cracked cell is the weighted least-squares fit of a complete linear
polynomial p(x) = {1, x - x_c, y - y_c} to the displacements of its visible satellite
nodes (eq. 2.10), with the quartic spline weight (2.11) of the node's distance r_I to the
cell's centroid x_c. The centre is fixed at the centroid (Edo (2016): "r_I is the distance
between the centroid and node I"), so A and B of (2.14)-(2.15) are constant over the cell,
the terms with ∂A/∂x and ∂B/∂x in (B.9) vanish, and the field is linear: the cell has a
constant strain and its stiffness (2.19) is t · area · Bᵀ D B. Shifting the basis to the
centroid changes nothing mathematically and keeps A well conditioned.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LinearFit", "linear_fit", "quartic_spline", "strain_matrix"]

#: A fit whose moment matrix A has a condition number above this is rejected.
MAX_CONDITION = 1e10


def quartic_spline(r: np.ndarray, h: float) -> np.ndarray:
    """Weight (2.11): 5/(π h²) [1 - 6 s² + 8 s³ - 3 s⁴] for s = r/h ≤ 1, else 0.

    Args:
        r: distances, shape=(n,).
        h: radius of the influence circle.

    Returns:
        weights, shape=(n,).
    """
    s = np.asarray(r, dtype=float) / h
    w = 5.0 / (np.pi * h * h) * (1.0 - 6.0 * s**2 + 8.0 * s**3 - 3.0 * s**4)
    return np.where(s <= 1.0, w, 0.0)


@dataclass(frozen=True)
class LinearFit:
    """The linear MLS field of one cell: u(x) = Σ_I φ_I(x) u_I, eq. (2.17).

    Attributes:
        centre: the fixed centre x_c, shape=(2,).
        h: influence radius.
        nodes: satellite node ids, shape=(n,).
        coefficients: A⁻¹ B, the map from nodal values to (a, b, c) of
            a + b (x - x_c) + c (y - y_c), shape=(3, n).
    """

    centre: np.ndarray
    h: float
    nodes: np.ndarray
    coefficients: np.ndarray

    def shape_functions(self, points: np.ndarray) -> np.ndarray:
        """φ_I at points, eq. (2.18), shape=(m, n) for points of shape=(m, 2)."""
        d = np.atleast_2d(points) - self.centre
        p = np.column_stack([np.ones(len(d)), d])
        return p @ self.coefficients

    def gradients(self) -> np.ndarray:
        """∂φ_I/∂x and ∂φ_I/∂y (constant over the cell), shape=(2, n)."""
        return self.coefficients[1:]


def linear_fit(
    centre: np.ndarray, h: float, nodes: np.ndarray, *, coords: np.ndarray
) -> LinearFit | None:
    """Fit the linear MLS field (2.13)-(2.18) centred at ``centre``.

    Args:
        centre: the cell centroid, shape=(2,).
        h: influence radius (nodes at r ≥ h get zero weight).
        nodes: satellite node ids, shape=(n,).
        coords: their coordinates, shape=(n, 2).

    Returns:
        the fit, or None when fewer than 3 nodes carry weight or they are (nearly)
        collinear, so that A (2.14) cannot be inverted reliably.
    """
    d = np.asarray(coords, dtype=float) - centre
    w = quartic_spline(np.hypot(d[:, 0], d[:, 1]), h)
    keep = w > 0.0
    if keep.sum() < 3:
        return None
    p = np.column_stack([np.ones(len(d)), d / h])  # scaled by h: A is O(1)
    A = (p[keep].T * w[keep]) @ p[keep]  # eq. (2.14), shape=(3, 3)
    if np.linalg.cond(A) > MAX_CONDITION:
        return None
    B = p.T * w  # eq. (2.15), shape=(3, n)
    coefficients = np.linalg.solve(A, B)
    coefficients[1:] /= h  # undo the scaling of the basis
    return LinearFit(np.asarray(centre, float), float(h), np.asarray(nodes), coefficients)


def strain_matrix(fit: LinearFit) -> np.ndarray:
    """B_MLSM of (2.19) for DOFs (u_1, v_1, u_2, v_2, ...), shape=(3, 2 n).

    Rows are ε_xx, ε_yy, γ_xy (engineering shear).
    """
    gx, gy = fit.gradients()
    n = len(gx)
    B = np.zeros((3, 2 * n))
    B[0, 0::2] = gx
    B[1, 1::2] = gy
    B[2, 0::2] = gy
    B[2, 1::2] = gx
    return B
