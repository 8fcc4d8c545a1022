"""Checkpoints of a cracking run with ``[[stages]]`` (docs/cracking.md, "Checkpoints and resume").

A staged run's checkpoint is the event loop's (:mod:`~geofrac.fracture.replay`: the log,
each event's sites and the state at the start of the replay event j) with the stages'
state at that start (:attr:`~geofrac.fracture.replay.EventStart.loop`, :func:`snapshot`):

- JSON: the scene's stage layout (each stage's name, removed groups and relaxation); the
  running stage, its share s and the least λ of the last choice; the share a of the
  pending release applied before it; how many events had cracked when each stage began
  (``starts``); the finished stages' ``summary.json`` entries; the running stage's events
  and first event; the sites cracked at λ = 0 and those over their strength at the
  start; with contact, the active-set steps judged at the stage's end and the states
  they left;
- arrays, shape=(n_global,): the pending release P, the constant load's solution u_c
  before event j (its solve's guess) and the state u_e where each finished stage ended.

The rest is derived (:func:`restore`): the crack state by cracking each event's sites
again with each stage's removal between them where it happened (the void cells, their σ0
and weight gone, ``alive`` and the MLS fits beside the new wall follow from both and from
their order); each finished stage's ``results.xdmf`` step from its u_e, with ``alive`` as
it was then; the constant right-hand side F0 − (1 − a) P from the restored state. The
resumed run then computes events j … k again, as the unstaged loops do.
"""

from __future__ import annotations

from typing import Protocol

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

__all__ = ["KIND", "StagedLoop", "Stepped", "layout", "refuse_support", "restore", "snapshot"]

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


def refuse_support(stages: tuple[Stage, ...]) -> None:
    """Refuse a resume of stages that install support (``add``).

    Raises:
        RunError: naming the stages: checkpoints do not keep the installations yet.
    """
    added = [st.name for st in stages if st.add]
    if added:
        raise RunError(
            f"--resume: stage(s) {', '.join(added)} install support (add), which "
            "checkpoints do not keep yet; run the scene again without --resume"
        )


def layout(stages: tuple[Stage, ...]) -> list[JsonValue]:
    """Each stage's [name, removed groups, relaxation (None: what remains)]."""
    return [[s.name, list(s.remove), s.relaxation] for s in stages]


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
    stage = int(data["stage"])
    starts = [int(i) for i in data["starts"]]
    if not 0 <= stage < len(ours) or len(starts) != stage + 1:
        raise RunError(f"--resume: the checkpoint {ck.path} has no valid stage state")
    return data, stage


def restore(loop: StagedLoop, ck: Checkpoint) -> Restored:
    """Bring the parts and the stages to the start of ``ck``'s replay event (collective).

    Raises:
        RunError: on every rank, for a checkpoint of a run without stages, of another
            stage layout or of another mesh.
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
        """The stages that began with ``done`` events cracked: their frames, removals."""
        for s in range(stage + 1):
            if starts[s] != done:
                continue
            if s > 0 and xdmf:  # the step of the stage before, with alive as it was
                loop.frames.append(loop._frame(s, loop.stages[s - 1].name, ends[s - 1]))
            if loop.stages[s].remove:
                loop._remove(loop.stages[s])

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
