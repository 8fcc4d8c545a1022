"""The sequentially linear event loop (Edo (2016), Fig. 2.6), on any composition of parts.

Each event: unit load (the scene's loads and prescribed displacements as given) → solve
(:class:`~geofrac.fracture.linear.SolverStrategy`) → σ1 of the units
(:class:`~geofrac.fracture.units.Units`) → σ1 per site and the sites of least
r = f_t/σ1 (:class:`~geofrac.fracture.event_criterion.EventCriterion`) → the solution
scaled by r is the state of the event (2.21) → record
(:class:`~geofrac.fracture.output.OutputWriter`) → refit the changed units → repeat.

With a :class:`~geofrac.io.checkpoint.RunControl` the loop asks it after each event
whether to write a checkpoint or to stop on a signal, and continues from
``control.resume`` when given.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fracture.assembly import Assembler
from geofrac.fracture.contact import SLIP, edge_frames, edge_tractions, shear_factors
from geofrac.fracture.context import CrackContext, JsonValue, Sites
from geofrac.fracture.criterion import TIE_TOLERANCE, edge_means, least
from geofrac.fracture.event_criterion import EventCriterion
from geofrac.fracture.incremental import Gather
from geofrac.fracture.linear import SolverStrategy, Timing
from geofrac.fracture.output import OutputWriter, Row, read_checkpoint, save_checkpoint
from geofrac.fracture.scales import TENSION_FLOOR
from geofrac.fracture.units import Units
from geofrac.io.checkpoint import Checkpoint, RunControl
from geofrac.log import format_seconds

if TYPE_CHECKING:
    from geofrac.fracture.faces import Faces
    from geofrac.solvers import Vector

__all__ = ["END_REASONS", "MODES", "ContactUnsettled", "EventLoop"]

#: Why an event loop ends ("contact": the crack faces' states did not settle).
END_REASONS = (
    "max_events",
    "energy_drop",
    "no_tensile_edge",
    "separated",
    "singular",
    "contact",
)

#: Event modes (``events.csv`` column ``mode``): an edge cracks in tension (2.20) or in
#: shear (Mohr-Coulomb), a bonded joint starts to slip, or the cohesive faces of a crack
#: drop to their next tooth (fracture energy, docs/cracking.md "Fracture energy").
MODES = ("tension", "shear", "slip", "soften")


class ContactUnsettled(Exception):
    """The crack faces' states still changed after ``contact_iterations`` iterations."""


@dataclass
class _Start:
    """The loop's state at the start of an event (what a checkpoint restarts from)."""

    event: int
    u_prev: np.ndarray
    fragment_nodes: np.ndarray
    pinned_dofs: np.ndarray
    pinned_nodes: np.ndarray
    face_hit: tuple[int, float] | None
    extra: dict[str, JsonValue]
    timing: dict[str, JsonValue]
    #: the criterion's own state (``EventCriterion.snapshot``).
    criterion: dict[str, JsonValue]
    #: crack-face contact (:meth:`~geofrac.fracture.faces.Faces.snapshot`), or None.
    contact: tuple[dict[str, JsonValue], dict[str, np.ndarray]] | None = None


