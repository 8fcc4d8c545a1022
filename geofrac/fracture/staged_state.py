"""Cells removed by construction stages in a cracking run (docs/insitu.md).

A stage of a cracking scene removes cell groups (an excavation). A removed cell is
*void*, as a fragment's cell is (:class:`~geofrac.fracture.state.CrackState`): it carries
no stiffness, and :class:`~geofrac.fracture.insitu.InitialStressLoad` gives it no
internal force of σ0. Its edges are no crack sites, and neither are the edges of the new
wall (one live cell; only interior edges crack, the rule of the mesh's own boundary).
The new wall bounds the MLS fits' visibility as the mesh boundary does, so a fit near it
takes no satellite inside the opening, and a node on it counts as a boundary node for
the cut cells. :class:`StagedCrackState` keeps removed cells void through every refit;
:data:`~geofrac.fracture.staged_variant.STAGED_EDGES` is the edge variant whose units
carry it.

A later stage may install removed cells again (support, backfill: ``add``):
:meth:`StagedCrackState.install` makes them element cells again; their edges are crack
sites again where the caller says (the support's strength), the wall between them and
the rock becomes an ordinary interior edge (no longer blocking visibility, its nodes no
longer boundary nodes), and fits made from then on see across it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac.fem.insitu import cell_dofs
from geofrac.fem.insitu import group_cells as local_group_cells
from geofrac.fracture.context import CrackContext, JsonValue
from geofrac.fracture.state import CrackState
from geofrac.fracture.units import Block, EdgeUnits
from geofrac.fracture.visibility import Bins
from geofrac.mls.shape import LinearFit

__all__ = [
    "StagedCrackState",
    "group_cells",
    "internal_force",
    "kill_groups",
    "live_max_displacement",
    "probe_displacements",
    "state_of",
]


@dataclass
class StagedCrackState(CrackState):
    """A crack state whose removed cells stay void.

    Attributes:
        removed: whether each cell has been removed by a stage, shape=(num_cells,).
    """

    def __post_init__(self) -> None:  # noqa: D105
        super().__post_init__()
        self.removed = np.zeros(self.mesh.num_cells, dtype=bool)

    def refit(self, cells: np.ndarray) -> np.ndarray:
        """:meth:`CrackState.refit` of the cells that are not removed."""
        cells = np.asarray(cells, dtype=np.int64)
        return super().refit(cells[~self.removed[cells]])

    def remove(self, cells: np.ndarray) -> np.ndarray:
        """Remove ``cells`` (shape=(k,)); return the cells whose field changed, sorted.

        The removed cells become void; their edges stop being crack sites; the wall
        edges (a removed and a live cell) join the boundary that blocks visibility and
        their nodes count as boundary nodes. Fits that used a node of a removed cell
        are refitted against the new wall.
        """
        m = self.mesh
        cells = np.unique(np.asarray(cells, dtype=np.int64))
        cells = cells[~self.removed[cells]]
        self.removed[cells] = True
        edges = np.unique(m.cell_edges[cells])
        self.crackable[edges] = False
        ec = m.edge_cells[edges]  # shape=(k, 2), -1: no cell
        live = (ec >= 0) & ~self.removed[np.maximum(ec, 0)]
        wall = edges[live.any(axis=1)]
        for e in wall.tolist():
            a, b = self.segments[e]
            self.boundary_bins.add(e, np.minimum(a, b), np.maximum(a, b))
        self._on_boundary[m.edges[wall].ravel()] = True
        for c in cells.tolist():
            self.own_fits[c] = None
        self._h[cells] = 0.0
        inside = np.zeros(len(m.coords), dtype=bool)
        inside[m.cells[cells].ravel()] = True
        near = [
            c
            for c, fit in self.own_fits.items()
            if fit is not None and bool(inside[fit.nodes].any())
        ]
        refitted = self.refit(np.array(sorted(near), dtype=np.int64))
        return self.conform(np.union1d(cells, refitted), wall)

    def install(self, cells: np.ndarray, *, sites: bool) -> np.ndarray:
        """Install removed ``cells`` (shape=(k,)) again; return the changed cells, sorted.

        They become element cells (no fit); the edges with two live cells, neither
        frozen, become crack sites when ``sites`` (the installed material has a
        strength), else not; the wall edges that now have two live cells stop blocking
        visibility and their nodes stop being boundary nodes (unless on another wall or
        the mesh boundary). Fits already made are kept: a refit would change a cell's
        field without a load (the state left the last stage in balance); those made
        later see across the new interior edges.
        """
        m = self.mesh
        cells = np.unique(np.asarray(cells, dtype=np.int64))
        cells = cells[self.removed[cells]]
        self.removed[cells] = False
        for c in cells.tolist():
            self.own_fits.pop(c, None)
            if self.fits is not self.own_fits:
                self.fits.pop(c, None)
        edges = np.unique(m.cell_edges[cells])
        ec = m.edge_cells[edges]
        live = (ec >= 0).all(axis=1) & ~self.removed[np.maximum(ec, 0)].any(axis=1)
        live &= ~self.frozen[np.maximum(ec, 0)].any(axis=1)
        self.crackable[edges] = live & sites
        self._rebuild_walls()
        mine = set(cells.tolist())  # installed cells at a cut node use MLS at once
        cut = [c for c in self._cut_cells(m.cells[cells].ravel()) if c in mine]
        changed = np.union1d(cells, self.refit(np.array(sorted(set(cut)), dtype=np.int64)))
        return self.conform(changed.astype(np.int64), edges)

    def _rebuild_walls(self) -> None:
        """The visibility boundary and boundary nodes: the mesh's and the live cells' walls."""
        m = self.mesh
        ec = m.edge_cells
        gone = (ec >= 0) & self.removed[np.maximum(ec, 0)]
        wall = np.flatnonzero(gone.any(axis=1) & ((ec >= 0) & ~gone).any(axis=1))
        bins = Bins(self.boundary_bins.size)
        for e in np.union1d(np.flatnonzero(m.boundary_edges), wall).tolist():
            a, b = self.segments[e]
            bins.add(e, np.minimum(a, b), np.maximum(a, b))
        self.boundary_bins = bins
        self._on_boundary = m.boundary_nodes()
        self._on_boundary[m.edges[wall].ravel()] = True


def group_cells(ctx: CrackContext, groups: tuple[str, ...]) -> np.ndarray:
    """The gathered-mesh cells of cell groups, from every rank, sorted, shape=(k,)."""
    n_own = ctx.tagged.mesh.topology.index_map(2).size_local
    mine = [np.zeros(0, dtype=np.int64)]
    for group in groups:
        _, local = ctx.tagged.entities(group)
        mine.append(ctx.gm.local_cell[local[local < n_own]].astype(np.int64))
    return np.unique(np.concatenate(ctx.comm.allgather(np.concatenate(mine))))


def internal_force(
    ctx: CrackContext,
    units: EdgeUnits,
    u: np.ndarray,
    *,
    pairs: list[Block] | None = None,
    only: np.ndarray | None = None,
) -> np.ndarray:
    """K u of the current crack state, gathered on every rank, shape=(n_global,).

    The owned cells' element matrices (intact cells) and MLS stiffness (2.19) (fitted
    cells), the matrices the assembly uses; void cells give nothing; ``pairs``: the
    owned crack-face pairs' blocks in their current states (with contact); ``only``:
    whether each cell counts (the cells of one installation), shape=(num_cells,),
    None: all. ``u``: shape=(n_global,). Collective.
    """
    state = units.state
    f = np.zeros(ctx.n_global)
    fe = ~state.is_mls()[units.own]
    if only is not None:
        fe &= only[units.own]
    dofs = units.fe_dofs[fe]
    np.add.at(f, dofs, np.einsum("cij,cj->ci", units.K_fe[fe], u[dofs]))
    for c, fit in state.fits.items():
        if fit is None or not units.owned[c] or (only is not None and not only[c]):
            continue
        assert isinstance(fit, LinearFit)
        block = units.fit_block(c, fit)
        assert block is not None
        d, k = block
        np.add.at(f, d, k @ u[d])
    for d, k in pairs or ():
        np.add.at(f, d, k @ u[d])
    ctx.comm.Allreduce(MPI.IN_PLACE, f, op=MPI.SUM)
    return f


def state_of(loop: Any) -> StagedCrackState:
    """The staged crack state of a loop's units."""
    state = loop.parts.units.state
    assert isinstance(state, StagedCrackState)
    return state


