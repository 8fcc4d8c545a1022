"""Loads switched on and off by the stages of a cracking scene (docs/insitu.md).

The plate of scenes/plate_hole_staged.toml (12 x 12, CST, plane strain, an opening of
radius a = 1) under a hydrostatic σ0 = −p (p = 10) is excavated in one stage; a pressure
q on the top side is switched on at a stage (``from``). The tensile strength is 100, so
nothing cracks and the run is elastic. References independent of the crack loop:

- **The elastic staged FEM path** (geofrac/fem/stages.py, itself checked against closed
  forms in tests/fem/test_stage_loads.py and tests/fem/test_insitu.py) on the same mesh
  (P1 = CST): the crown's displacement after each stage to 1e-9 of the wall
  displacement scale, whether the surcharge comes with the excavation (whose stage
  releases half: the surcharge is applied whole at the stage's start, the release by its
  share) or a stage later (linearity: the final state does not depend on the order).
- **Linearity**: the surcharge's share of the crown displacement is q times that of a
  unit surcharge, and switched off at the next stage (``until``) it leaves the bare
  excavation's state (to 1e-9).
- **A wall pressure** p_i on the opening's wall (group "wall", inside the mesh until the
  excavation) from the excavation's stage: the same elastic path (1e-9); linearity,
  u(p_i) = u(0) + p_i (u(1) − u(0)) (1e-9); p_i = p moves nothing (1e-9); the
  convergence 2 (p − p_i) a (1 + ν)/E (Lamé) within the 3 % below.
- **Closed form**, a wall displacement check of the excavation itself: for the
  hydrostatic opening u_r(a) = p a (1 + ν)/E (Kirsch; Jaeger, Cook and Zimmerman
  (2007)), so crown and invert converge by 2 p a (1 + ν)/E (the rollers' rigid shift
  cancels) within 3 %: the finite plate (12a) is softer by O((a/L)²) (Lamé's thick
  cylinder of outer radius 6a…8.5a, the square's inscribed and circumscribed circles:
  +4.3 %…+2.1 %), the P1 mesh stiffer; measured +1.5 %.
"""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.runner import solve_scene
from geofrac.scene import SceneError, load_scene_collective
from tests.fracture.test_constant_loads import run
from tests.fracture.test_staged_cracking import PLATE, SCENES

P, E, NU, A, Q = 10.0, 1000.0, 0.25, 1.0, 3.0
#: the wall displacement's scale p a (1 + ν)/E.
U = P * A * (1 + NU) / E

#: the crown and the invert of the opening.
PROBES = "crown = [0.0, 1.0], invert = [0.0, -1.0]"
EXCAVATE = '[[stages]]\nname = "excavate"\nremove = ["hole"]\n'
LATER = EXCAVATE + '[[stages]]\nname = "surcharge"\n'
SURCHARGE = '[[load]]\ntype = "pressure"\ngroup = "top"\nvalue = {q}\nfrom = "{stage}"\n'


def _scene(tmp, stages: str, *, cracking: bool = True, name: str = "s") -> str:
    """The hydrostatic plate with ``stages`` (and loads); without ``cracking``: elastic."""
    text = PLATE.read_text().replace("../../../meshes", str(SCENES.parents[2] / "meshes"))
    text = text.replace("stress = [-2.0, -10.0, 0.0]", "stress = [-10.0, -10.0, 0.0]")
    text = text.replace("tensile_strength = 1.0", "tensile_strength = 100.0")
    text = text.replace("crown = [0.0, 1.0] }", f"{PROBES} }}")
    start, end = text.index("[[stages]]"), text.index("[cracking]")
    tail = text[end:]
    if not cracking:
        text = text.replace('effects = ["cracking"]\n', "").replace(
            "tensile_strength = 100.0\n", ""
        )
        start, tail = text.index("[[stages]]"), f"[output]\nprobes = {{ {PROBES} }}\n"
    path = tmp / f"{name}.toml"
    path.write_text(text[:start] + stages + "\n" + tail)
    return str(path)


def _elastic(path: str) -> list[np.ndarray]:
    """The crown's displacement after each stage of the elastic staged FEM path."""
    solution = solve_scene(load_scene_collective(MPI.COMM_SELF, path, []), MPI.COMM_SELF)
    try:
        return [np.array(s["probes"]["crown"]) for s in solution.results["stages"][1:]]
    finally:
        solution.problem.destroy()


