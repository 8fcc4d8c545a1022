"""EFMM on DOLFINx: C cell kernels through the custom-integral hook, PETSc condensation.

The displacement is the CST field (P1, block size 2). Node i's stress field is
σ = P_i(x) e_i with 9 coefficients e_i (Edo (2016), eq. 3.2b), so the stress coefficients form
a vertex field E (P1, block size 9). The compiled kernels of :mod:`geofrac.kernels`
(``efmm.c``) integrate, cell by cell, each of the cell's three nodes' share of

    A_i = ∫_Ω_i Pᵀ D⁻¹ P dΩ  (eq. 3.4a),   C_i = ∫_Ω_i Pᵀ B dΩ  (eq. 3.4b)

over the part of the node's integration domain Ω_i inside the cell (Fig. 3.3). A_i couples
node i's coefficients only with themselves, so it is assembled as a vertex vector of
9 × 9 blocks (block size 81), summed over ranks by the vector's ghost update and inverted
block by block; C is a PETSc matrix from E to the displacement DOFs. The node stiffness
summed over nodes, K = Σ_i C_iᵀ A_i⁻¹ C_i (eq. 3.6), is then K = Cᵀ A⁻¹ C, one
``MatPtAP`` with A⁻¹ block diagonal. Every step is cell-local or node-local, so this runs
in parallel with no communication but PETSc's assembly and one ghost update.

The integration domains need, per cell, its inner point and the crossings X on its three
edges; X depends on the inner points of the two cells sharing the edge, which are
exchanged through a facet vector (:func:`domain_data`), so no ghost cells are needed.
The pure-numpy reference of the same stiffness is :mod:`geofrac.elements.efmm_numpy`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac import kernels
from geofrac.elements.base import Element
from geofrac.elements.efmm_numpy import edge_crossings
from geofrac.errors import RunError
from geofrac.geometry.triangles import inner_points
from geofrac.solvers import Matrix, assemble_matrix, block_diagonal, function_vector

__all__ = ["DomainData", "EfmmElement", "domain_data", "efmm"]

#: Values per cell of the domain coefficient: the inner point, then X_0, X_1, X_2.
DOMAIN_SIZE = 8


@dataclass
class DomainData:
    """The integration domains of this rank's cells (owned, then ghost).

    Attributes:
        values: per cell the inner point p and the crossings X_k on the edge opposite
            local vertex k, shape=(num_cells, 8) as (p, X_0, X_1, X_2).
        length: the length h that scales the stress basis (the same on every rank).
        clamped: global number of edges whose crossing was clamped onto the edge.
    """

    values: np.ndarray
    length: float
    clamped: int


def _cells(mesh: dolfinx.mesh.Mesh) -> tuple[int, int, np.ndarray]:
    """(owned cells, local cells, geometry nodes per cell shape=(num_local, 3))."""
    imap = mesh.topology.index_map(2)
    nc = imap.size_local + imap.num_ghosts
    return imap.size_local, nc, mesh.geometry.dofmaps[0][:nc]


def domain_data(mesh: dolfinx.mesh.Mesh, q_rand: float, seed: int) -> DomainData:
    """Inner points and edge crossings of every local cell (collective).

    Inner points are seeded by the cell's corner coordinates
    (:func:`~geofrac.geometry.triangles.coordinate_keys`) and see the corners in
    input-vertex order, and every edge is oriented by its input vertex ids, so the domains
    are the same on any number of ranks and however the mesh numbers its nodes and cells.
    Each owned cell writes its inner point into the slot of its
    side (left or right of the oriented edge) of a facet vector; one reverse and one
    forward ghost update give every rank both points of every edge it touches.

    Raises:
        RunError: two cells lie on the same side of an edge (an inverted or overlapping
            mesh), on every rank.
    """
    topology, geometry = mesh.topology, mesh.geometry
    num_owned, nc, nodes = _cells(mesh)
    x = geometry.x[nodes][:, :, :2]  # shape=(nc, 3, 2)
    gid = np.asarray(geometry.input_global_indices, dtype=np.int64)[nodes]
    order = np.argsort(gid, axis=1)
    inner = inner_points(
        np.take_along_axis(x, order[:, :, None], axis=1),
        None,
        "random" if q_rand > 0 else "incentre",
        radius=q_rand,
        convex=False,
        seed=seed,
    )
    topology.create_entities(1)
    topology.create_connectivity(2, 1)
    c2f = topology.connectivity(2, 1).array.reshape(-1, 3)[:nc]
    k = np.arange(3)
    ia, ib = (k + 1) % 3, (k + 2) % 3  # facet k is opposite vertex k
    swap = gid[:, ia] > gid[:, ib]  # orient every edge from its smaller input id
    lo = np.where(swap, ib[None, :], ia[None, :])
    hi = np.where(swap, ia[None, :], ib[None, :])
    x_lo = np.take_along_axis(x, lo[:, :, None], axis=1)  # shape=(nc, 3, 2)
    x_hi = np.take_along_axis(x, hi[:, :, None], axis=1)
    e, r = x_hi - x_lo, x - x_lo
    left = e[..., 0] * r[..., 1] - e[..., 1] * r[..., 0] > 0  # the cell's side of edge k
    fmap = topology.index_map(1)
    slots = dolfinx.la.vector(fmap, 6)  # left point, right point, left count, right count
    arr = slots.array.reshape(-1, 6)
    f = c2f[:num_owned].ravel()
    side = left[:num_owned].ravel()
    p = np.repeat(inner[:num_owned], 3, axis=0)
    for s, (cols, count) in enumerate(((slice(0, 2), 4), (slice(2, 4), 5))):
        mine = side if s == 0 else ~side
        np.add.at(arr[:, cols], f[mine], p[mine])
        np.add.at(arr[:, count], f[mine], 1.0)
    slots.scatter_reverse(dolfinx.la.InsertMode.add)
    slots.scatter_forward()
    bad = int(np.count_nonzero(arr[: fmap.size_local, 4:] > 1.5))
    bad = mesh.comm.allreduce(bad, op=MPI.SUM)
    if bad:
        raise RunError(
            f"efmm: {bad} mesh edge(s) have two cells on the same side (inverted or "
            "overlapping triangles)"
        )
    shared = arr[c2f, 4] + arr[c2f, 5] > 1.5  # shape=(nc, 3)
    cross = 0.5 * (x_lo + x_hi)  # boundary edges: the midpoint
    xs, clamped = edge_crossings(
        x_lo[shared], x_hi[shared], left=arr[c2f[shared], 0:2], right=arr[c2f[shared], 2:4]
    )
    cross[shared] = xs
    flags = np.zeros(fmap.size_local + fmap.num_ghosts)
    flags[c2f[shared][clamped]] = 1.0
    n_clamped = mesh.comm.allreduce(int(flags[: fmap.size_local].sum()), op=MPI.SUM)
    d = x[:num_owned, 1:] - x[:num_owned, :1]
    area = 0.5 * np.abs(d[:, 0, 0] * d[:, 1, 1] - d[:, 0, 1] * d[:, 1, 0]).sum()
    total = mesh.comm.allreduce(float(area), op=MPI.SUM)
    count = mesh.comm.allreduce(num_owned, op=MPI.SUM)
    length = float(np.sqrt(2.0 * total / max(count, 1)))
    values = np.concatenate([inner, cross.reshape(nc, 6)], axis=1)
    return DomainData(values=values, length=length, clamped=n_clamped)


def _form(spaces: list[Any], function: str, coefficient: Any, constant: Any) -> dolfinx.fem.Form:
    """A DOLFINx form whose cell integral over the owned cells is a kernel of efmm.c."""
    mesh = spaces[0].mesh
    module = kernels.load("efmm", mesh.comm)
    cells = np.arange(mesh.topology.index_map(2).size_local, dtype=np.int32)
    integrals = {
        dolfinx.fem.IntegralType.cell: [
            (0, kernels.address(module, function), cells, np.array([0], dtype=np.int8))
        ]
    }
    cpp = dolfinx.cpp.fem.Form_float64(
        [V._cpp_object for V in spaces],
        integrals,
        [coefficient._cpp_object],
        [constant._cpp_object],
        False,
        [],
        mesh._cpp_object,
    )
    return dolfinx.fem.Form(cpp)


@dataclass
class EfmmElement(Element):
    """EFMM: CST displacement, one linear stress field per node patch (Edo (2016), §3.2).

    Call :meth:`setup` with the material before :meth:`stiffness`.

    Attributes:
        stress_space: the stress coefficients e, P1 with block size 9 (σx, σy, τxy) x
            (1, (x - x_i)/h, (y - y_i)/h).
        domains: the integration domains (after :meth:`setup`).
        D: the stress-strain matrix, shape=(3, 3), Voigt with engineering shear.
    """

    stress_space: Any = None
    domains: DomainData | None = None
    D: np.ndarray | None = None
    _Ainv: Matrix | None = field(default=None, repr=False)
    _C: Matrix | None = field(default=None, repr=False)

    def setup(self, D: np.ndarray, q_rand: float = 0.0, seed: int = 0) -> None:
        """Build the domains, compile the kernels, assemble C and A⁻¹ (collective)."""
        self.destroy()
        mesh = self.space.mesh
        self.D = np.asarray(D, dtype=float)
        self.domains = domain_data(mesh, q_rand, seed)
        W = dolfinx.fem.functionspace(mesh, ("DG", 0, (DOMAIN_SIZE,)))
        w = dolfinx.fem.Function(W, name="efmm_domain")
        _, nc, _ = _cells(mesh)
        w.x.array.reshape(-1, DOMAIN_SIZE)[W.dofmap.list[:nc, 0]] = self.domains.values
        c = dolfinx.fem.Constant(
            mesh, np.concatenate([np.linalg.inv(self.D).ravel(), [self.domains.length]])
        )
        E = self.stress_space
        S = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (81,)))
        mass = dolfinx.fem.assemble_vector(_form([S], "efmm_stress_mass", w, c))
        mass.scatter_reverse(dolfinx.la.InsertMode.add)
        coupling = _form([E, self.space], "efmm_coupling", w, c)
        self._C = assemble_matrix(coupling)
        # S and E number vertices alike in practice; map through the cell dofmaps anyway
        n = E.dofmap.index_map.size_local
        to_e = np.empty(S.dofmap.index_map.size_local + S.dofmap.index_map.num_ghosts, np.int64)
        to_e[S.dofmap.list.ravel()] = E.dofmap.list.ravel()
        blocks = np.empty((n, 9, 9))
        owned = np.flatnonzero(to_e[: S.dofmap.index_map.size_local] < n)
        blocks[to_e[owned]] = mass.array.reshape(-1, 9, 9)[owned]
        self._Ainv = block_diagonal(np.linalg.inv(blocks), E)

    def stiffness(self) -> Matrix:
        """K = Cᵀ A⁻¹ C on the displacement DOFs (a new matrix; the caller destroys it)."""
        if self._C is None or self._Ainv is None:
            raise RuntimeError("EfmmElement.setup() must be called before stiffness()")
        K = self._Ainv.ptap(self._C)
        K.setBlockSize(2)
        return K

    def stress_coefficients(self, u: dolfinx.fem.Function) -> dolfinx.fem.Function:
        """E = A⁻¹ C u: each node's stress coefficients (eq. 3.3), ghosts updated."""
        if self._C is None or self._Ainv is None:
            raise RuntimeError("EfmmElement.setup() must be called first")
        e = dolfinx.fem.Function(self.stress_space, name="stress_coefficients")
        y = self._C.createVecLeft()
        try:
            self._C.mult(function_vector(u), y)
            self._Ainv.mult(y, function_vector(e))
        finally:
            y.destroy()
        e.x.scatter_forward()
        return e

    def destroy(self) -> None:
        """Free the PETSc matrices C and A⁻¹."""
        for M in (self._C, self._Ainv):
            if M is not None:
                M.destroy()
        self._C = self._Ainv = None


def efmm(mesh: dolfinx.mesh.Mesh) -> EfmmElement:
    """The EFMM element on a mesh of straight-sided triangles.

    Raises:
        ValueError: the mesh is not made of linear triangles.
    """
    if mesh.topology.cell_type != dolfinx.mesh.CellType.triangle:
        raise ValueError(f"efmm needs triangles, not {mesh.topology.cell_type.name}")
    if mesh.geometry.dofmaps[0].shape[1] != 3:
        raise ValueError("efmm needs a linear (straight-sided) triangle mesh")
    space = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (2,)))
    stress = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (9,)))
    return EfmmElement(name="efmm", space=space, degree=1, stress_space=stress)
