"""The ``plasticity`` effect's loop for FEM scenes: the elasto-plastic load-stepped solve.

Builds :class:`geofrac.fem.plastic.PlasticProblem` on the scene's set-up elastic problem
(its P2 or P3 space, Dirichlet conditions and load forms), with the law the effect built from
its validated ``[plasticity]`` table. The load factor λ goes 0 → 1: the scene's ``[[load]]`` entries
are scaled by λ; the effects' terms (gravity) and, with ``[initial_stress]``, the
``loaded`` sides' σ0·n act in full from the start, the initial stress σ0 being the
starting stress at the quadrature points (it must balance them: the initial state of
docs/insitu.md). The displacement is measured from the initial state. The results hold
every attempted step (factor, SNES converged reason, iterations, final residual,
plastic points, and the reaction force per ``[[bc]]`` group: the sum of F(u) = I(σ) − λ
F_ext over the group's held DOFs, per component); a ``[[bc]]`` with a nonzero value is
a prescribed displacement ramped with λ (displacement control: the reaction of its
group is the load it takes). A run whose increment could not converge after ``max_cuts`` halvings
ends with ``converged = false``, ``end_reason = "step_too_small"`` and the displacement
of the last converged factor (never of the failed one).

With ``gravity_phase`` (``gravity_steps`` > 0) a gravity phase comes first: the effects'
terms ramped with the loads off and the Dirichlet values held at 0, the displacements
reset (:meth:`~geofrac.fem.plastic.PlasticProblem.reset_displacement`), then the loads
ramped with gravity held: one switch constant s in the external work, terms times
λ + s (1 − λ), loads times s λ (docs/plasticity.md, "Gravity phase").

With ``[[stages]]`` the stages follow (:mod:`geofrac.fem.plastic_stages`): the problem
carries the scene's ``alive`` field, the loads are held in full through them, and a
scene with no loads and no prescribed displacement skips the analysis (nothing to ramp).

With ``strength_reduction = true`` (:func:`run_reduction`) the solve is repeated for
trial factors F (c, tan φ, tan ψ divided by F) in a bisection to the factor of safety
(:mod:`geofrac.fem.strength_reduction`); without ``[initial_stress]`` the effects'
terms (gravity) are then ramped with λ too (a stress-free start, the slope brought to
its own weight in load steps), with it they are held (the K0 start balances them). The
fields left in the scene's outputs are those of the last stable F, re-solved.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.insitu import in_plane
from geofrac.fem.joints import JointInterface, joint_springs
from geofrac.fem.plastic import GravityPhase, GravityRecord, Law, PlasticProblem
from geofrac.fem.plastic_checkpoint import LoadHooks, ReductionHooks
from geofrac.fem.plastic_outputs import (
    ProbeHistory,
    cell_fields,
    displacement_magnitude,
    plot_cell_field,
    step_rows,
    write_reduction_csv,
)
from geofrac.fem.plastic_stages import PlasticStages
from geofrac.fem.solution import Solution
from geofrac.fem.strength_reduction import factor_of_safety, largest_monitor, point_monitor
from geofrac.plasticity.interface import JointStrength
from geofrac.plasticity.strength_reduction import reduce_strength
from geofrac.solvers.types import SCALAR
from geofrac_forms import elasticity as forms

__all__ = ["gravity_summary", "run", "run_reduction"]


def _external(
    problem: Any, *, ramp_terms: bool = False, switch: Any = None, hold: Any = None
) -> Callable[[Any, Any], Any]:
    """(λ, v) → the external work.

    The effects' terms (times λ when ``ramp_terms``) and σ0·n of the loaded sides held,
    the scene's loads times λ. With a gravity phase's ``switch`` s (a constant: 0 in the
    gravity phase, 1 in the analysis) the terms are scaled by λ + s (1 − λ) and the
    loads by s λ: gravity ramped with the loads off, then gravity held with the loads
    ramped. With construction stages' ``hold`` h (a constant: 0 before the stages, 1 in
    them) the loads' factor λ becomes λ + h (1 − λ): held in full during the stages.
    """
    scene = problem.scene

    def external(factor: Any, v: Any) -> Any:
        ctx = problem.form_context(v)
        scale: Any = factor if ramp_terms else 1.0
        load_scale: Any = factor if hold is None else factor + hold * (1.0 - factor)
        if switch is not None:
            scale, load_scale = factor + switch * (1.0 - factor), switch * load_scale
        held = [scale * term(ctx) for term in problem.terms]
        if scene.initial_stress is not None and problem.insitu is not None:
            gdim = problem.mesh.geometry.dim
            traction = in_plane(problem.insitu.sigma0, gdim) * ufl.FacetNormal(problem.mesh)
            held += [
                forms.traction_form(
                    v, traction, problem.thickness, problem.ds(problem.tagged.groups[g][1])
                )
                for g in scene.initial_stress.loaded
            ]
        ramped = [load_scale * problem._load_term(load, v) for load in scene.loads]
        zero = ufl.inner(ufl.as_vector([0.0] * problem.mesh.geometry.dim), v) * problem.dx
        return sum(held + ramped, zero)

    return external


def _factory(
    solution: Solution,
    *,
    ramp_terms: bool,
    max_iterations: int,
    joints: Callable[[Law], JointInterface] | None = None,
    gravity_steps: int = 0,
    hold: Any = None,
) -> Callable[[Law], PlasticProblem]:
    """The map law ↦ the scene's elasto-plastic problem with that law (and its joints).

    With joints the line search defaults to ``bt`` (``l2`` stalled on the springs'
    stick/slip switches: docs/plasticity.md, "Joints in the strength reduction").
    ``gravity_steps`` > 0: every problem runs a gravity phase of that many steps first
    (one switch constant shared by the problems, which are solved one at a time).
    ``hold``: a scene with ``[[stages]]``: the loads' holding constant of
    :func:`_external`; the problem takes the scene's ``alive`` field.
    """
    problem = solution.problem
    insitu = None if solution.scene.initial_stress is None else problem.insitu  # (stages: zero)
    sigma0 = None if insitu is None else insitu.sigma0
    gravity = None
    if gravity_steps:
        switch = dolfinx.fem.Constant(problem.mesh, SCALAR(1.0))
        gravity = GravityPhase(switch, gravity_steps)
    external = _external(
        problem,
        ramp_terms=ramp_terms,
        switch=None if gravity is None else gravity.switch,
        hold=hold,
    )
    alive = None if hold is None or problem.insitu is None else problem.insitu.alive
    options = dict(solution.scene.solver.options)
    if joints is not None:
        options = {"snes_linesearch_type": "bt", **options}

    def make(law: Law) -> PlasticProblem:
        return PlasticProblem(
            problem.element.space,
            law,
            external,
            bcs=problem.bcs,
            initial_stress=sigma0,
            prefix="geofrac_plastic_",
            options=options,
            max_it=max_iterations,
            joints=None if joints is None else joints(law),
            gravity=gravity,
            alive=alive,
        )

    return make


def _reactions(solution: Solution) -> Callable[[PlasticProblem], dict[str, list[float]]]:
    """The map problem ↦ per ``[[bc]]`` group the reaction per component (collective).

    Held components only, others 0; summed over the group's owned held DOFs of
    F(u) = I(σ) − λ F_ext (the force the support exerts on the body).
    """
    problem = solution.problem
    V, gdim = problem.element.space, problem.mesh.geometry.dim
    owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
    rows: dict[str, list[tuple[int, np.ndarray]]] = {}
    for i, bc in enumerate(problem.scene.bcs):
        dim, entities = problem._bc_entities(i)
        for c in bc.components:
            dofs = dolfinx.fem.locate_dofs_topological(V.sub(c), dim, entities)
            rows.setdefault(bc.group, []).append((c, np.unique(dofs[dofs < owned])))

    def observe(plastic: PlasticProblem) -> dict[str, list[float]]:
        r = plastic.residual()
        out: dict[str, list[float]] = {}
        for group, held in rows.items():
            sums = np.zeros(gdim)
            for c, dofs in held:
                sums[c] = float(np.sum(r[dofs]))
            total = np.empty_like(sums)
            problem.mesh.comm.Allreduce(sums, total, op=MPI.SUM)
            out[group] = [float(x) + 0.0 for x in total]
        return out

    return observe


def _joints(
    solution: Solution, law: Law, joints: Sequence[Any], penalty: float
) -> Callable[[Law], JointInterface] | None:
    """The scene's ``plasticity.joints`` as springs (:func:`geofrac.fem.joints.joint_springs`)."""
    if not joints:
        return None
    problem = solution.problem
    return joint_springs(
        problem.element.space,
        solution.tagged,
        [(j.name, JointStrength(j.cohesion, j.friction)) for j in joints],
        bcs=problem.bcs,
        rock=law,
        penalty=penalty,
        stiffness=[(j.normal_stiffness, j.shear_stiffness) for j in joints],
    )