def _crown(res: dict) -> list[np.ndarray]:
    return [np.array(s["probes"]["crown"]) for s in res["stages"]]


def test_surcharge_from_the_excavation_matches_the_elastic_path(tmp_path):
    """Half the release in the excavation's stage: the surcharge is all there at once."""
    half = EXCAVATE + 'relaxation = 0.5\n[[stages]]\nname = "rest"\n'
    stages = half + SURCHARGE.format(q=Q, stage="excavate")
    driver, res = run(_scene(tmp_path, stages))
    assert not driver.rows and res["end_reason"] == "stages_done"
    middle, crown = _crown(res)
    refs = _elastic(_scene(tmp_path, stages, cracking=False, name="e"))
    np.testing.assert_allclose(middle, refs[0], rtol=0, atol=1e-9 * U)
    np.testing.assert_allclose(crown, refs[1], rtol=0, atol=1e-9 * U)
    # linearity: the surcharge's share is Q times a unit surcharge's
    _, bare = run(_scene(tmp_path, EXCAVATE, name="b"))
    _, unit = run(_scene(tmp_path, EXCAVATE + SURCHARGE.format(q=1.0, stage="excavate")))
    (c0,), (c1,) = _crown(bare), _crown(unit)
    np.testing.assert_allclose(crown - c0, Q * (c1 - c0), rtol=0, atol=1e-9 * U)
    assert crown[1] < c0[1] < 0.0  # the surcharge pushes the crown further down
    # switched off at the next stage (until): back to the bare excavation's state
    off = LATER + SURCHARGE.format(q=Q, stage="excavate") + 'until = "surcharge"\n'
    _, res_off = run(_scene(tmp_path, off, name="f"))
    np.testing.assert_allclose(_crown(res_off)[1], c0, rtol=0, atol=1e-9 * U)
    # the excavation alone: crown and invert converge by 2 p a (1 + ν)/E (Kirsch), 3 %
    invert = np.array(bare["stages"][0]["probes"]["invert"])
    assert c0[1] - invert[1] == pytest.approx(-2.0 * U, rel=0.03)


def test_surcharge_at_a_later_stage_ends_where_the_elastic_path_does(tmp_path):
    later = LATER + SURCHARGE.format(q=Q, stage="surcharge")
    driver, res = run(_scene(tmp_path, later))
    assert not driver.rows and [s["events"] for s in res["stages"]] == [0, 0]
    first, end = _crown(res)
    ref_first, ref_end = _elastic(_scene(tmp_path, later, cracking=False, name="e"))
    np.testing.assert_allclose(first, ref_first, rtol=0, atol=1e-9 * U)
    np.testing.assert_allclose(end, ref_end, rtol=0, atol=1e-9 * U)
    _, once = run(_scene(tmp_path, EXCAVATE + SURCHARGE.format(q=Q, stage="excavate"), name="o"))
    np.testing.assert_allclose(end, _crown(once)[0], rtol=0, atol=1e-9 * U)
    assert res["stages"][1]["share"] == 0.0  # the switch alone: a jump of the constant load


@pytest.mark.parametrize(("pull", "cracks"), [(4.0, False), (15.0, True)])
def test_a_pull_switched_on_cracks_at_zero_release_of_its_stage(tmp_path, pull, cracks):
    """A load's jump cracks the sites it overstresses at λ = 0 of its stage.

    f_t = 1: the excavation does not crack (its least λ > 1); a vertical pull t on top
    switched on in the next stage (share 0) adds Kirsch's 3t to the sidewall's hoop stress
    −2p: −8 < f_t for t = 4, 25 > f_t for t = 15, whose sites crack at λ = 0 there.
    """
    stages = LATER + SURCHARGE.format(q=-pull, stage="surcharge")
    driver, res = run(_scene(tmp_path, stages), "material.tensile_strength=1.0")
    first, second = res["stages"]
    assert first["events"] == 0 and first["next_load_factor"] > 1.0
    assert (second["events"] > 0) == cracks
    if cracks:
        assert second["first_event"]["load_factor"] == 0.0
        assert all(r["load_factor"] == 0.0 for r in driver.rows)
        x, _ = driver.units.site_point(driver.rows[0]["edge"])
        assert abs(x) > A  # at a sidewall, not above or below the opening


