"""Only interior edges crack: a free surface has no second face to open (issue 45).

The quarter plate with a hole of ``scenes/quarter_hole_displacement.toml`` is loaded by a
prescribed displacement of its top side, in tension and in compression, under every
event criterion. Its hole's edges have one cell each; none may ever crack, and the first
crack lies where the elastic field is most tensile, judged by the closed form of Kirsch
(1898) for a hole in an infinite plate (the plate is 10 radii wide, so the finite width
changes the peak by about 1 %: Howland's Kt = 3.03 against 3).
"""

import math
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.fracture.event_criterion import CRITERIA
from geofrac.scene import load_scene_collective

SCENE = Path(__file__).parent / "scenes" / "quarter_hole_displacement.toml"
#: Mesh size on the hole (the scene's h_hole).
H_HOLE = 0.1


def kirsch_sigma1(points: np.ndarray, sigma: float) -> np.ndarray:
    """Largest principal stress about a unit hole under a far-field σ_yy = sigma.

    Kirsch (1898); Jaeger, Cook and Zimmerman (2007), §8.4, with θ measured from the
    load's direction y. ``points``: shape=(n, 2); returns shape=(n,).
    """
    r = np.hypot(points[:, 0], points[:, 1])
    t = np.arctan2(points[:, 0], points[:, 1])  # angle from +y
    q2, q4 = 1.0 / r**2, 1.0 / r**4
    c, s = np.cos(2 * t), np.sin(2 * t)
    srr = 0.5 * sigma * ((1 - q2) + (1 - 4 * q2 + 3 * q4) * c)
    stt = 0.5 * sigma * ((1 + q2) - (1 + 3 * q4) * c)
    srt = -0.5 * sigma * (1 + 2 * q2 - 3 * q4) * s
    mean, half = 0.5 * (srr + stt), np.hypot(0.5 * (srr - stt), srt)
    return mean + half


def run(criterion: str, top: float, events: int, *, comm: MPI.Comm = MPI.COMM_SELF):
    """The driver after ``events`` events of the scene; top displacement ``top``."""
    overrides = [
        f"cracking.criterion={criterion}",
        f"cracking.max_events={events}",
        f"bc.2.value=[{top}]",
    ]
    scene = load_scene_collective(comm, SCENE, overrides)
    driver = scene_driver(scene, comm)
    try:
        result = driver.run()
    finally:
        driver.problem.destroy()
    return driver, result


@pytest.mark.parametrize("criterion", sorted(CRITERIA))
@pytest.mark.parametrize("top", [0.001, -0.001], ids=["tension", "compression"])
def test_no_boundary_edge_cracks_and_the_first_crack_is_where_kirsch_peaks(criterion, top):
    driver, _ = run(criterion, top, 1)
    mesh, state = driver.state.mesh, driver.state
    (first,) = np.flatnonzero(state.cracked)
    mid = mesh.midpoints()
    # the candidates: edges the rule lets crack (interior, not frozen next to a roller)
    cand = np.flatnonzero(state.crackable)
    assert not mesh.boundary_edges[cand].any()
    s1 = kirsch_sigma1(mid[cand], math.copysign(1.0, top))
    best = cand[np.argmax(s1)]
    # the field peaks at the hole's side under tension, at its crown under compression
    peak = np.array([1.0, 0.0]) if top > 0 else np.array([0.0, 1.0])
    assert np.hypot(*(mid[best] - peak)) < 3 * H_HOLE
    # the first crack lies within two hole cells of that peak: the edge criteria take the
    # edge at the peak, the direction criterion the edge there most nearly across σ1,
    # which may be the next one out (docs/cracking.md); Kirsch's σ1 falls by a fifth over
    # one cell there, so the distance, not the stress, is the test
    assert np.hypot(*(mid[first] - mid[best])) < 2 * H_HOLE

    driver, result = run(criterion, top, 20)
    cracked = np.flatnonzero(driver.state.cracked)
    assert len(cracked) >= 20 or result["end_reason"] != "max_events"
    assert not driver.state.mesh.boundary_edges[cracked].any()


@pytest.mark.mpi(min_size=2)
def test_two_ranks_crack_the_same_interior_edges():
    """On N ranks the same 20 edges crack as on one, none of them on the boundary."""
    many, _ = run("direction", 0.001, 20, comm=MPI.COMM_WORLD)
    one, _ = run("direction", 0.001, 20)
    cracked = np.flatnonzero(many.state.cracked)
    assert np.array_equal(cracked, np.flatnonzero(one.state.cracked))
    assert len(cracked) == 20 and not many.state.mesh.boundary_edges[cracked].any()
    assert MPI.COMM_WORLD.allreduce(len(cracked), op=MPI.MIN) == 20
