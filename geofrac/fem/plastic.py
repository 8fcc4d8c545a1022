"""Elasto-plastic static solve: return mapping at quadrature points, Newton through SNES.

Plane strain (2D) with P2 displacements (or higher Lagrange degree); the stress and the
consistent tangent live in DOLFINx quadrature spaces (``basix.ufl.quadrature_element``)
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
whether it converged and the monitor displacement. See docs/plasticity.md.
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
from geofrac.plasticity import DruckerPrager, MohrCoulomb
from geofrac.plasticity.davis import Davis
from geofrac.plasticity.elasticity import to_voigt
from geofrac.plasticity.ellipticity import lost_ellipticity
from geofrac.solvers.snes import NewtonReport, NewtonSolver
from geofrac.solvers.types import SCALAR

__all__ = [
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

Law = MohrCoulomb | DruckerPrager | Davis


@dataclass
class StepRecord:
    """One attempted load increment.

    Attributes:
        factor: the load factor tried.
        report: its Newton report (reason, residual norms).
        accepted: whether it was committed.
        plastic_points: quadrature points (all ranks) whose return was plastic.
    """

    factor: float
    report: NewtonReport
    accepted: bool
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
    """

    converged: bool
    factor: float
    end_reason: str
    steps: list[StepRecord] = field(default_factory=list)
    monitor: np.ndarray | None = None
    ellipticity: tuple[int, int] | None = None


