"""GIMP: the hat averaged over the particle's box (``ugimp``, ``cpgimp``; Edo (2016)).

χ_p is the particle's box of half-width l_p (eq. 4.27), φ_ip the hat averaged over it
(eqs. 4.30-4.31). ``ugimp``: l_p keeps its initial value (eq. 4.71); ``cpgimp``: l_p
follows the deformation gradient, l_p = G_p l_p⁰ (eqs. 4.69-4.70; per direction the
diagonal of G_p).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import Grid
from geofrac.mpm.shapes.base import Shape, Weights

__all__ = ["CPGIMP", "UGIMP", "Gimp", "gimp_1d", "gimp_nodes"]


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


@dataclass(frozen=True)
class Gimp(Shape):
    """Box particles (:attr:`Shape.boxes`): the hat averaged over [x_p − l_p, x_p + l_p]."""

    boxes: bool = True

    def nodes_per_direction(self, spacing: float, lp: np.ndarray) -> int:
        """:func:`gimp_nodes`: enough for the widest box."""
        return gimp_nodes(spacing, lp)

    def per_direction(
        self, g: Grid, x: np.ndarray, lp: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`Shape.per_direction` (``lp`` required)."""
        assert lp is not None, "GIMP weights need the half-widths l_p"
        L = g.spacing
        n, dim = x.shape
        k1 = gimp_nodes(L, lp)
        start = np.floor((x - L - lp - g.origin) / L).astype(np.int64) + 1
        idx = start[:, :, None] + np.arange(k1)
        r = x[:, :, None] - (g.origin[:, None] + L * idx)
        phi, dphi = gimp_1d(r.reshape(n * dim, k1), L, lp.reshape(n * dim, 1))
        return idx, phi.reshape(n, dim, k1), dphi.reshape(n, dim, k1)

    def fill_compiled(self, g: Grid, x: np.ndarray, lp: np.ndarray | None, *, out: Weights) -> bool:
        """:func:`geofrac.mpm.kernels.weights_gimp`."""
        from geofrac.mpm import kernels

        assert lp is not None, "GIMP weights need the half-widths l_p"
        shape = np.asarray(g.shape, dtype=np.int64)
        origin = np.ascontiguousarray(g.origin, dtype=float)
        k1 = gimp_nodes(g.spacing, lp)
        return kernels.weights_gimp(
            x, lp, origin, g.spacing, shape, k1, out.nodes, out.phi, out.grad
        )


#: uGIMP: l_p keeps its initial value (eq. 4.71).
UGIMP = Gimp("ugimp", "GIMP with the initial half-widths (eqs. 4.30-4.31, 4.71)")
#: cpGIMP: l_p = l_p⁰ |G_aa| (eqs. 4.69-4.70).
CPGIMP = Gimp(
    "cpgimp",
    "GIMP with half-widths following the deformation gradient (eqs. 4.69-4.70)",
    follows_deformation=True,
)
