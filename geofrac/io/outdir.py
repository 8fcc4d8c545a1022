"""Owned output directories: one run at a time, staged writes, publication on success.

Layout of an output directory ``OUT`` (docs/guide.md, "Running on a cluster")::

    OUT/                  the last complete run: its files and its summary.json (status ok)
    OUT/.lock             locked (``flock``) by the run that owns OUT while it runs
    OUT/incomplete/       the run in progress, or the last one that failed, was
                          interrupted or was killed: its files so far, its summary.json
                          (status "running", "interrupted" or "error: ..."), checkpoint/

A run writes only into ``OUT/incomplete/``. On success it publishes: the previous run's
files (listed in its ``summary.json`` under ``files``) are removed, ``summary.json``
first, the new files moved in and the new ``summary.json`` written last, so ``OUT``
never holds one run's files beside another run's summary. A run that fails or is
interrupted leaves ``OUT`` as it was. A second run into the same ``OUT`` while the first
holds the lock is refused.

One rule for a new run (:func:`preflight`, before any work; the CLI exits 2): ``OUT``
that holds a completed run (``OUT/summary.json``) is refused unless the run says
``--overwrite`` (the old results are replaced only when the new run succeeds) or
``--resume`` (continue the interrupted run in ``OUT/incomplete``); ``OUT`` that is a file,
or that cannot be created, is refused too. The lock is an advisory ``flock``, released by the kernel
when the process dies, so a killed run never leaves a stale lock.

Collective functions return the same result or raise the same :class:`RunError` on
every rank; only rank 0 touches the file system.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as dt
import fcntl
import json
import os
import shutil
import socket
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from geofrac import interrupt
from geofrac.errors import RunError
from geofrac.io.checkpoint import CheckpointPolicy, RunControl, latest
from geofrac.io.summary import finish_summary, write_json
from geofrac.log import sayer
from geofrac.model.errors import SceneError
from geofrac.model.scene import Scene
from geofrac.timing import Timings

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["INCOMPLETE", "SUBDIRECTORIES", "OutputDir", "claim", "owned_run", "preflight"]

#: The staging directory's name inside the output directory.
INCOMPLETE = "incomplete"
#: Sub-directories whose files a run publishes too, listed as ``sub/name`` in ``files``
#: (``lines``: :data:`geofrac.io.lines.DIRECTORY`).
SUBDIRECTORIES = ("lines",)
_LOCK = ".lock"
_CHECKPOINT = "checkpoint"


@dataclasses.dataclass
class OutputDir:
    """An output directory this run owns (rank 0 holds the lock).

    Attributes:
        final: where complete results are published.
        stage: where this run writes (``final / "incomplete"``).
        notes: messages for the user about what was found (rank 0; e.g. a killed run).
        resume_from: the checkpoint directory to resume from, or None.
    """

    final: Path
    stage: Path
    comm: MPI.Comm
    notes: list[str] = dataclasses.field(default_factory=list)
    resume_from: Path | None = None
    _lock: TextIO | None = None

    @property
    def checkpoints(self) -> Path:
        """The checkpoint directory of this run."""
        return self.stage / _CHECKPOINT

    def staged(self, scene: Scene) -> Scene:
        """``scene`` with its output directory set to the staging directory."""
        return dataclasses.replace(scene, output=dataclasses.replace(scene.output, dir=self.stage))

    def keep(self, summary: dict[str, Any], timings: Timings) -> None:
        """Finish ``summary`` into the staging directory and leave ``final`` as it is."""
        finish_summary(summary, self.stage / "summary.json", self.comm, timings=timings)

    def publish(self, summary: dict[str, Any], timings: Timings, legacy: Sequence[str]) -> None:
        """Move the staged files into ``final``, replacing the previous run's (collective).

        Args:
            summary: the run's summary (``files`` is added).
            timings: the run's timings (reduced into the summary).
            legacy: file names a previous run may have left without a ``files`` list.
        """
        error = None
        if self.comm.rank == 0:
            try:
                new = _staged_files(self.stage)
                summary["files"] = new
                old = _published_files(self.final, legacy)
                (self.final / "summary.json").unlink(missing_ok=True)  # first: never stale
                for name in old:
                    target = self.final / name
                    if target.is_file() or target.is_symlink():
                        target.unlink()
                for sub in SUBDIRECTORIES:  # gone when the old run's files were all it held
                    with contextlib.suppress(OSError):
                        (self.final / sub).rmdir()
                for name in new:
                    (self.final / name).parent.mkdir(exist_ok=True)
                    os.replace(self.stage / name, self.final / name)
            except OSError as exc:
                error = f"output.dir: cannot publish the results into {self.final}: {exc}"
        error = self.comm.bcast(error, root=0)
        if error is not None:
            raise RunError(error)
        finish_summary(summary, self.final / "summary.json", self.comm, timings=timings)
        if self.comm.rank == 0:
            shutil.rmtree(self.stage, ignore_errors=True)

    def release(self) -> None:
        """Unlock (rank 0); the lock file stays (removing it would race a waiting run)."""
        if self._lock is not None:
            fcntl.flock(self._lock, fcntl.LOCK_UN)
            self._lock.close()
            self._lock = None


def _is_temporary(name: str) -> bool:
    return name.endswith(".tmp") or name.startswith(".")


def _staged_files(stage: Path) -> list[str]:
    """The run's files in ``stage``: plain names, and ``sub/name`` in :data:`SUBDIRECTORIES`."""
    files = [
        p.name
        for p in stage.iterdir()
        if p.is_file() and p.name != "summary.json" and not _is_temporary(p.name)
    ]
    for sub in SUBDIRECTORIES:
        if (stage / sub).is_dir():
            files += [
                f"{sub}/{p.name}"
                for p in (stage / sub).iterdir()
                if p.is_file() and not _is_temporary(p.name)
            ]
    return sorted(files)


