"""Loads that do not scale together: ``cracking.constant`` (DeJong, Hendriks and Rots 2008).

- A beam (scenes/beam_axial.toml, RGNT) bent by a scaled pressure under a constant axial
  compression σ_c = −N/A: with N = 0 the event log equals the proportional run's, bit for
  bit; with N > 0 the first crack's factor rises to λ_N = λ_0 (1 + (N/A)/f_t) (beam
  theory at the crack site, whose σ1 lies along the axis), within 2 %.
- A plate (scenes/plate_confined.toml, CST) under constant biaxial compression pulled by
  a scaled traction along its bottom: the first site and λ agree with an independent
  evaluation from two plain elastic solves (DOLFINx's assembly and solver, CST stresses
  in numpy, λ by bisection on the definition).
- Sites over their strength under the constant load alone crack first, at λ = 0, the
  most overstressed first.
- The three solver strategies give the same events; 1 and 2 ranks too (MPI test).
"""

from pathlib import Path

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects import linear_terms
from geofrac.effects.cracking import scene_driver
from geofrac.elements import make_element
from geofrac.fem.elastic import make_problem
from geofrac.fracture.driver import CrackDriver
from geofrac.meshing.distribute import build_mesh
from geofrac.scene import SceneError, load_scene_collective

SCENES = Path(__file__).resolve().parent / "scenes"
BEAM = SCENES / "beam_axial.toml"
PLATE = SCENES / "plate_confined.toml"
#: the plate's f_t, E, ν and its constant compressions p (x) and q (y).
FT, E, NU, P, Q = 3.0, 100.0, 0.25, 1.0, 2.0


def run(scene: Path, *overrides: str, comm: MPI.Comm = MPI.COMM_SELF) -> tuple[CrackDriver, dict]:
    """Run ``scene`` with ``overrides`` on ``comm``: the driver (its rows) and the results."""
    driver = scene_driver(load_scene_collective(comm, scene, overrides), comm)
    try:
        return driver, driver.run()
    finally:
        driver.problem.destroy()


def cst_stress(scene: Path, *overrides: str) -> tuple[np.ndarray, dict, np.ndarray]:
    """A plain elastic solve of ``scene`` (one rank): CST stress per cell and edge cells.

    DOLFINx assembles and solves the scene's loads (no crack driver); the stress of each
    triangle follows from its vertex displacements in numpy (plane stress, E, ν of the
    plate). Returns (stress, shape=(num_cells, 3); edge midpoint (rounded) -> cells;
    cell areas, shape=(num_cells,)).
    """
    scene_ = load_scene_collective(MPI.COMM_SELF, scene, overrides)
    tagged = build_mesh(scene_.geometry, MPI.COMM_SELF)
    element = make_element(scene_.discretization.element, tagged.mesh)
    problem = make_problem(tagged, element, scene_, terms=linear_terms(scene_.effects))
    try:
        u = problem.solve()
        mesh = tagged.mesh
        V = u.function_space
        nc = mesh.topology.index_map(2).size_local
        x = mesh.geometry.x[:, :2][mesh.geometry.dofmaps[0][:nc]]  # (nc, 3, 2)
        disp = u.x.array.reshape(-1, 2)[V.dofmap.list[:nc]]  # (nc, 3, 2)
        d = np.stack([x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]], axis=2)  # columns: edges
        g = np.stack([disp[:, 1] - disp[:, 0], disp[:, 2] - disp[:, 0]], axis=2)
        grad = g @ np.linalg.inv(d)  # ∂u_i/∂x_j, (nc, 2, 2)
        eps = np.stack([grad[:, 0, 0], grad[:, 1, 1], grad[:, 0, 1] + grad[:, 1, 0]], axis=1)
        D = E / (1 - NU**2) * np.array([[1, NU, 0], [NU, 1, 0], [0, 0, (1 - NU) / 2]])
        stress = eps @ D.T
        mesh.topology.create_connectivity(1, 2)
        e2c = mesh.topology.connectivity(1, 2)
        n_edges = mesh.topology.index_map(1).size_local
        ends = dolfinx.mesh.entities_to_geometry(mesh, 1, np.arange(n_edges, dtype=np.int32))
        mids = mesh.geometry.x[ends][:, :, :2].mean(axis=1)
        cells = {key(m): list(e2c.links(e)) for e, m in enumerate(mids)}
        return stress, cells, 0.5 * np.abs(np.linalg.det(d))
    finally:
        problem.destroy()


