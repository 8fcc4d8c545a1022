"""Loads that stay constant while the others scale: the two right-hand sides and the choice.

With ``cracking.constant`` (docs/cracking.md, "Loads that do not scale together";
DeJong, Hendriks and Rots (2008)) each event solves the current crack state twice with
one factorisation: the *variable* load at unit factor (every load and prescribed
displacement not named, the control group's among them; the constant groups'
prescribed displacements held at 0) and the *constant* load (the named groups' loads
and prescribed displacements at their full value; the others' prescribed displacements
held at 0). The stress at each site is σ_c + λ σ_v; :class:`ConstantChooser` finds the
least λ ≥ 0 at which a site reaches its strength (:mod:`~geofrac.fracture.nonprop`),
and cracks first, at λ = 0, sites that the constant load alone already brings over it.

The seam for an initial (in-situ) stress: :class:`ConstantLoad` takes an extra load
vector added to the constant right-hand side (``extra_load``) and an extra stress per
cell and local edge added to the constant stress at the sites (``extra_stress``).
"""

from __future__ import annotations

from dataclasses import dataclass

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.assembly import LoadCase
from geofrac.fracture.config import CrackingConfig
from geofrac.fracture.contact import edge_frames, edge_tractions
from geofrac.fracture.context import CrackContext, facet_nodes
from geofrac.fracture.criterion import TIE_TOLERANCE, edge_means, least, normal_stress, tie_order
from geofrac.fracture.event_criterion import EdgeCriterion, TractionCriterion
from geofrac.fracture.modes import Choice
from geofrac.fracture.nonprop import principal_factors, shear_factors_affine, traction_factors
from geofrac.fracture.units import EdgeUnits
from geofrac.solvers import Vector

__all__ = ["BODY_FORCE", "ConstantChooser", "ConstantLoad", "constant_load"]

#: The name in ``cracking.constant`` of the scene's ``body_force`` loads (they act on
#: no group).
BODY_FORCE = "body_force"


@dataclass
class ConstantLoad:
    """The two right-hand sides of a run with constant loads.

    Attributes:
        groups: the ``cracking.constant`` groups.
        variable: the variable load at unit factor (the default right-hand side of the
            assembler and the solver strategy).
        constant: the constant load.
        extra_stress: a constant stress added at the sites to that of ``constant``
            (an initial stress), per cell and local edge midpoint, shape=(num_cells, 3,
            3), or None.
    """

    groups: tuple[str, ...]
    variable: LoadCase
    constant: LoadCase
    extra_stress: np.ndarray | None = None

    def destroy(self) -> None:
        """Free the load vectors."""
        self.variable.load.destroy()
        self.constant.load.destroy()


def _constant_rows(ctx: CrackContext, groups: tuple[str, ...]) -> np.ndarray:
    """Which Dirichlet DOFs ``ctx.bc_rows`` prescribe a constant non-zero value, shape=(k,).

    A DOF is constant when its node lies on a constant ``[[bc]]`` group; a non-zero
    prescribed DOF whose node lies on a variable ``[[bc]]`` group with a non-zero value
    too is ambiguous (which value it took depends on the order of the conditions).
    """
    scene = ctx.scene
    const_nodes, var_nodes = [], []
    for bc in scene.bcs:
        nodes = np.unique(facet_nodes(ctx.tagged, ctx.gm, bc.group))
        if bc.group in groups:
            const_nodes.append(nodes)
        elif bc.value == "exact" or any(v != 0 for v in bc.value):
            var_nodes.append(nodes)
    empty = np.zeros(0, dtype=np.int64)
    const = np.isin(ctx.bc_row_nodes, np.concatenate(const_nodes) if const_nodes else empty)
    nonzero = ctx.bc_vals != 0
    var = np.isin(ctx.bc_row_nodes, np.concatenate(var_nodes) if var_nodes else empty)
    both = const & var & nonzero
    if both.any():
        node = int(ctx.gm.input_ids[ctx.bc_row_nodes[np.flatnonzero(both)[0]]])
        raise RunError(
            f"cracking.constant: node {node} (mesh file numbering) lies on a constant and "
            "on a variable [[bc]] group that both prescribe a non-zero displacement; "
            "which part its value belongs to is ambiguous"
        )
    return const & nonzero


