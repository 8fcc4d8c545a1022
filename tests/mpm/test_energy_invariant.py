"""The contact's energy invariant (docs/mpm_energy.md, "The contact's invariant").

(a) The contact's work at its own velocities, Σ ½ m (|v_after|² − |v_before|²) over the
contact nodes, is ≤ 0 in every step up to round-off: the contact only removes an
approach and slows a slide, at most to rest. (b) In a friction run with gravity the
budget's numerical work stays within 1 % of gravity's work. A run that breaks either
says so in summary.json and in its report lines.
"""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.mpm.boundaries import boundary_rows, scene_grid
from geofrac.mpm.energy import (
    CONTACT_FLOOR,
    CONTACT_ROUNDOFF,
    GRAVITY_JUDGED,
    NUMERICAL_BOUND,
    EnergyLog,
    StepBudget,
)
from geofrac.mpm.friction import friction
from geofrac.mpm.parallel import decompose
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, time_step
from geofrac.scene import load_scene
from tests.conftest import JOBS
from tests.mpm.test_friction import (
    ALL_SIDES,
    BOX,
    CELL,
    COVER,
    G0,
    MAT,
    RHO,
    _block,
    _settings,
)


def _contact_steps(g, p, s, t_end):
    """Step to ``t_end`` with a budget: per step (contact work, its scale), shape=(k, 2)."""
    out = []
    for _ in range(round(t_end / s.dt)):
        b = StepBudget()
        step(g, p, MAT, settings=s, budget=b)
        out.append((b.contact, b.contact_scale))
    return np.array(out)


def _slid(shape, scheme):
    """A stress-free block launched at 1 m/s on a level floor, μ = 0.5 (it slips, then sticks)."""
    p, gravity = _block(0.0, prestress=False, v0=1.0)
    g = scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2)
    return _contact_steps(g, p, _settings(g, gravity, 0.5, scheme, shape), 0.3), p


def _thrown_steps(shape, scheme):
    """The block of test_friction's ``_thrown``: thrown at (3, 2) m/s around the closed box."""
    p = lattice([0.5, 0.2], [10, 10], CELL / 2, density=RHO)
    p.v[:] = [3.0, 2.0]
    g = scene_grid((0.0, 0.0), BOX, CELL, padding=2)
    fixed, ids, nrm, planes, _ = boundary_rows(
        g, (0.0, 0.0), BOX, walls=ALL_SIDES, bed=(), frictional=tuple(ALL_SIDES)
    )
    fr = friction(ids, nrm, 0.5, offsets=planes)
    dt = time_step(0.2, CELL, MAT, density=RHO, dim=2)
    s = StepSettings(scheme, shape, dt, np.array([0.0, -G0]), fixed, friction=fr)
    return _contact_steps(g, p, s, 0.8), p


def _assert_never_positive(work):
    """Every step's contact work at most round-off of its scale; and the contact worked."""
    contact, scale = work.T
    bound = CONTACT_ROUNDOFF * (scale + CONTACT_FLOOR)
    worst = int(np.argmax(contact - bound))
    assert contact[worst] <= bound[worst], (
        f"step {worst + 1}: contact work {contact[worst]:.3g} J > {bound[worst]:.3g} J"
    )
    return -contact.sum()


@pytest.mark.parametrize(("shape", "scheme"), COVER)
def test_the_contact_never_creates_energy_under_a_block_sliding_on_a_level_floor(shape, scheme):
    """Launched at v₀ = 1 m/s, stress-free: every step's contact work ≤ round-off.

    The contact takes out (most of) the kinetic energy ½ M v₀² = 250 J (the rest goes
    to the elastic ringing and the budget's friction term): judged against 10 % of it so
    that a contact doing nothing fails.
    """
    work, p = _slid(shape, scheme)
    kinetic0 = 0.5 * p.mass.sum() * 1.0**2
    assert _assert_never_positive(work) > 0.1 * kinetic0


@pytest.mark.parametrize(("shape", "scheme"), COVER)
def test_the_contact_never_creates_energy_in_a_closed_frictional_box(shape, scheme):
    """Thrown around the box (several impacts on four frictional walls in 0.8 s)."""
    work, p = _thrown_steps(shape, scheme)
    kinetic0 = 0.5 * p.mass.sum() * (3.0**2 + 2.0**2)
    assert _assert_never_positive(work) > 0.01 * kinetic0


def _log(*steps):
    """An EnergyLog of a body starting at rest fed (kinetic, Π, StepBudget) steps."""
    log = EnergyLog(0.0, 0.0)
    for kinetic, potential, b in steps:
        log.record(kinetic, 0.0, potential, terms=b.terms())
    return log


