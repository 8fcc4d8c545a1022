"""One run pipeline for every method: validate → build → run → report.

The scene arrives validated (:func:`geofrac.scene.load_scene_collective`). The pipeline
owns the rest, the same for FEM, MPM and blocks: the head of ``summary.json``
(:func:`~geofrac.io.summary.start_summary`), the owned and staged output directory, its
checkpoints, the status on an error or a signal, the timings and the publishing of the
files (:func:`~geofrac.io.outdir.owned_run`), and the lines the command line prints.
A method gives only what is its own, through :class:`Method`:

- ``name``: ``"fem"``, ``"mpm"`` or ``"blocks"`` (the checkpoint kind);
- ``output_files``: the files a run of it writes (removed before a new run);
- ``head(scene)``: its entries of the summary's head;
- ``run(scene, comm, timings, *, verbose, control)``: build and run in ``scene.output.dir``
  (the staged directory) and return its summary entries (``results``...);
- ``report(summary)``: its lines for the terminal before the result block (files
  written...);
- ``result(scene, summary)``: its lines of the result block, the headline numbers with
  the scene's units and their differences from the references the scene names.

A new method is one module with such an object and one line in :data:`METHODS`. The
result block (:func:`report`) is the method's ``result`` lines, then each declared
effect's (:func:`geofrac.effects.result_lines`).
"""

from __future__ import annotations

import importlib
from typing import Any, Protocol

from mpi4py import MPI

from geofrac.io.checkpoint import RunControl
from geofrac.io.summary import start_summary
from geofrac.log import format_seconds
from geofrac.model.scene import Scene
from geofrac.timing import Timings

__all__ = ["METHODS", "Method", "get", "report", "run_scene"]

#: scene ``method`` -> ``"module:object"`` of its :class:`Method` (imported on use: an
#: MPM run imports neither DOLFINx nor PETSc).
METHODS: dict[str, str] = {
    "fem": "geofrac.runner:FEM",
    "mpm": "geofrac.mpm.driver:MPM",
    "blocks": "geofrac.blocks.driver:BLOCKS",
}


class Method(Protocol):
    """What a method gives the pipeline (see the module text)."""

    name: str
    output_files: tuple[str, ...]

    def head(self, scene: Scene) -> dict[str, Any]:
        """Keyword arguments of :func:`~geofrac.io.summary.start_summary`.

        ``fem``: the versions list DOLFINx and PETSc; the rest are summary entries.
        """
        ...

    def run(
        self, scene: Scene, comm: MPI.Comm, timings: Timings, *, verbose: bool, control: RunControl
    ) -> dict[str, Any]:
        """Build and run ``scene`` in its (staged) output directory; the summary entries."""
        ...

    def report(self, summary: dict[str, Any]) -> list[str]:
        """The method's lines about a finished run before the result block."""
        ...

    def result(self, scene: Scene, summary: dict[str, Any]) -> list[str]:
        """The method's lines of the result block (:mod:`geofrac.headline` words them)."""
        ...


def get(name: str) -> Method:
    """The method of scene ``method = name`` (imports its module)."""
    module, attribute = METHODS[name].split(":")
    method: Method = getattr(importlib.import_module(module), attribute)
    return method


def run_scene(
    scene: Scene,
    comm: MPI.Comm,
    timings: Timings | None = None,
    *,
    verbose: bool = True,
    resume: bool = False,
) -> dict[str, Any]:
    """Run ``scene`` in its owned output directory; publish on success; return the summary.

    The run writes into ``output.dir/incomplete`` and moves its files into ``output.dir``
    only when it succeeds (:func:`geofrac.io.outdir.owned_run`): on a
    :class:`~geofrac.errors.RunError` or a signal, ``output.dir`` keeps the previous
    complete results and ``incomplete/summary.json`` records ``status`` =
    ``"error: ..."`` or ``"interrupted"``. ``resume`` continues a loop (cracking events,
    MPM steps) from its newest checkpoint. Collective.
    """
    from geofrac.io.outdir import owned_run

    method = get(scene.method)
    timings = timings or Timings()
    start = start_summary(scene, comm, **method.head(scene))

    def body(staged: Scene, control: RunControl) -> dict[str, Any]:
        return method.run(staged, comm, timings, verbose=verbose, control=control)

    return owned_run(
        scene,
        comm,
        timings,
        start=start,
        body=body,
        legacy=method.output_files,
        kind=method.name,
        resume=resume,
        verbose=verbose,
    )


def report(method: Method, summary: dict[str, Any], scene: Scene) -> list[str]:
    """The lines about a finished run: the method's, the result block, then the timings.

    The result block (``result:``, its lines indented) holds the method's headline
    numbers and each declared effect's, in ``scene``'s units.
    """
    from geofrac.effects import result_lines

    t = summary["timings_s"]
    lines = list(method.report(summary))
    block = [*method.result(scene, summary), *result_lines(scene, summary["results"])]
    lines += ["result:", *(f"  {line}" for line in block)] if block else []
    return [*lines, "time: " + ", ".join(f"{k} {format_seconds(v)}" for k, v in t.items())]