class EventLoop:
    """Runs events on the parts until an end condition.

    Args:
        ctx: the shared set-up data.
        units, criterion, strategy, assembler, output: the parts.
        sites: the pre-cracked sites.
        timing: the phases and solver counts (shared with ``strategy``).
        control: checkpoints, signal stop and resume data, or None.
        contact: the crack faces' pairs (contact, cohesive faces), or None.
    """

    def __init__(
        self,
        ctx: CrackContext,
        units: Units,
        criterion: EventCriterion,
        strategy: SolverStrategy,
        assembler: Assembler,
        output: OutputWriter,
        sites: Sites,
        timing: Timing,
        control: RunControl | None,
        contact: Faces | None = None,
    ) -> None:
        self.ctx, self.units, self.criterion = ctx, units, criterion
        self.contact = contact
        #: how each edge cracked: 0 not (or before loading), 1 + index in MODES.
        self.modes = np.zeros(0, dtype=np.int8)
        # unit tangents and normals of the edges (shear events), computed once
        self._frames: tuple[np.ndarray, np.ndarray] | None = None
        self.strategy, self.assembler, self.output = strategy, assembler, output
        self.sites, self.timing, self.control = sites, timing, control
        #: the rows of the event log, set when the loop ends.
        self.rows: list[Row] = []
        self.gather: Gather | None = None

    def run(self, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """Run; put the last state into ``unknown``; return the JSON results (collective)."""
        ctx, cfg, units, control = self.ctx, self.ctx.config, self.units, self.control
        state, timing, strategy, output = units.state, self.timing, self.strategy, self.output
        scales = ctx.scales
        say = ctx.say
        t0 = time.perf_counter()
        state.start(self.sites.precracked)
        contact = self.contact
        if contact is not None:
            contact.start(np.flatnonzero(state.cracked))
        self.modes = np.zeros(len(state.cracked), dtype=np.int8)
        work = dolfinx.fem.Function(unknown.function_space)  # a ghosted vector
        x = work.x.petsc_vec
        self.gather = gather = Gather(x)
        u_unit = np.zeros(ctx.n_global)
        rows: list[Row] = []
        #: the sites cracked by each event, in order (what a checkpoint replays).
        batches: list[list[int]] = []
        end, peak, first_energy = "max_events", 0.0, 0.0
        #: why the run ended as it did, in words (``end_detail`` of the results).
        detail: str | None = None
        face_hit: tuple[int, float] | None = None
        first = 1  # the first event to compute
        done = 0  # events already in the log (a resumed run recomputes those after first)
        resume = control.resume if control is not None else None
        if resume is not None:
            assert control is not None
            control.check_resume()  # the same scene and number of ranks
            rows, batches, u_unit, first, first_energy, face_hit = self._restore(resume)
            done = len(rows)
            peak = max((r["strain_energy"] for r in rows[: first - 1]), default=0.0)
        setup = format_seconds(time.perf_counter() - t0)
        say(
            "cracking: "
            f"{units.state_text(len(self.sites.precracked), len(self.sites.random))}; "
            f"set-up {setup}"
        )
        if resume is not None:
            say(
                f"cracking: resuming after event {done} from {resume.path} (events {first}-"
                f"{done} are recomputed from the factorisation they used)"
            )
        output.open(rows, None if resume is None else float(done))
        started = time.perf_counter()
        error = None
        #: the last solved unit-load state: (strain energy, control displacement, force).
        unit: tuple[float, float, float] | None = None
        if cfg.max_events == 0:
            u_unit, _ = strategy.solve(u_unit, x, gather)
            _, energy_unit, reaction_unit = units.measures(u_unit)
            unit = (energy_unit, *ctx.control.measure(u_unit, reaction_unit))
            if ctx.problem.exact is not None:
                error = units.l2_error(u_unit)
                say(f"cracking: displacement error (2.22) {error:.4e}")
        # the loop's state at the start of the event whose solve factorised last: a
        # checkpoint restarts from there, so that a resumed run repeats the solver's
        # arithmetic (the update and reuse solvers reuse that factorisation)
        ref: _Start | None = None
        try:
            for event in range(first, cfg.max_events + 1):
                replay = event <= done
                start = self._event_start(event, u_unit, face_hit)
                changes: list[tuple[int, int, int]] = []
                try:
                    u_unit, its = strategy.solve(u_unit, x, gather)
                    if contact is not None:
                        u_unit, changes = self._settle(u_unit, x, gather)
                except ContactUnsettled as exc:
                    end = "contact"
                    say(f"cracking: event {event}: {exc}")
                    break
                except RunError as exc:
                    if replay:
                        raise RunError(f"--resume: event {event} failed on replay: {exc}") from None
                    end = "singular"
                    say(f"cracking: event {event}: the system is singular ({exc})")
                    break
                if timing.factorizations > start.timing["factorizations"] or ref is None:  # type: ignore[operator]
                    ref = start
                    # a resumed run factorises this event without a stale reference to
                    # drop: it keeps the reasons and refinements counted by this solve
                    ref.timing["stale"] = dict(timing.stale)  # type: ignore[assignment]
                    ref.timing["refinements"] = timing.refinements
                timing.iterations += its
                t = time.perf_counter()
                unit_s1, energy_unit, reaction_unit = units.measures(u_unit)
                unit = (energy_unit, *ctx.control.measure(u_unit, reaction_unit))
                sigma1 = self.criterion.site_stress(unit_s1)
                first_r = rows[0]["load_factor"] if event > 1 and rows else None
                detail = scales.separated(energy_unit, first_energy if event > 1 else None)
                first_energy = energy_unit if event == 1 else first_energy
                if detail is not None:
                    end = "separated"
                    break
                floor = TENSION_FLOOR * scales.rms_stress(energy_unit)
                edges, r = self.criterion.select(sigma1, floor=floor)
                edges, r, mode = self._other_modes(edges, r, floor)
                t = timing.add("criterion", t)
                if len(edges) == 0:
                    end = "no_tensile_edge"
                    break
                detail = scales.beyond(r, first_r, control_displacement=r * unit[1])
                if detail is not None:
                    end = "separated"
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
                    row = self._row(event, edges, r, its, energy, (unit[1], unit[2]))
                    row["mode"] = mode
                    if contact is not None and contact.softening:
                        row["dissipated_energy"] = 0.0  # set below, after the event
                    if contact is not None and cfg.contact:
                        row |= contact.record(r)
                        row["contact_changes"] = len(changes)
                        pairs = contact.pairs
                        output.contact_changes(
                            event,
                            [(e, a, b, r * pairs.gap[e], r * pairs.slip[e]) for e, a, b in changes],
                        )
                    rows.append(row)
                    batches.append(cracked)
                if mode == "slip":
                    assert contact is not None
                    contact.pairs.unbond(cracked[0])
                    changed = np.zeros(0, dtype=np.int64)
                elif mode == "soften":
                    assert contact is not None
                    strategy.contact_changed(contact.soften(cracked[0]))
                else:
                    self.modes[cracked] = 1 + MODES.index(mode)
                    changed = state.crack_many(cracked)
                    self.criterion.cracked(np.array(cracked, dtype=np.int64))
                    strategy.changed(changed)
                    units.changed(changed)
                    if contact is not None:
                        blocks = contact.cracked(edges, changed, cohesive=mode == "tension")
                        strategy.contact_changed(blocks)
                if not replay and contact is not None and contact.softening:
                    row["dissipated_energy"] = contact.dissipated
                if face_hit is None and ctx.face_nodes is not None:
                    x_hit = units.face_x(edges)
                    if x_hit is not None:
                        face_hit = (event, x_hit)
                peak = max(peak, energy)
                timing.add("update", t)
                if replay:
                    continue
                if event % cfg.output_every == 0 or event == 1:
                    output.frame(event, r * u_unit, self._edge_data(r))
                output.row(row)  # flushed: a killed run keeps every completed event
                if event % max(1, cfg.max_events // 20) == 0:
                    rate = (event - first + 1) / (time.perf_counter() - started)
                    say(
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
                        output.sync()  # the log on disk holds the checkpoint's rows
                        self._checkpoint(control, event, rows, batches, first_energy, ref)
                    if stop:
                        control.interrupt(f"event {event}")
        finally:
            strategy.drop()
            output.close()
        elapsed = time.perf_counter() - started
        if rows:
            # the final pattern; it replaces a frame already written for this event, so
            # each time appears once in the series
            r_last = rows[-1]["load_factor"]
            output.frame(int(rows[-1]["event"]), r_last * u_unit, self._edge_data(r_last))
        self._finish_field(unknown, rows[-1]["load_factor"] * u_unit if rows else u_unit)
        self.rows = rows
        output.finish(rows, self.modes, self._slipping())
        self.destroy()
        results = self._results(rows, end, elapsed, face_hit, len(rows) - first + 1)
        if detail is not None:
            results["end_detail"] = detail
        if unit is not None:
            results["unit_load"] = self._unit_load(*unit)
        if resume is not None:
            results["resumed_after_event"] = done
        if error is not None:
            results["displacement_error_l2"] = error
        say(
            f"cracking: {len(rows)} events in {format_seconds(elapsed)} "
            f"({results['events_per_s']:.2f} events/s), end: {end}"
            + ("" if detail is None else f" ({detail})")
        )
        return results

    def _row(
        self,
        event: int,
        edges: np.ndarray,
        r: float,
        its: int,
        energy: float,
        control: tuple[float, float],
    ) -> Row:
        """The event log's row of an event that cracked ``edges`` (the first is reported).

        ``control``: the unit solution's control displacement and force
        (:meth:`~geofrac.fracture.control.Control.measure`); the row holds r times them.
        """
        gm, state = self.ctx.gm, self.units.state
        a, b = state.mesh.edges[edges[0]]
        mid = self.units.site_point(int(edges[0]))
        return {
            "event": event,
            "edge": int(edges[0]),
            "node_a": int(gm.input_ids[a]),
            "node_b": int(gm.input_ids[b]),
            "x": float(mid[0]),
            "y": float(mid[1]),
            "r": r,
            "load_factor": r,
            "control_displacement": r * control[0],
            "reaction": r * control[1],
            "strain_energy": energy,
            "edges_cracked": len(edges),
            "iterations": its,
        }

    def _settle(
        self, u: np.ndarray, x: Vector, gather: Gather
    ) -> tuple[np.ndarray, list[tuple[int, int, int]]]:
        """Active-set iteration on the crack faces from the solution u (collective).

        Every pair whose state the solution violates changes at once. A pair that would
        return to a state it left earlier in the event cycles (no set of states
        satisfies every pair's conditions, which penalty friction without load steps
        allows): it is held in the state it violated least (counted, with the largest
        violation, in the results), also in later events until a cell beside it changes
        or the field violates its held state by more than twice as much. So each pair
        changes at most three times per event. Returns the settled solution and every
        state change (edge, old, new) made.

        Raises:
            ContactUnsettled: states still change after ``contact_iterations`` solves.
            RunError: a solve failed.
        """
        contact, cfg = self.contact, self.ctx.config
        assert contact is not None
        made: list[tuple[int, int, int]] = []
        history: dict[int, dict[int, tuple[float, float]]] = {}
        pairs = contact.pairs
        for it in range(cfg.contact_iterations + 1):
            changes, blocks = contact.update(u)
            if not changes:
                return u, made
            cycling = []
            for e, old, new in changes:
                left = history.setdefault(e, {})
                left[old] = (float(pairs.violation[e]), float(pairs.sign[e]))
                if new in left:
                    cycling.append(e)
            made += changes
            if it == cfg.contact_iterations:
                break
            if cycling:
                entered = {e: new for e, _, new in changes}
                contact.freeze_least_violated({e: history[e] for e in cycling})
                blocks += contact.resync(cycling)
                made += [
                    (e, entered[e], int(pairs.state[e]))
                    for e in cycling
                    if pairs.state[e] != entered[e]
                ]
            self.strategy.contact_changed(blocks)
            u, _ = self.strategy.solve(u, x, self.gather or gather)
            contact.iterations += 1
        raise ContactUnsettled(
            f"the crack faces' contact states did not settle in {cfg.contact_iterations} "
            f"iterations ({len(changes)} pairs still changed state, e.g. edge "
            f"{changes[0][0]}); raise cracking.contact_iterations or contact_penalty"
        )

    def _other_modes(
        self, edges: np.ndarray, r: float, floor: float
    ) -> tuple[np.ndarray, float, str]:
        """The event of least r over tension (given), shear, joint slip and softening.

        A shear, slip or softening drive counts only above ``floor`` (the stress floor
        of the tension criterion). Ties within :data:`~geofrac.fracture.criterion.TIE_TOLERANCE`
        keep the earlier mode of :data:`MODES`, then the edge that comes first by
        position (:func:`~geofrac.fracture.criterion.tie_order`).
        """
        cfg, state = self.ctx.config, self.units.state
        mode = "tension"
        if cfg.shear_cohesion is not None:
            sigma = edge_means(state.mesh, self.units.midpoint_stress)  # type: ignore[attr-defined]
            cand = np.flatnonzero(~state.cracked & state.crackable)
            if self._frames is None:
                self._frames = edge_frames(state.mesh)
            t, n = self._frames
            sn, tau = edge_tractions(sigma[cand], t[cand], n[cand])
            r_s = shear_factors(sn, tau, cfg.shear_cohesion, cfg.shear_friction_angle, floor=floor)
            e, rs = least(cand, r_s, self.criterion.points)
            if rs < r * (1.0 - TIE_TOLERANCE):
                edges, r, mode = np.array([e]), rs, "shear"
        if self.contact is not None:
            pairs, r_j = self.contact.pairs.slip_factors(floor=floor)
            e, rj = least(pairs, r_j, self.criterion.points)
            if rj < r * (1.0 - TIE_TOLERANCE):
                edges, r, mode = np.array([e]), rj, "slip"
        if self.contact is not None and self.contact.softening:
            pairs, r_c = self.contact.pairs.soften_factors(floor=floor)
            e, rc = least(pairs, r_c, self.criterion.points)
            if rc < r * (1.0 - TIE_TOLERANCE):
                edges, r, mode = np.array([e]), rc, "soften"
        return edges, r, mode

    def _edge_data(self, r: float) -> dict[str, np.ndarray]:
        """Per-edge fields of the crack series beside ``crack``: mode, contact at load r."""
        out = {"mode": self.modes.astype(float)}
        if self.contact is not None and self.ctx.config.contact:
            out |= self.contact.frame(r)
        return out

    def _slipping(self) -> np.ndarray:
        """Edges whose faces slip in the last state, shape=(k,)."""
        if self.contact is None or not self.ctx.config.contact:
            return np.zeros(0, dtype=np.int64)
        pairs = self.contact.pairs
        act = pairs.active()
        return act[pairs.state[act] == SLIP]

    def _finish_field(self, unknown: dolfinx.fem.Function, u: np.ndarray) -> None:
        """Put the last event's state into the problem's displacement (results.xdmf)."""
        ctx = self.ctx
        v = unknown.x.petsc_vec
        v.setArray(u[ctx.row0 : ctx.row0 + ctx.n_local])
        unknown.x.scatter_forward()
        ctx.problem.to_field()

    # -- checkpoints -----------------------------------------------------------------
    def _event_start(
        self, event: int, u_prev: np.ndarray, face_hit: tuple[int, float] | None
    ) -> _Start:
        """What a checkpoint needs to restart at ``event``: the state before its solve.

        ``u_prev`` is kept by reference (the loop replaces, never changes, the array).
        """
        t, held = self.timing, self.assembler
        return _Start(
            event=event,
            u_prev=u_prev,
            fragment_nodes=held.fragment_nodes,
            pinned_dofs=held.pinned_dofs,
            pinned_nodes=held.pinned_nodes,
            face_hit=face_hit,
            extra=self.units.checkpoint_extra(),
            criterion=self.criterion.snapshot(),
            contact=None if self.contact is None else self.contact.snapshot(),
            timing={
                "factorizations": t.factorizations,
                "iterations": t.iterations,
                "refinements": t.refinements,
                "stale": dict(t.stale),  # type: ignore[dict-item]
            },
        )

    def _checkpoint(
        self,
        control: RunControl,
        event: int,
        rows: list[Row],
        batches: list[list[int]],
        first_energy: float,
        ref: _Start,
    ) -> None:
        """Write checkpoint ``event`` (collective).

        It holds the event log and each event's cracked sites up to ``event`` (JSON),
        and the state at the start of event ``ref.event``, whose solve factorised last:
        the unit solution before it, the held and pinned DOFs and, with contact, the face
        pairs' states (arrays alike on every rank, written once). A resumed run recomputes
        the events from there with the same factorisation, so it repeats the interrupted
        run's arithmetic.
        """
        data: dict[str, JsonValue] = {
            "rows": rows,  # type: ignore[dict-item]
            "batches": batches,  # type: ignore[dict-item]
            "first_energy": first_energy,
            "replay_from": ref.event,
            "face_hit": None if ref.face_hit is None else list(ref.face_hit),
            "timing": ref.timing,
            "extra": ref.extra,
            "criterion": ref.criterion,
        }
        arrays = {
            "u_prev": ref.u_prev,
            "fragment_nodes": ref.fragment_nodes,
            "pinned_dofs": ref.pinned_dofs,
            "pinned_nodes": ref.pinned_nodes,
        }
        if ref.contact is not None:
            data["contact"] = ref.contact[0]
            arrays |= ref.contact[1]
        save_checkpoint(control, event, data, arrays)

    def _restore(
        self, ck: Checkpoint
    ) -> tuple[list[Row], list[list[int]], np.ndarray, int, float, tuple[int, float] | None]:
        """Bring the parts to the start of checkpoint ``ck``'s replay event.

        The crack state is rebuilt by cracking the sites of each event before it again,
        in event order (the fits are a function of the cracked sites); the held and
        pinned DOFs and the unit solution before that event (whose values held DOFs
        keep) are read back. Returns (rows, batches, u_unit, replay_from, first_energy,
        face_hit).
        """
        data, arrays = read_checkpoint(ck, self.ctx.n_global)
        replay_from = int(data["replay_from"])  # type: ignore[arg-type]
        batches: list[list[int]] = data["batches"]  # type: ignore[assignment]
        logged: list[Row] = data["rows"]  # type: ignore[assignment]
        for batch, row in zip(batches[: replay_from - 1], logged, strict=False):
            if row.get("mode") == "soften":  # a tooth of an edge cracked before
                continue
            self.units.state.crack_many([int(e) for e in batch])
        held = self.assembler
        held.fragment_nodes = arrays["fragment_nodes"].astype(np.int64)
        held.pinned_dofs = arrays["pinned_dofs"].astype(np.int64)
        held.pinned_nodes = arrays["pinned_nodes"].astype(np.int64)
        self.strategy.reset()
        self.units.reset()
        t: dict[str, JsonValue] = data["timing"]  # type: ignore[assignment]
        self.timing.factorizations = int(t["factorizations"])  # type: ignore[arg-type]
        self.timing.iterations = int(t["iterations"])  # type: ignore[arg-type]
        self.timing.refinements = int(t["refinements"])  # type: ignore[arg-type]
        self.timing.stale = {k: int(v) for k, v in t["stale"].items()}  # type: ignore[union-attr, arg-type]
        self.units.restore_extra(data.get("extra", {}))  # type: ignore[arg-type]
        self.criterion.restore(data.get("criterion", {}))  # type: ignore[arg-type]
        if self.contact is not None:
            if "contact" not in data:
                raise RunError(f"--resume: {ck.path} was written without crack-face contact")
            rows: list[Row] = data["rows"]  # type: ignore[assignment]
            self.contact.restore(
                data["contact"],  # type: ignore[arg-type]
                arrays,
                [float(r.get("min_gap", 0.0)) for r in rows],
            )
        hit = data["face_hit"]
        face_hit = None if hit is None else (int(hit[0]), float(hit[1]))  # type: ignore[index, arg-type]
        return (
            data["rows"],  # type: ignore[return-value]
            batches,
            np.array(arrays["u_prev"], dtype=float),
            replay_from,
            float(data["first_energy"]),  # type: ignore[arg-type]
            face_hit,
        )

    # -- results ---------------------------------------------------------------------
    def _results(
        self,
        rows: list[Row],
        end: str,
        elapsed: float,
        face_hit: tuple[int, float] | None,
        done: int,
    ) -> dict[str, JsonValue]:
        """The loop's JSON results; ``done``: events this run computed."""
        ctx, state, t, held = self.ctx, self.units.state, self.timing, self.assembler
        cfg = ctx.config
        n_pre = len(self.sites.precracked)
        out: dict[str, JsonValue] = {
            "events": len(rows),
            "end_reason": end,
            "cracked_edges": int(state.cracked.sum()),
            "new_cracked_edges": int(state.cracked.sum()) - n_pre,
            "precracked_edges": n_pre,
            "mls_cells": len(state.fits),
            "void_cells": len(state.void_cells()),
            "fragment_nodes": len(held.fragment_nodes),
            "pinned_dofs": len(held.pinned_dofs),
            "edges": len(state.mesh.edges),
            "dofs": ctx.n_global,
            "events_per_s": done / elapsed if elapsed > 0 else float("nan"),
            "phase_s": {k: ctx.comm.allreduce(v, op=MPI.MAX) for k, v in t.seconds.items()},
            "factorizations": t.factorizations,
            "refactor_reasons": dict(sorted(t.stale.items())),
            "refinement_solves": t.refinements,
            "cg_iterations": t.iterations,
            "solver": cfg.solver,
        }
        if rows:
            peak = max(rows, key=lambda r: r["reaction"])
            out |= {
                "peak_reaction": peak["reaction"],
                "peak_event": peak["event"],
                "final_strain_energy": rows[-1]["strain_energy"],
            }
        if cfg.face is not None:
            x = None if face_hit is None else face_hit[1] - cfg.face_origin
            out["crack_face"] = {
                "group": cfg.face,
                "event": None if face_hit is None else face_hit[0],
                "x_from_origin": x,
            }
            if cfg.face == "top":
                out["crack_top_x_mm"] = x
        out["control"] = ctx.control.describe(ctx.gm.input_ids, ctx.gm.coords)  # type: ignore[assignment]
        self.units.results(out, n_pre, len(self.sites.random))
        modes = MODES if self.contact is not None and self.contact.softening else MODES[:3]
        out["events_by_mode"] = {m: sum(1 for r in rows if r.get("mode") == m) for m in modes}
        if self.contact is not None and cfg.contact:
            control = max((abs(r["control_displacement"]) for r in rows), default=0.0)
            out["contact"] = self.contact.summary(len(rows), control)  # type: ignore[assignment]
        if self.contact is not None and self.contact.softening:
            out["dissipated_energy"] = self.contact.dissipated
        return out

    def _unit_load(self, energy: float, delta: float, reaction: float) -> dict[str, JsonValue]:
        """The last solved unit-load state (the results' ``unit_load``).

        What the body carries at the end under the scene's loads and prescribed
        displacements as given (before any scaling by r): also when the run ends before
        its first event (a crack pulled open, a specimen in which no edge reaches
        tension). ``delta``, ``reaction``: the control displacement and force
        (:meth:`~geofrac.fracture.control.Control.measure`); the stiffness is their ratio.
        """
        out: dict[str, JsonValue] = {
            "control_displacement": delta,
            "reaction": reaction,
            "strain_energy": energy,
            "stiffness": reaction / delta if delta != 0.0 else None,  # a held control point
        }
        if self.contact is not None and self.ctx.config.contact:
            pairs = self.contact.pairs
            act = pairs.active()
            out["min_gap"] = min(float(pairs.gap[act].min()), 0.0) if len(act) else 0.0
        return out

    def destroy(self) -> None:
        """Free the solvers, the load vector and the gather."""
        self.strategy.destroy()
        self.assembler.destroy()
        if self.gather is not None:
            self.gather.destroy()
        self.gather = None
