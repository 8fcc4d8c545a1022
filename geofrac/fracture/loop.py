"""The sequentially linear event loop (Edo (2016), Fig. 2.6), on any composition of parts.

Each event, :meth:`EventLoop.run` asks its parts in turn:

1. *solve* the unit load (the scene's loads and prescribed displacements as given) and
   settle the crack faces (:class:`~geofrac.fracture.equilibrium.Equilibrium`);
2. *criterion*: σ1 of the units (:class:`~geofrac.fracture.units.Units`) and per site
   (:class:`~geofrac.fracture.event_criterion.EventCriterion`);
3. *choose* the sites of least r = f_t/σ1 over the modes
   (:class:`~geofrac.fracture.modes.ModeChooser`); the solution scaled by r is the state
   of the event (2.21), recorded (:class:`~geofrac.fracture.output.OutputWriter`);
4. *crack* them and *update* the changed units, the criterion, the solver and the faces
   (:class:`~geofrac.fracture.crack_update.CrackUpdate`);

until an end condition (:data:`END_REASONS`). With a
:class:`~geofrac.io.checkpoint.RunControl` the loop asks it after each event whether to
write a checkpoint or to stop on a signal, and continues from ``control.resume`` when
given (:class:`~geofrac.fracture.replay.Replay`); :class:`~geofrac.fracture.summary.Summary`
writes the results.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.assembly import Assembler
from geofrac.fracture.config import LoopSettings
from geofrac.fracture.context import CrackContext, JsonValue, Sites
from geofrac.fracture.crack_update import CrackUpdate
from geofrac.fracture.equilibrium import ContactUnsettled, Equilibrium, Solved
from geofrac.fracture.event_criterion import EventCriterion
from geofrac.fracture.faces import Faces
from geofrac.fracture.linear import SolverStrategy, Timing
from geofrac.fracture.modes import MODES, Choice, ModeChooser
from geofrac.fracture.output import OutputWriter, Row
from geofrac.fracture.record import Recorder
from geofrac.fracture.replay import EventStart, Replay, Restored
from geofrac.fracture.scales import TENSION_FLOOR
from geofrac.fracture.summary import Summary
from geofrac.fracture.units import Units
from geofrac.io.checkpoint import Checkpoint, RunControl
from geofrac.log import format_seconds

__all__ = ["END_REASONS", "MODES", "ContactUnsettled", "EventLoop", "LoopParts"]

#: Why an event loop ends ("contact": the crack faces' states did not settle;
#: "stages_done": a staged run, :mod:`~geofrac.fracture.staged`, ran its last stage).
END_REASONS = (
    "max_events",
    "energy_drop",
    "no_tensile_edge",
    "separated",
    "singular",
    "contact",
    "stages_done",
)


@dataclass(frozen=True)
class LoopParts:
    """The parts the loop asks, in the order of an event (the driver composes them).

    Attributes:
        units: the discretisation of the crack state.
        criterion: σ1 per site and the tension criterion.
        strategy: the solver strategy (``cracking.solver``).
        assembler: the stiffness and the held DOFs.
        equilibrium: solve (and settle the crack faces).
        chooser: choose the event's sites, r and mode.
        crack: crack them and update the parts.
        record: the event's row and frame fields.
        output: the event log, series and pictures.
        replay: checkpoints and resume.
        summary: the JSON results.
        timing: the phases and solver counts (shared with ``strategy``).
        contact: the crack faces' pairs (contact, cohesive faces), or None.
    """

    units: Units
    criterion: EventCriterion
    strategy: SolverStrategy
    assembler: Assembler
    equilibrium: Equilibrium
    chooser: ModeChooser
    crack: CrackUpdate
    record: Recorder
    output: OutputWriter
    replay: Replay
    summary: Summary
    timing: Timing
    contact: Faces | None = None


@dataclass
class _Run:
    """The loop's running record (what an event reads and leaves for the next)."""

    #: the unit solution of the last solve, shape=(n_global,).
    u_unit: np.ndarray
    #: the rows of the event log and the sites each event cracked, in order.
    rows: list[Row] = field(default_factory=list)
    batches: list[list[int]] = field(default_factory=list)
    #: the first event to compute; events up to ``done`` are in the log already (a
    #: resumed run recomputes those after ``first``).
    first: int = 1
    done: int = 0
    resume: Checkpoint | None = None
    first_energy: float = 0.0
    peak: float = 0.0
    face_hit: tuple[int, float] | None = None
    end: str = "max_events"
    #: why the run ended as it did, in words (``end_detail`` of the results).
    detail: str | None = None
    #: the last solved unit-load state: (strain energy, control displacement, force).
    unit: tuple[float, float, float] | None = None
    #: the loop's state at the start of the event whose solve factorised last: a
    #: checkpoint restarts from there, so that a resumed run repeats the solver's
    #: arithmetic (the update and reuse solvers reuse that factorisation).
    ref: EventStart | None = None
    error: float | None = None
    started: float = 0.0
    clock: float = 0.0

    def resumed(self, back: Restored) -> None:
        """Continue from a checkpoint's restored state (:meth:`EventLoop._restore`)."""
        self.rows, self.batches, self.u_unit = back.rows, back.batches, back.u_unit
        self.first, self.first_energy = back.replay_from, back.first_energy
        self.face_hit, self.done = back.face_hit, len(back.rows)
        self.peak = max((r["strain_energy"] for r in self.rows[: self.first - 1]), default=0.0)


