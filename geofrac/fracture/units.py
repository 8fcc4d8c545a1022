"""The discretisation of the crack state: which units carry stiffness, and their matrices.

A *unit* is what one crack state entry switches between its element field and a fitted
(MLS) field: a triangle for edge cracking (Edo (2016), chapter 2), a node's grain for
grain cracking (chapter 3, :mod:`geofrac.fracture.grain_driver`). The event loop, the
assembly and the solver strategies see the units only through :class:`Units`;
:class:`EdgeUnits` is the edge variant: the element's own cell matrices
(:func:`~geofrac.fracture.cells.fe_matrices` of the :class:`~geofrac.elements.spec.ElementSpec`)
for intact cells, the MLS stiffness (2.19) for cracked ones.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from mpi4py import MPI

from geofrac import kernels
from geofrac.elements.kinematics import KINDS, dofs_from_gradient, vertex_field
from geofrac.errors import RunError
from geofrac.fracture.cells import (
    MIDPOINTS,
    MlsTable,
    fe_matrices,
    mls_matrix,
    principal_max,
    strain_operator,
)
from geofrac.fracture.config import CrackingConfig
from geofrac.fracture.context import CrackContext, JsonValue
from geofrac.fracture.grains import GrainState
from geofrac.fracture.state import CrackState, MlsSettings
from geofrac.fracture.topology import EdgeMesh, edge_mesh
from geofrac.mls.cmulti import NodeFit
from geofrac.mls.shape import LinearFit, strain_matrix

__all__ = [
    "GAUSS_6",
    "Block",
    "EdgeUnits",
    "Fit",
    "SiteState",
    "Units",
    "cell_stresses",
    "cell_stresses_numpy",
    "mls_settings",
    "penalty_of",
    "set_material",
    "unit_masks",
]

#: A unit's fitted field: an MLS fit (cells), a C-MultiMLSM fit (grains), or None (void).
Fit = LinearFit | NodeFit | None

#: The replicated crack state of either variant.
SiteState = CrackState | GrainState

#: (global DOFs, shape=(m,); stiffness, shape=(m, m)) of one unit.
Block = tuple[np.ndarray, np.ndarray]

#: Six-point Gauss rule of degree 4 on a triangle: barycentric points, shape=(6, 3), and
#: weights summing to 1 (multiply by the area).
_A6, _B6 = 0.445948490915965, 0.091576213509771
GAUSS_6 = (
    np.array(
        [
            [_A6, _A6, 1 - 2 * _A6],
            [_A6, 1 - 2 * _A6, _A6],
            [1 - 2 * _A6, _A6, _A6],
            [_B6, _B6, 1 - 2 * _B6],
            [_B6, 1 - 2 * _B6, _B6],
            [1 - 2 * _B6, _B6, _B6],
        ]
    ),
    np.array([0.223381589678011] * 3 + [0.109951743655322] * 3),
)


def cell_stresses_numpy(
    S: np.ndarray, K: np.ndarray, dofs: np.ndarray, *, u: np.ndarray, use: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """Midpoint stresses, σ1 and strain energy of the cells ``use`` (numpy reference).

    Args:
        S: stress operators, shape=(num_cells, 9, nd) (row 3q + i: midpoint q,
            component i of (σ_xx, σ_yy, σ_xy)).
        K: stiffness matrices, shape=(num_cells, nd, nd).
        dofs: the cells' global DOFs, shape=(num_cells, nd).
        u: the global solution, shape=(n_global,).
        use: the cells to evaluate, shape=(num_cells,) bool.

    Returns:
        σ1 per cell and midpoint, shape=(num_cells, 3), the stresses, shape=(num_cells,
        9) (zero for cells not used), and Σ ½ u_cᵀ K_c u_c over the cells used.
    """
    ud = u[dofs[use]]
    sig = np.zeros((len(dofs), 9))
    sig[use] = np.einsum("crp,cp->cr", S[use], ud)
    s1 = np.zeros((len(dofs), 3))
    s1[use] = principal_max(sig[use].reshape(-1, 3, 3))
    energy = 0.5 * float(np.einsum("cp,cpq,cq->", ud, K[use], ud))
    return s1, sig, energy


def cell_stresses(
    S: np.ndarray, K: np.ndarray, dofs: np.ndarray, *, u: np.ndarray, use: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`cell_stresses_numpy` by the compiled kernel ``cellstress`` (one pass)."""
    lib, ffi = (module := kernels.load("cellstress")).lib, module.ffi
    nc, _, nd = S.shape
    S, K = np.ascontiguousarray(S, dtype=float), np.ascontiguousarray(K, dtype=float)
    dofs = np.ascontiguousarray(dofs, dtype=np.int64)
    u = np.ascontiguousarray(u, dtype=float)
    flags = np.ascontiguousarray(use, dtype=np.uint8)
    s1, sig = np.zeros((nc, 3)), np.zeros((nc, 9))
    if not nc:
        return s1, sig, 0.0

    def buf(kind: str, a: np.ndarray) -> Any:
        return ffi.from_buffer(kind, a)

    energy = lib.cell_stresses(
        nc,
        nd,
        buf("int64_t[]", dofs),
        buf("double[]", u),
        buf("double[]", S),
        buf("double[]", K),
        buf("unsigned char[]", flags),
        buf("double[]", s1),
        buf("double[]", sig),
    )
    if not math.isfinite(energy):
        raise RunError(f"cell_stresses: {nd} DOFs per cell exceed the kernel's 64")
    return s1, sig, float(energy)