def key(point: np.ndarray) -> tuple[float, float]:
    return (round(float(point[0]), 8), round(float(point[1]), 8))


def sigma1(s: np.ndarray) -> np.ndarray:
    return 0.5 * (s[..., 0] + s[..., 1]) + np.hypot(0.5 * (s[..., 0] - s[..., 1]), s[..., 2])


def site_factor(sc: np.ndarray, sv: np.ndarray) -> float:
    """Least λ with mean σ1(σ_c + λ σ_v) over the site's cells = f_t (bisection); inf if none."""

    def f(lam: float) -> float:
        return float(np.mean(sigma1(sc + lam * sv))) - FT

    if f(0.0) >= 0.0:
        return 0.0
    hi = 1.0
    while f(hi) < 0.0:
        hi *= 2.0
        if hi > 1e12:
            return np.inf
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < 0.0 else (lo, mid)
    return hi


def shear_factor(sc: np.ndarray, sv: np.ndarray, t: np.ndarray, c: float, phi: float) -> float:
    """Least λ of Mohr-Coulomb failure on the plane of tangent t (bisection); inf if none.

    σ the mean of the site's cells' stress; σn = n·σ n (tension > 0), τ = t·σ n.
    """
    n = np.array([-t[1], t[0]])
    mu = np.tan(np.radians(phi))

    def g(lam: float) -> float:
        sx, sy, sxy = np.mean(sc + lam * sv, axis=0)
        tr = np.array([sx * n[0] + sxy * n[1], sxy * n[0] + sy * n[1]])
        return abs(float(tr @ t)) + float(tr @ n) * mu - c

    if g(0.0) >= 0.0:
        return 0.0
    hi = 1.0
    while g(hi) < 0.0:
        hi *= 2.0
        if hi > 1e12:
            return np.inf
    lo = 0.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(mid) < 0.0 else (lo, mid)
    return hi


def independent(scene: Path, constant: list[str], variable: list[str], *overrides: str):
    """Per crackable edge of the intact plate: λ and the overstress ratio, independently.

    Two plain elastic solves: the constant loads alone (the variable ones set to zero)
    and the variable ones alone. ``constant``, ``variable``: ``load.i.value`` overrides
    that zero each. Returns {edge midpoint: (λ, mean σ1(σ_c)/f_t)} over the edges the
    driver may crack.
    """
    sc, cells, _ = cst_stress(scene, *overrides, *variable)
    sv, _, _ = cst_stress(scene, *overrides, *constant)
    driver = scene_driver(load_scene_collective(MPI.COMM_SELF, scene, overrides), MPI.COMM_SELF)
    try:
        state = driver.state
        points = driver.criterion.points
        out = {}
        mat = driver.ctx.scene.material
        coh, phi = getattr(mat, "cohesion", None), getattr(mat, "friction_angle", 0.0)
        xy = state.mesh.coords[:, :2]
        for e in np.flatnonzero(state.crackable & ~state.cracked):
            c = cells[key(points[e])]
            ratio = float(np.mean(sigma1(sc[c]))) / FT
            lam_s = np.inf
            if coh is not None:
                a, b = state.mesh.edges[e]
                t = (xy[b] - xy[a]) / np.hypot(*(xy[b] - xy[a]))
                lam_s = shear_factor(sc[c], sv[c], t, coh, phi)
            out[key(points[e])] = (site_factor(sc[c], sv[c]), ratio, lam_s)
        return out
    finally:
        driver.problem.destroy()


# -- the beam --------------------------------------------------------------------------


@pytest.mark.parametrize("criterion", ["direction", "principal"])
def test_zero_constant_load_repeats_the_proportional_run(criterion):
    """N = 0: the run with a constant group equals the run without, bit for bit."""
    sets = (f"cracking.criterion={criterion}", "cracking.max_events=12")
    plain, res_p = run(BEAM, "cracking.constant=[]", *sets)
    const, res_c = run(BEAM, *sets)
    assert "constant" not in res_p and res_c["constant"]["groups"] == ["tip"]
    assert len(plain.rows) == 12
    assert const.rows == plain.rows  # every column, exactly


