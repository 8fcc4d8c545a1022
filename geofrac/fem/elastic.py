"""The linear elastic problem of a scene: forms, boundary conditions, assembly, solve."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac import elements
from geofrac.analytic import ExactSolution, displacement_gradient, make_exact
from geofrac.elements.base import Element
from geofrac.elements.kinematics import constrained_bases, dofs_from_gradient
from geofrac.errors import RunError
from geofrac.fem import loads
from geofrac.fem.walls import facet_measure
from geofrac.materials import lame
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Load, Scene
from geofrac.solvers import (
    SCALAR,
    LinearSolver,
    Matrix,
    NullSpace,
    Vector,
    assemble_matrix,
    assemble_vector,
    function_vector,
    rigid_body_modes,
    set_bc,
    zero_rows_columns,
)
from geofrac_forms import elasticity as forms
from geofrac_forms.gradient_dofs import penalty_forms

if TYPE_CHECKING:
    from geofrac.elements.gradient import GradientDofElement
    from geofrac.fem.insitu import InsituFields

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
        density: the mass density as UFL (per cell group, zero in excavated cells) in a
            scene with an initial stress or stages, or None (``material.density``).
    """

    mesh: dolfinx.mesh.Mesh
    v: Any
    dx: Any
    thickness: Any
    density: Any = None

    def constant(self, value: float) -> dolfinx.fem.Constant:
        """A scalar DOLFINx constant on the mesh."""
        return dolfinx.fem.Constant(self.mesh, SCALAR(value))

    def vector(self, values: tuple[float, ...]) -> dolfinx.fem.Constant:
        """A vector DOLFINx constant on the mesh, shape=(gdim,)."""
        return dolfinx.fem.Constant(self.mesh, np.asarray(values, dtype=SCALAR))


#: A right-hand-side term added to the loads (an effect's ``linear_form`` bound to its
#: config by the run pipeline, :func:`geofrac.runner.linear_terms`).
LinearTerm = Callable[[FormContext], ufl.Form]


def exact_ufl(exact: ExactSolution, mesh: dolfinx.mesh.Mesh) -> tuple[Any, Any]:
    """(displacement vector, stress tensor) of an exact solution as UFL expressions."""
    x = ufl.SpatialCoordinate(mesh)
    coords = [x[i] for i in range(mesh.geometry.dim)]
    return ufl.as_vector(exact.displacement(*coords)), ufl.as_matrix(exact.stress(*coords))


#: largest |t_axis| / |t| of a symmetry group's edge directions t (mesh round-off).
SYMMETRY_TOLERANCE = 1e-8


