"""Construction stages in a cracking run: each stage's release drives the events.

A cracking scene with ``[initial_stress]`` and ``[[stages]]`` (docs/insitu.md, "Stages in
a cracking scene") runs :class:`StagedEventLoop`, the loop of an initial stress
(:class:`~geofrac.fracture.insitu.InsituEventLoop`; DeJong, Hendriks and Rots (2008))
whose variable load is the release of the running stage:

- a stage that removes cell groups makes them void (:mod:`~geofrac.fracture.staged_state`)
  and forms the release P = F0 − K u_e: the out-of-balance force of the remaining body
  in the state u_e where the last stage ended, F0 = F_ext,0 − I(σ0) on the new crack and
  void state (what the removed cells carried across the new wall, plus any part of an
  earlier release not yet applied); a stage without ``remove`` goes on with the pending
  release;
- the constant load is F0 − (1 − a) P, a the share of P applied by the earlier stages
  (0 after a removal), and the variable load is P: the state is u = u_c + λ u_v, both
  solved on the current crack state each event, with λ from 0 up to the stage's share
  s (``relaxation``; all that remains without it); at λ = 0 the constant solve gives
  u_e back;
- each event the least λ of the sites (:class:`~geofrac.fracture.constant.ConstantChooser`):
  λ ≤ s cracks the sites; λ > s ends the stage at λ = s without an event (a += s, and
  u_c + s u_v is the state the next stage starts from). After the last stage the run
  ends (``stages_done``);
- a stage's ``add`` installs removed groups again after its removal, stress-free in the
  state u_e, with their own material (:mod:`~geofrac.fracture.support`).

Each stage's end is a step of ``results.xdmf`` (step 0 the initial state), and
``summary.json`` has a ``stages`` entry per stage (its events, share, the first event's
release and the probes' displacement at the nearest node). A run stopped by a signal
resumes at the stage and event where it stopped (:mod:`~geofrac.fracture.staged_resume`).
"""

from __future__ import annotations

import dataclasses
import time

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.fem.solution import Solution
from geofrac.fem.stage_checkpoint import Frame
from geofrac.fem.stages import install_fields, state_frame
from geofrac.fracture import staged_resume
from geofrac.fracture.config import LoopSettings
from geofrac.fracture.constant import ConstantChooser, ConstantLoad, constant_load
from geofrac.fracture.constant_loop import ConstantEventLoop
from geofrac.fracture.context import CrackContext, JsonValue, Sites
from geofrac.fracture.control import release_control
from geofrac.fracture.equilibrium import ContactEquilibrium, Solved, Visited
from geofrac.fracture.insitu import InitialStressLoad, InsituEventLoop, checked_initial_stress
from geofrac.fracture.loop import LoopParts, _Run
from geofrac.fracture.modes import Choice
from geofrac.fracture.replay import Restored
from geofrac.fracture.staged_loads import StageLoads
from geofrac.fracture.staged_state import (
    StagedCrackState,
    group_cells,
    internal_force,
    kill_groups,
    live_max_displacement,
    probe_displacements,
    state_of,
)
from geofrac.fracture.support import SupportChooser, Supports
from geofrac.fracture.units import EdgeUnits
from geofrac.io.checkpoint import Checkpoint, RunControl
from geofrac.model.scene import Stage

__all__ = ["StagedEventLoop", "StagedInitialStress", "staged_loop"]


