"""An elastic run from an initial stress through construction stages (docs/insitu.md).

The stress is σ = σ0 + C ε(u): u (and the strains and reactions) are measured from the
initial state, the stress is the total. The vectors, on the unknowns (thickness t in 2D):

- internal force I(σ) = t ∫_live Bᵀ σ dx (``alive`` × the integrand);
- external force F = the scene's loads, the effects' terms (gravity, ρ per cell group,
  zero on removed cells) and the ``loaded`` sides' traction t ∫ σ0·n v ds;
- out of balance R(u) = F − I(σ0 + C ε(u)).

1. **Check**: r0 = F_init − I(σ0) on the free DOFs, F_init = gravity + ``loaded``
   sides (the scene's ``[[load]]`` entries are the analysis loads, applied on top);
   its largest entry over the largest entry of F_init and I(σ0) must be at most
   :data:`TOLERANCE`, or the run stops naming the fix.
2. **Step 0** (``initial``): K u = R(0), the loads and prescribed displacements.
3. **Stages**: removing cells sets ``alive`` to 0 there (their stiffness, weight and
   internal force go), holds the DOFs no live cell touches, and computes the release
   R(u) of the remaining body from the current stress; adding cells brings them back
   with their own material, stress-free in the current state; a stage solves
   K Δu = s R for its share s of it (``relaxation``; default: all that remains).
4. **Switches** (``from``/``until`` of a load or support, :mod:`.stage_switches`): a
   stage releases the supports it removes (−their reaction, before its removal), holds
   those it installs (their ``value`` an increment, lifted) and adds the change of the
   loads, all in full: K Δu = s R + ΔF + R_s + lifting (docs/insitu.md, "Loads and
   supports per stage").
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem import stage_checkpoint
from geofrac.fem.elastic import ElasticProblem
from geofrac.fem.insitu import (
    InsituFields,
    cell_dofs,
    group_cells,
    in_plane,
    untouched_blocks,
)
from geofrac.fem.post import TENSOR_FIELDS, probe
from geofrac.fem.stage_checkpoint import Frame
from geofrac.fem.stage_switches import Switches, owned_rows
from geofrac.io.checkpoint import RunControl
from geofrac.log import format_seconds
from geofrac.materials import lame
from geofrac.model.scene import Material, Stage
from geofrac.solvers import (
    Vector,
    assemble_matrix,
    assemble_vector,
    function_vector,
    set_bc,
)
from geofrac.timing import Timings
from geofrac_forms import elasticity as forms

__all__ = [
    "STATE_FIELDS",
    "TOLERANCE",
    "Frame",
    "StagedResults",
    "StagedRun",
    "initial_balance",
    "install_fields",
    "refusal",
    "run_stages",
    "state_frame",
]

#: Largest accepted out-of-balance force of the initial state, relative to the largest
#: applied force. An initial state in equilibrium leaves round-off (about 1e-13 with the
#: exact quadrature of :mod:`geofrac.fem.insitu`); an imbalance of 1e-6 of the load
#: moves the body by 1e-6 of the load's displacements, below anything reported. A state
#: that is not in equilibrium (K0 under a slope) is off by O(1).
TOLERANCE = 1e-6
#: The staged fields a checkpoint saves (:class:`~geofrac.fem.insitu.InsituFields`).
STATE_FIELDS = ("alive", "lam", "mu", "rho", "sigma0", "u_ref")


class StagedRun:
    """The vectors and the stage loop of a staged elastic problem.

    Args:
        problem: a compiled :class:`ElasticProblem` with ``insitu`` fields.
        say: progress printer (rank 0).
    """

    def __init__(self, problem: ElasticProblem, say: Callable[[str], None]) -> None:
        assert problem.insitu is not None
        self.problem, self.say = problem, say
        self.insitu: InsituFields = problem.insitu
        self.comm = problem.comm
        mesh, V = problem.mesh, problem.element.space
        self.V, self.bs = V, V.dofmap.index_map_bs
        self.owned = V.dofmap.index_map.size_local * self.bs
        gdim = mesh.geometry.dim
        v = ufl.TestFunction(V)
        u = problem.uh
        elastic = forms.epsilon(u - self.insitu.u_ref)  # u_ref: added cells only
        lam, mu = problem.lam, problem.mu
        sigma = in_plane(self.insitu.sigma0, gdim) + 2.0 * mu * elastic
        sigma += lam * ufl.tr(elastic) * ufl.Identity(gdim)
        t, alive = problem.thickness, self.insitu.alive
        internal = t * alive * ufl.inner(sigma, forms.epsilon(v)) * problem.dx
        loaded = self._loaded_terms(v)
        initial = loaded + [term(problem.form_context(v)) for term in problem.terms]
        zero = ufl.inner(dolfinx.fem.Constant(mesh, np.zeros(gdim)), v) * problem.dx
        if not initial:
            initial = [zero]
        #: the loads and supports of each step (``from``/``until``).
        self.switches = Switches(problem)
        self.step = 0  # the step whose loads and supports act
        external = sum(loaded, problem._L)
        if self.switches.enabled:  # each load's form times its factor
            terms = self.switches.load_terms(v) + initial
            external = sum(terms[1:], terms[0]) if terms else zero
        self.residual = dolfinx.fem.form(external - internal)
        self.initial = dolfinx.fem.form(sum(initial[1:], initial[0]))
        self.internal = dolfinx.fem.form(internal)
        self._zero = zero  # a zero load: the lifting of an installed support's increment
        self.du = dolfinx.fem.Function(V)
        self.bcs = self._supports()
        self.held = owned_rows(self.bcs, V)  # owned local rows of [[bc]]
        self.orphans = np.empty(0, dtype=np.int32)  # owned local rows no live cell touches
        self.release: Vector | None = None
        self.share = 1.0  # of the pending release applied so far
        self.scale = 0.0  # the largest applied force (of the initial check)
        self.r0: Vector | None = None  # F_init - I(σ0), every row (reactions' origin)

    def _loaded_terms(self, v: Any) -> list[Any]:
        """The traction terms t ∫ (σ0 n)·v ds of the ``loaded`` sides."""
        problem = self.problem
        spec = problem.scene.initial_stress
        if spec is None:
            return []
        gdim = problem.mesh.geometry.dim
        traction = in_plane(self.insitu.sigma0, gdim) * ufl.FacetNormal(problem.mesh)
        return [
            forms.traction_form(
                v, traction, problem.thickness, problem.ds(problem.tagged.groups[g][1])
            )
            for g in spec.loaded
        ]

    def _max(self, b: Vector, rows: np.ndarray | None = None) -> float:
        """Largest |entry| of ``b`` over all ranks, on the owned ``rows`` (default all)."""
        a = b.array_r if rows is None else b.array_r[rows]
        return float(self.comm.allreduce(float(np.max(np.abs(a), initial=0.0)), op=MPI.MAX))

    def _free(self, b: Vector) -> None:
        """Zero the rows of held and orphaned DOFs of ``b`` (owned entries)."""
        b.array_w[self.held] = 0.0
        b.array_w[self.orphans] = 0.0

    def _vector(self, form: dolfinx.fem.Form, *, points: bool = False) -> Vector:
        b = assemble_vector(form)
        if points and self.switches.enabled:
            self.switches.add_points(b)
        elif points:
            self.problem._add_point_forces(b)
        return b

    def _supports(self) -> list[dolfinx.fem.DirichletBC]:
        """The DOLFINx conditions of the supports acting in the current step."""
        if not self.switches.enabled:
            return list(self.problem.bcs)
        return self.switches.conditions(self.step)

    def check(self) -> float:
        """The largest |r0| on the free DOFs over the force scale (collective; before step 0).

        r0 = F_init − I(σ0); the scale is the largest entry of F_init, I(σ0) and F (the
        loads included), and is kept for :meth:`out_of_balance`. Without an initial
        stress the state is stress-free and r0 is not kept (reactions are totals).
        """
        f_init = self._vector(self.initial)
        i0 = self._vector(self.internal)
        self.switches.all_on()  # the scale: every load, whenever it acts
        f_ext = self._vector(self.residual, points=True)  # F − I(σ0) at u = 0
        self.switches.set_step(self.step)
        f_ext.axpy(1.0, i0)
        self.scale = max(self._max(f_init), self._max(i0), self._max(f_ext))
        f_ext.destroy()
        r0 = f_init.copy()
        r0.axpy(-1.0, i0)
        i0.destroy()
        f_init.destroy()
        if self.problem.scene.initial_stress is not None:
            self.r0 = r0.copy()
        self._free(r0)
        value = self._max(r0)
        r0.destroy()
        return value / self.scale if self.scale > 0 else 0.0

    def _factor(self) -> None:
        """Assemble K with the conditions (held and orphaned DOFs) and set up the solver."""
        problem = self.problem
        problem._free_operators()
        assert problem.a is not None
        problem.A = assemble_matrix(problem.a, self.bcs)
        problem.solver = problem.make_solver()

    def _solve(self, b: Vector) -> None:
        """Add K⁻¹ b to the displacement."""
        problem = self.problem
        assert problem.solver is not None
        self.du.x.array[:] = 0.0
        problem.iterations = problem.solver.solve(b, function_vector(self.du))
        self.du.x.scatter_forward()
        problem.uh.x.array[:] += self.du.x.array
        problem.uh.x.scatter_forward()

    def initial_step(self) -> None:
        """Step 0: the scene's loads and prescribed displacements on the initial state."""
        self._factor()
        problem = self.problem
        assert problem.a is not None
        b = assemble_vector(self.residual, (problem.a, self.bcs))
        if self.switches.enabled:
            self.switches.add_points(b)
        else:
            problem._add_point_forces(b)
        set_bc(b, self.bcs)
        try:
            self._solve(b)
        finally:
            b.destroy()

    def remove(self, groups: Sequence[str]) -> None:
        """Excavate cell groups: no stiffness, weight or internal force; the release R(u)."""
        problem = self.problem
        alive = self.insitu.alive
        for group in groups:
            _, cells = problem.tagged.entities(group)
            alive.x.array[cell_dofs(alive, cells)] = 0.0
        alive.x.scatter_forward()
        self._hold_orphans()
        self._factor()
        if self.release is not None:
            self.release.destroy()
        self.release = self._vector(self.residual, points=True)
        self._free(self.release)
        self.share = 0.0

    def add(self, groups: Sequence[str], material: Material) -> None:
        """Install cell groups with ``material``, stress-free in the current state.

        Their stiffness, weight and internal force come back with their own E, ν and
        density; their stress is C ε(u − u at installation).
        """
        install_fields(self.problem, groups, material)
        self._hold_orphans()
        self._factor()

    def _hold_orphans(self) -> None:
        """Hold at their values the DOFs that no live cell touches (collective)."""
        imap = self.V.dofmap.index_map
        blocks = untouched_blocks(self.V, self.insitu.alive)
        zero = dolfinx.fem.Function(self.V)
        self.bcs = [*self._supports(), dolfinx.fem.dirichletbc(zero, blocks)]
        owned = blocks[blocks < imap.size_local]
        self.orphans = (owned[:, None] * self.bs + np.arange(self.bs)).ravel().astype(np.int32)

    def apply(self, relaxation: float | None, *, extra: Vector | None = None) -> float:
        """Apply ``relaxation`` of the pending release (None: all that remains); the share.

        ``extra``: forces applied in full with it (loads and released supports).
        """
        share = 1.0 - self.share if relaxation is None else relaxation
        if self.release is None or share <= 0.0:
            if extra is not None:
                self._solve(extra)
            return 0.0
        b = self.release.copy()
        try:
            b.scale(share)
            if extra is not None:
                b.axpy(1.0, extra)
            self._solve(b)
        finally:
            b.destroy()
        self.share += share
        return share

    def free_supports(self, step: int) -> tuple[Vector | None, dict[str, list[float]]]:
        """The release of the supports switched off at the start of ``step`` (collective).

        R(u) = F − I(σ) of the state at the end of the previous step on the rows that no
        support acting in ``step`` holds: minus the total force the supports carried
        (their reaction, the initial state's included), zero elsewhere; and its sum per
        component for each such support's group (what the release applies). Call before
        the step's removal and switch.
        """
        off = self.switches.changed(step)[3]
        if not off:
            return None, {}
        freed = np.setdiff1d(self.held, owned_rows(self.switches.conditions(step), self.V))
        b = self._vector(self.residual, points=True)
        values = b.array_r[freed].copy()
        b.array_w[:] = 0.0
        b.array_w[freed] = values
        forces: dict[str, list[float]] = {}
        for i in off:
            rows = np.intersect1d(owned_rows(self.switches.supports[i], self.V), freed)
            sums = np.zeros(self.problem.mesh.geometry.dim)
            np.add.at(sums, rows % self.bs, b.array_r[rows])
            total = np.empty_like(sums)
            self.comm.Allreduce(sums, total, op=MPI.SUM)
            forces[self.problem.scene.bcs[i].group] = [float(x) + 0.0 for x in total]
        return b, forces

    def set_supports(self, step: int) -> None:
        """Hold the DOFs of the supports acting in ``step`` (no factorisation here)."""
        self.step = step
        self.held = owned_rows(self._supports(), self.V)

    def switch_loads(self, step: int) -> Vector | None:
        """Set the loads of ``step``; their change F_step − F_before, or None (collective)."""
        on, off, _, _ = self.switches.changed(step)
        if not on and not off:
            self.switches.set_step(step)
            return None
        before = self._vector(self.residual, points=True)
        self.switches.set_step(step)
        after = self._vector(self.residual, points=True)
        after.axpy(-1.0, before)
        before.destroy()
        return after

    def lift(self, step: int) -> Vector | None:
        """The increments of the supports installed at ``step`` (collective).

        −K g on the free rows and g on the rows of the installed supports (g: their
        ``value``), or None when every installed support holds its DOFs where they are.
        """
        on = self.switches.changed(step)[2]
        scene = self.problem.scene
        moved = [i for i in on if any(x != 0 for x in scene.bcs[i].value)]
        bcs = [c for i in moved for c in self.switches.supports[i]]
        if not bcs:  # the same on every rank (the scene's)
            return None
        assert self.problem.a is not None
        b = assemble_vector(dolfinx.fem.form(self._zero), (self.problem.a, bcs))
        self._free(b)
        set_bc(b, bcs)
        return b

    def out_of_balance(self) -> float:
        """The largest |R(u)| on the free DOFs over the check's force scale (collective)."""
        r = self._vector(self.residual, points=True)
        self._free(r)
        value = self._max(r)
        r.destroy()
        scale = self.scale if self.scale > 0 else 1.0
        return value / scale

    def reactions(self) -> dict[str, list[float]]:
        """Per [[bc]] group, the reaction force per component relative to the initial state.

        The sum over the group's held DOFs of I(σ) − F minus its value in the initial
        state (I(σ0) − F_init); held components only, others 0 (collective). A support
        installed in a stage had none in the initial state; one not acting now has
        none now (its value is minus the initial one).
        """
        problem = self.problem
        r = self._vector(self.residual, points=True)
        total_r = r.copy() if self.switches.enabled else None
        if self.r0 is not None:
            r.axpy(-1.0, self.r0)
        out: dict[str, list[float]] = {}
        gdim = problem.mesh.geometry.dim
        for i, bc in enumerate(problem.scene.bcs):
            dim, entities = problem._bc_entities(i)
            sums = np.zeros(gdim)
            acting = not self.switches.enabled or self.switches.bc_on(i, self.step)
            rel = r if acting and bc.switch_on is None else total_r
            for c in bc.components:
                dofs = dolfinx.fem.locate_dofs_topological(self.V.sub(c), dim, entities)
                dofs = np.unique(dofs[dofs < self.owned])
                if acting:
                    assert rel is not None
                    sums[c] = -float(np.sum(rel.array_r[dofs]))
                elif bc.switch_on is None and self.r0 is not None:
                    sums[c] = float(np.sum(self.r0.array_r[dofs]))
            total = np.empty_like(sums)
            self.comm.Allreduce(sums, total, op=MPI.SUM)
            out[bc.group] = [float(x) + 0.0 for x in total]
        r.destroy()
        if total_r is not None:
            total_r.destroy()
        return out

    def max_displacement(self) -> float:
        """Largest |u| over the nodes of live cells (collective)."""
        u = self.problem.uh.x.array[: self.owned].reshape(-1, self.bs).copy()
        if len(self.orphans):
            u[self.orphans[:: self.bs] // self.bs] = 0.0
        local = float(np.max(np.linalg.norm(u, axis=1), initial=0.0))
        return float(self.comm.allreduce(local, op=MPI.MAX))

    def state(self) -> dict[str, np.ndarray]:
        """This rank's arrays of the state (:mod:`geofrac.fem.stage_checkpoint`).

        ``u`` and the staged fields (local, with ghosts), ``release`` (owned rows, when
        a removal is pending).
        """
        arrays = {"u": self.problem.uh.x.array}
        for name in STATE_FIELDS:
            arrays[name] = getattr(self.insitu, name).x.array
        if self.release is not None:
            arrays["release"] = np.asarray(self.release.array_r).copy()
        return arrays

    def set_state(self, arrays: dict[str, np.ndarray], share: float, *, step: int = 0) -> None:
        """Put back a :meth:`state` after ``step`` and the applied ``share``; factorise.

        The loads and supports are those of ``step`` (collective).
        """
        self.set_supports(step)
        self.switches.set_step(step)
        self.problem.uh.x.array[:] = arrays["u"]
        self.problem.uh.x.scatter_forward()
        for name in STATE_FIELDS:
            f = getattr(self.insitu, name)
            f.x.array[:] = arrays[name]
            f.x.scatter_forward()
        self._hold_orphans()
        self._factor()
        if "release" in arrays:
            self.release = self._vector(self.residual, points=True)
            self.release.array_w[:] = arrays["release"]
        self.share = share

    def frame(self, index: int, name: str) -> Frame:
        """The fields of the current state for ``results.xdmf``."""
        return state_frame(self.problem, self.insitu.alive, index=index, name=name)

    def destroy(self) -> None:
        """Free the vectors this run made (the problem frees its operators)."""
        for vec in (self.release, self.r0):
            if vec is not None:
                vec.destroy()
        self.release = self.r0 = None


def install_fields(problem: ElasticProblem, groups: Sequence[str], material: Material) -> None:
    """Set the staged fields of installed groups: live, ``material``, σ0 = 0, u_ref = uh.

    The elastic and the cracking stages alike (collective).
    """
    fields = problem.insitu
    assert fields is not None
    gdim = problem.mesh.geometry.dim
    lam, mu = lame(material.E, material.nu, gdim, plane=material.plane)
    for group in groups:
        cells = np.asarray(group_cells(problem.tagged, group), dtype=np.int32)
        dofs = cell_dofs(fields.alive, cells)
        fields.alive.x.array[dofs] = 1.0
        fields.lam.x.array[dofs] = lam
        fields.mu.x.array[dofs] = mu
        fields.rho.x.array[dofs] = material.density or 0.0
        blocks = fields.sigma0.function_space.dofmap.list[cells].ravel()
        fields.sigma0.x.array.reshape(-1, 9)[blocks] = 0.0
        fields.u_ref.interpolate(problem.uh, cells0=cells, cells1=cells)
    for f in (fields.alive, fields.lam, fields.mu, fields.rho, fields.sigma0, fields.u_ref):
        f.x.scatter_forward()


def refusal(value: float) -> str:
    """Why a run refuses an initial state out of balance by ``value``, and the fix."""
    return (
        f"initial_stress: the initial state is out of balance: its largest out-of-balance "
        f"force is {value:.3g} of the largest applied force (tolerance {TOLERANCE:g}). "
        "A K0 or constant stress is in equilibrium only under a level ground surface with "
        "its far sides held ([[bc]]) or loaded by σ0·n (initial_stress.loaded); otherwise "
        "use a gravity-loading stage: remove [initial_stress] and let the initial step load "
        "the body's weight (docs/insitu.md)"
    )


def state_frame(
    problem: ElasticProblem, alive: dolfinx.fem.Function, *, index: int, name: str
) -> Frame:
    """The fields of ``problem.uh`` for ``results.xdmf``: step ``index`` named ``name``.

    The displacement and the tensor fields ``output.fields`` asks for (stresses as
    totals, :meth:`ElasticProblem.tensor_fields`), and ``alive`` (0 on removed cells):
    the steps of the elastic and of the cracking stages alike.
    """
    fields = problem.scene.output.fields
    functions = []
    if "displacement" in fields:
        u = problem.uh.copy()
        u.name = "displacement"
        functions.append(u)
    wanted = [f for f in fields if f in TENSOR_FIELDS]
    tensors = problem.tensor_fields(wanted)
    functions += [tensors[f] for f in wanted]
    kept = alive.copy()
    kept.name = "alive"
    functions.append(kept)
    return Frame(index, name, functions)


@dataclass
class StagedResults:
    """What :func:`run_stages` hands back: the summary entries and the XDMF frames."""

    results: dict[str, Any]
    frames: list[Frame]


def _record(run: StagedRun, index: int, name: str, *, probes: dict[str, Any]) -> dict[str, Any]:
    """The summary entry of a step (collective)."""
    entry: dict[str, Any] = {"index": index, "name": name}
    entry["max_displacement"] = run.max_displacement()
    names, points, cells = probes["names"], probes["points"], probes["cells"]
    if len(names):
        values = probe(run.problem.uh, points, cells)
        entry["probes"] = {n: values[i].tolist() for i, n in enumerate(names)}
    entry["reactions"] = run.reactions()
    entry["out_of_balance"] = run.out_of_balance()
    return entry


def run_stages(
    problem: ElasticProblem,
    *,
    timings: Timings,
    say: Callable[[str], None],
    probes: dict[str, Any],
    control: RunControl | None = None,
) -> StagedResults:
    """Check the initial state, solve step 0 and every stage (collective).

    Args:
        problem: the scene's problem, with ``insitu`` fields.
        timings: per-phase wall times.
        say: progress (rank 0).
        probes: ``names``, ``points`` shape=(n, 3), ``cells`` (:func:`locate_points`).
        control: checkpoints and the stop signal, polled after step 0 and each stage
            but the last (:mod:`geofrac.fem.stage_checkpoint`); with ``control.resume``
            the run continues at the stage after the checkpoint's.

    Raises:
        RunError: collectively, when the initial state is out of balance.
        Interrupted: after a signal, once the checkpoint is written.
    """
    scene = problem.scene
    with timings.phase("compile"):
        problem.compile()
    run = StagedRun(problem, say)
    try:
        with timings.phase("assemble"):
            balance = run.check()
        if scene.initial_stress is not None:
            say(
                f"initial stress ({scene.initial_stress.kind}): out of balance "
                f"{balance:.2e} of the applied force (tolerance {TOLERANCE:g})"
            )
        if scene.initial_stress is not None and balance > TOLERANCE:
            raise RunError(refusal(balance))
        results: dict[str, Any] = {}
        if scene.initial_stress is not None:
            results["initial_stress"] = {"out_of_balance": balance, "tolerance": TOLERANCE}
        resume = control.resume if control is not None else None
        if resume is not None:
            assert control is not None
            control.check_resume()  # the same scene, loop and number of ranks
            done, entries, frames = stage_checkpoint.restore(run, resume)
            say(f"stages: resuming after step {done} of {len(scene.stages)} from {resume.path}")
        else:
            done, entries, frames = 0, [], []
            with timings.phase("solve"):
                run.initial_step()
            entries.append(_record(run, 0, "initial", probes=probes))
            if scene.output.xdmf:
                frames.append(run.frame(0, "initial"))
            say(
                f"stage 0/{len(scene.stages)} 'initial': "
                f"max |u| = {entries[0]['max_displacement']:.4g}"
            )
            _poll(run, control, 0, entries=entries, frames=frames)
        for k, stage in enumerate(scene.stages, start=1):
            if k <= done:
                continue
            entries.append(_stage(run, k, stage, timings=timings, probes=probes))
            if scene.output.xdmf:
                frames.append(run.frame(k, stage.name))
            if k < len(scene.stages):
                _poll(run, control, k, entries=entries, frames=frames)
        results["stages"] = entries
        return StagedResults(results, frames)
    finally:
        run.destroy()


def _stage(
    run: StagedRun, k: int, stage: Stage, *, timings: Timings, probes: dict[str, Any]
) -> dict[str, Any]:
    """Run stage ``k``: remove, add, switch, apply its share; its summary row (collective).

    A support switched off releases what it carried (:meth:`StagedRun.free_supports`,
    before the removal, so that the removal's release is the excavation's alone); the
    loads switched on or off and the released supports are applied in full with the
    stage's share of the release.
    """
    switching = run.switches.enabled
    with timings.phase("stages"):
        start = MPI.Wtime()
        freed, forces = run.free_supports(k) if switching else (None, {})
        if switching:
            run.set_supports(k)
        if stage.remove:
            run.remove(stage.remove)
            if freed is not None and run.release is not None:
                run.release.axpy(-1.0, freed)  # the excavation's part on the freed rows
        if stage.add:
            assert stage.material is not None  # the loader requires one
            run.add(stage.add, stage.material)
        extra = _switch(run, k, freed, refactor=not (stage.remove or stage.add))
        try:
            share = run.apply(stage.relaxation, extra=extra)
        finally:
            for vec in (extra, freed):
                if vec is not None:
                    vec.destroy()
        entry = _record(run, k, stage.name, probes=probes)
        seconds = run.comm.allreduce(MPI.Wtime() - start, op=MPI.MAX)
    entry |= {"removed": list(stage.remove), "added": list(stage.add)}
    entry |= {"share": share, "released": run.share}
    removed = f"removed {', '.join(stage.remove)}; " if stage.remove else ""
    removed += f"added {', '.join(stage.add)}; " if stage.add else ""
    if switching:
        switched = _switched(run, k)
        entry |= switched | {"released_supports": forces}
        removed += "".join(
            f"{key.replace('_', ' ')} {', '.join(v)}; " for key, v in switched.items() if v
        )
    run.say(
        f"stage {k}/{len(run.problem.scene.stages)} '{stage.name}': {removed}share {share:.3g} "
        f"(released {run.share:.3g}), max |u| = {entry['max_displacement']:.4g}, "
        f"out of balance {entry['out_of_balance']:.1e} ({format_seconds(seconds)})"
    )
    return entry


def _switch(run: StagedRun, k: int, freed: Vector | None, *, refactor: bool) -> Vector | None:
    """Switch the loads of stage ``k``; the forces it applies in full (collective).

    The loads' change, the released supports' forces ``freed`` and the lifting of the
    installed supports' increments; None when stage ``k`` switches nothing.
    ``refactor``: the stage neither removed nor added cells, so the supports' change
    still needs a new operator.
    """
    if not run.switches.enabled:
        return None
    _, _, bc_on, bc_off = run.switches.changed(k)
    if (bc_on or bc_off) and refactor:
        run._hold_orphans()
        run._factor()
    delta = run.switch_loads(k)
    lift = run.lift(k)
    b = None
    for part in (delta, freed):
        if part is None:
            continue
        if b is None:
            b = part.copy()
        else:
            b.axpy(1.0, part)
    if delta is not None:
        delta.destroy()
    if b is not None:
        run._free(b)
    if lift is not None and b is not None:
        b.axpy(1.0, lift)
        lift.destroy()
    elif lift is not None:
        b = lift
    return b


def _switched(run: StagedRun, k: int) -> dict[str, list[str]]:
    """The loads and supports switched at the start of stage ``k``, as scene keys."""
    on, off, bc_on, bc_off = run.switches.changed(k)
    return {
        "loads_on": [f"load[{i}]" for i in on],
        "loads_off": [f"load[{i}]" for i in off],
        "supports_on": [f"bc[{i}]" for i in bc_on],
        "supports_off": [f"bc[{i}]" for i in bc_off],
    }


def _poll(
    run: StagedRun,
    control: RunControl | None,
    k: int,
    *,
    entries: list[dict[str, Any]],
    frames: list[Frame],
) -> None:
    """After step ``k``: checkpoint when due or signalled; stop on a signal (collective)."""
    if control is None:
        return
    save, stop = control.poll(k)
    if save:
        stage_checkpoint.save(run, control, k, entries=entries, frames=frames)
    if stop:
        control.interrupt(f"stage {k}")


def initial_balance(problem: ElasticProblem) -> float:
    """The initial state's out-of-balance ratio of :meth:`StagedRun.check` (collective)."""
    problem.compile()
    run = StagedRun(problem, lambda _: None)
    try:
        return run.check()
    finally:
        run.destroy()