def kill_groups(ctx: CrackContext, groups: tuple[str, ...]) -> None:
    """``alive`` = 0 on the removed groups (their weight and the stress output)."""
    insitu = ctx.problem.insitu
    assert insitu is not None
    for group in groups:
        cells = np.asarray(local_group_cells(ctx.tagged, group), dtype=np.int32)
        insitu.alive.x.array[cell_dofs(insitu.alive, cells)] = 0.0
    insitu.alive.x.scatter_forward()


def probe_displacements(ctx: CrackContext, u: np.ndarray) -> dict[str, JsonValue]:
    """Each ``output.probes`` point's displacement at the mesh node nearest to it.

    ``u``: shape=(n_global,) (gathered).
    """
    gm, out = ctx.gm, {}
    for name, point in ctx.scene.output.probes.items():
        node = int(np.argmin(np.hypot(*(gm.coords - np.asarray(point)[:2]).T)))
        out[name] = [float(v) for v in u[ctx.node_dofs(np.array([node]), 2)]]
    return out  # type: ignore[return-value]


def live_max_displacement(ctx: CrackContext, state: StagedCrackState, u: np.ndarray) -> float:
    """Largest |u| over the nodes of live cells (``u``: shape=(n_global,))."""
    gm = ctx.gm
    live = np.zeros(len(gm.coords), dtype=bool)
    live[gm.cells[~state.removed].ravel()] = True
    uv = u[ctx.node_dofs(np.flatnonzero(live), 2)].reshape(-1, 2)
    return float(np.max(np.hypot(uv[:, 0], uv[:, 1]), initial=0.0))
