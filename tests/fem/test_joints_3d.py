"""3D joints: split surface groups with Coulomb springs (geofrac/fem/joints.py in 3D).

Closed forms, each on two gmsh 3D algorithms (1 Delaunay, 4 Frontal) and, where cheap, two
mesh sizes:

- a persistent joint set of spacing s and normal stiffness kₙ under a uniaxial stress
  normal to it: 1/E_eff = 1/E + 1/(kₙ s) (Goodman 1976); the stress is uniform and the
  middle-node springs carry it exactly, so the modulus is the closed form to round-off;
- the same prism with one joint pulled apart: the joint opens by the whole displacement
  and carries nothing;
- Jaeger's plane of weakness: the axial stress stays at σ1 = 2c/((1 − μ cot β) sin 2β)
  once the joint slips;
- Sneddon's penny crack (coarse): the opening w(r) = 8(1 − ν²)σ/(πE) sqrt(a² − r²) within
  3 % of w(0) up to r = 0.8a (the refined mesh's whole profile is a validation case).

Every test starts from the stress-free state at rest. The 2-rank tests compare with the
1-rank solve.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

E, NU = 10000.0, 0.25


def _solve(name: str, *overrides: str, comm: MPI.Comm = MPI.COMM_WORLD, out: Path | None = None):
    """Solve jobs/<name>.toml with overrides; the plasticity results (and the solution)."""
    extra = () if out is None else (f"output.dir={out}",)
    scene = load_scene_collective(comm, JOBS / f"{name}.toml", (*overrides, *extra))
    solution = solve_scene(scene, comm, verbose=False, write=out is not None)
    results = solution.results["plasticity"]
    solution.problem.destroy()
    return results


def _bcs(top: float, *, top_pins: bool) -> str:
    """The scenes' ``bc`` list with the top's displacement ``top`` (an override)."""
    pins = ["{group='pin_xy', value=[0.0, 0.0], components=['x', 'y']}"]
    pins.append("{group='pin_y', value=[0.0], components=['y']}")
    if top_pins:
        pins.append("{group='top_xy', value=[0.0, 0.0], components=['x', 'y']}")
        pins.append("{group='top_y', value=[0.0], components=['y']}")
    rows = ["{group='bottom', value=[0.0], components=['z']}", *pins]
    rows.append(f"{{group='top', value=[{top!r}], components=['z']}}")
    return "bc=[" + ", ".join(rows) + "]"


def _top(results: dict, step: int = -1) -> float:
    """The axial reaction on the top (compression positive)."""
    return -float(results["steps"][step]["reactions"]["top"][2])


@pytest.mark.parametrize("algorithm3d", [1, 4])
@pytest.mark.parametrize("h", [0.5, 0.25])
def test_joint_set_compliance_is_the_closed_form(algorithm3d: int, h: float) -> None:
    """Four joints 0.25 apart, kₙ = 4e4: E_eff = 1/(1/E + 1/(kₙ s)) = 5000 to 1e-9."""
    r = _solve(
        "joint_set_3d",
        f"geometry.parameters.h={h}",
        f"geometry.parameters.algorithm3d={algorithm3d}",
    )
    kn, s, d, height = 40000.0, 0.25, 0.001, 1.0
    e_eff = _top(r) / (d / height)  # the prism's section is 1 x 1
    assert e_eff == pytest.approx(1.0 / (1.0 / E + 1.0 / (kn * s)), rel=1e-9)
    joints = r["joints"]
    assert joints["pairs"] > 0 and joints["open"] == 0 and joints["slipping"] == 0
    # without the joints' compliance the prism would carry twice the load: they act
    assert _top(r) < 0.51 * E * d / height


def test_an_open_joint_carries_nothing(tmp_path: Path) -> None:
    """One joint, the top raised by d: the reaction vanishes, the joint opens by d."""
    d = 0.001
    r = _solve(
        "joint_set_3d",
        "geometry.parameters.n=1",
        "geometry.parameters.s=1.0",
        "geometry.parameters.h=0.5",
        _bcs(d, top_pins=True),
        out=tmp_path,
    )
    assert abs(_top(r)) < 1e-9 * E * d  # against the scale of the closed joint's load
    table = np.loadtxt(tmp_path / "joints.csv", delimiter=",", skiprows=1)
    opening, state = table[:, 6], table[:, 11]
    assert np.allclose(opening, d, rtol=1e-9, atol=0)
    assert np.all(state == 2)  # open
    assert (tmp_path / "fracture_faces.vtu").stat().st_size > 0


def jaeger(beta_deg: float, *, c: float = 1.0, mu: float = 0.5) -> float:
    """σ1 at slip on a plane whose normal is at β from the load (Jaeger et al. 2007, §4.7)."""
    b = math.radians(beta_deg)
    return 2.0 * c / ((1.0 - mu / math.tan(b)) * math.sin(2.0 * b))


@pytest.mark.parametrize(("beta", "algorithm3d"), [(45.0, 1), (60.0, 4), (60.0, 1)])
def test_jaeger_plane_of_weakness_in_3d(beta: float, algorithm3d: int) -> None:
    """The axial stress rises elastically, then holds at Jaeger's σ1 while the joint slips."""
    sigma = jaeger(beta)
    slip_d = sigma / E * 2.5  # the elastic shortening of the 2.5 m prism at slip
    r = _solve(
        "jaeger_joint_3d",
        f"geometry.parameters.beta={beta}",
        "geometry.parameters.h=0.5",
        f"geometry.parameters.algorithm3d={algorithm3d}",
        "plasticity.load_steps=4",
        _bcs(-2.1 * slip_d, top_pins=False),
    )
    stresses = [_top(r, k) for k in range(4)]
    assert stresses[0] < 0.9 * sigma  # 0.525 of the slip displacement: sticking
    assert stresses[0] == pytest.approx(0.525 * sigma, rel=0.01)
    for s in stresses[2:]:  # beyond slip: the plateau
        assert s == pytest.approx(sigma, rel=1e-6)
    assert r["joints"]["slipping"] == r["joints"]["pairs"]


