"""The crack driver: the sequentially linear event loop (Edo (2016), Fig. 2.6) composed of parts.

Division of work:

- the crack state (cracked sites, visibility, fits) is pure numpy on the *global* mesh
  and replicated on every rank, in the mesh file's numbering; the event sequence
  therefore does not depend on the number of ranks;
- each rank computes the matrices, stresses, energy and reactions of the units it owns
  in DOLFINx's partition; the stiffness is assembled through PETSc's COO interface; the
  σ1 values are summed to every rank for the criterion.

:class:`CrackDriver` composes the parts, each behind a protocol in its own module:

- :class:`~geofrac.fracture.units.Units` (the discretisation of the crack state),
- :class:`~geofrac.fracture.event_criterion.EventCriterion` (which sites crack, r),
- :class:`~geofrac.fracture.linear.SolverStrategy` (``cracking.solver``),
- :class:`~geofrac.fracture.output.OutputWriter` with a
  :class:`~geofrac.fracture.output.SiteDrawing` (events.csv, series, pictures),
- :class:`~geofrac.fracture.assembly.Assembler` (stiffness and held DOFs) and the loop
  :class:`~geofrac.fracture.loop.EventLoop`.

A :class:`Variant` makes the site-specific parts: :data:`EDGES` (element edges, MLS
cells; chapter 2) here, :data:`~geofrac.fracture.grain_driver.GRAINS` (grain
interfaces; chapter 3) in :mod:`~geofrac.fracture.grain_driver`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.errors import RunError
from geofrac.fem.elastic import ElasticProblem
from geofrac.fem.solution import Solution
from geofrac.fracture.assembly import Assembler
from geofrac.fracture.config import CrackingConfig, LoopSettings
from geofrac.fracture.context import (
    CrackContext,
    GlobalMesh,
    JsonValue,
    Say,
    Sites,
    crack_context,
    facet_nodes,
)
from geofrac.fracture.crack_update import CrackUpdate
from geofrac.fracture.equilibrium import ContactEquilibrium, Equilibrium, LinearEquilibrium
from geofrac.fracture.event_criterion import CRITERIA, EdgeCriterion, EventCriterion
from geofrac.fracture.faces import Faces, Softening, joint_properties
from geofrac.fracture.linear import SolverStrategy, Timing, make_strategy
from geofrac.fracture.loop import EventLoop, LoopParts
from geofrac.fracture.modes import ModeChooser, ShearStrength
from geofrac.fracture.output import EdgeDrawing, EventOutput, Row, SiteDrawing
from geofrac.fracture.record import Recorder
from geofrac.fracture.replay import Replay
from geofrac.fracture.summary import FaceReport, Summary
from geofrac.fracture.topology import random_sites
from geofrac.fracture.units import EdgeUnits, SiteState, Units, mls_settings
from geofrac.solvers import Matrix, Vector

__all__ = ["EDGES", "CrackDriver", "EdgeVariant", "Variant"]


class Variant(Protocol):
    """The site-specific parts of a crack driver (element edges, grain interfaces).

    Attributes:
        kind: the loop's kind in its checkpoints
            (:class:`~geofrac.io.checkpoint.RunControl`).
    """

    kind: str

    def units(self, ctx: CrackContext) -> Units:
        """The discretisation of the crack state (builds the replicated state)."""
        ...

    def criterion(self, ctx: CrackContext, units: Units) -> EventCriterion:
        """The event criterion on ``units``' sites."""
        ...

    def drawing(self, ctx: CrackContext, units: Units, sites: Sites) -> SiteDrawing:
        """How the sites appear in the series and pictures."""
        ...


@dataclass(frozen=True)
class EdgeVariant:
    """Element edges: MLS-cracked cells (chapter 2)."""

    kind: str = "cracking"

    def units(self, ctx: CrackContext) -> Units:
        """:class:`~geofrac.fracture.units.EdgeUnits`.

        Cracks cut cells with contact and the tip criteria; the stress tensors are kept
        for shear events and the criteria that read them.
        """
        cfg = ctx.config
        return EdgeUnits(
            ctx,
            mls=mls_settings(cfg),
            cut=cfg.contact or cfg.criterion != "principal",
            keep_stress=cfg.shear_cohesion is not None
            or CRITERIA[cfg.criterion].needs_stress
            or bool(cfg.constant)
            or ctx.scene.initial_stress is not None,
        )

    def criterion(self, ctx: CrackContext, units: Units) -> EventCriterion:
        """The ``cracking.criterion`` of :data:`~geofrac.fracture.event_criterion.CRITERIA`."""
        assert isinstance(units, EdgeUnits)
        return CRITERIA[ctx.config.criterion](units, ctx.config)

    def drawing(self, ctx: CrackContext, units: Units, sites: Sites) -> SiteDrawing:
        """:class:`~geofrac.fracture.output.EdgeDrawing`."""
        return EdgeDrawing(units.state)


