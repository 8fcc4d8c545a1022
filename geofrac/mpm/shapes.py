"""Particle–node weights φ_ip and their gradients (Edo (2016), eqs. 4.24-4.32, 4.69-4.71).

Three kinds, as the scene's ``shape``:

- ``mpm``: the particle is a point (χ_p = δ(x − x_p) V_p, eq. 4.26), so φ_ip = N_i(x_p),
  the linear hat of eqs. 4.28-4.29. At a cell boundary the particle belongs to the cell
  on its upper side (its gradients are that cell's), so a particle on a node still
  carries forces;
- ``ugimp``: χ_p is the particle's box of half-width l_p (eq. 4.27), φ_ip the hat
  averaged over it (eqs. 4.30-4.31); l_p keeps its initial value (eq. 4.71);
- ``cpgimp``: the same, with l_p following the deformation gradient, l_p = F_p l_p⁰
  (eqs. 4.69-4.70; per direction, the diagonal of F_p).

- ``bspline2``: not in Edo (2016); the quadratic B-spline of the node distance,
  N(r) = 3/4 − (r/L)² for |r| < L/2 and (3/2 − |r|/L)²/2 for L/2 ≤ |r| < 3L/2 (support
  1.5 cells each side, three nodes per direction). Its gradient is continuous, so a
  particle crossing a cell boundary changes no force abruptly (the cell-crossing error
  of ``mpm``); docs/mpm_energy.md.

In 2D and 3D the weights are tensor products of the 1D ones (eq. 4.32).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import Grid

__all__ = [
    "SHAPES",
    "Weights",
    "bspline2_1d",
    "gimp_1d",
    "gimp_nodes",
    "hat_1d",
    "support_margin",
    "weights",
]

#: Shape function kinds.
SHAPES = ("mpm", "ugimp", "cpgimp", "bspline2")


def support_margin(shape: str, spacing: float) -> float | None:
    """How far from a particle the nodes with weight reach beyond the grid check, or None.

    None: the particle's half-widths l_p (GIMP) or nothing (``mpm``) decide. For
    ``bspline2`` the three nodes around the particle must exist: half a cell.
    """
    return 0.5 * spacing if shape == "bspline2" else None


def bspline2_1d(r: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """The quadratic B-spline N(r) and dN/dx for r = x_p − x_i, each the shape of r."""
    a = np.abs(r) / L
    sign = np.sign(r)
    phi = np.where(a < 0.5, 0.75 - a**2, np.where(a < 1.5, 0.5 * (1.5 - a) ** 2, 0.0))
    dphi = np.where(a < 0.5, -2 * a, np.where(a < 1.5, -(1.5 - a), 0.0)) * sign / L
    return phi, dphi


@dataclass(frozen=True)
class Weights:
    """The nodes each particle touches, with φ_ip and ∇φ_ip.

    Attributes:
        nodes: flat node ids, shape=(n, k); a node out of the grid never carries weight.
        phi: φ_ip, shape=(n, k); each row sums to 1.
        grad: dφ_ip/dx, shape=(n, k, dim).
    """

    nodes: np.ndarray
    phi: np.ndarray
    grad: np.ndarray


def hat_1d(s: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 4.28-4.29 for the two nodes of the particle's cell.

    Args:
        s: the particle's position in its cell, 0 <= s < L, shape=(n,).
        L: cell size.

    Returns:
        φ and dφ/dx for the lower and upper node, each shape=(n, 2).
    """
    phi = np.stack([1.0 - s / L, s / L], axis=1)
    dphi = np.broadcast_to(np.array([-1.0 / L, 1.0 / L]), phi.shape).copy()
    return phi, dphi


