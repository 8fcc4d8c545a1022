"""Support installed by construction stages in a cracking run (docs/insitu.md).

A stage of a cracking scene may ``add`` cell groups that an earlier stage removed: a
lining, backfill, with the stage's ``material`` (E, ν and optionally a tensile strength).
Until their stage the cells are void (:class:`~geofrac.fracture.staged_state.StagedCrackState`);
at it they are installed, stress-free in the state u_I where the last stage ended:

- their stiffness is that of their own material
  (:func:`~geofrac.fracture.units.set_material`), element cells again, MLS once a crack
  reaches them;
- their stress is D ε(u − u_I) and they carry no σ0: their internal force is
  K_s (u − u_I), so the constant right-hand side gains F_I = K_s u_I (each event, on the
  current crack state), and at the sites their constant stress gains −D ε(u_I)
  (:meth:`Supports.offset`); at λ = 0 the state is still u_I;
- their σ0 leaves the initial internal force (:func:`drop_initial_stress`);
- their interior edges (both cells installed by the same stage) are crack sites when
  their material has a tensile strength f_e; an edge between two materials (support and
  rock, or supports of two stages) is bonded: no crack site, as a liner is attached to
  the rock in RS2 unless a joint is placed between them (a bond strength is no key yet).
  The chooser takes one strength (``material.tensile_strength``, f_ref): a site of
  strength f_e is judged with its cells' stresses times f_ref / f_e
  (:class:`SupportChooser`), which gives its λ exactly (σ1, the normal traction and the
  mean of either are homogeneous of degree one in the stress); Mohr-Coulomb shear is
  judged on the same scaled stresses, so a support's cohesion is ``material.cohesion``
  × f_e / f_ref (its friction angle the rock's).
"""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fracture.constant import ConstantChooser
from geofrac.fracture.context import CrackContext
from geofrac.fracture.insitu import InitialStressLoad
from geofrac.fracture.modes import Choice
from geofrac.fracture.staged_state import StagedCrackState, group_cells, internal_force
from geofrac.fracture.units import EdgeUnits, set_material
from geofrac.materials import d_matrix
from geofrac.model.scene import Stage

__all__ = ["SupportChooser", "Supports", "drop_initial_stress"]


class SupportChooser(ConstantChooser):
    """:class:`ConstantChooser` with a strength per site (installed support).

    Attributes:
        scale: f_ref / f_e of the site of each cell's local edge, shape=(num_cells, 3),
            or None (every site has f_ref).
    """

    scale: np.ndarray | None = None

    def choose(self, sc: np.ndarray, sv: np.ndarray, *, floor: float) -> Choice:
        """The event of :meth:`ConstantChooser.choose` with each site's own strength."""
        if self.scale is None:
            return super().choose(sc, sv, floor=floor)
        choice = super().choose(sc * self.scale[..., None], sv * self.scale[..., None], floor=floor)
        finite = np.isfinite(choice.r) and np.any(sc)
        self.units.midpoint_stress = sc + choice.r * sv if finite else sv  # unscaled
        return choice


def drop_initial_stress(insitu: InitialStressLoad, cells: np.ndarray) -> None:
    """Installed ``cells`` (gathered ids, shape=(k,)) carry no σ0 (collective).

    Their element field's t ∫ Bᵀ σ0 dA leaves the intact part of I(σ0) (into ``base``),
    and their σ0 means and site stresses become 0.
    """
    ctx, units = insitu.ctx, insitu.units
    change = np.zeros(ctx.n_global)
    for c in np.asarray(cells, dtype=np.int64).tolist():
        i = insitu.position.get(c)
        if i is None:
            continue
        np.add.at(change, units.fe_dofs[i], insitu.fe_force[i])
        insitu.fe_force[i] = 0.0
    ctx.comm.Allreduce(MPI.IN_PLACE, change, op=MPI.SUM)
    insitu.base = insitu.base + change
    insitu.cell_mean[cells] = 0.0
    insitu.site_stress[cells] = 0.0


