"""Helpers shared by the finite element tests."""

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
