"""Cell stiffness matrices and stresses of intact and cracked triangles (pure numpy).

Intact cells use their element's field: CST (P1), or the RGNT/GNT vertex-DOF field of
:mod:`geofrac.elements.kinematics`, whose stiffness is Tᵀ K_P2 T plus the zero-mode
penalty of :mod:`geofrac_forms.gradient_dofs` (Edo (2016), eqs. 2.4, 2.29). The integrands are
quadratic on an affine triangle, so the three-point edge-midpoint rule is exact and these
matrices equal the UFL-assembled ones to round-off (``tests/fracture/test_cells.py``
checks this against DOLFINx). Cracked cells use the MLS field (2.19):
k = t · area · Bᵀ D B on the translations of their satellite nodes.

DOFs of a cell are ordered vertex by vertex, ``block_size`` per vertex (translations
first). The driver needs the matrices one cell at a time for the changed cells of an
event, which is why they are computed here rather than by a global assembly.
"""

from __future__ import annotations

import numpy as np

from geofrac.elements.kinematics import KINDS, local_prolongation
from geofrac.elements.spec import ElementSpec
from geofrac.mls.shape import LinearFit, strain_matrix

__all__ = [
    "MIDPOINTS",
    "P2_EDGES",
    "MlsTable",
    "fe_matrices",
    "fe_stresses",
    "mls_matrix",
    "principal_max",
    "strain_operator",
]

#: P2 edge nodes in basix order: edge e joins local vertices P2_EDGES[e].
P2_EDGES = np.array([[1, 2], [0, 2], [0, 1]])


