"""Pressure, point and expression loads against closed forms.

Lamé's thick cylinder (Timoshenko & Goodier, §28) in 2D and 3D; resultants and first
moments of hydrostatic pressures, expression tractions and body forces; a point load's
resultant on every 2D element and a cantilever under a point tip load against the
Timoshenko beam solution (Edo (2016), eq. 2.24-2.25).
"""

from pathlib import Path

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.elements import make_element
from geofrac.errors import RunError
from geofrac.fem.elastic import ElasticProblem, make_problem
from geofrac.meshing.distribute import build_mesh
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS
from tests.fem.helpers import solve_job

HERE = Path(__file__).resolve().parent
BEAM = HERE / "point_beam.toml"  # L = 10, D = 1 cantilever with a physical point at (L, 0)


def _problem(path: Path, *overrides: str) -> ElasticProblem:
    """The elastic problem of a scene, assembled by nobody yet; the caller destroys it."""
    comm = MPI.COMM_WORLD
    scene = load_scene_collective(comm, path, overrides)
    tagged = build_mesh(scene.geometry, comm)
    element = make_element(scene.discretization.element, tagged.mesh)
    return make_problem(tagged, element, scene)


def _sums(problem: ElasticProblem, weight: int | None = None) -> np.ndarray:
    """Σ_i b_i,c, or Σ_i b_i,c x_i[weight], over all ranks, shape=(gdim,).

    b is the load vector on ``element.space`` (owned nodes). With ``weight``, Σ b·v for
    v = x[weight] e_c, which P1 and P2 interpolate exactly.
    """
    V = problem.element.space
    b = ElasticProblem.load_vector(problem)  # on the displacement space itself
    bs = V.dofmap.index_map_bs
    n = V.dofmap.index_map.size_local
    values = b.array_r.reshape(-1, bs)[:n]
    b.destroy()
    if weight is not None:
        values = values * V.tabulate_dof_coordinates()[:n, weight : weight + 1]
    return MPI.COMM_WORLD.allreduce(values.sum(axis=0), op=MPI.SUM)


# --- Lamé's thick cylinder ------------------------------------------------------------


@pytest.mark.parametrize(("plane", "dim"), [("strain", 2), ("stress", 2), ("strain", 3)])
def test_lame_solution_satisfies_its_boundary_conditions_and_hooke(plane, dim):
    # σ_rr(a) = -p, σ_rr(b) = -p_outer, and σ = λ tr ε I + 2μ ε with ε from the
    # displacement (complex-step gradient), in the plane of the solution
    from geofrac.analytic import displacement_gradient, make_exact
    from geofrac.materials import lame

    name = "lame_cylinder" if dim == 2 else "lame_cylinder_3d"
    ex = make_exact(
        name, {"a": 1.0, "b": 2.5, "p": 7.0, "p_outer": 2.0}, E=900.0, nu=0.3, plane=plane
    )
    assert ex.radial_stress(1.0) == pytest.approx(-7.0, rel=1e-14)
    assert ex.radial_stress(2.5) == pytest.approx(-2.0, rel=1e-14)
    rng = np.random.default_rng(1)
    r, t = rng.uniform(1.0, 2.5, 20), rng.uniform(0.0, np.pi / 2, 20)
    pts = np.stack([r * np.cos(t), r * np.sin(t), np.zeros(20)], axis=1)[:, :dim]
    g = displacement_gradient(ex, pts)
    eps = 0.5 * (g + g.transpose(0, 2, 1))
    lam, mu = lame(900.0, 0.3, dim, plane=plane)
    hooke = lam * np.trace(eps, axis1=1, axis2=2)[:, None, None] * np.eye(dim) + 2 * mu * eps
    stress = np.array(ex.stress(*pts.T), dtype=float).transpose(2, 0, 1)
    assert np.allclose(hooke, stress, rtol=0, atol=1e-12 * 7.0)
    u = np.array(ex.displacement(*pts.T), dtype=float)
    assert np.allclose(u[0] * pts[:, 0] + u[1] * pts[:, 1], r * ex.radial_displacement(r))