def _is_published_name(name: Any) -> bool:
    """A plain file name, or ``sub/name`` with ``sub`` in :data:`SUBDIRECTORIES`."""
    if not isinstance(name, str) or not name:
        return False
    sub, _, rest = name.rpartition("/")
    return (
        (not sub or sub in SUBDIRECTORIES) and rest == Path(rest).name and rest[:1] not in ("", ".")
    )


def _published_files(final: Path, legacy: Sequence[str]) -> list[str]:
    """The files of the run published in ``final``: its summary's ``files``, else ``legacy``."""
    try:
        files = json.loads((final / "summary.json").read_text()).get("files")
    except (OSError, ValueError, AttributeError):
        files = None
    if not isinstance(files, list):
        files = list(legacy)
    # only the run's own names: a summary.json edited by hand must not delete anything else
    return [f for f in files if _is_published_name(f)]


def _describe_holder(lock: Path) -> str:
    try:
        info = json.loads(lock.read_text())
        return f" (pid {info['pid']} on {info['host']}, started {info['started']})"
    except (OSError, ValueError, KeyError, TypeError):
        return ""


def _claim_rank0(final: Path, resume: bool) -> tuple[TextIO, list[str], Path | None]:
    """Lock ``final`` and prepare its staging directory (rank 0). Raises RunError."""
    try:
        final.mkdir(parents=True, exist_ok=True)
        handle = open(final / _LOCK, "a+")  # noqa: SIM115 - held for the whole run
    except OSError as exc:
        raise RunError(f"output.dir: cannot create {final}: {exc.strerror}") from None
    try:
        fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.close()
        raise RunError(
            f"output.dir: {final} is in use by another run{_describe_holder(final / _LOCK)}; "
            "wait for it to finish or choose another directory with --out"
        ) from None
    try:
        handle.seek(0)
        handle.truncate()
        started = dt.datetime.now(dt.UTC).isoformat(timespec="seconds")
        holder = {"pid": os.getpid(), "host": socket.gethostname(), "started": started}
        handle.write(json.dumps(holder))
        handle.flush()
        stage = final / INCOMPLETE
        notes: list[str] = []
        previous = _previous_status(stage)
        checkpoint = latest(stage / _CHECKPOINT)
        if resume:
            if checkpoint is None:
                raise RunError(
                    f"--resume: no complete checkpoint in {stage / _CHECKPOINT}; "
                    "nothing to resume (run without --resume to start afresh)"
                )
            if previous == "running":
                notes.append(f"the run in {stage} was killed; resuming from its last checkpoint")
            return handle, notes, checkpoint.path
        if stage.exists():
            if previous == "running":
                notes.append(f"the previous run in {stage} was killed before it finished")
            if checkpoint is not None:
                notes.append(
                    f"discarding the unfinished run in {stage} and its checkpoint at "
                    f"{checkpoint.meta.get('kind')} step/event {checkpoint.k} "
                    "(use --resume to continue such a run)"
                )
            shutil.rmtree(stage)
        stage.mkdir()
        return handle, notes, None
    except RunError:
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.close()
        raise
    except OSError as exc:
        fcntl.flock(handle, fcntl.LOCK_UN)
        handle.close()
        raise RunError(f"output.dir: cannot prepare {final}: {exc}") from None


