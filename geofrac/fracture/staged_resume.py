"""Checkpoints of a cracking run with ``[[stages]]`` (docs/cracking.md, "Checkpoints and resume").

A staged run's checkpoint is the event loop's (:mod:`~geofrac.fracture.replay`: the log,
each event's sites and the state at the start of the replay event j) with the stages'
state at that start (:attr:`~geofrac.fracture.replay.EventStart.loop`, :func:`snapshot`):

- JSON: the scene's stage layout (each stage's name, removed groups and relaxation) and
  its installations (each stage's added groups and their material, :func:`supports`); the
  running stage, its share s and the least λ of the last choice; the share a of the
  pending release applied before it; how many events had cracked when each stage began
  (``starts``); the finished stages' ``summary.json`` entries; the running stage's events
  and first event; the sites cracked at λ = 0 and those over their strength at the
  start; with contact, the active-set steps judged at the stage's end and the states
  they left;
- arrays, shape=(n_global,): the pending release P, the constant load's solution u_c
  before event j (its solve's guess) and the state u_e where each finished stage ended.

The rest is derived (:func:`restore`): the crack state by cracking each event's sites
again with each stage's removal and installation between them where they happened (the
void cells, their σ0 and weight gone, ``alive`` and the MLS fits beside the new wall
follow from both and from their order); an installation is made again at u_I = the
stored u_e of the stage before it (:mod:`~geofrac.fracture.support`: the installed cells
live, their material's element matrices and D, their σ0 dropped from I(σ0), their sites'
strengths and the chooser's scale, the support's reference u_I, the refits at cut nodes,
the output's material fields and reference); each finished stage's ``results.xdmf`` step
from its u_e, with ``alive`` and the installations as they were then; the constant
right-hand side F0 + F_I − (1 − a) P and the support's site stresses −D ε(u_I) from the
restored state. The resumed run then computes events j … k again, as the unstaged loops
do. A checkpoint whose installations differ from the scene's (``add``, ``material``) is
refused naming the key.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any, Protocol

import numpy as np

from geofrac.errors import RunError
from geofrac.fem.solution import Solution
from geofrac.fem.stage_checkpoint import Frame
from geofrac.fracture.constant import ConstantLoad
from geofrac.fracture.context import CrackContext, JsonValue
from geofrac.fracture.equilibrium import Visited
from geofrac.fracture.loop import LoopParts
from geofrac.fracture.replay import LOOP_ARRAYS, Restored, read_checkpoint
from geofrac.io.checkpoint import Checkpoint
from geofrac.model.scene import Stage

__all__ = ["KIND", "StagedLoop", "Stepped", "layout", "restore", "snapshot", "supports"]

#: The ``kind`` of a staged run's own checkpoint data.
KIND = "stages"


class Stepped(Protocol):
    """The step whose switched loads act (:class:`~geofrac.fracture.staged.StagedInitialStress`)."""

    step: int


class StagedLoop(Protocol):
    """What a checkpoint reads and sets of :class:`~geofrac.fracture.staged.StagedEventLoop`."""

    ctx: CrackContext
    parts: LoopParts
    load: ConstantLoad
    staged_insitu: Stepped
    solution: Solution
    stages: tuple[Stage, ...]
    k: int
    begun: bool
    share: float
    beyond: float
    applied: float
    release: np.ndarray
    u_const: np.ndarray
    u_end: np.ndarray
    entries: list[dict[str, JsonValue]]
    frames: list[Frame]
    over_cracked: int
    over_at_start: int | None
    _starts: list[int]
    _ends: list[np.ndarray]
    _events: list[int]
    _first: dict[str, JsonValue] | None
    _share_settles: int
    _share_history: Visited
    _rows: slice

    def _frame(self, index: int, name: str, u: np.ndarray) -> Frame:
        """The fields of the state u for ``results.xdmf``."""
        ...

    def _remove(self, stage: Stage) -> tuple[np.ndarray, np.ndarray]:
        """Make the stage's cells void (collective)."""
        ...

    def _install(self, stage: Stage, index: int) -> None:
        """Install the stage's groups at u_I = ``u_end`` (collective)."""
        ...


def layout(stages: tuple[Stage, ...]) -> list[JsonValue]:
    """Each stage's [name, removed groups, relaxation (None: what remains)]."""
    return [[s.name, list(s.remove), s.relaxation] for s in stages]