def _barycentric_gradients(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(∇λ_i, shape=(nc, 3, 2); areas, shape=(nc,)) of triangles x, shape=(nc, 3, 2)."""
    d1, d2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    inv = np.empty((len(x), 2, 2))  # inverse Jacobian of the map from the reference cell
    inv[:, 0, 0], inv[:, 0, 1] = d2[:, 1] / det, -d2[:, 0] / det
    inv[:, 1, 0], inv[:, 1, 1] = -d1[:, 1] / det, d1[:, 0] / det
    g1, g2 = inv[:, 0], inv[:, 1]
    grads = np.stack([-g1 - g2, g1, g2], axis=1)
    return grads, 0.5 * np.abs(det)


def _voigt(grad: np.ndarray) -> np.ndarray:
    """Strain rows (ε_xx, ε_yy, γ_xy) from basis gradients, for vector DOFs.

    Args:
        grad: gradients of scalar basis functions, shape=(..., nb, 2).

    Returns:
        B with DOFs (u_0, v_0, u_1, ...), shape=(..., 3, 2 nb).
    """
    *lead, nb, _ = grad.shape
    B = np.zeros((*lead, 3, 2 * nb))
    B[..., 0, 0::2] = grad[..., 0]
    B[..., 1, 1::2] = grad[..., 1]
    B[..., 2, 0::2] = grad[..., 1]
    B[..., 2, 1::2] = grad[..., 0]
    return B


def _p2_gradients(lam_grad: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """Gradients of the six P2 basis functions at barycentric points.

    Args:
        lam_grad: ∇λ_i, shape=(nc, 3, 2).
        bary: barycentric coordinates of the points, shape=(nq, 3).

    Returns:
        shape=(nc, nq, 6, 2), P2 nodes in basix order (vertices, then P2_EDGES).
    """
    nc, nq = len(lam_grad), len(bary)
    out = np.empty((nc, nq, 6, 2))
    for i in range(3):  # λ_i (2 λ_i - 1)
        out[:, :, i] = (4.0 * bary[:, i] - 1.0)[None, :, None] * lam_grad[:, None, i]
    for e, (a, b) in enumerate(P2_EDGES):  # 4 λ_a λ_b
        out[:, :, 3 + e] = 4.0 * (
            bary[None, :, b, None] * lam_grad[:, None, a]
            + bary[None, :, a, None] * lam_grad[:, None, b]
        )
    return out


#: Edge midpoints in barycentric coordinates, with equal weights 1/3: exact for quadratics.
MIDPOINTS = np.array([[0.0, 0.5, 0.5], [0.5, 0.0, 0.5], [0.5, 0.5, 0.0]])


def strain_operator(spec: ElementSpec, x: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """Strain operator at barycentric points: ε = B d for the cell DOFs d.

    Args:
        spec: the element; linear Lagrange (CST) when ``spec.kinematics`` is None, else
            the vertex-DOF field of :data:`~geofrac.elements.kinematics.KINDS`.
        x: vertex coordinates, shape=(nc, 3, 2).
        bary: barycentric coordinates of the points, shape=(nq, 3).

    Returns:
        B, shape=(nc, nq, 3, 3 bs).
    """
    lam_grad, _ = _barycentric_gradients(x)
    if spec.kinematics is None:
        B = _voigt(lam_grad)[:, None]
        return np.broadcast_to(B, (len(x), len(bary), 3, 6))
    kind = KINDS[spec.kinematics]
    T = local_prolongation(kind, x, P2_EDGES)  # shape=(nc, 6, 2, 3, bs)
    T = T.reshape(len(x), 12, 3 * kind.block_size)  # rows (node, comp), cols (vertex, dof)
    return _voigt(_p2_gradients(lam_grad, bary)) @ T[:, None]


def fe_matrices(
    spec: ElementSpec, x: np.ndarray, D: np.ndarray, *, thickness: float, penalty: float = 0.0
) -> np.ndarray:
    """Stiffness matrices of intact cells.

    Args:
        spec: the element (see :func:`strain_operator`).
        x: vertex coordinates, shape=(nc, 3, 2).
        D: stress-strain matrix (Voigt, engineering shear), shape=(3, 3).
        thickness: t.
        penalty: α μ of the zero-mode penalty (vertex-DOF fields; ignored for CST).

    Returns:
        K_e with DOFs vertex by vertex, shape=(nc, 3 bs, 3 bs).
    """
    _, area = _barycentric_gradients(x)
    B = strain_operator(spec, x, MIDPOINTS)  # shape=(nc, 3, 3, n)
    w = thickness * area / 3.0
    K = np.einsum("c,cqip,ij,cqjr->cpr", w, B, D, B)
    if spec.kinematics is None or penalty == 0.0:
        return K
    kind = KINDS[spec.kinematics]
    gdim, bs = 2, kind.block_size
    lam_grad, _ = _barycentric_gradients(x)
    T = local_prolongation(kind, x, P2_EDGES).reshape(len(x), 12, 3 * bs)
    grad_u = _p2_gradients(lam_grad, MIDPOINTS)  # shape=(nc, nq, 6, 2)
    for c, E in enumerate(kind.basis):
        norm2 = float(np.sum(E * E))
        # d_c(u) = ½ <E, ∇u> / |E|² as a row acting on P2 DOFs (node, comp)
        dcu = 0.5 / norm2 * np.einsum("rs,cqns->cqnr", E, grad_u).reshape(len(x), 3, 12)
        d = dcu @ T  # shape=(nc, nq, 3 bs)
        g = np.zeros((len(x), 3, 3 * bs))  # g_c at the midpoints: P1 interpolation
        for v in range(3):
            g[:, :, v * bs + gdim + c] = MIDPOINTS[:, v]
        r = g - d
        K += penalty * thickness * norm2 * np.einsum("c,cqp,cqr->cpr", area / 3.0, r, r)
    return K


def fe_stresses(spec: ElementSpec, x: np.ndarray, dofs: np.ndarray, *, D: np.ndarray) -> np.ndarray:
    """Stress (σ_xx, σ_yy, σ_xy) of intact cells at their three edge midpoints.

    Args:
        spec: the element (see :func:`strain_operator`).
        x: vertex coordinates, shape=(nc, 3, 2).
        dofs: cell DOFs vertex by vertex, shape=(nc, 3 bs).
        D: stress-strain matrix, shape=(3, 3).

    Returns:
        shape=(nc, 3, 3): [cell, local edge j (opposite vertex j), component].
    """
    B = strain_operator(spec, x, MIDPOINTS)  # point q is the midpoint of edge q
    return np.einsum("ij,cqjp,cp->cqi", D, B, dofs)


def mls_matrix(fit: LinearFit, D: np.ndarray, thickness: float, *, area: float) -> np.ndarray:
    """Stiffness (2.19) of a cracked cell on its satellites' translations, shape=(2n, 2n)."""
    B = strain_matrix(fit)
    return thickness * area * B.T @ D @ B


def principal_max(s: np.ndarray) -> np.ndarray:
    """Largest in-plane principal stress of (σ_xx, σ_yy, σ_xy), shape=(..., 3) -> (...)."""
    c = 0.5 * (s[..., 0] + s[..., 1])
    r = np.hypot(0.5 * (s[..., 0] - s[..., 1]), s[..., 2])
    return c + r


class MlsTable:
    """Strain operators of MLS cells in padded arrays, for vectorised stresses and energies.

    Row r holds one cell: its DOFs padded with ``n_dofs`` (an index whose value the
    caller sets to 0 by appending a zero to u), its B of (2.19) padded with zero columns,
    and t · area. Rows of removed cells are recycled.

    Args:
        n_dofs: number of global DOFs (the padding index).
    """

    def __init__(self, n_dofs: int) -> None:
        self.n_dofs = n_dofs
        self.row: dict[int, int] = {}
        self._free: list[int] = []
        self.cells = np.zeros(0, dtype=np.int64)  # shape=(rows,); -1 for a free row
        self.dofs = np.zeros((0, 0), dtype=np.int64)  # shape=(rows, width)
        self.B = np.zeros((0, 3, 0))  # shape=(rows, 3, width)
        self.weight = np.zeros(0)  # t · area, 0 for a free row, shape=(rows,)

    def _grow(self, rows: int, width: int) -> None:
        r0, w0 = self.dofs.shape
        rows, width = max(rows, r0), max(width, w0)
        if (rows, width) == (r0, w0):
            return
        dofs = np.full((rows, width), self.n_dofs, dtype=np.int64)
        dofs[:r0, :w0] = self.dofs
        B = np.zeros((rows, 3, width))
        B[:r0, :, :w0] = self.B
        self.dofs, self.B = dofs, B
        self.cells = np.concatenate([self.cells, np.full(rows - r0, -1, dtype=np.int64)])
        self.weight = np.concatenate([self.weight, np.zeros(rows - r0)])
        self._free += list(range(rows - 1, r0 - 1, -1))

    def set(self, cell: int, dofs: np.ndarray, B: np.ndarray, *, weight: float) -> None:
        """Put (or replace) a cell: DOFs shape=(p,), B shape=(3, p)."""
        if cell in self.row:
            r = self.row[cell]
        else:
            if not self._free:
                self._grow(max(16, 2 * len(self.cells)), 0)
            r = self._free.pop()
            self.row[cell] = r
        if len(dofs) > self.dofs.shape[1]:
            self._grow(0, len(dofs))
        self.dofs[r] = self.n_dofs
        self.dofs[r, : len(dofs)] = dofs
        self.B[r] = 0.0
        self.B[r, :, : len(dofs)] = B
        self.weight[r] = weight
        self.cells[r] = cell

    def remove(self, cell: int) -> None:
        """Drop a cell (it uses its element again, or became void)."""
        r = self.row.pop(cell, None)
        if r is not None:
            self.cells[r] = -1
            self.weight[r] = 0.0
            self.B[r] = 0.0
            self.dofs[r] = self.n_dofs
            self._free.append(r)

    def strains(self, u_ext: np.ndarray) -> np.ndarray:
        """Constant strain of every row; u_ext has a trailing 0, shape=(rows, 3)."""
        if not len(self.cells):
            return np.zeros((0, 3))
        return np.einsum("rip,rp->ri", self.B, u_ext[self.dofs])