@dataclass
class LoadState:
    """Where a load-stepped solve stands after a converged step (checkpoint and resume).

    Attributes:
        done: the last converged load factor.
        inc: the current increment (halved by cuts, kept once a step converges).
        records: every attempted step so far.
    """

    done: float
    inc: float
    records: list[StepRecord]


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
    if mesh.topology.dim != 2 or gdim != 2:
        raise RunError(
            "plasticity: the elasto-plastic solver is plane strain (2D) only; 3D is not built "
            "(its stress storage and forms would need the 6-component Voigt form)"
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
        V: vector Lagrange space of degree >= 2 on a 2D mesh (plane strain).
        law: the plastic law (its E, ν are the elasticity).
        external: (load factor constant, test function) → the external work form at that
            factor (e.g. tractions that move from their initial to final values).
        bcs: Dirichlet conditions (held through the steps).
        initial_stress: σ₀ at u = 0 (in equilibrium with the external loads at factor
            0): a constant array, shape=(3, 3), a 3×3 UFL tensor (interpolated at the
            quadrature points; :mod:`geofrac.fem.insitu`'s field), or None for zero.
        prefix: PETSc options prefix of the Newton solver.
        options: user PETSc options (without prefix).
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
    ) -> None:
        degree = _check_space(V)
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
        Qs = dolfinx.fem.functionspace(
            self.mesh, basix.ufl.quadrature_element(cell, value_shape=(4,), degree=qdeg)
        )
        Qt = dolfinx.fem.functionspace(
            self.mesh, basix.ufl.quadrature_element(cell, value_shape=(9,), degree=qdeg)
        )
        Qe = dolfinx.fem.functionspace(
            self.mesh, basix.ufl.quadrature_element(cell, value_shape=(3,), degree=qdeg)
        )
        self.u = dolfinx.fem.Function(V, name="displacement")
        self.sig = dolfinx.fem.Function(Qs, name="stress")
        self.tan = dolfinx.fem.Function(Qt, name="tangent")
        self.eps = dolfinx.fem.Function(Qe, name="strain")
        eps_u = ufl.sym(ufl.grad(self.u))
        self._eps_expr = dolfinx.fem.Expression(
            ufl.as_vector([eps_u[0, 0], eps_u[1, 1], eps_u[0, 1]]),
            Qe.element.interpolation_points,
        )
        n = self.eps.x.array.size // 3
        #: converged stress σₙ and strain εₙ at every local quadrature point, shape=(n, 3, 3).
        self.stress_n = self._initial(initial_stress, n, cell, qdeg)
        self.strain_n = np.zeros((n, 3, 3))
        #: accumulated plastic strain, shape=(n, 3, 3).
        self.plastic_strain = np.zeros((n, 3, 3))
        self._ret: Any = None
        self.factor = dolfinx.fem.Constant(self.mesh, SCALAR(0.0))
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        s = self.sig
        sigma = ufl.as_tensor([[s[0], s[3]], [s[3], s[1]]])

        def voigt(w: Any) -> Any:
            e = ufl.sym(ufl.grad(w))
            return ufl.as_vector([e[0, 0], e[1, 1], 2 * e[0, 1]])

        D = ufl.as_matrix([[self.tan[3 * i + j] for j in range(3)] for i in range(3)])
        F = ufl.inner(sigma, ufl.sym(ufl.grad(v))) * self.dx - external(self.factor, v)
        J = ufl.inner(D * voigt(du), voigt(v)) * self.dx
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
        self.eps.interpolate(self._eps_expr)
        e = self.eps.x.array.reshape(-1, 3)
        eps = np.zeros((e.shape[0], 3, 3))
        eps[:, 0, 0], eps[:, 1, 1] = e[:, 0], e[:, 1]
        eps[:, 0, 1] = eps[:, 1, 0] = e[:, 2]
        ret = self.law.update(self.stress_n, eps - self.strain_n, tangent=True)
        self._ret, self._eps_now = ret, eps
        st = self.sig.x.array.reshape(-1, 4)
        for k, (i, j) in enumerate(STRESS_2D):
            st[:, k] = ret.stress[:, i, j]
        assert ret.tangent is not None  # asked for
        D = to_voigt(ret.tangent)[:, VOIGT_2D][:, :, VOIGT_2D]
        self.tan.x.array[:] = D.reshape(-1)

    def state(self) -> dict[str, np.ndarray]:
        """This rank's arrays of the converged state (local, with ghosts).

        ``u`` shape=(dofs × gdim,); ``stress_n``, ``strain_n``, ``plastic_strain``
        shape=(n, 3, 3) at the local quadrature points.
        """
        return {
            "u": self.u.x.array.copy(),
            "stress_n": self.stress_n.copy(),
            "strain_n": self.strain_n.copy(),
            "plastic_strain": self.plastic_strain.copy(),
        }

    def set_state(self, arrays: dict[str, np.ndarray], factor: float) -> None:
        """Put back a :meth:`state` reached at load ``factor`` (same mesh distribution)."""
        self.u.x.array[:] = arrays["u"]
        self.stress_n = np.array(arrays["stress_n"], dtype=float)
        self.strain_n = np.array(arrays["strain_n"], dtype=float)
        self.plastic_strain = np.array(arrays["plastic_strain"], dtype=float)
        self.factor.value = factor
        self._update()

    def _commit(self) -> int:
        """Accept the current state as converged; the number of plastic points (all ranks)."""
        self._update()
        ret = self._ret
        self.stress_n = ret.stress.copy()
        self.strain_n = self._eps_now.copy()
        self.plastic_strain += ret.plastic_strain
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
        local = int(np.count_nonzero(self.plastic_shear_strain()[:owned] > 0.0))
        return int(self.comm.allreduce(local, op=MPI.SUM))

    def yielded_area(self) -> float:
        """∫ 1[the point has yielded] dx over the mesh (all ranks), with the solver's rule."""
        if self._yielded is None:
            cell = self.mesh.basix_cell()
            element = basix.ufl.quadrature_element(cell, value_shape=(), degree=self._qdeg)
            self._yielded = dolfinx.fem.Function(dolfinx.fem.functionspace(self.mesh, element))
            self._area = dolfinx.fem.form(self._yielded * self.dx)
        self._yielded.x.array[:] = self.plastic_shear_strain() > 0.0
        local = dolfinx.fem.assemble_scalar(self._area)
        return float(self.comm.allreduce(local, op=MPI.SUM))

    def ellipticity(self) -> tuple[int, int]:
        """(owned plastic points whose tangent lost ellipticity, owned plastic points), all ranks.

        At the current state's returns (:func:`geofrac.plasticity.ellipticity.lost_ellipticity`,
        in-plane normals, scale G²): non-associated flow (ψ < φ) loses it at plastic
        points, where the rate problem need not have a unique solution.
        """
        ret = self._ret
        owned = self.eps.function_space.dofmap.index_map.size_local
        plastic = np.flatnonzero(ret.kind[:owned] > 0)
        _, G = self.law.moduli()
        lost = lost_ellipticity(ret.tangent[plastic], shear_modulus=G, dim=2)
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
        hooks: StepHooks | None = None,
    ) -> PlasticResult:
        """Load factor 0 → 1 in ``steps`` increments, halving a diverged increment.

        ``say`` receives one line per attempted step (the caller prints on rank 0).
        ``hooks``: a checkpoint to continue from, and the poll after each converged step
        (:mod:`geofrac.fem.plastic_checkpoint`).

        Returns:
            the result; ``converged = False`` with the last converged factor when an
            increment cut ``max_cuts`` times still diverged (the state is the last
            converged one).
        """
        start = None if hooks is None else hooks.restore(self)
        records: list[StepRecord] = [] if start is None else list(start.records)
        done, inc, cuts = (0.0, 1.0 / steps, 0) if start is None else (start.done, start.inc, 0)
        t0, done0 = time.perf_counter(), done
        while done < 1.0 - 1e-12:
            target = min(1.0, done + inc)
            u_saved = self.u.x.array.copy()
            self.factor.value = target
            report = self.newton.solve()
            if report.converged:
                plastic = self._commit()
                records.append(StepRecord(target, report, True, plastic))
                done, cuts = target, 0
                if say is not None:
                    eta = (time.perf_counter() - t0) * (1.0 - done) / (done - done0)
                    say(
                        f"plastic: factor {done:.4f} converged ({report.reason_name}, "
                        f"{report.iterations} its, |F| {report.residuals[-1]:.2e}), "
                        f"{plastic} plastic points, ETA {eta:.1f} s"
                    )
                if hooks is not None and done < 1.0 - 1e-12:
                    hooks.after_step(self, LoadState(done, inc, records))
                continue
            records.append(StepRecord(target, report, False, 0))
            self.u.x.array[:] = u_saved
            self.factor.value = done
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
                say(f"plastic: factor {target:.4f} diverged ({report.reason_name}), {what}")
            if stop:
                return PlasticResult(
                    False, done, "step_too_small", records, self._monitor(monitor), lost
                )
            inc, cuts = inc / 2, cuts + 1
        return PlasticResult(True, 1.0, "converged", records, self._monitor(monitor))

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
