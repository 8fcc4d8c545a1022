"""Post-processing in parallel: global integrals, point probes, stress fields, error norms.

A probe's stress is the element's own field in one cell (discontinuous across cells for
CST and P1); :func:`locate_points` says which cell wins on a shared edge or vertex. The
nodal average of XDMF's ``stress_nodal`` is a separate recovery that probes do not use.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.io.lines import sample_points
from geofrac.model.fields import COMPONENT_INDEX, tensor_components
from geofrac.model.scene import Line
from geofrac_forms import elasticity as forms

__all__ = [
    "TENSOR_FIELDS",
    "error_norms",
    "integrate",
    "locate_line",
    "locate_points",
    "point_tensors",
    "principal_of",
    "probe",
    "probe_fields",
    "tensor_fields",
    "von_mises_of",
]


def integrate(form: Any, comm: MPI.Comm) -> float:
    """Integrate a UFL functional over the whole distributed mesh (sum of owned cells)."""
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form))
    return float(comm.allreduce(local, op=MPI.SUM))


def locate_points(
    mesh: dolfinx.mesh.Mesh, points: np.ndarray, labels: Sequence[str] | None = None
) -> np.ndarray:
    """The cell each point is evaluated in, on its owning rank; -1 elsewhere.

    A point on an edge or vertex shared by several cells goes to the one with the
    smallest original (input) cell index, so the choice, and a discontinuous field's
    value there, is the same on any number of ranks.

    Args:
        mesh: the mesh.
        points: coordinates, shape=(num_points, 3).
        labels: what to call each point in an error (default ``point i``).

    Returns:
        local cell indices, shape=(num_points,); -1 where another rank owns the point.

    Raises:
        RunError: a point lies outside the mesh (on every rank), naming the first.
    """
    tdim = mesh.topology.dim
    num_owned = mesh.topology.index_map(tdim).size_local
    tree = dolfinx.geometry.bb_tree(mesh, tdim, entities=np.arange(num_owned, dtype=np.int32))
    candidates = dolfinx.geometry.compute_collisions_points(tree, points)
    colliding = dolfinx.geometry.compute_colliding_cells(mesh, candidates, points)
    original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)
    none = np.iinfo(np.int64).max
    cells = np.full(len(points), -1, dtype=np.int32)
    key = np.full(len(points), none, dtype=np.int64)
    for i in range(len(points)):
        links = colliding.links(i)
        if len(links):
            best = int(np.argmin(original[links]))
            cells[i], key[i] = links[best], original[links[best]]
    first = np.empty_like(key)
    mesh.comm.Allreduce(key, first, op=MPI.MIN)
    missing = np.flatnonzero(first == none)
    if len(missing):
        i = int(missing[0])
        label = labels[i] if labels is not None else f"point {i}"
        where = [float(c) for c in points[i, : mesh.geometry.dim]]
        more = f" ({len(missing)} points in all)" if len(missing) > 1 else ""
        raise RunError(f"{label} at {where} lies outside the mesh{more}")
    cells[key != first] = -1
    return cells


def locate_line(
    mesh: dolfinx.mesh.Mesh, name: str, line: Line
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The samples of ``line`` and their cells (:func:`locate_points`).

    Returns:
        ``s`` shape=(points,), the points shape=(points, 3), the cells shape=(points,).

    Raises:
        RunError: collectively, naming the line and its first sample outside the mesh.
    """
    s, xyz = sample_points(line)
    labels = [f"output.lines.{name}: sample {i} (s = {s[i]:.6g})" for i in range(len(s))]
    return s, xyz, locate_points(mesh, xyz, labels)