def run(
    law: Law,
    solution: Solution,
    say: Callable[[str], None],
    *,
    steps: int,
    max_cuts: int,
    max_iterations: int,
    write: bool = False,
    ground: Any = None,
    joints: Sequence[Any] = (),
    penalty: float = 100.0,
    gravity_steps: int = 0,
) -> dict[str, Any]:
    """Solve ``steps`` load increments; copy u into the elastic problem's ``uh``; the results.

    The probes are evaluated at every converged step (``steps[i].probes``; with ``write``
    ``load_steps.csv``); ``ground`` (the effect's ``GroundReactionConfig``) adds the
    ground reaction curve. The DG0 stress, von Mises and plastic shear strain go to
    ``solution.fields`` (``results.xdmf``); with ``write`` rank 0 also draws
    ``plastic_shear_strain.png``. ``joints``: the effect's ``JointConfig`` entries
    (springs of ``penalty`` · E / ℓ). ``gravity_steps`` > 0: a gravity phase of that
    many steps first, the displacements reset, then the ``steps`` of the analysis
    (``gravity_phase`` in the results; the probes and reactions are the analysis's).
    """
    problem = solution.problem
    scene = solution.scene
    springs = _joints(solution, law, joints, penalty)
    hold = dolfinx.fem.Constant(problem.mesh, SCALAR(0.0)) if scene.stages else None
    make = _factory(
        solution,
        ramp_terms=False,
        max_iterations=max_iterations,
        joints=springs,
        gravity_steps=gravity_steps,
        hold=hold,
    )
    plastic = make(law)
    comm = solution.tagged.mesh.comm
    talk = say if comm.rank == 0 else None
    initial = scene.initial_stress
    history = ProbeHistory(
        plastic.u,
        scene.output.probes,
        ground=ground,
        # the loader checked: with a ground reaction, σ0 is constant and isotropic in-plane
        p0=0.0 if initial is None or ground is None else -float(initial.stress[0]),
        law=law,
    )
    reactions = _reactions(solution)

    def observe(p: PlasticProblem) -> dict[str, Any]:
        return {"reactions": reactions(p), "probes": history.record()}

    control = solution.control
    hooks = None if control is None else LoadHooks(control, say)
    if scene.stages:  # not checkpointed
        _no_resume(control, say=say)
        hooks = None
    staged: dict[str, Any] = {}
    try:
        # staged without loads or moving supports: no analysis (nothing to ramp)
        moving = any(bc.value == "exact" or any(v != 0 for v in bc.value) for bc in scene.bcs)
        result = plastic.solve_steps(
            steps,
            max_cuts=max_cuts,
            say=talk,
            observe=observe,
            hooks=hooks,
            analysis=not scene.stages or bool(scene.loads) or moving,
        )
        gravity_ok = result.gravity is None or result.gravity.converged
        if scene.stages and result.converged and gravity_ok:
            assert hold is not None
            staged = _stages(
                plastic, solution, say, hold=hold, steps=steps, max_cuts=max_cuts, history=history
            )
            result.converged = staged["converged"]
            result.end_reason = staged.pop("end_reason")
        history.replay([(s.factor, s.observed["probes"]) for s in result.steps if s.accepted])
        problem.uh.x.array[:] = plastic.u.x.array
        solution.fields = cell_fields(plastic)
        gravity = result.gravity
        if gravity is not None and not gravity.converged:
            say(
                "plastic: NOT CONVERGED: the gravity phase's increment beyond factor "
                f"{gravity.factor:.4f} diverged after {max_cuts} halvings (the body cannot "
                "carry its own weight); the analysis was not run, the fields are those of "
                "the gravity phase's last converged factor"
            )
        elif not result.converged and result.end_reason != "stage_step_too_small":
            say(
                f"plastic: NOT CONVERGED: the increment beyond factor {result.factor:.4f} "
                f"diverged after {max_cuts} halvings; the fields are those of the "
                "last converged factor"
            )
        out: dict[str, Any] = {
            "converged": result.converged,
            "end_reason": result.end_reason,
            "factor": result.factor,
            "law": type(law).__name__,
            "plastic_points": plastic.plastic_points(),
            "yielded_area": plastic.yielded_area(),
            "max_plastic_shear_strain": _max_shear(plastic),
            "ellipticity_lost": None if result.ellipticity is None else result.ellipticity[0],
            "steps": step_rows(result.steps, probes=bool(history.names)),
            "solver": plastic.newton.describe(),
            **({} if plastic.joints is None else {"joints": plastic.joints.summary()}),
            **({} if gravity is None else {"gravity_phase": gravity_summary(gravity)}),
            **({"stages": staged["stages"]} if staged else {}),
        }
    finally:
        plastic.destroy()
    directory = scene.output.dir if write and comm.rank == 0 else None
    if directory is not None and plastic.joints is not None and len(plastic.joints.geometry.faces):
        plastic.joints.write_outputs(directory)
    if ground is not None:
        title = f"{scene.name}: ground reaction curve"
        out["ground_reaction"] = history.ground_reaction(directory, title=title, units=scene.units)
    if directory is not None and history.names:
        history.write_steps(directory / "load_steps.csv")
    if write:
        at = f"at load factor {result.factor:.4g}"
        if staged:
            at = f"after stage '{staged['stages'][-1]['name']}'"
        plot_cell_field(
            solution.fields["plastic_shear_strain"],
            scene.output.dir / "plastic_shear_strain.png",
            title=f"{scene.name}: plastic shear strain {at}",
            label="plastic shear strain γᵖ (−)",
            length=scene.units.length,
            alive=plastic.alive,
        )
    return out