BAD = [
    (EXCAVATE + '[[load]]\ntype = "pressure"\ngroup = "top"\nvalue = 1.0\n', "stages", "'from'"),
    (
        LATER + '[[load]]\ntype = "body_force"\nvalue = [0.0, -1.0]\nfrom = "surcharge"\n',
        "load[0].type",
        "traction or pressure",
    ),
    (
        LATER + '[[bc]]\ngroup = "top"\ncomponents = ["y"]\nvalue = [0.0]\nfrom = "surcharge"\n',
        "bc[2].from",
        "not supports",
    ),
]


@pytest.mark.parametrize(("stages", "key", "message"), BAD, ids=[b[1] for b in BAD])
def test_bad_switches_in_a_cracking_scene_name_the_key(tmp_path, stages, key, message):
    with pytest.raises(SceneError) as info:
        load_scene_collective(MPI.COMM_SELF, _scene(tmp_path, stages), [])
    assert info.value.key == key and message in info.value.message


@pytest.mark.mpi(min_size=2)
def test_switched_load_on_1_and_2_ranks(tmp_path):
    comm = MPI.COMM_WORLD
    stages = LATER + SURCHARGE.format(q=Q, stage="surcharge")
    path = comm.bcast(_scene(tmp_path, stages) if comm.rank == 0 else None)
    _, res = run(path, comm=comm)
    _, ref = run(path, comm=MPI.COMM_SELF)
    for a, b in zip(_crown(res), _crown(ref), strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * U)
    ends = comm.allgather(_crown(res)[-1].tolist())
    assert all(e == ends[0] for e in ends)


#: A wall pressure (support pressure, group "wall": inside the mesh until the excavation)
#: of 4 from the excavation until 'free', 1 from 'unit', and 1 + 9 = p from 'full'.
WALL = (
    EXCAVATE
    + "".join(f'[[stages]]\nname = "{name}"\n' for name in ("free", "unit", "full"))
    + "".join(
        SURCHARGE.format(q=q, stage=on).replace('"top"', '"wall"') + off
        for q, on, off in (
            (4.0, "excavate", 'until = "free"\n'),
            (1.0, "unit", ""),
            (9.0, "full", ""),
        )
    )
)


def test_a_wall_pressure_from_the_excavation_matches_the_elastic_path(tmp_path):
    """p_i on the opening's wall from its excavation, integrated on the rock's side.

    Before the wall loads (geofrac/fem/walls.py) such a pressure was refused, and before
    that it changed nothing, without a word (measured: a wall pressure of 4, 0 or −4 gave
    the same crown displacement).
    """
    driver, res = run(_scene(tmp_path, WALL))
    assert not driver.rows and res["end_reason"] == "stages_done"
    refs = _elastic(_scene(tmp_path, WALL, cracking=False, name="e"))
    for crown, ref in zip(_crown(res), refs, strict=True):
        np.testing.assert_allclose(crown, ref, rtol=0, atol=1e-9 * U)
    four, free, unit, full = (
        {k: np.array(v) for k, v in s["probes"].items()} for s in res["stages"]
    )
    for name in ("crown", "invert"):
        np.testing.assert_allclose(
            four[name], free[name] + 4.0 * (unit[name] - free[name]), rtol=0, atol=1e-9 * U
        )
        assert np.max(np.abs(full[name])) < 1e-9 * U  # p_i = p: the wall stays where it was
    for p_i, state in ((4.0, four), (0.0, free)):  # Kirsch/Lamé, 3 % as above
        convergence = state["crown"][1] - state["invert"][1]
        assert convergence == pytest.approx(-2.0 * (P - p_i) / P * U, rel=0.03), p_i


@pytest.mark.mpi(min_size=2)
def test_wall_pressure_on_1_and_2_ranks(tmp_path):
    comm = MPI.COMM_WORLD
    path = comm.bcast(_scene(tmp_path, WALL) if comm.rank == 0 else None)
    _, res = run(path, comm=comm)
    _, ref = run(path, comm=MPI.COMM_SELF)
    for a, b in zip(_crown(res), _crown(ref), strict=True):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * U)