def _lame_errors(h: float, plane: str) -> tuple[float, float]:
    """(relative error of u_r at (a, 0), relative energy error) of jobs/thick_cylinder."""
    sol = solve_job(
        "thick_cylinder",
        f"geometry.parameters.h={h}",
        f"material.plane={plane}",
        "output.xdmf=false",
    )
    sol.problem.destroy()
    r = sol.results
    u, exact = r["probes"]["inner"][0], r["exact_probes"]["inner"][0]
    return abs(u - exact) / exact, r["errors"]["energy_relative"]


@pytest.mark.mpi
@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_lame_cylinder_2d_converges_at_rate_two(plane):
    # P2 on straight-sided cells: the polygonal boundary (chord sag h²/8a) limits the
    # error to O(h²) in u and in energy; measured 8.2e-3 -> 2.0e-3 (u_r at r = a) and
    # 1.2e-2 -> 3.0e-3 (energy) in plane strain.
    e1, w1 = _lame_errors(0.2, plane)
    e2, w2 = _lame_errors(0.1, plane)
    assert e1 < 1.5e-2
    assert e2 < 4e-3
    assert np.log2(e1 / e2) > 1.8
    assert np.log2(w1 / w2) > 1.8


@pytest.mark.mpi
def test_lame_cylinder_3d_matches_plane_strain():
    # u_z = 0 at both ends: the plane-strain solution. Coarse mesh (h = 0.25 = a/4):
    # measured 1.1e-2 on u_r at r = a and 1.6e-2 in energy; the 2D O(h²) bound at this
    # h (from the 2D rates above: 8.2e-3 × (0.25/0.2)² = 1.3e-2) plus the 3D mesh.
    sol = solve_job("thick_cylinder_3d", "output.xdmf=false")
    sol.problem.destroy()
    r = sol.results
    u, exact = r["probes"]["inner"], r["exact_probes"]["inner"]
    assert exact[0] == pytest.approx(1.3e-3 * (0.4 * 10 / 3 + 40 / 3), rel=1e-12)
    assert abs(u[0] - exact[0]) / exact[0] < 2e-2
    assert abs(u[2]) < 1e-3 * exact[0]
    assert r["errors"]["energy_relative"] < 2.5e-2


def test_pressure_as_a_constant_expression_equals_the_number():
    a = _problem(JOBS / "thick_cylinder.toml", "geometry.parameters.h=0.3")
    b = _problem(
        JOBS / "thick_cylinder.toml",
        "geometry.parameters.h=0.3",
        'load.0.value="2*5 + 0*x*y"',
    )
    va, vb = a.load_vector(), b.load_vector()
    assert va.norm() > 1.0
    vb.axpy(-1.0, va)
    assert vb.norm() < 1e-12 * va.norm()
    for obj in (va, vb):
        obj.destroy()
    a.destroy()
    b.destroy()


# --- expressions: hydrostatic pressure, traction, body force ------------------------------


@pytest.mark.mpi
def test_hydrostatic_pressure_resultant_and_moment():
    # p = ρg (D/2 - y) on the end x = L (outward normal +x) of the D = 1 beam, t = 0.5:
    # traction -p n = -p e_x; resultant -t ρg D²/2, first moment Σ b_x y = t ρg D³/12
    t, rho_g = 0.5, 3.0
    common = (
        f"material.thickness={t}",
        "load.0.type=pressure",
        "load.0.group=end",
    )
    p = _problem(BEAM, *common, f'load.0.value="{rho_g}*(0.5 - y)"')
    force, moment = _sums(p), _sums(p, weight=1)
    p.destroy()
    assert force[0] == pytest.approx(-t * rho_g / 2, rel=1e-12)
    assert force[1] == pytest.approx(0.0, abs=1e-12)
    assert moment[0] == pytest.approx(t * rho_g / 12, rel=1e-12)
    # the same load written as a traction expression
    q = _problem(BEAM, *common, "load.0.type=traction", f'load.0.value=["-{rho_g}*(0.5 - y)", 0]')
    assert _sums(q) == pytest.approx(force, abs=1e-12)
    assert _sums(q, weight=1) == pytest.approx(moment, abs=1e-12)
    q.destroy()