def constant_load(
    ctx: CrackContext, config: CrackingConfig, extra_load: Vector | None = None
) -> ConstantLoad:
    """The variable and constant right-hand sides of ``config.constant`` (collective).

    The constant load vector sums the scene's ``[[load]]`` terms on the constant groups
    (:meth:`~geofrac.fem.elastic.ElasticProblem.load_part`; ``body_force`` names the
    body-force loads) and ``extra_load``; the variable one is the scene's whole load
    vector minus the constant loads (so the effects' terms, e.g. ``gravity``, vary).
    """
    problem, groups = ctx.problem, config.constant
    b_var = problem.load_vector()
    b_const = b_var.duplicate()
    b_const.set(0.0)
    for i, load in enumerate(ctx.scene.loads):
        name = BODY_FORCE if load.type == "body_force" else load.group
        if name not in groups:
            continue
        part = problem.load_part(i)
        try:
            b_const.axpy(1.0, part)
        finally:
            part.destroy()
    if any(ld.type == "body_force" or ld.group in groups for ld in ctx.scene.loads):
        b_var.axpy(-1.0, b_const)
    if extra_load is not None:
        b_const.axpy(1.0, extra_load)
    const = _constant_rows(ctx, groups)
    vals_c = np.where(const, ctx.bc_vals, 0.0)
    vals_v = np.where(const, 0.0, ctx.bc_vals)
    full_c, full_v = np.zeros(ctx.n_global), np.zeros(ctx.n_global)
    full_c[ctx.bc_rows], full_v[ctx.bc_rows] = vals_c, vals_v
    return ConstantLoad(
        groups=groups,
        variable=LoadCase(b_var, vals_v, full_v),
        constant=LoadCase(b_const, vals_c, full_c),
    )


def _edge_cells(cell_edges: np.ndarray, num_edges: int) -> tuple[np.ndarray, np.ndarray]:
    """Each edge's (cell, local edge) slots in the flattened cell_edges, and weights.

    Args:
        cell_edges: edge id of each cell's local edge j, shape=(nc, 3).
        num_edges: number of edges.

    Returns:
        (slots, shape=(num_edges, 2), padded with 0; weights 1/count, 0 on the padding,
        shape=(num_edges, 2)).
    """
    ids = cell_edges.ravel()
    order = np.argsort(ids, kind="stable")
    count = np.bincount(ids, minlength=num_edges)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    slots = np.zeros((num_edges, 2), dtype=np.int64)
    weights = np.zeros((num_edges, 2))
    for k in range(2):
        has = count > k
        slots[has, k] = order[start[has] + k]
        weights[has, k] = 1.0 / count[has]
    return slots, weights


