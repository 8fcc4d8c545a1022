"""The sequentially linear event loop (seed Fig. 2.6) on a distributed mesh.

Division of work:

- the crack state (:class:`~geofrac.fracture.state.CrackState`: edges, visibility, MLS
  fits) is pure numpy on the *global* mesh and replicated on every rank, in the mesh
  file's numbering; the event sequence therefore does not depend on the number of ranks;
- each rank computes the matrices, stresses, energy and reactions of the cells it owns in
  DOLFINx's partition; the stiffness is assembled through PETSc's COO interface (entries
  of other ranks' rows travel with PETSc's own assembly), because an MLS cell couples
  nodes that are not its vertices and so falls outside any finite element sparsity
  pattern; the per-cell σ1 values are gathered to every rank for the criterion;
- the solve is PETSc's MUMPS. ``solver = "update"`` (the default) keeps one
  factorisation for many events and corrects its solution exactly for the cells changed
  since (:mod:`geofrac.fracture.incremental`: Woodbury on the touched DOFs, with entries
  of the inverse from MUMPS's sparse solves), refactorising when the touched DOFs exceed
  ``update_dofs`` or a piece is cut free; ``"reuse"`` uses the factorisation as the
  preconditioner of CG, renewed when CG needs more than ``reuse_iterations``
  iterations; ``"refactor"`` factorises every event (the reference).

Each event: unit load (the scene's prescribed displacements as given) → solve → σ1 per
edge → the edge with least r = f_t/σ1 cracks → the solution scaled by r is the state of
the event (2.21) → record → refit the changed cells → repeat.
"""

from __future__ import annotations

import csv
import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from geofrac import elements
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
from geofrac.fracture.criterion import edge_principal, select_edges
from geofrac.fracture.incremental import Gather, IncrementalSolver, Stale
from geofrac.fracture.state import CrackState, MlsSettings
from geofrac.fracture.topology import (
    EdgeMesh,
    components,
    edge_mesh,
    free_motion_pins,
    random_sites,
    zero_energy_rows,
)
from geofrac.log import format_seconds
from geofrac.materials import d_matrix, lame
from geofrac.mls.shape import strain_matrix
from geofrac.solvers import LinearSolver

__all__ = ["END_REASONS", "CrackDriver", "GlobalMesh", "gather_mesh"]

#: Why an event loop ends.
END_REASONS = ("max_events", "energy_drop", "no_tensile_edge", "separated", "singular")

#: The body is *separated* when the unit-load strain energy falls below this fraction of
#: its value at the first event: no load path is left between the control group and the
#: supports (the seed's "unstable" end, reached without a singular matrix because both
#: pieces are held by Dirichlet conditions).
SEPARATED = 1e-9

#: Options prefix of the crack solver.
PREFIX = "geofrac_crack_"

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

#: Marks a cell that uses its element's field (not an MLS fit).
_FE = "fe"

EVENT_COLUMNS = (
    "event",
    "edge",
    "node_a",
    "node_b",
    "x",
    "y",
    "r",
    "load_factor",
    "control_displacement",
    "reaction",
    "strain_energy",
    "edges_cracked",
    "iterations",
)


@dataclass
class GlobalMesh:
    """The distributed mesh gathered on every rank in a rank-independent numbering.

    Attributes:
        coords: node coordinates, shape=(num_nodes, 2).
        cells: node ids per cell, ordered by the mesh file's cell order, shape=(nc, 3).
        input_ids: the mesh file's node index of each node (sorted), shape=(num_nodes,).
        node_block: PETSc global block (vertex) index of each node, shape=(num_nodes,).
        owned: whether this rank owns each cell, shape=(nc,).
        local_cell: global cell id of each local (owned + ghost) DOLFINx cell,
            shape=(num_local_cells,).
    """

    coords: np.ndarray
    cells: np.ndarray
    input_ids: np.ndarray
    node_block: np.ndarray
    owned: np.ndarray
    local_cell: np.ndarray

    def nodes_of(self, input_ids: np.ndarray) -> np.ndarray:
        """Node ids of mesh-file node indices, same shape."""
        return np.searchsorted(self.input_ids, input_ids)


def gather_mesh(mesh: dolfinx.mesh.Mesh, space: dolfinx.fem.FunctionSpace) -> GlobalMesh:
    """Gather cells, coordinates and DOF blocks of a P1-geometry triangle mesh (collective).

    ``space`` is a vertex (P1) space whose blocks follow the cell vertices.
    """
    comm = mesh.comm
    n_own = mesh.topology.index_map(2).size_local
    geo = mesh.geometry.dofmaps[0]  # shape=(num_local_cells, 3): geometry nodes
    inp = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    orig = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)
    imap = space.dofmap.index_map
    blocks = imap.local_to_global(space.dofmap.list[:n_own].ravel().astype(np.int32))
    parts = comm.allgather(
        (
            orig[:n_own],
            inp[geo[:n_own]],
            np.asarray(blocks, dtype=np.int64).reshape(-1, 3),
            mesh.geometry.x[geo[:n_own]][:, :, :2],
        )
    )
    orig_all = np.concatenate([p[0] for p in parts])
    rank_of = np.concatenate([np.full(len(p[0]), r) for r, p in enumerate(parts)])
    order = np.argsort(orig_all)
    cell_inp = np.concatenate([p[1] for p in parts])[order]
    cell_blocks = np.concatenate([p[2] for p in parts])[order]
    cell_x = np.concatenate([p[3] for p in parts])[order]
    ids, inverse = np.unique(cell_inp, return_inverse=True)
    inverse = inverse.reshape(-1, 3)
    coords = np.zeros((len(ids), 2))
    coords[inverse.ravel()] = cell_x.reshape(-1, 2)
    node_block = np.zeros(len(ids), dtype=np.int64)
    node_block[inverse.ravel()] = cell_blocks.ravel()
    sorted_orig = orig_all[order]
    local = np.searchsorted(sorted_orig, orig[: len(geo)])
    return GlobalMesh(coords, inverse, ids, node_block, rank_of[order] == comm.rank, local)


def _facet_nodes(
    mesh: dolfinx.mesh.Mesh, gm: GlobalMesh, dim: int, entities: np.ndarray
) -> np.ndarray:
    """Global node ids of local mesh entities, gathered from all ranks, shape=(n, dim + 1)."""
    if dim == 0:
        nodes = dolfinx.mesh.entities_to_geometry(mesh, 0, entities.astype(np.int32)).reshape(-1, 1)
    else:
        nodes = dolfinx.mesh.entities_to_geometry(mesh, dim, entities.astype(np.int32))
    inp = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[nodes]
    parts = mesh.comm.allgather(inp.reshape(-1, dim + 1))
    out = np.concatenate(parts) if parts else np.zeros((0, dim + 1), dtype=np.int64)
    return gm.nodes_of(out)