def _no_resume(control: Any, *, say: Callable[[str], None]) -> None:
    """A staged plastic run is not checkpointed: refuse to resume one, say so (collective)."""
    if control is None:
        return
    if control.resume is not None:
        raise RunError(
            "plasticity: a run with [[stages]] is not checkpointed yet and cannot be resumed "
            f"from {control.resume.path}; run it again from the start"
        )
    if control.policy.every or control.policy.minutes:
        say(
            "plastic: a run with [[stages]] writes no checkpoints yet: the checkpoint policy "
            "is ignored, and a stop signal stops it after the current stage, to be run again"
        )


def _stages(
    plastic: PlasticProblem,
    solution: Solution,
    say: Callable[[str], None],
    *,
    hold: Any,
    steps: int,
    max_cuts: int,
    history: ProbeHistory,
) -> dict[str, Any]:
    """The scene's ``[[stages]]`` after the analysis (:mod:`geofrac.fem.plastic_stages`).

    Their entries, the overall verdict and ``end_reason`` (``"stage_step_too_small"``
    when a stage could not converge: the later stages are not run); with
    ``output.xdmf`` the XDMF frames (the analysis's end, then each stage's) go to
    ``solution.frames``.
    """
    scene = solution.scene
    reactions = _reactions(solution)
    run = PlasticStages(plastic, solution, hold=hold, say=say)
    run.probes = history.record if history.names else None
    frames = [run.frame(0, "initial")] if scene.output.xdmf else []
    entries: list[dict[str, Any]] = []
    converged = True
    for k, stage in enumerate(scene.stages, start=1):
        entry, converged = run.run(
            k,
            stage,
            steps=steps,
            max_cuts=max_cuts,
            observe=lambda p: {"reactions": reactions(p)},
        )
        entries.append(entry)
        if scene.output.xdmf:
            frames.append(run.frame(k, stage.name))
        control = solution.control
        if converged and k < len(scene.stages) and control is not None and control.poll(k)[1]:
            control.interrupt(f"after stage {k} '{stage.name}' (not checkpointed: run it again)")
        if not converged:
            say(
                f"plastic: NOT CONVERGED: stage '{stage.name}' could not be applied beyond "
                f"{entry['factor']:.4f} of its share after {max_cuts} halvings; the fields are "
                "those of its last converged share, the later stages were not run"
            )
            break
    solution.frames = frames
    end = "converged" if converged else "stage_step_too_small"
    return {"stages": entries, "converged": converged, "end_reason": end}