def supports(stages: tuple[Stage, ...]) -> list[Any]:
    """Each stage's [added groups, their material's fields (None: the stage adds none)].

    As JSON reads it back (lists, not tuples).
    """
    out = [
        [list(s.add), dataclasses.asdict(s.material) if s.add and s.material else None]
        for s in stages
    ]
    back: list[Any] = json.loads(json.dumps(out))
    return back


def _check_supports(ck: Checkpoint, saved: Any, stages: tuple[Stage, ...]) -> None:
    """Refuse a checkpoint whose installations are not the scene's, naming the key.

    ``saved``: the checkpoint's :func:`supports` (None: written before they were kept;
    such a checkpoint resumes only stages that add nothing).
    """
    ours = supports(stages)
    theirs = [[[], None] for _ in stages] if saved is None else saved
    if not isinstance(theirs, list) or len(theirs) != len(ours):
        raise RunError(f"--resume: the checkpoint {ck.path} has no valid stage state")
    for i, ((added, then), (adds, now)) in enumerate(zip(theirs, ours, strict=True)):
        if added != adds:
            raise RunError(
                f"--resume: the checkpoint {ck.path} was written with stages[{i}].add = "
                f"{added}; this scene's stages[{i}].add is {adds} (run without --resume "
                "to start afresh)"
            )
        old, new = then or {}, now or {}
        keys = sorted(k for k in {*old, *new} if old.get(k) != new.get(k))
        if keys:
            words = ", ".join(
                f"stages[{i}].material.{k} = {old.get(k)} there, {new.get(k)} here" for k in keys
            )
            raise RunError(
                f"--resume: the checkpoint {ck.path} was written with another support "
                f"material ({words}); run without --resume to start afresh"
            )


def _words(stages: list[JsonValue]) -> str:
    """A stage layout in words, e.g. ``heading (removes heading, 0.4), bench (...)``."""
    out = []
    for stage in stages:
        name, remove, relaxation = stage  # type: ignore[misc]
        share = "all that remains" if relaxation is None else f"{relaxation:g}"
        removes = f"removes {', '.join(remove)}, " if remove else ""
        out.append(f"'{name}' ({removes}{share})")
    return "; ".join(out) or "none"


def snapshot(loop: StagedLoop) -> tuple[dict[str, JsonValue], dict[str, np.ndarray]]:
    """The stages' state at an event's start: (JSON data, arrays of shape=(n_global,)).

    The arrays are kept by reference (the loop replaces, never changes, them).
    """
    history = [
        [int(e), [[int(state), float(v), float(d)] for state, (v, d) in seen.items()]]
        for e, seen in loop._share_history.items()
    ]
    data: dict[str, JsonValue] = {
        "kind": KIND,
        "layout": layout(loop.stages),
        "supports": supports(loop.stages),
        "stage": loop.k,
        "share": loop.share,
        "beyond": loop.beyond if np.isfinite(loop.beyond) else None,
        "applied": loop.applied,
        "starts": list(loop._starts),  # type: ignore[dict-item]
        "entries": list(loop.entries),  # type: ignore[dict-item]
        "events": list(loop._events),  # type: ignore[dict-item]
        "first": loop._first,
        "over_cracked": loop.over_cracked,
        "over_at_start": loop.over_at_start,
        "share_settles": loop._share_settles,
        "share_history": history,  # type: ignore[dict-item]
    }
    arrays = {"release": loop.release, "u_const": loop.u_const}
    arrays |= {f"end{i}": u for i, u in enumerate(loop._ends)}
    return data, arrays


def _checked(loop: StagedLoop, ck: Checkpoint) -> tuple[dict[str, JsonValue], int]:
    """The checkpoint's stage data and its number of finished stages, or a refusal."""
    data = ck.data.get("loop")
    ours = layout(loop.stages)
    if not isinstance(data, dict) or data.get("kind") != KIND:
        raise RunError(
            f"--resume: the checkpoint {ck.path} was written by a cracking run without "
            f"[[stages]]; this scene has {len(ours)} stages (run without --resume to "
            "start afresh)"
        )
    if data["layout"] != ours:
        raise RunError(
            f"--resume: the checkpoint {ck.path} was written with other [[stages]] "
            f"({_words(data['layout'])}); this scene's are {_words(ours)} (run without "
            "--resume to start afresh)"
        )
    _check_supports(ck, data.get("supports"), loop.stages)
    stage = int(data["stage"])
    starts = [int(i) for i in data["starts"]]
    if not 0 <= stage < len(ours) or len(starts) != stage + 1:
        raise RunError(f"--resume: the checkpoint {ck.path} has no valid stage state")
    return data, stage


