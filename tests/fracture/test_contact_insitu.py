"""Crack-face contact under an initial stress: joints start closed and carry σ0.

scenes/joint_insitu.toml is Jaeger's specimen (jobs/jaeger_joint.toml, h = 5: a joint
whose normal makes β = 45° with the load axis y, c = 1, μ = 0.5, smooth platens) starting
from a uniform σ0 = (σxx0, σyy0, 0) with its sides loaded by σ0·n; the top platen's
displacement scales with λ (the variable stress σ_v = (0, −s, 0), s = E δ / H).

- Jaeger, Cook and Zimmerman (2007), §4.7 (single plane of weakness), superposed: with
  σxx = −a, σyy = −b − λ s the joint carries p = a sin²β + (b + λ s) cos²β and
  |τ| = (b − a + λ s) sinβ cosβ (b ≥ a), so it slips at
      λ = [c + μ (a sin²β + b cos²β) − (b − a) sinβ cosβ] / (s sinβ cosβ − μ s cos²β),
  that is λ_0 (c + μ p0 − |τ0|) / c with λ_0 the slip of σ0 = 0. The ratio to the run
  with σ0 = 0 is exact in the code too (the stuck joint moves nothing at λ = 0, and each
  pair's faces' stress is p0 + λ p_v): tested to 1e-9. λ itself is 5.3 % below the law on
  this mesh (the MLS cells' patch-test error of docs/validation.md, the −6 % of the
  Jaeger test): held as a strict xfail at the Jaeger test's 3 %.
- σ0 = 0, and a zero ``cracking.constant`` part without σ0, repeat the proportional
  contact run (jobs/jaeger_joint.toml) event by event.
- A joint under compression with zero release stays closed and stuck: no event at λ = 0
  and the constant load's solution is zero (the pre-cracked closed state is in balance).
- A joint whose initial shear exceeds c + μ p0 slips before any release (the count is
  reported) and the run goes on; friction never creates energy: at every event the
  slipping pairs' Coulomb traction μ p does work μ p sgn s ≥ 0 on their slip.
- 1 and 2 ranks give the same events.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.fracture.contact import SLIP, STICK
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS
from tests.fracture.test_constant_loads import run

SCENES = Path(__file__).resolve().parent / "scenes"
JOINT = SCENES / "joint_insitu.toml"
JAEGER = JOBS / "jaeger_joint.toml"
#: the scene's specimen height, E, platen displacement, joint angle and strengths
H, E, DELTA, BETA, C, MU = 80.0, 10000.0, 0.01, 45.0, 1.0, 0.5
#: the Jaeger test's tolerance (tests/fracture/test_contact_mechanics.py, JAEGER_RTOL)
JAEGER_RTOL = 0.03


def jaeger_lambda(a: float, b: float) -> float:
    """λ of the first slip under σ0 = (−a, −b, 0) plus λ (0, −s, 0) (module docstring)."""
    beta = math.radians(BETA)
    sn, cs = math.sin(beta), math.cos(beta)
    s = E * DELTA / H
    p0, tau0 = a * sn**2 + b * cs**2, (b - a) * sn * cs
    return (C + MU * p0 - tau0) / (s * sn * cs - MU * s * cs**2)


def test_zero_initial_stress_repeats_the_proportional_contact_run():
    """The constant-load loop with σ0 = 0 slips the same pairs at the same λ (rtol 1e-12)."""
    prop, _ = run(JAEGER, "geometry.parameters.h=5", "cracking.max_events=2")
    zero, res = run(JOINT, "initial_stress.stress=[0.0, 0.0, 0.0]")
    assert [r["mode"] for r in zero.rows] == ["slip", "slip"]
    assert [r["edge"] for r in zero.rows] == [r["edge"] for r in prop.rows]
    np.testing.assert_allclose(
        [r["load_factor"] for r in zero.rows], [r["load_factor"] for r in prop.rows], rtol=1e-12
    )
    assert res["contact_initial"]["open"] == res["contact_initial"]["slipping"] == 0


def test_zero_constant_load_repeats_the_proportional_contact_run():
    """``cracking.constant`` naming the held bottom (a zero constant part): the same 3 events.

    The loop of constant loads with contact (no initial stress) settles the states at
    u_c + λ u_v = λ u_v: the proportional run's slips, λ and reactions to 1e-12.
    """
    sets = ("geometry.parameters.h=5", "cracking.max_events=3")
    prop, _ = run(JAEGER, *sets)
    const, res = run(JAEGER, *sets, "cracking.constant=['bottom']")
    assert res["constant"]["groups"] == ["bottom"] and len(const.rows) == 3
    assert [r["edge"] for r in const.rows] == [r["edge"] for r in prop.rows]
    for key in ("load_factor", "reaction"):
        np.testing.assert_allclose(
            [r[key] for r in const.rows], [r[key] for r in prop.rows], rtol=1e-12, err_msg=key
        )


@pytest.mark.parametrize(("a", "b"), [(2.0, 2.0), (1.0, 2.0)])
def test_initial_stress_raises_the_slip_by_jaegers_ratio(a, b):
    """λ(σ0) / λ(0) = (c + μ p0 − |τ0|) / c exactly (1e-9): hydrostatic 2, biaxial 1.25."""
    base, _ = run(JOINT, "initial_stress.stress=[0.0, 0.0, 0.0]", "cracking.max_events=1")
    pre, _ = run(JOINT, f"initial_stress.stress=[{-a}, {-b}, 0.0]", "cracking.max_events=1")
    ratio = jaeger_lambda(a, b) / jaeger_lambda(0.0, 0.0)
    assert pre.rows[0]["mode"] == "slip" and pre.rows[0]["edge"] == base.rows[0]["edge"]
    assert pre.rows[0]["load_factor"] / base.rows[0]["load_factor"] == pytest.approx(
        ratio, rel=1e-9
    )


MLS_NOT_CONSISTENT = pytest.mark.xfail(
    strict=True, reason="MLS cells fail the stress patch test (docs/validation.md)"
)


@pytest.mark.parametrize("gradient", [pytest.param("fit", marks=MLS_NOT_CONSISTENT), "consistent"])
def test_first_slip_at_jaegers_load(gradient):
    """σ0 = (−1, −2, 0): the fits' own gradient 3.788 against 4.0 (−5.3 %, h = 5).

    With ``mls_gradient = "consistent"`` the faces read the uniform field: 4.0 to 1e-12.
    """
    pre, _ = run(
        JOINT,
        "initial_stress.stress=[-1.0, -2.0, 0.0]",
        "cracking.max_events=1",
        f"cracking.mls_gradient={gradient}",
    )
    assert pre.rows[0]["load_factor"] == pytest.approx(jaeger_lambda(1.0, 2.0), rel=JAEGER_RTOL)


def test_closed_joint_under_compression_moves_nothing_at_zero_release():
    """σ0 = −2 I: every pair closed and stuck, no event at λ = 0, u_c zero to round-off."""
    driver, res = run(JOINT, "initial_stress.stress=[-2.0, -2.0, 0.0]", "cracking.max_events=1")
    row = driver.rows[0]
    pairs = res["contact"]["pairs"]
    assert pairs >= 8
    assert row["load_factor"] > 1.0 and row["mode"] == "slip"
    assert row["stick"] == pairs and row["open"] == row["slip"] == 0
    assert res["contact_initial"]["open"] == res["contact_initial"]["slipping"] == 0
    assert res["initial_stress"]["out_of_balance"] < 1e-12
    assert res["constant"]["cracked_at_zero"] == 0
    # the platen's displacement λ δ is the scale of the event's displacements
    assert np.abs(driver.loop.u_const).max() <= 1e-12 * abs(row["control_displacement"])


def confined(tmp: Path) -> Path:
    """scenes/joint_insitu.toml with its sides held in x instead of loaded.

    The joint then cannot slide off as a rigid block (with its sides free, a joint that
    slips all along lets the platen push the upper block down it: no load path).
    """
    text = JOINT.read_text().replace("../../../meshes", str(SCENES.parents[2] / "meshes"))
    text = text.replace('loaded = ["left", "right"]', "loaded = []")
    held = "".join(
        f'[[bc]]\ngroup = "{g}"\nvalue = [0.0]\ncomponents = ["x"]\n\n' for g in ("left", "right")
    )
    path = tmp / "joint_confined.toml"
    path.write_text(text.replace("[initial_stress]", held + "[initial_stress]"))
    return path


#: σ0 = (−1, −5, 0) on the 45° joint: p0 = 3, |τ0| = 2 > c + μ p0 = 1.7 with c = 0.2; the
#: rock fails in Mohr-Coulomb shear (c = 3, φ = 30°) as the platen moves.
SLIPPING = (
    "initial_stress.stress=[-1.0, -5.0, 0.0]",
    "cracking.joints.joint.cohesion=0.2",
    "material.cohesion=3.0",
    "material.friction_angle=30.0",
    "cracking.max_events=4",
)


def run_watching(scene: Path, *overrides: str, comm: MPI.Comm = MPI.COMM_SELF):
    """Run; the pairs' (state, sign, p, slip, μ, L) at every event (after its settling)."""
    driver = scene_driver(load_scene_collective(comm, scene, list(overrides)), comm)
    seen = []
    loop = driver.loop
    publish = loop._publish

    def watch(run_, event, *, row, energy):
        p = driver.contact.pairs
        act = p.active()
        seen.append(
            tuple(
                a[act].copy()
                for a in (p.state, p.sign, p.pressure, p.slip, p.friction, p.length, p.tau0)
            )
        )
        return publish(run_, event, row=row, energy=energy)

    loop._publish = watch
    try:
        return driver, driver.run(), seen
    finally:
        driver.problem.destroy()