def test_axial_compression_raises_the_first_crack_by_beam_theory():
    """λ_N = λ_0 (1 + s/f_t), s = N/A, at the crack site (σ1 along the beam's axis).

    Beam theory at the site: σ_c = −s (uniform compression, exact in the FE model away
    from the end support: the linear displacement of a uniform stress is in the element
    space) and σ_v = σ_xx e_x e_x, so σ1(σ_c + λ σ_v) = −s + λ σ_xx and the root is
    (f_t + s)/σ_xx, λ_0 (1 + s/f_t) with λ_0 = f_t/σ_xx. The FE σ_v at the site also has
    a small σ_yy (the pressure) and shear (the element's), so σ1(σ_v) > σ_xx and the
    measured λ_N falls below the beam-theory value by a relative 0.7 % at s = f_t (RGNT,
    4 elements through the depth).
    """
    sets = ("discretization.element=rgnt", "cracking.max_events=1")
    base, _ = run(BEAM, *sets)
    lam0 = base.rows[0]["load_factor"]
    for s in (0.5, 1.0, 2.0):
        beam, res = run(BEAM, *sets, f"load.1.value=[{-s}, 0.0]")
        row = beam.rows[0]
        assert row["edge"] == base.rows[0]["edge"] and row["mode"] == "tension"
        assert row["load_factor"] == pytest.approx(lam0 * (1.0 + s / 1.0), rel=0.02)
        assert res["constant"]["cracked_at_zero"] == 0


# -- the plate -------------------------------------------------------------------------

#: overrides that zero the constant loads, and the variable load (the plain solves do not
#: read [cracking]; its control must still name a non-zero load)
CONSTANT = ["load.1.value=[0.0, 0.0]", "load.2.value=[0.0, 0.0]", "cracking.constant=[]"]
VARIABLE = ["load.0.value=[0.0, 0.0]", "cracking.constant=[]", "cracking.control=right"]


def test_constant_part_is_the_uniform_biaxial_compression():
    """The plain solve of the constant loads alone: σ = (−p, −q, 0) in every cell."""
    sc, _, _ = cst_stress(PLATE, *VARIABLE)
    np.testing.assert_allclose(sc, np.tile([-P, -Q, 0.0], (len(sc), 1)), atol=1e-12)


def test_event_state_is_the_superposed_one():
    """The first event's state is σ_c + λ σ_v: its energy and force.

    Energy from the plain solves, E = ½ t Σ A σ·C⁻¹σ; the force is λ F, F = 0.4 × 5 × 2
    the bottom traction's resultant.
    """
    sc, _, area = cst_stress(PLATE, *VARIABLE)
    sv, _, _ = cst_stress(PLATE, *CONSTANT)
    driver, _ = run(PLATE, "cracking.max_events=1")
    row = driver.rows[0]
    lam = row["load_factor"]
    s = sc + lam * sv
    compliance = np.array([[1, -NU, 0], [-NU, 1, 0], [0, 0, 2 * (1 + NU)]]) / E
    energy = 0.5 * 2.0 * float(np.sum(area * np.einsum("ci,ij,cj->c", s, compliance, s)))
    assert row["strain_energy"] == pytest.approx(energy, rel=1e-9)
    assert row["reaction"] == pytest.approx(lam * 0.4 * 5.0 * 2.0, rel=1e-12)


def test_plate_cracks_where_the_superposed_field_first_reaches_ft():
    ref = independent(PLATE, CONSTANT, VARIABLE)
    site = min(ref, key=lambda k: ref[k][0])
    lam = ref[site][0]
    assert all(ratio < 1.0 for _, ratio, _ in ref.values())
    driver, res = run(PLATE, "cracking.max_events=1")
    row = driver.rows[0]
    assert (round(row["x"], 8), round(row["y"], 8)) == site
    assert row["load_factor"] == pytest.approx(lam, rel=1e-9)
    assert res["constant"] == {
        "groups": ["right", "top"],
        "overstressed_at_start": 0,
        "cracked_at_zero": 0,
    }


