"""Support installed by a stage of a cracking scene (``[[stages]]`` with ``add``).

The lined opening of tests/fem/lined.toml as a cracking scene (scenes/lined_cracking.toml:
CST on straight cells, L = 20a, h = 0.05a): a circular opening (a = 1) under hydrostatic
σ0 = −p I, p = 10, E = 10⁴, ν = 0.25, plane strain, excavated with λ = 0.4 of its
release, then a ring b < r < a (b = 0.9, E_l = 3·10⁴, ν_l = 0.2) installed stress-free
and the rest released. The closed form of the ground-support interaction (Brady and
Brown (2004), §7.3; tests/fem/test_insitu.py): the rock's wall moves by −λ p a/(2G),
then by −((1 − λ) p − p_s) a/(2G); the ring is Lamé's cylinder under the external
pressure p_s = (1 − λ) p/(1 + 2 G k), k = (1 + ν_l)/E_l ((1 − 2ν_l) a² + b²)/(a² − b²),
with σθθ = −p_s a² (1 + b²/r²)/(a² − b²).

- With strengths no stress reaches, the crack driver gives the elastic staged run on the
  same mesh (P1 = CST) to round-off, and both the closed form: the wall displacement of
  each stage and the support pressure (from the ring's hoop thrust) within 1 %.
- Released from a tensile σ0 = +p I (every closed form with p → −p: the ring is pulled
  outward, σθθ > 0 largest at r = b) with a ring of strength f_s below its final hoop
  stress, the first crack is an edge of the ring's inner layer, at the share where the
  closed-form σθθ at the edge's midpoint reaches f_s (3 %: half a mesh size times
  |∂σθθ/∂r|/σθθ at r = b is 2.8 %); nothing cracks before the ring is installed.
- 1 and 2 ranks crack the same edges at the same λ (MPI test).
"""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.fem.post import locate_points, probe_fields
from geofrac.runner import solve_scene
from geofrac.scene import SceneError, load_scene_collective

SCENES = Path(__file__).resolve().parent / "scenes"
LINED = SCENES / "lined_cracking.toml"
ELASTIC = SCENES.parents[1] / "fem" / "lined.toml"
#: in-situ p, rock E, ν, ring E_l, ν_l, radii a, b, the first stage's share, mesh size h.
P, E, NU, E_L, NU_L, A, B, LAM, H = 10.0, 1.0e4, 0.25, 3.0e4, 0.2, 1.0, 0.9, 0.4, 0.05
G = E / (2 * (1 + NU))
K = (1 + NU_L) / E_L * ((1 - 2 * NU_L) * A * A + B * B) / (A * A - B * B)
PS = (1 - LAM) * P / (1 + 2 * G * K)  # the support pressure at the end
#: the ray along which the ring's thrust is integrated (off the symmetry lines).
RAY = np.linspace(B, A, 401)[:-1] + (A - B) / 800


def hoop(r: np.ndarray | float, ps: float) -> np.ndarray | float:
    """The ring's σθθ at radius r under the external pressure ps (Lamé)."""
    return -ps * A * A * (1 + B * B / (np.asarray(r) ** 2)) / (A * A - B * B)


def crack_run(path: Path, *overrides: str, comm: MPI.Comm = MPI.COMM_SELF):
    """Run a cracking scene; (event rows, results, the ring's σθθ along :data:`RAY`)."""
    driver = scene_driver(load_scene_collective(comm, path, list(overrides)), comm)
    try:
        results = driver.run()
        return driver.rows, results, ring_hoop(driver.problem)
    finally:
        driver.problem.destroy()


def ring_hoop(problem) -> np.ndarray:
    """σθθ of the problem's final state along :data:`RAY` at 45°, shape=(len(RAY),)."""
    c = s = np.sqrt(0.5)
    pts = np.zeros((len(RAY), 3))
    pts[:, 0], pts[:, 1] = RAY * c, RAY * s
    cells = locate_points(problem.mesh, pts)
    stress = probe_fields(problem, ["stress"], pts, cells=cells)["stress"]
    sxx, syy, sxy = stress[:, 0], stress[:, 1], stress[:, 3]  # xx, yy, zz, xy
    return sxx * s * s + syy * c * c - 2 * sxy * s * c


def tensile(tmp: Path, strength: float) -> Path:
    """The lined scene released from σ0 = +p I with a ring of tensile strength ``strength``."""
    text = LINED.read_text().replace("../../fem/lined.geo", str(ELASTIC.parent / "lined.geo"))
    text = text.replace("stress = [-10.0, -10.0, 0.0]", "stress = [10.0, 10.0, 0.0]")
    text = text.replace("tensile_strength = 1.0e9 }", f"tensile_strength = {strength!r} }}")
    text = text.replace("max_events = 2", "max_events = 1")
    path = tmp / "tensile.toml"
    path.write_text(text)
    return path