def probe(
    u: dolfinx.fem.Function, points: np.ndarray, cells: np.ndarray | None = None
) -> np.ndarray:
    """Values of ``u`` at points, identical on every rank.

    Args:
        u: a function.
        points: coordinates, shape=(num_points, 3).
        cells: result of :func:`locate_points` (computed when None).

    Returns:
        values, shape=(num_points, value_size).
    """
    mesh = u.function_space.mesh
    if cells is None:
        cells = locate_points(mesh, points)
    size = int(np.prod(u.ufl_shape)) if u.ufl_shape else 1
    local = np.zeros((len(points), size))
    mine = np.flatnonzero(cells >= 0)
    if len(mine):
        local[mine] = u.eval(points[mine], cells[mine]).reshape(len(mine), size)
    values = np.empty_like(local)
    mesh.comm.Allreduce(local, values, op=MPI.SUM)
    return values


def von_mises_of(stress: np.ndarray) -> np.ndarray:
    """Von Mises stress sqrt(3/2 s:s), s the deviator; stress shape=(n, 3, 3) -> (n,)."""
    s = stress - np.trace(stress, axis1=1, axis2=2)[:, None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("nij,nij->n", s, s))


def principal_of(stress: np.ndarray) -> np.ndarray:
    """Principal stresses σ1 >= σ2 >= σ3; stress shape=(n, 3, 3) -> (n, 3)."""
    return np.linalg.eigvalsh(stress)[:, ::-1]


def probe_fields(
    problem: Any, fields: Sequence[str], points: np.ndarray, *, cells: np.ndarray
) -> dict[str, np.ndarray]:
    """The probe fields at points, each evaluated in the cell :func:`locate_points` chose.

    Stress and strain come from ``problem.point_tensors`` (the element's own field in
    that cell); von Mises and the principal stresses from the same stress tensor.
    Collective; identical on every rank.

    Args:
        problem: the solved :class:`~geofrac.fem.elastic.ElasticProblem`.
        fields: names from ``geofrac.scene.load.PROBE_FIELDS``.
        points: coordinates, shape=(n, 3).
        cells: result of :func:`locate_points`.

    Returns:
        field -> values, shape=(n, len(field_columns(field, gdim))).
    """
    gdim = problem.mesh.geometry.dim
    out: dict[str, np.ndarray] = {}
    if "displacement" in fields:
        out["displacement"] = probe(problem.uh, points, cells)
    wanted = {"strain"} & set(fields)
    if {"stress", "von_mises", "principal_stress"} & set(fields):
        wanted.add("stress")
    tensors = problem.point_tensors(sorted(wanted), points, cells) if wanted else {}
    pairs = [COMPONENT_INDEX[c] for c in tensor_components(gdim)]
    for name in ("stress", "strain"):
        if name in fields:
            out[name] = np.stack([tensors[name][:, i, j] for i, j in pairs], axis=1)
    if "von_mises" in fields:
        out["von_mises"] = von_mises_of(tensors["stress"])[:, None]
    if "principal_stress" in fields:
        out["principal_stress"] = principal_of(tensors["stress"])
    return out


def point_tensors(
    uh: dolfinx.fem.Function,
    lam: Any,
    mu: Any,
    *,
    plane: str,
    names: Sequence[str],
    points: np.ndarray,
    cells: np.ndarray,
    initial: Any = None,
    alive: Any = None,
) -> dict[str, np.ndarray]:
    """3×3 stress and/or strain of ``uh`` at points, in the given cells (collective).

    ``initial``: an initial stress (3×3) added to the stress; ``alive``: a factor of the
    fields, 0 on excavated cells (:func:`_quantities`).

    The cell's field (:func:`_quantities`) is interpolated into discontinuous Lagrange
    of the degree of ``uh`` and evaluated at the point: exact on affine cells, where the
    gradient of a degree-k field is a polynomial of degree k - 1 (Qk on parallelograms).

    Returns:
        name -> values, shape=(n, 3, 3), identical on every rank.
    """
    mesh = uh.function_space.mesh
    degree = uh.function_space.ufl_element().embedded_superdegree
    exprs = _quantities(uh, lam, mu, plane, initial=initial, alive=alive)
    space = dolfinx.fem.functionspace(mesh, ("DG", degree, (3, 3)))
    out = {}
    for name in names:
        f = dolfinx.fem.Function(space)
        f.interpolate(dolfinx.fem.Expression(exprs[name], space.element.interpolation_points))
        out[name] = probe(f, points, cells).reshape(-1, 3, 3)
    return out


