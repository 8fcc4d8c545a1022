"""The linear elastic problem of a scene: forms, boundary conditions, assembly, solve."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import ufl
from mpi4py import MPI
from petsc4py import PETSc

from geofrac import elements
from geofrac.analytic import ExactSolution, displacement_gradient, make_exact
from geofrac.elements.base import Element
from geofrac.elements.kinematics import dofs_from_gradient
from geofrac.errors import RunError
from geofrac.materials import lame
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Scene
from geofrac.solvers import LinearSolver, rigid_body_modes
from geofrac_forms import elasticity as forms
from geofrac_forms.gradient_dofs import penalty_forms

__all__ = [
    "ElasticProblem",
    "FormContext",
    "GradientDofProblem",
    "LinearTerm",
    "exact_ufl",
    "make_problem",
]

#: options prefix of the elastic solver.
PREFIX = "geofrac_elastic_"


@dataclass(frozen=True)
class FormContext:
    """What an effect's ``linear_form`` hook may use.

    Attributes:
        mesh: the DOLFINx mesh.
        v: test function.
        dx: cell measure.
        thickness: thickness constant t.
    """

    mesh: dolfinx.mesh.Mesh
    v: Any
    dx: Any
    thickness: Any

    def constant(self, value: float) -> dolfinx.fem.Constant:
        """A scalar DOLFINx constant on the mesh."""
        return dolfinx.fem.Constant(self.mesh, PETSc.ScalarType(value))

    def vector(self, values: tuple[float, ...]) -> dolfinx.fem.Constant:
        """A vector DOLFINx constant on the mesh, shape=(gdim,)."""
        return dolfinx.fem.Constant(self.mesh, np.asarray(values, dtype=PETSc.ScalarType))


#: A right-hand-side term added to the loads (an effect's ``linear_form`` bound to its
#: config by the run pipeline, :func:`geofrac.runner.linear_terms`).
LinearTerm = Callable[[FormContext], ufl.Form]


def exact_ufl(exact: ExactSolution, mesh: dolfinx.mesh.Mesh) -> tuple[Any, Any]:
    """(displacement vector, stress tensor) of an exact solution as UFL expressions."""
    x = ufl.SpatialCoordinate(mesh)
    coords = [x[i] for i in range(mesh.geometry.dim)]
    return ufl.as_vector(exact.displacement(*coords)), ufl.as_matrix(exact.stress(*coords))


class ElasticProblem:
    """Linear elasticity of a validated scene on a distributed mesh.

    Phases are separate methods so that callers can time them: :meth:`compile` (JIT of
    the forms), :meth:`assemble`, :meth:`solve`. Call :meth:`destroy` when done.

    Args:
        tagged: the distributed mesh with its physical groups.
        element: the displacement discretisation.
        scene: the validated scene (material, loads, bcs, solver).
        terms: right-hand-side terms beyond the scene's loads (the effects', e.g. gravity).
    """

    def __init__(
        self,
        tagged: TaggedMesh,
        element: Element,
        scene: Scene,
        terms: Sequence[LinearTerm] = (),
    ) -> None:
        self.tagged, self.element, self.scene = tagged, element, scene
        self.terms = tuple(terms)
        mesh = tagged.mesh
        self.mesh = mesh
        self.comm: MPI.Comm = mesh.comm
        V = element.space
        mat = scene.material
        gdim = mesh.geometry.dim
        lam, mu = lame(mat.E, mat.nu, gdim, mat.plane)
        self.lam = dolfinx.fem.Constant(mesh, PETSc.ScalarType(lam))
        self.mu = dolfinx.fem.Constant(mesh, PETSc.ScalarType(mu))
        self.thickness = dolfinx.fem.Constant(
            mesh, PETSc.ScalarType(mat.thickness if gdim == 2 else 1.0)
        )
        q = scene.discretization.quadrature_degree
        self.dx = ufl.Measure(
            "dx", domain=mesh, metadata={} if q is None else {"quadrature_degree": q}
        )
        fdim = mesh.topology.dim - 1
        self.ds = ufl.Measure("ds", domain=mesh, subdomain_data=tagged.tags.get(fdim))
        self.exact = (
            make_exact(scene.exact.name, scene.exact.parameters, mat.E, mat.nu, mat.plane)
            if scene.exact is not None
            else None
        )
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        self._a = forms.stiffness_form(u, v, self.lam, self.mu, self.thickness, self.dx)
        self._L = self._linear_form(v)
        self.bcs = self._boundary_conditions()
        self.uh = dolfinx.fem.Function(V, name="displacement")
        self.a: dolfinx.fem.Form | None = None
        self.L: dolfinx.fem.Form | None = None
        self.A: PETSc.Mat | None = None
        self.b: PETSc.Vec | None = None
        self.solver: LinearSolver | None = None
        self.iterations = 0

    def _linear_form(self, v: Any) -> Any:
        mesh, gdim = self.mesh, self.mesh.geometry.dim
        terms = []
        for load in self.scene.loads:
            if load.value == "exact":
                assert self.exact is not None
                u_ex, sig = exact_ufl(self.exact, mesh)
                if load.type == "traction":
                    value = sig * ufl.FacetNormal(mesh)
                else:  # the body force that makes u_exact an equilibrium state
                    value = -ufl.div(forms.sigma(u_ex, self.lam, self.mu))
            else:
                value = dolfinx.fem.Constant(mesh, np.asarray(load.value, dtype=PETSc.ScalarType))
            if load.type == "traction":
                _, tag = self.tagged.groups[load.group]  # type: ignore[index]
                terms.append(forms.traction_form(v, value, self.thickness, self.ds(tag)))
            else:
                terms.append(forms.body_force_form(v, value, self.thickness, self.dx))
        ctx = FormContext(mesh, v, self.dx, self.thickness)
        terms += [term(ctx) for term in self.terms]
        if not terms:
            zero = dolfinx.fem.Constant(mesh, np.zeros(gdim, dtype=PETSc.ScalarType))
            terms.append(ufl.inner(zero, v) * self.dx)
        return sum(terms[1:], terms[0])

    def _bc_entities(self, i: int) -> tuple[int, np.ndarray]:
        """(dimension, local entities, shape=(n,)) of Dirichlet condition ``i``.

        Raises:
            RunError: collectively, when the group has no entities on any rank.
        """
        group = self.scene.bcs[i].group
        dim, entities = self.tagged.entities(group)
        self.mesh.topology.create_connectivity(dim, self.mesh.topology.dim)
        if self.comm.allreduce(len(entities), op=MPI.SUM) == 0:
            raise RunError(f"bc[{i}].group: physical group '{group}' has no mesh entities")
        return dim, entities

    def _boundary_conditions(self) -> list[dolfinx.fem.DirichletBC]:
        V, mesh = self.element.space, self.mesh
        bcs = []
        for i, bc in enumerate(self.scene.bcs):
            dim, entities = self._bc_entities(i)
            if bc.value == "exact":
                assert self.exact is not None
                g = dolfinx.fem.Function(V)
                g.interpolate(
                    lambda x, ex=self.exact: np.stack(ex.displacement(*x[: mesh.geometry.dim]))
                )
                dofs = dolfinx.fem.locate_dofs_topological(V, dim, entities)
                bcs.append(dolfinx.fem.dirichletbc(g, dofs))
                continue
            for comp, value in zip(bc.components, bc.value, strict=True):
                Vc = V.sub(comp)
                dofs = dolfinx.fem.locate_dofs_topological(Vc, dim, entities)
                bcs.append(dolfinx.fem.dirichletbc(PETSc.ScalarType(value), dofs, Vc))
        return bcs

    def compile(self) -> None:
        """JIT-compile the bilinear and linear forms."""
        self.a = dolfinx.fem.form(self._a)
        self.L = dolfinx.fem.form(self._L)

    def assemble(self) -> None:
        """Assemble the stiffness matrix and load vector with the Dirichlet conditions."""
        if self.a is None or self.L is None:
            self.compile()
        assert self.a is not None and self.L is not None
        self._free_operators()  # a new operator needs a new factorisation/preconditioner
        self.A = dolfinx.fem.petsc.assemble_matrix(self.a, bcs=self.bcs)
        self.A.assemble()
        self.b = dolfinx.fem.petsc.assemble_vector(self.L)
        dolfinx.fem.petsc.apply_lifting(self.b, [self.a], bcs=[self.bcs])
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        dolfinx.fem.petsc.set_bc(self.b, self.bcs)

    def _constrain(self) -> None:
        """Impose :meth:`dirichlet` on an assembled ``A`` and ``b`` by elimination.

        Symmetric row and column elimination (``MatZeroRowsColumns`` with lifting), for
        operators that are not assembled from a DOLFINx form with its conditions.
        """
        assert self.A is not None and self.b is not None
        rows, vals = self.dirichlet()
        rows = rows.astype(PETSc.IntType)
        g = self.A.createVecRight()
        try:
            g.setValues(rows, vals)
            g.assemble()
            self.A.zeroRowsColumns(rows, 1.0, g, self.b)
        finally:
            g.destroy()

    def tensor_fields(self, names: list[str]) -> dict[str, dolfinx.fem.Function]:
        """Stress/strain fields of the solution for XDMF (see :func:`post.tensor_fields`)."""
        from geofrac.fem.post import tensor_fields

        plane = self.scene.material.plane
        return tensor_fields(self.uh, self.lam, self.mu, plane, names)

    def point_tensors(
        self, names: Sequence[str], points: np.ndarray, cells: np.ndarray
    ) -> dict[str, np.ndarray]:
        """3×3 ``stress``/``strain`` of the solution at points (see :func:`post.point_tensors`).

        Args:
            names: ``"stress"`` and/or ``"strain"``.
            points: coordinates, shape=(n, 3).
            cells: the cell of each point on its owning rank (:func:`post.locate_points`).

        Returns:
            name -> values, shape=(n, 3, 3), identical on every rank.
        """
        from geofrac.fem.post import point_tensors

        plane = self.scene.material.plane
        return point_tensors(self.uh, self.lam, self.mu, plane, names, points, cells)

    def write_extra(self, directory: Path) -> list[Path]:
        """Write the discretisation's own output files (collective); none here."""
        return []

    def describe(self) -> dict[str, Any]:
        """The discretisation's own facts for the results; none here."""
        return {}

    def error_norms(self) -> dict[str, float]:
        """Error norms against the scene's exact solution (see :func:`post.error_norms`)."""
        from geofrac.fem.post import error_norms

        assert self.exact is not None
        u_exact, _ = exact_ufl(self.exact, self.mesh)
        return error_norms(self.uh, u_exact, self.lam, self.mu)

    def load_vector(self) -> PETSc.Vec:
        """The assembled load vector on the unknowns, without Dirichlet conditions."""
        if self.L is None:
            self.compile()
        b = dolfinx.fem.petsc.assemble_vector(self.L)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return b

    def dirichlet(self) -> tuple[np.ndarray, np.ndarray]:
        """Global unknown indices, shape=(p,), and values, shape=(p,), of the Dirichlet DOFs.

        Owned entries only; a DOF in two conditions takes the value of the last, as in
        the assembly.
        """
        V = self.element.space
        imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
        n = imap.size_local * bs
        x = np.full((imap.size_local + imap.num_ghosts) * bs, np.nan)
        for bc in self.bcs:
            bc.set(x)
        local = np.flatnonzero(~np.isnan(x[:n]))
        blocks = imap.local_to_global((local // bs).astype(np.int32)).astype(np.int64)
        return blocks * bs + local % bs, x[local]

    def solve(self) -> dolfinx.fem.Function:
        """Factorise/precondition and solve; return the displacement function."""
        if self.A is None:
            self.assemble()
        assert self.A is not None and self.b is not None
        if self.solver is None:
            s = self.scene.solver
            self.solver = LinearSolver(
                self.A, PREFIX, s.preset, s.options, self.element.num_dofs, self._near_nullspace
            )
        unknown = self.unknown()
        self.iterations = self.solver.solve(self.b, unknown.x.petsc_vec)
        unknown.x.scatter_forward()
        self.to_field()
        return self.uh

    def unknown(self) -> dolfinx.fem.Function:
        """The function the linear system is solved for."""
        return self.uh

    def to_field(self) -> None:
        """Set the displacement ``uh`` from the solved unknowns (nothing to do here)."""

    def _near_nullspace(self) -> PETSc.NullSpace:
        return rigid_body_modes(self.element.space)

    def destroy(self) -> None:
        """Free the PETSc objects this problem and its element created."""
        self._free_operators()
        self.element.destroy()

    def _free_operators(self) -> None:
        for obj in (self.A, self.b):
            if obj is not None:
                obj.destroy()
        if self.solver is not None:
            self.solver.destroy()
        self.A = self.b = self.solver = None


class GradientDofProblem(ElasticProblem):
    """Linear elasticity with RGNT, GNT or RGNQ: forms on P2, unknowns at the vertices.

    The elastic form and the zero-mode penalty (:mod:`geofrac_forms.gradient_dofs`) are
    assembled on the P2 space and the vertex space W, reduced to W by
    :meth:`GradientDofElement.reduce`, and the Dirichlet conditions are applied to the
    reduced matrix with ``MatZeroRowsColumns`` (symmetric, with lifting). The displacement
    ``uh`` is the P2 field T w of the solution ``wh``.

    Dirichlet conditions fix the translations of the vertices on the group and, with
    ``discretization.gradient_bc = "fixed"`` (the default), their extra DOFs: to the
    exact field's values for ``value = "exact"``, to 0 for a constant value, so the
    boundary edges follow the data between the vertices (see docs/elements.md).
    """

    def __init__(
        self,
        tagged: TaggedMesh,
        element: Element,
        scene: Scene,
        terms: Sequence[LinearTerm] = (),
    ) -> None:
        super().__init__(tagged, element, scene, terms)
        W = element.unknowns
        self.wh = dolfinx.fem.Function(W, name="vertex_dofs")
        g, h = ufl.TrialFunction(W), ufl.TestFunction(W)
        u, v = ufl.TrialFunction(element.space), ufl.TestFunction(element.space)
        alpha = scene.discretization.zero_mode_penalty
        self.penalty_scale = dolfinx.fem.Constant(
            self.mesh, PETSc.ScalarType(alpha * float(self.mu.value))
        )
        pen_vv, self._a_wv, self._a_ww = penalty_forms(
            u, v, g, h, element.kind.basis, self.penalty_scale * self.thickness, self.dx
        )
        self._a = self._a + pen_vv
        self.a_wv: dolfinx.fem.Form | None = None
        self.a_ww: dolfinx.fem.Form | None = None

    def _boundary_conditions(self) -> list[tuple[np.ndarray, np.ndarray]]:  # type: ignore[override]
        """(global DOF indices, values) per Dirichlet condition, owned DOFs only."""
        element = self.element
        kind = element.kind
        gdim, bs = kind.gdim, kind.block_size
        out = []
        for i, bc in enumerate(self.scene.bcs):
            dim, entities = self._bc_entities(i)
            if bc.value == "exact":
                exact = self.exact
                assert exact is not None

                def values(x: np.ndarray, ex: ExactSolution = exact) -> np.ndarray:
                    u = np.stack(np.broadcast_arrays(*ex.displacement(*x[:, :gdim].T)), axis=1)
                    g = dofs_from_gradient(kind, displacement_gradient(ex, x))
                    return np.hstack([u, g])

                comps = tuple(range(gdim))
            else:
                fixed = np.zeros(bs)  # the extra DOFs of a constant boundary value are 0
                fixed[list(bc.components)] = bc.value

                def values(x: np.ndarray, fixed: np.ndarray = fixed) -> np.ndarray:
                    return np.tile(fixed, (len(x), 1))

                comps = bc.components
            if self.scene.discretization.gradient_bc == "fixed":
                comps = (*comps, *range(gdim, bs))
            out.append(element.vertex_constraints(dim, entities, values, comps))
        return out  # type: ignore[return-value]

    def compile(self) -> None:
        """JIT-compile the forms and build the vertex-to-P2 map T (set-up, timed here)."""
        super().compile()
        self.element.prolongation()
        self.a_wv = dolfinx.fem.form(self._a_wv)
        self.a_ww = dolfinx.fem.form(self._a_ww)

    def assemble(self) -> None:
        """Assemble on P2 and W, reduce to W, apply the Dirichlet conditions."""
        if self.a is None:
            self.compile()
        assert self.a is not None and self.L is not None
        self._free_operators()
        mats = [dolfinx.fem.petsc.assemble_matrix(f) for f in (self.a, self.a_wv, self.a_ww)]
        try:
            for M in mats:
                M.assemble()
            self.A = self.element.reduce(*mats)
        finally:
            for M in mats:
                M.destroy()
        self.b = self.load_vector()
        self._constrain()

    def load_vector(self) -> PETSc.Vec:
        """Tᵀ b_P2: the load vector on the vertex DOFs, without Dirichlet conditions."""
        b_v = super().load_vector()
        try:
            b = self.element.prolongation().createVecRight()
            self.element.prolongation().multTranspose(b_v, b)
        finally:
            b_v.destroy()
        return b

    def dirichlet(self) -> tuple[np.ndarray, np.ndarray]:
        """(global vertex-DOF indices, values) fixed by the Dirichlet conditions (owned)."""
        rows = np.concatenate([r for r, _ in self.bcs]).astype(np.int64)
        return rows, np.concatenate([v for _, v in self.bcs])

    def unknown(self) -> dolfinx.fem.Function:
        """The vertex DOFs ``wh``."""
        return self.wh

    def to_field(self) -> None:
        """The displacement ``uh`` = T wh."""
        self.element.prolongation().mult(self.wh.x.petsc_vec, self.uh.x.petsc_vec)
        self.uh.x.scatter_forward()

    def _near_nullspace(self) -> PETSc.NullSpace:
        return self.element.rigid_body_modes()


def make_problem(
    tagged: TaggedMesh, element: Element, scene: Scene, terms: Sequence[LinearTerm] = ()
) -> ElasticProblem:
    """The elastic problem of ``element`` with the right-hand-side ``terms``.

    The class is the one the element's :class:`~geofrac.elements.spec.ElementSpec` names
    (``problem``); no element is named here.
    """
    problem: type[ElasticProblem] = elements.get(element.name).problem_class()
    return problem(tagged, element, scene, terms)
