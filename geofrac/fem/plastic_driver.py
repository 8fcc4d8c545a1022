"""The ``plasticity`` effect's loop for FEM scenes: the elasto-plastic load-stepped solve.

Builds :class:`geofrac.fem.plastic.PlasticProblem` on the scene's set-up elastic problem
(its P2 space, Dirichlet conditions and load forms), with the law the effect built from
its validated ``[plasticity]`` table. The load factor λ goes 0 → 1: the scene's ``[[load]]`` entries
are scaled by λ; the effects' terms (gravity) and, with ``[initial_stress]``, the
``loaded`` sides' σ0·n act in full from the start, the initial stress σ0 being the
starting stress at the quadrature points (it must balance them: the initial state of
docs/insitu.md). The displacement is measured from the initial state. The results hold
every attempted step (factor, SNES converged reason, iterations, final residual,
plastic points); a run whose increment could not converge after ``max_cuts`` halvings
ends with ``converged = false``, ``end_reason = "step_too_small"`` and the displacement
of the last converged factor (never of the failed one).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import ufl

from geofrac.fem.insitu import in_plane
from geofrac.fem.plastic import Law, PlasticProblem
from geofrac.fem.solution import Solution
from geofrac_forms import elasticity as forms

__all__ = ["run"]


def _external(problem: Any) -> Callable[[Any, Any], Any]:
    """(λ, v) → the external work.

    The effects' terms and σ0·n of the loaded sides held, the scene's loads times λ.
    """
    scene = problem.scene

    def external(factor: Any, v: Any) -> Any:
        ctx = problem.form_context(v)
        held = [term(ctx) for term in problem.terms]
        if scene.initial_stress is not None and problem.insitu is not None:
            gdim = problem.mesh.geometry.dim
            traction = in_plane(problem.insitu.sigma0, gdim) * ufl.FacetNormal(problem.mesh)
            held += [
                forms.traction_form(
                    v, traction, problem.thickness, problem.ds(problem.tagged.groups[g][1])
                )
                for g in scene.initial_stress.loaded
            ]
        ramped = [factor * problem._load_term(load, v) for load in scene.loads]
        zero = ufl.inner(ufl.as_vector([0.0] * problem.mesh.geometry.dim), v) * problem.dx
        return sum(held + ramped, zero)

    return external


def run(
    law: Law,
    solution: Solution,
    say: Callable[[str], None],
    *,
    steps: int,
    max_cuts: int,
    max_iterations: int,
) -> dict[str, Any]:
    """Solve ``steps`` load increments; copy u into the elastic problem's ``uh``; the results."""
    problem = solution.problem
    sigma0 = None if problem.insitu is None else problem.insitu.sigma0
    plastic = PlasticProblem(
        problem.element.space,
        law,
        _external(problem),
        bcs=problem.bcs,
        initial_stress=sigma0,
        prefix="geofrac_plastic_",
        options=dict(solution.scene.solver.options),
        max_it=max_iterations,
    )
    talk = say if solution.tagged.mesh.comm.rank == 0 else None
    try:
        result = plastic.solve_steps(steps, max_cuts=max_cuts, say=talk)
        problem.uh.x.array[:] = plastic.u.x.array
        if not result.converged:
            say(
                f"plastic: NOT CONVERGED: the increment beyond factor {result.factor:.4f} "
                f"diverged after {max_cuts} halvings; the fields are those of the "
                "last converged factor"
            )
        return {
            "converged": result.converged,
            "end_reason": result.end_reason,
            "factor": result.factor,
            "law": type(law).__name__,
            "plastic_points": plastic.plastic_points(),
            "yielded_area": plastic.yielded_area(),
            "steps": [
                {
                    "factor": s.factor,
                    "accepted": s.accepted,
                    "reason": s.report.reason_name,
                    "iterations": s.report.iterations,
                    "residual": s.report.residuals[-1] if s.report.residuals else None,
                    "plastic_points": s.plastic_points,
                }
                for s in result.steps
            ],
            "solver": plastic.newton.describe(),
        }
    finally:
        plastic.destroy()
