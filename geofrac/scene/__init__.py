"""Scenes: the TOML files under ``jobs/`` that declare what to simulate.

:func:`load_scene` validates on one process; :func:`load_scene_collective` does it on
rank 0 of a communicator and hands every rank the same :class:`Scene` or the same
:class:`SceneError`, so a bad scene stops all ranks together, before any heavy work.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from geofrac.scene.errors import SceneError
from geofrac.scene.load import load_scene
from geofrac.scene.model import Scene

__all__ = ["Scene", "SceneError", "load_scene", "load_scene_collective"]


def load_scene_collective(
    comm: Any, path: str | Path, overrides: Sequence[str] = (), out: str | Path | None = None
) -> Scene:
    """Validate on rank 0 and broadcast; every rank returns the scene or raises the error.

    Args:
        comm: an ``mpi4py`` communicator.
        path: scene TOML file.
        overrides: ``KEY=VALUE`` strings applied before validation.
        out: output directory replacing ``output.dir``.
    """
    result: Scene | Exception | None = None
    failure: Exception | None = None
    if comm.rank == 0:
        try:
            result = load_scene(path, overrides, out)
        except SceneError as exc:
            result = exc
        except Exception as exc:  # a bug must not leave the other ranks waiting in bcast
            failure = exc
            result = RuntimeError(f"scene loading failed on rank 0: {exc!r}")
    result = comm.bcast(result, root=0)
    if failure is not None:
        raise failure
    if isinstance(result, Exception):
        raise result
    assert isinstance(result, Scene)
    return result
