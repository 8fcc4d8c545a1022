"""Factor of safety by shear strength reduction on the elasto-plastic solver.

Each trial factor F solves the whole load-stepped problem (e.g. gravity ramped from a
stress-free start) with c/F, tan φ/F, tan ψ/F
(:func:`geofrac.plasticity.strength_reduction.reduce_strength`) through
:func:`geofrac.fem.plastic.solve_plastic`. A trial is *failed* when some load
increment did not converge within the Newton iteration limit after ``max_cuts``
halvings (``end_reason = "step_too_small"``): Griffiths and Lane's (1999) criterion,
non-convergence of the global equilibrium. The monitor displacement at the end of each
trial (at load factor 1 when stable, at the last converged factor when failed) is
recorded as the second indicator: it grows sharply as F nears the factor of safety
(Dawson, Roth and Drescher (1999)). The bisection of
:func:`geofrac.plasticity.strength_reduction.bisect_factor` narrows [stable, failed]
to the tolerance. See docs/plasticity.md, "Factor of safety by strength reduction".
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.plastic import Law, PlasticProblem, StepHooks, solve_plastic
from geofrac.plasticity.strength_reduction import (
    Bracket,
    bisect_factor,
    reduce_strength,
    trials_left,
)

__all__ = [
    "Monitor",
    "ReductionHooks",
    "ReductionResult",
    "Trial",
    "factor_of_safety",
    "largest_monitor",
    "point_monitor",
]

Monitor = Callable[[dolfinx.fem.Function], np.ndarray]


def point_monitor(point: Sequence[float]) -> Monitor:
    """The monitor u ↦ u(``point``) at (x, y), shape=(gdim,), the same on every rank.

    Raises RunError (on every rank) when the point is outside the mesh.
    """

    def monitor(u: dolfinx.fem.Function) -> np.ndarray:
        mesh = u.function_space.mesh
        gdim = mesh.geometry.dim
        x = np.zeros((1, 3))
        x[0, :gdim] = point[:gdim]
        tree = dolfinx.geometry.bb_tree(mesh, mesh.topology.dim)
        cand = dolfinx.geometry.compute_collisions_points(tree, x)
        cells = dolfinx.geometry.compute_colliding_cells(mesh, cand, x).links(0)
        owned = cells[cells < mesh.topology.index_map(mesh.topology.dim).size_local]
        value, count = np.zeros(gdim), 0
        if len(owned):
            value, count = np.asarray(u.eval(x, owned[:1])).reshape(gdim), 1
        total = mesh.comm.allreduce(value, op=MPI.SUM)
        found = mesh.comm.allreduce(count, op=MPI.SUM)
        if found == 0:
            raise RunError(f"plasticity.reduction_monitor: {list(point)} is outside the mesh")
        return np.asarray(total / found)

    return monitor


def largest_monitor(u: dolfinx.fem.Function) -> np.ndarray:
    """[max over the nodes of |u|], shape=(1,), the same on every rank."""
    bs = u.function_space.dofmap.index_map_bs
    owned = u.function_space.dofmap.index_map.size_local
    nodes = u.x.array[: owned * bs].reshape(-1, bs)
    local = float(np.linalg.norm(nodes, axis=1).max()) if len(nodes) else 0.0
    return np.array([u.function_space.mesh.comm.allreduce(local, op=MPI.MAX)])


@dataclass
class Trial:
    """One trial factor.

    Attributes:
        factor: the trial F.
        stable: every load increment converged.
        load_factor: the last converged load factor (1 when stable).
        end_reason: ``"converged"`` or ``"step_too_small"``.
        monitor: |u| at the monitor point at the end of the trial, or None.
        iterations: Newton iterations of all attempted increments.
        seconds: wall time of the trial.
        diverged: PETSc reason name → count, over the rejected increments (e.g.
            DIVERGED_MAX_IT, DIVERGED_LINEAR_SOLVE: which way Newton failed).
    """

    factor: float
    stable: bool
    load_factor: float
    end_reason: str
    monitor: float | None
    iterations: int
    seconds: float
    diverged: dict[str, int] = field(default_factory=dict)


class ReductionHooks(Protocol):
    """Checkpoints and resume of :func:`factor_of_safety` (collective methods).

    :class:`geofrac.fem.plastic_checkpoint.ReductionHooks` implements them on the run's
    control.
    """

    def replay(self, factor: float) -> Trial | None:
        """A finished trial at ``factor`` known from a checkpoint (not solved again)."""
        ...

    def trial(self, factor: float, trials: list[Trial], *, final: bool = False) -> StepHooks:
        """The load-step hooks of the solve at ``factor`` (``trials``: those so far)."""
        ...

    def finished(self, trials: list[Trial]) -> None:
        """After a finished trial (the last of ``trials``): checkpoint, stop on a signal."""
        ...


@dataclass
class ReductionResult:
    """The factor of safety with its bracket and every trial.

    Attributes:
        bracket: [stable, failed] and the order of the trials.
        trials: the trials in the order run.
        tolerance: the bracket width asked for.
    """

    bracket: Bracket
    tolerance: float
    trials: list[Trial] = field(default_factory=list)

    @property
    def factor_of_safety(self) -> float:
        """The middle of the bracket."""
        return self.bracket.factor_of_safety

    def as_dict(self) -> dict[str, object]:
        """JSON-ready summary (the results file's ``strength_reduction``)."""
        return {
            "factor_of_safety": self.factor_of_safety,
            "stable": self.bracket.stable,
            "failed": self.bracket.failed,
            "tolerance": self.tolerance,
            "trials": [dict(vars(t)) for t in self.trials],
        }


def factor_of_safety(
    problem_factory: Callable[[Law], PlasticProblem],
    law: Law,
    *,
    steps: int,
    low: float,
    high: float,
    tolerance: float,
    max_cuts: int = 4,
    monitor: Monitor | None = None,
    say: Callable[[str], None] | None = None,
    hooks: ReductionHooks | None = None,
) -> ReductionResult:
    """Bisection on the trial factor F between a stable ``low`` and a failed ``high``.

    ``problem_factory(reduced law)`` builds a fresh problem per trial (freed after it);
    ``monitor(u)`` gives the monitor point's displacement components, shape=(gdim,),
    the same on every rank; ``say`` gets one line per trial with the time so far and an
    estimate of the trials left (the caller prints on rank 0). ``hooks``: checkpoints
    after every load step and trial, and the trials a resumed run replays
    (:mod:`geofrac.fem.plastic_checkpoint`).
    """
    trials: list[Trial] = []
    start = time.perf_counter()

    def progress(trial: Trial, *, replayed: bool) -> None:
        if say is None:
            return
        tried = [(t.factor, t.stable) for t in trials]
        left = trials_left(tried, low=low, high=high, tolerance=tolerance)
        solved = [t.seconds for t in trials]
        eta = left * sum(solved) / len(solved)
        state = "stable" if trial.stable else f"FAILED at load factor {trial.load_factor:.4f}"
        if trial.end_reason == "gravity_step_too_small":
            state = "FAILED in the gravity phase"
        shown = "" if trial.monitor is None else f", monitor |u| {trial.monitor:.4e}"
        if trial.diverged:
            shown += ", rejected: " + ", ".join(f"{k} x{v}" for k, v in trial.diverged.items())
        how = "replayed from the checkpoint" if replayed else f"{trial.seconds:.1f} s"
        say(
            f"strength reduction: F = {trial.factor:.4f} {state} ({trial.iterations} Newton "
            f"its{shown}, {how}); {time.perf_counter() - start:.1f} s so far, about "
            f"{left} trial(s) left, ETA {eta:.0f} s"
        )

    def is_stable(factor: float) -> bool:
        known = None if hooks is None else hooks.replay(factor)
        if known is not None:
            trials.append(known)
            progress(known, replayed=True)
            return known.stable
        t0 = time.perf_counter()
        result = solve_plastic(
            problem_factory,
            reduce_strength(law, factor),
            steps=steps,
            monitor=monitor,
            max_cuts=max_cuts,
            hooks=None if hooks is None else hooks.trial(factor, trials),
        )
        its = sum(s.report.iterations for s in result.attempted)
        diverged: dict[str, int] = {}
        for s in result.attempted:
            if not s.accepted:
                diverged[s.report.reason_name] = diverged.get(s.report.reason_name, 0) + 1
        u = None if result.monitor is None else float(np.linalg.norm(result.monitor))
        trial = Trial(
            factor,
            result.converged,
            result.factor,
            result.end_reason,
            u,
            its,
            time.perf_counter() - t0,
            diverged,
        )
        trials.append(trial)
        progress(trial, replayed=False)
        if hooks is not None:
            hooks.finished(trials)
        return trial.stable

    bracket = bisect_factor(is_stable, low=low, high=high, tolerance=tolerance)
    if say is not None:
        say(
            f"strength reduction: factor of safety {bracket.factor_of_safety:.4f} "
            f"(stable {bracket.stable:.4f}, failed {bracket.failed:.4f})"
        )
    return ReductionResult(bracket, tolerance, trials)
