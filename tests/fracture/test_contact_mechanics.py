"""Crack faces in contact against closed forms (docs/cracking.md, "Crack faces in contact").

All scenes are jobs/jaeger_joint.toml (meshes/jaeger_joint.geo: a 40 x 80 specimen in
uniaxial compression between smooth platens, crossed by one straight joint at β to the x
axis), coarsened for speed, run through the crack driver in-process:

- Jaeger's single plane of weakness (Jaeger, Cook and Zimmerman, Fundamentals of Rock
  Mechanics, 4th ed., 2007, §4.7): a joint of cohesion c and friction μ whose normal
  makes β with the load slips at σ1 = 2c / ((1 − μ cot β) sin 2β), never for β ≤ atan μ;
- two blocks pressed together across a through crack transmit the intact load;
- a block on an inclined crack without cohesion sticks for μ > tan θ and slips otherwise;
- a crack pulled open carries nothing, the same crack pressed shut carries the load.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

JOB = JOBS / "jaeger_joint.toml"
#: The scene's specimen (width, height), thickness, E, joint cohesion and friction.
W, H, THICKNESS, E, C, MU = 40.0, 80.0, 1.0, 10000.0, 1.0, 0.5
#: Mesh size of the tests: about 300 triangles (the stress is uniform).
MESH_H = 5.0
COARSE = (f"geometry.parameters.h={MESH_H}",)
#: Relative tolerance of the joint's slip load against Jaeger's law.
JAEGER_RTOL = 0.03
#: Axial stiffness of the intact specimen between smooth platens: E W t / H.
INTACT = E * W * THICKNESS / H
#: Relative tolerance of a closed crack's stiffness against the intact one: the penalty
#: (contact_penalty = 100) adds a compliance of 1 / 100 of a cell, h / (100 H) = 0.06 %.
STIFFNESS_RTOL = 0.02
#: No cohesion on the crack faces (the contact tests).
FRICTIONAL = ("cracking.joints.joint.cohesion=0",)


def jaeger_sigma1(beta: float, c: float = C, mu: float = MU) -> float:
    """Axial stress at which the joint slips; inf for β ≤ atan μ (Jaeger et al. 2007, §4.7)."""
    b = math.radians(beta)
    if math.tan(b) <= mu:
        return math.inf
    return 2.0 * c / ((1.0 - mu / math.tan(b)) * math.sin(2.0 * b))


def run(*overrides: str, comm: MPI.Comm = MPI.COMM_SELF, job: Path = JOB) -> tuple[list, dict]:
    """(event rows, results) of ``job`` on the coarse mesh with ``overrides``."""
    scene = load_scene_collective(comm, job, [*COARSE, *overrides])
    driver = scene_driver(scene, comm)
    try:
        res = driver.run()
        return driver.rows, res
    finally:
        driver.problem.destroy()


def no_contact_job(tmp_path: Path) -> Path:
    """jobs/jaeger_joint.toml with ``contact = false`` (and so without its joint table)."""
    text = re.sub(r"\[cracking\.joints\.joint\][^\[]*", "", JOB.read_text())
    text = text.replace("contact = true", "contact = false")
    text = text.replace('"../meshes/', f'"{JOB.parent.parent / "meshes"}/')
    path = tmp_path / "no_contact.toml"
    path.write_text(text)
    return path


def stiffness(row: dict) -> float:
    """Reaction / control displacement of an event or of the results' ``unit_load``.

    Relative to the intact specimen's.
    """
    return row["reaction"] / row["control_displacement"] / INTACT


def penetration_bound(row: dict) -> float:
    """Twice the penalty's penetration σ h / (penalty E) under the row's mean stress."""
    return 2.0 * abs(row["reaction"]) / (W * THICKNESS) * MESH_H / (100.0 * E)


def ends_without_an_absurd_event(rows: list, res: dict) -> bool:
    """The intact rock never reaches f_t before a control displacement beyond its size.

    In uniaxial compression between smooth platens σ_xx = 0: the only tension is the
    MLS cells' few per cent of |σ_yy| next to the crack, which would reach f_t = 1000 c
    at a shortening three times the specimen's height. The run ends ``separated`` with
    that reason instead of recording such an event, or, when the criterion judges the
    averaged stress (``"direction"``, the default) in which that tension does not reach
    the floor, ``no_tensile_edge``.
    """
    if rows:
        return False
    if res["end_reason"] == "no_tensile_edge":
        return True
    return res["end_reason"] == "separated" and "beyond the specimen's size" in res["end_detail"]


def slip_stress(
    beta: float, comm: MPI.Comm = MPI.COMM_SELF, *, overrides: tuple[str, ...] = ()
) -> float:
    """σ1 = reaction / (W t) at the first event, which must be the joint's slip."""
    rows, res = run(
        f"geometry.parameters.beta={beta}", "cracking.max_events=1", *overrides, comm=comm
    )
    assert rows, f"no event at beta = {beta}: {res['end_reason']}"
    assert rows[0]["mode"] == "slip"
    return rows[0]["reaction"] / (W * THICKNESS)


