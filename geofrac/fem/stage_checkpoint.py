"""Checkpoints of a staged elastic run: save after a completed stage, resume at the next.

A checkpoint after step k (0: the initial step) holds what the next stage needs and what
the run has reported so far (:class:`~geofrac.io.checkpoint.RunControl`, kind ``fem``):

- per rank (``rank-<r>.npz``, this rank's local arrays with ghosts): the displacement
  ``u``; the staged fields ``alive``, ``lam``, ``mu``, ``rho``, ``sigma0`` (zeroed in
  installed cells) and ``u_ref`` (the per-cell installation displacement); the owned
  rows of the pending ``release``; the arrays of every XDMF frame written so far;
- ``meta.json`` data: ``loop = "stages"``, the last completed step ``done``, the share of
  the pending release applied so far, the summary rows of the steps and the frames'
  names and field names.

The loads and supports that act (``from``/``until``) are those of step ``done``: they
follow from the scene, so they are not stored. The arrays are this rank's part of a
mesh distributed the same way, so a checkpoint
resumes on the number of ranks that wrote it only (as the crack loops'). The initial
check is recomputed on resume (it depends on the initial fields only).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.io.checkpoint import Checkpoint, RunControl

__all__ = ["Frame", "Staged", "restore", "save"]

_LOOP = "stages"


@dataclass
class Frame:
    """One time step of ``results.xdmf``: a step's name and the fields written."""

    index: int
    name: str
    functions: list[dolfinx.fem.Function] = field(default_factory=list)


class Staged(Protocol):
    """What a checkpoint needs of a staged run (:class:`geofrac.fem.stages.StagedRun`)."""

    comm: MPI.Comm
    share: float

    def state(self) -> dict[str, np.ndarray]:
        """This rank's arrays of the state (local, with ghosts; the release's owned rows)."""
        ...

    def set_state(self, arrays: dict[str, np.ndarray], share: float, *, step: int = 0) -> None:
        """Put a saved state after ``step`` back and factorise its operator (collective)."""
        ...

    def frame(self, index: int, name: str) -> Frame:
        """The fields of the current state for ``results.xdmf``."""
        ...


def save(
    run: Staged,
    control: RunControl,
    done: int,
    *,
    entries: list[dict[str, Any]],
    frames: list[Frame],
) -> None:
    """Write the checkpoint after step ``done`` (collective).

    Args:
        run: the staged run, its state after step ``done``.
        control: the run's control (with a directory).
        done: the last completed step (0: the initial step).
        entries: the summary rows of steps 0..done.
        frames: the XDMF frames written so far.
    """
    local = run.state()
    for i, frame in enumerate(frames):
        for j, f in enumerate(frame.functions):
            local[f"frame{i}_{j}"] = f.x.array
    data = {
        "loop": _LOOP,
        "done": done,
        "share": run.share,
        "entries": entries,
        "frames": [[fr.index, fr.name, [f.name for f in fr.functions]] for fr in frames],
    }
    control.save(done, data, local=local)


def restore(run: Staged, ck: Checkpoint) -> tuple[int, list[dict[str, Any]], list[Frame]]:
    """Put the state of ``ck`` into ``run`` (collective; after the initial check).

    Returns:
        the last completed step, the summary rows so far and the frames written so far.

    Raises:
        RunError: collectively, for a checkpoint of another loop or another distribution.
    """
    data = ck.data
    comm = run.comm
    arrays = ck.local(comm.rank)
    current = run.state()
    error = None
    if data.get("loop") != _LOOP:
        error = f"--resume: the checkpoint {ck.path} is not of a staged run"
    elif any(
        name not in arrays or arrays[name].shape != value.shape for name, value in current.items()
    ):
        error = f"--resume: the checkpoint {ck.path} is of another mesh or distribution"
    errors = comm.allgather(error)
    if any(errors):
        raise RunError(next(e for e in errors if e))
    run.set_state(arrays, float(data["share"]), step=int(data["done"]))
    frames = []
    for i, (index, name, names) in enumerate(data["frames"]):
        frame = run.frame(int(index), str(name))
        if [f.name for f in frame.functions] != list(names):
            raise RunError(f"--resume: the checkpoint {ck.path} has other output fields")
        for j, f in enumerate(frame.functions):
            f.x.array[:] = arrays[f"frame{i}_{j}"]
        frames.append(frame)
    return int(data["done"]), list(data["entries"]), frames
