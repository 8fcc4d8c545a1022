"""``geofrac bench mms3d``: accuracy against cost on a manufactured 3D solution.

The scene ``jobs/mms3d.toml`` imposes the smooth quartic displacement of
:class:`geofrac.analytic.ManufacturedBox` on the boundary of the unit cube and loads it
with the matching body force; each element is solved on structured tetrahedral meshes
of n × n × n cubes (6 tets each) and the study reports the displacement L2 and energy
errors against DOFs and wall time, the rates against h ∝ nodes^(-1/3), and the cost of
a target relative error (see :mod:`geofrac.bench.study`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mpi4py import MPI

__all__ = ["DEFAULT_MESHES", "add_arguments", "run"]

#: Cubes per side of the default refinements.
DEFAULT_MESHES = (2, 4, 6, 8, 12)
_DEFAULT_SCENE = Path(__file__).resolve().parents[2] / "jobs" / "mms3d.toml"


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    from geofrac.bench.cantilever import int_list
    from geofrac.bench.study import add_common_arguments

    add_common_arguments(p, "mms3d", "p1,p2,rgnq", default_scene=_DEFAULT_SCENE)
    p.add_argument(
        "--meshes",
        type=int_list,
        default=list(DEFAULT_MESHES),
        help=f"comma-separated cubes per side n (default: {','.join(map(str, DEFAULT_MESHES))})",
    )


def run(args: argparse.Namespace, comm: MPI.Comm) -> dict[str, Any]:
    """Run the study; return the JSON report (identical on every rank)."""
    from geofrac.bench.study import Case, parse_elements, run_study

    cases = [
        Case(
            element,
            f"{n}x{n}x{n}",
            (f"discretization.element={element}", f"geometry.parameters.n={n}"),
        )
        for element in parse_elements(args.elements, 3)
        for n in args.meshes
    ]
    return run_study(
        args,
        comm,
        "mms3d",
        title="Manufactured 3D displacement on the unit cube: accuracy vs cost",
        cases=cases,
        dim=3,
    )
