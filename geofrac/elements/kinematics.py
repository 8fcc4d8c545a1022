"""Vertex-gradient-DOF fields of RGNT, GNT and RGNQ as maps onto P2 (pure numpy, no MPI).

The three elements of Edo (2016) share one displacement field,

    u(x) = Σ_i N_i(x) (u_i + G_i (x - x_i)),                                   (*)

with N_i the linear (CST / linear tet) shape functions and G_i a gdim × gdim matrix of
vertex DOFs spanned by fixed basis matrices E_c: G_i = Σ_c g_ic E_c.

- RGNT, eq. (2.1): G = θ [[0, -1], [1, 0]] (one drilling DOF θ per vertex).
- GNT, eq. (2.29): G = θ [[0, -1], [1, 0]] + [[εx, γxy/2], [γxy/2, εy]].
- RGNQ, eq. (2.5): G r = θ × r (three rotations θx, θy, θz per vertex).

Every term N_i (x - x_i) is quadratic and vanishes at the vertices, so (*) is a P2
field. Its value at vertex i is u_i and at the midpoint of edge (a, b)

    u(m_ab) = ½ (u_a + u_b) + ¼ (G_a - G_b)(x_b - x_a),                          (**)

which depends on the edge alone: the field is conforming, and the P2 nodal values are a
sparse linear map T of the vertex DOFs (the stiffness is K = Tᵀ K_P2 T). Two facts
follow from (**) and drive the zero-mode treatment and the boundary conditions
(docs/elements.md):

- a constant G (the same at every vertex) moves no P2 node: 1 spurious zero-energy mode
  for RGNT, 3 for RGNQ, 4 for GNT, on top of the rigid body modes;
- a quadratic field u is reproduced with G_i = ½ Π(∇u(x_i)), Π the orthogonal projection
  onto span(E_c) (GNT reproduces every quadratic; RGNT and RGNQ those whose gradient
  jumps fit their span). The vertex DOFs are therefore *half* the nodal rotation/strain,
  not the rotation itself: :func:`dofs_from_gradient` gives that value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "KINDS",
    "GradientDofKind",
    "condition_functionals",
    "constrained_bases",
    "dofs_from_gradient",
    "local_prolongation",
    "symmetry_functionals",
    "vertex_field",
]

_J = np.array([[0.0, -1.0], [1.0, 0.0]])


@dataclass(frozen=True)
class GradientDofKind:
    """One vertex-DOF layout.

    Attributes:
        name: element name.
        gdim: geometric dimension.
        names: names of the extra DOFs per vertex, shape=(k,).
        basis: the matrices E_c, shape=(k, gdim, gdim); mutually orthogonal.
    """

    name: str
    gdim: int
    names: tuple[str, ...]
    basis: np.ndarray

    @property
    def block_size(self) -> int:
        """DOFs per vertex: gdim translations followed by the k extra DOFs."""
        return self.gdim + len(self.names)

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Names of all DOFs of a vertex in block order, shape=(block_size,)."""
        return ("ux", "uy", "uz")[: self.gdim] + self.names

    @property
    def basis_norms2(self) -> np.ndarray:
        """Squared Frobenius norms |E_c|², shape=(k,)."""
        return np.einsum("cij,cij->c", self.basis, self.basis)


def _rgnq_basis() -> np.ndarray:
    basis = np.zeros((3, 3, 3))
    for c in range(3):  # E_c r = e_c × r
        for j in range(3):
            basis[c, :, j] = np.cross(np.eye(3)[c], np.eye(3)[j])
    return basis


#: name -> vertex DOF layout.
KINDS: dict[str, GradientDofKind] = {
    "rgnt": GradientDofKind("rgnt", 2, ("theta",), _J[None]),
    "gnt": GradientDofKind(
        "gnt",
        2,
        ("theta", "ex", "ey", "gxy"),
        np.array(
            [_J, [[1.0, 0.0], [0.0, 0.0]], [[0.0, 0.0], [0.0, 1.0]], [[0.0, 0.5], [0.5, 0.0]]]
        ),
    ),
    "rgnq": GradientDofKind("rgnq", 3, ("theta_x", "theta_y", "theta_z"), _rgnq_basis()),
}


def dofs_from_gradient(kind: GradientDofKind, grad: np.ndarray) -> np.ndarray:
    """Extra vertex DOFs g_c = ½ <E_c, ∇u> / |E_c|² that reproduce a quadratic field.

    For RGNT this is θ = ½ ω with ω = ½ (∂v/∂x - ∂u/∂y) the rotation; for GNT also
    εx = ½ ∂u/∂x, εy = ½ ∂v/∂y, γxy = ½ (∂u/∂y + ∂v/∂x); for RGNQ θ = ½ ω (vector).

    Args:
        kind: the DOF layout.
        grad: displacement gradients ∂u_r/∂x_s, shape=(n, gdim, gdim).

    Returns:
        extra DOFs, shape=(n, k).
    """
    return 0.5 * np.einsum("cij,nij->nc", kind.basis, grad) / kind.basis_norms2