class Supports:
    """The installations of a staged cracking run and their loads.

    Args:
        ctx: the crack context.
        units: the edge units (a :class:`StagedCrackState`).
        insitu: σ0 and its force.
        chooser: the event chooser (its per-site strengths).
    """

    def __init__(
        self,
        ctx: CrackContext,
        units: EdgeUnits,
        insitu: InitialStressLoad,
        *,
        chooser: ConstantChooser,
    ) -> None:
        self.ctx, self.units, self.insitu, self.chooser = ctx, units, insitu, chooser
        #: f_t of each cell's material (inf: none, its edges never crack), shape=(nc,).
        self.strength = np.full(len(ctx.gm.cells), ctx.config.tensile_strength)
        #: each cell's material: 0 the scene's, k the k-th installation's, shape=(nc,).
        self.material = np.zeros(len(ctx.gm.cells), dtype=np.int64)
        #: (the installation's cells, shape=(nc,) bool; u_I, shape=(n_global,)).
        self.installed: list[tuple[np.ndarray, np.ndarray]] = []

    def install(self, stage: Stage, u_ref: np.ndarray, *, index: int) -> np.ndarray:
        """Install ``stage.add`` with its material at u_I = ``u_ref``; the changed cells.

        ``u_ref``: shape=(n_global,); ``index``: the stage's (1-based, for the message).
        Collective.

        Raises:
            RunError: when an edge of the cells cracked before they were removed.
        """
        material = stage.material
        assert material is not None
        cells = group_cells(self.ctx, stage.add)
        state = self.units.state
        assert isinstance(state, StagedCrackState)
        m = state.mesh
        edges = np.unique(m.cell_edges[cells])
        if state.cracked[edges].any():
            raise RunError(
                "stages: an added group's edges cracked before a stage removed it; "
                "installing support on cracked cells is not supported"
            )
        D = d_matrix(material.E, material.nu, 2, plane=material.plane)
        set_material(self.units, cells, D)
        f_t = material.tensile_strength
        self.strength[cells] = np.inf if f_t is None else f_t
        self.material[cells] = len(self.installed) + 1
        changed = state.install(cells, sites=f_t is not None)
        ec = m.edge_cells[edges]
        kind = self.material[np.maximum(ec, 0)]
        state.crackable[edges] &= (ec >= 0).all(axis=1) & (kind[:, 0] == kind[:, 1])
        drop_initial_stress(self.insitu, cells)
        for earlier, _ in self.installed:  # removed since, now installed again
            earlier[cells] = False
        mask = np.zeros(len(m.cells), dtype=bool)
        mask[cells] = True
        self.installed.append((mask, u_ref.copy()))
        self._scale()
        self.ctx.say(
            f"stage {index}/{len(self.ctx.scene.stages)} '{stage.name}': installed "
            f"{', '.join(stage.add)} ({len(cells)} cells, E = {material.E:g}, f_t = "
            f"{'none' if f_t is None else f'{f_t:g}'})"
        )
        return changed

    def _scale(self) -> None:
        """f_ref / f_e per cell and local edge (f_e of the edge's cells; inf: 0)."""
        if not isinstance(self.chooser, SupportChooser):
            return
        m = self.units.state.mesh
        ec = m.edge_cells
        site = np.where(ec >= 0, self.strength[np.maximum(ec, 0)], np.inf).min(axis=1)
        ratio = np.where(np.isfinite(site), self.ctx.config.tensile_strength / site, 0.0)
        per_cell = ratio[m.cell_edges]  # shape=(nc, 3)
        self.chooser.scale = None if np.all(per_cell == 1.0) else per_cell

    def force(self) -> np.ndarray:
        """F_I = Σ K_s u_I over the installations, shape=(n_global,) (collective)."""
        f = np.zeros(self.ctx.n_global)
        for mask, u_ref in self.installed:
            f += internal_force(self.ctx, self.units, u_ref, only=mask)
        return f

    def offset(self, extra: np.ndarray) -> None:
        """Set the installed cells' constant site stress to −D ε(u_I) (collective).

        ``extra``: the constant stress added at the sites, shape=(nc, 3, 3) (σ0
        elsewhere).
        """
        for mask, u_ref in self.installed:
            self.units.measures(u_ref)
            extra[mask] = -self.units.midpoint_stress[mask]
