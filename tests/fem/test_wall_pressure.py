"""A support pressure on an opening's wall from the excavation's stage (docs/insitu.md).

The geometry of tests/fracture/scenes/plate_hole_staged.toml (meshes/opening.geo: a
circular opening of radius a = 1 meshed whole, h = 0.1 on the wall) with its outer
square enlarged to L = 40a, P2, plane strain, E = 1000, ν = 0.25, under a hydrostatic
in-situ stress σ0 = −p0 I (p0 = 10), far sides on rollers (left, bottom) or loaded by
σ0·n (right, top). One stage excavates the opening; a pressure p_i on the wall
(``group = "wall"``, inside the mesh until the excavation) acts from that stage. Later
stages switch the pressure off and on again, so one run gives the states for p_i = 4,
0, 1 and p0 (``WALL`` of tests/fracture/test_staged_loads.py). References:

- **Kirsch/Lamé** (Jaeger, Cook and Zimmerman (2007), §8.4): the opening in an infinite
  plate under −p0 with p_i on its wall moves radially by u_r(a) = −(p0 − p_i) a (1 + ν)/E
  (inward for p_i < p0; plane strain and plane stress alike, a/(2G)). The crown and the
  invert converge by 2 u_r, as do the sidewalls (the rollers' rigid shift cancels),
  within 1 %, the tolerance of the P2 Kirsch wall-displacement tests
  (tests/fem/test_insitu.py, L = 40a: the finite plate is softer by O((a/L)²) ≈ 0.1 %).
  Measured: −0.03 % (crown) and +0.04 % (sidewalls) at p_i = 0, 1 and 4.
- **p_i = p0** restores what the removed cells carried: the release is cancelled on
  every wall facet and the body does not move (|u| < 1e-9 of p0 a (1 + ν)/E;
  measured 7e-15).
- **Linearity**: u(p_i) = u(0) + p_i (u(1) − u(0)) (1e-9), and switched off (``until``)
  the pressure leaves the bare excavation's state, that of a run without it (1e-9).
"""

from __future__ import annotations

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.fracture.test_staged_loads import EXCAVATE, WALL, _scene

P0, E, NU, A = 10.0, 1000.0, 0.25, 1.0
U = P0 * A * (1 + NU) / E  # the wall displacement's scale
POINTS = {"crown": (0, 1), "invert": (0, -1), "right": (1, 0), "left": (-1, 0)}

#: P2 on the plate's mesh with its outer square at 40a, probes on the wall.
OVERRIDES = [
    "discretization.element=p2",
    "geometry.parameters.L=40.0",
    "geometry.parameters.h_far=3.0",
    "output.probes={" + ", ".join(f"{k} = [{x}.0, {y}.0]" for k, (x, y) in POINTS.items()) + "}",
]


def _states(stages: str, tmp, comm=MPI.COMM_WORLD) -> list[dict[str, np.ndarray]]:
    """Each stage's probe displacements, shape=(2,) per point, of the plate with ``stages``."""
    path = comm.bcast(_scene(tmp, stages, cracking=False) if comm.rank == 0 else None)
    scene = load_scene_collective(comm, path, OVERRIDES)
    solution = solve_scene(scene, comm, verbose=False)
    try:
        stages_ = solution.results["stages"][1:]
        return [{k: np.array(v) for k, v in s["probes"].items()} for s in stages_]
    finally:
        solution.problem.destroy()


def _wall(state: dict[str, np.ndarray]) -> np.ndarray:
    """Half the convergence crown–invert and sidewall–sidewall: u_r(a) at θ = 90°, 0°."""
    return np.array(
        [
            (state["crown"][1] - state["invert"][1]) / 2,
            (state["right"][0] - state["left"][0]) / 2,
        ]
    )


def test_wall_pressure_gives_lame_and_superposes(tmp_path):
    four, free, unit, full = _states(WALL, tmp_path)
    for p_i, state in ((4.0, four), (0.0, free), (1.0, unit)):
        closed = -(P0 - p_i) * A * (1 + NU) / E
        np.testing.assert_allclose(_wall(state), closed, rtol=0.01, err_msg=f"p_i = {p_i}")
    for name in POINTS:  # p_i = p0: nothing moves
        assert np.max(np.abs(full[name])) < 1e-9 * U, name
        np.testing.assert_allclose(
            four[name], free[name] + 4.0 * (unit[name] - free[name]), atol=1e-9 * U
        )
    (bare,) = _states(EXCAVATE, tmp_path)
    for name in POINTS:  # switched off: the bare excavation's state
        np.testing.assert_allclose(free[name], bare[name], rtol=0, atol=1e-9 * U)


def test_a_wall_pressure_without_from_is_refused_naming_the_key(tmp_path):
    text = EXCAVATE + '[[load]]\ntype = "pressure"\ngroup = "wall"\nvalue = 4.0\n'
    with pytest.raises(RunError, match=r"load\[0\]\.group: \d+ facets of group 'wall' lie inside"):
        _states(text, tmp_path, comm=MPI.COMM_SELF)


@pytest.mark.mpi(min_size=2)
def test_wall_pressure_on_2_ranks_equals_1(tmp_path):
    comm = MPI.COMM_WORLD
    many = _states(WALL, tmp_path, comm=comm)
    ref = comm.bcast(_states(WALL, tmp_path, comm=MPI.COMM_SELF) if comm.rank == 0 else None)
    for a, b in zip(many, ref, strict=True):
        for name in POINTS:
            np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-9 * U)
