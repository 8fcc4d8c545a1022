"""What every part of the MPM may ask of a kind of shape functions: :class:`Shape`.

A shape declares itself once (one module per shape or family, one line in
:data:`geofrac.mpm.shapes.REGISTRY`): its 1D weights per direction, how many nodes per
direction they touch, how far beyond a particle its support reaches (the grid check and
the padding), whether the particle is a box of half-widths l_p (GIMP's particle domain) and
whether those follow the deformation (cpGIMP). The step, the driver and the scene loader
ask the :class:`Shape`, never its name.

In 2D and 3D the weights are tensor products of the 1D ones (Edo (2016), eq. 4.32):
:func:`weights` (numpy reference) and :func:`compiled_weights` (the compiled loops of
:mod:`~geofrac.mpm.kernels`, imported by its first call).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.mpm.grid import Grid

__all__ = ["Shape", "Weights", "compiled_weights", "weights"]


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


@dataclass(frozen=True)
class Shape:
    """One kind of particle–node weights (``mpm.shape``), declared once.

    Subclasses give the 1D weights (:meth:`per_direction`), the nodes they touch per
    direction (:meth:`nodes_per_direction`) and, optionally, compiled weights
    (:meth:`fill_compiled`; the default copies the numpy reference) and a support reaching
    beyond a point particle (:meth:`reach`).

    Attributes:
        name: the scene name (``mpm.shape``).
        description: one line for docs and errors.
        boxes: the particle is a box of half-widths l_p (GIMP's particle domain, eq. 4.27):
            its weights and its grid check read ``Particles.lp``.
        follows_deformation: l_p = l_p⁰ |G_aa| after every stress update (cpGIMP, eqs.
            4.69-4.70); else l_p keeps its initial value (uGIMP, 4.71).
        phi_bound: an upper bound of every φ_ip (the exact nodal sums scale their terms
            by it, :mod:`~geofrac.mpm.fixedpoint`).
        grad_bound: an upper bound of every |∂φ_ip/∂x_a| times the cell size.
    """

    name: str
    description: str
    boxes: bool = False
    follows_deformation: bool = False
    phi_bound: float = 1.0
    grad_bound: float = 1.0

    def __str__(self) -> str:
        """The scene name."""
        return self.name

    def reach(self, spacing: float) -> float:
        """How far beyond a point particle the nodes with weight reach, beyond the grid check.

        0 (the default): the nodes of the particle's cell, which the grid holds when the
        particle is inside it. Not used for :attr:`boxes` shapes (their l_p decide).
        """
        return 0.0

    def margin(self, spacing: float, lp: np.ndarray) -> np.ndarray | float:
        """The half-width around each particle that must lie inside the grid.

        The one padding rule of the grid check (the step's and the driver's start):
        ``lp`` (shape=(n, dim)) for :attr:`boxes` shapes, else :meth:`reach`.
        """
        return lp if self.boxes else self.reach(spacing)

    def nodes_per_direction(self, spacing: float, lp: np.ndarray) -> int:
        """Nodes per direction that hold the support of every particle (lp shape=(n, dim))."""
        raise NotImplementedError

    def per_direction(
        self, g: Grid, x: np.ndarray, lp: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Node indices, φ and dφ/dx per direction (numpy), each shape=(n, dim, k1).

        Args:
            g: the grid.
            x: particle positions, shape=(n, dim).
            lp: half-widths, shape=(n, dim) (read by :attr:`boxes` shapes only).
        """
        raise NotImplementedError

    def fill_compiled(self, g: Grid, x: np.ndarray, lp: np.ndarray | None, *, out: Weights) -> bool:
        """The weights into ``out``'s arrays (shape=(n, k1**dim) ...), compiled.

        The default copies the numpy reference (a new shape may add a numba kernel
        later). Returns False when a node with weight lies outside the grid.
        """
        try:
            ref = weights(g, x, self, lp=lp)
        except ValueError:
            return False
        out.nodes[...] = ref.nodes
        out.phi[...] = ref.phi
        out.grad[...] = ref.grad
        return True


def _tensor(g: Grid, idx: np.ndarray, phi1: np.ndarray, dphi1: np.ndarray) -> Weights:
    """Tensor products (eq. 4.32) of per-direction weights (each shape=(n, dim, k1))."""
    n, dim, k1 = idx.shape
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


def weights(g: Grid, x: np.ndarray, shape: Shape, *, lp: np.ndarray | None = None) -> Weights:
    """φ_ip and ∇φ_ip of particles at x (tensor products, eq. 4.32), numpy.

    Args:
        g: the grid.
        x: particle positions, all inside the grid, shape=(n, dim).
        shape: the kind of weights.
        lp: half-widths, shape=(n, dim); needed by :attr:`Shape.boxes` shapes only.

    Raises:
        ValueError: a node with weight lies outside the grid (check
            :meth:`Grid.outside` first).
    """
    return _tensor(g, *shape.per_direction(g, x, lp))


def compiled_weights(
    g: Grid,
    x: np.ndarray,
    shape: Shape,
    *,
    lp: np.ndarray | None = None,
    reuse: bool = False,
) -> Weights:
    """Compiled :func:`weights` (same arguments, same result).

    With ``reuse`` the arrays are :func:`geofrac.mpm.kernels.scratch` buffers, overwritten
    by the next call (a step's own weights).

    Raises:
        ValueError: a node with weight lies outside the grid.
    """
    from geofrac.mpm import kernels

    n, dim = x.shape
    k = shape.nodes_per_direction(g.spacing, lp) ** dim  # type: ignore[arg-type]
    if reuse:
        nodes = kernels.scratch("nodes", (n, k), np.int64)
        phi = kernels.scratch("phi", (n, k))
        grad = kernels.scratch("grad", (n, k, dim))
    else:
        nodes = np.empty((n, k), np.int64)
        phi = np.empty((n, k))
        grad = np.empty((n, k, dim))
    out = Weights(nodes, phi, grad)
    if not shape.fill_compiled(g, x, lp, out=out):
        raise ValueError("weights: a particle's support reaches beyond the grid")
    return out
