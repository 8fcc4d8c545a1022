"""An initial (in-situ) stress in cracking scenes: part of the constant load.

- The plate of scenes/plate_confined.toml confined by constant tractions and the same
  plate confined by an initial stress σ0 = (−1, −2, 0) with its right and top sides
  loaded (scenes/plate_insitu.toml) are the same physics through two code paths (the
  tractions' solution u_c on the cracked mesh, against σ0 plus the solution of its
  out-of-balance force F0 = F_ext,0 − I(σ0) on the cracked mesh): the same sites and λ
  over eight events. Without reassembling F0 after each crack the two part after the
  first event.
- A hydrostatic σ0 = −p on the beam of scenes/beam_axial.toml (RGNT): σ1(−p I + λ σ_v)
  = −p + λ σ1(σ_v), so the first crack's factor is exactly λ_0 (1 + p/f_t).
- σ0 = 0 repeats the run without an initial stress, bit for bit.
- Under displacement control the reaction is relative to the initial state: the total
  one of the same physics posed by constant loads, minus σ_xx0 × height × t.
- A layered geostatic state under gravity (tests/fem/layers.toml) is in balance with
  the crack driver's own cell operators to round-off (CST, RGNT).
- An initial state out of balance, grain interfaces and a scene without a
  variable load are refused with messages; 1 and 2 ranks give the same events.
"""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.scene import SceneError, load_scene_collective
from tests.fracture.test_constant_loads import run

SCENES = Path(__file__).resolve().parent / "scenes"
PLATE = SCENES / "plate_confined.toml"
INSITU = SCENES / "plate_insitu.toml"
BEAM = SCENES / "beam_axial.toml"
LAYERS = Path(__file__).resolve().parents[1] / "fem" / "layers.toml"


def test_initial_stress_and_constant_tractions_give_the_same_events():
    """Same sites, λ to 1e-9, over 8 events (several cracks release σ0 on their faces)."""
    traction, _ = run(PLATE, "cracking.max_events=8")
    insitu, res = run(INSITU, "cracking.max_events=8")
    assert len(traction.rows) == len(insitu.rows) == 8
    assert [r["edge"] for r in insitu.rows] == [r["edge"] for r in traction.rows]
    np.testing.assert_allclose(
        [r["load_factor"] for r in insitu.rows],
        [r["load_factor"] for r in traction.rows],
        rtol=1e-9,
    )
    assert res["initial_stress"]["kind"] == "constant"
    assert res["initial_stress"]["out_of_balance"] < 1e-12
    assert res["constant"] == {"groups": [], "overstressed_at_start": 0, "cracked_at_zero": 0}


@pytest.mark.parametrize("element", ["rgnt", "gnt"])
def test_hydrostatic_initial_stress_raises_the_first_crack_by_p_over_ft(element):
    """RGNT and GNT beams: λ_p = (f_t + p)/D_v = λ_0 (1 + p/f_t) (f_t = 1), same site."""
    sets = (
        f"discretization.element={element}",
        "discretization.gradient_bc=fixed",  # GNT's held lines (docs/elements.md)
        "cracking.max_events=1",
        "cracking.constant=[]",
    )
    base, _ = run(BEAM, *sets)
    lam0 = base.rows[0]["load_factor"]
    for p in (0.5, 2.0):
        beam, res = run(
            BEAM,
            *sets,
            "initial_stress.kind=constant",
            f"initial_stress.stress=[{-p}, {-p}, 0.0]",
            'initial_stress.loaded=["tip", "top", "bottom"]',
        )
        row = beam.rows[0]
        assert row["edge"] == base.rows[0]["edge"] and row["mode"] == "tension"
        assert row["load_factor"] == pytest.approx(lam0 * (1.0 + p), rel=1e-12)
        assert res["initial_stress"]["out_of_balance"] < 1e-12


def _held_right(name: str, tmp: Path) -> Path:
    """``name`` with its right side held in x by a [[bc]] (prescribed 0.01: the control)."""
    bc = '[[bc]]\ngroup = "right"\ncomponents = ["x"]\nvalue = [0.01]\n\n[[load]]'
    text = (SCENES / name).read_text().replace("../../../meshes", str(SCENES.parents[2] / "meshes"))
    path = tmp / name
    path.write_text(text.replace("[[load]]", bc, 1))
    return path


def test_reaction_is_relative_to_the_initial_state(tmp_path):
    """Displacement control on the held right side; MLS cells next to it from the start.

    The plate confined by a constant top traction −2 with its left and right sides held
    carries σ = (ν (−2), −2, 0) = (−0.5, −2, 0) (plane stress, ε_xx = 0); the same
    plate given that state as σ0 (top `loaded`) is the same physics, so the events agree
    and its reaction, relative to the initial state, is the total one minus the initial
    state's, σ_xx0 × height × t = −0.5 × 5 × 2 = −5. The MLS cells of ``mls_region``
    reach the control nodes: their share of I(σ0) differs from the element cells'
    (without it the difference drifts from −4.4 to −9.7 over the events).
    """
    common = (
        "cracking.mls_region=[2.9, -0.1, 5.1, 5.1]",
        "cracking.control=right",
        "load.0.value=[0.0, 0.0]",
        "cracking.max_events=8",
    )
    total, _ = run(
        _held_right("plate_confined.toml", tmp_path),
        *common,
        "load.1.value=[0.0, 0.0]",
        'cracking.constant=["top"]',
    )
    relative, _ = run(
        _held_right("plate_insitu.toml", tmp_path),
        *common,
        'initial_stress.loaded=["top"]',
        "initial_stress.stress=[-0.5, -2.0, 0.0]",
    )
    assert len(total.rows) == len(relative.rows) == 8
    assert [r["edge"] for r in relative.rows] == [r["edge"] for r in total.rows]
    for a, b in zip(total.rows, relative.rows, strict=True):
        assert b["load_factor"] == pytest.approx(a["load_factor"], rel=1e-9)
        assert a["reaction"] - b["reaction"] == pytest.approx(-5.0, rel=1e-9)


