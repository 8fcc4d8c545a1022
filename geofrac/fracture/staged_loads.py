"""Loads switched on and off by the stages of a cracking run (docs/insitu.md).

A traction or pressure ``[[load]]`` with ``from``/``until`` (:mod:`geofrac.scene.switches`)
in a cracking scene with ``[[stages]]`` acts from the start of one stage to the start of
another (docs/insitu.md, "Stages in a cracking scene"). Its force vector is assembled
once; :class:`~geofrac.fracture.staged.StagedInitialStress` adds the loads acting in the
running stage to F0, so a switch is a jump of the constant load at the start of its stage,
before the stage's release is applied.
"""

from __future__ import annotations

import numpy as np

from geofrac.fracture.context import CrackContext, gather_vector
from geofrac.model.scene import Load, acts

__all__ = ["StageLoads"]


class StageLoads:
    """The scene's loads on the unknowns and the stages they act in.

    Args:
        ctx: the crack context (the scene's loads all have ``from``: the scene checks).

    Attributes:
        forces: per load, its force on the unknowns, gathered, shape=(n_global,).
    """

    def __init__(self, ctx: CrackContext) -> None:
        self.n_global = ctx.n_global
        self.names = [stage.name for stage in ctx.scene.stages]
        self.loads: tuple[Load, ...] = tuple(ctx.scene.loads)
        self.forces: list[np.ndarray] = []
        for i in range(len(self.loads)):
            b = ctx.problem.load_part(i)
            try:
                self.forces.append(gather_vector(b, ctx.comm))
            finally:
                b.destroy()

    def at(self, step: int) -> np.ndarray:
        """The sum of the loads acting in ``step`` (0: the initial state), shape=(n_global,)."""
        out = np.zeros(self.n_global)
        for load, force in zip(self.loads, self.forces, strict=True):
            if acts(load, step, self.names):
                out += force
        return out