def test_shear_event_against_plain_solves():
    """A shear event: the least λ over tension and Mohr-Coulomb shear, independently.

    With cohesion 1.5 and φ = 30° the least λ over both (plain solves, bisection) is a
    shear one here; the run finds its site and λ.
    """
    mat = ("material.cohesion=1.5", "material.friction_angle=30")
    ref = independent(PLATE, CONSTANT, VARIABLE, *mat)
    site = min(ref, key=lambda k: min(ref[k][0], ref[k][2]))
    lam, mode = min((ref[site][0], "tension"), (ref[site][2], "shear"))
    assert mode == "shear"
    driver, _ = run(PLATE, "cracking.max_events=1", *mat)
    row = driver.rows[0]
    assert (round(row["x"], 8), round(row["y"], 8)) == site and row["mode"] == mode
    assert row["load_factor"] == pytest.approx(lam, rel=1e-9)


@pytest.mark.parametrize("solver", ["refactor", "reuse"])
def test_solver_strategies_agree(solver):
    """Ten events: the update solver's (one factorisation) equal the others' to 1e-9."""
    ref, _ = run(PLATE, "cracking.max_events=10")
    other, _ = run(PLATE, "cracking.max_events=10", f"cracking.solver={solver}")
    assert [r["edge"] for r in other.rows] == [r["edge"] for r in ref.rows]
    for k in ("load_factor", "reaction", "control_displacement", "strain_energy"):
        np.testing.assert_allclose(
            [r[k] for r in other.rows], [r[k] for r in ref.rows], rtol=1e-9, err_msg=k
        )


# -- overstressed at the start ---------------------------------------------------------

TENSILE_TOP = ('load.2.value=[0.0, "1.0 + 0.5 * x"]',)


def test_overstressed_sites_crack_first_most_overstressed_first():
    """Sites over f_t under the constant load alone crack first, most overstressed first.

    A tensile top traction 1 + x/2 brings the top right over f_t under the constant
    load alone; those sites crack first at λ = 0, the most overstressed (by an
    independent plain solve) first, and the run counts them.

    Each crack redistributes the constant load, so the next most overstressed site is
    that of the new state: later λ = 0 events may even follow a scaled one.
    """
    ref = independent(PLATE, CONSTANT, VARIABLE, *TENSILE_TOP)
    over = {k: r for k, (_, r, _) in ref.items() if r >= 1.0}
    assert len(over) >= 2
    driver, res = run(PLATE, "cracking.max_events=6", *TENSILE_TOP)
    rows = driver.rows
    zero = [r for r in rows if r["load_factor"] == 0.0]
    lead = next(i for i, r in enumerate(rows) if r["load_factor"] > 0.0)
    assert lead >= 1  # the run starts with λ = 0 events
    # (cracks redistribute the constant load: later λ = 0 events may follow a scaled one)
    first = (round(rows[0]["x"], 8), round(rows[0]["y"], 8))
    assert first == max(over, key=lambda k: over[k])
    assert res["constant"]["overstressed_at_start"] == len(over)
    assert res["constant"]["cracked_at_zero"] == len(zero)
    # the event's state is the constant load's: no reaction of the scaled load
    assert rows[0]["reaction"] == 0.0


# -- scene errors ----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("cracking.constant=['bottom']", "is the control group"),
        ("cracking.constant=['nowhere']", "has no [[bc]]"),
        ("cracking.constant=['gravity']", "gravity"),
        ("cracking.constant='top'", "must be a list"),
    ],
)
def test_bad_constant_is_refused(override, message):
    with pytest.raises(SceneError, match=r"cracking\.constant") as err:
        load_scene_collective(MPI.COMM_SELF, PLATE, [override])
    assert message in str(err.value)


# -- 1 and 2 ranks ---------------------------------------------------------------------


@pytest.mark.mpi(min_size=2)
def test_same_events_on_1_and_2_ranks():
    sets = ("geometry.parameters.h=0.5", "cracking.max_events=8")
    parallel, res = run(PLATE, *sets, comm=MPI.COMM_WORLD)
    serial, ref = run(PLATE, *sets, comm=MPI.COMM_SELF)
    assert len(parallel.rows) == len(serial.rows) == 8
    assert [r["edge"] for r in parallel.rows] == [r["edge"] for r in serial.rows]
    for k in ("load_factor", "reaction", "control_displacement", "strain_energy"):
        np.testing.assert_allclose(
            [r[k] for r in parallel.rows], [r[k] for r in serial.rows], rtol=1e-8, err_msg=k
        )
    edges = MPI.COMM_WORLD.allgather([r["edge"] for r in parallel.rows])
    assert all(e == edges[0] for e in edges)
    assert res["constant"] == ref["constant"]
