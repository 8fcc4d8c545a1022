"""A load-stepped run with a gravity phase stopped in either phase resumes to the whole run.

As tests/fem/test_plastic_resume.py (its helpers): SIGTERM at a chosen poll, the
checkpoint, ``resume``, and every number of the summary's results and every dataset of
``results.h5`` equal to the uninterrupted run's, bit for bit on one rank. The scene: the
Rankine layer of tests/fem/test_gravity_phase.py (c = 1, φ = 30°: it yields in the
gravity phase) with a pressure of 50 on the footing group in the analysis; 4 gravity
steps and 3 analysis steps: polls after gravity steps 1-3 (checkpoints 1-3) and after
analysis steps 1-2 (checkpoints 5-6: the number counts the converged steps of both
phases, the last gravity step included).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mpi4py import MPI

from tests.conftest import JOBS
from tests.fem.test_gravity_phase import _planar_joint
from tests.fem.test_plastic_resume import (
    _on_root,
    _resumed,
    _same,
    _shared,
    _stopped,
    _whole,
)

LAYER = Path(__file__).parent / "gravity_layer.toml"
SETS = (
    "plasticity.cohesion=1.0",
    "plasticity.gravity_steps=4",
    "plasticity.load_steps=3",
    "output.xdmf=true",
)
PRESSURE = '\n[[load]]\ntype = "pressure"\ngroup = "footing"\nvalue = 50.0\n'


def _scene(directory: Path) -> Path:
    """The layer with the footing pressure (the mesh file's path made absolute)."""
    geo = (JOBS / "../meshes/footing_prandtl.geo").resolve()
    text = LAYER.read_text().replace('"../../meshes/footing_prandtl.geo"', f'"{geo}"')
    path = directory / "layer.toml"
    if MPI.COMM_WORLD.rank == 0:
        path.write_text(text + PRESSURE)
    MPI.COMM_WORLD.barrier()
    return path


@pytest.mark.parametrize(("at", "phase"), [(2, "gravity"), (4, "analysis")])
def test_a_run_stopped_in_either_phase_resumes_to_the_whole_run(tmp_path, monkeypatch, at, phase):
    comm = MPI.COMM_WORLD
    base = _shared(tmp_path, comm)
    job = _scene(base)
    whole = base / "whole"
    counts = _whole(job, SETS, whole, monkeypatch)
    assert counts.polls == 5
    out = base / "stopped"
    k = at if phase == "gravity" else at + 1
    stopping = _stopped(job, SETS, out, monkeypatch, at, checkpoint=k)
    meta = out / "incomplete" / "checkpoint" / f"ckpt-{k:09d}" / "meta.json"
    data = json.loads(meta.read_text())["data"]
    assert data["phase"] == phase
    assert (data["gravity"] is None) == (phase == "gravity")
    again = _resumed(job, SETS, out, monkeypatch)
    comm.barrier()  # rank 0 writes the summary
    if comm.size == 1:
        assert stopping.newton + again.newton == counts.newton  # nothing solved twice
    _on_root(_check, out, whole, rtol=0.0 if comm.size == 1 else 1e-10)


def _check(out: Path, whole: Path, *, rtol: float) -> None:
    """The resumed run equals the whole one (Newton counts too on one rank)."""
    results = _same(out, whole, rtol=rtol, newton=rtol == 0.0)
    plastic = results["plasticity"]
    assert plastic["converged"] and len(plastic["gravity_phase"]["steps"]) == 4
    assert plastic["gravity_phase"]["plastic_points"] > 0


def test_joints_resume_in_the_analysis_with_their_kept_jump(tmp_path, monkeypatch):
    """The planar slide's block (tests/fem/test_gravity_phase.py): stopped in the analysis.

    5 gravity steps, 2 analysis steps: poll 5 is after the first analysis step
    (checkpoint 6). The resumed run equals the whole one: the joints' kept jump is in the
    checkpoint (without it the block would rest on nothing after the resume).
    """
    comm = MPI.COMM_WORLD
    base = _shared(tmp_path, comm)
    job = _planar_joint(base)
    sets = (
        "plasticity.gravity_phase=true",
        "plasticity.gravity_steps=5",
        "plasticity.load_steps=2",
        "output.xdmf=true",
    )
    whole = base / "whole"
    assert _whole(job, sets, whole, monkeypatch).polls == 5
    out = base / "stopped"
    _stopped(job, sets, out, monkeypatch, 5, checkpoint=6)
    _resumed(job, sets, out, monkeypatch)
    comm.barrier()
    _on_root(_check_joints, out, whole)


def _check_joints(out: Path, whole: Path) -> None:
    results = _same(out, whole, rtol=0.0)
    plastic = results["plasticity"]
    assert plastic["converged"] and plastic["joints"]["slipping"] > 0


@pytest.mark.mpi(min_size=2)
def test_a_run_stopped_in_the_analysis_resumes_on_two_ranks(tmp_path, monkeypatch):
    test_a_run_stopped_in_either_phase_resumes_to_the_whole_run(
        tmp_path, monkeypatch, 4, "analysis"
    )
