"""Joints in the elasto-plastic solve: node-to-node Coulomb springs across a split joint.

The mesh is split along the joint, when meshed (:mod:`geofrac.meshing.split`: a node
gets a copy per side, tips none, junctions 3 or 4) or in the geometry (the two sides
separate surfaces whose common curve is drawn twice, e.g. meshes/slope_planar_joint.geo),
so the P2 displacement is discontinuous there and the two faces' nodes lie on top of
each other. :class:`JointGeometry` finds the faces' facets (each through its one cell),
decides each facet's side from its cell (the + side is where the joint normal n points,
n oriented upwards: n_y > 0, or n_x > 0 on a vertical joint), matches each + facet with
the − facet at the same place, pairs their nodes by position, lumps the facet's length
on its nodes with Simpson's weights (L/6, 2L/3, L/6: Newton-Cotes lumping, which keeps
the tractions of a P2 interface free of oscillations) and merges the pairs of the same
two nodes (at a junction each facet pairs the copies of its own two sides; a tip, not
split, pairs with itself and is left out). Every rank gathers every pair (their global
indices and weights, the same arrays in the same order on every rank), so the joint's
arithmetic is the same on 1 and N ranks; each rank adds the rows it owns.

:class:`JointInterface` holds the pairs' Coulomb strengths and slips; at each Newton
update it gathers u at the joint nodes (an allreduce), forms the jump δ = u⁺ − u⁻, the
law (:func:`geofrac.plasticity.interface.coulomb_joint`) and the pair forces
f = w (σₙ n + τ t) on u⁺ (−f on u⁻) with the Jacobian blocks ±w Q D Qᵀ, Q = [n t]. The
springs: kₙ = kₛ = penalty · E / ℓ (ℓ the mean length of the pair's joint facets), as the
crack-face contact of the cracking work (docs/cracking.md). See docs/plasticity.md,
"Joints in the strength reduction".
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.joint_facets3d import (
    ROW,
    face_facets_3d,
    facet_faces_3d,
    facet_pairs_3d,
    tangent_frames,
)
from geofrac.meshing.distribute import TaggedMesh
from geofrac.plasticity.interface import (
    SLIP,
    JointReturn,
    JointStrength,
    coulomb_joint,
    coulomb_joint_3d,
)

__all__ = ["JointGeometry", "JointInterface"]

#: Simpson's weights of a P2 edge's nodes (end, end, middle) per unit length.
SIMPSON = np.array([1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0])
#: |n_y| below which a unit joint normal counts as horizontal (the joint as vertical).
VERTICAL = 1e-9


def _face_facets(
    V: dolfinx.fem.FunctionSpace, tagged: TaggedMesh, group: str, key: str
) -> np.ndarray:
    """This rank's owned facets of ``group`` with one cell, as rows.

    A facet with two cells is a piece of a split joint that stayed whole (a one-edge
    joint between two tips: no jump) and is left out; in a group that was not split
    (``tagged.split``) it is an error.

    Returns:
        (global nodes of the two ends and the middle (3), side ±1, their x, y (6),
        n_x, n_y, facet length), shape=(m, 13) for m owned facets with one cell.
    """
    mesh = V.mesh
    tdim = mesh.topology.dim
    dim, facets = tagged.entities(group)
    if dim != tdim - 1:
        raise RunError(f"{key}: the group '{group}' is not a curve group")
    facets = tagged.owned(dim, facets)
    mesh.topology.create_connectivity(dim, tdim)
    mesh.topology.create_connectivity(tdim, dim)
    f2c = mesh.topology.connectivity(dim, tdim)
    c2f = mesh.topology.connectivity(tdim, dim)
    coords = V.tabulate_dof_coordinates()
    imap = V.dofmap.index_map
    layout = V.dofmap.dof_layout
    geom = mesh.geometry
    rows = []
    for f in facets:
        cells = f2c.links(f)
        if len(cells) != 1:
            if group in tagged.split:
                continue
            raise RunError(
                f"{key}: the joint '{group}' is not split (a facet with {len(cells)} cells); "
                "draw it twice, one curve per side (meshes/slope_planar_joint.geo), or let "
                "the scene split it (a [plasticity.joints.NAME] group is split when meshed)"
            )
        cell = cells[0]
        local = int(np.flatnonzero(c2f.links(cell) == f)[0])
        nodes = V.dofmap.cell_dofs(cell)[layout.entity_closure_dofs(dim, local)]
        xy = coords[nodes, :2]
        # the two ends are the farthest apart; the third is the middle node
        d = np.linalg.norm(xy[:, None] - xy[None], axis=2)
        a, b = np.unravel_index(np.argmax(d), d.shape)
        order = np.array([a, b, 3 - a - b])
        t = xy[b] - xy[a]
        length = float(np.linalg.norm(t))
        normal = np.array([-t[1], t[0]]) / length
        # upwards, or +x on a joint vertical to round-off (both faces agree)
        if normal[1] < -VERTICAL or (abs(normal[1]) <= VERTICAL and normal[0] < 0):
            normal = -normal
        centre = geom.x[geom.dofmaps[0][cell], :2].mean(axis=0)
        side = 1.0 if np.dot(centre - xy[order[2]], normal) > 0 else -1.0
        glob = imap.local_to_global(nodes[order].astype(np.int32))
        rows.append([*glob, side, *xy[order].ravel(), *normal, length])
    return np.asarray(rows, dtype=float).reshape(-1, 13)


def _facet_pairs(rows: np.ndarray, key: str) -> np.ndarray:
    """Each + facet with the − facet at the same place; their node pairs.

    At a junction the joint node has several copies (one per sector), and each facet
    pairs the copies of its own two sides; a tip (a node not split) pairs with itself
    and is left out (its jump is zero).

    Args:
        rows: the facets of :func:`_face_facets`, all ranks, shape=(k, 13).
        key: the scene key named in errors.

    Returns:
        (plus node, minus node, x, y, weight, n_x, n_y, facet length) per facet node,
        shape=(p, 8); a node pair appears once per facet it belongs to.

    Raises:
        RunError: a facet without a facet on the other side at the same place.
    """
    from scipy.spatial import cKDTree

    up, down = rows[rows[:, 3] > 0], rows[rows[:, 3] < 0]
    tol = 1e-6 * float(rows[:, 12].min()) if len(rows) else 0.0
    match = np.full(len(up), -1)
    if len(up) and len(down):
        dist, near = cKDTree(down[:, 8:10]).query(up[:, 8:10])
        match = np.where(dist <= tol, near, -1)
    if len(up) == 0 or len(up) != len(down) or np.any(match < 0):
        raise RunError(
            f"{key}: the joint's faces have {len(up)} and {len(down)} facets, "
            f"{int(np.count_nonzero(match < 0))} with no facet at the same place on the other "
            "side; a joint must be split (meshed alike on both faces)"
        )
    if len(np.unique(match)) != len(up):
        raise RunError(f"{key}: two facets of one face lie on each other")
    down = down[match]
    flip = np.linalg.norm(up[:, 4:6] - down[:, 4:6], axis=1) > tol
    minus = down[:, :3].copy()
    minus[flip, 0], minus[flip, 1] = down[flip, 1], down[flip, 0]
    length = 0.5 * (up[:, 12] + down[:, 12])
    out = np.zeros((3 * len(up), 8))
    for k in range(3):
        part = out[k::3]
        part[:, 0], part[:, 1] = up[:, k], minus[:, k]
        part[:, 2:4] = up[:, 4 + 2 * k : 6 + 2 * k]
        part[:, 4] = SIMPSON[k] * length
        part[:, 5:7] = up[:, 10:12]
        part[:, 7] = length
    return out[out[:, 0] != out[:, 1]]


def _merge(rows: np.ndarray, dim: int) -> tuple[np.ndarray, ...]:
    """One pair per (plus, minus) node: weights summed, normals weight-averaged.

    Args:
        rows: the facet node pairs (plus, minus, x (dim), weight, n (dim), length) of
            :func:`_facet_pairs` (dim 2) or
            :func:`geofrac.fem.joint_facets3d.facet_pairs_3d` (dim 3), shape=(k, 4 + 2 dim).
        dim: the geometric dimension.

    Returns:
        plus, minus (global nodes), x (m, dim), normal (m, dim), weight (m,), length (m,)
        (the mean facet length), sorted by (plus, minus).
    """
    uniq, inverse = np.unique(rows[:, :2], axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    m = len(uniq)
    w_col, n_col, l_col = 2 + dim, 3 + dim, 3 + 2 * dim
    count = np.bincount(inverse, minlength=m).astype(float)
    weight = np.bincount(inverse, weights=rows[:, w_col], minlength=m)
    x = np.stack(
        [np.bincount(inverse, weights=rows[:, c], minlength=m) for c in range(2, w_col)], 1
    )
    length = np.bincount(inverse, weights=rows[:, l_col], minlength=m) / count
    normal = np.stack(
        [
            np.bincount(inverse, weights=rows[:, c] * rows[:, w_col], minlength=m)
            for c in range(n_col, l_col)
        ],
        1,
    )
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    return uniq[:, 0], uniq[:, 1], x / count[:, None], normal, weight, length


@dataclass
class JointGeometry:
    """The node pairs of the split joints (the same arrays on every rank).

    Attributes:
        names: the joint groups, in the order of ``group``'s indices.
        plus: global node of the + face, shape=(m,).
        minus: global node of the − face, shape=(m,).
        x: coordinates of the pairs, shape=(m, d) (d = 2 or 3).
        normal: unit normal n (from − to +), shape=(m, d).
        weight: tributary length (2D) or area (3D) w, shape=(m,).
        length: the mean facet length (2D) or edge length (3D) ℓ at the pair, shape=(m,).
        group: index into ``names`` of each pair, shape=(m,).
        fixed: the pair's DOFs (u⁺ then u⁻, d each) are Dirichlet DOFs, shape=(m, 2 d).
        faces: 3D: the joints' faces (their + facets' vertices), shape=(k, 3, 3);
            2D: none, shape=(0, 3, 3).
        face_pairs: the pairs of each face's three middle nodes (−1 for an edge on the
            joint's edge, not split), shape=(k, 3).
        face_group: index into ``names`` of each face, shape=(k,).
    """

    names: tuple[str, ...]
    plus: np.ndarray
    minus: np.ndarray
    x: np.ndarray
    normal: np.ndarray
    weight: np.ndarray
    length: np.ndarray
    group: np.ndarray
    fixed: np.ndarray
    faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 3)))
    face_pairs: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    face_group: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @classmethod
    def build(
        cls,
        V: dolfinx.fem.FunctionSpace,
        tagged: TaggedMesh,
        groups: Sequence[str],
        *,
        bcs: Sequence[dolfinx.fem.DirichletBC] = (),
        key: str = "plasticity.joints",
    ) -> JointGeometry:
        """Find, weigh and pair the faces' nodes of each group (collective).

        Raises:
            RunError: (every rank) a group is missing, is not split, or its faces' nodes
                do not pair one to one (the two curves not meshed alike).
        """
        comm = V.mesh.comm
        dim = V.mesh.geometry.dim
        find, pair, width = (
            (_face_facets, _facet_pairs, 13) if dim == 2 else (face_facets_3d, facet_pairs_3d, ROW)
        )
        parts: list[list[np.ndarray]] = [[] for _ in range(7)]
        faces: list[tuple[np.ndarray, np.ndarray, int]] = []
        offset = 0
        for g, name in enumerate(groups):
            where = f"{key}.{name}"
            if name not in tagged.groups:
                known = ", ".join(sorted(tagged.groups))
                raise RunError(f"{where}: no group '{name}' in the mesh (groups: {known})")
            message, rows = None, np.zeros((0, width))
            try:
                rows = find(V, tagged, name, key=where)
            except RunError as exc:
                message = str(exc)
            messages = [m for m in comm.allgather(message) if m]
            if messages:
                raise RunError(messages[0])
            every = np.concatenate(comm.allgather(rows))
            pairs = _merge(pair(every, where), dim)
            for part, value in zip(parts, (*pairs, np.full(len(pairs[0]), g)), strict=True):
                part.append(value)
            if dim == 3:
                corners, keys = facet_faces_3d(every, where)
                index = _pair_index(pairs[0], pairs[1], keys)
                faces.append((corners, np.where(index >= 0, index + offset, -1), g))
            offset += len(pairs[0])
        cat = [np.concatenate(p) if p else np.zeros(0) for p in parts]
        plus, minus = cat[0].astype(np.int64), cat[1].astype(np.int64)
        x, normal = cat[2].reshape(-1, dim), cat[3].reshape(-1, dim)
        fixed = _fixed(V, bcs, plus, minus)
        out = cls(tuple(groups), plus, minus, x, normal, cat[4], cat[5], cat[6].astype(int), fixed)
        if faces:
            out.faces = np.concatenate([f[0] for f in faces])
            out.face_pairs = np.concatenate([f[1] for f in faces])
            out.face_group = np.concatenate([np.full(len(f[0]), f[2]) for f in faces])
        return out

    @property
    def size(self) -> int:
        """The number of pairs."""
        return len(self.plus)


def _pair_index(plus: np.ndarray, minus: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Index of each (plus, minus) key among the sorted pairs, −1 where plus == minus.

    Args:
        plus: the pairs' + nodes of :func:`_merge` (sorted by (plus, minus)), shape=(m,).
        minus: their − nodes, shape=(m,).
        keys: (plus, minus) global nodes, shape=(k, 3, 2).

    Returns:
        shape=(k, 3).
    """
    width = int(max(plus.max(initial=0), minus.max(initial=0), keys.max(initial=0))) + 1
    code = plus.astype(np.int64) * width + minus.astype(np.int64)
    wanted = keys[..., 0] * width + keys[..., 1]
    where = np.clip(np.searchsorted(code, wanted), 0, max(len(code) - 1, 0))
    found = (len(code) > 0) & (code[where] == wanted) if len(code) else np.zeros(wanted.shape, bool)
    return np.where(found & (keys[..., 0] != keys[..., 1]), where, -1)


