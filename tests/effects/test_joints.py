"""The joints effect: elastic rock with 3D Coulomb joints on RGNQ and P2.

The closed forms of tests/fem/test_joints_3d.py again, solved in the element's own
unknowns (RGNQ: vertex DOFs with rotations, the P2 field through its map T):

- a joint set's compliance, 1/E_eff = 1/E + 1/(kₙ s), to 1e-9, on two gmsh 3D algorithms;
- one joint pulled apart carries nothing;
- Jaeger's plane of weakness: the axial stress holds at σ1 = 2c/((1 − μ cot β) sin 2β);
- 1 and 2 ranks agree to 1e-10.

From rest, stress-free; the scenes are jobs/jaeger_joint_3d_rgnq.toml and the joint
set's prism of jobs/joint_set_3d.toml with its ``[plasticity]`` table turned into
``[joints]``.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.model.errors import SceneError
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

E = 10000.0


def joint_set_scene(tmp_path: Path) -> Path:
    """jobs/joint_set_3d.toml with the joints effect instead of plasticity (elastic rock)."""
    text = (JOBS / "joint_set_3d.toml").read_text()
    text = text.replace('effects = ["plasticity"]', 'effects = ["joints"]')
    text = re.sub(r"\[plasticity\]\n(.*\n)*?\n", "[joints]\nload_steps = 2\n\n", text, count=1)
    text = text.replace("[plasticity.joints.joints]", "[joints.joints]")
    text = text.replace('"../meshes/', f'"{JOBS.parent / "meshes"}/')
    path = tmp_path / "joint_set_3d_joints.toml"
    path.write_text(text)
    return path


def _solve(scene: Path, *overrides: str, comm: MPI.Comm = MPI.COMM_WORLD) -> dict:
    loaded = load_scene_collective(comm, scene, overrides)
    solution = solve_scene(loaded, comm, verbose=False)
    solution.problem.destroy()
    return solution.results["joints"]


def _top(results: dict, step: int = -1) -> float:
    return -float(results["steps"][step]["reactions"]["top"][2])


def jaeger(beta_deg: float, *, c: float = 1.0, mu: float = 0.5) -> float:
    """σ1 at slip (Jaeger, Cook and Zimmerman 2007, §4.7)."""
    b = math.radians(beta_deg)
    return 2.0 * c / ((1.0 - mu / math.tan(b)) * math.sin(2.0 * b))


@pytest.mark.parametrize(("element", "algorithm3d"), [("rgnq", 1), ("rgnq", 4), ("p2", 1)])
def test_joint_set_compliance(tmp_path: Path, element: str, algorithm3d: int) -> None:
    """E_eff = 1/(1/E + 1/(kₙ s)) = 5000 to 1e-9, the joints closed and sticking."""
    r = _solve(
        joint_set_scene(tmp_path),
        f"discretization.element={element}",
        "geometry.parameters.h=0.5",
        f"geometry.parameters.algorithm3d={algorithm3d}",
    )
    assert _top(r) / 0.001 == pytest.approx(1.0 / (1.0 / E + 1.0 / (40000.0 * 0.25)), rel=1e-9)
    assert r["converged"] and r["joints"]["slipping"] == 0 and r["joints"]["open"] == 0


def test_an_open_joint_carries_nothing_with_rgnq(tmp_path: Path) -> None:
    """One joint, the top raised: no reaction, every pair open by the displacement."""
    r = _solve(
        joint_set_scene(tmp_path),
        "discretization.element=rgnq",
        "geometry.parameters.n=1",
        "geometry.parameters.s=1.0",
        "geometry.parameters.h=0.5",
        "bc=[{group='bottom', value=[0.0], components=['z']}, "
        "{group='pin_xy', value=[0.0, 0.0], components=['x', 'y']}, "
        "{group='pin_y', value=[0.0], components=['y']}, "
        "{group='top_xy', value=[0.0, 0.0], components=['x', 'y']}, "
        "{group='top_y', value=[0.0], components=['y']}, "
        "{group='top', value=[0.001], components=['z']}]",
    )
    assert abs(_top(r)) < 1e-9 * E * 0.001
    assert r["joints"]["open"] == r["joints"]["pairs"] > 0
    assert r["joints"]["max_opening"] == pytest.approx(0.001, rel=1e-9)


@pytest.mark.parametrize(("beta", "element"), [(45.0, "rgnq"), (60.0, "rgnq"), (60.0, "p2")])
def test_jaeger_plateau(beta: float, element: str) -> None:
    """Sticking below the slip load, then σ1 held to 1e-6 with every pair slipping."""
    sigma = jaeger(beta)
    r = _solve(
        JOBS / "jaeger_joint_3d_rgnq.toml",
        f"discretization.element={element}",
        f"geometry.parameters.beta={beta}",
        "geometry.parameters.h=0.5",
        "joints.load_steps=4",
        "bc=[{group='bottom', value=[0.0], components=['z']}, "
        "{group='pin_xy', value=[0.0, 0.0], components=['x', 'y']}, "
        "{group='pin_y', value=[0.0], components=['y']}, "
        f"{{group='top', value=[{-2.1 * sigma / E * 2.5!r}], components=['z']}}]",
    )
    stresses = [_top(r, k) for k in range(4)]
    assert stresses[0] == pytest.approx(0.525 * sigma, rel=0.01)
    for s in stresses[2:]:
        assert s == pytest.approx(sigma, rel=1e-6)
    assert r["joints"]["slipping"] == r["joints"]["pairs"] > 0


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("discretization.element=p1", "discretization.element"),
        ("joints.nothing={friction=0.5}", "joints.nothing"),
        ("joints.joint.friction=-1.0", "joints.joint.friction"),
        ("joints.load_steps=0", "joints.load_steps"),
    ],
)
def test_bad_tables_are_refused(override: str, key: str) -> None:
    """Each bad value is a SceneError naming its key, before any mesh."""
    with pytest.raises(SceneError, match=re.escape(key)):
        load_scene_collective(MPI.COMM_SELF, JOBS / "jaeger_joint_3d_rgnq.toml", (override,))


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("beta", [45.0, 60.0])
def test_two_ranks_agree_with_one(beta: float) -> None:
    """RGNQ's Jaeger prism: the reactions of every step on 2 ranks within 1e-10 of 1 rank."""
    overrides = (
        f"geometry.parameters.beta={beta}",
        "geometry.parameters.h=0.5",
        "joints.load_steps=4",
    )
    scene = JOBS / "jaeger_joint_3d_rgnq.toml"
    comm = MPI.COMM_WORLD
    many = _solve(scene, *overrides, comm=comm)
    one = _solve(scene, *overrides, comm=MPI.COMM_SELF) if comm.rank == 0 else None
    one = comm.bcast(one, root=0)
    a = np.array([_top(one, k) for k in range(4)])
    b = np.array([_top(many, k) for k in range(4)])
    assert np.max(np.abs(a - b)) <= 1e-10 * np.max(np.abs(a))
    assert many["joints"]["slipping"] == one["joints"]["slipping"]
