"""Force control: a traction, pressure or point load drives the events.

A 5 x 5 plate on rollers pulled by a uniform traction σ on its right side
(scenes/plate_force.toml) carries the uniform uniaxial stress σ_xx = σ, which CST
reproduces exactly, so the first event is known in closed form: r = f_t / σ, the force
r σ W t = f_t W t and the right side's displacement r σ L / E = f_t L / E. The twin moved
by a prescribed displacement (scenes/plate_displacement.toml) gives the same numbers.
"""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.fracture.control import SELF_EQUILIBRATED, force_control
from geofrac.fracture.driver import CrackDriver
from geofrac.scene import SceneError, load_scene, load_scene_collective

SCENES = Path(__file__).resolve().parent / "scenes"
FORCE = SCENES / "plate_force.toml"
TWIN = SCENES / "plate_displacement.toml"

#: the scenes' plate: side L = W, thickness, E, f_t, the traction σ and the twin's u_x.
L, T, E, FT, SIGMA, U = 5.0, 2.0, 100.0, 3.0, 1.0, 0.05
#: closed forms of the first event: force, work-conjugate displacement, load factor.
FORCE_1 = FT * L * T
DISPLACEMENT_1 = FT * L / E


def run(scene: Path, *overrides: str, comm: MPI.Comm = MPI.COMM_SELF) -> tuple[CrackDriver, dict]:
    """Run ``scene`` with ``overrides`` on ``comm``: the driver (its rows) and the results."""
    driver = scene_driver(load_scene_collective(comm, scene, overrides), comm)
    try:
        return driver, driver.run()
    finally:
        driver.problem.destroy()


def test_traction_first_event_is_the_closed_form():
    driver, res = run(FORCE)
    row = driver.rows[0]
    assert res["control"]["kind"] == "force"
    assert res["control"]["unit_force"] == pytest.approx(SIGMA * L * T, rel=1e-12)
    np.testing.assert_allclose(res["control"]["resultant"], [SIGMA * L * T, 0.0], atol=1e-12)
    assert row["load_factor"] == pytest.approx(FT / SIGMA, rel=1e-9)
    assert row["reaction"] == pytest.approx(FORCE_1, rel=1e-9)
    assert row["control_displacement"] == pytest.approx(DISPLACEMENT_1, rel=1e-9)
    # the unit load: F over its work-conjugate displacement σ L / E is the bar's E W t / L
    unit = res["unit_load"]
    assert unit["reaction"] == pytest.approx(SIGMA * L * T, rel=1e-12)
    assert unit["control_displacement"] == pytest.approx(SIGMA * L / E, rel=1e-9)
    assert unit["stiffness"] == pytest.approx(E * L * T / L, rel=1e-9)


def test_grain_interfaces_under_force_control():
    """EFMM (grain interfaces): F and the force column are exact, the rest near the bar's.

    EFMM's grain fields reproduce a uniform stress only approximately: r, hence the
    displacement, within a relative 1e-5 of the closed form.
    """
    driver, res = run(FORCE, "discretization.element=efmm")
    row = driver.rows[0]
    assert res["control"]["unit_force"] == pytest.approx(SIGMA * L * T, rel=1e-12)
    assert row["reaction"] == pytest.approx(row["load_factor"] * SIGMA * L * T, rel=1e-12)
    assert row["reaction"] == pytest.approx(FORCE_1, rel=1e-5)
    assert row["control_displacement"] == pytest.approx(DISPLACEMENT_1, rel=1e-5)


def test_displacement_twin_gives_the_same_first_event():
    driver, res = run(TWIN)
    row = driver.rows[0]
    assert (res["control"]["group"], res["control"]["kind"]) == ("right", "displacement")
    assert res["control"]["unit_displacement"] == pytest.approx(U, rel=1e-12)
    assert row["load_factor"] == pytest.approx(FT * L / (E * U), rel=1e-9)
    assert row["reaction"] == pytest.approx(FORCE_1, rel=1e-9)
    assert row["control_displacement"] == pytest.approx(DISPLACEMENT_1, rel=1e-9)
    assert res["unit_load"]["stiffness"] == pytest.approx(E * L * T / L, rel=1e-9)


def test_control_point_reads_the_nearest_node_along_the_load():
    point = np.array([4.0, 2.6])
    driver, res = run(FORCE, "cracking.control_point=[4.0, 2.6]")
    ctl = res["control"]
    coords = driver.ctx.gm.coords
    nearest = coords[np.argmin(np.hypot(*(coords - point).T))]
    np.testing.assert_array_equal(ctl["point_xy"], nearest)
    node = int(np.flatnonzero(driver.ctx.gm.input_ids == ctl["point_node"])[0])
    np.testing.assert_array_equal(coords[node], nearest)
    # u_x = σ x / E in the plate, so the node moves by f_t x / E at the first event
    row = driver.rows[0]
    assert row["control_displacement"] == pytest.approx(FT * nearest[0] / E, rel=1e-9)
    assert row["reaction"] == pytest.approx(FORCE_1, rel=1e-9)


def test_force_control_ends_when_the_plate_is_cut_through():
    """Once a crack crosses the plate the load finds no path: the run ends ``separated``.

    The bound is the measured control displacement r δ_u against the plate's diagonal,
    not the a-priori r F/(E t), which stays far below it while the loaded side runs off.
    """
    driver, res = run(FORCE, "cracking.max_events=300")
    assert res["end_reason"] == "separated"
    assert "beyond the specimen's size" in res["end_detail"]
    assert max(abs(r["control_displacement"]) for r in driver.rows) <= L * np.sqrt(2.0)


