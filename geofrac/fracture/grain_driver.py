"""Grain variant of the crack driver: cracks along grain interfaces (Edo (2016), §3.3, Fig. 3.8).

:data:`GRAINS` composes :class:`~geofrac.fracture.driver.CrackDriver` with nodes (grains)
as its units instead of cells: the same loop, solvers (``update``/``reuse``/``refactor``),
tie-break, fragment handling and end conditions, with these parts of its own:

- :class:`GrainUnits`: crack sites are the grain interfaces, one per mesh edge
  (:mod:`geofrac.fracture.grains`); the replicated state is a
  :class:`~geofrac.fracture.grains.GrainState`; an intact node's stiffness is EFMM's
  K_i = C_iᵀ A_i⁻¹ C_i (eq. 3.6) on its patch
  (:func:`geofrac.elements.efmm_numpy.node_operator`); a node with a cracked interface
  uses its C-MultiMLSM stiffness (eq. 3.28) on itself and its visible satellites,
  computed by the compiled kernel ``cmulti`` (:mod:`geofrac.mls.cmulti`); rotation-only
  and fragment grains carry no stiffness;
- :class:`GrainCriterion`: the interface stress is the larger of the two grains'
  tractions normal to the interface, n·σ n, at the interface centre X_ij (Edo (2016),
  3.3.1 and Fig. 3.4 take the direction-blind σ1 there; only the traction across an
  interface opens it, docs/granular.md), each from the grain's own field (the EFMM patch
  stress P(x) A_i⁻¹ C_i u, or D B(x) u of the C-MultiMLSM field); the least
  r = f_t / σ_n (3.8) cracks and the state is r times the unit solution (3.9)-(3.10);
- :class:`GrainDrawing`: interfaces as grain polylines in ``cracks.xdmf`` and
  ``cracks.png``, node fields in ``damage.xdmf``, fragment grains filled, and the grain
  file of the last state (:func:`geofrac.io.grains.write_grains`).

The node matrices are not cell-local (a C-MultiMLSM node couples its satellites, an EFMM
node its whole patch), so they are assembled through PETSc's COO interface like chapter
2's MLS cells; each rank computes the nodes whose PETSc block it owns.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac import kernels
from geofrac.elements.efmm_numpy import NodeOperator, integration_domains, node_operator
from geofrac.errors import RunError
from geofrac.fracture.context import CrackContext, JsonValue, Sites
from geofrac.fracture.criterion import normal_stress
from geofrac.fracture.event_criterion import EventCriterion, StatelessCriterion, next_sites
from geofrac.fracture.grains import (
    GrainState,
    Interfaces,
    connected_cracks,
    interfaces,
    side_sites,
)
from geofrac.fracture.output import FrameData, SiteDrawing
from geofrac.fracture.state import MlsSettings, segment_distance
from geofrac.fracture.topology import edge_mesh
from geofrac.fracture.units import GAUSS_6, Block, Fit, Units, mls_settings, unit_masks
from geofrac.mls import cmulti
from geofrac.mls.cmulti import NodeFit

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["GRAINS", "GrainCriterion", "GrainDrawing", "GrainUnits", "GrainVariant"]


@dataclass(frozen=True)
class _NodeTables:
    """The owned nodes' EFMM data: matrices as COO and padded, stress at their interfaces.

    Attributes:
        own: the owned nodes, shape=(n,); owned: the mask, shape=(num_nodes,).
        coo: (rows, cols, values, owned node index) of the EFMM matrices, shape=(m,) each.
        dofs: each owned node's patch DOFs padded with n_global, shape=(n, d).
        K: its t K_i padded with zeros, shape=(n, d, d).
        pair_unit, pair_edge, pair_slot: per (node, interface) pair, the node's index in
            ``own``, the interface and the node's side (0/1), shape=(p,) each.
        pair_S: the pair's stress operator at the interface centre, shape=(p, 3, d).
    """

    own: np.ndarray
    owned: np.ndarray
    coo: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    dofs: np.ndarray
    K: np.ndarray
    pair_unit: np.ndarray
    pair_edge: np.ndarray
    pair_slot: np.ndarray
    pair_S: np.ndarray


def _node_tables(
    ctx: CrackContext, state: GrainState, faces: Interfaces, operator: Callable[[int], NodeOperator]
) -> _NodeTables:
    """Owned nodes, their EFMM matrices (COO) and stress operators at the interfaces."""
    gm, bs = ctx.gm, ctx.bs
    lo, hi = ctx.row0 // bs, (ctx.row0 + ctx.n_local) // bs
    own = np.flatnonzero((gm.node_block >= lo) & (gm.node_block < hi))
    owned = np.zeros(len(gm.coords), dtype=bool)
    owned[own] = True
    ops = [operator(int(i)) for i in own]
    pad = ctx.n_global
    nd = max((2 * len(op.patch) for op in ops), default=2)
    dofs = np.full((len(own), nd), pad, dtype=np.int64)
    K = np.zeros((len(own), nd, nd))
    rows, cols, vals, unit = [], [], [], []
    pair_unit, pair_edge, pair_slot, pair_S = [], [], [], []
    for k, (i, op) in enumerate(zip(own, ops, strict=True)):
        dd = ctx.mls_dofs(op.patch)
        m = len(dd)
        dofs[k, :m] = dd
        Kt = ctx.t * op.K  # per unit thickness in node_operator; t as the C-MultiMLSM K
        K[k, :m, :m] = Kt
        rows.append(np.repeat(dd, m))
        cols.append(np.tile(dd, m))
        vals.append(Kt.ravel())
        unit.append(np.full(m * m, k))
        edges = state.edges_of_node(int(i))
        S = op.stress_at(faces.point[edges])  # shape=(k, 3, m)
        Sp = np.zeros((len(edges), 3, nd))
        Sp[:, :, :m] = S
        pair_unit.append(np.full(len(edges), k))
        pair_edge.append(edges)
        pair_slot.append((state.mesh.edges[edges, 1] == i).astype(np.int64))
        pair_S.append(Sp)
    cat = np.concatenate
    empty_i = np.zeros(0, dtype=np.int64)
    return _NodeTables(
        own=own,
        owned=owned,
        coo=(
            cat(rows) if rows else empty_i,
            cat(cols) if cols else empty_i,
            cat(vals) if vals else np.zeros(0),
            cat(unit) if unit else empty_i,
        ),
        dofs=dofs,
        K=K,
        pair_unit=cat(pair_unit) if pair_unit else empty_i,
        pair_edge=cat(pair_edge) if pair_edge else empty_i,
        pair_slot=cat(pair_slot) if pair_slot else empty_i,
        pair_S=cat(pair_S) if pair_S else np.zeros((0, 3, nd)),
    )


class MainCrack:
    """The crack joined to its origin: where it reaches the ``face`` group, where it ends.

    The origin is the interfaces of the ``precracked`` groups, else the first event's.

    Args:
        state: the grain state (cracked interfaces, the mesh).
        faces: the interfaces (their centres).
        face_nodes: the nodes of the ``face`` group, or None.
    """

    def __init__(self, state: GrainState, faces: Interfaces, face_nodes: np.ndarray | None) -> None:
        self.state, self.faces, self.face_nodes = state, faces, face_nodes
        # the crack's origin and the interfaces on the face, set at the first event
        self._origin: np.ndarray | None = None
        self._face_sites = np.zeros(0, dtype=np.int64)
        self._group_precracked = np.zeros(0, dtype=np.int64)

    def add_group(self, sites: np.ndarray) -> None:
        """The interfaces of a ``precracked`` group join the origin."""
        self._group_precracked = np.union1d(self._group_precracked, sites)

    def face_x(self, sites: np.ndarray) -> float | None:
        """Where the crack from the notch first reaches the ``face`` group: x or None.

        The crack is the set of cracked interfaces joined to its origin (the interfaces
        of the ``precracked`` groups, else the first event's), see
        :func:`~geofrac.fracture.grains.connected_cracks`. It reaches the face when it
        contains the interface of a boundary edge on the face (a grain polyline ends
        on the surface only there); x is that interface's centre, the one nearest the
        origin when there are several. Cracks elsewhere (under a point load, say) do
        not count until they join it.
        """
        m = self.state.mesh
        if self._origin is None:
            group = self._group_precracked
            self._origin = group if len(group) else np.asarray(sites, dtype=np.int64)
            on = np.isin(m.edges, self.face_nodes).all(axis=1) & m.boundary_edges
            self._face_sites = np.flatnonzero(on)
        at = self._face_sites[self.state.cracked[self._face_sites]]
        if not len(at):
            return None
        main = connected_cracks(m, self.state.cracked, self._origin)
        at = at[main[at]]
        if not len(at):
            return None
        centre = self.faces.centre
        d = np.hypot(*(centre[at] - centre[self._origin].mean(axis=0)).T)
        return float(centre[at[np.argmin(d)], 0])

    def describe(self) -> dict[str, JsonValue] | None:
        """The crack joined to the origin (see :meth:`face_x`) at the end.

        Its interfaces (the origin's included) and, with a ``face``, its interface
        centre nearest to the face's boundary edges and that distance: where a crack
        that stops short of the face ends.
        """
        if self._origin is None:
            return None
        m, centre = self.state.mesh, self.faces.centre
        main = np.flatnonzero(connected_cracks(m, self.state.cracked, self._origin))
        out: dict[str, JsonValue] = {"interfaces": len(main)}
        if len(self._face_sites) and len(main):
            ends = m.coords[m.edges[self._face_sites]]  # the face's edges, shape=(f, 2, 2)
            d = np.min([segment_distance(centre[main], a, b) for a, b in ends], axis=0)
            k = int(np.argmin(d))
            out["nearest_to_face"] = {
                "x": float(centre[main[k], 0]),
                "y": float(centre[main[k], 1]),
                "distance": float(d[k]),
            }
        return out

    def snapshot(self) -> dict[str, JsonValue]:
        """The crack origin that ``face`` reports follow (set at the first event)."""
        origin = None if self._origin is None else [int(e) for e in self._origin]
        return {"origin": origin, "face_sites": [int(e) for e in self._face_sites]}  # type: ignore[dict-item]

    def restore(self, extra: dict[str, JsonValue]) -> None:
        """Restore the crack origin."""
        if extra.get("origin") is not None:
            self._origin = np.asarray(extra["origin"], dtype=np.int64)
            self._face_sites = np.asarray(extra.get("face_sites", []), dtype=np.int64)


class GrainUnits:
    """Nodes (grains) as units: EFMM node operators, C-MultiMLSM on cracked interfaces.

    The interfaces inside the triangles that touch a Dirichlet node never crack (the
    edges chapter 2 freezes: point supports and loads concentrate stress there);
    ``mls_region`` selects nodes (not cells) that use C-MultiMLSM from the start.

    Args:
        ctx: the shared set-up data.
        mls: the C-MultiMLSM fits' neighbours, margin and radius.
        switch: which nodes switch to C-MultiMLSM when an interface cracks
            (``cracking.switch``, :class:`~geofrac.fracture.grains.GrainState`).
    """

    def __init__(self, ctx: CrackContext, *, mls: MlsSettings, switch: str) -> None:
        self.ctx = ctx
        gm, d = ctx.gm, ctx.scene.discretization
        self.rotation = np.zeros(0)
        self._ops: dict[int, NodeOperator] = {}
        self._fit_k: dict[int, tuple[NodeFit, np.ndarray]] = {}
        mesh_e = edge_mesh(gm.coords, gm.cells)
        frozen, forced_nodes = unit_masks(ctx, mesh_e, gm.coords)
        self.domains = integration_domains(gm.coords, gm.cells, d.q_rand, seed=d.domain_seed)
        self.faces = interfaces(mesh_e, self.domains)
        frozen_nodes = np.zeros(len(gm.coords), dtype=bool)
        frozen_nodes[ctx.bc_nodes] = True
        self.state: GrainState = GrainState(
            mesh_e, self.faces, frozen_nodes, forced_nodes, mls, ctx.rank_map, switch
        )
        self.state.crackable[np.unique(mesh_e.cell_edges[frozen])] = False
        #: the crack joined to its origin (``face`` reports, ``main_crack``).
        self.main = MainCrack(self.state, self.faces, ctx.face_nodes)
        t = _node_tables(ctx, self.state, self.faces, self.operator)
        self.own, self.owned, self._coo = t.own, t.owned, t.coo
        self._int_dofs, self._int_K = t.dofs, t.K
        self._pair_unit, self._pair_edge, self._pair_slot = t.pair_unit, t.pair_edge, t.pair_slot
        self._pair_S = t.pair_S
        # the element's own domains and stress coefficients serve results.xdmf and the
        # grains file of the last state
        ctx.problem.element.setup(ctx.D, d.q_rand, d.domain_seed)
        kernels.load("cmulti", ctx.comm)  # collective: rank 0 compiles on first use

    def operator(self, node: int) -> NodeOperator:
        """EFMM operators of any node (cached)."""
        op = self._ops.get(node)
        if op is None:
            f, gm = self.faces, self.ctx.gm
            mine = f.grain_order[f.grain_offsets[node] : f.grain_offsets[node + 1]]
            op = node_operator(
                gm.coords, gm.cells, self.ctx.D, domains=self.domains, node=node, mine=mine
            )
            self._ops[node] = op
        return op

    # -- sites --------------------------------------------------------------------------
    def group_sites(self, pairs: np.ndarray) -> np.ndarray:
        """A notch line: the interfaces between its nodes and those on its left."""
        sites = side_sites(self.state.mesh, pairs)
        self.main.add_group(sites)
        return sites

    def site_point(self, site: int) -> np.ndarray:
        """The interface's centre X_ij, shape=(2,)."""
        return self.faces.centre[site]

    def face_x(self, sites: np.ndarray) -> float | None:
        """Where the crack from the notch first reaches the ``face`` group (:class:`MainCrack`)."""
        return self.main.face_x(sites)

    # -- stiffness ----------------------------------------------------------------------
    def intact_coo(self, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """COO triplets of the owned EFMM nodes with ``keep``, shape=(len(own),)."""
        rows, cols, vals, unit = self._coo
        on = keep[unit]
        return rows[on], cols[on], vals[on]

    def intact_blocks(self, units: list[int]) -> dict[int, Block]:
        """(patch DOFs, t K_i) of any nodes' EFMM operators, by node."""
        out = {}
        for i in units:
            op = self.operator(int(i))
            out[i] = (self.ctx.mls_dofs(op.patch), self.ctx.t * op.K)
        return out

    def fit_block(self, unit: int, fit: Fit) -> Block | None:
        """(DOFs, C-MultiMLSM stiffness) of node ``unit``; None for rotation and fragment."""
        if fit is None:
            return None
        assert isinstance(fit, NodeFit)
        if fit.order <= 0:
            return None
        return self.ctx.mls_dofs(fit.nodes), self._stiffness(unit, fit)

    def _stiffness(self, c: int, fit: NodeFit) -> np.ndarray:
        """C-MultiMLSM stiffness (3.28) of node c by the compiled kernel (cached per fit)."""
        cached = self._fit_k.get(c)
        if cached is not None and cached[0] is fit:
            return cached[1]
        coords = self.ctx.gm.coords
        order, _, k = cmulti.compiled_node(
            coords[c],
            fit.h,
            coords[fit.nodes[1:]],
            order=fit.order,
            triangles=self.faces.grain(c),
            D=self.ctx.D,
            thickness=self.ctx.t,
            comm=None,
        )
        if order != fit.order:
            raise RunError(
                f"cracking: the C-MultiMLSM kernel chose order {order} for node {c}, the "
                f"reference {fit.order}"
            )
        if self.state.fits.get(c) is fit:
            self._fit_k[c] = (fit, k)
        return k

    def use_counts(self, is_mls: np.ndarray) -> np.ndarray:
        """How many grains give stiffness to each DOF (replicated), shape=(n_global,)."""
        ctx = self.ctx
        e = self.state.mesh.edges
        n = len(ctx.gm.coords)
        intact = ~is_mls
        nodes = [np.flatnonzero(intact), e[intact[e[:, 0]], 1], e[intact[e[:, 1]], 0]]
        counts = np.bincount(np.concatenate(nodes), minlength=n)
        for fit in self.state.fits.values():
            if fit.order > 0:
                counts[fit.nodes] += 1
        use = np.zeros(ctx.n_global, dtype=np.int64)
        for k in range(2):
            use[ctx.gm.node_block * ctx.bs + k] = counts
        return use

    def stiffless_nodes(self) -> np.ndarray:
        """Switched nodes with a rotation-only or no field: their grain has no strain."""
        nodes = [i for i, f in self.state.fits.items() if f is None or f.order <= 0]
        return np.array(sorted(nodes), dtype=np.int64)

    def links(self, is_mls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Node pairs joined by an intact grain's edge or a C-MultiMLSM fit."""
        e = self.state.mesh.edges
        on = ~is_mls[e[:, 0]] | ~is_mls[e[:, 1]]
        a, b = [e[on, 0]], [e[on, 1]]
        for fit in self.state.fits.values():
            if fit.order > 0:
                a.append(np.full(len(fit.nodes) - 1, fit.nodes[0]))
                b.append(fit.nodes[1:])
        return np.concatenate(a).astype(np.int64), np.concatenate(b).astype(np.int64)

    # -- measures -----------------------------------------------------------------------
    def changed(self, units: np.ndarray) -> None:
        """Nothing cached: the fits' stiffness is cached per fit."""

    def reset(self) -> None:
        """Nothing cached."""

    def measures(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(normal traction of each interface's two grains, strain energy, reaction) of u.

        The tractions n·σ n (the criterion's σ1) have shape=(num_interfaces, 2):
        [interface, its node 0 / node 1 grain] at its centre; each rank evaluates the
        grains it owns. Collective.
        """
        state, ctx = self.state, self.ctx
        is_mls = state.is_mls()
        ne = len(state.mesh.edges)
        s1 = np.zeros((ne, 2))
        u_ext = np.append(u, 0.0)
        live = ~is_mls[self.own]
        p = live[self._pair_unit]
        ud_pairs = u_ext[self._int_dofs[self._pair_unit[p]]]
        stress = np.einsum("psd,pd->ps", self._pair_S[p], ud_pairs)
        s1[self._pair_edge[p], self._pair_slot[p]] = normal_stress(
            stress, self.faces.normal[self._pair_edge[p]]
        )
        ud = u_ext[self._int_dofs[live]]
        ku = np.einsum("nij,nj->ni", self._int_K[live], ud)
        energy = 0.5 * float(np.sum(ud * ku))
        sign = ctx.control_sign
        reaction = float(np.sum(ku * sign[self._int_dofs[live]]))
        for i, fit in state.fits.items():
            if not self.owned[i]:
                continue
            edges = state.edges_of_node(i)
            d = ctx.mls_dofs(fit.nodes)
            uf = u[d]
            if fit.order > 0:
                B = fit.strain_matrix(self.faces.point[edges])  # shape=(k, 3, nd)
                sig = np.einsum("ij,kjd,d->ki", ctx.D, B, uf)
                slot = (state.mesh.edges[edges, 1] == i).astype(np.int64)
                s1[edges, slot] = normal_stress(sig, self.faces.normal[edges])
                k = self._stiffness(i, fit)
                f = k @ uf
                energy += 0.5 * float(uf @ f)
                reaction += float(f @ sign[d])
        ctx.comm.Allreduce(MPI.IN_PLACE, s1, op=MPI.SUM)
        energy = ctx.comm.allreduce(energy, op=MPI.SUM)
        reaction = ctx.comm.allreduce(reaction, op=MPI.SUM)
        return s1, energy, reaction

    def l2_error(self, u: np.ndarray) -> float:
        """||u_h - u_exact||_L2 of the CST displacement field (EFMM's, eq. 3.2a).

        A 6-point rule of degree 4 on the owned cells (exact for a linear solution).
        """
        ctx = self.ctx
        exact = ctx.problem.exact
        gm = ctx.gm
        bary, w = GAUSS_6
        cells = np.flatnonzero(gm.owned)
        x = gm.coords[gm.cells[cells]]  # shape=(n, 3, 2)
        d = u[ctx.mls_dofs(gm.cells[cells].ravel())].reshape(len(cells), 3, 2)
        pts = np.einsum("qk,ckd->cqd", bary, x)
        uh = np.einsum("qk,ckd->cqd", bary, d)
        ue = np.stack(np.broadcast_arrays(*exact.displacement(pts[..., 0], pts[..., 1])), axis=-1)
        area = self.state.mesh.areas()[cells]
        total = float(np.sum(area[:, None] * w * np.sum((uh - ue) ** 2, axis=-1)))
        return math.sqrt(ctx.comm.allreduce(total, op=MPI.SUM))

    # -- reporting ----------------------------------------------------------------------
    def state_text(self, precracked: int, random_precracked: int) -> str:
        """The crack state in a few words, for the start-up message."""
        state = self.state
        return (
            f"{len(state.mesh.edges)} grain interfaces, {precracked} pre-cracked "
            f"({random_precracked} at random), {len(state.fits)} C-MultiMLSM "
            f"grains, {int((~state.crackable).sum())} interfaces frozen next to Dirichlet nodes"
        )

    def checkpoint_extra(self) -> dict[str, JsonValue]:
        """The crack origin that ``face`` reports follow (set at the first event)."""
        return self.main.snapshot()

    def restore_extra(self, extra: dict[str, JsonValue]) -> None:
        """Restore the crack origin."""
        self.main.restore(extra)

    def results(self, out: dict[str, JsonValue], precracked: int, random_precracked: int) -> None:
        """Interfaces and grains instead of edges and MLS cells."""
        orders = self.state.orders()
        for key in ("mls_cells", "void_cells", "cracked_edges", "new_cracked_edges",
                    "precracked_edges", "edges"):  # fmt: skip
            out.pop(key)
        state = self.state
        out |= {
            "sites": "grain interfaces",
            "interfaces": len(state.mesh.edges),
            "cracked_interfaces": int(state.cracked.sum()),
            "new_cracked_interfaces": int(state.cracked.sum()) - precracked,
            "precracked_interfaces": precracked,
            "random_precracked_interfaces": random_precracked,
            "grains": len(orders),
            "main_crack": self.main.describe(),
            "grains_by_field": {
                name: int(np.sum(orders == k))
                for name, k in (
                    ("efmm", 3),
                    ("quadratic", 2),
                    ("linear", 1),
                    ("rotation", 0),
                    ("fragment", -1),
                )
            },
        }


class GrainCriterion(StatelessCriterion):
    """Grain interfaces: σ1 of an interface is the larger of its two grains' (Edo (2016), §3.3.1).

    Args:
        units: the grain units.
    """

    def __init__(self, units: GrainUnits) -> None:
        self.units = units
        #: the interface centres X_ij, shape=(num_interfaces, 2).
        self.points = units.faces.centre

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """σ1 per interface from its grains' values, shape=(num_interfaces, 2)."""
        return unit_s1.max(axis=1)

    def select(self, sigma1: np.ndarray, *, floor: float) -> tuple[np.ndarray, float]:
        """The interfaces of least r (:func:`~geofrac.fracture.event_criterion.next_sites`)."""
        units = self.units
        return next_sites(units.state, units.ctx.config, sigma1, floor=floor, points=self.points)


class GrainDrawing:
    """Interfaces as grain polylines, node fields, fragment grains and the grain file.

    Args:
        ctx: the shared set-up data.
        units: the grain units.
        sites: the interfaces cracked before loading.
    """

    def __init__(self, ctx: CrackContext, units: GrainUnits, sites: Sites) -> None:
        self.ctx, self.units, self.sites = ctx, units, sites

    def crack_geometry(self) -> tuple[np.ndarray, np.ndarray]:
        """Two segments per interface (4 points), shape=(4 ne, 2), lines (2 ne, 2)."""
        seg = self.units.faces.segments.reshape(-1, 2)
        return seg, np.arange(len(seg)).reshape(-1, 2)

    def frame(self, disp: np.ndarray) -> FrameData:
        """``crack``, ``precracked`` per segment; ``displacement``, ``order``, ``fragment``."""
        state = self.units.state
        crack = np.repeat(state.cracked.astype(float), 2)
        pre = np.zeros(len(state.cracked))
        pre[self.sites.precracked] = 1.0
        order = state.orders().astype(float)
        return (
            {"crack": crack, "precracked": np.repeat(pre, 2)},
            {"displacement": disp, "order": order, "fragment": (order < 0).astype(float)},
            {},
        )

    def segments(self, sites: np.ndarray) -> np.ndarray:
        """The two segments of each selected interface, shape=(2k, 2, 2)."""
        return self.units.faces.segments[sites].reshape(-1, 2, 2)

    def draw_extra(self, ax: Axes) -> None:
        """Fill the fragment grains in ``cracks.png``."""
        from matplotlib.collections import PolyCollection

        frag = self.units.state.fragments()
        if len(frag):
            polys = [t for i in frag for t in self.units.faces.grain(int(i))]
            ax.add_collection(PolyCollection(polys, facecolors="0.3", edgecolors="none"))

    def write_extra(self, out_dir: Path) -> None:
        """``grain_cracks``: the grains with their field order and cracked interfaces."""
        from geofrac.io.grains import grain_polygons, write_grains

        f, gm, state = self.units.faces, self.ctx.gm, self.units.state
        node = np.repeat(np.arange(len(f.grain_offsets) - 1), np.diff(f.grain_offsets))
        grains = grain_polygons(gm.input_ids[node], f.grain_subs)
        cracked = np.bincount(
            state.mesh.edges[state.cracked].ravel(), minlength=len(gm.coords)
        ).astype(float)
        order = state.orders().astype(float)
        at = np.searchsorted(gm.input_ids, grains.node)
        write_grains(
            out_dir / "grain_cracks",
            grains,
            {
                "order": order[at],
                "fragment": (order[at] < 0).astype(float),
                "cracked_interfaces": cracked[at],
            },
        )


@dataclass(frozen=True)
class GrainVariant:
    """Grain interfaces of an EFMM scene (chapter 3)."""

    kind: str = "grains"

    def units(self, ctx: CrackContext) -> Units:
        """:class:`GrainUnits`."""
        return GrainUnits(ctx, mls=mls_settings(ctx.config), switch=ctx.config.switch)

    def criterion(self, ctx: CrackContext, units: Units) -> EventCriterion:
        """:class:`GrainCriterion`."""
        assert isinstance(units, GrainUnits)
        return GrainCriterion(units)

    def drawing(self, ctx: CrackContext, units: Units, sites: Sites) -> SiteDrawing:
        """:class:`GrainDrawing`."""
        assert isinstance(units, GrainUnits)
        return GrainDrawing(ctx, units, sites)


#: The grain variant.
GRAINS = GrainVariant()