#: Known failure, not fixed: the slip criterion judges each pair on its faces' stress (the
#: mean of the two cells' MLS stresses), which along the joint runs 2-5 % above the uniform
#: field and up to 19 % at the specimen's sides: the MLS cells and the elements next to them
#: are not conforming (a bonded horizontal joint already moves the element stresses beside
#: it by -11 to +6 %). The slip load comes 4-6 % early for beta = 45-75 and 32 % at 30
#: (where 1 - mu cot beta = 0.13 amplifies any traction error eightfold); docs/cracking.md,
#: "Crack faces in contact", status. The recovery itself is exact and the MLS cells fail the
#: stress patch test (tests/fracture/test_joint_faces.py). strict: a fix makes these fail.
TRACTIONS_UNRELIABLE = pytest.mark.xfail(
    strict=True, reason="the faces' stress along the joint is 2-5 % off the uniform field"
)


@TRACTIONS_UNRELIABLE
@pytest.mark.parametrize("beta", [30.0, 45.0, 60.0, 75.0])
def test_joint_slips_at_jaegers_load(beta):
    assert slip_stress(beta) == pytest.approx(jaeger_sigma1(beta), rel=JAEGER_RTOL)


#: Known failure of the consistent cells: at β = 75° the joint ends on the platens and
#: cuts wedges of 10-25° there; the first slip comes 9.3 % early at the pair next to the
#: platen (docs/cracking.md, "Integration-consistent MLS cells").
STEEP_WEDGES = pytest.mark.xfail(strict=True, reason="wedges at the platens: 9 % early")


@pytest.mark.parametrize("beta", [30.0, 45.0, 60.0, pytest.param(75.0, marks=STEEP_WEDGES)])
def test_joint_slips_at_jaegers_load_with_consistent_mls_cells(beta):
    """``mls_gradient = "consistent"``: the faces read the uniform field, Jaeger's law holds.

    Measured: exact to 1e-11 at β = 30° and 45°; +1.3 % at 60°, the reaction's own error
    on this coarse mesh (a face pair's fit reaches the platen: docs/cracking.md).
    """
    sigma = slip_stress(beta, overrides=("cracking.mls_gradient=consistent",))
    assert sigma == pytest.approx(jaeger_sigma1(beta), rel=JAEGER_RTOL)


@pytest.mark.parametrize("beta", [20.0, 25.0])
def test_joint_flatter_than_the_friction_angle_never_slips(beta):
    """β ≤ atan μ = 26.6°: the shear never reaches c + μ σn, however large the load."""
    rows, res = run(f"geometry.parameters.beta={beta}")
    assert all(r["mode"] != "slip" for r in rows), (rows, res["end_reason"])


@pytest.mark.mpi(min_size=2)
def test_slip_load_is_the_same_on_1_and_n_ranks():
    world = MPI.COMM_WORLD
    parallel = slip_stress(60.0, world)
    serial = slip_stress(60.0, MPI.COMM_SELF)
    assert parallel == pytest.approx(serial, rel=1e-8)
    loads = world.allgather(parallel)
    assert all(x == loads[0] for x in loads)


