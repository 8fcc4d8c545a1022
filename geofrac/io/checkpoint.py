"""Checkpoints of long loops, and the per-step question "save? stop?" (collective).

A checkpoint is a directory ``ckpt-<k>`` (k = the last completed event or step, nine
digits) inside the run's checkpoint directory::

    ckpt-000000120/
        meta.json       kind, k, scene sha256, ranks, geofrac version, the loop's own
                        JSON data (event rows, histories); written last
        shared.npz      arrays every rank holds alike (written by rank 0)
        rank-<r>.npz    arrays of rank r (distributed state, e.g. MPM particles)

It is written into ``ckpt-<k>.tmp`` and renamed when every rank has written its part, so
a directory named ``ckpt-<k>`` with a ``meta.json`` is complete; a run killed while
writing leaves only a ``.tmp`` directory, which :func:`latest` ignores and the next save
removes. The newest :data:`KEEP` complete checkpoints are kept.

:class:`RunControl` is what a loop asks after each completed step or event:
``save, stop = control.poll(k)`` is collective (one small allreduce), so every rank
saves and stops at the same k. ``stop`` is true once any rank received SIGTERM/SIGINT
(:mod:`geofrac.interrupt`); the loop then saves and calls :meth:`RunControl.interrupt`.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

import geofrac
from geofrac import interrupt
from geofrac.errors import RunError

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["KEEP", "Checkpoint", "CheckpointPolicy", "RunControl", "latest"]

#: Complete checkpoints kept in the directory (older ones are removed after a save).
KEEP = 2
_PREFIX = "ckpt-"


@dataclass(frozen=True)
class CheckpointPolicy:
    """When to write checkpoints besides on a signal.

    Attributes:
        every: every this many events or steps (0: never by count).
        minutes: every this many minutes of wall time (0: never by time).
    """

    every: int = 0
    minutes: float = 10.0


@dataclass
class Checkpoint:
    """A complete checkpoint on disk.

    Attributes:
        path: its directory.
        meta: the contents of ``meta.json`` (``kind``, ``k``, ``sha256``, ``ranks``,
            ``geofrac``, ``data``: the loop's JSON data).
    """

    path: Path
    meta: dict[str, Any]

    @property
    def k(self) -> int:
        """The last completed event or step."""
        return int(self.meta["k"])

    @property
    def data(self) -> dict[str, Any]:
        """The loop's JSON data saved with the checkpoint."""
        return self.meta["data"]

    def shared(self) -> dict[str, np.ndarray]:
        """The arrays every rank held alike."""
        return _load(self.path / "shared.npz")

    def local(self, rank: int) -> dict[str, np.ndarray]:
        """The arrays rank ``rank`` saved."""
        return _load(self.path / f"rank-{rank}.npz")

    def ranks(self) -> int:
        """The number of ranks that wrote it."""
        return int(self.meta["ranks"])


def _load(path: Path) -> dict[str, np.ndarray]:
    if not path.exists():
        return {}
    with np.load(path, allow_pickle=False) as f:
        return {k: f[k] for k in f.files}


def latest(directory: Path) -> Checkpoint | None:
    """The newest complete checkpoint in ``directory``, or None (no MPI)."""
    if not directory.is_dir():
        return None
    found = []
    for p in directory.iterdir():
        name = p.name
        digits = name[len(_PREFIX) :]
        if name.startswith(_PREFIX) and digits.isdigit() and (p / "meta.json").is_file():
            found.append((int(digits), p))
    for _, p in sorted(found, reverse=True):
        try:
            meta = json.loads((p / "meta.json").read_text())
        except (OSError, ValueError):
            continue
        return Checkpoint(p, meta)
    return None


@dataclass
class RunControl:
    """Checkpoint policy, signal stop and resume data of one run (collective methods).

    Args:
        comm: the run's communicator.
        directory: where checkpoints go (None: never saved, signals still stop the run).
        sha256: the scene's hash (a checkpoint resumes only the same scene).
        kind: the loop, e.g. ``"cracking"``, ``"grains"``, ``"mpm"``.
        policy: when to save besides on a signal.
        resume: the checkpoint to continue from, or None.
    """

    comm: MPI.Comm
    directory: Path | None
    sha256: str
    kind: str
    policy: CheckpointPolicy = field(default_factory=CheckpointPolicy)
    resume: Checkpoint | None = None
    _last: float = field(default_factory=time.monotonic, init=False)
    _signum: int = field(default=0, init=False)
    #: the newest checkpoint this run wrote.
    saved: Path | None = field(default=None, init=False)

    def poll(self, k: int) -> tuple[bool, bool]:
        """After completed step/event ``k``: (save a checkpoint now, stop now). Collective.

        ``stop`` implies ``save`` (when there is a directory).
        """
        every = self.policy.every
        due = bool(every) and k % every == 0
        timed = self.policy.minutes > 0 and (
            time.monotonic() - self._last >= 60.0 * self.policy.minutes
        )
        local = np.array([interrupt.received(), int(timed)], dtype=np.int64)
        if self.comm.size > 1:
            from mpi4py import MPI

            flags = np.zeros_like(local)
            self.comm.Allreduce(local, flags, op=MPI.MAX)
        else:
            flags = local
        self._signum = int(flags[0])
        stop = bool(flags[0])
        save = self.directory is not None and (due or bool(flags[1]) or stop)
        return save, stop

    def save(
        self,
        k: int,
        data: dict[str, Any],
        shared: dict[str, np.ndarray] | None = None,
        *,
        local: dict[str, np.ndarray] | None = None,
    ) -> Path:
        """Write checkpoint ``k`` (collective).

        Args:
            k: the last completed event or step.
            data: JSON-ready loop data (identical on every rank; rank 0's is written).
            shared: arrays every rank holds alike (rank 0 writes them).
            local: this rank's own arrays.

        Raises:
            RunError: on every rank, when a rank could not write its part.
        """
        assert self.directory is not None
        comm = self.comm
        final = self.directory / f"{_PREFIX}{k:09d}"
        tmp = self.directory / f"{_PREFIX}{k:09d}.tmp"
        error = None
        if comm.rank == 0:
            try:
                shutil.rmtree(tmp, ignore_errors=True)
                tmp.mkdir(parents=True)
            except OSError as exc:
                error = f"cannot write checkpoint {tmp}: {exc.strerror}"
        error = comm.bcast(error, root=0)
        if error is None:
            try:
                if comm.rank == 0 and shared:
                    # numpy's stub: a ** dict could hold the flag allow_pickle
                    np.savez(tmp / "shared.npz", **shared)  # type: ignore[arg-type]
                if local:
                    np.savez(tmp / f"rank-{comm.rank}.npz", **local)  # type: ignore[arg-type]
            except OSError as exc:
                error = f"cannot write checkpoint {tmp}: {exc.strerror}"
            errors = comm.allgather(error)
            error = next((e for e in errors if e), None)
        if error is None and comm.rank == 0:
            meta = {
                "kind": self.kind,
                "k": k,
                "sha256": self.sha256,
                "ranks": comm.size,
                "geofrac": geofrac.__version__,
                "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                "data": data,
            }
            try:
                (tmp / "meta.json").write_text(json.dumps(meta) + "\n")
                shutil.rmtree(final, ignore_errors=True)
                os.replace(tmp, final)
                self._prune(final)
            except OSError as exc:
                error = f"cannot write checkpoint {final}: {exc.strerror}"
        error = comm.bcast(error, root=0)
        if error is not None:
            raise RunError(error)
        self._last = time.monotonic()
        self.saved = final
        return final

    def _prune(self, newest: Path) -> None:
        """Remove ``.tmp`` leftovers and all but the newest KEEP complete checkpoints."""
        assert self.directory is not None
        complete = []
        for p in self.directory.iterdir():
            if p.name.endswith(".tmp") and p != newest:
                shutil.rmtree(p, ignore_errors=True)
            elif p.name.startswith(_PREFIX) and p.is_dir():
                complete.append(p)
        for p in sorted(complete)[:-KEEP]:
            shutil.rmtree(p, ignore_errors=True)

    def interrupt(self, where: str) -> None:
        """Raise :class:`~geofrac.interrupt.Interrupted` (after :meth:`poll` said stop)."""
        raise interrupt.Interrupted(self._signum, where)

    def check_resume(self, *, ranks_must_match: bool = True, check_kind: bool = True) -> None:
        """Refuse a resume checkpoint of another scene, loop or (optionally) rank count."""
        ck = self.resume
        if ck is None:
            return
        if ck.meta.get("sha256") != self.sha256:
            raise RunError(
                f"--resume: the checkpoint {ck.path} is of another scene or other --set "
                "overrides (its sha256 differs); run without --resume to start afresh"
            )
        if check_kind and ck.meta.get("kind") != self.kind:
            raise RunError(
                f"--resume: the checkpoint {ck.path} is of a '{ck.meta.get('kind')}' loop, "
                f"this run is '{self.kind}'"
            )
        if ranks_must_match and ck.ranks() != self.comm.size:
            raise RunError(
                f"--resume: the checkpoint {ck.path} was written on {ck.ranks()} rank(s); "
                f"resume it on {ck.ranks()} (this run has {self.comm.size})"
            )
