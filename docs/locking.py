"""Measure where each element locks volumetrically as ν → 0.5 (docs/stability.md, "Locking").

Run from the repository root: ``PYTHONPATH=$PWD .venv/bin/python docs/locking.py``
(1 rank, about three minutes). Every registered 2D element solves two plane-strain
specimens for the Poisson's ratios ``NUS``, everything else fixed:

- the cantilever, jobs/cantilever.toml (Timoshenko's closed form, E = 100, ``--nx`` x
  ``--ny`` = 80 x 8 squares split in two): the relative L2 displacement error;
- Cook's membrane, jobs/cook_membrane.toml (Cook 1974: the 48 x 44/16 tapered panel,
  clamped at x = 0, total shear 100 on x = 48, E = 250, ``--n`` x ``--n`` = 16 x 16
  quadrilaterals split in two): the relative error of the tip deflection u_y(48, 60)
  against P3 on the ``--n-ref`` (64) mesh at the same ν (no closed form; the reference's
  own error, P3 at 64 against P3 at 32, is printed too).

An element is locked on a specimen at ν when its error there exceeds both ``--factor``
(10) times its ν = 0.3 error and ``--floor`` (0.05, 5 %). The floor keeps the growth
of a tiny error (P3, GNT on the cantilever: 1e-10 and 2e-7) from counting as locking;
the factor keeps an element that is merely coarse on a specimen (CST on Cook's membrane
at ν = 0.3) from counting. Its threshold (``ElementSpec.locking_nu``) is the smallest ν of
``NUS`` at which it is locked on either specimen, "-" when on neither (the element does
not lock down to ν = 0.49999). ``--elements`` restricts the set (comma-separated),
``--json F`` writes the table.

3D is not measured: the only 3D closed form, jobs/mms3d.toml, keeps its quartic field
(div u ≠ 0) as ν → 0.5, so its error cannot show locking (linear tets: 1.03 times the
ν = 0.3 error at ν = 0.4999).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from mpi4py import MPI

from geofrac import elements
from geofrac.runner import solve_scene
from geofrac.scene import load_scene_collective

JOBS = Path(__file__).resolve().parent.parent / "jobs"
NUS = (0.3, 0.45, 0.49, 0.495, 0.499, 0.4999, 0.49999)
__all__ = ["NUS", "cantilever_error", "cook_tip", "locked_from", "main"]


def _solve(job: str, overrides: list[str]) -> dict:
    scene = load_scene_collective(MPI.COMM_SELF, JOBS / f"{job}.toml", overrides)
    solution = solve_scene(scene, MPI.COMM_SELF, verbose=False)
    solution.problem.destroy()
    return solution.results


def cantilever_error(name: str, nu: float, nx: int, ny: int) -> float:
    """Relative L2 displacement error of the plane-strain cantilever."""
    overrides = [
        "material.plane=strain",
        f"geometry.parameters.nx={nx}",
        f"geometry.parameters.ny={ny}",
        f"discretization.element={name}",
        f"material.nu={nu}",
        "output.probes={}",
    ]
    return float(_solve("cantilever", overrides)["errors"]["u_relative"])


def cook_tip(name: str, nu: float, n: int) -> float:
    """Tip deflection u_y(48, 60) of Cook's membrane in plane strain on the n x n mesh."""
    overrides = [
        f"geometry.parameters.n={n}",
        f"discretization.element={name}",
        f"material.nu={nu}",
    ]
    return float(_solve("cook_membrane", overrides)["probes"]["tip"][1])


def locked_from(errors: dict[float, float], factor: float, floor: float) -> float | None:
    """Smallest ν whose |error| exceeds both ``factor`` |error(0.3)| and ``floor``."""
    base = abs(errors[NUS[0]])
    locked = [nu for nu in NUS if abs(errors[nu]) > max(factor * base, floor)]
    return locked[0] if locked else None


def main() -> None:
    """Print the tables (and write ``--json``)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--elements", default=",".join(elements.available()))
    parser.add_argument("--nx", type=int, default=80)
    parser.add_argument("--ny", type=int, default=8)
    parser.add_argument("--n", type=int, default=16)
    parser.add_argument("--n-ref", type=int, default=64)
    parser.add_argument("--factor", type=float, default=10.0)
    parser.add_argument("--floor", type=float, default=0.05)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    start = time.perf_counter()
    reference = {nu: cook_tip("p3", nu, args.n_ref) for nu in NUS}
    check = {nu: cook_tip("p3", nu, args.n_ref // 2) for nu in NUS}
    print("Cook reference u_y(48, 60), P3 on", f"{args.n_ref}x{args.n_ref}:")
    for nu in NUS:
        drift = check[nu] / reference[nu] - 1
        print(f"  nu={nu:<8g} {reference[nu]:.6f}  (P3 at n/2: {drift:+.1e})")
    rows = []
    for name in args.elements.split(","):
        if 2 not in elements.get(name).dims:
            continue
        beam = {nu: cantilever_error(name, nu, args.nx, args.ny) for nu in NUS}
        cook = {nu: cook_tip(name, nu, args.n) / reference[nu] - 1.0 for nu in NUS}
        found = [locked_from(e, args.factor, args.floor) for e in (beam, cook)]
        threshold = min((t for t in found if t is not None), default=None)
        rows.append(
            {
                "element": name,
                "cantilever": {str(k): v for k, v in beam.items()},
                "cook": {str(k): v for k, v in cook.items()},
                "locked_cantilever": found[0],
                "locked_cook": found[1],
                "threshold": threshold,
            }
        )
        print(f"{name:5s} cantilever " + " ".join(f"{beam[nu]:9.2e}" for nu in NUS), found[0])
        print(f"{'':5s} cook       " + " ".join(f"{cook[nu]:+9.1%}" for nu in NUS), found[1])
        print(f"{'':5s} threshold: {threshold if threshold is not None else '-'}", flush=True)
    print("nu:", " ".join(f"{nu:g}" for nu in NUS))
    print(f"wall time {time.perf_counter() - start:.0f} s")
    if args.json:
        args.json.write_text(json.dumps({"reference": reference, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