def test_blocks_pressed_together_across_a_crack_carry_the_intact_load():
    """A horizontal through crack without cohesion, pressed shut: the specimen's stiffness.

    Under the unit load every face pair is closed and sticking (τ = 0), the stiffness is
    the intact E W t / H and the faces interpenetrate by no more than twice the
    penalty's σ h / (penalty E); no event is recorded at an absurd load.
    """
    rows, res = run("geometry.parameters.beta=0", *FRICTIONAL, "cracking.max_events=1")
    assert ends_without_an_absurd_event(rows, res), (rows, res.get("end_detail"))
    contact, unit = res["contact"], res["unit_load"]
    assert contact["open"] == contact["slip"] == 0 and contact["stick"] > 0
    assert stiffness(unit) == pytest.approx(1.0, rel=STIFFNESS_RTOL)
    assert unit["min_gap"] >= -penetration_bound(unit)


@pytest.mark.parametrize(
    ("friction", "sticks"),
    [(0.8, True), (0.4, False)],
)
def test_block_on_an_inclined_crack_sticks_only_if_friction_exceeds_its_slope(friction, sticks):
    """A crack at θ = 30° (tan θ = 0.577) without cohesion under uniaxial compression.

    μ > tan θ: every pair sticks and the specimen is as stiff as the intact one. μ < tan θ:
    the top block slides off along the crack on its smooth platen (u_x free), the faces
    slip and nothing is carried: the unit-load energy is nil (``separated``), or the
    stiffness collapses.
    """
    rows, res = run(
        "geometry.parameters.beta=30",
        *FRICTIONAL,
        f"cracking.joints.joint.friction={friction}",
        "cracking.max_events=1",
    )
    contact = res["contact"]
    if sticks:
        assert ends_without_an_absurd_event(rows, res), (rows, res.get("end_detail"))
        assert contact["open"] == contact["slip"] == 0 and contact["stick"] > 0
        assert stiffness(res["unit_load"]) == pytest.approx(1.0, rel=STIFFNESS_RTOL)
    else:
        assert contact["slip"] == contact["pairs"] > 0
        assert res["end_reason"] == "separated" and not rows, rows
        assert stiffness(res["unit_load"]) < 1e-3


def test_crack_pulled_open_carries_nothing_and_pressed_shut_carries_the_load():
    """A crack opened in tension carries nothing; pressed shut, it carries the load again.

    In tension the horizontal crack opens: every pair is open and there is no load path
    (``separated``); the same specimen in compression has the intact stiffness again.
    """
    rows, res = run("geometry.parameters.beta=0", *FRICTIONAL, "bc.2.value=[0.01]")
    assert res["end_reason"] == "separated" and not rows, rows
    assert res["contact"]["open"] == res["contact"]["pairs"] > 0
    assert abs(stiffness(res["unit_load"])) < 1e-9
    rows, res = run("geometry.parameters.beta=0", *FRICTIONAL, "cracking.max_events=1")
    assert ends_without_an_absurd_event(rows, res), (rows, res.get("end_detail"))
    assert res["contact"]["open"] == 0
    assert stiffness(res["unit_load"]) == pytest.approx(1.0, rel=STIFFNESS_RTOL)


def test_dcn_plate_with_contact_runs_past_an_element_cell_left_on_a_hinge():
    """jobs/dcn_plate.toml, coarse, with contact, to event 80.

    An element cell hanging on one node (no MLS fit used its other vertices) made the
    system singular at event 76.
    """
    rows, res = run(
        "cracking.contact=true",
        "geometry.parameters.h=4",
        "cracking.max_events=80",
        "cracking.contact_iterations=100",
        job=JOBS / "dcn_plate.toml",
    )
    assert res["end_reason"] == "max_events"
    assert len(rows) == 80
    assert res["contact"]["worst_gap_relative"] > -0.01