def error_norms(
    uh: dolfinx.fem.Function, u_exact: Any, lam: Any, *, mu: Any, extra_degree: int = 4
) -> dict[str, float]:
    """Displacement L2 error and energy error (Edo (2016), eqs. 2.22 and 3.30b), plus norms.

    The exact field enters as a UFL expression, integrated with a quadrature degree of
    ``2 * max(degree(uh), 3) + extra_degree`` (exact fields here are up to cubic), so the
    exact solution is never interpolated.

    Returns:
        ``u``: ||u - u_exact||_L2, ``energy``: sqrt(∫ ½ (ε-ε_ex):(σ-σ_ex)),
        ``u_norm`` and ``energy_norm`` of the exact solution, and the relative errors.
    """
    mesh = uh.function_space.mesh
    degree = uh.function_space.ufl_element().embedded_superdegree
    dx = ufl.Measure(
        "dx", domain=mesh, metadata={"quadrature_degree": 2 * max(degree, 3) + extra_degree}
    )
    zero = ufl.as_vector([0.0] * mesh.geometry.dim)
    e_u = integrate(forms.l2_error_form(uh, u_exact, dx), mesh.comm)
    e_en = integrate(forms.energy_error_form(uh, u_exact, lam, mu, dx), mesh.comm)
    n_u = integrate(forms.l2_error_form(zero, u_exact, dx), mesh.comm)
    n_en = integrate(forms.energy_error_form(zero, u_exact, lam, mu, dx), mesh.comm)
    out = {
        "u": float(np.sqrt(e_u)),
        "energy": float(np.sqrt(e_en)),
        "u_norm": float(np.sqrt(n_u)),
        "energy_norm": float(np.sqrt(n_en)),
    }
    out["u_relative"] = out["u"] / out["u_norm"]
    out["energy_relative"] = out["energy"] / out["energy_norm"]
    return out


#: Tensor fields :func:`tensor_fields` can recover: name -> (quantity, recovery).
TENSOR_FIELDS = {
    "stress": ("stress", "cell"),
    "strain": ("strain", "cell"),
    "von_mises": ("von_mises", "cell"),
    "stress_nodal": ("stress", "nodal"),
    "strain_nodal": ("strain", "nodal"),
}


def _quantities(
    uh: dolfinx.fem.Function,
    lam: Any,
    mu: Any,
    plane: str,
    *,
    initial: Any = None,
    alive: Any = None,
) -> dict[str, Any]:
    """UFL stress (3×3), strain (3×3) and von Mises stress of ``uh``.

    In 2D the out-of-plane components are those of the analysis plane: plane strain
    has εzz = 0 and σzz = λ tr(ε); plane stress has σzz = 0 and εzz = -λ*/(2μ) tr(ε)
    = -ν/(1-ν) tr(ε) (λ* the plane-stress λ of :func:`geofrac.materials.lame`).

    With an ``initial`` stress σ0 (3×3) the stress is the total σ0 + σ(u) (the strain
    stays relative to the initial state); ``alive`` (1 on live cells, 0 on excavated
    ones) multiplies every field.
    """
    gdim = uh.function_space.mesh.geometry.dim
    sig, eps = forms.sigma(uh, lam, mu), forms.epsilon(uh)
    szz = ezz = 0.0
    if gdim == 2 and plane == "strain":
        szz = lam * ufl.tr(eps)
    elif gdim == 2:
        ezz = -lam / (2.0 * mu) * ufl.tr(eps)
    if initial is None and alive is None:
        return {
            "stress": forms.stress_3d(sig, szz),
            "strain": forms.stress_3d(eps, ezz),
            "von_mises": forms.von_mises(sig, szz),
        }
    stress = forms.stress_3d(sig, szz) + (0 if initial is None else initial)
    factor = 1.0 if alive is None else alive
    return {
        "stress": factor * stress,
        "strain": factor * forms.stress_3d(eps, ezz),
        "von_mises": factor * forms.von_mises(stress),
    }


