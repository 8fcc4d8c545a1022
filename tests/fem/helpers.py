"""Helpers shared by the finite element tests."""

import json
from pathlib import Path

import h5py
import numpy as np
from mpi4py import MPI

from geofrac.fem.solution import Solution
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS


def solve_job(name: str, *overrides: str, comm: MPI.Comm = MPI.COMM_WORLD) -> Solution:
    """Solve ``jobs/<name>.toml`` with overrides; the caller destroys the problem."""
    scene = load_scene_collective(comm, JOBS / f"{name}.toml", overrides)
    return solve_scene(scene, comm, verbose=False)


def errors_and_tip(solution: Solution) -> tuple[dict[str, float], float, float]:
    """(error norms, computed tip deflection, exact tip deflection)."""
    r = solution.results
    return r["errors"], r["probes"]["tip"][1], r["exact_probes"]["tip"][1]


def h5_datasets(h5: Path) -> dict[str, np.ndarray]:
    """Every dataset of an HDF5 file by its path (for comparing two runs' results.h5)."""
    found: dict[str, np.ndarray] = {}
    with h5py.File(h5, "r") as f:
        f.visititems(
            lambda n, o: found.__setitem__(n, o[()]) if isinstance(o, h5py.Dataset) else None
        )
    return found


def check_interrupted(out: Path, at: int) -> None:
    """A run stopped at poll ``at``: its status says so, its checkpoint is ``at``, no summary."""
    status = json.loads((out / "incomplete" / "summary.json").read_text())
    assert status["status"] == "interrupted"
    assert status["interrupted"]["checkpoint"].endswith(f"ckpt-{at:09d}")
    assert not (out / "summary.json").exists()
