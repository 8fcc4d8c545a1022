"""The elastic problem with the EFMM element: condensed node stiffness, patch stresses.

The stiffness is t × :meth:`geofrac.elements.efmm.EfmmElement.stiffness` (K = Cᵀ A⁻¹ C,
Edo (2016), eq. 3.6, per unit thickness); the load vector is the CST one (eq. 3.4c, N^u the
CST shape functions), assembled from the scene's UFL loads, which carry t; Dirichlet
conditions are imposed on K by symmetric elimination. The stress of the solution is each
node's own linear field σ = P_i e_i with e = A⁻¹ C u (eq. 3.3): the energy error of the
results is measured with it (eq. 3.30b), and it is what the grains and the nodal
stress show.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import basix
import dolfinx
import numpy as np
from mpi4py import MPI

from geofrac.elements.efmm import EfmmElement
from geofrac.elements.efmm_numpy import stress_error
from geofrac.fem.elastic import ElasticProblem, LinearTerm
from geofrac.materials import d_matrix
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Scene

__all__ = ["EfmmProblem"]

#: Degree of the rule for the stress error on each sub-triangle (the error of a linear
#: field against a quadratic exact stress, squared: degree 4, plus margin).
ERROR_DEGREE = 6


def _tensor(voigt: np.ndarray, problem: ElasticProblem) -> np.ndarray:
    """3x3 stresses, shape=(n, 9), from (σx, σy, τxy), shape=(n, 3), with σzz of the plane."""
    out = np.zeros((len(voigt), 3, 3))
    out[:, 0, 0], out[:, 1, 1] = voigt[:, 0], voigt[:, 1]
    out[:, 0, 1] = out[:, 1, 0] = voigt[:, 2]
    mat = problem.scene.material
    assert mat is not None  # a fem scene has one
    if mat.plane == "strain":
        out[:, 2, 2] = mat.nu * (voigt[:, 0] + voigt[:, 1])
    return out.reshape(-1, 9)


def _contains(triangle: np.ndarray, x: np.ndarray, tol: float = 1e-10) -> bool:
    """Whether point ``x``, shape=(2,), lies in ``triangle``, shape=(3, 2) (borders included)."""
    a, b, c = triangle
    m = np.column_stack([b - a, c - a])
    if abs(np.linalg.det(m)) == 0.0:  # a degenerate part (a crossing at a vertex)
        return False
    l1, l2 = np.linalg.solve(m, x - a)
    return bool(min(l1, l2, 1.0 - l1 - l2) >= -tol)


class EfmmProblem(ElasticProblem):
    """Linear elasticity with EFMM (Edo (2016), §3.2); see the module text.

    Attributes:
        e: the stress coefficients after :meth:`solve`, P1 with block size 9.
    """

    element: EfmmElement

    def __init__(
        self,
        tagged: TaggedMesh,
        element: EfmmElement,
        scene: Scene,
        *,
        terms: Sequence[LinearTerm] = (),
    ) -> None:
        super().__init__(tagged, element, scene, terms=terms)
        mat = scene.material
        assert mat is not None  # a fem scene has one
        self.D = d_matrix(mat.E, mat.nu, 2, plane=mat.plane)
        self.e: dolfinx.fem.Function | None = None

    def compile(self) -> None:
        """Compile the load form and load the C kernels (compiled once, then cached)."""
        from geofrac import kernels

        self.L = dolfinx.fem.form(self._L)
        kernels.load("efmm", self.comm)

    def assemble(self) -> None:
        """Domains, C and A⁻¹ (kernels), K = Cᵀ A⁻¹ C, the CST load vector, conditions."""
        if self.L is None:
            self.compile()
        self._free_operators()
        d = self.scene.discretization
        assert d is not None  # a fem scene has one
        self.element.setup(self.D, d.q_rand, d.domain_seed)
        self.A = self.element.stiffness()  # per unit thickness (A and C integrate over areas)
        self.A.scale(float(self.thickness.value))  # as the loads, which carry t (forms/)
        self.b = self.load_vector()
        self._constrain()

    def to_field(self) -> None:
        """The stress coefficients e = A⁻¹ C u of the solution."""
        self.e = self.element.stress_coefficients(self.uh)

    def cell_data(self) -> dict[str, np.ndarray]:
        """This rank's owned cells with their domains and stresses.

        Returns:
            ``x`` vertices shape=(n, 3, 2), ``gid`` input vertex ids shape=(n, 3),
            ``domain`` shape=(n, 8), ``e`` stress coefficients of the vertices
            shape=(n, 3, 9).
        """
        assert self.e is not None and self.element.domains is not None
        mesh = self.mesh
        n = mesh.topology.index_map(2).size_local
        nodes = mesh.geometry.dofmaps[0][:n]
        E = self.element.stress_space
        return {
            "x": mesh.geometry.x[nodes][:, :, :2],
            "gid": np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[nodes],
            "domain": self.element.domains.values[:n],
            "e": self.e.x.array.reshape(-1, 9)[E.dofmap.list[:n]],
        }

    def error_norms(self) -> dict[str, float]:
        """Displacement error of the CST field; energy error of the patch stresses.

        ``energy_cst`` is the energy error of the CST strain B u, for comparison.
        """
        out = super().error_norms()
        assert self.exact is not None
        exact = self.exact
        data = self.cell_data()
        pts, wts = basix.make_quadrature(basix.CellType.triangle, ERROR_DEGREE)

        def stress(x: np.ndarray, y: np.ndarray) -> np.ndarray:
            # array coordinates give array fields
            rows = cast("tuple[tuple[np.ndarray, ...], ...]", exact.stress(x, y))
            (sxx, sxy), (_, syy) = rows
            return np.stack(np.broadcast_arrays(sxx, syy, sxy), axis=1)

        assert self.element.domains is not None
        err, norm = stress_error(
            data["x"],
            data["domain"],
            data["e"],
            Dinv=np.linalg.inv(self.D),
            length=self.element.domains.length,
            exact_stress=stress,
            rule=(pts, wts),
        )
        err, norm = self.comm.allreduce(np.array([err, norm]), op=MPI.SUM)
        out["energy_cst"] = out["energy"]
        out["energy"] = float(np.sqrt(err))
        out["energy_norm"] = float(np.sqrt(norm))
        out["energy_relative"] = out["energy"] / out["energy_norm"]
        return out

    def node_stress(self) -> dolfinx.fem.Function:
        """Each node's stress σ_i(x_i) = its field's constant term, 3x3 P1 (vertex values).

        Out of plane: σzz = ν (σx + σy) in plane strain, 0 in plane stress.
        """
        assert self.e is not None
        mesh = self.mesh
        T = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3, 3)))
        out = dolfinx.fem.Function(T, name="stress_nodal")
        E = self.element.stress_space
        e = self.e.x.array.reshape(-1, 9)
        values = out.x.array.reshape(-1, 9)
        values[T.dofmap.list.ravel()] = _tensor(e[E.dofmap.list.ravel()][:, [0, 3, 6]], self)
        return out

    def point_tensors(
        self, names: Sequence[str], points: np.ndarray, cells: np.ndarray
    ) -> dict[str, np.ndarray]:
        """The stress of the node whose integration domain holds each point (eq. 3.3).

        In the located cell, the point's node part is the one of its six sub-triangles
        (:func:`~geofrac.elements.efmm_numpy.cell_subtriangles`) that contains it; on a
        border between parts the node with the smallest input index wins (the same on
        any number of ranks). σ = e_i0 + e_i1 ξ + e_i2 η, (ξ, η) = (x - x_i) / h, with
        σzz of the plane (:func:`_tensor`); the strain is the compliance of that 3×3
        stress, ε = ((1 + ν) σ - ν tr(σ) I) / E (εzz = 0 in plane strain).

        Returns:
            name -> values, shape=(n, 3, 3), identical on every rank.
        """
        from geofrac.elements.efmm_numpy import cell_subtriangles

        assert self.element.domains is not None
        data = self.cell_data()
        mine = np.flatnonzero(cells >= 0)
        local = np.zeros((len(points), 9))
        for i in mine:
            c = int(cells[i])
            x = points[i, :2]
            subs = cell_subtriangles(data["x"][c : c + 1], data["domain"][c : c + 1])[0]
            inside = [j for j in range(3) if any(_contains(t, x) for t in subs[j])]
            j = min(inside or range(3), key=lambda k: data["gid"][c, k])
            coef = data["e"][c, j].reshape(3, 3)  # (σx, σy, τxy) x (1, ξ, η)
            xi = (x - data["x"][c, j]) / self.element.domains.length
            local[i] = _tensor((coef @ np.array([1.0, *xi]))[None, :], self)[0]
        stress: np.ndarray = np.empty_like(local)
        self.comm.Allreduce(local, stress, op=MPI.SUM)
        stress = stress.reshape(-1, 3, 3)
        out = {"stress": stress}
        if "strain" in names:
            mat = self.scene.material
            assert mat is not None  # a fem scene has one
            trace = np.trace(stress, axis1=1, axis2=2)[:, None, None]
            out["strain"] = ((1 + mat.nu) * stress - mat.nu * trace * np.eye(3)) / mat.E
        return {n: out[n] for n in names}

    def tensor_fields(self, names: list[str]) -> dict[str, dolfinx.fem.Function]:
        """As the base class; ``stress_nodal`` is each node's own stress (node_stress)."""
        fields = super().tensor_fields([n for n in names if n != "stress_nodal"])
        if "stress_nodal" in names:
            fields["stress_nodal"] = self.node_stress()
        return fields

    def write_extra(self, directory: Path) -> list[Path]:
        """The grains: ``grains.vtu``, ``grains.xdmf`` + ``grains.h5`` (:meth:`write_grains`)."""
        return self.write_grains(directory / "grains")

    def write_grains(self, stem: Path) -> list[Path]:
        """Write the integration domains as polygons with their mean stress (collective).

        Rank 0 gathers the owned cells' sub-triangles and stress coefficients, joins each
        node's sub-triangles into its polygon (:func:`geofrac.io.grains.grain_polygons`)
        and writes ``stem.vtu``, ``stem.xdmf`` and ``stem.h5``
        (:func:`geofrac.io.grains.write_grains`) with, per grain, ``stress`` (the mean of
        the node's stress field over its domain, 3x3), ``stress_node`` (at the node) and
        the cell arrays ``node`` (input vertex id) and ``area``.

        Returns:
            the paths written (rank 0), an empty list elsewhere.
        """
        from geofrac.elements.efmm_numpy import cell_subtriangles, triangle_areas
        from geofrac.io.grains import grain_polygons, write_grains

        assert self.element.domains is not None
        data = self.cell_data()
        parts = self.comm.gather(data, root=0)
        if self.comm.rank != 0:
            return []
        assert parts is not None
        x, gid, domain, e = (
            np.concatenate([p[k] for p in parts]) for k in ("x", "gid", "domain", "e")
        )
        subs = cell_subtriangles(x, domain)  # shape=(nc, 3, 2, 3, 2)
        area = triangle_areas(subs)  # shape=(nc, 3, 2)
        rel = (subs.mean(axis=3) - x[:, :, None, :]) / self.element.domains.length
        coef = e.reshape(len(e), 3, 3, 3)  # (cell, node, component, monomial)
        at_centroid = coef[..., 0][:, :, None] + np.einsum("cjsm,cjkm->cjsk", rel, coef[..., 1:])
        node = np.broadcast_to(gid[:, :, None], area.shape).ravel()
        grains = grain_polygons(node, subs.reshape(-1, 3, 2))
        index = np.searchsorted(grains.node, node)
        integral = np.zeros((grains.num_grains, 3))
        np.add.at(integral, index, (at_centroid * area[..., None]).reshape(-1, 3))
        at_node = np.zeros((grains.num_grains, 3))
        at_node[np.searchsorted(grains.node, gid.ravel())] = e.reshape(-1, 9)[:, [0, 3, 6]]
        return write_grains(
            stem,
            grains,
            {
                "stress": _tensor(integral / grains.area[:, None], self),
                "stress_node": _tensor(at_node, self),
            },
        )

    def describe(self) -> dict[str, Any]:
        """Domain facts for the results: the length h and the clamped edge crossings."""
        assert self.element.domains is not None
        d = self.scene.discretization
        assert d is not None  # a fem scene has one
        return {
            "q_rand": d.q_rand,
            "domain_seed": d.domain_seed,
            "length": self.element.domains.length,
            "clamped_crossings": self.element.domains.clamped,
        }