def local_prolongation(kind: GradientDofKind, coords: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Per-cell map from vertex DOFs to P2 nodal values, eq. (**) of this module.

    Args:
        kind: the DOF layout.
        coords: vertex coordinates of each cell, shape=(num_cells, nv, gdim).
        edges: local vertex pairs of the cell's edges in P2 node order (basix),
            shape=(ne, 2).

    Returns:
        T_loc with T_loc[c, node, r, i, d] the weight of DOF d of local vertex i in
        component r of P2 node ``node`` (vertices first, then edges),
        shape=(num_cells, nv + ne, gdim, nv, block_size).
    """
    nc, nv, gdim = coords.shape
    ne, bs = len(edges), kind.block_size
    T = np.zeros((nc, nv + ne, gdim, nv, bs))
    for i in range(nv):
        T[:, i, np.arange(gdim), i, np.arange(gdim)] = 1.0
    for e, (a, b) in enumerate(edges):
        node = nv + e
        T[:, node, np.arange(gdim), a, np.arange(gdim)] = 0.5
        T[:, node, np.arange(gdim), b, np.arange(gdim)] = 0.5
        t = coords[:, b] - coords[:, a]  # shape=(nc, gdim)
        w = 0.25 * np.einsum("crs,ns->nrc", kind.basis, t)  # ¼ E_c (x_b - x_a)
        T[:, node, :, a, gdim:] = w
        T[:, node, :, b, gdim:] = -w
    return T


def vertex_field(
    kind: GradientDofKind, coords: np.ndarray, dofs: np.ndarray, *, points: np.ndarray
) -> np.ndarray:
    """Evaluate the field (*) on one cell directly (a reference for tests).

    Args:
        kind: the DOF layout.
        coords: the cell's vertex coordinates, shape=(nv, gdim).
        dofs: the cell's vertex DOFs, shape=(nv, block_size).
        points: evaluation points inside the cell, shape=(n, gdim).

    Returns:
        displacement, shape=(n, gdim).
    """
    nv, gdim = coords.shape
    M = np.vstack([coords.T, np.ones(nv)])  # barycentric coordinates, Edo (2016), eq. (2.9)
    rhs = np.vstack([points.T, np.ones(len(points))])
    N = np.linalg.solve(M, rhs).T  # shape=(n, nv)
    G = np.einsum("ic,crs->irs", dofs[:, gdim:], kind.basis)  # shape=(nv, gdim, gdim)
    rel = points[:, None, :] - coords[None, :, :]  # shape=(n, nv, gdim)
    local = dofs[None, :, :gdim] + np.einsum("irs,nis->nir", G, rel)
    return np.einsum("ni,nir->nr", N, local)


def condition_functionals(
    kind: GradientDofKind, components: tuple[int, ...], tangents: np.ndarray
) -> np.ndarray:
    """What holding components ``components`` at a constant value implies for the DOFs.

    Along a tangent t of the held boundary entity u_c is constant, so t·∇u_c = 0 at the
    vertex, i.e. (G t)_c = Σ_k g_k (E_k t)_c = 0 (Edo (2016), eq. 2.1, 2.5, 2.29 give E_k).
    Each row a of the result is one such functional, a · g = 0.

    Args:
        kind: the DOF layout.
        components: held displacement components, shape=(q,).
        tangents: tangent directions of the entity, shape=(m, gdim).

    Returns:
        functionals, shape=(m * q, k).
    """
    rows = kind.basis[:, list(components), :]  # shape=(k, q, gdim)
    return np.einsum("kcs,ms->mck", rows, tangents).reshape(-1, len(kind.names))


def symmetry_functionals(kind: GradientDofKind, axis: int) -> np.ndarray:
    """What mirror symmetry about the plane x_axis = const implies beyond the held normal.

    The tangential components u_s (s ≠ axis) are even in x_axis, so ∂u_s/∂n = 0 with
    n = e_axis: (G n)_s = Σ_k g_k (E_k)_{s, axis} = 0.

    Returns:
        functionals, shape=(gdim - 1, k).
    """
    others = [s for s in range(kind.gdim) if s != axis]
    return kind.basis[:, others, axis].T.copy()


def constrained_bases(
    gram: np.ndarray, tol: float = 1e-8, floor: float = 1e-12
) -> tuple[np.ndarray, np.ndarray]:
    """Per vertex, an orthonormal DOF basis that separates constrained and free directions.

    The constrained directions span the row space of the vertex's functionals, the range
    of their Gram matrix M = Σ a aᵀ (eigenvalues above ``tol`` times the largest and
    above ``floor``: the functionals are of unit scale, unit tangents and basis entries
    of at most 1, so a functional below 1e-6 is the round-off of a straight line). When
    that space is spanned by coordinate axes of the DOF layout the basis is the identity
    and the constrained DOFs are those axes; otherwise the basis is the eigenvectors,
    constrained ones first.

    Args:
        gram: Gram matrices, shape=(n, k, k) (all zero: nothing constrained).
        tol: relative eigenvalue threshold.
        floor: absolute eigenvalue threshold.

    Returns:
        (Q, fixed): Q orthogonal with the new DOF directions as columns, shape=(n, k, k);
        fixed[i, j] whether new DOF j of vertex i is held at 0, shape=(n, k).
    """
    n, k, _ = gram.shape
    Q = np.broadcast_to(np.eye(k), (n, k, k)).copy()
    fixed = np.zeros((n, k), dtype=bool)
    if n == 0:
        return Q, fixed
    lam, vec = np.linalg.eigh(gram)  # ascending
    lam, vec = lam[:, ::-1], vec[:, :, ::-1]  # descending: constrained first
    top = lam[:, :1]
    cons = (lam > tol * top) & (lam > floor)
    proj = np.einsum("nij,nkj,nj->nik", vec, vec, cons.astype(float))  # projector on the span
    diag = np.round(np.einsum("nii->ni", proj))
    aligned = np.abs(proj - np.einsum("ni,ij->nij", diag, np.eye(k))).max(axis=(1, 2)) < 1e-10
    fixed[aligned] = diag[aligned] == 1.0
    Q[~aligned] = vec[~aligned]
    fixed[~aligned] = cons[~aligned]
    return Q, fixed