class EventLoop:
    """Runs events on the parts until an end condition.

    Args:
        ctx: the shared set-up data.
        parts: the parts.
        sites: the pre-cracked sites.
        settings: what the loop reads of ``[cracking]``.
        control: checkpoints, signal stop and resume data, or None.
    """

    def __init__(
        self,
        ctx: CrackContext,
        parts: LoopParts,
        sites: Sites,
        *,
        settings: LoopSettings,
        control: RunControl | None,
    ) -> None:
        self.ctx, self.parts, self.sites = ctx, parts, sites
        self.settings, self.control = settings, control
        #: the rows of the event log, set when the loop ends.
        self.rows: list[Row] = []

    @property
    def modes(self) -> np.ndarray:
        """How each site cracked (:attr:`~geofrac.fracture.crack_update.CrackUpdate.modes`)."""
        return self.parts.crack.modes

    def run(self, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """Run; put the last state into ``unknown``; return the JSON results (collective)."""
        parts, last = self.parts, self.settings.max_events
        t0 = time.perf_counter()
        run = self._begin(unknown.function_space)
        self._announce(run, t0)
        parts.output.open(run.rows, None if run.resume is None else float(run.done))
        run.started = time.perf_counter()
        if last == 0:
            self._unit_only(run)
        try:
            for event in range(run.first, last + 1):
                if not self._event(run, event):
                    break
        finally:
            parts.strategy.drop()
            parts.output.close()
        return self._finish(run, unknown)

    # -- the steps of an event ---------------------------------------------------------
    def _event(self, run: _Run, event: int) -> bool:
        """Event ``event``: solve, criterion, choose, crack, update; False: the loop ends."""
        parts = self.parts
        replay = event <= run.done
        start = parts.replay.start(event, run.u_unit, run.face_hit)
        solved = self._solve(run, event, replay=replay)
        if solved is None:
            return False
        self._keep_reference(run, start)
        parts.timing.iterations += solved.iterations
        run.clock = time.perf_counter()
        choice = self._choose(run, event)
        if choice is None:
            return False
        assert run.unit is not None
        energy = choice.r * choice.r * run.unit[0]
        row = None if replay else self._log(run, event, choice, solved=solved, energy=energy)
        if replay:
            self._check_replay(run, event, choice)
        parts.crack.apply(choice)
        parts.timing.part("crack", run.clock)  # from the criterion's end
        self._after_crack(run, event, choice, row=row, energy=energy)
        if row is None:  # a replayed event: in the log and the series already
            return True
        return self._publish(run, event, row=row, energy=energy)

    def _solve(self, run: _Run, event: int, *, replay: bool) -> Solved | None:
        """The unit-load solution, settled; None when the run ends here (contact, singular)."""
        say, equilibrium = self.ctx.say, self.parts.equilibrium
        try:
            solved = equilibrium.solve(run.u_unit)
            run.u_unit = solved.u
            solved = equilibrium.settle(solved)
        except ContactUnsettled as exc:
            run.end = "contact"
            say(f"cracking: event {event}: {exc}")
            return None
        except RunError as exc:
            if replay:
                raise RunError(f"--resume: event {event} failed on replay: {exc}") from None
            run.end = "singular"
            say(f"cracking: event {event}: the system is singular ({exc})")
            return None
        run.u_unit = solved.u
        return solved

    def _keep_reference(self, run: _Run, start: EventStart) -> None:
        """Keep ``start`` as the checkpoints' restart when this event's solve factorised."""
        timing = self.parts.timing
        if timing.factorizations > start.timing["factorizations"] or run.ref is None:  # type: ignore[operator]
            run.ref = start
            # a resumed run factorises this event without a stale reference to drop: it
            # keeps the reasons and refinements counted by this solve
            start.timing["stale"] = dict(timing.stale)  # type: ignore[assignment]
            start.timing["refinements"] = timing.refinements

    def _choose(self, run: _Run, event: int) -> Choice | None:
        """σ1 per site and the event of least r; None when the run ends here."""
        ctx, parts, scales = self.ctx, self.parts, self.ctx.scales
        unit_s1, energy_unit, reaction_unit = parts.units.measures(run.u_unit)
        t = parts.timing.part("stresses", run.clock)  # from the solve's end
        run.unit = (energy_unit, *ctx.control.measure(run.u_unit, reaction_unit))
        sigma1 = parts.criterion.site_stress(unit_s1)
        first_r = run.rows[0]["load_factor"] if event > 1 and run.rows else None
        run.detail = scales.separated(energy_unit, run.first_energy if event > 1 else None)
        run.first_energy = energy_unit if event == 1 else run.first_energy
        if run.detail is not None:
            run.end = "separated"
            return None
        floor = TENSION_FLOOR * scales.rms_stress(energy_unit)
        choice = parts.chooser.choose(sigma1, floor=floor)
        run.clock = parts.timing.add("criterion", run.clock, part=("choose", t))
        if len(choice.sites) == 0:
            run.end = "no_tensile_edge"
            return None
        run.detail = scales.beyond(choice.r, first_r, control_displacement=choice.r * run.unit[1])
        if run.detail is not None:
            run.end = "separated"
            return None
        return choice

    def _log(self, run: _Run, event: int, choice: Choice, *, solved: Solved, energy: float) -> Row:
        """The event's row, appended to the log with the sites it cracks."""
        assert run.unit is not None
        control = (run.unit[1], run.unit[2])
        row = self.parts.record.row(event, choice, solved=solved, control=control, energy=energy)
        run.rows.append(row)
        run.batches.append([int(e) for e in choice.sites])
        return row

    def _check_replay(self, run: _Run, event: int, choice: Choice) -> None:
        """A replayed event must crack the sites the interrupted run cracked."""
        cracked = [int(e) for e in choice.sites]
        if cracked != run.batches[event - 1]:
            raise RunError(
                f"--resume: event {event} cracked edges {cracked}, the interrupted "
                f"run {run.batches[event - 1]}; the checkpoint does not reproduce it"
            )

    def _after_crack(
        self, run: _Run, event: int, choice: Choice, *, row: Row | None, energy: float
    ) -> None:
        """What the event leaves: its dissipation, where the crack reached the face, the peak."""
        units = self.parts.units
        if row is not None:
            self.parts.record.dissipation(row)
        if run.face_hit is None and self.ctx.face_nodes is not None:
            x_hit = units.face_x(choice.sites)
            if x_hit is not None:
                run.face_hit = (event, x_hit)
        run.peak = max(run.peak, energy)
        self.parts.timing.add("update", run.clock)

    def _publish(self, run: _Run, event: int, *, row: Row, energy: float) -> bool:
        """Frame, row and progress of a computed event; checkpoint, stop; False: the end."""
        cfg, output, timing, r = self.settings, self.parts.output, self.parts.timing, row["r"]
        if event % cfg.output_every == 0 or event == 1:
            output.frame(event, self._state(run, r), self._edge_data(r))
        output.row(row)  # flushed: a killed run keeps every completed event
        if event % max(1, cfg.max_events // 20) == 0:
            rate = (event - run.first + 1) / (time.perf_counter() - run.started)
            self.ctx.say(
                f"cracking: event {event}/{cfg.max_events}, r = {r:.4g}, energy "
                f"{energy:.4g}, {rate:.2f} events/s, {timing.factorizations} factorisations"
            )
        if cfg.energy_drop is not None and energy < (1.0 - cfg.energy_drop) * run.peak:
            run.end = "energy_drop"
            return False
        control = self.control
        if control is not None and event < cfg.max_events:
            save, stop = control.poll(event)
            if save:
                assert run.ref is not None
                output.sync()  # the log on disk holds the checkpoint's rows
                self.parts.replay.save(
                    control,
                    event,
                    rows=run.rows,
                    batches=run.batches,
                    first_energy=run.first_energy,
                    ref=run.ref,
                )
            if stop:
                control.interrupt(f"event {event}")
        return True

    # -- start and end ---------------------------------------------------------------
    def _begin(self, space: dolfinx.fem.FunctionSpace) -> _Run:
        """The state before loading, or a checkpoint's when resuming (collective)."""
        run, control = self._fresh(space), self.control
        if run.resume is not None and control is not None:
            control.check_resume()  # the same scene and number of ranks
            back = self._restore(run.resume)
            self.parts.crack.replayed(back.rows[: back.replay_from - 1], back.batches)
            run.resumed(back)
        return run

    def _fresh(self, space: dolfinx.fem.FunctionSpace) -> _Run:
        """The state before loading (a resume starts from it too; collective)."""
        self.parts.crack.start(self.sites.precracked)
        self.parts.equilibrium.open(space)
        resume = self.control.resume if self.control is not None else None
        return _Run(u_unit=np.zeros(self.ctx.n_global), resume=resume)

    def _restore(self, ck: Checkpoint) -> Restored:
        """The parts at the start of ``ck``'s replay event (a staged loop's own state too)."""
        return self.parts.replay.restore(ck, self.ctx.n_global)

    def _announce(self, run: _Run, t0: float) -> None:
        """The start-up message: the crack state, the set-up time, what a resume repeats."""
        say, units = self.ctx.say, self.parts.units
        setup = format_seconds(time.perf_counter() - t0)
        say(
            "cracking: "
            f"{units.state_text(len(self.sites.precracked), len(self.sites.random))}; "
            f"set-up {setup}"
        )
        if run.resume is not None:
            say(
                f"cracking: resuming after event {run.done} from {run.resume.path} (events "
                f"{run.first}-{run.done} are recomputed from the factorisation they used)"
            )

    def _unit_only(self, run: _Run) -> None:
        """``max_events = 0``: the unit-load state only (and its error against an exact one)."""
        ctx, units = self.ctx, self.parts.units
        run.u_unit = self.parts.equilibrium.solve(run.u_unit).u
        _, energy_unit, reaction_unit = units.measures(run.u_unit)
        run.unit = (energy_unit, *ctx.control.measure(run.u_unit, reaction_unit))
        if ctx.problem.exact is not None:
            run.error = units.l2_error(run.u_unit)
            ctx.say(f"cracking: displacement error (2.22) {run.error:.4e}")

    def _finish(self, run: _Run, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """Write the final frame and field, free the parts; the results (collective)."""
        parts, rows, u_unit = self.parts, run.rows, run.u_unit
        elapsed = time.perf_counter() - run.started
        if rows:
            # the final pattern; it replaces a frame already written for this event, so
            # each time appears once in the series
            r_last = rows[-1]["load_factor"]
            parts.output.frame(
                int(rows[-1]["event"]), self._state(run, r_last), self._edge_data(r_last)
            )
        self._finish_field(unknown, self._state(run, rows[-1]["load_factor"]) if rows else u_unit)
        self.rows = rows
        parts.output.finish(rows, self.modes, parts.summary.face_states())
        self.destroy()
        results = parts.summary.results(
            rows,
            end=run.end,
            elapsed=elapsed,
            face_hit=run.face_hit,
            done=len(rows) - run.first + 1,
        )
        if run.detail is not None:
            results["end_detail"] = run.detail
        if run.unit is not None:
            results["unit_load"] = parts.summary.unit_load(*run.unit)
        if run.resume is not None:
            results["resumed_after_event"] = run.done
        if run.error is not None:
            results["displacement_error_l2"] = run.error
        self.ctx.say(
            f"cracking: {len(rows)} events in {format_seconds(elapsed)} "
            f"({results['events_per_s']:.2f} events/s), end: {run.end}"
            + ("" if run.detail is None else f" ({run.detail})")
        )
        return results

    def _state(self, run: _Run, r: float) -> np.ndarray:
        """The displacement at load factor ``r`` of the last solve, shape=(n_global,)."""
        return r * run.u_unit

    def _edge_data(self, r: float) -> dict[str, np.ndarray]:
        return self.parts.record.edge_data(r, self.modes)

    def _finish_field(self, unknown: dolfinx.fem.Function, u: np.ndarray) -> None:
        """Put the last event's state into the problem's displacement (results.xdmf)."""
        ctx = self.ctx
        v = unknown.x.petsc_vec
        v.setArray(u[ctx.row0 : ctx.row0 + ctx.n_local])
        unknown.x.scatter_forward()
        ctx.problem.to_field()

    def destroy(self) -> None:
        """Free the solvers, the load vector and the gather."""
        self.parts.strategy.destroy()
        self.parts.assembler.destroy()
        self.parts.equilibrium.destroy()
