"""The sequentially linear event loop on grain interfaces (seed 3.3, Fig. 3.8).

:class:`GrainDriver` is :class:`~geofrac.fracture.driver.CrackDriver` with nodes (grains)
as its units instead of cells: the same loop, solvers (``update``/``reuse``/``refactor``),
criterion, tie-break, fragment handling and end conditions, with these pieces swapped:

- crack sites are the grain interfaces, one per mesh edge
  (:mod:`geofrac.fracture.grains`); the replicated state is a
  :class:`~geofrac.fracture.grains.GrainState`;
- an intact node's stiffness is EFMM's K_i = C_iᵀ A_i⁻¹ C_i (eq. 3.6) on its patch
  (:func:`geofrac.elements.efmm_numpy.node_operator`); a node with a cracked interface
  uses its C-MultiMLSM stiffness (eq. 3.28) on itself and its visible satellites,
  computed by the compiled kernel ``cmulti`` (:mod:`geofrac.mls.cmulti`); rotation-only
  and fragment grains carry no stiffness;
- the interface stress (seed 3.3.1, Fig. 3.4) is the larger of the two grains' largest
  principal stresses at the interface centre X_ij, each from the grain's own field (the
  EFMM patch stress P(x) A_i⁻¹ C_i u, or D B(x) u of the C-MultiMLSM field); the least
  r = f_t / σ1 (3.8) cracks and the state is r times the unit solution (3.9)-(3.10).

The node matrices are not cell-local (a C-MultiMLSM node couples its satellites, an EFMM
node its whole patch), so they are assembled through PETSc's COO interface like chapter
2's MLS cells; each rank computes the nodes whose PETSc block it owns.
"""

from __future__ import annotations

import math
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac import kernels
from geofrac.elements.efmm_numpy import NodeOperator, integration_domains, node_operator
from geofrac.errors import RunError
from geofrac.fracture.criterion import normal_stress
from geofrac.fracture.driver import GAUSS_6, CrackDriver
from geofrac.fracture.grains import GrainState, connected_cracks, interfaces, side_sites
from geofrac.fracture.state import MlsSettings, segment_distance
from geofrac.fracture.topology import EdgeMesh
from geofrac.mls import cmulti

__all__ = ["GrainDriver"]


