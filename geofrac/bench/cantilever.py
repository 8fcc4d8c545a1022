"""``geofrac bench cantilever``: accuracy against cost on the Timoshenko cantilever.

For each element and each seed mesh ny × nx (4×40 … 11×110, seed 2.4.1) the scene
``jobs/cantilever.toml`` is solved; the bench reports nodes, DOFs, the displacement
L2 error (seed eq. 2.22), the energy error (seed eq. 3.30b) and the assemble/solve wall
times, fits the rate R against √nodes (seed Fig. 2.8: R = 2.0 for CST, 2.1 for RGNT),
states the cost of a target relative error per element, and writes ``cantilever.json``
and ``cantilever.png`` to the output directory (see :mod:`geofrac.bench.study`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from geofrac.bench.args import number_list

__all__ = ["SEED_MESHES", "add_arguments", "int_list", "run"]

#: Seed meshes: ny (depth) values; nx = 10 ny.
SEED_MESHES = (4, 5, 6, 7, 8, 9, 10, 11)
_DEFAULT_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "cantilever.toml"


#: Positive integers from a comma-separated list (an argparse type).
int_list = number_list(int, lambda v: v >= 1, "positive")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    from geofrac.bench.study import add_common_arguments

    add_common_arguments(p, "cantilever", "cst,p2", _DEFAULT_SCENE)
    p.add_argument(
        "--meshes",
        type=int_list,
        default=list(SEED_MESHES),
        help="comma-separated depths ny; nx = 10 ny (default: the seed's 4,...,11)",
    )


def run(args: argparse.Namespace, comm: Any) -> dict[str, Any]:
    """Run the study; return the JSON report (identical on every rank)."""
    from geofrac.bench.study import Case, parse_elements, run_study

    cases = [
        Case(
            element,
            f"{ny}x{10 * ny}",
            (
                f"discretization.element={element}",
                f"geometry.parameters.nx={10 * ny}",
                f"geometry.parameters.ny={ny}",
            ),
        )
        for element in parse_elements(args.elements, 2)
        for ny in args.meshes
    ]
    return run_study(
        args,
        comm,
        "cantilever",
        "Timoshenko cantilever (seed 2.4.1): accuracy vs cost",
        cases,
        dim=2,
        extra={
            "seed_reference": "Fig. 2.8: R = 2.0 (CST), R = 2.1 (RGNT) in the displacement norm"
        },
    )