@pytest.mark.parametrize("criterion", ["principal", "direction"])
def test_zero_initial_stress_repeats_the_run_without_it(criterion):
    sets = (f"cracking.criterion={criterion}", "cracking.max_events=8")
    plain, res_p = run(
        PLATE, "load.1.value=[0.0, 0.0]", "load.2.value=[0.0, 0.0]", "cracking.constant=[]", *sets
    )
    zero, res_z = run(
        INSITU, "initial_stress.stress=[0.0, 0.0, 0.0]", "initial_stress.loaded=[]", *sets
    )
    assert "initial_stress" not in res_p and res_z["initial_stress"]["out_of_balance"] == 0.0
    assert len(plain.rows) == 8
    assert zero.rows == plain.rows  # every column, exactly


@pytest.mark.parametrize("element", ["cst", "rgnt"])
def test_layered_geostatic_state_is_in_balance_with_the_crack_cells(element):
    """Gravity with a density per layer, K0 per layer, the cover's weight on the top.

    F_ext,0 (DOLFINx: gravity, σ0·n) against the crack driver's ∫ Bᵀ σ0 (numpy, the pure
    field at six points per cell): round-off. The sides pulled apart (displacement
    control on the right) crack the rock near the surface, where σ0 is least.
    """
    driver, res = run(
        LAYERS,
        'effects=["gravity", "cracking"]',
        f"discretization.element={element}",
        'output.probe_fields=["displacement"]',
        "material.tensile_strength=1e4",
        "bc.2.value=[1e-5]",
        "cracking.control=right",
        "cracking.max_events=1",
        "cracking.criterion=principal",
    )
    assert res["initial_stress"]["kind"] == "geostatic"
    assert res["initial_stress"]["out_of_balance"] < 1e-12
    row = driver.rows[0]
    assert row["load_factor"] > 0.0 and row["y"] > 4.0  # the top layer (y ≤ 5)


def test_check_reports_the_crack_cells_balance():
    """``geofrac check``'s number for a cracking scene is the crack driver's (RGNT too)."""
    from geofrac.runner import initial_balance

    sets = [
        'effects=["gravity", "cracking"]',
        "discretization.element=rgnt",
        'output.probe_fields=["displacement"]',
        "material.tensile_strength=1e4",
        "bc.2.value=[1e-5]",
        "cracking.control=right",
    ]
    scene = load_scene_collective(MPI.COMM_SELF, LAYERS, sets)
    assert initial_balance(scene, MPI.COMM_SELF) < 1e-12
    unloaded = load_scene_collective(MPI.COMM_SELF, LAYERS, [*sets, "initial_stress.loaded=[]"])
    assert initial_balance(unloaded, MPI.COMM_SELF) > 1e-3  # the cover's weight is missing


def test_initial_state_out_of_balance_is_refused():
    with pytest.raises(RunError, match="out of balance"):
        run(INSITU, 'initial_stress.loaded=["right"]')


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (("discretization.element=efmm",), "grain interfaces"),
    ],
)
def test_refused_scenes(overrides, message):
    with pytest.raises(SceneError) as err:
        load_scene_collective(MPI.COMM_SELF, INSITU, list(overrides))
    assert message in str(err.value) and "initial_stress" in str(err.value)


def test_scene_without_a_variable_load_is_refused(tmp_path):
    text = INSITU.read_text().replace("../../../meshes", str(SCENES.parents[2] / "meshes"))
    start = text.index("[[load]]")
    text = text[:start] + text[text.index("[initial_stress]") :]
    scene = tmp_path / "still.toml"
    scene.write_text(text)
    with pytest.raises(SceneError, match="needs a variable load"):
        load_scene_collective(MPI.COMM_SELF, scene, [])


@pytest.mark.mpi(min_size=2)
def test_same_events_on_1_and_2_ranks():
    sets = ("geometry.parameters.h=0.5", "cracking.max_events=6")
    parallel, res = run(INSITU, *sets, comm=MPI.COMM_WORLD)
    serial, ref = run(INSITU, *sets, comm=MPI.COMM_SELF)
    assert len(parallel.rows) == len(serial.rows) == 6
    assert [r["edge"] for r in parallel.rows] == [r["edge"] for r in serial.rows]
    for k in ("load_factor", "reaction", "control_displacement", "strain_energy"):
        np.testing.assert_allclose(
            [r[k] for r in parallel.rows], [r[k] for r in serial.rows], rtol=1e-8, err_msg=k
        )
    edges = MPI.COMM_WORLD.allgather([r["edge"] for r in parallel.rows])
    assert all(e == edges[0] for e in edges)
    assert res["initial_stress"]["kind"] == ref["initial_stress"]["kind"]
