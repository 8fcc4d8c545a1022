"""``geofrac bench cantilever``: accuracy against cost on the Timoshenko cantilever.

Two set-ups of Edo (2016) (``--setup``):

- ``2.4.1`` (Fig. 2.7-2.8): ``jobs/cantilever.toml``, L = 10, D = 1, E = 100; meshes
  ny × nx = 4×40 … 11×110 (``--meshes`` are the depths ny, nx = 10 ny). Edo (2016):
  R = 2.0 for CST, 2.1 for RGNT.
- ``3.4.1`` (Fig. 3.9-3.11): ``jobs/cantilever_efmm.toml``, L = 8, d = 2, E = 1000;
  meshes nx × ny = 8×2 … 96×24 (``--meshes`` are the depths ny, nx = 4 ny). Edo (2016): EFMM
  6.20e-2 → 9.41e-5 (R = 2.9) in displacement, R = 1.9 in energy; CST R = 2.0 and 0.9.

The default is ``3.4.1`` when ``efmm`` is among ``--elements`` (the chapter that
introduces it) and ``2.4.1`` otherwise. The bench reports nodes, DOFs, the displacement
L2 error (Edo (2016), eq. 2.22/3.30a), the energy error (eq. 3.30b; for EFMM with its patch
stresses) and the assemble/solve wall times, fits the rate R against √nodes, states the
cost of a target relative error and the error reached in equal time per element, and
writes ``cantilever.json`` and ``cantilever.png`` (see :mod:`geofrac.bench.study`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import number_list

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["SETUPS", "THESIS_MESHES", "add_arguments", "int_list", "run"]

_JOBS = Path(__file__).resolve().parents[2] / "jobs"

#: Set-ups of Edo (2016): section -> (scene, default depths ny, nx / ny, its results).
SETUPS: dict[str, tuple[Path, tuple[int, ...], int, str]] = {
    "2.4.1": (
        _JOBS / "cantilever.toml",
        (4, 5, 6, 7, 8, 9, 10, 11),
        10,
        "Fig. 2.8: R = 2.0 (CST), R = 2.1 (RGNT) in the displacement norm",
    ),
    "3.4.1": (
        _JOBS / "cantilever_efmm.toml",
        tuple(range(2, 25, 2)),
        4,
        "Fig. 3.10-3.11: EFMM ||E||_u 6.20e-2 (8x2) to 9.41e-5 (96x24), R = 2.9; ||E||_e "
        "2.61e-1 to 7.70e-3, R = 1.9; CST ||E||_u 2.29e-1 to 2.95e-3, R = 2.0; ||E||_e "
        "1.94e-1 to 2.45e-2, R = 0.9",
    ),
}

#: Meshes of Edo (2016), §2.4.1: ny (depth) values; nx = 10 ny.
THESIS_MESHES = SETUPS["2.4.1"][1]


#: Positive integers from a comma-separated list (an argparse type).
int_list = number_list(int, lambda v: v >= 1, "positive")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    from geofrac.bench.study import add_common_arguments

    add_common_arguments(p, "cantilever", "cst,p2", default_scene=None)
    p.add_argument(
        "--setup",
        choices=tuple(SETUPS),
        help="section of Edo (2016) whose beam and meshes to use (default: 3.4.1 when efmm "
        "is among --elements, else 2.4.1)",
    )
    p.add_argument(
        "--meshes",
        type=int_list,
        help="comma-separated depths ny (default: the set-up's meshes in Edo (2016); "
        "2.4.1: 4,...,11 with nx = 10 ny; 3.4.1: 2,4,...,24 with nx = 4 ny)",
    )


def run(args: argparse.Namespace, comm: MPI.Comm) -> dict[str, Any]:
    """Run the study; return the JSON report (identical on every rank)."""
    from geofrac.bench.study import Case, parse_elements, run_study
    from geofrac.log import echo

    elements = parse_elements(args.elements, 2)
    setup = args.setup or ("3.4.1" if "efmm" in elements else "2.4.1")
    scene, meshes, aspect, reference = SETUPS[setup]
    if args.scene is None:
        args.scene = scene
    depths = args.meshes or list(meshes)
    echo(comm, f"bench cantilever: set-up of Edo (2016), §{setup}, scene {args.scene}")
    cases = [
        Case(
            element,
            f"{aspect * ny}x{ny}" if setup == "3.4.1" else f"{ny}x{aspect * ny}",
            (
                f"discretization.element={element}",
                f"geometry.parameters.nx={aspect * ny}",
                f"geometry.parameters.ny={ny}",
            ),
        )
        for element in elements
        for ny in depths
    ]
    return run_study(
        args,
        comm,
        "cantilever",
        title=f"Timoshenko cantilever (Edo (2016), §{setup}): accuracy vs cost",
        cases=cases,
        dim=2,
        extra={"setup": setup, "thesis_reference": reference},
    )
