"""The generated DFN slope (jobs/slope_dfn.toml): a trial's verdict does not depend on the ranks.

The trial F = 1.8 failed on 1 rank (Newton at load factor 0.975, DIVERGED_MAX_IT after
25 iterations, the residual still falling by about 10 % an iteration, one spring
switching stick/slip per iteration) and held on 2: a budget too small for the steps
near the limit, not a failure of equilibrium (measured: with 100 iterations it holds on
both, as do F up to 2.2; docs/plasticity.md, "A generated DFN slope"). The job's
budget (``max_iterations = 100``) must give the same verdict and the same crest
displacement on 1 and N ranks. No closed form for the slope's factor: the check is the
agreement, the reference the serial solve of the same mesh. Not yet robust: the job's
brackets on 1 and 2 ranks still differ by 0.05 (F = 2.25 fails on 1 rank on one load
path; docs/plasticity.md).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.effects.plasticity import PlasticityConfig
from geofrac.fem.joints import joint_springs
from geofrac.fem.plastic import Law, PlasticProblem
from geofrac.fem.strength_reduction import point_monitor
from geofrac.meshing.distribute import build_mesh
from geofrac.plasticity import MohrCoulomb
from geofrac.plasticity.interface import JointStrength
from geofrac.plasticity.strength_reduction import reduce_strength
from geofrac.scene.load import load_scene
from tests.fem.helpers import JOBS
from tests.fem.test_joint_interface import _space_and_bcs

JOB = JOBS / "slope_dfn.toml"


class TrialResult(NamedTuple):
    """One trial: verdict, crest |u| (m), Newton iterations, increments tried, watchdogs."""

    converged: bool
    crest: float
    iterations: int
    attempts: int
    watchdog_steps: int


#: the job's rock (strong: it never yields) and unit weight γ = ρ g (kN/m³).
ROCK = MohrCoulomb(E=1e6, nu=0.25, cohesion=1e5, friction_angle=45.0, dilatancy_angle=0.0)
GAMMA = 26.0
#: the trial whose verdict flipped with the ranks under the old budget of 25 iterations.
FLIPPED = 1.8

#: relative changes of E (round-off of another machine) with which Newton's line search
#: stalled at load factor 1.0 before the watchdog step (geofrac.solvers.snes): the
#: increment was cut, the load path changed and the crest displacement with it (by
#: 2.9e-6 and 1.4e-6 of itself, the first as CI's 2-rank run measured).
STALLED = (5e-12, 15e-12)

pytestmark = pytest.mark.robust


def dfn_trial(comm: MPI.Comm, factor: float, *, rock: MohrCoulomb = ROCK) -> TrialResult:
    """The job's trial ``factor`` on ``comm`` with the rock ``rock``.

    The job's mesh (cut along its fractures), supports, joints, load steps, cuts and
    Newton budget, gravity ramped from a stress-free start, as ``geofrac run`` does.
    """
    scene = load_scene(JOB, [])
    config = scene.effect_config("plasticity", PlasticityConfig)
    assert scene.geometry is not None and config is not None
    assert config.strength_reduction is not None
    tagged = build_mesh(scene.geometry, comm)
    V, bcs = _space_and_bcs(tagged, base_group="side_1", back_group="side_2")
    joints = [(j.name, JointStrength(j.cohesion, j.friction)) for j in config.joints]
    springs = joint_springs(V, tagged, joints, bcs=bcs, rock=rock, penalty=config.contact_penalty)
    mesh = tagged.mesh

    def external(f: Any, v: Any) -> Any:
        return ufl.inner(f * ufl.as_vector([0.0, -GAMMA]), v) * ufl.dx(domain=mesh)

    law: Law = reduce_strength(rock, factor)
    problem = PlasticProblem(
        V,
        law,
        external,
        bcs=bcs,
        joints=springs(law),
        max_it=config.max_iterations,
        options={"snes_linesearch_type": "bt"},
    )
    monitor = point_monitor(config.strength_reduction.monitor or (6.0, 10.0))
    try:
        result = problem.solve_steps(config.load_steps, max_cuts=config.max_cuts, monitor=monitor)
    finally:
        problem.destroy()
    assert result.monitor is not None
    return TrialResult(
        result.converged,
        float(np.linalg.norm(result.monitor)),
        sum(s.report.iterations for s in result.steps),
        len(result.steps),
        sum(s.report.watchdog_steps for s in result.steps),
    )


def test_job_states_its_budget() -> None:
    """The job's budget and materials are those the measurements were made with."""
    scene = load_scene(JOB, [])
    config = scene.effect_config("plasticity", PlasticityConfig)
    assert config is not None
    assert config.max_iterations == 100 and config.load_steps == 5 and config.max_cuts == 4
    (joint,) = config.joints
    assert joint.friction == pytest.approx(math.tan(math.radians(35.0)), rel=1e-12)
    assert scene.material is not None
    assert scene.material.E == ROCK.E and config.cohesion == ROCK.cohesion


@pytest.mark.mpi(min_size=2)
def test_two_ranks_same_dfn_verdict() -> None:
    """F = 1.8 holds on 2 ranks and on each rank alone, with one crest displacement."""
    world = MPI.COMM_WORLD
    (ok_n, u_n, *_), (ok_1, u_1, *_) = (dfn_trial(c, FLIPPED) for c in (world, MPI.COMM_SELF))
    assert ok_n and ok_1
    # the same equilibrium: the displacement agrees to far below its size (about 1 mm)
    assert abs(u_n - u_1) <= 1e-6 * u_1
    assert world.allreduce(int(ok_1), op=MPI.SUM) == world.size


@pytest.mark.parametrize("change", STALLED)
def test_stalled_line_search_keeps_the_load_path(change: float) -> None:
    """E changed by round-off: the five increments hold uncut, the crest as unperturbed.

    Without the watchdog step the line search stalled at load factor 1.0 (||F|| stuck at
    7.1, five springs switching back and forth), the increment was cut and the crest
    moved by 1e-6 of itself: a load path chosen by round-off. The crest scales as 1/E,
    so the two agree to the change of E, far below 1e-9.
    """
    rock = dataclasses.replace(ROCK, E=ROCK.E * (1.0 + change))
    base, changed = dfn_trial(MPI.COMM_SELF, FLIPPED), dfn_trial(MPI.COMM_SELF, FLIPPED, rock=rock)
    assert base.converged and changed.converged
    assert base.attempts == changed.attempts == 5  # the job's load steps, none cut
    assert changed.watchdog_steps >= 1  # the stall happened and was left
    assert abs(changed.crest - base.crest) <= 1e-9 * base.crest
