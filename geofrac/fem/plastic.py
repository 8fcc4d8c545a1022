"""Elasto-plastic static solve: return mapping at quadrature points, Newton through SNES.

Plane strain (2D) or 3D with P2 displacements (or higher Lagrange degree); the stress and
the consistent tangent live in DOLFINx quadrature spaces (``basix.ufl.quadrature_element``)
of degree 2(p − 1) (exact for the elastic stiffness), at whose points each residual
evaluation calls the shared return mapping of :mod:`geofrac.plasticity` (Mohr-Coulomb
with tension cut-off or Drucker-Prager): ``law.update(σₙ, ε − εₙ, tangent=True)``.

    F(u; v) = ∫ σ(u) : ε(v) dx − λ-scaled external work,   J = ∫ ε(v) : D_alg : ε(du) dx

The state (σₙ, εₙ, the accumulated plastic strain) is committed only at a converged load
step. Load stepping: the load factor goes 0 → 1 in ``steps`` equal increments, an
increment whose Newton solve diverges is halved (up to ``max_cuts`` times in a row,
the state restored), and a run that still fails ends with ``converged = False`` and the
last converged factor: a non-converged step is never the result. The solver is reusable
for strength reduction: :func:`solve_plastic` takes the law (any c, φ) and returns
whether it converged and the monitor displacement. With a :class:`GravityPhase` the
stepping runs twice: the gravity phase, the reset of u and εₙ, then the analysis. With
``alive`` (construction stages, :mod:`geofrac.fem.plastic_stages`) the internal force
and the tangent are those of the live cells, and :meth:`PlasticProblem.solve_stage`
ramps a stage's release (:mod:`geofrac.fem.stage_release`) with the same stepping.
See docs/plasticity.md.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import basix.ufl
import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.joints import JointInterface
from geofrac.fem.stage_release import StageRelease
from geofrac.plasticity import DruckerPrager, MohrCoulomb
from geofrac.plasticity.davis import Davis
from geofrac.plasticity.elasticity import VOIGT, to_voigt
from geofrac.plasticity.ellipticity import lost_ellipticity
from geofrac.solvers.snes import NewtonReport, NewtonSolver
from geofrac.solvers.types import SCALAR

__all__ = [
    "GravityPhase",
    "GravityRecord",
    "LoadState",
    "PlasticProblem",
    "PlasticResult",
    "StepHooks",
    "StepRecord",
    "solve_plastic",
]

#: Plane strain: tensor index pairs of the stored stress (xx, yy, zz, xy).
STRESS_2D = ((0, 0), (1, 1), (2, 2), (0, 1))
#: Plane strain: the Voigt rows of the tangent (xx, yy, xy with engineering shear).
VOIGT_2D = (0, 1, 5)


@dataclass(frozen=True)
class Layout:
    """How a dimension stores stress, strain and tangent at the quadrature points.

    Attributes:
        stress: tensor index pairs of the stored stress components.
        strain: tensor index pairs of the stored strain components (tensor shear).
        voigt: the rows of :func:`~geofrac.plasticity.elasticity.to_voigt` the tangent
            keeps (engineering shear strains, as the strain pairs' order).
    """

    stress: tuple[tuple[int, int], ...]
    strain: tuple[tuple[int, int], ...]
    voigt: tuple[int, ...]


#: Plane strain (σ_zz kept) and 3D (the Voigt order xx, yy, zz, yz, xz, xy).
LAYOUTS = {
    2: Layout(STRESS_2D, ((0, 0), (1, 1), (0, 1)), VOIGT_2D),
    3: Layout(VOIGT, VOIGT, tuple(range(6))),
}

Law = MohrCoulomb | DruckerPrager | Davis


@dataclass
class StepRecord:
    """One attempted load increment.

    Attributes:
        factor: the load factor tried.
        report: its Newton report (reason, residual norms).
        accepted: whether it was committed.
        plastic_points: quadrature points (all ranks) whose return was plastic.
        observed: what the ``observe`` callback of :meth:`PlasticProblem.solve_steps`
            returned at this accepted step (e.g. the reactions), or None.
    """

    factor: float
    report: NewtonReport
    accepted: bool
    plastic_points: int
    observed: Any = None


@dataclass(frozen=True)
class GravityPhase:
    """A gravity-loading phase before the analysis (docs/plasticity.md, "Gravity phase").

    Attributes:
        switch: the constant the external work reads as its phase: 0 in the gravity
            phase (the effects' terms times λ, the loads off), 1 in the analysis (the
            terms held, the loads times λ); see :func:`geofrac.fem.plastic_driver`'s
            ``_external``.
        steps: load increments of the gravity phase (λ 0 → 1).
    """

    switch: dolfinx.fem.Constant
    steps: int


@dataclass
class GravityRecord:
    """What the gravity phase did, kept through the reset (and in checkpoints).

    Attributes:
        records: its attempted steps.
        converged: it reached λ = 1.
        factor: its last converged λ.
        max_displacement: the largest nodal |u| (all ranks) before the reset.
        plastic_points: points with plastic strain at its end (all ranks).
    """

    records: list[StepRecord]
    converged: bool
    factor: float
    max_displacement: float
    plastic_points: int


@dataclass
class PlasticResult:
    """The end of a load-stepped solve.

    Attributes:
        converged: every step to factor 1 converged.
        factor: the last converged load factor (1 when converged).
        end_reason: ``"converged"`` or ``"step_too_small"`` (the increment was cut
            ``max_cuts`` times and still diverged: the last record says how).
        steps: every attempted step, in order.
        monitor: the monitor displacement at the last converged factor (components,
            shape=(gdim,)), or None without a monitor point.
        ellipticity: at the end of a run that did not converge, (plastic points whose
            tangent has lost ellipticity, plastic points) at the last converged factor
            (:meth:`PlasticProblem.ellipticity`); None for a converged run.
        gravity: the gravity phase, or None without one. When it failed the analysis
            was not run: ``end_reason = "gravity_step_too_small"``, ``factor`` 0,
            ``steps`` empty, ``monitor`` at the gravity phase's last converged λ.
    """

    converged: bool
    factor: float
    end_reason: str
    steps: list[StepRecord] = field(default_factory=list)
    monitor: np.ndarray | None = None
    ellipticity: tuple[int, int] | None = None
    gravity: GravityRecord | None = None

    @property
    def attempted(self) -> list[StepRecord]:
        """Every attempted step of both phases (the gravity phase's first)."""
        return ([] if self.gravity is None else self.gravity.records) + self.steps


def _bc_view(bc: dolfinx.fem.DirichletBC) -> np.ndarray:
    """A writable view of a Dirichlet condition's value (a constant's or a function's array)."""
    g = bc.g
    if hasattr(g, "x"):  # a Function's values
        return np.asarray(g.x.array)
    view = g.value
    if not isinstance(view, np.ndarray):
        raise RunError("plasticity: a Dirichlet value that is not an array cannot be ramped")
    return view


@dataclass
class LoadState:
    """Where a load-stepped solve stands after a converged step (checkpoint and resume).

    Attributes:
        done: the last converged load factor.
        inc: the current increment (halved by cuts, kept once a step converges).
        records: every attempted step so far (of this phase).
        phase: ``"gravity"`` or ``"analysis"`` (also without a gravity phase).
        gravity: in the analysis after a gravity phase, that phase's record.
    """

    done: float
    inc: float
    records: list[StepRecord]
    phase: str = "analysis"
    gravity: GravityRecord | None = None


class StepHooks(Protocol):
    """Checkpoint and resume of :meth:`PlasticProblem.solve_steps` (collective methods).

    :mod:`geofrac.fem.plastic_checkpoint` implements them on the run's control.
    """

    def restore(self, problem: PlasticProblem) -> LoadState | None:
        """Put a checkpoint's state into ``problem``; where to continue (None: from 0)."""
        ...

    def after_step(self, problem: PlasticProblem, state: LoadState) -> None:
        """After a converged step short of factor 1: checkpoint, stop on a signal."""
        ...


def _check_space(V: dolfinx.fem.FunctionSpace) -> int:
    """The displacement degree; refuses what the solver is not valid for (RunError)."""
    mesh = V.mesh
    gdim = mesh.geometry.dim
    if mesh.topology.dim != gdim or gdim not in LAYOUTS:
        raise RunError(
            "plasticity: the elasto-plastic solver takes plane strain (2D) or 3D solid "
            f"meshes, got a {mesh.topology.dim}D mesh in {gdim}D"
        )
    element = V.ufl_element()
    family = element.basix_element.family
    degree = int(element.embedded_superdegree)
    if family != basix.ElementFamily.P or degree < 2 or element.basix_element.discontinuous:
        raise RunError(
            "plasticity: needs continuous Lagrange displacements of degree >= 2 (P2); P1 "
            "triangles lock under incompressible plastic flow (psi = 0) and the enriched or "
            "gradient elements have no quadrature-point stress update"
        )
    return degree


class PlasticProblem:
    """The elasto-plastic problem on a displacement space.

    Args:
        V: vector Lagrange space of degree >= 2 on a 2D (plane strain) or 3D mesh.
        law: the plastic law (its E, ν are the elasticity).
        external: (load factor constant, test function) → the external work form at that
            factor (e.g. tractions that move from their initial to final values).
        bcs: Dirichlet conditions; their values g are ramped with the load factor (λ g
            at factor λ: a prescribed displacement under displacement control; zero
            supports are held) and restored to g when :meth:`solve_steps` ends.
        initial_stress: σ₀ at u = 0 (in equilibrium with the external loads at factor
            0): a constant array, shape=(3, 3), a 3×3 UFL tensor (interpolated at the
            quadrature points; :mod:`geofrac.fem.insitu`'s field), or None for zero.
        prefix: PETSc options prefix of the Newton solver.
        options: user PETSc options (without prefix).
        joints: Coulomb springs across split joints (:class:`geofrac.fem.joints.JointInterface`),
            updated with the quadrature points and committed with them, or None.
        gravity: a gravity phase run by :meth:`solve_steps` before the analysis (the
            displacements reset between them: :meth:`reset_displacement`), or None.
            Not with ``initial_stress`` (a K0 start is the alternative).
        alive: construction stages (docs/plasticity.md, "Construction stages"): a DG0
            indicator (1 live, 0 removed) multiplying the internal force and the
            tangent (the external work's density is the caller's), with the stages'
            release in the residual (:meth:`solve_stage`), or None. Not with ``joints``.
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        law: Law,
        external: Callable[[dolfinx.fem.Constant, Any], ufl.Form],
        *,
        bcs: Sequence[dolfinx.fem.DirichletBC] = (),
        initial_stress: Any = None,
        prefix: str = "geofrac_plastic_",
        options: dict[str, str] | None = None,
        atol: float = 1e-10,
        rtol: float = 1e-9,
        max_it: int = 25,
        joints: JointInterface | None = None,
        gravity: GravityPhase | None = None,
        alive: dolfinx.fem.Function | None = None,
    ) -> None:
        degree = _check_space(V)
        if alive is not None and joints is not None:
            raise RunError("plasticity: construction stages do not take joints yet")
        if gravity is not None and initial_stress is not None:
            raise RunError(
                "plasticity: a gravity phase takes no initial stress (the K0 start is the "
                "alternative to a gravity phase)"
            )
        self.joints, self.gravity = joints, gravity
        #: the gravity phase is running: the Dirichlet values are held at 0.
        self._in_gravity = False
        #: the stage being solved (its name), or None: the Dirichlet values held in full.
        self._stage: str | None = None
        #: :meth:`solve_steps` runs the gravity phase only (``analysis`` False).
        self._skip_analysis = False
        self.alive = alive
        self.V, self.law, self.mesh = V, law, V.mesh
        self.comm: MPI.Comm = V.mesh.comm
        qdeg = 2 * (degree - 1)
        self._qdeg = qdeg
        self._yielded: dolfinx.fem.Function | None = None
        self._area: dolfinx.fem.Form | None = None
        cell = self.mesh.basix_cell()
        self.dx = ufl.Measure(
            "dx",
            domain=self.mesh,
            metadata={"quadrature_degree": qdeg, "quadrature_scheme": "default"},
        )
        gdim = self.mesh.geometry.dim
        self.layout = layout = LAYOUTS[gdim]
        ns, ne = len(layout.stress), len(layout.strain)

        def space(size: int) -> dolfinx.fem.FunctionSpace:
            element = basix.ufl.quadrature_element(cell, value_shape=(size,), degree=qdeg)
            return dolfinx.fem.functionspace(self.mesh, element)

        Qe = space(ne)
        self.u = dolfinx.fem.Function(V, name="displacement")
        self.sig = dolfinx.fem.Function(space(ns), name="stress")
        self.tan = dolfinx.fem.Function(space(ne * ne), name="tangent")
        self.eps = dolfinx.fem.Function(Qe, name="strain")
        eps_u = ufl.sym(ufl.grad(self.u))
        self._eps_expr = dolfinx.fem.Expression(
            ufl.as_vector([eps_u[i, j] for i, j in layout.strain]),
            Qe.element.interpolation_points,
        )
        n = self.eps.x.array.size // ne
        #: converged stress σₙ and strain εₙ at every local quadrature point, shape=(n, 3, 3).
        self.stress_n = self._initial(initial_stress, n, cell, qdeg)
        self.strain_n = np.zeros((n, 3, 3))
        #: accumulated plastic strain, shape=(n, 3, 3).
        self.plastic_strain = np.zeros((n, 3, 3))
        #: local quadrature points of removed cells (their state frozen), shape=(n,).
        self.dead = np.zeros(n, dtype=bool)
        self._ret: Any = None
        #: (writable view of each Dirichlet value, its full value g), shape=(k,) each.
        self._bc_values = [(view, view.copy()) for view in map(_bc_view, bcs)]
        self.factor = dolfinx.fem.Constant(self.mesh, SCALAR(0.0))
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        index = {pair: k for k, pair in enumerate(layout.stress)}
        index.update({(j, i): k for (i, j), k in list(index.items())})
        sigma = ufl.as_tensor([[self.sig[index[i, j]] for j in range(gdim)] for i in range(gdim)])

        def voigt(w: Any) -> Any:
            e = ufl.sym(ufl.grad(w))
            return ufl.as_vector([e[i, j] if i == j else 2 * e[i, j] for i, j in layout.strain])

        D = ufl.as_matrix([[self.tan[ne * i + j] for j in range(ne)] for i in range(ne)])
        internal = ufl.inner(sigma, ufl.sym(ufl.grad(v)))
        tangent = ufl.inner(D * voigt(du), voigt(v))
        if alive is not None:  # removed cells carry nothing
            internal, tangent = alive * internal, alive * tangent
        F = internal * self.dx - external(self.factor, v)
        J = tangent * self.dx
        self.release = None if alive is None else StageRelease(V, self.factor)
        self._update()  # the initial state's stress and tangent
        self.newton = NewtonSolver(
            dolfinx.fem.form(F),
            dolfinx.fem.form(J),
            self.u,
            bcs=bcs,
            update=self._update,
            prefix=prefix,
            options=options,
            atol=atol,
            rtol=rtol,
            max_it=max_it,
            extra=joints if self.release is None else self.release,
            watchdog=joints is not None,
        )

    def _initial(self, initial_stress: Any, n: int, cell: Any, qdeg: int) -> np.ndarray:
        """σ₀ at every local quadrature point, shape=(n, 3, 3).

        From a constant (3, 3) array, a 3×3 UFL tensor (e.g. the in-situ field) or None (zero).
        """
        if initial_stress is None:
            return np.zeros((n, 3, 3))
        if isinstance(initial_stress, np.ndarray):
            return np.broadcast_to(initial_stress, (n, 3, 3)).copy()
        element = basix.ufl.quadrature_element(cell, value_shape=(9,), degree=qdeg)
        Q9 = dolfinx.fem.functionspace(self.mesh, element)
        field = dolfinx.fem.Function(Q9)
        flat = ufl.as_vector([initial_stress[i, j] for i in range(3) for j in range(3)])
        field.interpolate(dolfinx.fem.Expression(flat, Q9.element.interpolation_points))
        return field.x.array.reshape(n, 3, 3).copy()

    def _update(self) -> None:
        """Return-map every quadrature point at the current u; fill stress and tangent."""
        layout = self.layout
        self.eps.interpolate(self._eps_expr)
        e = self.eps.x.array.reshape(-1, len(layout.strain))
        eps = np.zeros((e.shape[0], 3, 3))
        for k, (i, j) in enumerate(layout.strain):
            eps[:, i, j] = eps[:, j, i] = e[:, k]
        dead = self.dead
        eps[dead] = self.strain_n[dead]  # removed cells: no strain increment
        ret = self.law.update(self.stress_n, eps - self.strain_n, tangent=True)
        ret.stress[dead], ret.kind[dead], ret.plastic_strain[dead] = self.stress_n[dead], 0, 0.0
        self._ret, self._eps_now = ret, eps
        st = self.sig.x.array.reshape(-1, len(layout.stress))
        for k, (i, j) in enumerate(layout.stress):
            st[:, k] = ret.stress[:, i, j]
        assert ret.tangent is not None  # asked for
        rows = list(layout.voigt)
        D = to_voigt(ret.tangent)[:, rows][:, :, rows]
        self.tan.x.array[:] = D.reshape(-1)
        if self.joints is not None:
            self.joints.update(self.u)

    def state(self) -> dict[str, np.ndarray]:
        """This rank's arrays of the converged state (local, with ghosts).

        ``u`` shape=(dofs × gdim,); ``stress_n``, ``strain_n``, ``plastic_strain``
        shape=(n, 3, 3) at the local quadrature points; with joints ``joint_slip``, the
        committed slip of every pair, shape=(pairs,), and with a gravity phase also
        ``joint_offset``, the jump kept at the reset, shape=(pairs, 2) (the same on every
        rank).
        """
        arrays = {
            "u": self.u.x.array.copy(),
            "stress_n": self.stress_n.copy(),
            "strain_n": self.strain_n.copy(),
            "plastic_strain": self.plastic_strain.copy(),
        }
        if self.joints is not None:
            arrays["joint_slip"] = self.joints.slip_n.copy()
            if self.gravity is not None:
                arrays["joint_offset"] = self.joints.offset.copy()
        return arrays

    def set_state(self, arrays: dict[str, np.ndarray], factor: float) -> None:
        """Put back a :meth:`state` reached at load ``factor`` (same mesh distribution)."""
        self.u.x.array[:] = arrays["u"]
        self.stress_n = np.array(arrays["stress_n"], dtype=float)
        self.strain_n = np.array(arrays["strain_n"], dtype=float)
        self.plastic_strain = np.array(arrays["plastic_strain"], dtype=float)
        if self.joints is not None:
            self.joints.slip_n = np.array(arrays["joint_slip"], dtype=float)
            if self.gravity is not None:
                self.joints.offset = np.array(arrays["joint_offset"], dtype=float)
        self.factor.value = factor
        self._update()

    def _commit(self) -> int:
        """Accept the current state as converged; the number of plastic points (all ranks)."""
        self._update()
        ret = self._ret
        self.stress_n = ret.stress.copy()
        self.strain_n = self._eps_now.copy()
        self.plastic_strain += ret.plastic_strain
        if self.joints is not None:
            self.joints.commit()
        owned = self.eps.function_space.dofmap.index_map.size_local
        return int(self.comm.allreduce(int(np.count_nonzero(ret.kind[:owned])), op=MPI.SUM))

    def plastic_shear_strain(self) -> np.ndarray:
        """√(2/3 dev εᵖ : dev εᵖ) accumulated, at every local quadrature point, shape=(n,)."""
        ep = self.plastic_strain
        dev = ep - np.trace(ep, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
        return np.sqrt(2.0 / 3.0 * np.sum(dev * dev, axis=(1, 2)))

    def plastic_points(self) -> int:
        """Owned quadrature points (all ranks) with accumulated plastic strain."""
        owned = self.eps.function_space.dofmap.index_map.size_local
        yielded = (self.plastic_shear_strain() > 0.0) & ~self.dead
        local = int(np.count_nonzero(yielded[:owned]))
        return int(self.comm.allreduce(local, op=MPI.SUM))

    def yielded_area(self) -> float:
        """∫ 1[the point has yielded] dx over the mesh (all ranks), with the solver's rule."""
        if self._yielded is None:
            cell = self.mesh.basix_cell()
            element = basix.ufl.quadrature_element(cell, value_shape=(), degree=self._qdeg)
            self._yielded = dolfinx.fem.Function(dolfinx.fem.functionspace(self.mesh, element))
            self._area = dolfinx.fem.form(self._yielded * self.dx)
        self._yielded.x.array[:] = (self.plastic_shear_strain() > 0.0) & ~self.dead
        local = dolfinx.fem.assemble_scalar(self._area)
        return float(self.comm.allreduce(local, op=MPI.SUM))

    def ellipticity(self) -> tuple[int, int]:
        """(owned plastic points whose tangent lost ellipticity, owned plastic points), all ranks.

        At the current state's returns (:func:`geofrac.plasticity.ellipticity.lost_ellipticity`;
        in-plane normals in plane strain, all in 3D): non-associated flow (ψ < φ) loses it
        at plastic points, where the rate problem need not have a unique solution.
        """
        ret = self._ret
        owned = self.eps.function_space.dofmap.index_map.size_local
        plastic = np.flatnonzero(ret.kind[:owned] > 0)
        _, G = self.law.moduli()
        lost = lost_ellipticity(ret.tangent[plastic], shear_modulus=G, dim=self.mesh.geometry.dim)
        counts = np.array([np.count_nonzero(lost), len(plastic)], dtype=np.int64)
        total = self.comm.allreduce(counts, op=MPI.SUM)
        return int(total[0]), int(total[1])

    def solve_steps(
        self,
        steps: int,
        *,
        max_cuts: int = 4,
        say: Callable[[str], None] | None = None,
        monitor: Callable[[dolfinx.fem.Function], np.ndarray] | None = None,
        observe: Callable[[PlasticProblem], Any] | None = None,
        hooks: StepHooks | None = None,
        analysis: bool = True,
    ) -> PlasticResult:
        """Load factor 0 → 1 in ``steps`` increments, halving a diverged increment.

        ``say`` receives one line per attempted step (the caller prints on rank 0);
        ``observe`` (collective) is called after each accepted step, its value kept in
        the step's record (JSON-ready: it is checkpointed). The Dirichlet values are λ g
        during the run, g after it. ``hooks``: a checkpoint to continue from, and the
        poll after each converged step (:mod:`geofrac.fem.plastic_checkpoint`).
        ``analysis`` False: nothing to ramp (construction stages follow, with no loads and
        no prescribed displacements): only the gravity phase, if any, is run (an analysis
        from an equilibrium at round-off would never meet Newton's tolerances).

        Returns:
            the result; ``converged = False`` with the last converged factor when an
            increment cut ``max_cuts`` times still diverged (the state is the last
            converged one).
        """
        try:
            if not analysis and self.gravity is None:
                return PlasticResult(True, 1.0, "converged", [], self._monitor(monitor))
            self._skip_analysis = not analysis
            return self._steps(
                steps, max_cuts=max_cuts, say=say, monitor=monitor, observe=observe, hooks=hooks
            )
        finally:
            self._ramp_bcs(1.0)

    def _ramp_bcs(self, factor: float) -> None:
        """Set every Dirichlet value to ``factor`` times its full value g (gravity phase: 0)."""
        scale = 0.0 if self._in_gravity else (1.0 if self._stage is not None else factor)
        for view, full in self._bc_values:
            view[...] = scale * full

    def reset_displacement(self) -> None:
        """The end of the gravity phase: u = 0 and εₙ = 0, σₙ and the plastic strain kept.

        The stress at every point is then σₙ (a zero strain increment from the
        committed state), in equilibrium with the gravity phase's loads; the
        analysis's displacement is measured from here. The joints keep their jump
        (:meth:`~geofrac.fem.joints.JointInterface.keep_jump`): their forces unchanged.
        """
        if self.joints is not None:
            self.joints.keep_jump()
        self.u.x.array[:] = 0.0
        self.strain_n[...] = 0.0
        self.factor.value = 0.0
        self._update()

    def _max_displacement(self) -> float:
        """The largest nodal |u| over the owned nodes (all ranks)."""
        bs = self.V.dofmap.index_map_bs
        owned = self.V.dofmap.index_map.size_local
        nodes = self.u.x.array[: owned * bs].reshape(-1, bs)
        local = float(np.linalg.norm(nodes, axis=1).max()) if len(nodes) else 0.0
        return float(self.comm.allreduce(local, op=MPI.MAX))

    def _steps(
        self,
        steps: int,
        *,
        max_cuts: int,
        say: Callable[[str], None] | None,
        monitor: Callable[[dolfinx.fem.Function], np.ndarray] | None,
        observe: Callable[[PlasticProblem], Any] | None,
        hooks: StepHooks | None,
    ) -> PlasticResult:
        """The phases of :meth:`solve_steps` (the Dirichlet values left ramped).

        With a gravity phase: unless the checkpoint is of the analysis, the gravity
        phase (switch 0, no observe), the reset, then the analysis (switch 1).
        """
        start = None if hooks is None else hooks.restore(self)
        loop: dict[str, Any] = {
            "max_cuts": max_cuts,
            "say": say,
            "monitor": monitor,
            "hooks": hooks,
        }
        if self.gravity is None:
            return self._phase(steps, start, observe=observe, **loop)
        gravity = None if start is None else start.gravity
        if gravity is None:  # not yet through the gravity phase
            self._in_gravity, self.gravity.switch.value = True, 0.0
            try:
                first = self._phase(self.gravity.steps, start, observe=None, **loop)
            finally:
                self._in_gravity = False
            gravity = GravityRecord(
                first.steps,
                first.converged,
                first.factor,
                self._max_displacement(),
                self.plastic_points(),
            )
            if not first.converged:
                return PlasticResult(
                    False,
                    0.0,
                    "gravity_step_too_small",
                    [],
                    first.monitor,
                    first.ellipticity,
                    gravity,
                )
            self.reset_displacement()
            start = LoadState(0.0, 1.0 / steps, [], gravity=gravity)
            if say is not None:
                say(
                    f"plastic: gravity phase done (max |u| {gravity.max_displacement:.4e}, "
                    f"{gravity.plastic_points} plastic points); displacements reset"
                )
        self.gravity.switch.value = 1.0
        if self._skip_analysis:
            self.factor.value = 1.0
            return PlasticResult(True, 1.0, "converged", [], self._monitor(monitor), None, gravity)
        result = self._phase(steps, start, observe=observe, **loop)
        result.gravity = gravity
        return result

    def _phase(
        self,
        steps: int,
        start: LoadState | None,
        *,
        max_cuts: int,
        say: Callable[[str], None] | None,
        monitor: Callable[[dolfinx.fem.Function], np.ndarray] | None,
        observe: Callable[[PlasticProblem], Any] | None,
        hooks: StepHooks | None,
    ) -> PlasticResult:
        """One phase's load factor 0 → 1 from ``start`` (a checkpoint's state, or None)."""
        phase = "gravity" if self._in_gravity else "analysis"
        label = "" if self.gravity is None else f" ({phase} phase)"
        if self._stage is not None:
            label = f" (stage '{self._stage}')"
        gravity = None if start is None else start.gravity
        records: list[StepRecord] = [] if start is None else list(start.records)
        done, inc, cuts = (0.0, 1.0 / steps, 0) if start is None else (start.done, start.inc, 0)
        t0, done0 = time.perf_counter(), done
        while done < 1.0 - 1e-12:
            target = min(1.0, done + inc)
            u_saved = self.u.x.array.copy()
            self.factor.value = target
            self._ramp_bcs(target)
            report = self.newton.solve()
            if report.converged:
                plastic = self._commit()
                seen = None if observe is None else observe(self)
                records.append(StepRecord(target, report, True, plastic, seen))
                done, cuts = target, 0
                if say is not None:
                    eta = (time.perf_counter() - t0) * (1.0 - done) / (done - done0)
                    say(
                        f"plastic{label}: factor {done:.4f} converged ({report.reason_name}, "
                        f"{report.iterations} its, |F| {report.residuals[-1]:.2e}), "
                        f"{plastic} plastic points, ETA {eta:.1f} s"
                    )
                if hooks is not None and done < 1.0 - 1e-12:
                    hooks.after_step(self, LoadState(done, inc, records, phase, gravity))
                continue
            records.append(StepRecord(target, report, False, 0))
            self.u.x.array[:] = u_saved
            self.factor.value = done
            self._ramp_bcs(done)
            self._update()
            stop = cuts >= max_cuts
            lost = self.ellipticity() if stop else None
            if say is not None:
                what = "giving up" if stop else f"cut {cuts + 1}/{max_cuts}"
                if lost is not None and lost[0]:
                    what += (
                        f"; the tangent has lost ellipticity at {lost[0]} of {lost[1]} "
                        "plastic points (non-associated flow: docs/plasticity.md)"
                    )
                say(f"plastic{label}: factor {target:.4f} diverged ({report.reason_name}), {what}")
            if stop:
                return PlasticResult(
                    False, done, "step_too_small", records, self._monitor(monitor), lost
                )
            inc, cuts = inc / 2, cuts + 1
        return PlasticResult(True, 1.0, "converged", records, self._monitor(monitor))

    def residual(self) -> np.ndarray:
        """F(u; ·) = I(σ) − λ-scaled external forces without the Dirichlet rows replaced.

        At the current state (after a converged step: the committed stress). On the
        held DOFs its sum is the reaction the supports carry (collective), owned entries,
        shape=(owned nodes × gdim,).
        """
        vec = dolfinx.fem.assemble_vector(self.newton.F)
        vec.scatter_reverse(dolfinx.la.InsertMode.add)
        imap = self.V.dofmap.index_map
        out = vec.array[: imap.size_local * self.V.dofmap.index_map_bs].copy()
        if self.release is not None:  # a stage's pending release
            out += self.release.values()
        return out

    def set_alive(self) -> None:
        """Take the removed cells from ``alive``: their points' state frozen from now on."""
        assert self.alive is not None
        alive = self.alive
        cells = np.flatnonzero(alive.x.array[alive.function_space.dofmap.list[:, 0]] < 0.5)
        points = self.eps.function_space.dofmap.list[cells.astype(np.int32)].ravel()
        self.dead[:] = False
        self.dead[points] = True
        self._update()

    def solve_stage(
        self,
        name: str,
        steps: int,
        *,
        max_cuts: int = 4,
        say: Callable[[str], None] | None = None,
        observe: Callable[[PlasticProblem], Any] | None = None,
    ) -> PlasticResult:
        """Apply the share set in :attr:`release` in ``steps`` increments (λ 0 → 1).

        The loads and Dirichlet values are held in full (the caller's external work must
        hold the loads); the cuts and the verdict are those of :meth:`solve_steps`.
        """
        self._stage = name
        try:
            self.factor.value = 0.0
            self._ramp_bcs(0.0)
            return self._phase(
                steps, None, max_cuts=max_cuts, say=say, monitor=None, observe=observe, hooks=None
            )
        finally:
            self._stage = None

    def _monitor(self, monitor: Callable[[dolfinx.fem.Function], np.ndarray] | None) -> Any:
        return None if monitor is None else monitor(self.u)

    def destroy(self) -> None:
        """Free the Newton solver's PETSc objects."""
        self.newton.destroy()


def solve_plastic(
    problem_factory: Callable[[Law], PlasticProblem],
    law: Law,
    *,
    steps: int,
    monitor: Callable[[dolfinx.fem.Function], np.ndarray] | None = None,
    max_cuts: int = 4,
    hooks: StepHooks | None = None,
) -> PlasticResult:
    """Build the problem for ``law`` (e.g. reduced c, φ), solve it and free it.

    The entry point for strength reduction: whether the load steps converged and the
    monitor displacement, with every PETSc object destroyed. ``hooks``: checkpoint and
    resume (:meth:`PlasticProblem.solve_steps`).
    """
    problem = problem_factory(law)
    try:
        return problem.solve_steps(steps, max_cuts=max_cuts, monitor=monitor, hooks=hooks)
    finally:
        problem.destroy()