def gravity_summary(gravity: GravityRecord) -> dict[str, Any]:
    """The results' ``gravity_phase``: its verdict, largest |u| before the reset, steps."""
    return {
        "converged": gravity.converged,
        "factor": gravity.factor,
        "max_displacement": gravity.max_displacement,
        "plastic_points": gravity.plastic_points,
        "steps": step_rows(gravity.records),
    }


def _max_shear(plastic: PlasticProblem) -> float:
    """The largest accumulated plastic shear strain over the owned points (all ranks)."""
    shear = plastic.plastic_shear_strain()
    owned = plastic.eps.function_space.dofmap.index_map.size_local
    local = float(shear[:owned].max()) if owned else 0.0
    return float(plastic.comm.allreduce(local, op=MPI.MAX))


def run_reduction(
    law: Law,
    solution: Solution,
    say: Callable[[str], None],
    *,
    config: Any,
    write: bool,
    steps: int,
    max_cuts: int,
    max_iterations: int,
    joints: Sequence[Any] = (),
    penalty: float = 100.0,
    gravity_steps: int = 0,
) -> dict[str, Any]:
    """The factor of safety (``config``: the effect's ``StrengthReductionConfig``).

    ``joints``: the effect's ``JointConfig`` entries, whose c and μ each trial divides
    by its F with the rock's. ``gravity_steps`` > 0: each trial is a gravity phase of
    that many steps with the reduced law, the reset, then the analysis (the monitor
    measured from the gravity state); a trial whose gravity phase fails is failed.

    Bisection on F, then the last stable F re-solved: its displacement copied into the
    elastic problem's ``uh`` (probes, XDMF), its DG0 stress and plastic shear strain into
    ``solution.fields`` (XDMF: the failure mechanism), its plastic zone in the results.
    With ``write``, rank 0 draws ``strength_reduction.png`` (monitor |u| against F) and
    writes ``strength_reduction.csv`` (every trial) and, with joints, ``joints.csv``
    (each pair's x, y, σₙ, τ, opening, slip and state at the last stable F) into
    ``output.dir``; the ranks draw ``failure_mechanism.png`` (γᵖ at the last stable F)
    together.
    """
    problem = solution.problem
    ramp = problem.insitu is None and not gravity_steps
    springs = _joints(solution, law, joints, penalty)
    make = _factory(
        solution,
        ramp_terms=ramp,
        max_iterations=max_iterations,
        joints=springs,
        gravity_steps=gravity_steps,
    )
    monitor = largest_monitor if config.monitor is None else point_monitor(config.monitor)
    talk = say if solution.tagged.mesh.comm.rank == 0 else None
    control = solution.control
    hooks = None if control is None else ReductionHooks(control, say)
    result = factor_of_safety(
        make,
        law,
        steps=steps,
        low=config.low,
        high=config.high,
        tolerance=config.tolerance,
        max_cuts=max_cuts,
        monitor=monitor,
        say=talk,
        hooks=hooks,
    )
    stable = result.bracket.stable
    plastic = make(reduce_strength(law, stable))
    resolve = None if hooks is None else hooks.trial(stable, result.trials, final=True)
    try:
        last = plastic.solve_steps(steps, max_cuts=max_cuts, hooks=resolve)
        problem.uh.x.array[:] = plastic.u.x.array
        solution.fields = cell_fields(plastic)
        shear = plastic.plastic_shear_strain()
        owned = plastic.eps.function_space.dofmap.index_map.size_local
        local = float(shear[:owned].max()) if owned else 0.0
        out = result.as_dict()
        out.update(
            {
                "gravity": (
                    "gravity phase, then held"
                    if gravity_steps
                    else ("ramped" if ramp else "held (initial stress)")
                ),
                "monitor": "largest nodal |u|" if config.monitor is None else list(config.monitor),
                "last_stable": {
                    "factor": stable,
                    "converged": last.converged,
                    **(
                        {}
                        if last.gravity is None
                        else {"gravity_phase": gravity_summary(last.gravity)}
                    ),
                    "plastic_points": plastic.plastic_points(),
                    "yielded_area": plastic.yielded_area(),
                    "max_plastic_shear_strain": problem.mesh.comm.allreduce(local, op=MPI.MAX),
                    **({} if plastic.joints is None else {"joints": plastic.joints.summary()}),
                },
                "solver": plastic.newton.describe(),
            }
        )
    finally:
        plastic.destroy()
    if write and problem.mesh.comm.rank == 0:
        _plot(result, solution)
        write_reduction_csv(result.trials, solution.scene.output.dir / "strength_reduction.csv")
        if plastic.joints is not None:  # the last stable F's joint pairs
            plastic.joints.write_csv(solution.scene.output.dir / "joints.csv")
    if write:
        _plot_mechanism(solution, plastic, stable=stable, fos=result.factor_of_safety)
    if not out["last_stable"]["converged"]:  # type: ignore[index]
        say("strength reduction: WARNING: the last stable factor did not converge when re-solved")
    return out