def _gather(V: dolfinx.fem.FunctionSpace, array: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Values of a blocked local array at global nodes, shape=(len(nodes), bs); collective."""
    imap = V.dofmap.index_map
    bs = V.dofmap.index_map_bs
    local = imap.global_to_local(nodes.astype(np.int64))
    owned = (local >= 0) & (local < imap.size_local)
    out = np.zeros((len(nodes), bs))
    out[owned] = array.reshape(-1, bs)[local[owned]]
    return np.asarray(V.mesh.comm.allreduce(out, op=MPI.SUM))


def _fixed(
    V: dolfinx.fem.FunctionSpace,
    bcs: Sequence[dolfinx.fem.DirichletBC],
    plus: np.ndarray,
    minus: np.ndarray,
) -> np.ndarray:
    """Whether each pair DOF (u⁺ then u⁻, bs each) is a Dirichlet DOF, shape=(m, 2 bs)."""
    bs = V.dofmap.index_map_bs
    imap = V.dofmap.index_map
    marker = np.zeros((imap.size_local + imap.num_ghosts) * bs)
    for bc in bcs:
        marker[bc.dof_indices()[0]] = 1.0
    both = _gather(V, marker, np.concatenate([plus, minus]))
    m = len(plus)
    return np.concatenate([both[:m], both[m:]], axis=1) > 0


class JointInterface:
    """The joints' springs at one strength, with their slips (the state).

    In 2D the pair's frame is [n t] with t = (n_y, −n_x) and the law
    :func:`~geofrac.plasticity.interface.coulomb_joint`; in 3D it is [n t₁ t₂]
    (:func:`~geofrac.fem.joint_facets3d.tangent_frames`) and the law
    :func:`~geofrac.plasticity.interface.coulomb_joint_3d`, the slip a vector in the plane.

    Args:
        geometry: the pairs.
        V: the displacement space (P2 vector).
        strengths: each group's strength (``geometry.names`` order), already reduced.
        penalty: kₙ = kₛ = penalty · E / ℓ where a group gives no stiffness.
        E: Young's modulus of the rock.
        stiffness: each group's (kₙ, kₛ) in stress per length, None for the penalty's
            (``geometry.names`` order; empty: the penalty's for all).
    """

    def __init__(
        self,
        geometry: JointGeometry,
        V: dolfinx.fem.FunctionSpace,
        strengths: Sequence[JointStrength],
        *,
        penalty: float,
        E: float,
        stiffness: Sequence[tuple[float | None, float | None]] = (),
    ) -> None:
        self.geometry, self.V = geometry, V
        self.cohesion = np.array([s.cohesion for s in strengths])[geometry.group]
        self.friction = np.array([s.friction for s in strengths])[geometry.group]
        spring = penalty * E / geometry.length
        self.kn, self.ks = spring.copy(), spring.copy()
        for g, (kn, ks) in enumerate(stiffness):
            mine = geometry.group == g
            if kn is not None:
                self.kn[mine] = kn
            if ks is not None:
                self.ks[mine] = ks
        dim = geometry.x.shape[1]
        self.dim = dim
        #: the converged slip, shape=(m,) in 2D, (m, 2) in 3D (the tangent frame's t₁, t₂)
        self.slip_n = np.zeros(geometry.size) if dim == 2 else np.zeros((geometry.size, 2))
        #: the jump (δₙ, δₛ...) the displacement lost at a reset (a gravity phase's end),
        #: added to the jump of u, shape=(m, d), the same on every rank.
        self.offset = np.zeros((geometry.size, dim))
        self.ret: JointReturn | None = None
        bs = V.dofmap.index_map_bs
        comps = np.arange(bs)
        plus, minus = geometry.plus[:, None], geometry.minus[:, None]
        #: the pairs' global scalar DOFs (u⁺ then u⁻, bs each), shape=(m, 2 bs)
        self._dofs = np.concatenate([bs * plus + comps, bs * minus + comps], axis=1)
        lo, hi = V.dofmap.index_map.local_range
        self._owned = (self._dofs >= bs * lo) & (self._dofs < bs * hi) & ~geometry.fixed
        n = geometry.normal
        if dim == 2:  # (m, 2, 2): [n t]
            self._q = np.stack([n, np.stack([n[:, 1], -n[:, 0]], axis=1)], axis=2)
        else:  # (m, 3, 3): [n t1 t2]
            self._q = tangent_frames(n)

    def update(self, u: dolfinx.fem.Function) -> None:
        """The law at the jump of u plus :attr:`offset` (collective)."""
        g = self.geometry
        values = _gather(self.V, u.x.array, np.concatenate([g.plus, g.minus]))
        jump = values[: g.size] - values[g.size :]
        local = np.einsum("mij,mi->mj", self._q, jump) + self.offset  # (δₙ, δₛ...)
        law = coulomb_joint if self.dim == 2 else coulomb_joint_3d
        self.ret = law(
            local[:, 0],
            local[:, 1] if self.dim == 2 else local[:, 1:],
            self.slip_n,
            kn=self.kn,
            ks=self.ks,
            cohesion=self.cohesion,
            friction=self.friction,
        )
        self._jump = local

    def commit(self) -> None:
        """Accept the current slips as converged."""
        assert self.ret is not None
        self.slip_n = self.ret.slip.copy()

    def keep_jump(self) -> None:
        """Before u is reset to 0: keep the current jump in :attr:`offset`.

        The springs' forces, openings and slips are then unchanged by the reset (the
        jump is measured from the stress-free state, as the slip).
        """
        self.offset = self._jump.copy()

    def _traction(self) -> np.ndarray:
        """(σₙ, τ...) per pair in its frame, shape=(m, d)."""
        assert self.ret is not None
        return np.column_stack([self.ret.normal, self.ret.shear])

    def residual_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """(owned global rows, values): +w T on u⁺, −w T on u⁻, T = σₙ n + τ t."""
        trac = np.einsum("mij,mj->mi", self._q, self._traction())
        force = self.geometry.weight[:, None] * trac
        values = np.concatenate([force, -force], axis=1)  # (m, 2 d)
        return self._dofs[self._owned], values[self._owned]

    def jacobian_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rows, cols, values) of the owned rows, Dirichlet rows and columns left out."""
        assert self.ret is not None
        q = self._q
        K = self.geometry.weight[:, None, None] * np.einsum(
            "mij,mjk,mlk->mil", q, self.ret.tangent, q
        )
        block = np.block([[K, -K], [-K, K]])  # (m, 2 d, 2 d)
        rows, cols, keep = self._block_pattern()
        return rows[keep], cols[keep], block[keep]

    def _block_pattern(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, columns and which to keep of the pairs' blocks, shape=(m, 2 d, 2 d) each."""
        size = self._dofs.shape[1]
        shape = (len(self._dofs), size, size)
        rows = np.broadcast_to(self._dofs[:, :, None], shape)
        cols = np.broadcast_to(self._dofs[:, None, :], shape)
        keep = self._owned[:, :, None] & ~self.geometry.fixed[:, None, :]
        return rows, cols, keep

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of every entry :meth:`jacobian_entries` gives (the solver's pattern)."""
        rows, cols, keep = self._block_pattern()
        return rows[keep], cols[keep]

    def _slip_size(self) -> np.ndarray:
        """|s| per pair, shape=(m,)."""
        assert self.ret is not None
        slip = self.ret.slip
        return np.abs(slip) if slip.ndim == 1 else np.linalg.norm(slip, axis=1)

    def summary(self) -> dict[str, object]:
        """Pairs, slipping and open pairs, the largest slip and opening (JSON-ready)."""
        assert self.ret is not None
        opening = np.maximum(self._jump[:, 0], 0.0)
        return {
            "groups": list(self.geometry.names),
            "pairs": int(self.geometry.size),
            "slipping": int(np.count_nonzero(self.ret.state == SLIP)),
            "open": int(np.count_nonzero(self._jump[:, 0] > 0)),
            "max_slip": float(self._slip_size().max(initial=0.0)),
            "max_opening": float(opening.max(initial=0.0)),
        }

    def write_csv(self, path: Path) -> None:
        """The :meth:`table` as CSV (one rank writes: the table is the same on every rank)."""
        np.savetxt(
            path, self.table(), delimiter=",", header=self.header(), comments="", fmt="%.10g"
        )

    def write_outputs(self, directory: Path) -> list[Path]:
        """3D: ``joints.csv`` (per node pair) and ``fracture_faces.vtu`` (per face); rank 0.

        The VTU's cell data are :meth:`face_table`'s; docs/output.md.
        """
        from geofrac.io.fractures import write_fracture_faces

        self.write_csv(directory / "joints.csv")
        faces = directory / "fracture_faces.vtu"
        write_fracture_faces(faces, self.geometry.faces, self.face_table())
        return [directory / "joints.csv", faces]

    def header(self) -> str:
        """The :meth:`table`'s column names, comma-separated."""
        if self.dim == 2:
            return "x,y,normal_traction,shear_traction,opening,slip,state"
        return (
            "x,y,z,normal_traction,shear_traction_1,shear_traction_2,opening,"
            "slip_x,slip_y,slip_z,slip,state,group"
        )

    def face_table(self) -> dict[str, np.ndarray]:
        """3D: per joint face the mean over its split middle nodes' pairs (JSON-free arrays).

        Returns:
            ``opening`` δₙ, ``slip`` |s|, ``normal_traction`` σₙ, ``shear_traction`` |τ|,
            ``state`` (the most frequent of its pairs' states, the higher on a tie: open
            over slip over closed), ``set`` (the group index), shape=(k,) each; a face with
            no split middle node (its three edges on the joint's edge) gets zeros and state
            closed.
        """
        assert self.ret is not None
        g = self.geometry
        valid = g.face_pairs >= 0
        index = np.where(valid, g.face_pairs, 0)
        count = np.maximum(valid.sum(axis=1), 1)
        shear = self.ret.shear
        shear_size = np.abs(shear) if shear.ndim == 1 else np.linalg.norm(shear, axis=1)

        def mean(values: np.ndarray) -> np.ndarray:
            return np.where(valid, values[index], 0.0).sum(axis=1) / count

        votes = np.stack(
            [np.where(valid, self.ret.state[index] == k, False).sum(axis=1) for k in range(3)], 1
        )
        state = 2 - np.argmax(votes[:, ::-1], axis=1)  # the higher state on a tie
        return {
            "opening": mean(self._jump[:, 0]),
            "slip": mean(self._slip_size()),
            "normal_traction": mean(self.ret.normal),
            "shear_traction": mean(shear_size),
            "state": state.astype(np.int8),
            "set": g.face_group.astype(np.int32),
        }

    def table(self) -> np.ndarray:
        """Per pair: position, σₙ, τ, opening δₙ, slip, state (0 closed, 1 slip, 2 open).

        2D: x, y, σₙ, τ, δₙ, s, state, shape=(m, 7). 3D: x, y, z, σₙ, τ₁, τ₂, δₙ, the
        slip vector s₁ t₁ + s₂ t₂ (x, y, z), |s|, state, group index, shape=(m, 13).
        The same on every rank.
        """
        assert self.ret is not None
        if self.dim == 2:
            return np.column_stack(
                [
                    self.geometry.x,
                    self.ret.normal,
                    self.ret.shear,
                    self._jump[:, 0],
                    self.ret.slip,
                    self.ret.state,
                ]
            )
        slip = np.einsum("mij,mj->mi", self._q[:, :, 1:], self.ret.slip)
        return np.column_stack(
            [
                self.geometry.x,
                self.ret.normal,
                self.ret.shear,
                self._jump[:, 0],
                slip,
                self._slip_size(),
                self.ret.state,
                self.geometry.group,
            ]
        )


def joint_springs(
    V: dolfinx.fem.FunctionSpace,
    tagged: TaggedMesh,
    joints: Sequence[tuple[str, JointStrength]],
    *,
    bcs: Sequence[dolfinx.fem.DirichletBC],
    rock: Any,
    penalty: float,
    stiffness: Sequence[tuple[float | None, float | None]] = (),
) -> Callable[[Any], JointInterface]:
    """The map reduced rock law ↦ the joints' springs at the same trial factor (collective).

    The pairs are found once; each call divides every joint's c and μ by the factor F
    that divided the rock's (:func:`geofrac.plasticity.strength_reduction.trial_factor`
    of ``rock`` and the law given: F = 1 for ``rock`` itself).

    Args:
        V: the displacement space (P2 vector).
        tagged: the mesh with its groups.
        joints: (curve group, strength at F = 1) per joint group.
        bcs: the Dirichlet conditions (their DOFs get no spring rows or columns).
        rock: the rock's law at full strength (its E sets the springs).
        penalty: kₙ = kₛ = penalty · E / ℓ.
        stiffness: each joint's (kₙ, kₛ), None for the penalty's (empty: all the penalty's).
    """
    from geofrac.plasticity.strength_reduction import trial_factor

    geometry = JointGeometry.build(V, tagged, [name for name, _ in joints], bcs=bcs)
    strengths = [s for _, s in joints]

    def make(law: Any) -> JointInterface:
        factor = 1.0 if law is rock else trial_factor(rock, law)
        reduced = [s.reduced(factor) for s in strengths]
        return JointInterface(
            geometry, V, reduced, penalty=penalty, E=float(rock.E), stiffness=stiffness
        )

    return make
