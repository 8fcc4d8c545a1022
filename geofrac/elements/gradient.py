"""RGNT, GNT and RGNQ on DOLFINx: vertex DOFs, the vertex-to-P2 map T in PETSc, reduction.

The unknowns live in a P1 space W with block size gdim + k (translations, then the k
extra DOFs of :mod:`geofrac.elements.kinematics`); the displacement is the P2 field
u = T w. UFL forms are compiled and assembled on P2 (and the penalty between P2 and W,
:mod:`geofrac_forms.gradient_dofs`); PETSc then forms K = Tᵀ A T + ... with ``PtAP``.
T is built once per mesh from the cell dofmaps, cell by cell, with no communication
other than PETSc's own assembly of the distributed matrix.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import basix
import dolfinx
import numpy as np

from geofrac.elements.base import Element
from geofrac.elements.kinematics import (
    KINDS,
    GradientDofKind,
    condition_functionals,
    dofs_from_gradient,
    symmetry_functionals,
)
from geofrac.elements.kinematics import local_prolongation as _local_prolongation
from geofrac.solvers import (
    Matrix,
    NullSpace,
    add_matrix,
    block_diagonal,
    csr_matrix,
    orthonormal_nullspace,
    transposed,
)

__all__ = ["GradientDofElement", "gnt", "rgnq", "rgnt"]


def _owned_global(imap: Any, bs: int, blocks: np.ndarray, comps: np.ndarray) -> np.ndarray:
    """Global unrolled indices block*bs + comp of local blocks (int64)."""
    return imap.local_to_global(blocks.astype(np.int32)).astype(np.int64) * bs + comps


@dataclass
class GradientDofElement(Element):
    """A vertex-DOF element: P2 displacement space plus the space of the unknowns.

    Attributes:
        kind: the vertex DOF layout (RGNT, GNT or RGNQ).
        dof_space: P1 space of the unknowns, block size ``kind.block_size``.
    """

    kind: GradientDofKind = field(default=KINDS["rgnt"])
    dof_space: Any = None
    _T: Matrix | None = field(default=None, repr=False)

    @property
    def unknowns(self) -> Any:
        """The space of the unknowns, W."""
        return self.dof_space

    def prolongation(self) -> Matrix:
        """T: W → V (P2), shape=(num P2 DOFs, num vertex DOFs); built on first use.

        Each owned P2 node row is filled from a cell that contains it; an edge shared by
        several cells gives the same row from each (eq. (**) of the kinematics module
        depends on the edge alone), so duplicates are dropped, not summed.
        """
        if self._T is not None:
            return self._T
        V, W, kind = self.space, self.dof_space, self.kind
        mesh = V.mesh
        gdim, bs = kind.gdim, kind.block_size
        cell_type = mesh.topology.cell_type
        basix_cell = getattr(basix.CellType, cell_type.name)
        edges = np.array(basix.topology(basix_cell)[1], dtype=np.int64)
        v_dofs = V.dofmap.list.astype(np.int64)  # shape=(num_cells, nv + ne), blocks
        w_dofs = W.dofmap.list.astype(np.int64)  # shape=(num_cells, nv), blocks
        nv = w_dofs.shape[1]
        assert v_dofs.shape[1] == nv + len(edges)  # P2 nodes: vertices, then edges (basix)
        coords = W.tabulate_dof_coordinates()[:, :gdim][w_dofs]  # shape=(nc, nv, gdim)
        T_loc = _local_prolongation(kind, coords, edges)  # shape=(nc, nodes, gdim, nv, bs)
        rows_b = np.broadcast_to(v_dofs[:, :, None, None, None], T_loc.shape)
        rows_c = np.broadcast_to(np.arange(gdim)[None, None, :, None, None], T_loc.shape)
        cols_b = np.broadcast_to(w_dofs[:, None, None, :, None], T_loc.shape)
        cols_c = np.broadcast_to(np.arange(bs)[None, None, None, None, :], T_loc.shape)
        keep = (T_loc != 0.0) & (rows_b < V.dofmap.index_map.size_local)
        vimap, wimap = V.dofmap.index_map, W.dofmap.index_map
        rows = _owned_global(vimap, gdim, rows_b[keep], rows_c[keep])
        cols = _owned_global(wimap, bs, cols_b[keep], cols_c[keep])
        vals = T_loc[keep]
        n_cols_global = wimap.size_global * bs
        _, first = np.unique(rows * n_cols_global + cols, return_index=True)
        rows, cols, vals = rows[first], cols[first], vals[first]  # sorted by (row, col)
        row0 = vimap.local_range[0] * gdim
        n_rows = vimap.size_local * gdim
        indptr = np.searchsorted(rows - row0, np.arange(n_rows + 1))
        T = csr_matrix(
            mesh.comm,
            ((n_rows, vimap.size_global * gdim), (wimap.size_local * bs, n_cols_global)),
            (indptr, cols, vals),
        )
        self._T = T
        return T

    def reduce(self, A_vv: Matrix, A_wv: Matrix, A_ww: Matrix) -> Matrix:
        """K = Tᵀ A_vv T + A_wv T + (A_wv T)ᵀ + A_ww (a new matrix on W).

        Args:
            A_vv: P2 stiffness plus the penalty's P2 part, shape=(nV, nV).
            A_wv: penalty coupling, rows W, columns V, shape=(nW, nV).
            A_ww: penalty on the extra DOFs, shape=(nW, nW).
        """
        T = self.prolongation()
        K = A_vv.ptap(T)
        C = A_wv.matMult(T)
        Ct = transposed(C)
        try:
            for M in (C, Ct, A_ww):
                add_matrix(K, M)
        finally:
            C.destroy()
            Ct.destroy()
        K.assemble()
        return K

    def vertex_constraints(
        self,
        dim: int,
        entities: np.ndarray,
        values: Callable[[np.ndarray], np.ndarray],
        *,
        components: tuple[int, ...],
    ) -> tuple[np.ndarray, np.ndarray]:
        """Owned constrained DOFs on the vertices of mesh entities and their values.

        Args:
            dim: entity dimension.
            entities: local entity indices, shape=(n,).
            values: coordinates, shape=(m, 3) -> all vertex DOF values,
                shape=(m, block_size).
            components: the constrained DOF components (block positions).

        Returns:
            (global DOF indices, shape=(p,), values, shape=(p,)).
        """
        W, bs = self.dof_space, self.kind.block_size
        blocks = dolfinx.fem.locate_dofs_topological(W, dim, entities)
        blocks = blocks[blocks < W.dofmap.index_map.size_local].astype(np.int64)
        x = W.tabulate_dof_coordinates()[blocks]
        vals = np.asarray(values(x), dtype=float).reshape(len(blocks), bs)
        comps = np.asarray(components, dtype=np.int64)
        rows = _owned_global(
            W.dofmap.index_map, bs, np.repeat(blocks, len(comps)), np.tile(comps, len(blocks))
        )
        return rows, vals[:, comps].ravel()

    def vertex_blocks(self, dim: int, entities: np.ndarray) -> np.ndarray:
        """W blocks (local, ghosts included) of the vertices of mesh entities.

        Args:
            dim: entity dimension.
            entities: local entity indices, shape=(n,).

        Returns:
            blocks, shape=(n, dim + 1), in the entity's vertex order.
        """
        topology = self.dof_space.mesh.topology
        tdim = topology.dim
        topology.create_connectivity(dim, 0)
        topology.create_connectivity(tdim, 0)
        c2v = topology.connectivity(tdim, 0)
        num_vertices = topology.index_map(0).size_local + topology.index_map(0).num_ghosts
        block_of = np.empty(num_vertices, dtype=np.int64)
        block_of[c2v.array] = self.dof_space.dofmap.list.ravel()  # P1: one block per vertex
        e2v = topology.connectivity(dim, 0).array.reshape(-1, dim + 1)  # simplices
        return block_of[e2v[entities]]

    def boundary_gram(
        self, conditions: list[tuple[int, np.ndarray, tuple[int, ...], int | None]]
    ) -> np.ndarray:
        """Gram matrices of the functionals conditions impose on the extra DOFs (collective).

        Each condition holds ``components`` constant on the entities: along every edge
        direction t of an entity, (G t)_c = 0 at its vertices
        (:func:`~geofrac.elements.kinematics.condition_functionals`); a mirror-symmetry
        condition about the plane normal to ``axis`` adds (G e_axis)_s = 0 for s ≠ axis
        (:func:`~geofrac.elements.kinematics.symmetry_functionals`). A vertex of no entity
        of dimension ≥ 1 gets nothing. Contributions are summed over the entities of
        every rank onto the vertex owner (a vertex seen twice only scales its Gram matrix,
        which leaves its range unchanged), so 1 and 2 ranks agree.

        Args:
            conditions: (entity dimension, local entities shape=(n,), held components,
                symmetry axis or None) per condition.

        Returns:
            M_i = Σ a aᵀ per owned vertex block, shape=(num_owned, k, k).
        """
        W, kind = self.dof_space, self.kind
        gdim, k = kind.gdim, len(kind.names)
        imap = W.dofmap.index_map
        acc = dolfinx.la.vector(imap, bs=k * k)
        local = acc.array.reshape(-1, k, k)
        local[:] = 0.0  # not initialised by dolfinx.la.vector
        x = W.tabulate_dof_coordinates()[:, :gdim]
        for dim, entities, components, axis in conditions:
            if dim == 0 or len(entities) == 0:
                continue
            blocks = self.vertex_blocks(dim, entities)  # shape=(n, dim + 1)
            t = x[blocks[:, 1:]] - x[blocks[:, :1]]  # edges from the first vertex
            t /= np.linalg.norm(t, axis=2, keepdims=True)
            a = condition_functionals(kind, components, t.reshape(-1, gdim))
            a = a.reshape(len(entities), -1, k)  # shape=(n, dim * q, k)
            if axis is not None:
                sym = symmetry_functionals(kind, axis)
                a = np.concatenate([a, np.broadcast_to(sym, (len(entities), *sym.shape))], 1)
            gram = np.einsum("npk,npl->nkl", a, a)  # shape=(n, k, k)
            for j in range(dim + 1):
                np.add.at(local, blocks[:, j], gram)
        acc.scatter_reverse(dolfinx.la.InsertMode.add)
        return local[: imap.size_local].copy()

    def basis_change(self, Q: np.ndarray) -> Matrix:
        """The block-diagonal orthogonal map w = Q h on W (identity on the translations).

        Args:
            Q: per owned vertex, the extra DOFs' new basis, shape=(num_owned, k, k).

        Returns:
            Q as a square AIJ matrix on W (the caller destroys it).
        """
        W, gdim, bs = self.dof_space, self.kind.gdim, self.kind.block_size
        n = W.dofmap.index_map.size_local
        block = np.zeros((n, bs, bs))
        block[:, np.arange(gdim), np.arange(gdim)] = 1.0
        block[:, gdim:, gdim:] = Q
        return block_diagonal(block, W)

    def rigid_body_modes(self, Q: np.ndarray | None = None) -> NullSpace:
        """Orthonormal rigid body modes on W: translations, and rotations with g = ½ Π ω.

        With ``Q`` (per owned vertex, shape=(num_owned, k, k)) the modes are given in the
        DOFs h of the basis w = Q h: h = Qᵀ w on the extra DOFs.
        """
        W, kind = self.dof_space, self.kind
        gdim, bs = kind.gdim, kind.block_size
        n = W.dofmap.index_map.size_local
        x = W.tabulate_dof_coordinates()[:n, :gdim]
        rotations = [(0, 1)] if gdim == 2 else [(0, 1), (1, 2), (2, 0)]
        modes = []
        for i in range(gdim):
            m = np.zeros((n, bs))
            m[:, i] = 1.0
            modes.append(m)
        for a, b in rotations:  # u_a = -x_b, u_b = x_a: gradient e_b ⊗ e_a - e_a ⊗ e_b
            m = np.zeros((n, bs))
            m[:, a], m[:, b] = -x[:, b], x[:, a]
            grad = np.zeros((1, gdim, gdim))
            grad[0, b, a], grad[0, a, b] = 1.0, -1.0
            m[:, gdim:] = dofs_from_gradient(kind, grad)[0]
            modes.append(m)
        if Q is not None:
            for m in modes:
                m[:, gdim:] = np.einsum("nkj,nk->nj", Q, m[:, gdim:])
        return orthonormal_nullspace([m.ravel() for m in modes], W.mesh.comm)

    def destroy(self) -> None:
        """Free T."""
        if self._T is not None:
            self._T.destroy()
            self._T = None


def _make(name: str, mesh: dolfinx.mesh.Mesh) -> GradientDofElement:
    kind = KINDS[name]
    if mesh.geometry.dim != kind.gdim:
        raise ValueError(f"element '{name}' is {kind.gdim}D, the mesh is {mesh.geometry.dim}D")
    V = dolfinx.fem.functionspace(mesh, ("Lagrange", 2, (kind.gdim,)))
    W = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (kind.block_size,)))
    return GradientDofElement(name=name, space=V, degree=2, kind=kind, dof_space=W)


def rgnt(mesh: dolfinx.mesh.Mesh) -> GradientDofElement:
    """Triangle with a drilling DOF per vertex (u, v, θ), Edo (2016), eqs. (2.1)-(2.4)."""
    return _make("rgnt", mesh)


def gnt(mesh: dolfinx.mesh.Mesh) -> GradientDofElement:
    """Triangle with drilling and strain DOFs (u, v, θ, εx, εy, γxy), Edo (2016), eq. (2.29)."""
    return _make("gnt", mesh)


def rgnq(mesh: dolfinx.mesh.Mesh) -> GradientDofElement:
    """Tetrahedron with three rotations per vertex (u, v, w, θx, θy, θz).

    Edo (2016), eqs. (2.5)-(2.8).
    """
    return _make("rgnq", mesh)
