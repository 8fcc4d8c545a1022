"""Scenes: the TOML files under ``jobs/`` that declare what to simulate.

:func:`load_scene` validates on one process; :func:`load_scene_collective` does it on
rank 0 of a communicator and hands every rank the same :class:`Scene` or the same
:class:`SceneError`, so a bad scene stops all ranks together, before any heavy work.
"""

from __future__ import annotations

import pickle
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from geofrac.model.errors import SceneError
from geofrac.model.scene import Scene
from geofrac.scene.load import load_scene

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["Scene", "SceneError", "load_scene", "load_scene_collective"]


def load_scene_collective(
    comm: MPI.Comm,
    path: str | Path,
    overrides: Sequence[str] = (),
    *,
    out: str | Path | None = None,
    allow_large: bool = False,
) -> Scene:
    """Validate on rank 0 and broadcast; every rank returns the scene or raises the error.

    Rank 0 pickles its result before the broadcast, so that nothing can fail on rank 0
    alone inside the collective: every rank receives the same bytes and raises the same
    :class:`SceneError` (or returns equal scenes).

    Args:
        comm: an ``mpi4py`` communicator.
        path: scene TOML file.
        overrides: ``KEY=VALUE`` strings applied before validation.
        out: output directory replacing ``output.dir``.
        allow_large: run a scene beyond the size caps (``--allow-large``); the caps
            scale with ``comm.size``.
    """
    payload: bytes | None = None
    failure: BaseException | None = None
    if comm.rank == 0:
        try:
            result: Scene | Exception = load_scene(
                path, overrides, out, allow_large=allow_large, ranks=comm.size
            )
        except SceneError as exc:
            result = exc
        except Exception as exc:  # a bug must not leave the other ranks waiting in bcast
            failure = exc
            result = RuntimeError(f"scene loading failed on rank 0: {exc!r}")
        try:
            payload = pickle.dumps(result, protocol=pickle.HIGHEST_PROTOCOL)
        except (RecursionError, MemoryError, pickle.PicklingError, TypeError) as exc:
            payload = pickle.dumps(
                SceneError(path, "", f"the scene cannot be sent to the other ranks: {exc!r}")
            )
    result = pickle.loads(comm.bcast(payload, root=0))
    if failure is not None:
        raise failure
    if isinstance(result, BaseException):
        raise result
    assert isinstance(result, Scene)
    return result