def gimp_1d(r: np.ndarray, L: float, lp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. 4.30-4.31: GIMP weight and gradient for r = x_p − x_i.

    Args:
        r: particle minus node position, shape=(n, k).
        L: cell size.
        lp: particle half-width, 0 < l_p <= L/2, shape=(n, 1) or (n, k).

    Returns:
        φ and dφ/dx, each shape=(n, k).
    """
    lp = np.broadcast_to(lp, r.shape)
    conds = [
        (r > -L - lp) & (r <= -L + lp),
        (r > -L + lp) & (r <= -lp),
        (r > -lp) & (r <= lp),
        (r > lp) & (r <= L - lp),
        (r > L - lp) & (r < L + lp),
    ]
    phi = np.select(
        conds,
        [
            (L + lp + r) ** 2 / (4 * L * lp),
            1 + r / L,
            1 - (r**2 + lp**2) / (2 * L * lp),
            1 - r / L,
            (L + lp - r) ** 2 / (4 * L * lp),
        ],
        0.0,
    )
    dphi = np.select(
        conds,
        [
            (L + lp + r) / (2 * L * lp),
            np.full(r.shape, 1 / L),
            -r / (L * lp),
            np.full(r.shape, -1 / L),
            -(L + lp - r) / (2 * L * lp),
        ],
        0.0,
    )
    return phi, dphi


def gimp_nodes(L: float, lp: np.ndarray) -> int:
    """Nodes per direction that hold every GIMP support of half-widths lp (any shape)."""
    widest = float(lp.max()) if lp.size else 0.0
    return int(np.floor(2 * (L + widest) / L - 1e-12)) + 1


def _per_direction(
    g: Grid, x: np.ndarray, lp: np.ndarray | None, bspline: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node indices, φ and dφ/dx per direction, each shape=(n, dim, k1)."""
    L = g.spacing
    n, dim = x.shape
    if bspline:
        start = np.floor((x - g.origin) / L + 0.5).astype(np.int64) - 1
        idx = start[:, :, None] + np.arange(3)
        r = x[:, :, None] - (g.origin[:, None] + L * idx)
        phi, dphi = bspline2_1d(r, L)
        return idx, phi, dphi
    if lp is None:
        start = np.floor((x - g.origin) / L).astype(np.int64)
        start = np.clip(start, 0, np.asarray(g.cells) - 1)  # the upper boundary's cell
        s = x - (g.origin + L * start)
        idx = start[:, :, None] + np.arange(2)
        phi, dphi = hat_1d(s.ravel(), L)
        return idx, phi.reshape(n, dim, 2), dphi.reshape(n, dim, 2)
    k1 = gimp_nodes(L, lp)
    start = np.floor((x - L - lp - g.origin) / L).astype(np.int64) + 1
    idx = start[:, :, None] + np.arange(k1)
    r = x[:, :, None] - (g.origin[:, None] + L * idx)
    phi, dphi = gimp_1d(r.reshape(n * dim, k1), L, lp.reshape(n * dim, 1))
    return idx, phi.reshape(n, dim, k1), dphi.reshape(n, dim, k1)


def weights(g: Grid, x: np.ndarray, lp: np.ndarray | None = None, bspline: bool = False) -> Weights:
    """φ_ip and ∇φ_ip of particles at x (tensor products, eq. 4.32).

    Args:
        g: the grid.
        x: particle positions, all inside the grid, shape=(n, dim).
        lp: GIMP half-widths, shape=(n, dim); None for ``mpm`` (point particles).
        bspline: quadratic B-splines (``bspline2``; ``lp`` is then ignored).

    Raises:
        ValueError: a node with weight lies outside the grid (check
            :meth:`Grid.outside` first).
    """
    n, dim = x.shape
    idx, phi1, dphi1 = _per_direction(g, x, lp, bspline)
    k1 = idx.shape[2]
    upper = np.asarray(g.shape)[None, :, None] - 1
    off = (idx < 0) | (idx > upper)
    # exactly 0 beyond the open support, so a box reaching exactly to the grid's edge
    # passes (the same comparison as Grid.outside's, which the step runs first)
    if np.any(off & (phi1 != 0.0)):
        raise ValueError("weights: a particle's support reaches beyond the grid")
    idx = np.clip(idx, 0, upper)
    phi1 = np.where(off, 0.0, phi1)
    dphi1 = np.where(off, 0.0, dphi1)
    # tensor products over the k1**dim node combinations (eq. 4.32)
    combos = np.stack(np.meshgrid(*[np.arange(k1)] * dim, indexing="ij"), -1).reshape(-1, dim)
    rows = np.arange(dim)
    multi = idx[:, rows, combos]  # shape=(n, k, dim)
    p = phi1[:, rows, combos]  # shape=(n, k, dim)
    d = dphi1[:, rows, combos]
    phi = np.prod(p, axis=2)
    grad = np.empty((n, len(combos), dim))
    for b in range(dim):
        others = np.prod(np.delete(p, b, axis=2), axis=2) if dim > 1 else 1.0
        grad[:, :, b] = d[:, :, b] * others
    return Weights(g.flat(multi), phi, grad)