@pytest.mark.mpi
def test_body_force_expression_resultant():
    # b = (0, -3x²) on [0, 10] x [-0.5, 0.5], t = 0.5: resultant -t L³ D = -500
    p = _problem(
        BEAM,
        "material.thickness=0.5",
        "load.0.value=[0, 0]",
        'load.1.value=[0, "-3*x**2"]',
    )
    force = _sums(p)
    p.destroy()
    assert force == pytest.approx([0.0, -500.0], rel=1e-12, abs=1e-9)


# --- point loads ------------------------------------------------------------------------


@pytest.mark.mpi
@pytest.mark.parametrize("element", ["p1", "p2", "p3", "rgnt", "gnt", "efmm"])
def test_point_load_resultant_on_every_element(element):
    # F = (0.3, -2) per unit thickness, t = 0.5: the load vector on the unknowns carries
    # t F once (one owning rank); for the vertex-DOF elements Σ over translations of
    # Tᵀ b is F·(T w) for the rigid translation w, i.e. Σ b on P2.
    p = _problem(
        BEAM,
        f"discretization.element={element}",
        "material.thickness=0.5",
        "load.0.value=[0.3, -2.0]",
    )
    b = p.load_vector()
    space = getattr(p.element, "unknowns", p.element.space)
    bs, n = space.dofmap.index_map_bs, space.dofmap.index_map.size_local
    local = b.array_r.reshape(-1, bs)[:n, :2].sum(axis=0)
    b.destroy()
    p.destroy()
    total = MPI.COMM_WORLD.allreduce(local, op=MPI.SUM)
    assert total == pytest.approx([0.15, -1.0], rel=1e-12)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("element", ["p2", "gnt"])
def test_point_load_on_a_vertex_shared_by_two_ranks_counts_once(element):
    # 4 cells (nx = 1, ny = 2) all touching the tip: the tip vertex is on both ranks
    comm = MPI.COMM_WORLD
    p = _problem(
        BEAM,
        f"discretization.element={element}",
        "geometry.parameters.nx=1",
        "geometry.parameters.ny=2",
    )
    _, vertices = p.tagged.entities("tip")
    assert comm.allreduce(int(len(vertices) > 0), op=MPI.SUM) == 2  # the case under test
    rows = len(p.point_forces.rows)
    b = p.load_vector()
    space = getattr(p.element, "unknowns", p.element.space)
    bs, n = space.dofmap.index_map_bs, space.dofmap.index_map.size_local
    total = comm.allreduce(b.array_r.reshape(-1, bs)[:n, :2].sum(axis=0), op=MPI.SUM)
    b.destroy()
    p.destroy()
    assert total == pytest.approx([0.0, 1.0], rel=1e-12)
    assert comm.allreduce(rows, op=MPI.SUM) == 2  # u_x and u_y of one node
    assert comm.allreduce(int(rows > 0), op=MPI.SUM) == 1


@pytest.mark.mpi
@pytest.mark.parametrize("element", ["p2", "gnt"])
def test_cantilever_under_a_point_tip_load_follows_beam_theory(element):
    # P at (L, 0) instead of the parabolic end shear of the same resultant: by Saint-Venant
    # the Timoshenko solution holds away from the end (the difference decays as e^(-πx/D)),
    # so at x = L/2 (5 depths away) only the discretisation error remains (P2 on 40 x 4:
    # measured 1.2e-5; GNT 7e-7).
    comm = MPI.COMM_WORLD
    scene = load_scene_collective(comm, BEAM, [f"discretization.element={element}"])
    sol = solve_scene(scene, comm, verbose=False)
    sol.problem.destroy()
    r = sol.results
    v, exact = r["probes"]["middle"][1], r["exact_probes"]["middle"][1]
    assert exact == pytest.approx(12.625, rel=1e-12)  # P x²(3L - x)/6EI + shear term
    assert v == pytest.approx(exact, rel=1e-3)


def test_point_load_on_a_group_of_two_points_is_refused():
    with pytest.raises(RunError, match="'corners' has 2 mesh vertices; a point load needs"):
        _problem(BEAM, "load.0.group=corners")
