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
from petsc4py import PETSc

from geofrac.elements.base import Element
from geofrac.elements.kinematics import KINDS, GradientDofKind, dofs_from_gradient
from geofrac.elements.kinematics import local_prolongation as _local_prolongation
from geofrac.solvers import orthonormal_nullspace

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
    _T: PETSc.Mat | None = field(default=None, repr=False)

    @property
    def unknowns(self) -> Any:
        """The space of the unknowns, W."""
        return self.dof_space

    def prolongation(self) -> PETSc.Mat:
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
        indptr = np.searchsorted(rows - row0, np.arange(n_rows + 1)).astype(PETSc.IntType)
        T = PETSc.Mat().createAIJ(
            size=((n_rows, vimap.size_global * gdim), (wimap.size_local * bs, n_cols_global)),
            csr=(indptr, cols.astype(PETSc.IntType), vals),
            comm=mesh.comm,
        )
        T.assemble()
        self._T = T
        return T

    def reduce(self, A_vv: PETSc.Mat, A_wv: PETSc.Mat, A_ww: PETSc.Mat) -> PETSc.Mat:
        """K = Tᵀ A_vv T + A_wv T + (A_wv T)ᵀ + A_ww (a new matrix on W).

        Args:
            A_vv: P2 stiffness plus the penalty's P2 part, shape=(nV, nV).
            A_wv: penalty coupling, rows W, columns V, shape=(nW, nV).
            A_ww: penalty on the extra DOFs, shape=(nW, nW).
        """
        T = self.prolongation()
        K = A_vv.ptap(T)
        C = A_wv.matMult(T)
        Ct = C.transpose(PETSc.Mat())  # without an output matrix petsc4py works in place
        try:
            for M in (C, Ct, A_ww):
                K.axpy(1.0, M, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
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

    def rigid_body_modes(self) -> PETSc.NullSpace:
        """Orthonormal rigid body modes on W: translations, and rotations with g = ½ Π ω."""
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
    """Triangle with a drilling DOF per vertex (u, v, θ), seed eq. (2.1)-(2.4)."""
    return _make("rgnt", mesh)


def gnt(mesh: dolfinx.mesh.Mesh) -> GradientDofElement:
    """Triangle with drilling and strain DOFs (u, v, θ, εx, εy, γxy), seed eq. (2.29)."""
    return _make("gnt", mesh)


def rgnq(mesh: dolfinx.mesh.Mesh) -> GradientDofElement:
    """Tetrahedron with three rotations per vertex (u, v, w, θx, θy, θz), seed eq. (2.5)-(2.8)."""
    return _make("rgnq", mesh)
