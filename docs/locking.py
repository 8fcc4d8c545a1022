"""Measure where each element locks volumetrically as ν → 0.5 (docs/elements.md).

Run from the repository root: ``PYTHONPATH=$PWD .venv/bin/python docs/locking.py``
(1 rank, about two minutes). Every registered 2D element solves jobs/cantilever.toml in
plane strain (Timoshenko's closed form, E = 100, on the ``--nx`` x ``--ny`` mesh, 80 x 8)
for a ladder of Poisson's ratios, everything else fixed. 3D is not measured: the only 3D
closed form, jobs/mms3d.toml, keeps its quartic field (div u ≠ 0) as ν → 0.5, so its
error cannot show locking (linear tets: 1.03 times the ν = 0.3 error at ν = 0.4999).

It prints the relative L2 displacement error per ν (locking makes the displacements far
  too small), its ratio to the ν = 0.3 error, and the
threshold: the smallest ν of the ladder whose error exceeds both ``--factor`` (10) times
the ν = 0.3 error and ``--floor`` (0.01), or "-" when none does (the element does not
lock down to ν = 0.4999). The floor keeps round-off growth of an element that reproduces
the cantilever exactly (P3, GNT: errors 1e-10 and 2e-7) from counting as locking.
``--elements`` restricts the set (comma-separated), ``--json F`` writes the table.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from mpi4py import MPI

from geofrac import elements
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective

JOBS = Path(__file__).resolve().parent.parent / "jobs"
NUS = (0.3, 0.4, 0.45, 0.47, 0.48, 0.49, 0.495, 0.499, 0.4999)


def displacement_error(name: str, nu: float, nx: int, ny: int) -> float:
    """Relative L2 displacement error of element ``name`` at Poisson's ratio ``nu``."""
    overrides = [
        "material.plane=strain",
        f"geometry.parameters.nx={nx}",
        f"geometry.parameters.ny={ny}",
        f"discretization.element={name}",
        f"material.nu={nu}",
        "output.probes={}",
    ]
    scene = load_scene_collective(MPI.COMM_SELF, JOBS / "cantilever.toml", overrides)
    solution = solve_scene(scene, MPI.COMM_SELF, verbose=False)
    error = float(solution.results["errors"]["u_relative"])
    solution.problem.destroy()
    return error


def main() -> None:
    """Print the table (and write ``--json``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", default=",".join(elements.available()))
    parser.add_argument("--nx", type=int, default=80)
    parser.add_argument("--ny", type=int, default=8)
    parser.add_argument("--factor", type=float, default=10.0)
    parser.add_argument("--floor", type=float, default=0.01)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    rows = []
    for name in args.elements.split(","):
        if 2 not in elements.get(name).dims:
            continue
        errors = [displacement_error(name, nu, args.nx, args.ny) for nu in NUS]
        ratios = [e / errors[0] for e in errors]
        locked = [
            nu
            for nu, e in zip(NUS, errors, strict=True)
            if e > max(args.factor * errors[0], args.floor)
        ]
        rows.append(
            {
                "element": name,
                "errors": dict(zip(map(str, NUS), errors, strict=True)),
                "threshold": locked[0] if locked else None,
            }
        )
        cells = " ".join(f"{r:8.3g}" for r in ratios)
        print(
            f"{name:5s} err(0.3)={errors[0]:.3e}  ratio: {cells}  "
            f"threshold: {locked[0] if locked else '-'}",
            flush=True,
        )
    print("nu:", " ".join(f"{nu:8g}" for nu in NUS))
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
