"""Assembly of the crack state's stiffness, and the DOFs held so that it stays regular.

:class:`Assembler` assembles the stiffness of any :class:`~geofrac.fracture.units.Units`
through PETSc's COO interface (entries of other ranks' rows travel with PETSc's own
assembly: an MLS cell or a grain couples nodes that are not its vertices, outside any
finite element sparsity pattern) and owns the *holds*: the nodes of pieces cut free by
cracks and the DOFs pinned to stop a supported piece's free rigid motion.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np

from geofrac.fracture.contact import constraint_terms, pair_links
from geofrac.fracture.context import CrackContext
from geofrac.fracture.topology import components, motion_pins, motion_rows, zero_energy_rows
from geofrac.fracture.units import Units
from geofrac.solvers import (
    Matrix,
    Vector,
    coo_matrix,
    dense_submatrix,
    diagonal_norm1,
    zero_rows_columns,
)

if TYPE_CHECKING:
    from geofrac.fracture.faces import Faces

__all__ = ["Assembler", "LoadCase"]


@dataclass(frozen=True)
class LoadCase:
    """A right-hand side of the crack state's system other than the scene's whole load.

    Attributes:
        load: the load vector on the unknowns, without Dirichlet conditions (the
            caller owns and destroys it).
        bc_vals: the values of the Dirichlet DOFs ``ctx.bc_rows``, shape=(k,).
        bc_full: the same on all DOFs (0 elsewhere), shape=(n_global,).
    """

    load: Vector
    bc_vals: np.ndarray
    bc_full: np.ndarray


class Assembler:
    """Stiffness and load of the current crack state, and the held DOFs.

    Args:
        ctx: the shared set-up data.
        units: the discretisation of the crack state.
        contact: the crack faces, whose closed pairs add blocks and links, or None.

    Attributes:
        fragment_nodes: nodes of pieces cut free by cracks (no Dirichlet node), held
            like a node whose every edge is cracked, shape=(k,).
        pinned_dofs: DOFs pinned at their last displacement to stop a supported piece's
            free rigid motion, shape=(k,); pinned_nodes: their nodes, shape=(k,).
    """

    def __init__(self, ctx: CrackContext, units: Units, *, contact: Faces | None = None) -> None:
        self.ctx, self.units = ctx, units
        self.fragment_nodes = np.zeros(0, dtype=np.int64)
        self.pinned_dofs = np.zeros(0, dtype=np.int64)
        self.pinned_nodes = np.zeros(0, dtype=np.int64)
        self._b0: Vector | None = None
        #: the right-hand side :meth:`assemble` uses by default: None, the scene's loads
        #: and prescribed displacements as given; a :class:`LoadCase` (the variable part
        #: of a run with constant loads, docs/cracking.md "Loads that do not scale
        #: together").
        self.case: LoadCase | None = None
        #: crack-face contact (:class:`~geofrac.fracture.faces.Faces`), or None.
        self.contact = contact

    @property
    def bc_full(self) -> np.ndarray:
        """The prescribed values of the default right-hand side on all DOFs, shape=(n_global,)."""
        return self.ctx.bc_full if self.case is None else self.case.bc_full

    def assemble(
        self, held_values: np.ndarray, case: LoadCase | None = None
    ) -> tuple[Matrix, Vector, np.ndarray]:
        """Stiffness and load vector of the current crack state; returns (A, b, held DOFs).

        Dirichlet DOFs and held DOFs (no stiffness, or in a cut-free fragment) are
        applied with ``MatZeroRowsColumns``; held DOFs keep ``held_values``,
        shape=(n_global,). The right-hand side is ``case``'s, else :attr:`case`'s, else
        the scene's. The caller destroys A and b.
        """
        case = self.case if case is None else case
        ctx, units = self.ctx, self.units
        state = units.state
        is_mls = state.is_mls()
        r0, c0, v0 = units.intact_coo(~is_mls[units.own])
        rows, cols, vals = [r0], [c0], [v0]
        blocks = [units.fit_block(c, fit) for c, fit in state.fits.items() if units.owned[c]]
        if self.contact is not None:
            blocks += self.contact.owned_blocks()
        for block in blocks:
            if block is None:
                continue
            d, k = block
            rows.append(np.repeat(d, len(d)))
            cols.append(np.tile(d, len(d)))
            vals.append(k.ravel())
        diag = np.arange(ctx.row0, ctx.row0 + ctx.n_local, dtype=np.int64)
        rows.append(diag)
        cols.append(diag)
        vals.append(np.zeros(len(diag)))
        entries = (np.concatenate(rows), np.concatenate(cols), np.concatenate(vals))
        A = coo_matrix(ctx.comm, (ctx.n_local, ctx.n_global), entries)
        used = units.use_counts(is_mls) > 0
        used[ctx.node_dofs(self.fragment_nodes)] = False
        used[self.pinned_dofs] = False
        used[ctx.bc_rows] = True
        held = np.flatnonzero(~used)
        fixed = np.concatenate([ctx.bc_rows, held])
        bc_vals = ctx.bc_vals if case is None else case.bc_vals
        values = np.concatenate([bc_vals, held_values[held]])
        mine = (fixed >= ctx.row0) & (fixed < ctx.row0 + ctx.n_local)
        if case is not None:
            b = case.load.copy()
        else:
            if self._b0 is None:
                self._b0 = ctx.problem.load_vector()
            b = self._b0.copy()
        zero_rows_columns(A, fixed[mine], values[mine], b=b)
        return A, b, held

    def find_fragments(self) -> bool:
        """Hold what the supports no longer hold; True if anything new is held (collective).

        Pieces are the nodes joined by units with stiffness; closed crack faces join
        pieces into groups. A group with no Dirichlet DOF is cut free: all its nodes are
        held at their last displacement. In a supported group, the pieces' rigid motions
        (3 each) are constrained by the Dirichlet and pinned DOFs and by the contact
        pairs: a sticking pair ties its faces' jump at one point (a piece held by one
        pair can still turn about it), a slipping pair its normal jump only (a piece
        between parallel slipping faces can slide)
        (:func:`~geofrac.fracture.topology.motion_rows`). A motion they leave free
        (e.g. a column split off between the loading platens, free to slide sideways)
        gets the fewest u_x/u_y DOFs pinned at their last displacement that remove it
        (:func:`~geofrac.fracture.topology.motion_pins`), so the pieces go on carrying
        load. Both choices depend on coordinates only (rank-independent).
        """
        ctx, units = self.ctx, self.units
        gm, bs = ctx.gm, ctx.bs
        a, b = units.links(units.state.is_mls())
        pieces = components(len(gm.coords), a, b)
        labels = pieces
        if self.contact is not None:  # closed faces join pieces into groups
            ca, cb = pair_links(self.contact.pairs)
            labels = components(len(gm.coords), np.r_[a, ca], np.r_[b, cb])
        anchored = np.unique(labels[np.unique(ctx.bc_row_nodes)])
        touched = np.zeros(len(gm.coords), dtype=bool)
        touched[a] = True
        touched[b] = True
        loose = np.flatnonzero(touched & ~np.isin(labels, anchored))
        new = np.setdiff1d(loose, self.fragment_nodes)
        if len(new):
            self.fragment_nodes = np.union1d(self.fragment_nodes, new)
            ctx.say(f"cracking: {len(new)} nodes of cut-free fragments are held")
        pinned = self._pin_free_motions(labels, pieces, touched, anchored)
        if pinned:
            pn = np.array([p[0] for p in pinned], dtype=np.int64)
            self.pinned_nodes = np.concatenate([self.pinned_nodes, pn])
            dofs = gm.node_block[pn] * bs + np.array([p[1] for p in pinned])
            self.pinned_dofs = np.concatenate([self.pinned_dofs, dofs])
            ctx.say(f"cracking: {len(pinned)} DOFs pinned to stop free rigid motions")
        held = self.hold_zero_energy_modes()
        return len(new) > 0 or len(pinned) > 0 or held

    def _pin_free_motions(
        self, labels: np.ndarray, pieces: np.ndarray, touched: np.ndarray, anchored: np.ndarray
    ) -> list[tuple[int, int]]:
        """(node, component) of the DOFs to pin in each supported group of pieces.

        Args:
            labels: the group of each node, shape=(num_nodes,).
            pieces: the piece of each node, shape=(num_nodes,).
            touched: whether a unit uses each node, shape=(num_nodes,).
            anchored: the groups with Dirichlet DOFs, shape=(k,).
        """
        ctx, units = self.ctx, self.units
        xy = ctx.gm.coords[:, :2]
        fixed_rows = np.concatenate([ctx.bc_rows, self.pinned_dofs])
        fixed_nodes = np.concatenate([ctx.bc_row_nodes, self.pinned_nodes])
        terms = None if self.contact is None else constraint_terms(self.contact.pairs)
        moving = touched.copy()
        moving[self.fragment_nodes] = False  # held: they support what they touch
        pinned: list[tuple[int, int]] = []
        for label in anchored:
            members = np.flatnonzero(moving & (labels == label))
            if not len(members):
                continue  # no cell left to move
            ids, local = np.unique(pieces[members], return_inverse=True)
            nodes_of = [members[local == i] for i in range(len(ids))]
            piece_of = np.full(len(xy), -1, dtype=np.int64)
            piece_of[members] = local
            centres = np.array([xy[m].mean(axis=0) for m in nodes_of])
            scale = max(1.0, float(np.abs(xy[members] - centres[local]).max()))
            on = piece_of[fixed_nodes] >= 0
            n = fixed_nodes[on]
            C = motion_rows(
                xy[n],
                fixed_rows[on] % ctx.bs,
                units.rotation,
                pieces=piece_of[n],
                centres=centres,
                scale=scale,
            )
            if terms is not None and len(ids) > 1:
                rows, nodes, comps, weights = terms
                keep = piece_of[nodes] >= 0  # nodes that do not move: their terms drop
                n = nodes[keep]
                pairs = motion_rows(
                    xy[n],
                    comps[keep],
                    units.rotation,
                    pieces=piece_of[n],
                    centres=centres,
                    scale=scale,
                    rows=rows[keep],
                    weights=weights[keep],
                )
                C = np.vstack([C, pairs])
            candidates = [xy[m] for m in nodes_of]
            for i, node, comp in motion_pins(
                C, units.rotation, candidates, centres=centres, scale=scale
            ):
                pinned.append((int(nodes_of[i][node]), comp))
        return pinned

    def hold_zero_energy_modes(self) -> bool:
        """Pin the DOFs of the units' stiffless nodes that move without strain energy.

        The block of the assembled stiffness on the DOFs of
        :meth:`~geofrac.fracture.units.Units.stiffless_nodes` (Dirichlet, held and
        pinned ones left out) is gathered to every rank; the rows in its zero-energy
        modes (:func:`~geofrac.fracture.topology.zero_energy_rows`, eigenvalues below
        1e-10 of the mean diagonal entry) are pinned at their last displacement, as a
        piece's free rigid motion is. True if any DOF was pinned. Collective.
        """
        ctx = self.ctx
        nodes = np.setdiff1d(self.units.stiffless_nodes(), self.fragment_nodes)
        if not len(nodes):
            return False
        A, b, held = self.assemble(np.zeros(ctx.n_global))
        dofs = ctx.node_dofs(nodes)
        dofs = dofs[~np.isin(dofs, np.concatenate([ctx.bc_rows, held, self.pinned_dofs]))]
        if not len(dofs):  # the same on every rank
            A.destroy()
            b.destroy()
            return False
        try:
            scale = diagonal_norm1(A) / ctx.n_global
            K = dense_submatrix(A, dofs)
        finally:
            A.destroy()
            b.destroy()
        free = dofs[zero_energy_rows(K, 1e-10 * scale)]
        if not len(free):
            return False
        owner = np.empty(len(ctx.gm.node_block), dtype=np.int64)
        owner[ctx.gm.node_block] = np.arange(len(ctx.gm.node_block))
        self.pinned_nodes = np.concatenate([self.pinned_nodes, owner[free // ctx.bs]])
        self.pinned_dofs = np.concatenate([self.pinned_dofs, free])
        ctx.say(
            f"cracking: {len(free)} DOFs of grains without stiffness of their own pinned "
            "(they moved without strain energy)"
        )
        return True

    def destroy(self) -> None:
        """Free the load vector."""
        if self._b0 is not None:
            self._b0.destroy()
        self._b0 = None
