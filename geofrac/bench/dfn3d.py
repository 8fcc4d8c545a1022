"""``geofrac bench dfn3d``: what a conforming tetrahedral mesh of a 3D disc network costs.

For each fracture count in ``--fractures`` (default 1,000) a network of discs is drawn in
a cube of side ``--size`` (default 1) by a small local sampler: uniform centres in the
cube, uniformly random normals, radii from the power law p(r) ∝ r^-a truncated to
[``--rmin``, ``--rmax``] (defaults a = 3.5, 0.02, 0.5: 1,000 discs give P32 ≈ 5 per unit
length, a mean radius of 0.034 and a few discs larger than a third of the cube), from a
seeded ``numpy.random.default_rng``. It is cleaned and meshed by
:func:`geofrac.meshing.dfn3d.mesh_discs` in this process, with each algorithm of
``--algorithms`` (default HXT; or Delaunay) on ``--threads`` threads (default 1: one
core).
Rank 0 does the work; other ranks wait.

Prints one row per (count, algorithm): P32, fractures kept and meshed, pieces, nodes,
tetrahedra, the wall time of each phase (clean, build, fragment, surface mesh, volume
mesh, total) and the quality (minimum dihedral angle, maximum aspect ratio R / 3ρ,
minimum fracture triangle angle). ``--json F`` writes the records (the full
:func:`~geofrac.meshing.dfn3d.mesh_discs` reports without the surface map, plus
``p32``, ``seed``, the sampler's parameters and ``time_total_s``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import name_list, number_list

if TYPE_CHECKING:
    import numpy as np
    from mpi4py import MPI

    from geofrac.dfn3d.network import DiscNetwork

__all__ = ["COLUMNS", "add_arguments", "run", "sample_discs"]

#: (key, header, format) of the printed table.
COLUMNS = (
    ("fractures", "fractures", "d"),
    ("algorithm3d", "3D algorithm", "s"),
    ("p32", "P32", ".2f"),
    ("fractures_cleaned", "kept", "d"),
    ("fractures_inside", "meshed", "d"),
    ("pieces", "pieces", "d"),
    ("nodes", "nodes", "d"),
    ("tetrahedra", "tetrahedra", "d"),
    ("time_clean_s", "clean [s]", ".2f"),
    ("time_build_s", "build [s]", ".2f"),
    ("time_fragment_s", "fragment [s]", ".2f"),
    ("time_mesh_surface_s", "surfaces [s]", ".2f"),
    ("time_mesh_volume_s", "volume [s]", ".1f"),
    ("time_total_s", "total [s]", ".1f"),
    ("min_dihedral_deg", "min dihedral", ".2f"),
    ("max_aspect_ratio", "max R/3r", ".3g"),
    ("fracture_min_angle_deg", "min fracture angle", ".2f"),
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--fractures",
        type=number_list(int, lambda n: n >= 1, "positive"),
        default=[1000],
        help="comma-separated fracture counts (default 1000)",
    )
    p.add_argument(
        "--algorithms",
        type=name_list(("delaunay", "hxt"), "3D algorithm"),
        default=["hxt"],
        help="comma-separated gmsh 3D algorithms from delaunay, hxt (default hxt)",
    )
    p.add_argument("--seed", type=int, default=1, help="sampler seed (default 1)")
    p.add_argument("--size", type=float, default=1.0, help="side of the cube (default 1)")
    p.add_argument("--rmin", type=float, default=0.02, help="smallest radius (default 0.02)")
    p.add_argument("--rmax", type=float, default=0.5, help="largest radius (default 0.5)")
    p.add_argument("--exponent", type=float, default=3.5, help="a in p(r) ∝ r^-a (default 3.5)")
    p.add_argument(
        "--mesh-size", type=float, default=0.1, help="element size away from fractures (0.1)"
    )
    p.add_argument(
        "--fracture-mesh-size",
        type=float,
        default=0.02,
        help="element size on the fractures (default 0.02)",
    )
    p.add_argument(
        "--tolerance",
        type=float,
        default=None,
        help="cleaning tolerance (default: fracture mesh size / 4)",
    )
    p.add_argument("--threads", type=int, default=1, help="gmsh threads (default 1: one core)")
    p.add_argument("--json", type=Path, default=None, help="write the records to this file")


def sample_discs(
    count: int,
    rng: np.random.Generator,
    *,
    size: float = 1.0,
    rmin: float,
    rmax: float,
    exponent: float,
) -> DiscNetwork:
    """A bench network: uniform centres in [0, size]³, uniform normals, power-law radii.

    Args:
        count: number of discs.
        rng: the random generator (centres, then normals, then radii are drawn).
        size: side of the cube.
        rmin: smallest radius.
        rmax: largest radius.
        exponent: a in the density p(r) ∝ r^-a on [rmin, rmax] (a != 1).

    Returns:
        one set named ``discs``.
    """
    import numpy as np

    from geofrac.dfn3d.network import DiscNetwork, canonical_normals

    centre = rng.uniform(0.0, size, (count, 3))
    normal = canonical_normals(rng.normal(size=(count, 3)))
    k = 1.0 - exponent
    u = rng.uniform(size=count)
    radius = (rmin**k + u * (rmax**k - rmin**k)) ** (1.0 / k)
    return DiscNetwork(centre, normal, radius, np.zeros(count, dtype=np.int64), ("discs",))


def _case(args: argparse.Namespace, count: int, algorithm: str) -> dict[str, Any]:
    """Sample, clean and mesh one network; the record."""
    import numpy as np

    from geofrac.meshing.dfn3d import mesh_discs
    from geofrac.meshing.geo import gmsh_session

    net = sample_discs(
        count,
        np.random.default_rng(args.seed),
        size=args.size,
        rmin=args.rmin,
        rmax=args.rmax,
        exponent=args.exponent,
    )
    box = np.array([[0.0, 0.0, 0.0], [args.size] * 3])
    start = time.perf_counter()
    with gmsh_session(None, {}) as gmsh:
        report = mesh_discs(
            gmsh,
            net,
            box=box,
            mesh_size=args.mesh_size,
            fracture_mesh_size=args.fracture_mesh_size,
            algorithm3d=algorithm,
            tolerance=args.tolerance,
            threads=args.threads,
        )
    total = time.perf_counter() - start
    report.pop("surface_fracture")
    return {
        **report,
        "p32": float(net.area().sum()) / args.size**3,
        "seed": args.seed,
        "size": args.size,
        "rmin": args.rmin,
        "rmax": args.rmax,
        "exponent": args.exponent,
        "mean_radius": float(net.radius.mean()),
        "time_total_s": total,
    }


def run(args: argparse.Namespace, comm: MPI.Comm) -> dict[str, Any]:
    """Mesh every count with every algorithm; print the table (rank 0); return the report."""
    from geofrac.bench.report import format_table
    from geofrac.io.summary import versions, write_json
    from geofrac.log import echo

    records: list[dict[str, Any]] = []
    if comm.rank == 0:
        for count in args.fractures:
            for algorithm in args.algorithms:
                record = _case(args, count, algorithm)
                records.append(record)
                echo(
                    comm,
                    f"dfn3d {count} fractures, {algorithm}: {record['tetrahedra']} tetrahedra "
                    f"in {record['time_total_s']:.1f} s",
                )
    records = comm.bcast(records, root=0)
    report = {"bench": "dfn3d", "versions": versions(fem=False), "records": records, "rates": {}}
    if comm.rank == 0:
        print(format_table(records, COLUMNS))
        if args.json is not None:
            write_json(args.json, report)
    return report