def _tilt(mesh: dolfinx.mesh.Mesh, dim: int, entities: np.ndarray, axis: int) -> float:
    """Largest |t_axis| / |t| over the edge directions t of local entities (0 if none)."""
    if len(entities) == 0 or dim == 0:
        return 0.0
    nodes = dolfinx.mesh.entities_to_geometry(mesh, dim, entities.astype(np.int32))
    x = mesh.geometry.x[nodes]  # shape=(n, nodes per entity, 3)
    t = x[:, 1:] - x[:, :1]
    return float(np.max(np.abs(t[..., axis]) / np.linalg.norm(t, axis=2)))


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
        *,
        terms: Sequence[LinearTerm] = (),
    ) -> None:
        self.tagged, self.element, self.scene = tagged, element, scene
        self.terms = tuple(terms)
        mesh = tagged.mesh
        self.mesh = mesh
        self.comm: MPI.Comm = mesh.comm
        V = element.space
        mat = scene.material
        assert mat is not None and scene.discretization is not None  # a fem scene has both
        gdim = mesh.geometry.dim
        lam, mu = lame(mat.E, mat.nu, gdim, plane=mat.plane)
        #: the scene material's shear modulus (``mu`` is per cell in a staged scene).
        self.shear_modulus = float(mu)
        self.lam = dolfinx.fem.Constant(mesh, SCALAR(lam))
        self.mu = dolfinx.fem.Constant(mesh, SCALAR(mu))
        self.thickness = dolfinx.fem.Constant(mesh, SCALAR(mat.thickness if gdim == 2 else 1.0))
        q = scene.discretization.quadrature_degree
        self.dx = ufl.Measure(
            "dx", domain=mesh, metadata={} if q is None else {"quadrature_degree": q}
        )
        #: the facet measure and, per load on an opening's wall, its subdomain id
        #: (:mod:`geofrac.fem.walls`).
        self.ds, self.walls = facet_measure(tagged, scene)
        self.exact = (
            make_exact(
                scene.exact.name, scene.exact.parameters, E=mat.E, nu=mat.nu, plane=mat.plane
            )
            if scene.exact is not None
            else None
        )
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        #: a scene with an initial stress or stages: the live cells, σ0 and the density
        #: (:mod:`geofrac.fem.insitu`); None otherwise.
        self.insitu: InsituFields | None = None
        stiffness_t: Any = self.thickness
        if scene.initial_stress is not None or scene.stages:
            from geofrac.fem.insitu import insitu_fields

            degree = V.ufl_element().embedded_superdegree
            self.insitu = insitu_fields(tagged, scene, lam=lam, mu=mu, degree=degree)
            stiffness_t = self.thickness * self.insitu.alive
            self.lam, self.mu = self.insitu.lam, self.insitu.mu  # per cell: added groups
        self._a = forms.stiffness_form(u, v, self.lam, self.mu, stiffness_t, self.dx)
        self._L = self._linear_form(v)
        self.point_forces = loads.point_forces(
            tagged, V, scene.loads, thickness=float(self.thickness.value)
        )
        self.bcs = self._boundary_conditions()
        self.uh = dolfinx.fem.Function(V, name="displacement")
        self.a: dolfinx.fem.Form | None = None
        self.L: dolfinx.fem.Form | None = None
        self.A: Matrix | None = None
        self.b: Vector | None = None
        self.solver: LinearSolver | None = None
        self.iterations = 0

    def _linear_form(self, v: Any) -> Any:
        """The distributed loads (:mod:`geofrac.fem.loads`) and the effects' terms as one form."""
        mesh, gdim = self.mesh, self.mesh.geometry.dim
        terms = [self._load_term(load, v) for load in self.scene.loads if load.type != "point"]
        terms += [term(self.form_context(v)) for term in self.terms]
        if not terms:
            zero = dolfinx.fem.Constant(mesh, np.zeros(gdim, dtype=SCALAR))
            terms.append(ufl.inner(zero, v) * self.dx)
        return sum(terms[1:], terms[0])

    def form_context(self, v: Any) -> FormContext:
        """What the effects' terms see (:class:`FormContext`) for test function ``v``."""
        density = None if self.insitu is None else self.insitu.density
        return FormContext(self.mesh, v, self.dx, self.thickness, density)

    def _load_term(self, load: Load, v: Any) -> ufl.Form:
        """The linear form of one distributed load (not ``point``)."""
        value = None
        if load.value == "exact":
            assert self.exact is not None
            u_ex, sig = exact_ufl(self.exact, self.mesh)
            if load.type == "traction":
                value = sig * ufl.FacetNormal(self.mesh)
            else:  # the body force that makes u_exact an equilibrium state
                value = -ufl.div(forms.sigma(u_ex, self.lam, self.mu))
        wall = self.walls.get(self.scene.loads.index(load))  # equal loads: equal forms
        return loads.load_form(
            load,
            v,
            self.tagged,
            ds=self.ds,
            dx=self.dx,
            thickness=self.thickness,
            value=value,
            subdomain=wall,
        )

    @property
    def changes_basis(self) -> bool:
        """Whether the unknowns are in a changed basis (:class:`GradientDofProblem`)."""
        return False

    def _add_point_forces(self, b: Vector) -> None:
        """Add the point loads to an assembled vector on ``element.space``.

        When a load is an expression, a vector with inf or NaN entries is refused.
        """
        self.point_forces.add_to(b)
        if loads.has_expressions(self.scene.loads):
            loads.require_finite(b, self.comm)

    def _bc_entities(self, i: int) -> tuple[int, np.ndarray]:
        """(dimension, local entities, shape=(n,)) of Dirichlet condition ``i``.

        Raises:
            RunError: collectively, when the group has no entities on any rank, or when a
                ``symmetry`` condition's group is not a plane normal to its held axis.
        """
        bc = self.scene.bcs[i]
        dim, entities = self.tagged.entities(bc.group)
        self.mesh.topology.create_connectivity(dim, self.mesh.topology.dim)
        if self.comm.allreduce(len(entities), op=MPI.SUM) == 0:
            raise RunError(f"bc[{i}].group: physical group '{bc.group}' has no mesh entities")
        if bc.symmetry:
            axis = bc.components[0]
            tilt = _tilt(self.mesh, dim, entities, axis)
            tilt = self.comm.allreduce(tilt, op=MPI.MAX)
            if tilt > SYMMETRY_TOLERANCE:
                name = "xyz"[axis]
                raise RunError(
                    f"bc[{i}].symmetry: group '{bc.group}' is not a plane {name} = const "
                    f"(a symmetry condition holds the normal component '{name}'; an edge "
                    f"leaves the plane by {tilt:.2g} of its length)"
                )
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
                bcs.append(dolfinx.fem.dirichletbc(SCALAR(value), dofs, Vc))
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
        self.A = assemble_matrix(self.a, self.bcs)
        self.b = assemble_vector(self.L, (self.a, self.bcs))
        self._add_point_forces(self.b)
        set_bc(self.b, self.bcs)

    def stiffness(self) -> Matrix:
        """The stiffness on the unknowns without the Dirichlet conditions (a new matrix).

        For a nonlinear driver that imposes the conditions itself (the joints' Newton of
        :mod:`geofrac.fem.joints_elastic`); the caller destroys it.
        """
        if self.a is None or self.L is None:
            self.compile()
        assert self.a is not None
        return assemble_matrix(self.a)

    def _constrain(self) -> None:
        """Impose :meth:`dirichlet` on an assembled ``A`` and ``b`` by elimination.

        Symmetric row and column elimination (``MatZeroRowsColumns`` with lifting), for
        operators that are not assembled from a DOLFINx form with its conditions.
        """
        assert self.A is not None and self.b is not None
        rows, vals = self.dirichlet()
        zero_rows_columns(self.A, rows, vals, b=self.b)

    def tensor_fields(self, names: list[str]) -> dict[str, dolfinx.fem.Function]:
        """Stress/strain fields of the solution for XDMF (see :func:`post.tensor_fields`)."""
        from geofrac.fem.post import tensor_fields

        assert self.scene.material is not None  # a fem scene has one
        plane = self.scene.material.plane
        return tensor_fields(
            self.uh, self.lam, self.mu, plane=plane, names=names, **self._initial_state()
        )

    def _initial_state(self) -> dict[str, Any]:
        """σ0 (3×3), ``alive`` and the ``reference`` displacement of added cells."""
        if self.insitu is None:
            return {}
        return {
            "initial": self.insitu.sigma0,
            "alive": self.insitu.alive,
            "reference": self.insitu.u_ref,
        }

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

        assert self.scene.material is not None  # a fem scene has one
        plane = self.scene.material.plane
        return point_tensors(
            self.uh,
            self.lam,
            self.mu,
            plane=plane,
            names=names,
            points=points,
            cells=cells,
            **self._initial_state(),
        )

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
        return error_norms(self.uh, u_exact, self.lam, mu=self.mu)

    def load_vector(self) -> Vector:
        """The assembled load vector on the unknowns, without Dirichlet conditions.

        Point loads are included.
        """
        if self.L is None:
            self.compile()
        b = assemble_vector(self.L)
        self._add_point_forces(b)
        return b

    def load_part(self, index: int) -> Vector:
        """The load vector on the unknowns of the scene's load ``index`` alone (collective).

        Without Dirichlet conditions and without the other loads and the effects' terms
        (what :meth:`load_vector` sums); the caller destroys it.
        """
        load = self.scene.loads[index]
        V = self.element.space
        t = float(self.thickness.value)
        if load.type == "point":
            zero = dolfinx.fem.Constant(self.mesh, np.zeros(self.mesh.geometry.dim))
            form = ufl.inner(zero, ufl.TestFunction(V)) * self.dx
            points = loads.point_forces(self.tagged, V, (load,), thickness=t)
        else:
            form = self._load_term(load, ufl.TestFunction(V))
            points = loads.point_forces(self.tagged, V, (), thickness=t)
        b = assemble_vector(dolfinx.fem.form(form))
        points.add_to(b)
        return self._on_unknowns(b)

    def _on_unknowns(self, b: Vector) -> Vector:
        """A load vector of the displacement space on the unknowns: itself here."""
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
            self.solver = self.make_solver()
        unknown = self.unknown()
        self.iterations = self.solver.solve(self.b, function_vector(unknown))
        unknown.x.scatter_forward()
        self.to_field()
        return self.uh

    def make_solver(self) -> LinearSolver:
        """The scene's ``[solver]`` on the assembled matrix, with the elastic options prefix."""
        assert self.A is not None
        s = self.scene.solver
        return LinearSolver(
            self.A,
            PREFIX,
            s.preset,
            options=s.options,
            num_dofs=self.element.num_dofs,
            near_nullspace=self._near_nullspace,
        )

    def unknown(self) -> dolfinx.fem.Function:
        """The function the linear system is solved for."""
        return self.uh

    def to_field(self) -> None:
        """Set the displacement ``uh`` from the solved unknowns (nothing to do here)."""

    def _near_nullspace(self) -> NullSpace:
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

    Dirichlet conditions fix the translations of the vertices on the group. For the extra
    DOFs, ``discretization.gradient_bc`` (docs/elements.md, "Boundary DOFs"):
    ``"consistent"`` (default) holds what a constant-value condition implies, (G t)_c = 0
    for each held component c and edge direction t of the group (plus ∂u_s/∂n = 0 on a
    mirror-symmetry condition), possibly in a per-vertex orthogonal basis w = Q h
    (:attr:`basis`); ``"fixed"`` holds them all at 0; ``"free"`` holds none. A
    ``value = "exact"`` condition holds them at the exact field's values (all modes but
    ``"free"``).

    Attributes:
        basis: per owned vertex the basis Q_i of the extra DOFs, shape=(num_owned, k, k),
            or None when every vertex keeps the DOF axes (no change of basis). With a basis
            the system is solved for h (:meth:`unknown`), K' = Qᵀ K Q, b' = Qᵀ b.
    """

    basis: np.ndarray | None = None
    element: GradientDofElement

    def __init__(
        self,
        tagged: TaggedMesh,
        element: GradientDofElement,
        scene: Scene,
        *,
        terms: Sequence[LinearTerm] = (),
    ) -> None:
        super().__init__(tagged, element, scene, terms=terms)
        W = element.unknowns
        self.wh = dolfinx.fem.Function(W, name="vertex_dofs")
        g, h = ufl.TrialFunction(W), ufl.TestFunction(W)
        u, v = ufl.TrialFunction(element.space), ufl.TestFunction(element.space)
        assert scene.discretization is not None  # a fem scene has one
        alpha = scene.discretization.zero_mode_penalty
        self.penalty_scale = dolfinx.fem.Constant(self.mesh, SCALAR(alpha * self.shear_modulus))
        pen_vv, self._a_wv, self._a_ww = penalty_forms(
            u, v, g, h, element.kind.basis, self.penalty_scale * self.thickness, self.dx
        )
        self._a = self._a + pen_vv
        self.a_wv: dolfinx.fem.Form | None = None
        self.a_ww: dolfinx.fem.Form | None = None
        self._Q: Matrix | None = None
        self.hh: dolfinx.fem.Function | None = None
        if self.basis is not None:
            self._Q = element.basis_change(self.basis)
            self.hh = dolfinx.fem.Function(W, name="vertex_dofs_rotated")

    @property
    def changes_basis(self) -> bool:
        """Whether the unknowns are the rotated DOFs h (w = Q h), not w."""
        return self.basis is not None

    def _boundary_conditions(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """(global DOF indices, values) per Dirichlet condition, owned DOFs only.

        With ``gradient_bc = "consistent"`` the last entry holds the extra DOFs that the
        constant-value conditions imply (:meth:`_implied_constraints`), in the basis of
        :attr:`basis`.
        """
        element = self.element
        kind = element.kind
        gdim, bs = kind.gdim, kind.block_size
        assert self.scene.discretization is not None  # a fem scene has one
        mode = self.scene.discretization.gradient_bc
        out = []
        conditions = []
        values: Callable[[np.ndarray], np.ndarray]
        for i, bc in enumerate(self.scene.bcs):
            dim, entities = self._bc_entities(i)
            if bc.value == "exact":
                assert self.exact is not None
                exact: ExactSolution = self.exact

                def exact_values(x: np.ndarray, ex: ExactSolution = exact) -> np.ndarray:
                    # array coordinates give array fields
                    parts = cast("tuple[np.ndarray, ...]", ex.displacement(*x[:, :gdim].T))
                    u = np.stack(np.broadcast_arrays(*parts), axis=1)
                    g = dofs_from_gradient(kind, displacement_gradient(ex, x))
                    return np.hstack([u, g])

                values = exact_values

                comps = tuple(range(gdim))
                if mode != "free":  # the exact field's extra DOFs are data
                    comps = (*comps, *range(gdim, bs))
            else:
                fixed = np.zeros(bs)  # the extra DOFs of a constant boundary value are 0
                fixed[list(bc.components)] = bc.value

                def fixed_values(x: np.ndarray, fixed: np.ndarray = fixed) -> np.ndarray:
                    return np.tile(fixed, (len(x), 1))

                values = fixed_values

                comps = bc.components
                if mode == "fixed":
                    comps = (*comps, *range(gdim, bs))
                elif mode == "consistent":
                    axis = bc.components[0] if bc.symmetry else None
                    conditions.append((dim, entities, bc.components, axis))
            out.append(element.vertex_constraints(dim, entities, values, components=comps))
        if mode == "consistent":
            out.append(self._implied_constraints(conditions, out))
        return out

    def _implied_constraints(
        self,
        conditions: list[tuple[int, np.ndarray, tuple[int, ...], int | None]],
        explicit: list[tuple[np.ndarray, np.ndarray]],
    ) -> tuple[np.ndarray, np.ndarray]:
        """The extra DOFs a constant-value condition implies, held at 0 (collective).

        Per vertex the functionals of :meth:`GradientDofElement.boundary_gram` span the
        constrained directions (:func:`~geofrac.elements.kinematics.constrained_bases`).
        Where they are coordinate axes of the DOF layout those DOFs are held; elsewhere the
        vertex's extra DOFs get the orthogonal basis Q_i (w = Q h), stored in
        :attr:`basis`, and the constrained new DOFs are held. Vertices whose extra DOFs an
        ``exact`` condition already fixes are left to it.

        Returns:
            (global indices, shape=(p,), zeros, shape=(p,)).
        """
        element = self.element
        gdim, bs = element.kind.gdim, element.kind.block_size
        imap = element.unknowns.dofmap.index_map
        gram = element.boundary_gram(conditions)
        rows = np.concatenate([r for r, _ in explicit]).astype(np.int64)
        taken = rows[rows % bs >= gdim] // bs - imap.local_range[0]
        gram[taken] = 0.0
        Q, fixed = constrained_bases(gram)
        rotated = ~np.all(np.eye(Q.shape[1]) == Q, axis=(1, 2))
        if self.comm.allreduce(bool(rotated.any()), op=MPI.LOR):
            self.basis = Q
        blocks, slots = np.nonzero(fixed)
        g = imap.local_to_global(blocks.astype(np.int32)).astype(np.int64)
        return g * bs + gdim + slots, np.zeros(len(blocks))

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
        self.A = self.stiffness()
        self.b = self.load_vector()
        self._constrain()

    def stiffness(self) -> Matrix:
        """Qᵀ (Tᵀ A T + penalty) Q on the unknowns, without the Dirichlet conditions (new)."""
        if self.a is None:
            self.compile()
        assert self.a is not None and self.a_wv is not None and self.a_ww is not None
        mats = [assemble_matrix(f) for f in (self.a, self.a_wv, self.a_ww)]
        try:
            K = self.element.reduce(*mats)
        finally:
            for M in mats:
                M.destroy()
        if self._Q is not None:
            reduced = K
            K = reduced.ptap(self._Q)
            reduced.destroy()
        return K

    def load_vector(self) -> Vector:
        """Qᵀ Tᵀ b_P2: the load vector on the unknowns, without Dirichlet conditions."""
        return self._on_unknowns(super().load_vector())

    def _on_unknowns(self, b_v: Vector) -> Vector:
        """Qᵀ Tᵀ b_v of a load vector b_v on the displacement space (destroys b_v)."""
        try:
            b = self.element.prolongation().createVecRight()
            self.element.prolongation().multTranspose(b_v, b)
        finally:
            b_v.destroy()
        if self._Q is not None:
            w = b
            b = w.duplicate()
            self._Q.multTranspose(w, b)
            w.destroy()
        return b

    def dirichlet(self) -> tuple[np.ndarray, np.ndarray]:
        """(global indices, values) of the unknowns the Dirichlet conditions fix (owned)."""
        rows = np.concatenate([r for r, _ in self.bcs]).astype(np.int64)
        return rows, np.concatenate([v for _, v in self.bcs])

    def unknown(self) -> dolfinx.fem.Function:
        """The vertex DOFs ``wh``, or their rotated values ``hh`` (:attr:`basis`)."""
        return self.wh if self.hh is None else self.hh

    def to_field(self) -> None:
        """The vertex DOFs ``wh`` = Q hh (with a basis) and the displacement ``uh`` = T wh."""
        if self.hh is not None and self.basis is not None:
            gdim, bs = self.element.kind.gdim, self.element.kind.block_size
            n = len(self.basis)
            h = self.hh.x.array[: n * bs].reshape(n, bs)
            w = self.wh.x.array[: n * bs].reshape(n, bs)
            w[:, :gdim] = h[:, :gdim]
            w[:, gdim:] = np.einsum("nkj,nj->nk", self.basis, h[:, gdim:])
            self.wh.x.scatter_forward()
        self.element.prolongation().mult(function_vector(self.wh), function_vector(self.uh))
        self.uh.x.scatter_forward()

    def _near_nullspace(self) -> NullSpace:
        return self.element.rigid_body_modes(self.basis)

    def destroy(self) -> None:
        """Free the PETSc objects, the basis change Q included."""
        super().destroy()
        if self._Q is not None:
            self._Q.destroy()
            self._Q = None


def make_problem(
    tagged: TaggedMesh, element: Element, scene: Scene, *, terms: Sequence[LinearTerm] = ()
) -> ElasticProblem:
    """The elastic problem of ``element`` with the right-hand-side ``terms``.

    The class is the one the element's :class:`~geofrac.elements.spec.ElementSpec` names
    (``problem``); no element is named here.
    """
    problem: type[ElasticProblem] = elements.get(element.name).problem_class()
    return problem(tagged, element, scene, terms=terms)