def _previous_status(stage: Path) -> str | None:
    try:
        return json.loads((stage / "summary.json").read_text()).get("status")
    except (OSError, ValueError, AttributeError):
        return None


def _refusal(final: Path, *, overwrite: bool, resume: bool) -> str | None:
    """Why a new run must not start in ``final`` (rank 0), or None."""
    if final.exists() and not final.is_dir():
        return f"{final} exists and is not a directory; choose another with --out"
    existing = final
    while not existing.exists():  # the nearest ancestor that exists must let us write
        existing = existing.parent
    if not existing.is_dir() or not os.access(existing, os.W_OK | os.X_OK):
        return f"cannot create or write {final}: {existing} is not writable"
    if resume:
        if latest(final / INCOMPLETE / _CHECKPOINT) is None:
            return (
                f"--resume: no complete checkpoint in {final / INCOMPLETE / _CHECKPOINT}; "
                "nothing to resume (run without --resume to start afresh)"
            )
        return None
    summary = final / "summary.json"
    if overwrite or not summary.is_file():
        return None
    try:
        done = json.loads(summary.read_text())
        when = f" (scene '{done['scene']['name']}', finished {done['finished']})"
    except (OSError, ValueError, KeyError, TypeError):
        when = ""
    return (
        f"{final} holds a completed run{when}; a second run into it is refused. Pass "
        "--overwrite to replace its results (only when the new run succeeds), --resume to "
        "continue an interrupted run, or --out to choose another directory"
    )


def preflight(
    final: Path,
    comm: MPI.Comm,
    *,
    file: str | Path,
    key: str = "output.dir",
    overwrite: bool = False,
    resume: bool = False,
) -> None:
    """Refuse an output directory a new run must not use, before any work (collective).

    Args:
        final: the output directory.
        comm: the communicator (rank 0 looks, every rank raises).
        file: the scene file, for the message.
        key: what set the directory, for the message (``output.dir`` or ``--out``).
        overwrite: ``--overwrite``: a completed run in ``final`` may be replaced.
        resume: ``--resume``: ``final/incomplete`` must hold a complete checkpoint.

    Raises:
        SceneError: naming ``key`` (the CLI's exit code 2).
    """
    why = _refusal(final, overwrite=overwrite, resume=resume) if comm.rank == 0 else None
    why = comm.bcast(why, root=0)
    if why is not None:
        raise SceneError(file, key, why)


