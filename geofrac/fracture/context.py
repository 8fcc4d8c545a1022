"""What every part of the crack driver shares: the gathered mesh, DOF numbering, supports.

:func:`crack_context` builds a :class:`CrackContext` from a set-up problem (collective):
the mesh gathered on every rank in a rank-independent numbering (:class:`GlobalMesh`),
the element, the material matrices, the Dirichlet and control DOFs and the nodes of the
``face`` group. The parts (:mod:`~geofrac.fracture.units`,
:mod:`~geofrac.fracture.assembly`, :mod:`~geofrac.fracture.linear`,
:mod:`~geofrac.fracture.output`) read it; only the event loop changes what they hold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac import elements
from geofrac.elements.spec import ElementSpec
from geofrac.errors import RunError
from geofrac.fem.elastic import ElasticProblem
from geofrac.fem.solution import Solution
from geofrac.fracture.config import CrackingConfig
from geofrac.fracture.control import (
    FORCE_LOADS,
    RELEASE,
    Control,
    displacement_control,
    force_control,
    release_control,
)
from geofrac.fracture.scales import Scales
from geofrac.materials import d_matrix, lame
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Scene

__all__ = [
    "CrackContext",
    "GlobalMesh",
    "JsonValue",
    "Say",
    "Sites",
    "crack_context",
    "facet_nodes",
    "gather_mesh",
    "gather_vector",
]

#: A JSON-ready value (event rows, results, checkpoint data).
JsonValue = int | float | str | bool | None | list["JsonValue"] | dict[str, "JsonValue"]

#: Progress printer (rank 0 prints).
Say = Callable[[str], None]

if TYPE_CHECKING:
    from geofrac.solvers import Vector

_T = TypeVar("_T")


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


def facet_nodes(tagged: TaggedMesh, gm: GlobalMesh, group: str) -> np.ndarray:
    """Global node ids of the entities of ``group``, from all ranks, shape=(n, dim + 1)."""
    mesh = tagged.mesh
    dim, entities = tagged.entities(group)
    if dim == 0:
        nodes = dolfinx.mesh.entities_to_geometry(mesh, 0, entities.astype(np.int32)).reshape(-1, 1)
    else:
        nodes = dolfinx.mesh.entities_to_geometry(mesh, dim, entities.astype(np.int32))
    inp = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[nodes]
    parts = mesh.comm.allgather(inp.reshape(-1, dim + 1))
    out = np.concatenate(parts) if parts else np.zeros((0, dim + 1), dtype=np.int64)
    return gm.nodes_of(out)


@dataclass
class Sites:
    """The crack sites cracked before loading.

    Attributes:
        precracked: all of them, shape=(k,).
        group: those of the ``precracked`` groups (notches), shape=(g,).
        random: those of ``precracked_fraction``, shape=(r,).
    """

    precracked: np.ndarray
    group: np.ndarray
    random: np.ndarray

    def add(self, sites: np.ndarray) -> None:
        """Crack ``sites`` before loading too (tests: a node's star, an island)."""
        self.precracked = np.union1d(self.precracked, sites)


@dataclass
class CrackContext:
    """The set-up data every part of the crack driver reads (replicated unless noted).

    Attributes:
        config: the ``[cracking]`` settings.
        scene, problem, tagged: the scene, its set-up elastic problem and its mesh.
        spec: the element (:func:`geofrac.elements.get`).
        comm: the mesh's communicator.
        say: progress printer.
        gm: the gathered mesh.
        bs: DOFs per vertex (``spec.vertex_dofs[2]``).
        D: plane stress-strain matrix (Voigt, engineering shear), shape=(3, 3).
        t: thickness.
        penalty: α μ of the zero-mode penalty (0 without one).
        n_local, n_global, row0: this rank's DOFs, all DOFs, this rank's first DOF.
        bc_rows, bc_vals: Dirichlet DOFs and values, shape=(k,).
        bc_mask: Dirichlet DOFs, shape=(n_global,) bool; bc_full: their values (0
            elsewhere), shape=(n_global,).
        bc_row_nodes: node of each Dirichlet DOF, shape=(k,); bc_nodes: those nodes,
            unique.
        control_rows, control_vals: the prescribed non-zero DOFs of ``control`` (empty
            under force control).
        control_sign: their direction per DOF (0 elsewhere; one trailing 0 for the
            padding index of the MLS table), shape=(n_global + 1,); all 0 under force
            control, so the units' reaction on them is 0 and unused.
        control_unit: the unit load's a-priori displacement δ: the mean |prescribed
            control displacement|, or F/(E t) under force control (``scales.displacement``).
        control: how the events' control displacement and force are measured.
        face_nodes: nodes of the ``face`` group, or None.
        scales: the unit load's a-priori scales (size, δ, E, volume) that the loop's
            decisions are judged against.
    """

    config: CrackingConfig
    scene: Scene
    problem: ElasticProblem
    tagged: TaggedMesh
    spec: ElementSpec
    comm: MPI.Comm
    say: Say
    gm: GlobalMesh
    bs: int
    D: np.ndarray
    t: float
    penalty: float
    n_local: int
    n_global: int
    row0: int
    bc_rows: np.ndarray
    bc_vals: np.ndarray
    bc_mask: np.ndarray
    bc_full: np.ndarray
    bc_row_nodes: np.ndarray
    bc_nodes: np.ndarray
    control_rows: np.ndarray
    control_vals: np.ndarray
    control_sign: np.ndarray
    control_unit: float
    control: Control
    face_nodes: np.ndarray | None
    scales: Scales

    def node_dofs(self, nodes: np.ndarray, per_node: int | None = None) -> np.ndarray:
        """Global DOFs of nodes, node by node, shape=(len(nodes) * per_node,).

        All ``bs`` DOFs of each node, or its first ``per_node`` (2: translations).
        """
        k = self.bs if per_node is None else per_node
        return (self.gm.node_block[nodes][:, None] * self.bs + np.arange(k)).ravel()

    def mls_dofs(self, nodes: np.ndarray) -> np.ndarray:
        """The translation DOFs an MLS fit couples, shape=(2 len(nodes),)."""
        return self.node_dofs(nodes, 2)

    def rank_map(self, f: Callable[[int], _T], items: list[int]) -> list[_T]:
        """:data:`~geofrac.fracture.state.Mapper` sharing ``items`` among the ranks.

        Rank r computes items r, r + size, ...; the results are gathered on every rank
        in order. An exception on any rank is raised on every rank (no rank is left
        waiting in the gather).
        """
        size, rank = self.comm.size, self.comm.rank
        if size == 1 or len(items) < 2 * size:
            return [f(i) for i in items]
        mine: list[_T] | Exception
        try:
            mine = [f(i) for i in items[rank::size]]
        except Exception as exc:  # re-raised on every rank below
            mine = exc
        parts = self.comm.allgather(mine)
        for part in parts:
            if isinstance(part, Exception):
                raise part
        out: list[_T] = [None] * len(items)  # type: ignore[list-item]
        for r, part in enumerate(parts):
            out[r::size] = part
        return out


def gather_vector(v: Vector, comm: MPI.Comm) -> np.ndarray:
    """The owned entries of every rank in global order, shape=(size_global,) (collective)."""
    return np.concatenate(comm.allgather(np.array(v.getArray(readonly=True), dtype=float)))


def _force(
    config: CrackingConfig, problem: ElasticProblem, gm: GlobalMesh, *, bs: int, say: Say
) -> Control:
    """Force control by the traction, pressure and point loads on ``config.control``.

    Their unit nodal forces are assembled alone (:meth:`ElasticProblem.load_part`) and
    gathered on every rank. Collective.
    """
    scene, comm = problem.scene, problem.comm
    forces = None
    for i, load in enumerate(scene.loads):
        if load.group != config.control or load.type not in FORCE_LOADS:
            continue
        v = problem.load_part(i)
        try:
            part = gather_vector(v, comm)
        finally:
            v.destroy()
        forces = part if forces is None else forces + part
    if forces is None:  # the scene loader checked this
        raise RunError(f"cracking.control: no [[load]] on '{config.control}'")
    point = None
    if config.control_point is not None:
        xy = np.asarray(config.control_point)
        node = int(np.argmin(np.hypot(*(gm.coords - xy).T)))
        point = (node, gm.node_block[node] * bs + np.arange(2))
    mat = scene.material
    try:
        control = force_control(
            config.control, forces, bs=bs, modulus=mat.E, thickness=mat.thickness, point_dofs=point
        )
    except ValueError as exc:
        raise RunError(f"cracking.control: {exc}") from None
    text = f"F = {control.unit:.6g}"
    if control.direction is None:
        text += " (self-equilibrated: the sum of its nodal forces' magnitudes)"
    if control.node is not None:
        x, y = gm.coords[control.node]
        text += (
            f"; control_point reads node {int(gm.input_ids[control.node])} at ({x:.6g}, {y:.6g})"
        )
    say(f"cracking: force control by the [[load]] on '{config.control}', {text}")
    return control


def _dirichlet(
    problem: ElasticProblem, comm: MPI.Comm, n_global: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Dirichlet rows and values of every rank, shape=(k,), as a mask and a vector (collective).

    Returns:
        (rows, values, mask, full): the mask and the full vector have shape=(n_global,).
    """
    rows, vals = problem.dirichlet()
    parts = comm.allgather((rows, vals))
    bc_rows = np.concatenate([p[0] for p in parts]).astype(np.int64)
    bc_vals = np.concatenate([p[1] for p in parts])
    bc_mask = np.zeros(n_global, dtype=bool)
    bc_mask[bc_rows] = True
    bc_full = np.zeros(n_global)
    bc_full[bc_rows] = bc_vals
    return bc_rows, bc_vals, bc_mask, bc_full


def crack_context(config: CrackingConfig, solution: Solution, say: Say) -> CrackContext:
    """The shared data of a set-up problem (collective)."""
    scene, problem, tagged = solution.scene, solution.problem, solution.tagged
    comm = tagged.mesh.comm
    spec = elements.get(scene.discretization.element)
    if problem.changes_basis:
        raise RunError(
            "cracking: the boundary conditions give the vertex DOFs of "
            f"'{scene.discretization.element}' a change of basis (a held line that is not "
            "along a DOF axis), which the crack driver cannot assemble; set "
            "discretization.gradient_bc = 'fixed' or use symmetry conditions"
        )
    bs = spec.vertex_dofs[2]
    space = problem.unknown().function_space
    gm = gather_mesh(tagged.mesh, space)
    mat = scene.material
    _, mu = lame(mat.E, mat.nu, 2, plane=mat.plane)
    imap = space.dofmap.index_map
    n_global = imap.size_global * bs
    bc_rows, bc_vals, bc_mask, bc_full = _dirichlet(problem, comm, n_global)
    order = np.argsort(gm.node_block)
    bc_row_nodes = order[np.searchsorted(gm.node_block[order], bc_rows // bs)]
    # the control group: its prescribed, non-zero DOFs (none under force control or
    # the stages' release, which controls no group)
    if config.control_kind == RELEASE:
        on = np.zeros(len(bc_rows), dtype=bool)
    else:
        control_nodes = np.unique(facet_nodes(tagged, gm, config.control))
        on = np.isin(bc_row_nodes, control_nodes) & (bc_vals != 0)
    if config.control_kind == "force":
        on[:] = False
    control_sign = np.zeros(n_global + 1)
    control_sign[bc_rows[on]] = np.sign(bc_vals[on])
    face_nodes = None
    if config.face is not None:
        face_nodes = np.unique(facet_nodes(tagged, gm, config.face))
    if config.control_kind == "force":
        control = _force(config, problem, gm, bs=bs, say=say)
    elif config.control_kind == RELEASE:  # the staged loop sets the release's scale
        control = release_control(1.0 / mat.E)
    else:
        control = displacement_control(config.control, bc_vals[on])
    if not control.unit > 0.0:
        raise RunError(
            f"cracking.control: the group '{config.control}' prescribes no non-zero "
            "displacement, so there is no unit load to scale"
        )
    control_unit = control.scale
    return CrackContext(
        config=config,
        scene=scene,
        problem=problem,
        tagged=tagged,
        spec=spec,
        comm=comm,
        say=say,
        gm=gm,
        bs=bs,
        D=d_matrix(mat.E, mat.nu, 2, plane=mat.plane),
        t=mat.thickness,
        penalty=scene.discretization.zero_mode_penalty * mu,
        n_local=imap.size_local * bs,
        n_global=n_global,
        row0=imap.local_range[0] * bs,
        bc_rows=bc_rows,
        bc_vals=bc_vals,
        bc_mask=bc_mask,
        bc_full=bc_full,
        bc_row_nodes=bc_row_nodes,
        bc_nodes=np.unique(bc_row_nodes),
        control_rows=bc_rows[on],
        control_vals=bc_vals[on],
        control_sign=control_sign,
        control_unit=control_unit,
        control=control,
        face_nodes=face_nodes,
        scales=Scales.of_mesh(
            gm.coords, gm.cells, displacement=control_unit, modulus=mat.E, thickness=mat.thickness
        ),
    )