class GrainDriver(CrackDriver):
    """Sequentially linear cracking along the grain interfaces of an EFMM scene.

    Args: as :class:`~geofrac.fracture.driver.CrackDriver`.
    """

    state: GrainState
    CHECKPOINT_KIND = "grains"

    def __init__(self, config: Any, solution: Any, say: Any, write: bool = False) -> None:
        self._ops: dict[int, NodeOperator] = {}
        self._fit_k: dict[int, tuple[Any, np.ndarray]] = {}
        # the crack's origin and the interfaces on the face, set at the first event
        self._origin: np.ndarray | None = None
        self._face_sites = np.zeros(0, dtype=np.int64)
        super().__init__(config, solution, say, write)
        d = self.scene.discretization
        # the element's own domains and stress coefficients serve results.xdmf and the
        # grains file of the last state
        self.problem.element.setup(self.D, d.q_rand, d.domain_seed)
        kernels.load("cmulti", self.comm)  # collective: rank 0 compiles on first use

    # -- set-up ----------------------------------------------------------------------
    def _make_state(
        self,
        mesh_e: EdgeMesh,
        bc_nodes: np.ndarray,
        frozen: np.ndarray,
        forced: np.ndarray,
        settings: MlsSettings,
    ) -> GrainState:
        """The grain state: domains as the EFMM element builds them, interfaces per edge.

        The interfaces inside the triangles that touch a Dirichlet node never crack (the
        edges chapter 2 freezes: point supports and loads concentrate stress there);
        ``mls_region`` selects nodes (not cells) that use
        C-MultiMLSM from the start.
        """
        gm, d = self.gm, self.scene.discretization
        self.domains = integration_domains(gm.coords, gm.cells, d.q_rand, d.domain_seed)
        self.faces = interfaces(mesh_e, self.domains)
        n = len(gm.coords)
        frozen_nodes = np.zeros(n, dtype=bool)
        frozen_nodes[bc_nodes] = True
        forced_nodes = np.zeros(n, dtype=bool)
        if self.config.mls_region is not None:
            x0, y0, x1, y1 = self.config.mls_region
            c = gm.coords
            forced_nodes = (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)
        state = GrainState(
            mesh_e,
            self.faces,
            frozen_nodes,
            forced_nodes,
            settings,
            self._rank_map,
            self.config.switch,
        )
        state.crackable[np.unique(mesh_e.cell_edges[frozen])] = False
        return state

    def _group_sites(self, pairs: np.ndarray) -> np.ndarray:
        """A notch line: the interfaces between its nodes and those on its left."""
        return side_sites(self.state.mesh, pairs)

    def _operator(self, node: int) -> NodeOperator:
        """EFMM operators of any node (cached)."""
        op = self._ops.get(node)
        if op is None:
            f = self.faces
            mine = f.grain_order[f.grain_offsets[node] : f.grain_offsets[node + 1]]
            op = node_operator(self.gm.coords, self.gm.cells, self.D, self.domains, node, mine)
            self._ops[node] = op
        return op

    def _setup_cells(self) -> None:
        """Owned nodes, their EFMM matrices (COO) and stress operators at the interfaces."""
        gm, bs = self.gm, self.bs
        lo, hi = self.row0 // bs, (self.row0 + self.n_local) // bs
        own = np.flatnonzero((gm.node_block >= lo) & (gm.node_block < hi))
        self.own_cells = own  # the driver's units are nodes
        self.owned_flag = np.zeros(len(gm.coords), dtype=bool)
        self.owned_flag[own] = True
        ops = [self._operator(int(i)) for i in own]
        pad = self.n_global
        nd = max((2 * len(op.patch) for op in ops), default=2)
        dofs = np.full((len(own), nd), pad, dtype=np.int64)
        K = np.zeros((len(own), nd, nd))
        rows, cols, vals, unit = [], [], [], []
        pair_unit, pair_edge, pair_slot, pair_S = [], [], [], []
        for k, (i, op) in enumerate(zip(own, ops, strict=True)):
            dd = self._mls_dofs(op.patch)
            m = len(dd)
            dofs[k, :m] = dd
            Kt = self.t * op.K  # per unit thickness in node_operator; t as the C-MultiMLSM K
            K[k, :m, :m] = Kt
            rows.append(np.repeat(dd, m))
            cols.append(np.tile(dd, m))
            vals.append(Kt.ravel())
            unit.append(np.full(m * m, k))
            edges = self.state.edges_of_node(int(i))
            S = op.stress_at(self.faces.point[edges])  # shape=(k, 3, m)
            Sp = np.zeros((len(edges), 3, nd))
            Sp[:, :, :m] = S
            pair_unit.append(np.full(len(edges), k))
            pair_edge.append(edges)
            pair_slot.append((self.state.mesh.edges[edges, 1] == i).astype(np.int64))
            pair_S.append(Sp)
        cat = np.concatenate
        empty_i = np.zeros(0, dtype=np.int64)
        self._coo = (
            cat(rows) if rows else empty_i,
            cat(cols) if cols else empty_i,
            cat(vals) if vals else np.zeros(0),
            cat(unit) if unit else empty_i,
        )
        self._int_dofs, self._int_K = dofs, K
        self._pair_unit = cat(pair_unit) if pair_unit else empty_i
        self._pair_edge = cat(pair_edge) if pair_edge else empty_i
        self._pair_slot = cat(pair_slot) if pair_slot else empty_i
        self._pair_S = cat(pair_S) if pair_S else np.zeros((0, 3, nd))
        self._reacting = np.flatnonzero(np.any(self._control_sign[dofs] != 0, axis=1))

    # -- unit hooks of the event loop ------------------------------------------------
    def _intact_coo(self, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        rows, cols, vals, unit = self._coo
        on = keep[unit]
        return rows[on], cols[on], vals[on]

    def _intact_blocks(self, units: list[int]) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        out = {}
        for i in units:
            op = self._operator(int(i))
            out[i] = (self._mls_dofs(op.patch), self.t * op.K)
        return out

    def _fit_block(self, c: int, fit: Any) -> tuple[np.ndarray, np.ndarray] | None:
        if fit is None or fit.order <= 0:
            return None
        return self._mls_dofs(fit.nodes), self._mls_stiffness(c, fit)

    def _mls_stiffness(self, c: int, fit: Any) -> np.ndarray:
        """C-MultiMLSM stiffness (3.28) of node c by the compiled kernel (cached per fit)."""
        cached = self._fit_k.get(c)
        if cached is not None and cached[0] is fit:
            return cached[1]
        coords = self.gm.coords
        order, _, k = cmulti.compiled_node(
            coords[c],
            fit.h,
            coords[fit.nodes[1:]],
            fit.order,
            self.faces.grain(c),
            self.D,
            self.t,
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

    def _use_counts(self, is_mls: np.ndarray) -> np.ndarray:
        """How many grains give stiffness to each DOF (replicated), shape=(n_global,)."""
        e = self.state.mesh.edges
        n = len(self.gm.coords)
        intact = ~is_mls
        nodes = [np.flatnonzero(intact), e[intact[e[:, 0]], 1], e[intact[e[:, 1]], 0]]
        counts = np.bincount(np.concatenate(nodes), minlength=n)
        for fit in self.state.fits.values():
            if fit.order > 0:
                counts[fit.nodes] += 1
        use = np.zeros(self.n_global, dtype=np.int64)
        for k in range(2):
            use[self.gm.node_block * self.bs + k] = counts
        return use

    def _stiffless_nodes(self) -> np.ndarray:
        """Switched nodes with a rotation-only or no field: their grain has no strain."""
        nodes = [i for i, f in self.state.fits.items() if f is None or f.order <= 0]
        return np.array(sorted(nodes), dtype=np.int64)

    def _links(self, is_mls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        e = self.state.mesh.edges
        on = ~is_mls[e[:, 0]] | ~is_mls[e[:, 1]]
        a, b = [e[on, 0]], [e[on, 1]]
        for fit in self.state.fits.values():
            if fit.order > 0:
                a.append(np.full(len(fit.nodes) - 1, fit.nodes[0]))
                b.append(fit.nodes[1:])
        return np.concatenate(a).astype(np.int64), np.concatenate(b).astype(np.int64)

    def measures(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(σ1 per interface, strain energy, control reaction) of a global solution u.

        σ1 of an interface is the larger of its two grains' largest principal stresses at
        its centre (seed 3.3.1); each rank evaluates the grains it owns.
        """
        state = self.state
        is_mls = state.is_mls()
        ne = len(state.mesh.edges)
        s1 = np.zeros((ne, 2))
        u_ext = np.append(u, 0.0)
        live = ~is_mls[self.own_cells]
        p = live[self._pair_unit]
        ud_pairs = u_ext[self._int_dofs[self._pair_unit[p]]]
        stress = np.einsum("psd,pd->ps", self._pair_S[p], ud_pairs)
        s1[self._pair_edge[p], self._pair_slot[p]] = normal_stress(
            stress, self.faces.normal[self._pair_edge[p]]
        )
        ud = u_ext[self._int_dofs[live]]
        ku = np.einsum("nij,nj->ni", self._int_K[live], ud)
        energy = 0.5 * float(np.sum(ud * ku))
        sign = self._control_sign
        reaction = float(np.sum(ku * sign[self._int_dofs[live]]))
        for i, fit in state.fits.items():
            if not self.owned_flag[i]:
                continue
            edges = state.edges_of_node(i)
            d = self._mls_dofs(fit.nodes)
            uf = u[d]
            if fit.order > 0:
                B = fit.strain_matrix(self.faces.point[edges])  # shape=(k, 3, nd)
                sig = np.einsum("ij,kjd,d->ki", self.D, B, uf)
                slot = (state.mesh.edges[edges, 1] == i).astype(np.int64)
                s1[edges, slot] = normal_stress(sig, self.faces.normal[edges])
                k = self._mls_stiffness(i, fit)
                f = k @ uf
                energy += 0.5 * float(uf @ f)
                reaction += float(f @ sign[d])
        self.comm.Allreduce(MPI.IN_PLACE, s1, op=MPI.SUM)
        energy = self.comm.allreduce(energy, op=MPI.SUM)
        reaction = self.comm.allreduce(reaction, op=MPI.SUM)
        return s1.max(axis=1), energy, reaction

    def l2_error(self, u: np.ndarray) -> float:
        """||u_h - u_exact||_L2 of the CST displacement field (EFMM's, eq. 3.2a).

        A 6-point rule of degree 4 on the owned cells (exact for a linear solution).
        """
        exact = self.problem.exact
        gm = self.gm
        bary, w = GAUSS_6
        cells = np.flatnonzero(gm.owned)
        x = gm.coords[gm.cells[cells]]  # shape=(n, 3, 2)
        d = u[self._mls_dofs(gm.cells[cells].ravel())].reshape(len(cells), 3, 2)
        pts = np.einsum("qk,ckd->cqd", bary, x)
        uh = np.einsum("qk,ckd->cqd", bary, d)
        ue = np.stack(np.broadcast_arrays(*exact.displacement(pts[..., 0], pts[..., 1])), axis=-1)
        area = self.state.mesh.areas()[cells]
        total = float(np.sum(area[:, None] * w * np.sum((uh - ue) ** 2, axis=-1)))
        return math.sqrt(self.comm.allreduce(total, op=MPI.SUM))

    def _state_text(self) -> str:
        """The crack state in a few words, for the start-up message."""
        state = self.state
        return (
            f"{len(state.mesh.edges)} grain interfaces, {len(self.precracked)} pre-cracked "
            f"({len(self.random_precracked)} at random), {len(state.fits)} C-MultiMLSM "
            f"grains, {int((~state.crackable).sum())} interfaces frozen next to Dirichlet nodes"
        )

    def _site_point(self, edge: int) -> np.ndarray:
        """The interface's centre X_ij, shape=(2,)."""
        return self.faces.centre[edge]

    def _face_x(self, edges: np.ndarray) -> float | None:
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
            group = np.asarray(self.group_precracked, dtype=np.int64)
            self._origin = group if len(group) else np.asarray(edges, dtype=np.int64)
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

    # -- output ----------------------------------------------------------------------
    def _open_outputs(self, keep_until: float | None = None) -> Any:
        if not (self.write and self.scene.output.xdmf) or self.comm.rank != 0:
            return None
        seg = self.faces.segments.reshape(-1, 2)  # 4 points per interface
        lines = np.arange(len(seg)).reshape(-1, 2)
        return (
            self._series("cracks.xdmf", seg, lines, keep_until),
            self._series("damage.xdmf", self.gm.coords, self.gm.cells, keep_until),
        )

    def _checkpoint_extra(self) -> dict[str, Any]:
        """The crack origin that ``face`` reports follow (set at the first event)."""
        origin = None if self._origin is None else [int(e) for e in self._origin]
        return {"origin": origin, "face_sites": [int(e) for e in self._face_sites]}

    def _restore_extra(self, extra: dict[str, Any]) -> None:
        if extra.get("origin") is not None:
            self._origin = np.asarray(extra["origin"], dtype=np.int64)
            self._face_sites = np.asarray(extra.get("face_sites", []), dtype=np.int64)

    def _write_frame(self, writer: Any, event: int, u: np.ndarray, final: bool = False) -> None:
        state = self.state
        cracks, damage = writer
        crack = np.repeat(state.cracked.astype(float), 2)
        pre = np.zeros(len(state.cracked))
        pre[self.precracked] = 1.0
        cracks.write(float(event), cell_data={"crack": crack, "precracked": np.repeat(pre, 2)})
        disp = u[(self.gm.node_block[:, None] * self.bs + np.arange(2))]
        order = state.orders().astype(float)
        damage.write(
            float(event),
            point_data={
                "displacement": disp,
                "order": order,
                "fragment": (order < 0).astype(float),
            },
        )

    def _site_segments(self, sites: np.ndarray) -> np.ndarray:
        """The two segments of each selected interface, shape=(2k, 2, 2)."""
        return self.faces.segments[sites].reshape(-1, 2, 2)

    def _draw_extra(self, ax: Any) -> None:
        """Fill the fragment grains in ``cracks.png``."""
        from matplotlib.collections import PolyCollection

        frag = self.state.fragments()
        if len(frag):
            polys = [t for i in frag for t in self.faces.grain(int(i))]
            ax.add_collection(PolyCollection(polys, facecolors="0.3", edgecolors="none"))

    def _write_log(self, rows: list[dict[str, Any]]) -> None:
        super()._write_log(rows)
        if self.comm.rank != 0 or not self.write:
            return
        from geofrac.io.grains import grain_polygons, write_grains

        f = self.faces
        node = np.repeat(np.arange(len(f.grain_offsets) - 1), np.diff(f.grain_offsets))
        grains = grain_polygons(self.gm.input_ids[node], f.grain_subs)
        state = self.state
        cracked = np.bincount(
            state.mesh.edges[state.cracked].ravel(), minlength=len(self.gm.coords)
        ).astype(float)
        order = state.orders().astype(float)
        at = np.searchsorted(self.gm.input_ids, grains.node)
        write_grains(
            self.out_dir / "grain_cracks",
            grains,
            {
                "order": order[at],
                "fragment": (order[at] < 0).astype(float),
                "cracked_interfaces": cracked[at],
            },
        )

    def _main_crack(self) -> dict[str, Any] | None:
        """The crack joined to the origin (see :meth:`_face_x`) at the end.

        Its interfaces (the origin's included) and, with a ``face``, its interface
        centre nearest to the face's boundary edges and that distance: where a crack
        that stops short of the face ends.
        """
        if self._origin is None:
            return None
        m, centre = self.state.mesh, self.faces.centre
        main = np.flatnonzero(connected_cracks(m, self.state.cracked, self._origin))
        out: dict[str, Any] = {"interfaces": len(main)}
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

    def _results(
        self,
        rows: list[dict[str, Any]],
        end: str,
        elapsed: float,
        face_hit: Any,
        done: int | None = None,
    ) -> dict[str, Any]:
        out = super()._results(rows, end, elapsed, face_hit, done)
        orders = self.state.orders()
        for key in ("mls_cells", "void_cells", "cracked_edges", "new_cracked_edges",
                    "precracked_edges", "edges"):  # fmt: skip
            out.pop(key)
        state = self.state
        out |= {
            "sites": "grain interfaces",
            "interfaces": len(state.mesh.edges),
            "cracked_interfaces": int(state.cracked.sum()),
            "new_cracked_interfaces": int(state.cracked.sum()) - len(self.precracked),
            "precracked_interfaces": len(self.precracked),
            "random_precracked_interfaces": len(self.random_precracked),
            "grains": len(orders),
            "main_crack": self._main_crack(),
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
        return out