def restore(loop: StagedLoop, ck: Checkpoint) -> Restored:
    """Bring the parts and the stages to the start of ``ck``'s replay event (collective).

    Raises:
        RunError: on every rank, for a checkpoint of a run without stages, of another
            stage layout, other installations (``add``, their ``material``) or of
            another mesh.
    """
    data, stage = _checked(loop, ck)
    n_global = loop.ctx.n_global
    _, saved = read_checkpoint(ck, n_global)
    arrays = {k[len(LOOP_ARRAYS) :]: v for k, v in saved.items() if k.startswith(LOOP_ARRAYS)}
    names = ["release", "u_const", *(f"end{i}" for i in range(stage))]
    if any(name not in arrays or arrays[name].shape != (n_global,) for name in names):
        raise RunError(f"--resume: the checkpoint {ck.path} does not match this mesh")
    ends = [np.array(arrays[f"end{i}"], dtype=float) for i in range(stage)]
    starts = [int(i) for i in data["starts"]]  # type: ignore[union-attr]
    xdmf = loop.solution.scene.output.xdmf

    def removals(done: int) -> None:
        """The stages that began with ``done`` events cracked: frames, removals, adds."""
        for s in range(stage + 1):
            if starts[s] != done:
                continue
            if s > 0 and xdmf:  # the step of the stage before, with alive as it was
                loop.frames.append(loop._frame(s, loop.stages[s - 1].name, ends[s - 1]))
            if loop.stages[s].remove:
                loop._remove(loop.stages[s])
            if loop.stages[s].add:  # at u_I, where the stage before ended (the solver
                # parts it resets and the pairs it refreshes are restored after the replay)
                loop.u_end = ends[s - 1] if s > 0 else np.zeros(n_global)
                loop._install(loop.stages[s], s + 1)

    back = loop.parts.replay.restore(ck, n_global, between=removals)
    _put(loop, data, ends)
    loop.release = np.array(arrays["release"], dtype=float)
    loop.u_const = np.array(arrays["u_const"], dtype=float)
    loop.load.variable.load.setArray(loop.release[loop._rows])
    loop.ctx.say(
        f"stage {loop.k + 1}/{len(loop.stages)} '{loop.stages[loop.k].name}': resumed at "
        f"event {back.replay_from} ({loop.k} of {len(loop.stages)} stages finished; "
        f"{loop.applied:.4g} of the pending release applied before it)"
    )
    return back


def _put(loop: StagedLoop, data: dict[str, JsonValue], ends: list[np.ndarray]) -> None:
    """The stages' bookkeeping of ``data`` into ``loop`` (the running stage begun)."""
    loop.k, loop.begun = int(data["stage"]), True  # type: ignore[arg-type]
    loop.staged_insitu.step = loop.k + 1  # the running stage's loads
    loop.share, loop.applied = float(data["share"]), float(data["applied"])  # type: ignore[arg-type]
    beyond = data["beyond"]
    loop.beyond = float("inf") if beyond is None else float(beyond)  # type: ignore[arg-type]
    loop._starts = [int(i) for i in data["starts"]]  # type: ignore[union-attr]
    loop._ends = ends
    loop.u_end = ends[-1] if ends else np.zeros(loop.ctx.n_global)
    loop.entries = list(data["entries"])  # type: ignore[arg-type]
    loop._events = [int(e) for e in data["events"]]  # type: ignore[union-attr]
    loop._first = data["first"]  # type: ignore[assignment]
    loop.over_cracked = int(data["over_cracked"])  # type: ignore[arg-type]
    over = data["over_at_start"]
    loop.over_at_start = None if over is None else int(over)  # type: ignore[arg-type]
    loop._share_settles = int(data["share_settles"])  # type: ignore[arg-type]
    loop._share_history = {
        int(e): {int(s): (float(v), float(d)) for s, v, d in seen}  # type: ignore[misc]
        for e, seen in data["share_history"]  # type: ignore[misc, union-attr]
    }