def _nodal_average(expr: Any, mesh: dolfinx.mesh.Mesh, shape: tuple[int, ...], name: str) -> Any:
    """Vertex values: the mean over the owned cells around each vertex of the cell's value there.

    The expression is interpolated into discontinuous P1 (exact at the vertices for the
    linear stress of P2, RGNT, GNT and RGNQ fields), summed per vertex over owned cells,
    summed across ranks, and divided by the number of cells.
    """
    dg = dolfinx.fem.functionspace(mesh, ("DG", 1, shape))
    cg = dolfinx.fem.functionspace(mesh, ("Lagrange", 1, shape))
    d = dolfinx.fem.Function(dg)
    d.interpolate(dolfinx.fem.Expression(expr, dg.element.interpolation_points))
    out = dolfinx.fem.Function(cg, name=name)
    count = dolfinx.la.vector(cg.dofmap.index_map, 1)
    num_owned = mesh.topology.index_map(mesh.topology.dim).size_local
    bs = int(np.prod(shape)) if shape else 1
    d_cells = dg.dofmap.list[:num_owned]  # shape=(num_owned, nv), same vertex order as cg
    c_cells = cg.dofmap.list[:num_owned]
    vals = d.x.array.reshape(-1, bs)[d_cells]  # shape=(num_owned, nv, bs)
    acc = out.x.array.reshape(-1, bs)
    np.add.at(acc, c_cells.ravel(), vals.reshape(-1, bs))
    np.add.at(count.array, c_cells.ravel(), 1.0)
    out.x.scatter_reverse(dolfinx.la.InsertMode.add)
    count.scatter_reverse(dolfinx.la.InsertMode.add)
    n = cg.dofmap.index_map.size_local
    acc[:n] /= count.array[:n, None]
    out.x.scatter_forward()
    return out


def tensor_fields(
    uh: dolfinx.fem.Function,
    lam: Any,
    mu: Any,
    *,
    plane: str,
    names: Sequence[str],
    initial: Any = None,
    alive: Any = None,
) -> dict[str, dolfinx.fem.Function]:
    """Stress, strain and von Mises fields of ``uh`` for XDMF output.

    Cell fields are DG0 (value at the cell midpoint); nodal fields (``*_nodal``) are P1,
    the average over the cells around a vertex of each cell's value at that vertex.
    Tensors are always 3×3 (see :func:`_quantities`): DOLFINx's XDMF writer pads a 2×2
    tensor as (xx, xy, yx, yy, 0, ...), which ParaView would read as a wrong 3×3 tensor.

    Args:
        uh: displacement (any Lagrange degree).
        lam: Lamé λ of the analysis plane.
        mu: shear modulus μ.
        plane: ``"stress"`` or ``"strain"`` (ignored in 3D).
        names: keys of :data:`TENSOR_FIELDS` to compute.
        initial: an initial stress (3×3) added to the stress, or None.
        alive: a DG0 factor, 0 on excavated cells, or None.

    Returns:
        name -> function; tensors shape=(3, 3) per cell or vertex, von Mises scalar.
    """
    mesh = uh.function_space.mesh
    exprs = _quantities(uh, lam, mu, plane, initial=initial, alive=alive)
    out = {}
    for name in names:
        quantity, recovery = TENSOR_FIELDS[name]
        shape = () if quantity == "von_mises" else (3, 3)
        if recovery == "nodal":
            out[name] = _nodal_average(exprs[quantity], mesh, shape, name)
            continue
        space = dolfinx.fem.functionspace(mesh, ("DG", 0, shape))
        f = dolfinx.fem.Function(space, name=name)
        f.interpolate(dolfinx.fem.Expression(exprs[quantity], space.element.interpolation_points))
        out[name] = f
    return out