class ConstantChooser:
    """The event under a constant and a scaled load: overstressed sites first, then least λ.

    Tension by the criterion's own measure of a site (σ1, the mean of its cells' at
    the midpoint, for ``principal`` and ``direction``; n·σ·n of the mean stress for
    ``traction``), Mohr-Coulomb shear with the material's cohesion and friction angle.

    Args:
        criterion: the edge criterion (tension; its ``points`` break ties).
        units: the edge units (their ``midpoint_stress``).
        config: the ``[cracking]`` settings.

    Attributes:
        over_sites: the sites over their strength under the constant load alone at the
            last :meth:`choose`, shape=(k,).
    """

    def __init__(self, criterion: EdgeCriterion, units: EdgeUnits, config: CrackingConfig) -> None:
        self.criterion, self.units, self.config = criterion, units, config
        mesh = units.state.mesh
        self.slots, self.weights = _edge_cells(mesh.cell_edges, len(mesh.edges))
        self.tangents, self.normals = edge_frames(mesh)
        self.over_sites = np.zeros(0, dtype=np.int64)

    @property
    def modes(self) -> tuple[str, ...]:
        """The modes it can return."""
        return ("tension", "shear")

    def choose(self, sc: np.ndarray, sv: np.ndarray, *, floor: float) -> Choice:
        """The event from the cells' constant and variable stress (per local edge midpoint).

        Args:
            sc: constant stress, shape=(num_cells, 3, 3) ([cell, local edge, component]).
            sv: variable stress at λ = 1, same shape.
            floor: a variable drive must exceed it.

        Returns:
            the sites, λ (0 for sites over their strength at λ = 0) and mode; no site when
            none ever reaches its strength.
        """
        state = self.units.state
        cand = ~state.cracked & state.crackable
        lam_t, drive, ratio_t = self._tension(sc, sv, floor)
        lam_s, ratio_s = self._shear(sc, sv, floor)
        ratio = np.maximum(ratio_t, ratio_s)
        self.over_sites = np.flatnonzero(cand & (ratio >= 1.0))
        lam_min = float(np.min(np.where(cand, np.minimum(lam_t, lam_s), np.inf), initial=np.inf))
        # the criterion sees the stress of the event (its directions: σ_v's own when σ_c = 0)
        stress = sc + lam_min * sv if np.isfinite(lam_min) and np.any(sc) else sv
        self.units.midpoint_stress = stress
        self.criterion.set_drive(drive, stress)
        if len(self.over_sites):
            return self._overstressed(ratio_t, ratio_s)
        edges, r = self.criterion.select(drive, floor=0.0)
        mode = "tension"
        if self.config.shear_cohesion is not None:
            ids = np.flatnonzero(cand)
            e, re = least(ids, lam_s[ids], self.criterion.points)
            if re < r * (1.0 - TIE_TOLERANCE):
                edges, r, mode = np.array([e]), re, "shear"
        return Choice(edges, r, mode)

    def _overstressed(self, ratio_t: np.ndarray, ratio_s: np.ndarray) -> Choice:
        """The most overstressed site (and up to ``edges_per_event`` of its mode), λ = 0."""
        sites = self.over_sites
        ratio = np.maximum(ratio_t, ratio_s)[sites]
        order = tie_order(sites, self.criterion.points)
        sites, ratio = sites[order], ratio[order]
        sites = sites[np.argsort(-ratio, kind="stable")]
        shear = ratio_s[sites] > ratio_t[sites]
        same = sites[shear == shear[0]][: self.config.edges_per_event]
        return Choice(same, 0.0, "shear" if shear[0] else "tension")

    def _tension(
        self, sc: np.ndarray, sv: np.ndarray, floor: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(λ, equivalent drive, overstress ratio) of tension per edge."""
        ft = self.config.tensile_strength
        if self.config.criterion == "traction":
            assert isinstance(self.criterion, TractionCriterion)
            n = self.criterion.normals
            mesh = self.units.state.mesh
            tc = normal_stress(edge_means(mesh, sc), n)
            tv = normal_stress(edge_means(mesh, sv), n)
            return traction_factors(tc, tv, ft, floor=floor)
        flat_c, flat_v = sc.reshape(-1, 3), sv.reshape(-1, 3)
        return principal_factors(
            flat_c[self.slots], flat_v[self.slots], self.weights, tensile_strength=ft, floor=floor
        )

    def _shear(self, sc: np.ndarray, sv: np.ndarray, floor: float) -> tuple[np.ndarray, np.ndarray]:
        """(λ, overstress ratio) of Mohr-Coulomb shear per edge (inf, 0 without cohesion)."""
        n_edges = len(self.slots)
        c = self.config.shear_cohesion
        if c is None:
            return np.full(n_edges, np.inf), np.zeros(n_edges)
        mesh = self.units.state.mesh
        t, n = self.tangents, self.normals
        sn_c, tau_c = edge_tractions(edge_means(mesh, sc), t, n)
        sn_v, tau_v = edge_tractions(edge_means(mesh, sv), t, n)
        return shear_factors_affine(
            (sn_c, sn_v),
            (tau_c, tau_v),
            c,
            friction_angle=self.config.shear_friction_angle,
            floor=floor,
        )