def claim(final: Path, comm: MPI.Comm, *, resume: bool = False) -> OutputDir:
    """Lock ``final`` for this run and prepare ``final/incomplete`` (collective).

    Without ``resume`` an earlier unfinished run's staging directory is removed (with a
    note); with it, the newest complete checkpoint there is kept for the run to continue.

    Raises:
        RunError: on every rank: the directory is in use, cannot be written, or
            ``resume`` finds no checkpoint.
    """
    result: tuple[str | None, list[str], Path | None] = (None, [], None)
    handle = None
    if comm.rank == 0:
        try:
            handle, notes, resume_from = _claim_rank0(final, resume)
            result = (None, notes, resume_from)
        except RunError as exc:
            result = (str(exc), [], None)
    error, notes, resume_from = comm.bcast(result, root=0)
    if error is not None:
        raise RunError(error)
    return OutputDir(final, final / INCOMPLETE, comm, notes, resume_from, handle)


def owned_run(
    scene: Scene,
    comm: MPI.Comm,
    timings: Timings,
    *,
    start: dict[str, Any],
    body: Callable[[Scene, RunControl], dict[str, Any]],
    legacy: Sequence[str],
    kind: str,
    resume: bool = False,
    verbose: bool = False,
) -> dict[str, Any]:
    """Run ``body`` in an owned, staged output directory; publish on success (collective).

    Args:
        scene: the validated scene (its ``output.dir`` is the directory to own).
        comm: the communicator.
        timings: the run's :class:`~geofrac.timing.Timings`.
        start: the head of the summary (:func:`~geofrac.io.summary.start_summary`).
        body: ``body(staged_scene, control)`` does the work, writing into the staged
            scene's ``output.dir``, and returns the summary entries to add (``results``...).
        legacy: names of files an older geofrac wrote into the directory.
        kind: the checkpoint kind (``"fem"``, ``"mpm"``, ``"blocks"``).
        resume: continue from the newest checkpoint in ``output.dir/incomplete``.
        verbose: print notes about the directory (rank 0).

    Returns:
        the summary as written to ``summary.json``.

    Raises:
        RunError: collectively; :class:`~geofrac.interrupt.Interrupted` after a signal,
            with ``incomplete/summary.json`` saying ``status = "interrupted"``.
    """
    out = claim(scene.output.dir, comm, resume=resume)
    try:
        say = sayer(comm, verbose=verbose)
        for note in out.notes:
            say(f"note: {note}")
        output = scene.output
        policy = CheckpointPolicy(
            int(getattr(output, "checkpoint_every", 0)),
            float(getattr(output, "checkpoint_minutes", 10.0)),
        )
        control = RunControl(comm, out.checkpoints, scene.sha256, kind, policy)
        if out.resume_from is not None:
            control.resume = latest(out.checkpoints)
            if control.resume is None:  # pragma: no cover - claim found it just before
                raise RunError(f"--resume: the checkpoint in {out.checkpoints} disappeared")
            # the scene before any heavy work; the loop checks its kind and rank count
            control.check_resume(ranks_must_match=False, check_kind=False)
            start["resumed_from"] = {"checkpoint": str(control.resume.path), "k": control.resume.k}
        summary = dict(start) | {"status": "running"}
        if comm.rank == 0:
            write_json(out.stage / "summary.json", summary)
        staged = out.staged(scene)
        try:
            # a signal that came after a loop's last poll, or during a run without a loop,
            # finds the work done: it is published, nothing is lost
            summary |= body(staged, control)
            summary["status"] = "ok"
        except interrupt.Interrupted as exc:
            summary["status"] = "interrupted"
            summary["interrupted"] = {
                "signal": exc.signum,
                "after": exc.where,
                "checkpoint": None if control.saved is None else str(control.saved),
            }
            out.keep(summary, timings)
            exc.partial = out.stage  # type: ignore[attr-defined]
            raise
        except RunError as exc:
            summary["status"] = f"error: {exc}"
            out.keep(summary, timings)
            exc.partial = out.stage  # type: ignore[attr-defined]  # for the CLI's message
            raise
        except BaseException as exc:  # a bug: record it without collectives, then re-raise
            if comm.rank == 0:
                summary["status"] = f"error: internal error {exc!r}"
                with contextlib.suppress(OSError):
                    write_json(out.stage / "summary.json", summary)
            raise
        out.publish(summary, timings, legacy)
        return summary
    finally:
        out.release()