def test_positive_contact_work_breaks_the_invariant():
    """A step whose contact work is above 1e-12 of its scale: named, counted, warned."""
    below = StepBudget(contact=0.5 * CONTACT_ROUNDOFF * 2.0, contact_scale=2.0)
    above = StepBudget(contact=3e-9, contact_scale=1e-3)  # 3e-6 of its scale
    log = _log((1.0, -1.0, below), (1.0, -1.0, above))
    assert log.contact_positive == 1
    assert log.contact_max == 3e-9
    verdict, lines = log.invariant(contact=True, gravity=True)
    assert verdict == "contact work > 0 in 1 step(s)"
    assert len(lines) == 1 and lines[0].startswith("warning: the contact created energy in 1")
    assert "up to 3e-09 J = 3e-06 of" in lines[0] and "(bound 1e-12, round-off;" in lines[0]
    assert log.invariant(contact=False, gravity=True) == (None, [])


def test_numerical_work_above_one_percent_of_gravitys_breaks_the_invariant():
    """numerical_work = +0.23 J (K_tr) against W_g = 10 J: +2.3 %, over the 1 % bound."""
    log = _log((9.77, -10.0, StepBudget(transfer=0.23)))  # numerical = K_tr
    assert log.budget.numerical_work == pytest.approx(0.23)
    assert log.gravity_ratio == pytest.approx(0.023)
    verdict, lines = log.invariant(contact=True, gravity=True)
    assert verdict == "numerical work +2.3 % of gravity work"
    assert lines == [
        "warning: numerical work +2.3 % of the gravity work (bound 1 %): the scheme created "
        "energy (docs/mpm_energy.md)"
    ]
    assert log.invariant(contact=True, gravity=False) == ("ok", [])  # no gravity: not judged
    ok = _log((9.95, -10.0, StepBudget(transfer=0.5 * NUMERICAL_BOUND * 10.0)))
    assert ok.invariant(contact=True, gravity=True) == ("ok", [])


def test_the_ratio_waits_for_gravity_to_matter():
    """W_g below GRAVITY_JUDGED × S (a body thrown on a level floor): no ratio, no verdict."""
    log = EnergyLog(100.0, 0.0)  # S = 100
    w = 0.5 * GRAVITY_JUDGED * 100.0
    log.record(100.0, 0.0, -w, terms=StepBudget(transfer=w).terms())
    assert log.gravity_ratio is None and log.gravity_ratio_max is None
    assert log.invariant(contact=True, gravity=True) == ("ok", [])


def test_the_ratio_is_judged_where_gravity_did_a_tenth_of_its_work():
    """A ramp's start-up does not decide the verdict once gravity has done far more.

    The start-up: +33 µJ against 2.7 mJ (+1.2 %); later 0.33 J, the scheme then a loss.
    While gravity has not done ten times the start-up's work, the start-up is judged.
    """
    start = (0.0027, -0.0027, StepBudget(transfer=3.3e-5))  # body at rest: judged
    later = (0.33, -0.33, StepBudget(transfer=-0.003 - 3.3e-5))  # numerical −0.9 %
    log = _log(start, later)
    assert log.gravity_ratio == pytest.approx(-0.003 / 0.33)
    assert log.gravity_ratio_max == pytest.approx(-0.003 / 0.33)
    assert log.invariant(contact=True, gravity=True) == ("ok", [])
    early = _log(start, (0.02, -0.02, StepBudget(transfer=-3.2e-5)))  # 0.02 < 10 × 2.7 mJ
    assert early.gravity_ratio_max == pytest.approx(3.3e-5 / 0.0027)
    assert (
        early.invariant(contact=True, gravity=True)[0] == "numerical work +1.22 % of gravity work"
    )
    back = EnergyLog.from_state(early.state())
    assert back.gravity_ratio_max == early.gravity_ratio_max


def test_a_checkpoint_keeps_the_invariants_measures_and_an_older_one_loads():
    log = _log((1.0, -1.0, StepBudget(contact=3e-9, contact_scale=1e-3, transfer=0.5)))
    back = EnergyLog.from_state(log.state())
    for name in ("contact_max", "contact_relative_max", "contact_positive", "contact_total",
                 "gravity_ratio", "gravity_ratio_max"):  # fmt: skip
        assert getattr(back, name) == getattr(log, name)
    old = log.state()
    del old["contact"]
    older = EnergyLog.from_state(old)
    assert older.contact_positive == 0 and older.gravity_ratio_max is None
    assert older.budget == log.budget


