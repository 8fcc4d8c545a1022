"""What a solved scene hands to an effect's driver and to the report: :class:`Solution`."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from geofrac.fem.elastic import ElasticProblem
from geofrac.io.checkpoint import RunControl
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Scene
from geofrac.timing import Timings

__all__ = ["Solution"]


@dataclass
class Solution:
    """Everything a solved scene produced.

    Attributes:
        scene: the scene.
        tagged: distributed mesh and groups.
        problem: the elastic problem (call ``problem.destroy()`` when done).
        results: JSON-ready results (probes, errors, energy, solver).
        timings: per-phase wall times of this rank.
        control: checkpoints, signal stop and resume data for an effect's loop, or None.
    """

    scene: Scene
    tagged: TaggedMesh
    problem: ElasticProblem
    results: dict[str, Any] = field(default_factory=dict)
    timings: Timings = field(default_factory=Timings)
    #: checkpoints, signal stop and resume data for an effect's loop (None: a plain run).
    control: RunControl | None = None
    #: the sampled ``output.lines``: name -> (s, points, field -> values), written by the run
    #: pipeline (:func:`geofrac.io.lines.write_line`).
    lines: dict[str, Any] = field(default_factory=dict)
    #: a staged run's steps for ``results.xdmf`` (:class:`geofrac.fem.stages.Frame`), one
    #: time step each; empty: the single solve's fields.
    frames: list[Any] = field(default_factory=list)
    #: an effect loop's own fields for ``results.xdmf`` by name (plasticity: the returned
    #: stress, von Mises and plastic shear strain as DG0), written in place of the ones
    #: computed from ``problem.uh`` with the same name; empty: none.
    fields: dict[str, Any] = field(default_factory=dict)

    def mesh_counts(self) -> dict[str, int]:
        """Global numbers of cells and vertices, and the topological dimension."""
        tdim = self.tagged.mesh.topology.dim
        return {
            "cells": self.tagged.num_global(tdim),
            "vertices": self.tagged.num_global(0),
            "dim": tdim,
        }