def unit_masks(
    ctx: CrackContext, mesh_e: EdgeMesh, points: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(frozen, forced) per unit: touching a Dirichlet node / inside ``mls_region``.

    ``points`` locate the units (cell centroids or nodes), shape=(n, 2); ``frozen`` is
    per cell for both variants, shape=(num_cells,).
    """
    frozen = np.isin(ctx.gm.cells, ctx.bc_nodes).any(axis=1)
    forced = np.zeros(len(points), dtype=bool)
    if ctx.config.mls_region is not None:
        x0, y0, x1, y1 = ctx.config.mls_region
        c = points
        forced = (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)
    return frozen, forced


class Units(Protocol):
    """The discretisation of the crack state (cells and MLS, or grains and C-MultiMLSM).

    Attributes:
        state: the replicated crack state.
        own: this rank's units, shape=(k,); owned: per unit, shape=(num_units,) bool.
        rotation: extra vertex DOFs under a unit rigid rotation, shape=(bs - 2,).
    """

    state: SiteState
    own: np.ndarray
    owned: np.ndarray
    rotation: np.ndarray

    def group_sites(self, pairs: np.ndarray) -> np.ndarray:
        """Crack sites of a ``precracked`` facet group of sorted node pairs, shape=(n, 2)."""
        ...

    def intact_coo(self, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """COO (rows, cols, values) of the owned units with ``keep`` (per owned unit)."""
        ...

    def intact_blocks(self, units: list[int]) -> dict[int, Block]:
        """The element-field block of any units, by unit."""
        ...

    def fit_block(self, unit: int, fit: Fit) -> Block | None:
        """The block of ``unit`` under ``fit``; None when it has no stiffness."""
        ...

    def use_counts(self, is_mls: np.ndarray) -> np.ndarray:
        """How many units give stiffness to each DOF, shape=(n_global,) (replicated)."""
        ...

    def links(self, is_mls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Node pairs (a, b) joined by a unit with stiffness: the pieces' graph."""
        ...

    def stiffless_nodes(self) -> np.ndarray:
        """Nodes whose own unit gives no stiffness (held only through others), shape=(k,)."""
        ...

    def measures(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(σ1 of the units at their sites, strain energy, control reaction) of u (collective).

        The σ1 array is what :meth:`~geofrac.fracture.event_criterion.EventCriterion.site_stress`
        reduces to one value per site.
        """
        ...

    def changed(self, units: np.ndarray) -> None:
        """Note units whose field an event changed (cached measures are refreshed)."""
        ...

    def reset(self) -> None:
        """Forget cached measures (the state was rebuilt from a checkpoint)."""
        ...

    def l2_error(self, u: np.ndarray) -> float:
        """||u_h - u_exact||_L2 (2.22), each unit with its own field (collective)."""
        ...

    def state_text(self, precracked: int, random_precracked: int) -> str:
        """The crack state in a few words, for the start-up message."""
        ...

    def site_point(self, site: int) -> np.ndarray:
        """Where crack site ``site`` lies, for the event log, shape=(2,)."""
        ...

    def face_x(self, sites: np.ndarray) -> float | None:
        """X where the crack reaches the ``face`` group with the new ``sites``, or None."""
        ...

    def checkpoint_extra(self) -> dict[str, JsonValue]:
        """JSON-ready state the units keep across events."""
        ...

    def restore_extra(self, extra: dict[str, JsonValue]) -> None:
        """Restore what :meth:`checkpoint_extra` saved."""
        ...

    def results(self, out: dict[str, JsonValue], precracked: int, random_precracked: int) -> None:
        """Add (or replace) the variant's entries of the loop's results, in place.

        The loop's results count sites as edges and fitted units as MLS cells.
        """
        ...


def mls_settings(config: CrackingConfig) -> MlsSettings:
    """The MLS fits' settings of ``[cracking]`` (neighbours, margin, radius factor, gradient)."""
    return MlsSettings(
        config.neighbours, config.margin, config.max_radius_factor, config.mls_gradient
    )


class EdgeUnits:
    """Cells as units: element cells, MLS-cracked cells (2.19) (Edo (2016), chapter 2).

    Args:
        ctx: the shared set-up data.
        mls: the MLS fits' neighbours, margin and radius (``cracking.neighbours``, ...).
        cut: cracks cut the cells they end in (contact, the tip criteria; see
            :class:`~geofrac.fracture.state.CrackState`).
        keep_stress: keep the stress tensors of :meth:`measures` (the shear events and
            the criteria that read them need them).
    """

    def __init__(
        self, ctx: CrackContext, *, mls: MlsSettings, cut: bool, keep_stress: bool
    ) -> None:
        self.ctx = ctx
        gm, spec = ctx.gm, ctx.spec
        #: extra vertex DOFs under a unit rigid rotation, shape=(bs - 2,).
        self.rotation = (
            dofs_from_gradient(KINDS[spec.kinematics], np.array([[[0.0, -1.0], [1.0, 0.0]]]))[0]
            if spec.kinematics is not None
            else np.zeros(0)
        )
        mesh_e = edge_mesh(gm.coords, gm.cells)
        frozen, forced = unit_masks(ctx, mesh_e, mesh_e.centroids())
        self.state: CrackState = CrackState(
            mesh_e,
            frozen,
            forced,
            mls,
            ctx.rank_map,
            cut=cut,
        )
        self._edge_keys = mesh_e.edges[:, 0] * len(gm.coords) + mesh_e.edges[:, 1]
        own = np.flatnonzero(gm.owned)
        self.own = own
        x = gm.coords[gm.cells[own]]
        self.K_fe = fe_matrices(spec, x, ctx.D, thickness=ctx.t, penalty=ctx.penalty)
        self.fe_dofs = ctx.node_dofs(gm.cells[own].ravel()).reshape(len(own), 3 * ctx.bs)
        stress_op = np.einsum("ij,cqjp->cqip", ctx.D, strain_operator(spec, x, MIDPOINTS))
        nc, nd = self.fe_dofs.shape
        # for measures(): the stress at the 3 edge midpoints, shape=(n_own, 9, nd)
        # (row 3q + i: midpoint q, component i)
        self._stress_blocks = np.ascontiguousarray(stress_op.reshape(nc, 9, nd))
        try:  # compiled once, rank 0 first (collective); numpy where it cannot be
            kernels.load("cellstress", ctx.comm)
            self._stresses = cell_stresses
        except RuntimeError as exc:
            ctx.say(f"cracking: element stresses by numpy ({exc})")
            self._stresses = cell_stresses_numpy
        self.owned = np.zeros(len(gm.cells), dtype=bool)
        self.owned[own] = True
        # owned cells (positions in own) with a control DOF: the only ones whose forces
        # enter the reaction, shape=(k,)
        self._reacting = np.flatnonzero(np.any(ctx.control_sign[self.fe_dofs] != 0, axis=1))
        # MLS cells of this rank for the vectorised measures, and cells to refresh
        self._table: MlsTable | None = None
        self._table_dirty: list[int] = []
        # cell -> (its fit, the fit's stiffness): assembly and measures share it
        self._mls_k: dict[int, tuple[LinearFit, np.ndarray]] = {}
        #: keep the stress tensors of :meth:`measures` (shear events need them).
        self.keep_stress = keep_stress
        #: (σ_xx, σ_yy, σ_xy) of each cell at its edge midpoints from the last
        #: :meth:`measures` when ``keep_stress``, shape=(num_cells, 3, 3).
        self.midpoint_stress = np.zeros((0, 3, 3))
        #: each cell's elasticity matrix once :func:`set_material` gave some cells their
        #: own (installed support), shape=(num_cells, 3, 3); None: ``ctx.D`` everywhere.
        self.cell_D: np.ndarray | None = None

    def _D(self, c: int) -> np.ndarray:
        """Cell c's elasticity matrix, shape=(3, 3)."""
        return self.ctx.D if self.cell_D is None else self.cell_D[c]

    # -- sites ------------------------------------------------------------------------
    def group_sites(self, pairs: np.ndarray) -> np.ndarray:
        """Edge ids of sorted node pairs, shape=(n, 2); error if a pair is no edge."""
        keys = pairs[:, 0] * len(self.ctx.gm.coords) + pairs[:, 1]
        idx = np.searchsorted(self._edge_keys, keys)
        idx = np.minimum(idx, len(self._edge_keys) - 1)
        if len(keys) and not np.all(self._edge_keys[idx] == keys):
            raise RunError("cracking.precracked: a tagged facet is not an edge of the mesh")
        return idx

    def site_point(self, site: int) -> np.ndarray:
        """The edge midpoint, shape=(2,)."""
        return self.state.mesh.coords[self.state.mesh.edges[site]].mean(axis=0)

    def face_x(self, sites: np.ndarray) -> float | None:
        """X of the first node of the new crack sites on the ``face`` group, or None."""
        ends = self.state.mesh.edges[sites].ravel()
        hit = ends[np.isin(ends, self.ctx.face_nodes)]
        return float(self.state.mesh.coords[hit[0], 0]) if len(hit) else None

    # -- stiffness ----------------------------------------------------------------------
    def intact_coo(self, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """COO triplets of the owned cells that keep their element field.

        Args:
            keep: per owned cell, shape=(len(own),).
        """
        nd = self.fe_dofs.shape[1]
        rows = np.repeat(self.fe_dofs[keep], nd, axis=1).ravel()
        cols = np.tile(self.fe_dofs[keep], (1, nd)).ravel()
        return rows, cols, self.K_fe[keep].ravel()

    def intact_blocks(self, units: list[int]) -> dict[int, Block]:
        """(DOFs, stiffness) of the element field of any cells, by cell."""
        if not units:
            return {}
        gm, ctx = self.ctx.gm, self.ctx
        x = gm.coords[gm.cells[units]]
        ks = fe_matrices(ctx.spec, x, ctx.D, thickness=ctx.t, penalty=ctx.penalty)
        if self.cell_D is not None:  # installed support: its own D
            for i, c in enumerate(units):
                if not np.array_equal(self.cell_D[c], ctx.D):
                    D = self.cell_D[c]
                    ks[i] = fe_matrices(
                        ctx.spec, x[i : i + 1], D, thickness=ctx.t, penalty=penalty_of(ctx, D)
                    )[0]
        return {c: (ctx.node_dofs(gm.cells[c]), k) for c, k in zip(units, ks, strict=True)}

    def fit_block(self, unit: int, fit: Fit) -> Block | None:
        """(DOFs, stiffness) of cell ``unit`` under an MLS fit; None when void."""
        if fit is None:
            return None
        assert isinstance(fit, LinearFit)
        return self.ctx.mls_dofs(fit.nodes), self._mls_stiffness(unit, fit)

    def _mls_stiffness(self, c: int, fit: LinearFit) -> np.ndarray:
        """Stiffness (2.19) of MLS cell c, computed once per fit (cached for the current one)."""
        cached = self._mls_k.get(c)
        if cached is not None and cached[0] is fit:
            return cached[1]
        k = mls_matrix(fit, self._D(c), self.ctx.t, area=self.state.areas[c])
        if c in self.state.fits and self.state.fits[c] is fit:
            self._mls_k[c] = (fit, k)
        return k

    def use_counts(self, is_mls: np.ndarray) -> np.ndarray:
        """How many cells give stiffness to each global DOF, shape=(n_global,) (replicated)."""
        ctx = self.ctx
        dofs = [ctx.node_dofs(ctx.gm.cells[~is_mls].ravel())]
        dofs += [ctx.mls_dofs(f.nodes) for f in self.state.fits.values() if f is not None]
        return np.bincount(np.concatenate(dofs), minlength=ctx.n_global)

    def links(self, is_mls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Node pairs (a, b) joined by a cell with stiffness: the pieces' graph."""
        a, b = [], []
        for cell in self.ctx.gm.cells[~is_mls]:
            a += [cell[0], cell[0]]
            b += [cell[1], cell[2]]
        for fit in self.state.fits.values():
            if fit is not None and len(fit.nodes) > 1:
                a += [fit.nodes[0]] * (len(fit.nodes) - 1)
                b += list(fit.nodes[1:])
        return np.array(a, dtype=np.int64), np.array(b, dtype=np.int64)

    def stiffless_nodes(self) -> np.ndarray:
        """None: every node of an element cell has stiffness of its cells."""
        return np.zeros(0, dtype=np.int64)

    # -- measures -----------------------------------------------------------------------
    def changed(self, units: np.ndarray) -> None:
        """Refresh these cells' rows of the MLS table at the next :meth:`measures`."""
        self._table_dirty += units.tolist()

    def reset(self) -> None:
        """Rebuild the MLS table at the next :meth:`measures`."""
        self._table, self._table_dirty = None, []

    def _sync_table(self) -> None:
        """Bring the MLS table of the owned cells up to the crack state."""
        state, ctx = self.state, self.ctx
        if self._table is None:
            self._table = MlsTable(ctx.n_global)
            dirty = list(state.fits)
        else:
            dirty, self._table_dirty = self._table_dirty, []
        for c in dirty:
            if not self.owned[c]:
                continue
            fit = state.fits.get(c)
            if fit is None:
                self._table.remove(c)
            else:
                self._table.set(
                    c, ctx.mls_dofs(fit.nodes), strain_matrix(fit), weight=ctx.t * state.areas[c]
                )

    def measures(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(σ1 per cell at its edge midpoints, strain energy, control reaction) of u.

        σ1 has shape=(num_cells, 3) ([cell, local edge j]; an MLS cell's constant value
        on all three). Vectorised over the owned cells: element cells by their stress
        operators and matrices, MLS cells by the padded :class:`MlsTable`. The reaction
        sums the forces f = K u of the cells on the control DOFs (signed by the
        prescribed direction). Collective.
        """
        state, own, ctx = self.state, self.own, self.ctx
        is_mls = state.is_mls()
        s1 = np.zeros((len(ctx.gm.cells), 3))
        u_ext = np.append(u, 0.0)
        fe = ~is_mls[own]
        s1_fe, stress, energy = self._stresses(
            self._stress_blocks, self.K_fe, self.fe_dofs, u=u, use=fe
        )
        s1[own[fe]] = s1_fe[fe]
        full = np.zeros((len(ctx.gm.cells), 3, 3)) if self.keep_stress else None
        if full is not None:
            full[own[fe]] = stress[fe].reshape(-1, 3, 3)
        sign = ctx.control_sign
        r = self._reacting[fe[self._reacting]]
        ku = np.einsum("cpq,cq->cp", self.K_fe[r], u[self.fe_dofs[r]])
        reaction = float(np.sum(ku * sign[self.fe_dofs[r]]))
        self._sync_table()
        table = self._table
        assert table is not None
        eps = table.strains(u_ext)  # shape=(rows, 3)
        if self.cell_D is None:
            sig = eps @ ctx.D.T
        else:  # installed support: each row its cell's D
            sig = np.einsum("rij,rj->ri", self.cell_D[np.maximum(table.cells, 0)], eps)
        live = table.cells >= 0
        s1[table.cells[live]] = principal_max(sig[live])[:, None]
        if full is not None:
            full[table.cells[live]] = sig[live][:, None, :]
            ctx.comm.Allreduce(MPI.IN_PLACE, full, op=MPI.SUM)
            self.midpoint_stress = full
        energy += 0.5 * float(np.sum(table.weight * np.sum(eps * sig, axis=1)))
        signs = sign[table.dofs]  # shape=(rows, width)
        r = np.flatnonzero(signs.any(axis=1))  # the rows with a control DOF
        force = table.weight[r, None] * np.einsum("rip,ri->rp", table.B[r], sig[r])
        reaction += float(np.sum(force * signs[r]))
        ctx.comm.Allreduce(MPI.IN_PLACE, s1, op=MPI.SUM)
        energy = ctx.comm.allreduce(energy, op=MPI.SUM)
        reaction = ctx.comm.allreduce(reaction, op=MPI.SUM)
        return s1, energy, reaction

    def l2_error(self, u: np.ndarray) -> float:
        """||u_h - u_exact||_L2 of eq. (2.22), each cell with its own field (collective).

        A 6-point Gauss rule of degree 4 is exact for the squared error of the linear
        (CST, MLS) and quadratic (RGNT, GNT) fields against a linear exact solution.
        """
        ctx = self.ctx
        exact = ctx.problem.exact
        gm, state, bs, kinematics = ctx.gm, self.state, ctx.bs, ctx.spec.kinematics
        bary, w = GAUSS_6
        total = 0.0
        for c in self.own:
            x = gm.coords[gm.cells[c]]
            pts = bary @ x
            fit = state.fits.get(int(c))
            if int(c) not in state.fits:
                d = u[ctx.node_dofs(gm.cells[c])].reshape(3, bs)
                kind = None if kinematics is None else KINDS[kinematics]
                uh = bary @ d if kind is None else vertex_field(kind, x, d, points=pts)
            elif fit is None:
                uh = np.zeros((len(pts), 2))
            else:
                nodal = u[ctx.mls_dofs(fit.nodes)].reshape(-1, 2)
                uh = fit.shape_functions(pts) @ nodal
            ue = np.stack(np.broadcast_arrays(*exact.displacement(pts[:, 0], pts[:, 1])), axis=1)
            total += state.areas[c] * float(w @ np.sum((uh - ue) ** 2, axis=1))
        return math.sqrt(ctx.comm.allreduce(total, op=MPI.SUM))

    # -- reporting ----------------------------------------------------------------------
    def state_text(self, precracked: int, random_precracked: int) -> str:
        """The crack state in a few words, for the start-up message."""
        state = self.state
        return (
            f"{len(state.mesh.edges)} edges, {precracked} pre-cracked, "
            f"{len(state.fits)} MLS cells ({len(state.void_cells())} void), "
            f"{int((~state.crackable & ~state.mesh.boundary_edges).sum())} edges frozen next "
            f"to Dirichlet nodes, {int(state.mesh.boundary_edges.sum())} on the boundary "
            "(no crack sites)"
        )

    def checkpoint_extra(self) -> dict[str, JsonValue]:
        """Nothing: the edge state is a function of the cracked edges."""
        return {}

    def restore_extra(self, extra: dict[str, JsonValue]) -> None:
        """Nothing to restore."""

    def results(self, out: dict[str, JsonValue], precracked: int, random_precracked: int) -> None:
        """Nothing to add: the loop's results count edges and MLS cells."""


def penalty_of(ctx: CrackContext, D: np.ndarray) -> float:
    """The zero-mode penalty α μ of a material D, shape=(3, 3) (μ = D[2, 2]; ctx's for ctx.D)."""
    return float(ctx.penalty * D[2, 2] / ctx.D[2, 2])


def set_material(units: EdgeUnits, cells: np.ndarray, D: np.ndarray) -> None:
    """Give ``cells`` (gathered ids, shape=(k,)) of ``units`` the elasticity matrix D.

    D: shape=(3, 3). Their element matrices and stress operators are recomputed; their
    MLS fits take D from then on (installed support, docs/insitu.md).
    """
    ctx, gm = units.ctx, units.ctx.gm
    if units.cell_D is None:
        units.cell_D = np.broadcast_to(ctx.D, (len(gm.cells), 3, 3)).copy()
    cells = np.asarray(cells, dtype=np.int64)
    units.cell_D[cells] = D
    for c in cells.tolist():
        units._mls_k.pop(c, None)
    mine = np.flatnonzero(np.isin(units.own, cells))
    if not len(mine):
        return
    x = gm.coords[gm.cells[units.own[mine]]]
    units.K_fe[mine] = fe_matrices(ctx.spec, x, D, thickness=ctx.t, penalty=penalty_of(ctx, D))
    op = np.einsum("ij,cqjp->cqip", D, strain_operator(ctx.spec, x, MIDPOINTS))
    units._stress_blocks[mine] = op.reshape(len(mine), 9, -1)  # the operators' values