def _plot_mechanism(
    solution: Solution, plastic: PlasticProblem, *, stable: float, fos: float
) -> None:
    """``failure_mechanism.png`` (collective): the mechanism at the last stable F.

    γᵖ; with joints |u| and the joint pairs' states instead (a block sliding on a joint in
    strong rock has no γᵖ).
    """
    scene = solution.scene
    length = scene.units.length
    if plastic.joints is None:
        field, label = solution.fields["plastic_shear_strain"], "plastic shear strain γᵖ (−)"
        what = "plastic shear strain"
    else:
        field = displacement_magnitude(solution.problem.uh)
        label = scene.units.label("|u|", "length")
        what = "|u| and joint states"
    plot_cell_field(
        field,
        scene.output.dir / "failure_mechanism.png",
        title=f"{scene.name}: {what} at F = {stable:.4f} (FoS {fos:.3f})",
        label=label,
        length=length,
        joints=None if plastic.joints is None else plastic.joints.table(),
    )


def _plot(result: Any, solution: Solution) -> None:
    """``strength_reduction.png``: the monitor |u| of every trial against F."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene = solution.scene
    rows = sorted((t.factor, t.monitor, t.stable) for t in result.trials if t.monitor is not None)
    fig, ax = plt.subplots(figsize=(6, 4))
    for ok, mark, label in ((True, "o", "stable"), (False, "x", "failed (last converged load)")):
        pts = [(f, m) for f, m, s in rows if s == ok]
        if pts:
            ax.plot(*zip(*pts, strict=True), mark, label=label)
    ax.axvline(result.factor_of_safety, color="k", lw=0.8, ls="--", label="factor of safety")
    ax.set_xlabel("trial factor F")
    ax.set_ylabel(scene.units.label("monitor |u|", "length"))
    ax.set_title(f"{scene.name}: FoS {result.factor_of_safety:.3f}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(scene.output.dir / "strength_reduction.png", dpi=90)
    plt.close(fig)