def test_jaeger_under_an_in_situ_confining_stress() -> None:
    """σ0 = −p I in place, then the top lowered: the joint slips at Jaeger's confined σ1.

    σ1 − σ3 = 2 (c + μ σ3) / ((1 − μ cot β) sin 2β) with σ3 = p (compression positive;
    Jaeger et al. 2007, §4.7). The joint starts stress-free and closes under σ0 in the
    first step, as a 3DEC model is stepped to equilibrium under its in-situ stress.
    """
    beta, p = 60.0, 1.0
    sigma1 = p + (jaeger(beta) / 1.0) * (1.0 + 0.5 * p)  # 2(c + μ p)/(...) with c = 1
    slip_d = (sigma1 - p) / E * 2.5 * 1.2  # beyond the elastic shortening at slip
    r = _solve(
        "jaeger_joint_3d",
        f"geometry.parameters.beta={beta}",
        "geometry.parameters.h=0.5",
        "plasticity.load_steps=4",
        "initial_stress={kind='constant', stress=[-1.0, -1.0, -1.0, 0.0, 0.0, 0.0], "
        "loaded=['sides']}",
        _bcs(-2.0 * slip_d, top_pins=False),
    )
    stresses = [_top(r, k) for k in range(4)]
    assert stresses[0] < sigma1  # sticking at first
    for s in stresses[2:]:
        assert s == pytest.approx(sigma1, rel=1e-6)


def test_penny_crack_opening_coarse(tmp_path: Path) -> None:
    """At h = 0.1a: w within 3 % of w(0) for r <= 0.8 a (Sneddon 1946); the crack opens only."""
    _solve("penny_crack", "geometry.parameters.h=0.1", out=tmp_path)
    table = np.loadtxt(tmp_path / "joints.csv", delimiter=",", skiprows=1)
    r = np.hypot(table[:, 0], table[:, 1])
    w = table[:, 6]
    e, nu, sigma, a = 1000.0, 0.25, 1.0, 1.0
    w0 = 8.0 * (1.0 - nu**2) * sigma * a / (math.pi * e)
    exact = w0 * np.sqrt(np.clip(1.0 - (r / a) ** 2, 0.0, None))
    inner = r <= 0.8 * a
    assert np.count_nonzero(inner) > 50
    assert np.max(np.abs(w[inner] - exact[inner])) < 0.03 * w0
    assert np.all(table[:, 11] == 2)  # every pair open
    assert np.all(table[:, 3] == 0.0)  # and free of traction


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("name", ["joint_set_3d", "jaeger_joint_3d"])
def test_two_ranks_agree_with_one(name: str) -> None:
    """The reactions and the joints' counts on 2 ranks equal the 1-rank solve's to 1e-10.

    Newton is taken to |F| <= 1e-13 (relative) so that the two solves of Jaeger's slipping
    joint differ by round-off, not by where each stopped.
    """
    comm = MPI.COMM_WORLD
    overrides = (
        "geometry.parameters.h=0.5",
        "plasticity.load_steps=4",
        "solver.options={snes_rtol=1e-13, snes_atol=1e-13}",
    )
    many = _solve(name, *overrides, comm=comm)
    one = None
    if comm.rank == 0:
        one = _solve(name, *overrides, comm=MPI.COMM_SELF)
    one = comm.bcast(one, root=0)
    a = np.array([_top(one, k) for k in range(len(one["steps"]))])
    b = np.array([_top(many, k) for k in range(len(many["steps"]))])
    assert np.max(np.abs(a - b)) <= 1e-10 * np.max(np.abs(a))
    for key in ("pairs", "open", "slipping"):
        assert many["joints"][key] == one["joints"][key]