def test_pressure_load_drives_the_events():
    """A pressure p < 0 pulls (traction −p n): the same plate, the same first event."""
    driver, res = run(FORCE, "load.0.type=pressure", "load.0.value=[-1.0]")
    assert res["control"]["kind"] == "force"
    assert res["events"] == 1
    assert driver.rows[0]["reaction"] == pytest.approx(FORCE_1, rel=1e-9)
    assert driver.rows[0]["control_displacement"] == pytest.approx(DISPLACEMENT_1, rel=1e-9)


def test_point_load_force_is_thickness_times_its_value():
    """A point load is a force per unit thickness: F = t |P| (docs/scenes.md, "Loads")."""
    beam = SCENES.parents[1] / "fem" / "point_beam.toml"  # point load [0, 1] on "tip"
    sets = ('effects=["cracking"]', 'discretization.element="cst"')
    sets += ("material.tensile_strength=1.0", "material.thickness=2.0", "cracking.max_events=1")
    driver, res = run(beam, *sets)
    assert res["control"]["group"] == "tip" and res["control"]["kind"] == "force"
    assert res["control"]["unit_force"] == pytest.approx(2.0, rel=1e-12)
    np.testing.assert_allclose(res["control"]["resultant"], [0.0, 2.0], atol=1e-12)
    row = driver.rows[0]
    assert row["reaction"] == pytest.approx(row["load_factor"] * 2.0, rel=1e-12)


def test_force_control_of_a_self_equilibrated_and_a_point_load():
    """F is the resultant; a balanced load (a pressure in a hole) has F = Σ|f_i|."""
    bs = 2
    point = np.zeros(8)
    point[[2, 3]] = [3.0, -4.0]  # one node: a point force of magnitude 5
    ctl = force_control("p", point, bs=bs, modulus=10.0, thickness=0.5)
    assert ctl.unit == 5.0 and ctl.scale == 5.0 / (10.0 * 0.5)
    np.testing.assert_allclose(ctl.direction, [0.6, -0.8])
    u = np.arange(8.0)
    assert ctl.measure(u, reaction=123.0) == pytest.approx((0.6 * 2 - 0.8 * 3, 5.0))
    balanced = np.array([1.0, 0.0, -1.0, 0.0, 0.0, 2.0, 0.0, -2.0])
    ctl = force_control("hole", balanced, bs=bs, modulus=1.0, thickness=1.0)
    assert ctl.direction is None and ctl.unit == 6.0
    assert SELF_EQUILIBRATED < 1e-3
    with pytest.raises(ValueError, match="self-equilibrated"):
        force_control("hole", balanced, bs=bs, modulus=1.0, thickness=1.0, point_dofs=(0, [0, 1]))


def _refused(scene: Path, *overrides: str) -> str:
    with pytest.raises(SceneError) as info:
        load_scene(scene, overrides)
    assert info.value.key.startswith("cracking.control")
    return info.value.message


@pytest.mark.parametrize("name", ["gravity", "body_force"])
def test_a_body_force_cannot_be_the_control(name):
    assert "a body force cannot drive the events" in _refused(FORCE, f'cracking.control="{name}"')


def test_a_body_force_alone_drives_nothing(tmp_path):
    text = FORCE.read_text().replace(
        "../../../meshes/square.geo", str(SCENES.parents[2] / "meshes" / "square.geo")
    )
    text = text.replace(
        'type = "traction"\ngroup = "right"\nvalue = [1.0, 0.0]',
        'type = "body_force"\nvalue = [1.0, 0.0]',
    )
    scene = tmp_path / "body.toml"
    scene.write_text(text)
    message = _refused(scene)
    assert "no [[load]] is a traction, pressure or point load" in message


def test_control_errors_name_the_problem():
    assert "has neither a [[bc]] nor a [[load]]" in _refused(FORCE, 'cracking.control="top"')
    assert "prescribes no non-zero displacement" in _refused(FORCE, 'cracking.control="left"')
    assert "did you mean 'right'" in _refused(FORCE, 'cracking.control="rigth"')
    assert "is zero" in _refused(FORCE, "load.0.value=[0.0, 0.0]")
    assert "force control" in _refused(TWIN, "cracking.control_point=[1.0, 2.0]")
    assert "two finite numbers" in _refused(FORCE, "cracking.control_point=[1.0]")


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("overrides", [(), ("cracking.control_point=[4.0, 2.6]",)])
def test_same_first_events_on_1_and_2_ranks(overrides):
    """Five events on a finer plate: every rank's log equals the serial run's."""
    sets = ("geometry.parameters.h=0.5", "cracking.max_events=5", *overrides)
    parallel, res = run(FORCE, *sets, comm=MPI.COMM_WORLD)
    serial, ref = run(FORCE, *sets, comm=MPI.COMM_SELF)
    assert len(parallel.rows) == len(serial.rows) == 5
    assert [r["edge"] for r in parallel.rows] == [r["edge"] for r in serial.rows]
    for key in ("load_factor", "reaction", "control_displacement"):
        np.testing.assert_allclose(
            [r[key] for r in parallel.rows], [r[key] for r in serial.rows], rtol=1e-8
        )
    assert res["control"]["unit_force"] == pytest.approx(ref["control"]["unit_force"], rel=1e-12)
    assert res["control"].get("point_node") == ref["control"].get("point_node")
    logs = MPI.COMM_WORLD.allgather([r["reaction"] for r in parallel.rows])
    assert all(log == logs[0] for log in logs)