def test_the_incline_scene_reports_the_invariant_ok(tmp_path):
    """jobs/mpm_incline_block.toml (μ = 0.3 on 30°, from rest): the summary says "ok".

    The contact took energy out (its total < 0, and no step's work above round-off) and
    the numerical work stays below 1 % of gravity's (measured over t ≤ 1: ≤ −0.09 %).
    """
    from geofrac.mpm.driver import MPM
    from geofrac.pipeline import run_scene

    scene = load_scene(JOBS / "mpm_incline_block.toml", ["mpm.t_end=0.2"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_SELF, verbose=False)
    r = summary["results"]
    assert r["energy_invariant"] == "ok"
    assert r["energy_invariant_warnings"] == []
    assert r["contact_work_positive_steps"] == 0
    assert r["contact_work_relative_max"] <= CONTACT_ROUNDOFF
    assert r["contact_work_total"] < 0
    assert r["numerical_over_gravity_work"] < NUMERICAL_BOUND
    assert r["numerical_over_gravity_work_max"] < NUMERICAL_BOUND
    assert MPM.report(summary) == []  # no warning line
    assert MPM.result(scene, summary)[0].startswith("runout (front x moved): ")


def test_a_broken_run_warns_in_its_summary_and_report(tmp_path, monkeypatch):
    """Positive numerical work injected into every step: the verdict and the report line."""
    from geofrac.mpm.driver import MPM
    from geofrac.pipeline import run_scene

    def created(self):  # the step's numerical work: 2 % of gravity's work −ΔΠ
        return -0.02 * self.potential

    monkeypatch.setattr(StepBudget, "numerical", created)
    scene = load_scene(JOBS / "mpm_incline_block.toml", ["mpm.t_end=0.05"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_SELF, verbose=False)
    r = summary["results"]
    assert r["numerical_over_gravity_work"] == pytest.approx(0.02, rel=1e-9)
    assert r["energy_invariant"] == "numerical work +2 % of gravity work"
    line = "warning: numerical work +2 % of the gravity work (bound 1 %): the scheme created energy"
    assert MPM.report(summary)[0].startswith(line)


def test_a_run_without_friction_is_not_judged():
    from geofrac.bench.mpm import TRANSLATING_SCENE, translating_overrides
    from geofrac.mpm.driver import simulate

    overrides = translating_overrides("ugimp", "usavg", None, t_end=1.0)
    r = simulate(load_scene(TRANSLATING_SCENE, overrides), MPI.COMM_SELF, verbose=False)
    assert r["energy_invariant"] is None and r["contact_work_max"] is None


@pytest.mark.mpi(min_size=2)
def test_the_contact_work_on_two_ranks_is_the_serial_one(tmp_path_factory):
    """Each contact node counted once (the owned nodes): 1 and 2 ranks agree.

    The incline's block moved onto the slabs' cut (x = 2: it spans 1.5-2.5), so floor
    nodes are shared by both ranks: its contact work on 1 and 2 ranks agrees to
    round-off, and the invariant holds on both.
    """
    from geofrac.mpm.driver import simulate

    comm = MPI.COMM_WORLD
    overrides = ["mpm.t_end=0.2", "mpm.particles.lower=[1.5, 0.0]"]
    scene = load_scene(JOBS / "mpm_incline_block.toml", overrides)
    one = simulate(scene, MPI.COMM_SELF, verbose=False)
    two = simulate(scene, comm, verbose=False)
    assert two["energy_invariant"] == one["energy_invariant"] == "ok"
    assert two["contact_work_total"] == pytest.approx(one["contact_work_total"], rel=1e-10)
    assert two["contact_work_total"] < 0
    assert two["numerical_over_gravity_work"] == pytest.approx(
        one["numerical_over_gravity_work"], rel=1e-9
    )


@pytest.mark.mpi(min_size=2)
def test_the_contact_never_creates_energy_on_two_ranks():
    """The sliding block decomposed over the ranks (its floor nodes on both)."""
    comm = MPI.COMM_WORLD
    p, gravity = _block(0.0, prestress=False, v0=1.0)
    dom = decompose(scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2), comm)
    mine = dom.distribute(p)
    s = _settings(dom.local, gravity, 0.5, "usf", "cpgimp", domain=dom)
    work = np.array([comm.allreduce(row) for row in _contact_steps(dom.local, mine, s, 0.3)])
    assert _assert_never_positive(work) > 0.1 * 0.5 * p.mass.sum()
