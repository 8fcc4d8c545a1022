"""The event loop's checkpoints and their replay (docs/cracking.md, "Checkpoints and resume").

A checkpoint holds the event log and each event's cracked sites up to event k (JSON), and
the loop's state at the start of event j ≤ k, the last event whose solve factorised
(:class:`EventStart`): the unit solution before it, the held and pinned DOFs and, with
crack faces, the face pairs' states. A resumed run rebuilds the crack state from the
sites (:meth:`Replay.restore`) and recomputes events j … k with the same factorisation,
so it repeats the interrupted run's arithmetic.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.assembly import Assembler
from geofrac.fracture.context import JsonValue
from geofrac.fracture.event_criterion import EventCriterion
from geofrac.fracture.faces import Faces
from geofrac.fracture.linear import SolverStrategy, Timing
from geofrac.fracture.output import Row
from geofrac.fracture.units import Units
from geofrac.io.checkpoint import Checkpoint, RunControl

__all__ = ["LOOP_ARRAYS", "EventStart", "Replay", "Restored", "read_checkpoint"]


@dataclass
class EventStart:
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
    #: the loop's own state, (JSON data, arrays of shape=(n_global,)), or None: a
    #: staged run's stage and release (:mod:`~geofrac.fracture.staged_resume`).
    loop: tuple[dict[str, JsonValue], dict[str, np.ndarray]] | None = None


@dataclass
class Restored:
    """What a resumed loop continues from.

    Attributes:
        rows: the event log up to the checkpoint's event k.
        batches: the sites each of those events cracked, in order.
        u_unit: the unit solution before event ``replay_from``, shape=(n_global,).
        replay_from: j, the first event to compute again.
        first_energy: the first event's unit strain energy.
        face_hit: (event, x) where the crack first reached the ``face`` group, or None.
    """

    rows: list[Row]
    batches: list[list[int]]
    u_unit: np.ndarray
    replay_from: int
    first_energy: float
    face_hit: tuple[int, float] | None


#: The prefix of the loop's own arrays (:attr:`EventStart.loop`) in ``shared.npz``.
LOOP_ARRAYS = "loop_"


def read_checkpoint(
    ck: Checkpoint, n_global: int
) -> tuple[dict[str, JsonValue], dict[str, np.ndarray]]:
    """(JSON data, shared arrays) of a checkpoint of the event loop, checked against the mesh."""
    data, arrays = ck.data, ck.shared()
    u_prev = arrays.get("u_prev")
    replay_from = data.get("replay_from", 0)
    if u_prev is None or len(u_prev) != n_global or int(replay_from) < 1:  # type: ignore[arg-type]
        raise RunError(f"--resume: the checkpoint {ck.path} does not match this mesh")
    return data, arrays


class Replay:
    """Takes the parts' state at an event's start, writes checkpoints, restores them.

    Args:
        units, criterion, strategy, assembler: the parts whose state a checkpoint keeps.
        timing: the phases and solver counts.
        contact: the crack faces, or None.
    """

    def __init__(
        self,
        units: Units,
        criterion: EventCriterion,
        strategy: SolverStrategy,
        *,
        assembler: Assembler,
        timing: Timing,
        contact: Faces | None,
    ) -> None:
        self.units, self.criterion, self.strategy = units, criterion, strategy
        self.assembler, self.timing, self.contact = assembler, timing, contact

    def start(
        self, event: int, u_prev: np.ndarray, face_hit: tuple[int, float] | None
    ) -> EventStart:
        """What a checkpoint needs to restart at ``event``: the state before its solve.

        ``u_prev`` is kept by reference (the loop replaces, never changes, the array).
        """
        t, held = self.timing, self.assembler
        return EventStart(
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

    def save(
        self,
        control: RunControl,
        event: int,
        *,
        rows: list[Row],
        batches: list[list[int]],
        first_energy: float,
        ref: EventStart,
    ) -> None:
        """Write checkpoint ``event`` restarting at ``ref`` (collective).

        The arrays (alike on every rank) are written once.
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
        if ref.loop is not None:
            data["loop"] = ref.loop[0]
            arrays |= {LOOP_ARRAYS + name: a for name, a in ref.loop[1].items()}
        control.save(event, data, shared=arrays)

    def restore(
        self, ck: Checkpoint, n_global: int, *, between: Callable[[int], None] | None = None
    ) -> Restored:
        """Bring the parts to the start of checkpoint ``ck``'s replay event.

        The crack state is rebuilt by cracking the sites of each event before it again,
        in event order (the fits are a function of the cracked sites); the held and
        pinned DOFs and the unit solution before that event (whose values held DOFs
        keep) are read back. ``between(i)`` is called with i events' sites cracked, for
        i = 0 … j − 1: a staged run removes its stages' cells there, in their order (a
        checkpoint of a staged run is refused without it).
        """
        data, arrays = read_checkpoint(ck, n_global)
        if data.get("loop") is not None and between is None:  # (a staged run's removals)
            raise RunError(
                f"--resume: the checkpoint {ck.path} was written by a cracking run with "
                "[[stages]]; this scene has none (run without --resume to start afresh)"
            )
        replay_from = int(data["replay_from"])  # type: ignore[arg-type]
        batches: list[list[int]] = data["batches"]  # type: ignore[assignment]
        logged: list[Row] = data["rows"]  # type: ignore[assignment]
        for i, (batch, row) in enumerate(zip(batches[: replay_from - 1], logged, strict=False)):
            if between is not None:
                between(i)
            if row.get("mode") == "soften":  # a tooth of an edge cracked before
                continue
            self.units.state.crack_many([int(e) for e in batch])
        if between is not None:
            between(replay_from - 1)
        held = self.assembler
        held.fragment_nodes = arrays["fragment_nodes"].astype(np.int64)
        held.pinned_dofs = arrays["pinned_dofs"].astype(np.int64)
        held.pinned_nodes = arrays["pinned_nodes"].astype(np.int64)
        self.strategy.reset()
        self.units.reset()
        self._restore_timing(data["timing"])  # type: ignore[arg-type]
        self.units.restore_extra(data.get("extra", {}))  # type: ignore[arg-type]
        self.criterion.restore(data.get("criterion", {}))  # type: ignore[arg-type]
        if self.contact is not None:
            if "contact" not in data:
                raise RunError(f"--resume: {ck.path} was written without crack-face contact")
            self.contact.restore(
                data["contact"],  # type: ignore[arg-type]
                arrays,
                [float(r.get("min_gap", 0.0)) for r in logged],
            )
        hit = data["face_hit"]
        return Restored(
            rows=logged,
            batches=batches,
            u_unit=np.array(arrays["u_prev"], dtype=float),
            replay_from=replay_from,
            first_energy=float(data["first_energy"]),  # type: ignore[arg-type]
            face_hit=None if hit is None else (int(hit[0]), float(hit[1])),  # type: ignore[index, arg-type]
        )

    def _restore_timing(self, t: dict[str, JsonValue]) -> None:
        """The solver counts as they were at the replay event's start."""
        self.timing.factorizations = int(t["factorizations"])  # type: ignore[arg-type]
        self.timing.iterations = int(t["iterations"])  # type: ignore[arg-type]
        self.timing.refinements = int(t["refinements"])  # type: ignore[arg-type]
        self.timing.stale = {k: int(v) for k, v in t["stale"].items()}  # type: ignore[union-attr, arg-type]