#: The edge variant.
EDGES = EdgeVariant()


def _sites(ctx: CrackContext, units: Units, points: np.ndarray) -> Sites:
    """The sites of the ``precracked`` groups and of ``precracked_fraction`` (collective).

    ``points``: where each site lies (the random draw's order), shape=(num_sites, 2).
    """
    cfg, state = ctx.config, units.state
    pre = []
    for group in cfg.precracked:
        pairs = np.sort(facet_nodes(ctx.tagged, ctx.gm, group), axis=1)
        pre.append(units.group_sites(pairs))
    group_sites = np.unique(np.concatenate(pre)) if pre else np.zeros(0, dtype=np.int64)
    random = random_sites(
        state.crackable & ~state.mesh.boundary_edges,
        cfg.precracked_fraction,
        cfg.precrack_seed,
        points=points,
    )
    return Sites(np.union1d(group_sites, random), group_sites, random)


def _faces(ctx: CrackContext, units: Units, sites: Sites) -> Faces | None:
    """The crack faces: with ``cracking.contact`` or a fracture energy, else None."""
    cfg = ctx.config
    if not cfg.contact and cfg.fracture_energy is None:
        return None
    assert isinstance(units, EdgeUnits)
    softening = None
    if cfg.fracture_energy is not None:
        softening = Softening(cfg.tensile_strength, cfg.fracture_energy, cfg.teeth)
    return Faces(
        ctx,
        units,
        contact=cfg.contact,
        joints=joint_properties(ctx, units, sites) if cfg.contact else None,
        penalty=cfg.contact_penalty,
        softening=softening,
    )