def test_uncracked_lining_is_the_elastic_run_and_the_closed_form():
    rows, res, stt = crack_run(LINED)
    assert rows == [] and res["end_reason"] == "stages_done"
    first, last = res["stages"]
    assert first["added"] == [] and last["added"] == ["ring"] and last["released"] == 1.0
    elastic = solve_scene(
        load_scene_collective(
            MPI.COMM_SELF,
            ELASTIC,
            [
                "geometry.parameters.order=1",
                "geometry.parameters.L=20.0",
                'discretization.element="p1"',
                "output.lines={}",
            ],
        ),
        MPI.COMM_SELF,
        verbose=False,
    )
    try:
        ref = elastic.results["stages"]
        stt_ref = ring_hoop(elastic.problem)
    finally:
        elastic.problem.destroy()
    scale = abs(ref[2]["probes"]["wall"][0])
    for mine, theirs in zip((first, last), ref[1:], strict=True):
        for name, u in mine["probes"].items():
            assert np.allclose(u, theirs["probes"][name], rtol=0.0, atol=1e-9 * scale), name
    assert np.allclose(stt, stt_ref, rtol=0.0, atol=1e-8 * P)
    # the closed form: the wall after the excavation and at the end, the support pressure
    u1 = -LAM * P * A / (2 * G)
    assert first["probes"]["wall"][0] == pytest.approx(u1, rel=0.01)
    assert last["probes"]["wall"][0] == pytest.approx(u1 - PS * A * K, rel=0.01)
    thrust = float(np.mean(stt)) * (A - B)  # ∫ σθθ dr over the ring = −p_s a
    assert -thrust / A == pytest.approx(PS, rel=0.01)


def test_weak_lining_cracks_where_the_closed_form_hoop_stress_reaches_its_strength(tmp_path):
    """Tension (σ0 = +p I): σθθ = p_s(μ) a² (1 + b²/r²)/(a² − b²), p_s(μ) = μ p/(1 + 2Gk)."""
    strength = 9.0  # about half the ring's final hoop stress at r = b (18.7)
    rows, res, _ = crack_run(tensile(tmp_path, strength))
    first, last = res["stages"]
    assert first["events"] == 0 and first["complete"]
    assert last["events"] == 1 and last["first_event"]["event"] == 1
    row = rows[0]
    r = float(np.hypot(row["x"], row["y"]))
    assert B < r < B + H and row["mode"] == "tension"  # the inner layer, where σθθ peaks
    mu = strength / float(hoop(r, -P / (1 + 2 * G * K)))  # σθθ per unit share, at the site
    assert row["load_factor"] == pytest.approx(mu, rel=0.03)


def test_added_groups_are_refused_where_a_cracking_scene_cannot_install_them(tmp_path):
    text = LINED.read_text().replace("../../fem/lined.geo", str(ELASTIC.parent / "lined.geo"))
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace('remove = ["core", "ring"]', 'remove = ["core"]'))
    with pytest.raises(SceneError, match=r"stages\[1\]\.add"):
        load_scene_collective(MPI.COMM_SELF, bad, [])  # the ring was never excavated
    bad.write_text(text.replace("nu = 0.2, tensile", "nu = 0.2, density = 2000.0, tensile"))
    with pytest.raises(SceneError, match=r"stages\[1\]\.material\.density"):
        load_scene_collective(MPI.COMM_SELF, bad, [])
    elastic = ELASTIC.read_text().replace('"lined.geo"', f'"{ELASTIC.parent / "lined.geo"}"')
    bad.write_text(elastic.replace("nu = 0.2 }", "nu = 0.2, tensile_strength = 1.0 }"))
    with pytest.raises(SceneError, match=r"stages\[1\]\.material\.tensile_strength"):
        load_scene_collective(MPI.COMM_SELF, bad, [])  # an elastic scene has no sites


@pytest.mark.mpi(min_size=2)
def test_two_ranks_crack_the_lining_as_one(tmp_path_factory):
    comm = MPI.COMM_WORLD
    tmp = comm.bcast(str(tmp_path_factory.mktemp("lining")) if comm.rank == 0 else None)
    path = tensile(Path(tmp), 9.0) if comm.rank == 0 else None
    comm.barrier()
    path = Path(comm.bcast(str(path) if path else None))
    rows, res, _ = crack_run(path, "cracking.max_events=2", comm=comm)
    mine = ([r["edge"] for r in rows], [r["load_factor"] for r in rows], res["stages"])
    ref = None
    if comm.rank == 0:
        one = crack_run(path, "cracking.max_events=2")
        ref = ([r["edge"] for r in one[0]], [r["load_factor"] for r in one[0]], one[1]["stages"])
    ref = comm.bcast(ref)
    assert mine[0] == ref[0] and len(mine[0]) == 2
    assert np.allclose(mine[1], ref[1], rtol=1e-10, atol=0.0)
    for a, b in zip(mine[2], ref[2], strict=True):
        for name in a["probes"]:
            assert np.allclose(a["probes"][name], b["probes"][name], rtol=1e-9, atol=1e-16)