def test_joint_beyond_its_strength_slips_before_any_release(tmp_path):
    """All 12 pairs slip at the start, in the direction of τ0; four events follow.

    Friction never creates energy: at every event each slipping pair's Coulomb traction
    does work μ p sgn s ≥ 0 on its slip (to 1e-9 of the largest), and closed pairs
    carry no tension.
    """
    driver, res, seen = run_watching(confined(tmp_path), *SLIPPING)
    assert res["contact_initial"]["slipping"] >= 1
    assert res["contact_initial"]["slipping"] == res["contact"]["pairs"] - 4  # 4 new cracks
    assert len(driver.rows) == 4 and all(r["load_factor"] > 0.0 for r in driver.rows)
    for state, sign, p, s, mu, length, _tau0 in seen:
        slip = state == SLIP
        closed = slip | (state == STICK)
        assert np.all(p[closed] >= -1e-9 * np.abs(p).max())
        work = mu * p * sign * s * length
        assert np.all(work[slip] >= -1e-9 * np.abs(work).max())
        assert work[slip].sum() > 0.0
    state, sign, *_, tau0 = seen[0]
    joint = tau0 != 0.0
    assert np.all(sign[joint & (state == SLIP)] == np.sign(tau0[joint & (state == SLIP)]))


@pytest.mark.mpi(min_size=2)
def test_same_events_on_1_and_2_ranks(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("c0") if MPI.COMM_WORLD.rank == 0 else None
    tmp = MPI.COMM_WORLD.bcast(tmp)
    scene = confined(tmp) if MPI.COMM_WORLD.rank == 0 else None
    scene = MPI.COMM_WORLD.bcast(scene)
    parallel, res, _ = run_watching(scene, *SLIPPING, comm=MPI.COMM_WORLD)
    serial, ref, _ = run_watching(scene, *SLIPPING, comm=MPI.COMM_SELF)
    assert len(parallel.rows) == len(serial.rows) == 4
    assert [r["edge"] for r in parallel.rows] == [r["edge"] for r in serial.rows]
    np.testing.assert_allclose(
        [r["load_factor"] for r in parallel.rows],
        [r["load_factor"] for r in serial.rows],
        rtol=1e-8,
    )
    edges = MPI.COMM_WORLD.allgather([r["edge"] for r in parallel.rows])
    assert all(e == edges[0] for e in edges)
    assert res["contact_initial"] == ref["contact_initial"]