def _matvecs(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """One small matrix-vector product per cell, cells last (contiguous, vectorised).

    Args:
        M: the matrices, shape=(r, k, num_cells).
        x: the vectors, shape=(k, num_cells).

    Returns:
        M x per cell, shape=(r, num_cells).
    """
    out = M[:, 0] * x[0]
    for j in range(1, x.shape[0]):
        out += M[:, j] * x[j]
    return out


class _ReferencePC:
    """PCSHELL context: apply a reference factorisation (a :class:`LinearSolver`)."""

    def __init__(self, solver: LinearSolver) -> None:
        self.solver = solver

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        self.solver.ksp.solve(x, y)


@dataclass
class _Timing:
    """Seconds per phase of the event loop on this rank."""

    seconds: dict[str, float] = field(
        default_factory=lambda: dict.fromkeys(("assemble", "solve", "criterion", "update"), 0.0)
    )
    factorizations: int = 0
    iterations: int = 0
    #: why the ``update`` solver factorised afresh: kind -> count.
    stale: dict[str, int] = field(default_factory=dict)
    #: refinement steps of the ``update`` solver that needed solves with the factor.
    refinements: int = 0

    def add(self, phase: str, t0: float) -> float:
        t1 = time.perf_counter()
        self.seconds[phase] += t1 - t0
        return t1


#: Seconds between two ``fsync`` of the streamed event log (it is flushed every event).
FSYNC_S = 1.0


@dataclass
class _EventLog:
    """``events.csv`` open for appending rows (rank 0).

    Each row is flushed to the operating system as its event completes, which a killed
    process (SIGKILL) cannot undo; ``fsync`` (against a crash of the machine) costs about
    0.3 ms on the development machine, up to 1 % of a small model's event, so it runs at
    most once per :data:`FSYNC_S` seconds, at checkpoints and on closing.
    """

    handle: Any
    writer: Any
    synced: float = field(default_factory=time.monotonic)

    def writerow(self, row: dict[str, Any]) -> None:
        """Append one event's row and flush it."""
        self.writer.writerow(row)
        self.handle.flush()
        if time.monotonic() - self.synced >= FSYNC_S:
            self.sync()

    def sync(self) -> None:
        """Flush and ``fsync`` the file."""
        self.handle.flush()
        os.fsync(self.handle.fileno())
        self.synced = time.monotonic()

    def close(self) -> None:
        """Sync and close."""
        try:
            self.sync()
        finally:
            self.handle.close()


class CrackDriver:
    """Sequentially linear crack propagation for one scene.

    Args:
        config: the validated ``[cracking]`` settings.
        solution: the runner's :class:`~geofrac.runner.Solution` with the problem set up
            and compiled (its load vector and Dirichlet data are used; its matrix is not).
        say: progress printer (rank 0).
        write: write ``events.csv``, the pictures and the XDMF series into
            ``output.dir`` (the results are returned either way; the rows of the event
            log stay in :attr:`rows`).
    """

    #: the loop's kind in its checkpoints (:class:`~geofrac.io.checkpoint.RunControl`).
    CHECKPOINT_KIND = "cracking"

    def __init__(self, config: Any, solution: Any, say: Any, write: bool = False) -> None:
        self.config, self.say, self.write = config, say, write
        self.scene, self.problem, self.tagged = solution.scene, solution.problem, solution.tagged
        #: checkpoints, signal stop and resume data (:class:`~geofrac.io.checkpoint.RunControl`)
        self.control = getattr(solution, "control", None)
        if self.control is not None:  # checkpoints name the loop that wrote them
            self.control.kind = self.CHECKPOINT_KIND
        self.out_dir = self.scene.output.dir
        mesh = self.tagged.mesh
        self.mesh, self.comm = mesh, mesh.comm
        self.element = self.scene.discretization.element
        self.spec = elements.get(self.element)
        self.bs = self.spec.vertex_dofs[2]
        #: extra vertex DOFs under a unit rigid rotation, shape=(bs - 2,).
        self._rotation = (
            dofs_from_gradient(KINDS[self.element], np.array([[[0.0, -1.0], [1.0, 0.0]]]))[0]
            if self.element in KINDS
            else np.zeros(0)
        )
        self.unknown = self.problem._unknown()
        space = self.unknown.function_space
        self.gm = gather_mesh(mesh, space)
        mat = self.scene.material
        self.D = d_matrix(mat.E, mat.nu, 2, mat.plane)
        self.t = mat.thickness
        _, mu = lame(mat.E, mat.nu, 2, mat.plane)
        self.penalty = self.scene.discretization.zero_mode_penalty * mu
        imap = space.dofmap.index_map
        self.n_local = imap.size_local * self.bs
        self.n_global = imap.size_global * self.bs
        self.row0 = imap.local_range[0] * self.bs
        self._setup_crack_state()
        self._setup_cells()
        self.timing = _Timing()
        self.solver: LinearSolver | None = None
        self.ksp: PETSc.KSP | None = None
        #: the ``update`` solver's reference factorisation and correction.
        self.inc: IncrementalSolver | None = None
        #: cells changed by the last event, not yet applied to ``inc``, shape=(k,).
        self._pending = np.zeros(0, dtype=np.int64)
        #: MLS fits at the reference (cells absent use their element), and the
        #: contribution applied since for each cell changed after it (fit, None or _FE).
        self._ref_fits: dict[int, Any] = {}
        self._applied: dict[int, Any] = {}
        #: cells giving stiffness to each DOF as applied to ``inc``, shape=(n_global,).
        self._use = np.zeros(0, dtype=np.int64)
        #: MLS cells of this rank for the vectorised measures, and cells to refresh.
        self._table: MlsTable | None = None
        self._table_dirty: list[int] = []
        #: copies the work vector to every rank (set up by :meth:`run`).
        self._gather: Gather | None = None
        #: cell -> (its fit, the fit's stiffness): assembly and measures share it.
        self._mls_k: dict[int, tuple[Any, np.ndarray]] = {}
        self._b0: PETSc.Vec | None = None
        #: nodes of pieces cut free by cracks (no Dirichlet node), held like a node whose
        #: every edge is cracked, shape=(k,).
        self.fragment_nodes = np.zeros(0, dtype=np.int64)
        #: DOFs pinned at their last displacement to stop a supported piece's free
        #: rigid motion, shape=(k,), and their nodes, shape=(k,).
        self.pinned_dofs = np.zeros(0, dtype=np.int64)
        self._pinned_nodes = np.zeros(0, dtype=np.int64)
        self.rows: list[dict[str, Any]] = []

    # -- set-up ----------------------------------------------------------------------
    def _setup_crack_state(self) -> None:
        gm, cfg, bs = self.gm, self.config, self.bs
        rows, vals = self.problem.dirichlet()
        parts = self.comm.allgather((rows, vals))
        self.bc_rows = np.concatenate([p[0] for p in parts]).astype(np.int64)
        self.bc_vals = np.concatenate([p[1] for p in parts])
        order = np.argsort(gm.node_block)
        #: Dirichlet DOFs, shape=(n_global,) bool, and their values (0 elsewhere).
        self._bc_mask = np.zeros(self.n_global, dtype=bool)
        self._bc_mask[self.bc_rows] = True
        self._bc_full = np.zeros(self.n_global)
        self._bc_full[self.bc_rows] = self.bc_vals
        #: node of each Dirichlet DOF, shape=(len(bc_rows),).
        self.bc_row_nodes = order[np.searchsorted(gm.node_block[order], self.bc_rows // bs)]
        bc_nodes = np.unique(self.bc_row_nodes)
        mesh_e = edge_mesh(gm.coords, gm.cells)
        frozen = np.isin(gm.cells, bc_nodes).any(axis=1)
        forced = np.zeros(len(gm.cells), dtype=bool)
        if cfg.mls_region is not None:
            x0, y0, x1, y1 = cfg.mls_region
            c = mesh_e.centroids()
            forced = (c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)
        settings = MlsSettings(cfg.neighbours, cfg.margin, cfg.max_radius_factor)
        self.state = self._make_state(mesh_e, bc_nodes, frozen, forced, settings)
        keys = mesh_e.edges[:, 0] * len(gm.coords) + mesh_e.edges[:, 1]
        self._edge_keys = keys
        pre = []
        for group in cfg.precracked:
            dim, ents = self.tagged.entities(group)
            pairs = np.sort(_facet_nodes(self.mesh, gm, dim, ents), axis=1)
            pre.append(self._group_sites(pairs))
        self.precracked = np.unique(np.concatenate(pre)) if pre else np.zeros(0, dtype=np.int64)
        #: sites of the ``precracked`` groups (notches), without the random ones.
        self.group_precracked = self.precracked
        self.random_precracked = random_sites(
            self.state.crackable & ~self.state.mesh.boundary_edges,
            cfg.precracked_fraction,
            cfg.precrack_seed,
        )
        self.precracked = np.union1d(self.precracked, self.random_precracked)
        # control group: its prescribed, non-zero DOFs
        dim, ents = self.tagged.entities(cfg.control)
        control_nodes = np.unique(_facet_nodes(self.mesh, gm, dim, ents))
        on = np.isin(self.bc_row_nodes, control_nodes) & (self.bc_vals != 0)
        self.control_rows, self.control_vals = self.bc_rows[on], self.bc_vals[on]
        #: direction of the prescribed control displacement per DOF (0 elsewhere; one
        #: trailing 0 for the padding index of the MLS table), shape=(n_global + 1,).
        self._control_sign = np.zeros(self.n_global + 1)
        self._control_sign[self.control_rows] = np.sign(self.control_vals)
        self.control_unit = float(np.mean(np.abs(self.control_vals)))
        self.face_nodes = None
        if cfg.face is not None:
            dim, ents = self.tagged.entities(cfg.face)
            self.face_nodes = np.unique(_facet_nodes(self.mesh, gm, dim, ents))

    def _make_state(
        self,
        mesh_e: EdgeMesh,
        bc_nodes: np.ndarray,
        frozen: np.ndarray,
        forced: np.ndarray,
        settings: MlsSettings,
    ) -> Any:
        """The replicated crack state: cracked element edges and MLS cells (chapter 2).

        Args:
            mesh_e: the global mesh with edges.
            bc_nodes: nodes with a Dirichlet DOF, shape=(k,).
            frozen: cells touching a Dirichlet node (they never crack), shape=(nc,).
            forced: cells that use MLS from the start, shape=(nc,).
            settings: the MLS neighbourhood settings.
        """
        return CrackState(mesh_e, frozen, forced, settings, self._rank_map)

    def _group_sites(self, pairs: np.ndarray) -> np.ndarray:
        """Crack sites of a ``precracked`` facet group, given as sorted node pairs."""
        return self.edges_of(pairs)

    def edges_of(self, pairs: np.ndarray) -> np.ndarray:
        """Edge ids of sorted node pairs, shape=(n, 2); error if a pair is no edge."""
        keys = pairs[:, 0] * len(self.gm.coords) + pairs[:, 1]
        idx = np.searchsorted(self._edge_keys, keys)
        idx = np.minimum(idx, len(self._edge_keys) - 1)
        if len(keys) and not np.all(self._edge_keys[idx] == keys):
            raise RunError("cracking.precracked: a tagged facet is not an edge of the mesh")
        return idx

    def _setup_cells(self) -> None:
        gm, bs = self.gm, self.bs
        own = np.flatnonzero(gm.owned)
        self.own_cells = own
        x = gm.coords[gm.cells[own]]
        self.K_fe = fe_matrices(self.spec, x, self.D, self.t, self.penalty)
        self.fe_dofs = self._node_dofs(gm.cells[own].ravel()).reshape(len(own), 3 * bs)
        stress_op = np.einsum("ij,cqjp->cqip", self.D, strain_operator(self.spec, x, MIDPOINTS))
        nc, nd = self.fe_dofs.shape
        #: cells-last copies for :meth:`measures`: the stress at the 3 edge midpoints,
        #: shape=(9, nd, n_own), K, shape=(nd, nd, n_own), and the DOFs, shape=(nd, n_own).
        self._stress_op_t = np.ascontiguousarray(stress_op.reshape(nc, 9, nd).transpose(1, 2, 0))
        self._K_fe_t = np.ascontiguousarray(self.K_fe.transpose(1, 2, 0))
        self._fe_dofs_t = np.ascontiguousarray(self.fe_dofs.T)
        self.owned_flag = np.zeros(len(gm.cells), dtype=bool)
        self.owned_flag[own] = True
        #: owned cells (positions in own_cells) with a control DOF: the only ones whose
        #: forces enter the reaction, shape=(k,).
        self._reacting = np.flatnonzero(np.any(self._control_sign[self.fe_dofs] != 0, axis=1))

    def _rank_map(self, f: Any, items: list[int]) -> list[Any]:
        """:data:`~geofrac.fracture.state.Mapper` sharing ``items`` among the ranks.

        Rank r computes items r, r + size, ...; the results are gathered on every rank
        in order. An exception on any rank is raised on every rank (no rank is left
        waiting in the gather).
        """
        size, rank = self.comm.size, self.comm.rank
        if size == 1 or len(items) < 2 * size:
            return [f(i) for i in items]
        try:
            mine: Any = [f(i) for i in items[rank::size]]
        except Exception as exc:  # re-raised on every rank below
            mine = exc
        parts = self.comm.allgather(mine)
        for part in parts:
            if isinstance(part, Exception):
                raise part
        out: list[Any] = [None] * len(items)
        for r, part in enumerate(parts):
            out[r::size] = part
        return out

    # -- per-event pieces ------------------------------------------------------------
    def _node_dofs(self, nodes: np.ndarray, per_node: int | None = None) -> np.ndarray:
        """Global DOFs of nodes, node by node, shape=(len(nodes) * per_node,).

        All ``block_size`` DOFs of each node, or its first ``per_node`` (2: translations).
        """
        k = self.bs if per_node is None else per_node
        return (self.gm.node_block[nodes][:, None] * self.bs + np.arange(k)).ravel()

    def _mls_dofs(self, nodes: np.ndarray) -> np.ndarray:
        """The translation DOFs an MLS fit couples, shape=(2 len(nodes),)."""
        return self._node_dofs(nodes, 2)

    def _use_counts(self, is_mls: np.ndarray) -> np.ndarray:
        """How many cells give stiffness to each global DOF, shape=(n_global,) (replicated)."""
        dofs = [self._node_dofs(self.gm.cells[~is_mls].ravel())]
        dofs += [self._mls_dofs(f.nodes) for f in self.state.fits.values() if f is not None]
        return np.bincount(np.concatenate(dofs), minlength=self.n_global)

    def assemble(self, held_values: np.ndarray) -> tuple[PETSc.Mat, PETSc.Vec, np.ndarray]:
        """Stiffness and load vector of the current crack state; returns (A, b, held DOFs).

        Dirichlet DOFs and held DOFs (no stiffness, or in a cut-free fragment) are
        applied with ``MatZeroRowsColumns``; held DOFs keep ``held_values``.
        """
        state = self.state
        is_mls = state.is_mls()
        r0, c0, v0 = self._intact_coo(~is_mls[self.own_cells])
        rows, cols, vals = [r0], [c0], [v0]
        for c, fit in state.fits.items():
            block = self._fit_block(c, fit) if self.owned_flag[c] else None
            if block is None:
                continue
            d, k = block
            rows.append(np.repeat(d, len(d)))
            cols.append(np.tile(d, len(d)))
            vals.append(k.ravel())
        diag = np.arange(self.row0, self.row0 + self.n_local, dtype=np.int64)
        rows.append(diag)
        cols.append(diag)
        vals.append(np.zeros(len(diag)))
        A = PETSc.Mat().create(self.comm)
        A.setSizes(((self.n_local, self.n_global), (self.n_local, self.n_global)))
        A.setType(PETSc.Mat.Type.AIJ)
        A.setPreallocationCOO(
            np.concatenate(rows).astype(PETSc.IntType), np.concatenate(cols).astype(PETSc.IntType)
        )
        A.setValuesCOO(np.concatenate(vals), addv=PETSc.InsertMode.ADD_VALUES)
        A.assemble()
        used = self._use_counts(is_mls) > 0
        used[self._node_dofs(self.fragment_nodes)] = False
        used[self.pinned_dofs] = False
        used[self.bc_rows] = True
        held = np.flatnonzero(~used)
        fixed = np.concatenate([self.bc_rows, held])
        values = np.concatenate([self.bc_vals, held_values[held]])
        mine = (fixed >= self.row0) & (fixed < self.row0 + self.n_local)
        if self._b0 is None:
            self._b0 = self.problem.load_vector()
        b = self._b0.copy()
        g = A.createVecRight()
        g.setValues(fixed[mine].astype(PETSc.IntType), values[mine])
        g.assemble()
        A.zeroRowsColumns(fixed[mine].astype(PETSc.IntType), 1.0, g, b)
        g.destroy()
        return A, b, held

    def _intact_coo(self, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """COO triplets (rows, cols, values) of the owned units that keep their element field.

        Args:
            keep: per owned unit (cell), whether it uses its element field,
                shape=(len(own_cells),).
        """
        nd = self.fe_dofs.shape[1]
        rows = np.repeat(self.fe_dofs[keep], nd, axis=1).ravel()
        cols = np.tile(self.fe_dofs[keep], (1, nd)).ravel()
        return rows, cols, self.K_fe[keep].ravel()

    def _fit_block(self, c: int, fit: Any) -> tuple[np.ndarray, np.ndarray] | None:
        """(DOFs, stiffness) of unit c under an MLS fit; None when it has no stiffness."""
        if fit is None:
            return None
        return self._mls_dofs(fit.nodes), self._mls_stiffness(c, fit)

    def _intact_blocks(self, units: list[int]) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """(DOFs, stiffness) of the element field of any units (cells), by unit."""
        if not units:
            return {}
        x = self.gm.coords[self.gm.cells[units]]
        ks = fe_matrices(self.spec, x, self.D, self.t, self.penalty)
        return {c: (self._node_dofs(self.gm.cells[c]), k) for c, k in zip(units, ks, strict=True)}

    def _links(self, is_mls: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Node pairs (a, b) joined by a unit with stiffness: the pieces' graph."""
        a, b = [], []
        for cell in self.gm.cells[~is_mls]:
            a += [cell[0], cell[0]]
            b += [cell[1], cell[2]]
        for fit in self.state.fits.values():
            if fit is not None and len(fit.nodes) > 1:
                a += [fit.nodes[0]] * (len(fit.nodes) - 1)
                b += list(fit.nodes[1:])
        return np.array(a, dtype=np.int64), np.array(b, dtype=np.int64)

    def _find_fragments(self) -> bool:
        """Hold what the supports no longer hold; True if anything new is held.

        Pieces are the nodes joined by uncracked element cells and MLS fits. A piece
        with no Dirichlet DOF is cut free: all its nodes are held at their last
        displacement. A piece whose Dirichlet and pinned DOFs leave a rigid motion free
        (:func:`~geofrac.fracture.topology.constraint_rank` < 3; e.g. a column split off
        between the loading platens, free to slide sideways) gets the fewest u_x/u_y DOFs
        pinned at their last displacement that remove the free motions
        (:func:`~geofrac.fracture.topology.free_motion_pins`), so it goes on carrying load.
        Both choices depend on coordinates only (rank-independent).
        """
        gm, state, bs = self.gm, self.state, self.bs
        a, b = self._links(state.is_mls())
        labels = components(len(gm.coords), a, b)
        anchored = np.unique(labels[np.unique(self.bc_row_nodes)])
        touched = np.zeros(len(gm.coords), dtype=bool)
        touched[a] = True
        touched[b] = True
        loose = np.flatnonzero(touched & ~np.isin(labels, anchored))
        new = np.setdiff1d(loose, self.fragment_nodes)
        if len(new):
            self.fragment_nodes = np.union1d(self.fragment_nodes, new)
            self.say(f"cracking: {len(new)} nodes of cut-free fragments are held")
        rows = np.concatenate([self.bc_rows, self.pinned_dofs])
        nodes = np.concatenate([self.bc_row_nodes, self._pinned_nodes])
        xy = gm.coords[:, :2]
        pinned = []
        for label in anchored:
            on = labels[nodes] == label
            members = np.flatnonzero(touched & (labels == label))
            if not len(members):
                continue  # no cell left to move
            pins = free_motion_pins(xy[nodes[on]], rows[on] % bs, self._rotation, xy[members])
            pinned += [(int(members[i]), comp) for i, comp in pins]
        if pinned:
            pn = np.array([p[0] for p in pinned], dtype=np.int64)
            self._pinned_nodes = np.concatenate([self._pinned_nodes, pn])
            dofs = gm.node_block[pn] * bs + np.array([p[1] for p in pinned])
            self.pinned_dofs = np.concatenate([self.pinned_dofs, dofs])
            self.say(f"cracking: {len(pinned)} DOFs pinned to stop free rigid motions")
        held = self._hold_zero_energy_modes()
        return len(new) > 0 or len(pinned) > 0 or held

    def _stiffless_nodes(self) -> np.ndarray:
        """Nodes whose own unit gives no stiffness, shape=(k,); none for element cells.

        Their DOFs are held only through other units (a grain's satellites), which the
        pieces' graph of :meth:`_find_fragments` counts as joined even when those
        units leave some motion of the DOFs without strain energy.
        """
        return np.zeros(0, dtype=np.int64)

    def _hold_zero_energy_modes(self) -> bool:
        """Pin the DOFs of :meth:`_stiffless_nodes` that move without strain energy.

        The block of the assembled stiffness on those DOFs (Dirichlet, held and pinned
        ones left out) is gathered to every rank; the rows in its zero-energy modes
        (:func:`~geofrac.fracture.topology.zero_energy_rows`, eigenvalues below 1e-10 of
        the mean diagonal entry) are pinned at their last displacement, as a piece's free
        rigid motion is. True if any DOF was pinned. Collective.
        """
        nodes = np.setdiff1d(self._stiffless_nodes(), self.fragment_nodes)
        if not len(nodes):
            return False
        A, b, held = self.assemble(np.zeros(self.n_global))
        dofs = self._node_dofs(nodes)
        dofs = dofs[~np.isin(dofs, np.concatenate([self.bc_rows, held, self.pinned_dofs]))]
        if not len(dofs):  # the same on every rank
            A.destroy()
            b.destroy()
            return False
        index = PETSc.IS().createGeneral(dofs.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        diag = A.createVecLeft()
        try:
            A.getDiagonal(diag)
            scale = diag.norm(PETSc.NormType.NORM_1) / self.n_global
            (sub,) = A.createSubMatrices(index)
            K = sub.convert(PETSc.Mat.Type.DENSE).getDenseArray().copy()
            sub.destroy()
        finally:
            for obj in (A, b, index, diag):
                obj.destroy()
        free = dofs[zero_energy_rows(K, 1e-10 * scale)]
        if not len(free):
            return False
        owner = np.empty(len(self.gm.node_block), dtype=np.int64)
        owner[self.gm.node_block] = np.arange(len(self.gm.node_block))
        self._pinned_nodes = np.concatenate([self._pinned_nodes, owner[free // self.bs]])
        self.pinned_dofs = np.concatenate([self.pinned_dofs, free])
        self.say(
            f"cracking: {len(free)} DOFs of grains without stiffness of their own pinned "
            "(they moved without strain energy)"
        )
        return True

    def solve(self, A: PETSc.Mat, b: PETSc.Vec, x: PETSc.Vec) -> int:
        """Solve with reuse of the reference factorisation; returns CG iterations (0 = direct)."""
        cfg = self.config
        if cfg.solver == "reuse" and self.solver is not None:
            if self.ksp is None:
                self.ksp = PETSc.KSP().create(self.comm)
                self.ksp.setOptionsPrefix(PREFIX + "cg_")
                self.ksp.setType("cg")
                pc = self.ksp.getPC()
                pc.setType("python")
                pc.setPythonContext(_ReferencePC(self.solver))
                self.ksp.setTolerances(rtol=1e-10, atol=0.0, max_it=cfg.reuse_iterations)
                self.ksp.setInitialGuessNonzero(True)
                self.ksp.setFromOptions()
            self.ksp.setOperators(A)
            self.ksp.solve(b, x)
            if self.ksp.getConvergedReason() > 0 and np.isfinite(x.norm()):
                return int(self.ksp.getIterationNumber())
        self._refactor(A)
        assert self.solver is not None
        self.solver.solve(b, x)
        return 0

    def _refactor(self, A: PETSc.Mat) -> None:
        if self.solver is not None:
            self.solver.destroy()
        if self.ksp is not None:
            self.ksp.destroy()
            self.ksp = None
        self.solver = None
        s = self.scene.solver
        options = dict(s.options)
        self.solver = LinearSolver(A, PREFIX, "direct", options, self.n_global)
        self.timing.factorizations += 1

    def _solve_event(self, u_prev: np.ndarray, x: PETSc.Vec) -> tuple[np.ndarray, int]:
        """Unit-load solution of the current crack state on every rank; CG iterations.

        The iterations are 0 for a direct solve. Holds the nodes of cut-free pieces when
        the system turns singular; raises RunError when it stays singular.
        """
        if self.config.solver == "update":
            return self._solve_update(u_prev, x), 0
        t = time.perf_counter()
        A, b, _ = self.assemble(u_prev)
        t = self.timing.add("assemble", t)
        try:
            try:
                its = self.solve(A, b, x)
            except RunError:
                if not self._find_fragments():
                    raise
                A.destroy()
                b.destroy()
                A, b, _ = self.assemble(u_prev)
                its = self.solve(A, b, x)
        finally:
            A.destroy()  # a KSP that still uses it holds its own reference
            b.destroy()
        u = self._gather(x)
        self.timing.add("solve", t)
        return u, its

    def _solve_update(self, u_prev: np.ndarray, x: PETSc.Vec) -> np.ndarray:
        """``solver = "update"``: correct the reference solution, or start a new reference."""
        timing = self.timing
        t = time.perf_counter()
        if self.inc is not None and len(self._pending):
            try:
                self._apply_changes(self._pending, u_prev)
            except Stale as exc:
                self._drop_reference(exc)
        self._pending = np.zeros(0, dtype=np.int64)
        t = timing.add("assemble", t)
        if self.inc is not None:
            try:
                u = self.inc.solve(x)
                timing.add("solve", t)
                return u
            except Stale as exc:
                self._drop_reference(exc)
        return self._new_reference(u_prev, x)

    def _new_reference(self, u_prev: np.ndarray, x: PETSc.Vec) -> np.ndarray:
        """Assemble, factorise and solve the current state; it becomes the reference."""
        bc = self._bc_mask
        for attempt in range(2):
            t = time.perf_counter()
            A, b, held = self.assemble(u_prev)
            t = self.timing.add("assemble", t)
            fixed = bc.copy()
            fixed[held] = True
            try:
                self._refactor(A)
                assert self.solver is not None
                self.inc = IncrementalSolver(
                    A,
                    b,
                    fixed,
                    bc,
                    self._bc_full,
                    self.solver,
                    x,
                    self._gather,
                    self.config.update_dofs,
                )
                self.solver = None  # the reference owns it now
                break
            except RunError:
                self._drop_reference()
                A.destroy()
                b.destroy()
                if attempt or not self._find_fragments():
                    raise
            finally:
                self.timing.add("solve", t)
        self._ref_fits = dict(self.state.fits)
        self._applied = {}
        self._use = self._use_counts(self.state.is_mls())
        assert self.inc is not None
        return self.inc.y.copy()

    def _drop_reference(self, why: Stale | None = None) -> None:
        """Free the reference factorisation; count ``why`` in the refactor reasons."""
        if why is not None:
            self.timing.stale[why.kind] = self.timing.stale.get(why.kind, 0) + 1
        if self.inc is not None:
            self.timing.refinements += self.inc.refinements
        for obj in (self.inc, self.solver):
            if obj is not None:
                obj.destroy()
        self.inc = self.solver = None

    def _apply_changes(self, cells: np.ndarray, u_prev: np.ndarray) -> None:
        """Pass the changed cells' matrices (new − old) to the reference's correction.

        DOFs that lose their last cell are held at ``u_prev``, as :meth:`assemble` does.

        Raises:
            Stale: the change needs a new factorisation.
        """
        assert self.inc is not None
        state = self.state
        pairs = []
        for c in cells.tolist():
            old = self._applied.get(c, self._ref_fits.get(c, _FE))
            new = state.fits.get(c, _FE)
            if old is not new:
                pairs.append((c, old, new))
                self._applied[c] = new
        fe = self._intact_blocks([c for c, old, new in pairs if _FE in (old, new)])
        blocks = []
        for c, old, new in pairs:
            for fit, sign in ((old, -1.0), (new, 1.0)):
                block = fe[c] if fit is _FE else self._fit_block(c, fit)
                if block is None:
                    continue
                dofs, k = block
                self._use[dofs] += int(sign)
                blocks.append((dofs, sign * k))
        if not blocks:
            return
        inc = self.inc
        touched = np.unique(np.concatenate([d for d, _ in blocks]))
        if np.any(inc.held[touched] & (self._use[touched] > 0)):
            raise Stale("held", "a held DOF carries stiffness again")
        hold = touched[(self._use[touched] == 0) & ~inc.fixed[touched] & ~inc.held[touched]]
        inc.apply(blocks, hold, u_prev[hold])

    def _sync_table(self) -> None:
        """Bring the MLS table of the owned cells up to the crack state."""
        state = self.state
        if self._table is None:
            self._table = MlsTable(self.n_global)
            dirty = list(state.fits)
        else:
            dirty, self._table_dirty = self._table_dirty, []
        for c in dirty:
            if not self.owned_flag[c]:
                continue
            fit = state.fits.get(c)
            if fit is None:
                self._table.remove(c)
            else:
                self._table.set(
                    c, self._mls_dofs(fit.nodes), strain_matrix(fit), self.t * state.areas[c]
                )

    def measures(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(σ1 per edge, strain energy, control reaction) of a global solution u.

        Vectorised over the owned cells: element cells by their stress operators and
        matrices, MLS cells by the padded :class:`MlsTable`. The reaction sums the
        forces f = K u of the cells on the control DOFs (signed by the prescribed
        direction).
        """
        state, own = self.state, self.own_cells
        is_mls = state.is_mls()
        s1 = np.zeros((len(self.gm.cells), 3))
        u_ext = np.append(u, 0.0)
        ud = u[self._fe_dofs_t]  # shape=(nd, n_own)
        fe = ~is_mls[own]
        stress = _matvecs(self._stress_op_t, ud).reshape(3, 3, -1)  # (midpoint, component, cell)
        s1[own[fe]] = principal_max(np.moveaxis(stress, 1, 2)).T[fe]
        ku = _matvecs(self._K_fe_t, ud)  # shape=(nd, n_own)
        energy = 0.5 * float(np.sum(ud * ku, axis=0) @ fe)
        sign = self._control_sign
        r = self._reacting[fe[self._reacting]]
        reaction = float(np.sum(ku[:, r] * sign[self._fe_dofs_t[:, r]]))
        self._sync_table()
        table = self._table
        assert table is not None
        eps = table.strains(u_ext)  # shape=(rows, 3)
        sig = eps @ self.D.T
        live = table.cells >= 0
        s1[table.cells[live]] = principal_max(sig[live])[:, None]
        energy += 0.5 * float(np.sum(table.weight * np.sum(eps * sig, axis=1)))
        force = table.weight[:, None] * np.einsum("rip,ri->rp", table.B, sig)
        reaction += float(np.sum(force * sign[table.dofs]))
        self.comm.Allreduce(MPI.IN_PLACE, s1, op=MPI.SUM)
        energy = self.comm.allreduce(energy, op=MPI.SUM)
        reaction = self.comm.allreduce(reaction, op=MPI.SUM)
        return edge_principal(state.mesh, s1), energy, reaction

    def l2_error(self, u: np.ndarray) -> float:
        """||u_h - u_exact||_L2 of eq. (2.22), each cell with its own field (collective).

        A 6-point Gauss rule of degree 4 is exact for the squared error of the linear
        (CST, MLS) and quadratic (RGNT, GNT) fields against a linear exact solution.
        """
        exact = self.problem.exact
        gm, state, bs = self.gm, self.state, self.bs
        bary, w = GAUSS_6
        total = 0.0
        for c in self.own_cells:
            x = gm.coords[gm.cells[c]]
            pts = bary @ x
            fit = state.fits.get(int(c), _FE)
            if fit is _FE:
                d = u[self._node_dofs(gm.cells[c])].reshape(3, bs)
                if self.element in ("cst", "p1"):
                    uh = bary @ d
                else:
                    uh = vertex_field(KINDS[self.element], x, d, pts)
            elif fit is None:
                uh = np.zeros((len(pts), 2))
            else:
                nodal = u[self._mls_dofs(fit.nodes)].reshape(-1, 2)
                uh = fit.shape_functions(pts) @ nodal
            ue = np.stack(np.broadcast_arrays(*exact.displacement(pts[:, 0], pts[:, 1])), axis=1)
            total += state.areas[c] * float(w @ np.sum((uh - ue) ** 2, axis=1))
        return math.sqrt(self.comm.allreduce(total, op=MPI.SUM))

    def _mls_stiffness(self, c: int, fit: Any) -> np.ndarray:
        """Stiffness (2.19) of MLS cell c, computed once per fit (cached for the current one)."""
        cached = self._mls_k.get(c)
        if cached is not None and cached[0] is fit:
            return cached[1]
        k = mls_matrix(fit, self.D, self.t, self.state.areas[c])
        if self.state.fits.get(c, _FE) is fit:
            self._mls_k[c] = (fit, k)
        return k

    # -- the loop --------------------------------------------------------------------
    def run(self) -> dict[str, Any]:
        """Run events until an end condition; write the outputs; return the results.

        With a :class:`~geofrac.io.checkpoint.RunControl` (``solution.control``) the loop
        asks it after each event whether to write a checkpoint or to stop on a signal,
        and continues from ``control.resume`` when given (:meth:`_restore`).
        """
        try:
            return self._run()
        except RunError:  # raised on every rank (Interrupted too): free the solvers
            self.destroy()
            raise

    def _run(self) -> dict[str, Any]:
        cfg, state, control = self.config, self.state, self.control
        t0 = time.perf_counter()
        state.start(self.precracked)
        work = dolfinx.fem.Function(self.unknown.function_space)  # a ghosted vector
        x = work.x.petsc_vec
        self._gather = Gather(x)
        u_unit = np.zeros(self.n_global)
        rows: list[dict[str, Any]] = []
        #: the edges cracked by each event, in order (what a checkpoint replays).
        batches: list[list[int]] = []
        end, peak, face_hit, first_energy = "max_events", 0.0, None, 0.0
        first = 1  # the first event to compute
        done = 0  # events already in the log (a resumed run recomputes those after first)
        resume = control.resume if control is not None else None
        if resume is not None:
            assert control is not None
            control.check_resume()  # the same scene and number of ranks
            loop = self._restore(resume)
            rows, batches, u_unit = loop["rows"], loop["batches"], loop["u_unit"]
            first, done = int(loop["replay_from"]), len(rows)
            first_energy = loop["first_energy"]
            peak = max((r["strain_energy"] for r in rows[: first - 1]), default=0.0)
            face_hit = None if loop["face_hit"] is None else tuple(loop["face_hit"])
        setup = format_seconds(time.perf_counter() - t0)
        self.say(f"cracking: {self._state_text()}; set-up {setup}")
        if resume is not None:
            self.say(
                f"cracking: resuming after event {done} from {resume.path} (events {first}-"
                f"{done} are recomputed from the factorisation they used)"
            )
        writer = self._open_outputs(keep_until=None if resume is None else float(done))
        log = self._open_event_log(rows)
        timing = self.timing
        started = time.perf_counter()
        error = None
        if cfg.max_events == 0:
            u_unit, _ = self._solve_event(u_unit, x)
            if self.problem.exact is not None:
                error = self.l2_error(u_unit)
                self.say(f"cracking: displacement error (2.22) {error:.4e}")
            end = "max_events"
        #: the loop's state at the start of the event whose solve factorised last: a
        #: checkpoint restarts from there, so that a resumed run repeats the solver's
        #: arithmetic (the ``update`` and ``reuse`` solvers reuse that factorisation).
        ref: dict[str, Any] | None = None
        try:
            for event in range(first, cfg.max_events + 1):
                replay = event <= done
                start = self._event_start(event, u_unit, face_hit)
                try:
                    u_unit, its = self._solve_event(u_unit, x)
                except RunError as exc:
                    if replay:
                        raise RunError(f"--resume: event {event} failed on replay: {exc}") from None
                    end = "singular"
                    self.say(f"cracking: event {event}: the system is singular ({exc})")
                    break
                if timing.factorizations > start["timing"]["factorizations"] or ref is None:
                    ref = start
                    # a resumed run factorises this event without a stale reference to
                    # drop: it keeps the reasons and refinements counted by this solve
                    ref["timing"]["stale"] = dict(timing.stale)
                    ref["timing"]["refinements"] = timing.refinements
                timing.iterations += its
                t = time.perf_counter()
                sigma1, energy_unit, reaction_unit = self.measures(u_unit)
                first_energy = energy_unit if event == 1 else first_energy
                if energy_unit <= SEPARATED * first_energy:
                    end = "separated"
                    break
                candidates = ~state.cracked & state.crackable
                edges, r = select_edges(
                    sigma1,
                    candidates,
                    cfg.tensile_strength,
                    cfg.batch_tolerance,
                    cfg.edges_per_event,
                )
                t = timing.add("criterion", t)
                if len(edges) == 0:
                    end = "no_tensile_edge"
                    break
                energy = r * r * energy_unit
                cracked = [int(e) for e in edges]
                if replay:
                    if cracked != batches[event - 1]:
                        raise RunError(
                            f"--resume: event {event} cracked edges {cracked}, the interrupted "
                            f"run {batches[event - 1]}; the checkpoint does not reproduce it"
                        )
                else:
                    a, bnode = state.mesh.edges[edges[0]]
                    mid = self._site_point(int(edges[0]))
                    row = {
                        "event": event,
                        "edge": int(edges[0]),
                        "node_a": int(self.gm.input_ids[a]),
                        "node_b": int(self.gm.input_ids[bnode]),
                        "x": float(mid[0]),
                        "y": float(mid[1]),
                        "r": r,
                        "load_factor": r,
                        "control_displacement": r * self.control_unit,
                        "reaction": r * reaction_unit,
                        "strain_energy": energy,
                        "edges_cracked": len(edges),
                        "iterations": its,
                    }
                    rows.append(row)
                    batches.append(cracked)
                changed = state.crack_many(cracked)
                self._pending = np.union1d(self._pending, changed)
                self._table_dirty += changed.tolist()
                if face_hit is None and self.face_nodes is not None:
                    x_hit = self._face_x(edges)
                    if x_hit is not None:
                        face_hit = (event, x_hit)
                peak = max(peak, energy)
                timing.add("update", t)
                if replay:
                    continue
                if writer is not None and (event % cfg.output_every == 0 or event == 1):
                    self._write_frame(writer, event, r * u_unit)
                if log is not None:
                    log.writerow(row)  # flushed: a killed run keeps every completed event
                if event % max(1, cfg.max_events // 20) == 0:
                    rate = (event - first + 1) / (time.perf_counter() - started)
                    self.say(
                        f"cracking: event {event}/{cfg.max_events}, r = {r:.4g}, energy "
                        f"{energy:.4g}, {rate:.2f} events/s, {timing.factorizations} factorisations"
                    )
                if cfg.energy_drop is not None and energy < (1.0 - cfg.energy_drop) * peak:
                    end = "energy_drop"
                    break
                if control is not None and event < cfg.max_events:
                    save, stop = control.poll(event)
                    if save:
                        assert ref is not None
                        if log is not None:
                            log.sync()  # the log on disk holds the checkpoint's rows
                        self._checkpoint(control, event, rows, batches, first_energy, ref)
                    if stop:
                        control.interrupt(f"event {event}")
        finally:
            self._drop_reference()
            if log is not None:
                log.close()
        elapsed = time.perf_counter() - started
        if writer is not None and rows:
            # the final pattern; it replaces a frame already written for this event, so
            # each time appears once in the series
            self._write_frame(
                writer, rows[-1]["event"], rows[-1]["load_factor"] * u_unit, final=True
            )
        self._finish_field(rows[-1]["load_factor"] * u_unit if rows else u_unit)
        self._write_log(rows)
        self.destroy()
        results = self._results(rows, end, elapsed, face_hit, len(rows) - first + 1)
        if resume is not None:
            results["resumed_after_event"] = done
        if error is not None:
            results["displacement_error_l2"] = error
        self.say(
            f"cracking: {len(rows)} events in {format_seconds(elapsed)} "
            f"({results['events_per_s']:.2f} events/s), end: {end}"
        )
        return results

    # -- checkpoints -----------------------------------------------------------------
    def _event_start(self, event: int, u_prev: np.ndarray, face_hit: Any) -> dict[str, Any]:
        """What a checkpoint needs to restart at ``event``: the state before its solve.

        ``u_prev`` is kept by reference (the loop replaces, never changes, the array).
        """
        t = self.timing
        return {
            "event": event,
            "u_prev": u_prev,
            "fragment_nodes": self.fragment_nodes,
            "pinned_dofs": self.pinned_dofs,
            "pinned_nodes": self._pinned_nodes,
            "face_hit": face_hit,
            "extra": self._checkpoint_extra(),
            "timing": {
                "factorizations": t.factorizations,
                "iterations": t.iterations,
                "refinements": t.refinements,
                "stale": dict(t.stale),
            },
        }

    def _checkpoint(
        self,
        control: Any,
        event: int,
        rows: list[dict[str, Any]],
        batches: list[list[int]],
        first_energy: float,
        ref: dict[str, Any],
    ) -> None:
        """Write checkpoint ``event`` (collective).

        It holds the event log and each event's cracked edges up to ``event`` (JSON),
        and the state at the start of event ``ref["event"]``, whose solve factorised
        last: the unit solution before it and the held and pinned DOFs (arrays alike on
        every rank, written once). A resumed run recomputes the events from there with
        the same factorisation, so it repeats the interrupted run's arithmetic.
        """
        data = {
            "rows": rows,
            "batches": batches,
            "first_energy": first_energy,
            "replay_from": ref["event"],
            "face_hit": ref["face_hit"],
            "timing": ref["timing"],
            "extra": ref["extra"],
        }
        arrays = {
            "u_prev": ref["u_prev"],
            "fragment_nodes": ref["fragment_nodes"],
            "pinned_dofs": ref["pinned_dofs"],
            "pinned_nodes": ref["pinned_nodes"],
        }
        control.save(event, data, shared=arrays)

    def _restore(self, ck: Any) -> dict[str, Any]:
        """Bring the driver to the start of checkpoint ``ck``'s replay event.

        The crack state is rebuilt by cracking the edges of each event before it again,
        in event order (the MLS fits are a function of the cracked edges); the held and
        pinned DOFs and the unit solution before that event (whose values held DOFs
        keep) are read back. Returns the loop's variables (``rows``, ``batches``,
        ``replay_from``, ``u_unit``, ...).
        """
        data, arrays = ck.data, ck.shared()
        replay_from = int(data.get("replay_from", 0))
        u_prev = arrays.get("u_prev")
        if u_prev is None or len(u_prev) != self.n_global or replay_from < 1:
            raise RunError(f"--resume: the checkpoint {ck.path} does not match this mesh")
        for batch in data["batches"][: replay_from - 1]:
            self.state.crack_many([int(e) for e in batch])
        self.fragment_nodes = arrays["fragment_nodes"].astype(np.int64)
        self.pinned_dofs = arrays["pinned_dofs"].astype(np.int64)
        self._pinned_nodes = arrays["pinned_nodes"].astype(np.int64)
        self._pending = np.zeros(0, dtype=np.int64)
        self._table, self._table_dirty = None, []
        t = data["timing"]
        self.timing.factorizations = int(t["factorizations"])
        self.timing.iterations = int(t["iterations"])
        self.timing.refinements = int(t["refinements"])
        self.timing.stale = {k: int(v) for k, v in t["stale"].items()}
        self._restore_extra(data.get("extra", {}))
        return dict(data) | {"u_unit": np.array(u_prev, dtype=float)}

    def _checkpoint_extra(self) -> dict[str, Any]:
        """JSON-ready state a subclass keeps across events (nothing here)."""
        return {}

    def _restore_extra(self, extra: dict[str, Any]) -> None:
        """Restore what :meth:`_checkpoint_extra` saved (nothing here)."""

    def _state_text(self) -> str:
        """The crack state in a few words, for the start-up message."""
        state = self.state
        return (
            f"{len(state.mesh.edges)} edges, {len(self.precracked)} pre-cracked, "
            f"{len(state.fits)} MLS cells ({len(state.void_cells())} void), "
            f"{int((~state.crackable).sum())} edges frozen next to Dirichlet nodes"
        )

    def _site_point(self, edge: int) -> np.ndarray:
        """Where crack site ``edge`` lies, for the event log: the edge midpoint, shape=(2,)."""
        return self.state.mesh.coords[self.state.mesh.edges[edge]].mean(axis=0)

    def _face_x(self, edges: np.ndarray) -> float | None:
        """X of the first node of the new crack sites on the ``face`` group, or None."""
        ends = self.state.mesh.edges[edges].ravel()
        hit = ends[np.isin(ends, self.face_nodes)]
        return float(self.state.mesh.coords[hit[0], 0]) if len(hit) else None

    # -- output ----------------------------------------------------------------------
    def _open_outputs(self, keep_until: float | None = None) -> Any:
        """The XDMF series (rank 0, when writing): new, or continued up to ``keep_until``."""
        if not (self.write and self.scene.output.xdmf) or self.comm.rank != 0:
            return None
        gm, m = self.gm, self.state.mesh
        return (
            self._series("cracks.xdmf", gm.coords, m.edges, keep_until),
            self._series("damage.xdmf", gm.coords, gm.cells, keep_until),
        )

    def _series(
        self, name: str, coords: np.ndarray, cells: np.ndarray, keep_until: float | None
    ) -> Any:
        """Series ``name`` in the output directory; a resumed run keeps steps <= keep_until."""
        from geofrac.io.series import XdmfSeries

        series = XdmfSeries(self.out_dir / name, coords, cells, keep_until=keep_until)
        if series.note is not None:
            self.say(f"cracking: {series.note}")
        return series

    def _open_event_log(self, rows: list[dict[str, Any]]) -> Any:
        """``events.csv`` (rank 0, when writing) with ``rows`` written; None elsewhere.

        Rows are appended and flushed as events complete, so a killed run keeps them.
        """
        if self.comm.rank != 0 or not self.write:
            return None
        handle = open(self.out_dir / "events.csv", "w", newline="")  # noqa: SIM115
        writer = csv.DictWriter(handle, fieldnames=EVENT_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
        handle.flush()
        return _EventLog(handle, writer)

    def _write_frame(self, writer: Any, event: int, u: np.ndarray, final: bool = False) -> None:
        state = self.state
        cracks, damage = writer
        crack = state.cracked.astype(float)
        cracks.write(float(event), cell_data={"crack": crack})
        dmg = crack[state.mesh.cell_edges].mean(axis=1)
        disp = u[(self.gm.node_block[:, None] * self.bs + np.arange(2))]
        damage.write(
            float(event),
            point_data={"displacement": disp},
            cell_data={"damage": dmg, "mls": state.is_mls().astype(float)},
        )

    def _finish_field(self, u: np.ndarray) -> None:
        """Put the last event's state into the problem's displacement (results.xdmf)."""
        v = self.unknown.x.petsc_vec
        v.setArray(u[self.row0 : self.row0 + self.n_local])
        self.unknown.x.scatter_forward()
        self.problem._to_field()

    def _write_log(self, rows: list[dict[str, Any]]) -> None:
        """Keep the rows; draw the load-displacement curve and ``cracks.png`` (rank 0).

        ``events.csv`` was written event by event (:meth:`_open_event_log`).
        """
        self.rows = rows
        if self.comm.rank != 0 or not self.write:
            return
        if rows:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            fig, ax = plt.subplots(figsize=(5, 3.6))
            ax.plot(
                [r["control_displacement"] for r in rows], [r["reaction"] for r in rows], lw=0.8
            )
            ax.set_xlabel(f"control displacement ({self.config.control})")
            ax.set_ylabel("reaction")
            ax.set_title(f"{self.scene.name}: {len(rows)} events")
            fig.tight_layout()
            fig.savefig(self.out_dir / "load_displacement.png", dpi=90)
            plt.close(fig)
            self._plot_cracks(plt)

    def _plot_cracks(self, plt: Any) -> None:
        """``cracks.png``: the mesh outline, pre-existing (grey) and new (red) cracks."""
        from matplotlib.collections import LineCollection

        m, state = self.state.mesh, self.state
        pre = np.zeros(len(m.edges), dtype=bool)
        pre[self.precracked] = True
        new = state.cracked & ~pre
        x0, y0 = m.coords.min(axis=0)
        x1, y1 = m.coords.max(axis=0)
        width = 7.0
        fig, ax = plt.subplots(figsize=(width, max(2.0, width * (y1 - y0) / (x1 - x0))))
        outline = m.coords[m.edges[m.boundary_edges]]
        ax.add_collection(LineCollection(outline, colors="k", linewidths=0.6))
        self._draw_extra(ax)
        ax.add_collection(LineCollection(self._site_segments(pre), colors="0.6", linewidths=0.5))
        ax.add_collection(
            LineCollection(self._site_segments(new), colors="tab:red", linewidths=1.0)
        )
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.set_axis_off()
        fig.tight_layout()
        fig.savefig(self.out_dir / "cracks.png", dpi=110)
        plt.close(fig)

    def _site_segments(self, sites: np.ndarray) -> np.ndarray:
        """Line segments drawing the crack sites selected by a mask, shape=(k, 2, 2)."""
        m = self.state.mesh
        return m.coords[m.edges[sites]]

    def _draw_extra(self, ax: Any) -> None:
        """Draw anything else into ``cracks.png`` below the cracks (nothing here)."""

    def _results(
        self,
        rows: list[dict[str, Any]],
        end: str,
        elapsed: float,
        face_hit: Any,
        done: int | None = None,
    ) -> dict[str, Any]:
        """The loop's JSON results; ``done``: events this run computed (default all)."""
        state, t = self.state, self.timing
        done = len(rows) if done is None else done
        new = int(state.cracked.sum()) - len(self.precracked)
        out: dict[str, Any] = {
            "events": len(rows),
            "end_reason": end,
            "cracked_edges": int(state.cracked.sum()),
            "new_cracked_edges": new,
            "precracked_edges": len(self.precracked),
            "mls_cells": len(state.fits),
            "void_cells": len(state.void_cells()),
            "fragment_nodes": len(self.fragment_nodes),
            "pinned_dofs": len(self.pinned_dofs),
            "edges": len(state.mesh.edges),
            "dofs": self.n_global,
            "events_per_s": done / elapsed if elapsed > 0 else float("nan"),
            "phase_s": {k: self.comm.allreduce(v, op=MPI.MAX) for k, v in t.seconds.items()},
            "factorizations": t.factorizations,
            "refactor_reasons": dict(sorted(t.stale.items())),
            "refinement_solves": t.refinements + (self.inc.refinements if self.inc else 0),
            "cg_iterations": t.iterations,
            "solver": self.config.solver,
        }
        if rows:
            peak = max(rows, key=lambda r: r["reaction"])
            out |= {
                "peak_reaction": peak["reaction"],
                "peak_event": peak["event"],
                "final_strain_energy": rows[-1]["strain_energy"],
            }
        if self.config.face is not None:
            x = None if face_hit is None else face_hit[1] - self.config.face_origin
            out["crack_face"] = {
                "group": self.config.face,
                "event": None if face_hit is None else face_hit[0],
                "x_from_origin": x,
            }
            if self.config.face == "top":
                out["crack_top_x_mm"] = x
        return out

    def destroy(self) -> None:
        """Free the solvers."""
        self._drop_reference()
        for obj in (self.ksp, self._b0, self._gather):
            if obj is not None:
                obj.destroy()
        self.ksp = self._b0 = self._gather = None
