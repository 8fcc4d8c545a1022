"""The loads and supports of a staged run, switched on and off per step (docs/insitu.md).

A ``[[load]]`` or ``[[bc]]`` with ``from``/``until`` (:mod:`geofrac.scene.switches`)
acts from the start of one stage to the start of another. Each distributed load's form
is multiplied by a constant factor, 1 while it acts and 0 otherwise, so one compiled
residual serves every step; a point load's forces are added while it acts. The supports'
DOFs are held while they act (:class:`geofrac.fem.stages.StagedRun` does the release of
a removed support and the lifting of an installed one's increment).
"""

from __future__ import annotations

import itertools
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.fem import loads
from geofrac.fem.elastic import ElasticProblem
from geofrac.model.scene import BoundaryCondition, Load, acts
from geofrac.solvers import SCALAR, Vector

__all__ = ["Switches", "owned_rows"]


def owned_rows(bcs: list[dolfinx.fem.DirichletBC], V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """The owned local rows (unrolled) that ``bcs`` hold, sorted, shape=(p,), int32."""
    imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
    x = np.full((imap.size_local + imap.num_ghosts) * bs, np.nan)
    for bc in bcs:
        bc.set(x)
    return np.flatnonzero(~np.isnan(x[: imap.size_local * bs])).astype(np.int32)


class Switches:
    """Which loads and supports act in each step of a staged run.

    Args:
        problem: the staged problem (Lagrange element: one DOLFINx condition per held
            component of a ``[[bc]]``, or one for ``value = "exact"``).

    Attributes:
        enabled: some load or support has ``from`` or ``until`` (otherwise the run uses
            the problem's own load form and conditions, unchanged).
        step: the step whose loads and supports are set (0: the initial step).
        supports: per ``[[bc]]``, its DOLFINx conditions (values: the prescribed
            displacement, or the increment of a support installed in a stage).
    """

    def __init__(self, problem: ElasticProblem) -> None:
        scene = problem.scene
        self.problem, self.names = problem, [stage.name for stage in scene.stages]
        entries: list[BoundaryCondition | Load] = [*scene.bcs, *scene.loads]
        self.enabled = any(e.switch_on is not None or e.switch_off is not None for e in entries)
        self.step = 0
        counts = [1 if bc.value == "exact" else len(bc.components) for bc in scene.bcs]
        ends = np.cumsum([0, *counts])
        self.supports = [list(problem.bcs[a:b]) for a, b in itertools.pairwise(ends)]
        mesh, V = problem.mesh, problem.element.space
        t = float(problem.thickness.value)
        self.factors: dict[int, dolfinx.fem.Constant] = {}
        self.points: dict[int, loads.PointForces] = {}
        for i, load in enumerate(scene.loads if self.enabled else ()):
            if load.type == "point":
                self.points[i] = loads.point_forces(problem.tagged, V, (load,), thickness=t)
            else:
                self.factors[i] = dolfinx.fem.Constant(mesh, SCALAR(self.load_on(i, 0)))

    def load_on(self, i: int, step: int) -> bool:
        """Whether load ``i`` acts in ``step``."""
        return acts(self.problem.scene.loads[i], step, self.names)

    def bc_on(self, i: int, step: int) -> bool:
        """Whether ``[[bc]]`` ``i`` acts in ``step``."""
        return acts(self.problem.scene.bcs[i], step, self.names)

    def load_terms(self, v: Any) -> list[Any]:
        """Each distributed load's form times its factor (enabled runs)."""
        problem = self.problem
        return [c * problem._load_term(problem.scene.loads[i], v) for i, c in self.factors.items()]

    def set_step(self, step: int) -> None:
        """Set the loads' factors to those of ``step``."""
        self.step = step
        for i, c in self.factors.items():
            c.value = SCALAR(self.load_on(i, step))

    def all_on(self) -> None:
        """Every load's factor 1 (for the force scale of the initial check)."""
        self.step = -1
        for c in self.factors.values():
            c.value = SCALAR(1.0)

    def add_points(self, b: Vector) -> None:
        """Add the acting point loads (all of them at :meth:`all_on`) to ``b``."""
        for i, forces in self.points.items():
            if self.step < 0 or self.load_on(i, self.step):
                forces.add_to(b)
        if loads.has_expressions(self.problem.scene.loads):
            loads.require_finite(b, self.problem.comm)

    def conditions(self, step: int) -> list[dolfinx.fem.DirichletBC]:
        """The DOLFINx conditions of the supports acting in ``step``."""
        return [c for i, s in enumerate(self.supports) if self.bc_on(i, step) for c in s]

    def changed(self, step: int) -> tuple[list[int], list[int], list[int], list[int]]:
        """(loads on, loads off, supports on, supports off) at the start of ``step``."""
        scene = self.problem.scene
        ld, bc = range(len(scene.loads)), range(len(scene.bcs))
        return (
            [i for i in ld if self.load_on(i, step) and not self.load_on(i, step - 1)],
            [i for i in ld if self.load_on(i, step - 1) and not self.load_on(i, step)],
            [i for i in bc if self.bc_on(i, step) and not self.bc_on(i, step - 1)],
            [i for i in bc if self.bc_on(i, step - 1) and not self.bc_on(i, step)],
        )