class StagedInitialStress(InitialStressLoad):
    """σ0 and its out-of-balance force, with the removed cells' weight gone.

    F_ext,0 includes the effects' terms (gravity: ρ of the live cells, ``alive``);
    :meth:`refresh` reassembles it after a removal. :meth:`force` adds the scene's loads
    acting in ``step`` (:mod:`~geofrac.fracture.staged_loads`; the loop sets ``step`` to
    the running stage's at its start, after forming a removal's release).
    """

    def __init__(self, ctx: CrackContext, units: EdgeUnits) -> None:
        super().__init__(ctx, units)
        self.external = self._external()[0] if ctx.problem.terms else None
        self.loads = StageLoads(ctx) if ctx.scene.loads else None
        #: the step whose loads act (0: the initial state; k + 1: stage k, 0-based).
        self.step = 0

    def force(self) -> np.ndarray:
        """F0 on the current crack state plus the loads acting in ``step`` (collective)."""
        force = super().force()
        return force if self.loads is None else force + self.loads.at(self.step)

    def refresh(self) -> None:
        """F0 of the intact mesh with the current ``alive`` cells' weight (collective)."""
        if self.external is None:
            return
        external = self._external()[0]
        self.base = self.base + (external - self.external)
        self.external = external


class StagedEventLoop(InsituEventLoop):
    """The initial-stress loop whose variable load is the running stage's release.

    Args:
        ctx, parts, sites, settings, control, load, chooser, insitu: as
            :class:`~geofrac.fracture.insitu.InsituEventLoop` (``insitu`` a
            :class:`StagedInitialStress`).
        solution: where the stages' ``results.xdmf`` steps go (``frames``).
    """

    def __init__(
        self,
        ctx: CrackContext,
        parts: LoopParts,
        sites: Sites,
        *,
        settings: LoopSettings,
        control: RunControl | None,
        load: ConstantLoad,
        chooser: ConstantChooser,
        insitu: StagedInitialStress,
        solution: Solution,
    ) -> None:
        super().__init__(
            ctx,
            parts,
            sites,
            settings=settings,
            control=control,
            load=load,
            chooser=chooser,
            insitu=insitu,
        )
        self.staged_insitu = insitu
        #: the running stage's share s (no event beyond it), and the least λ of the
        #: last choice (inf: no site or slip in this release).
        self.share, self.beyond = 1.0, float("inf")
        self.solution = solution
        self.stages: tuple[Stage, ...] = ctx.scene.stages
        #: the running stage (0-based; len(stages) when done) and whether it has begun.
        self.k, self.begun = 0, False
        #: the pending release P and the share of it applied before the running stage.
        self.release, self.applied = np.zeros(ctx.n_global), 0.0
        #: the state where the last stage ended, shape=(n_global,).
        self.u_end = np.zeros(ctx.n_global)
        self.entries: list[dict[str, JsonValue]] = []
        self.frames: list[Frame] = []
        self._events: list[int] = []  # events of the running stage
        self._first: dict[str, JsonValue] | None = None
        self._unknown: dolfinx.fem.Function | None = None
        self._final: np.ndarray | None = None
        #: active-set steps judged at the running stage's end, and the states they left.
        self._share_settles = 0
        self._share_history: Visited = {}
        assert isinstance(parts.units, EdgeUnits)
        #: the support installed by stages' ``add`` (:mod:`~geofrac.fracture.support`).
        self.supports = Supports(ctx, parts.units, insitu, chooser=chooser)
        #: the events cracked before each stage began, and the state where each finished
        #: stage ended, shape=(n_global,) (what a checkpoint derives the rest from).
        self._starts: list[int] = []
        self._ends: list[np.ndarray] = []

    #: checkpoints keep the stages' state (:mod:`~geofrac.fracture.staged_resume`).
    resumable = True

    def run(self, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """Run the stages (or resume them from ``control.resume``)."""
        self._unknown = unknown
        if self.solution.scene.output.xdmf:
            self.frames.append(self._frame(0, "initial", self.u_end))
        return super().run(unknown)

    # -- the stages ----------------------------------------------------------------------
    def _share(self) -> float:
        """The running stage's share s: its relaxation, or all that remains of P."""
        relaxation = self.stages[self.k].relaxation
        return max(1.0 - self.applied, 0.0) if relaxation is None else relaxation

    def _begin_stage(self, event: int) -> None:
        """Remove the stage's cells and form its release P = F0 − K u_e (collective)."""
        ctx, stage = self.ctx, self.stages[self.k]
        units = self.parts.units
        assert isinstance(units, EdgeUnits)
        self._starts.append(event - 1)  # (one site batch per event before it)
        if stage.remove:
            cells, changed = self._remove(stage)
            if self.faces is not None:  # pairs beside a void cell are no pairs any more
                self.faces.faces.cracked(np.zeros(0, dtype=np.int64), changed)
            units.reset()  # the MLS table of the measures: rebuilt
            self.parts.strategy.reset()
            self.parts.strategy.drop()  # a new factorisation with the new release
            pairs = None if self.faces is None else self.faces.faces.owned_blocks()
            self.release = (
                self._initial_force()
                + self.supports.force()
                - internal_force(ctx, units, self.u_end, pairs=pairs)
            )
            self.release[ctx.bc_rows] = 0.0
            self.applied = 0.0
            self.load.variable.load.setArray(self.release[self._rows])
            ctx.say(
                f"stage {self.k + 1}/{len(self.stages)} '{stage.name}': removed "
                f"{', '.join(stage.remove)} ({len(cells)} cells, {len(changed)} changed)"
            )
        if stage.add:
            self._install(stage, self.k + 1)
        self.share, self.staged_insitu.step = self._share(), self.k + 1  # its loads: a jump
        self.begun, self._events, self._first = True, [], None
        self._share_settles, self._share_history = 0, {}

    def _install(self, stage: Stage, index: int) -> None:
        """Install stage ``index`` (1-based)'s groups, stress-free at u_e (also on resume)."""
        changed = self.supports.install(stage, self.u_end, index=index)
        if self.faces is not None:
            self.faces.faces.cracked(np.zeros(0, dtype=np.int64), changed)
        self.parts.units.reset()
        self.parts.strategy.reset()
        self.parts.strategy.drop()
        assert self._unknown is not None and stage.material is not None
        self._finish_field(self._unknown, self.u_end)  # u_ref of the output's fields
        install_fields(self.ctx.problem, stage.add, stage.material)

    def _remove(self, stage: Stage) -> tuple[np.ndarray, np.ndarray]:
        """Make the stage's cells void, σ0 and their weight gone (collective).

        Returns the removed cells and the cells whose field changed, shape=(k,).
        """
        state = self.parts.units.state
        assert isinstance(state, StagedCrackState)
        cells = group_cells(self.ctx, stage.remove)
        changed = state.remove(cells)
        assert self.load.extra_stress is not None
        self.load.extra_stress[cells] = 0.0  # no σ0 in the opening
        kill_groups(self.ctx, stage.remove)
        self.staged_insitu.refresh()
        return cells, changed

    def _end_stage(self, run: _Run, *, complete: bool) -> None:
        """Close the running stage at its share (or, not complete, at its last event)."""
        stage, share = self.stages[self.k], self._share()
        beyond = self.beyond  # inf: no site ever cracks in this release
        if complete:
            self.u_end = self.u_const + share * run.u_unit
        elif run.rows and self._events:
            self.u_end = self._state(run, run.rows[-1]["load_factor"])
        entry: dict[str, JsonValue] = {
            "index": self.k + 1,
            "name": stage.name,
            "removed": list(stage.remove),
            "added": list(stage.add),
            "share": share,
            "released": self.applied + share if complete else None,
            "complete": complete,
            "events": len(self._events),
            "event_ids": list(self._events),
            "first_event": self._first,
            "next_load_factor": beyond if complete and np.isfinite(beyond) else None,
            "probes": probe_displacements(self.ctx, self.u_end),
            "max_displacement": live_max_displacement(self.ctx, state_of(self), self.u_end),
        }
        self.entries.append(entry)
        if self.solution.scene.output.xdmf:
            self.frames.append(self._frame(self.k + 1, stage.name, self.u_end))
        self.ctx.say(
            f"stage {self.k + 1}/{len(self.stages)} '{stage.name}': {len(self._events)} events, "
            f"share {share:.4g} (released {self.applied + share:.4g} of the pending release)"
            + ("" if complete else ", not completed")
        )
        if complete:
            self.applied += share
            self._ends.append(self.u_end)
        self.k, self.begun = self.k + 1, False

    # -- an event ------------------------------------------------------------------------
    def _event(self, run: _Run, event: int) -> bool:
        """Solve, choose; crack when λ ≤ s, else end the stage and go on with the next."""
        parts, replay = self.parts, event <= run.done
        while self.k < len(self.stages):
            if not self.begun:
                self._begin_stage(event)
            start = parts.replay.start(event, run.u_unit, run.face_hit)
            start.loop = staged_resume.snapshot(self)
            solved = self._solve(run, event, replay=replay)
            if solved is None:
                return False
            self._keep_reference(run, start)
            parts.timing.iterations += solved.iterations
            run.clock = time.perf_counter()
            choice = self._choose(run, event)
            if choice is not None and self.faces is not None:
                settled = self._settle(run, event, choice, solved)
                if settled is None and run.end != "no_tensile_edge":
                    return False  # unsettled, singular or separated
                choice, solved = settled if settled is not None else (None, solved)
            if choice is not None:
                return self._crack(run, event, choice, solved, replay=replay)
            if run.end != "no_tensile_edge":  # separated
                return False
            if self.faces is not None:
                moved = self._settle_at_share(run, event)
                if moved is None:
                    return False
                if moved:  # other states at the stage's end: solve and choose again
                    continue
            run.end, run.detail = "max_events", None
            self._end_stage(run, complete=True)
        run.end = "stages_done"
        return False

    def _limit(self, choice: Choice) -> Choice:
        """No event beyond the running stage's share (a joint's slip included)."""
        self.beyond = choice.r if len(choice.sites) else float("inf")
        if choice.r > self.share:
            return Choice(np.zeros(0, dtype=np.int64), choice.r, choice.mode)
        return choice

    def _settle_at_share(self, run: _Run, event: int) -> bool | None:
        """Judge the pair states at the stage's end u_c + s u_v (with contact).

        Returns whether a state changed (the caller solves and chooses again), None when
        the states do not settle within ``contact_iterations`` (the run ends).
        """
        assert self.faces is not None
        faces = self.faces.faces
        equilibrium = self.parts.equilibrium
        assert isinstance(equilibrium, ContactEquilibrium)
        changes, blocks = faces.update(self._state(run, self.share))
        if not changes:
            return False
        self._share_settles += 1
        if self._share_settles > equilibrium.iterations:
            run.end = "contact"
            self.ctx.say(f"cracking: event {event}: {equilibrium.unsettled(changes)}")
            return None
        equilibrium.absorb(changes, blocks, history=self._share_history, made=[], last=False)
        return True

    def _crack(
        self, run: _Run, event: int, choice: Choice, solved: Solved, *, replay: bool
    ) -> bool:
        """Log the state u_c + λ u_v, crack, publish (``replay``: check it, as the log's)."""
        assert run.unit is not None
        r, (energy_c, _, _, cross) = choice.r, self._const
        energy = energy_c + r * cross + r * r * run.unit[0]
        row = None
        if replay:
            self._check_replay(run, event, choice)
        else:
            row = self._log(run, event, choice, solved=solved, energy=energy)
            row["control_displacement"] = 0.0
        if choice.r == 0.0:
            self.over_cracked += len(choice.sites)
        if not self._events:
            self._first = {"event": event, "load_factor": r, "release": self.applied + r}
        self._events.append(event)
        self.parts.crack.apply(choice)
        self._after_crack(run, event, choice, row=row, energy=energy)
        if row is None:  # a replayed event: in the log and the series already
            return True
        return self._publish(run, event, row=row, energy=energy)

    def _solve(self, run: _Run, event: int, *, replay: bool) -> Solved | None:
        """The constant load F0 − (1 − a) P on the current crack state, then both solves."""
        force = self._initial_force() - (1.0 - self.applied) * self.release
        if self.supports.installed:  # K_s u_I, and −D ε(u_I) at the support's sites
            force += self.supports.force()
            assert self.load.extra_stress is not None
            self.supports.offset(self.load.extra_stress)
        self.load.constant.load.setArray(force[self._rows])
        return ConstantEventLoop._solve(self, run, event, replay=replay)

    def _restore(self, ck: Checkpoint) -> Restored:
        """The parts and the stages at the start of ``ck``'s replay event."""
        return staged_resume.restore(self, ck)

    def _frame(self, index: int, name: str, u: np.ndarray) -> Frame:
        """The fields of the state u for ``results.xdmf`` (displacement, stresses, alive)."""
        assert self._unknown is not None
        problem = self.ctx.problem
        self._finish_field(self._unknown, u)
        assert problem.insitu is not None
        return state_frame(problem, problem.insitu.alive, index=index, name=name)

    def _state(self, run: _Run, r: float) -> np.ndarray:
        """u_c + r u_v, or after the stages the state where the last one ended."""
        return self._final if self._final is not None else super()._state(run, r)

    def _finish(self, run: _Run, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """The results, with ``stages``; the stages' steps go to the solution's frames."""
        if self.k < len(self.stages) and self.begun:  # ended within a stage
            self._end_stage(run, complete=False)
        self._final = self.u_end
        results = super()._finish(run, unknown)
        if not run.rows:  # no event: the field is where the last stage ended, not u_v
            self._finish_field(unknown, self.u_end)
        results["stages"] = self.entries  # type: ignore[assignment]
        self.solution.frames = self.frames
        return results


#: The least stress of the release's a-priori scale, as a fraction of E: a σ0 of zero
#: releases nothing, and its run ends ``separated`` against this scale.
MIN_RELEASE_STRESS = 1e-6


def _release_scale(ctx: CrackContext, insitu: InitialStressLoad) -> None:
    """The release's a-priori displacement |σ0|max L / E: the control and the scales."""
    sigma = float(np.max(np.abs(insitu.site_stress), initial=0.0))
    mat = ctx.scene.material
    assert mat is not None  # a fem scene has one
    scale = max(sigma, MIN_RELEASE_STRESS * mat.E) * ctx.scales.length / mat.E
    ctx.control = release_control(scale)
    ctx.control_unit = scale
    ctx.scales = dataclasses.replace(ctx.scales, displacement=scale)


def staged_loop(
    ctx: CrackContext,
    parts: LoopParts,
    sites: Sites,
    *,
    settings: LoopSettings,
    control: RunControl | None,
    solution: Solution,
) -> StagedEventLoop:
    """The loop of a cracking scene with ``[[stages]]`` (collective).

    Checks the initial state's balance as :func:`~geofrac.fracture.insitu.insitu_loop`
    does, sets σ0 at the sites and the release's scales.

    Raises:
        RunError: collectively, when the initial state is out of balance.
    """
    insitu, criterion = checked_initial_stress(
        ctx,
        parts,
        StagedInitialStress,
        key="stages",
        role=f"{len(ctx.scene.stages)} stages release it",
    )
    _release_scale(ctx, insitu)
    load = constant_load(ctx, ctx.config)
    load.variable.load.set(0.0)
    load.extra_stress = insitu.site_stress.copy()
    parts.assembler.case = load.variable
    adds = any(stage.add for stage in ctx.scene.stages)
    chooser = (SupportChooser if adds else ConstantChooser)(criterion, insitu.units, ctx.config)
    return StagedEventLoop(
        ctx,
        parts,
        sites,
        settings=settings,
        control=control,
        load=load,
        chooser=chooser,
        insitu=insitu,
        solution=solution,
    )