class CrackDriver:
    """Sequentially linear crack propagation for one scene.

    The ``[cracking]`` settings are read here, in the composition, and handed to the parts
    that need them as constructor arguments (the loop's own as
    :class:`~geofrac.fracture.config.LoopSettings`); no part reads ``cracking.contact``
    itself. The context, the criteria and the solver strategies still take the
    validated config as a whole.

    Args:
        config: the validated ``[cracking]`` settings.
        solution: the set-up and compiled problem (its load vector and Dirichlet data
            are used; its matrix is not), and the run control, if any.
        say: progress printer (rank 0).
        write: write ``events.csv``, the pictures and the XDMF series into
            ``output.dir`` (the results are returned either way; the rows of the event
            log stay in :attr:`rows`).
        variant: the site-specific parts (:data:`EDGES` by default).
    """

    def __init__(
        self,
        config: CrackingConfig,
        solution: Solution,
        say: Say,
        *,
        write: bool = False,
        variant: Variant = EDGES,
    ) -> None:
        self.config = config
        self.problem: ElasticProblem = solution.problem
        #: checkpoints, signal stop and resume data (:class:`~geofrac.io.checkpoint.RunControl`)
        self.control = solution.control
        if self.control is not None:  # checkpoints name the loop that wrote them
            self.control.kind = variant.kind
        self.ctx = ctx = crack_context(config, solution, say)
        self.unknown: dolfinx.fem.Function = self.problem.unknown()
        self.units: Units = variant.units(ctx)
        self.criterion: EventCriterion = variant.criterion(ctx, self.units)
        self.sites = _sites(ctx, self.units, self.criterion.points)
        #: crack-face contact (``cracking.contact``) and cohesive faces (fracture
        #: energy), or None.
        self.contact: Faces | None = _faces(ctx, self.units, self.sites)
        self.assembler = Assembler(ctx, self.units, contact=self.contact)
        self.timing = Timing()
        self.strategy: SolverStrategy = make_strategy(ctx, self.assembler, self.timing)
        self.drawing: SiteDrawing = variant.drawing(ctx, self.units, self.sites)
        settings = LoopSettings(
            max_events=config.max_events,
            output_every=config.output_every,
            energy_drop=config.energy_drop,
            contact=config.contact,
        )
        parts = self._parts(write=write)
        self.loop: EventLoop
        if ctx.scene.stages:  # the stages' release drives the events
            from geofrac.fracture.staged import staged_loop

            self.loop = staged_loop(
                ctx, parts, self.sites, settings=settings, control=self.control, solution=solution
            )
        elif ctx.scene.initial_stress is not None:  # σ0 joins the constant load
            from geofrac.fracture.insitu import insitu_loop

            self.loop = insitu_loop(ctx, parts, self.sites, settings=settings, control=self.control)
        elif config.constant:  # loads that do not scale together
            self.loop = self._constant_loop(parts, settings)
        else:
            self.loop = EventLoop(ctx, parts, self.sites, settings=settings, control=self.control)

    def _constant_loop(self, parts: LoopParts, settings: LoopSettings) -> EventLoop:
        """The loop of a run with ``cracking.constant`` (two right-hand sides per event)."""
        from geofrac.fracture.constant import ConstantChooser, constant_load
        from geofrac.fracture.constant_loop import ConstantEventLoop

        if not isinstance(self.units, EdgeUnits) or not isinstance(self.criterion, EdgeCriterion):
            raise RunError("cracking.constant: element edges only (not grain interfaces)")
        load = constant_load(self.ctx, self.config)
        self.assembler.case = load.variable
        return ConstantEventLoop(
            self.ctx,
            parts,
            self.sites,
            settings=settings,
            control=self.control,
            load=load,
            chooser=ConstantChooser(self.criterion, self.units, self.config),
        )

    def _parts(self, *, write: bool) -> LoopParts:
        """The loop's parts on the units, criterion, faces, solver and assembler."""
        ctx, config, contact = self.ctx, self.config, self.contact
        units, criterion, strategy = self.units, self.criterion, self.strategy
        equilibrium: Equilibrium = (
            LinearEquilibrium(strategy)
            if contact is None
            else ContactEquilibrium(strategy, contact, config.contact_iterations)
        )
        shear = None
        if config.shear_cohesion is not None:
            shear = ShearStrength(config.shear_cohesion, config.shear_friction_angle)
        chooser = ModeChooser(criterion, units, contact=contact, shear=shear)
        face = None if config.face is None else FaceReport(config.face, config.face_origin)
        output = EventOutput(
            ctx,
            units.state,
            self.drawing,
            sites=self.sites,
            write=write,
            contact=config.contact,
            softening=config.fracture_energy is not None,
        )
        return LoopParts(
            units=units,
            criterion=criterion,
            strategy=strategy,
            assembler=self.assembler,
            equilibrium=equilibrium,
            chooser=chooser,
            crack=CrackUpdate(units, criterion, strategy, contact=contact),
            record=Recorder(ctx, units, output, contact=contact, contact_on=config.contact),
            output=output,
            replay=Replay(
                units,
                criterion,
                strategy,
                assembler=self.assembler,
                timing=self.timing,
                contact=contact,
            ),
            summary=Summary(
                ctx,
                units,
                self.sites,
                timing=self.timing,
                assembler=self.assembler,
                contact=contact,
                contact_on=config.contact,
                modes=chooser.modes,
                face=face,
                solver=config.solver,
            ),
            timing=self.timing,
            contact=contact,
        )

    # -- views ---------------------------------------------------------------------------
    @property
    def state(self) -> SiteState:
        """The replicated crack state."""
        return self.units.state

    @property
    def gm(self) -> GlobalMesh:
        """The gathered mesh."""
        return self.ctx.gm

    @property
    def n_global(self) -> int:
        """Number of global DOFs."""
        return self.ctx.n_global

    @property
    def precracked(self) -> np.ndarray:
        """The sites cracked before loading, shape=(k,) (add to them with ``sites.add``)."""
        return self.sites.precracked

    @property
    def rows(self) -> list[Row]:
        """The event log's rows (after :meth:`run`)."""
        return self.loop.rows

    # -- one state, for tests and diagnostics -------------------------------------------
    def assemble(self, held_values: np.ndarray) -> tuple[Matrix, Vector, np.ndarray]:
        """Stiffness, load vector and held DOFs of the current state (see the assembler)."""
        return self.assembler.assemble(held_values)

    def solve(self, A: Matrix, b: Vector, x: Vector) -> int:
        """Solve an assembled system with the strategy's factorisation; CG iterations."""
        return self.strategy.solve_system(A, b, x)

    def measures(self, u: np.ndarray) -> tuple[np.ndarray, float, float]:
        """(σ1 per site, strain energy, control reaction) of a global solution u."""
        unit_s1, energy, reaction = self.units.measures(u)
        return self.criterion.site_stress(unit_s1), energy, reaction

    # -- the loop ------------------------------------------------------------------------
    def run(self) -> dict[str, JsonValue]:
        """Run events until an end condition; write the outputs; return the results.

        With a :class:`~geofrac.io.checkpoint.RunControl` (``solution.control``) the loop
        asks it after each event whether to write a checkpoint or to stop on a signal,
        and continues from ``control.resume`` when given.
        """
        try:
            return self.loop.run(self.unknown)
        except RunError:  # raised on every rank (Interrupted too): free the solvers
            self.destroy()
            raise

    def destroy(self) -> None:
        """Free the solvers and vectors."""
        self.loop.destroy()
