"""``geofrac bench blocks``: what 3D block models cost (Edo (2016), chapter 5), against Voronoi.

For each target count in ``--blocks`` (default 10k, 100k, 1M) a cube is meshed with gmsh
(HXT, tetrahedra of one size, on rank 0) to about that many vertices, distributed over
the ranks, and turned into blocks, one per vertex
(:func:`geofrac.blocks.distributed.build_blocks`). Reported separately: the wall time of
meshing (gmsh and the distribution of the mesh) and of block construction (slowest
rank), blocks per second, and each rank's peak memory. Beside it, in the same run, the
reference: a Voronoi tessellation of the same vertices in a periodic box half a
vertex spacing larger than the cube on every side, by freud (voro++,
``freud.locality.Voronoi``, as many threads as ranks), on rank 0.

Up to ``--check-max`` blocks (default 200,000) the set is gathered to rank 0 and
checked (:func:`geofrac.blocks.quality.summarize`: closure, Euler characteristic, face
pairing and the volume sum; the cell validator on ``--validate`` blocks, default 2000);
above it, ``volume_rel_error`` and ``invalid_blocks`` are None.

Prints a table; ``--json F`` writes records with ``dim``, ``blocks``, ``ranks``,
``time_mesh_s``, ``time_blocks_s``, ``blocks_per_s``, ``reference_blocks_per_s``,
``volume_rel_error``, ``invalid_blocks``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from geofrac.bench.args import number_list
from geofrac.timing import peak_rss_mb

if TYPE_CHECKING:
    import numpy as np
    from dolfinx.mesh import Mesh
    from mpi4py import MPI

    from geofrac.blocks.model import Blocks

__all__ = ["COLUMNS", "add_arguments", "run"]

#: (key, header, format) of the printed table.
COLUMNS = (
    ("blocks", "blocks", "d"),
    ("ranks", "ranks", "d"),
    ("time_mesh_s", "mesh (s)", ".2f"),
    ("time_blocks_s", "blocks (s)", ".2f"),
    ("blocks_per_s", "blocks/s", ".3g"),
    ("reference_seconds", "Voronoi (s)", ".2f"),
    ("reference_blocks_per_s", "Voronoi cells/s", ".3g"),
    ("peak_memory_mb", "peak MB/rank", ".0f"),
    ("volume_rel_error", "volume error", ".1e"),
    ("invalid_blocks", "invalid", "d"),
)
#: Vertices per unit volume of a gmsh HXT mesh of size h, times h³ (measured on the unit
#: cube at 1e5 vertices: 0.70-0.72).
_DENSITY = 0.72


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Options of this bench."""
    p.add_argument(
        "--blocks",
        type=number_list(int, lambda n: n >= 100, "at least 100"),
        default=[10_000, 100_000, 1_000_000],
        help="comma-separated target block counts (default 10000,100000,1000000)",
    )
    p.add_argument(
        "--check-max",
        type=int,
        default=200_000,
        help="check block sets up to this size (gathered to rank 0; default 200000)",
    )
    p.add_argument(
        "--validate", type=int, default=2000, help="blocks sampled for the cell validator (2000)"
    )
    p.add_argument("--json", type=Path, default=None, help="write the records to this file")


class _CubeBuilder:
    """A unit cube meshed by gmsh (HXT) with tetrahedra of size h."""

    name = "cube"

    def __init__(self, h: float) -> None:
        self.h = h

    def build(self, gmsh: ModuleType) -> tuple[dict[str, Any], None]:
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [1], name="domain")
        gmsh.option.setNumber("Mesh.MeshSizeMax", self.h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", self.h)
        gmsh.option.setNumber("Mesh.Algorithm3D", 10)
        gmsh.model.mesh.generate(3)
        return {}, None


def _voronoi(points: np.ndarray, threads: int) -> float:
    """Seconds freud takes for the Voronoi cells (volumes and polytopes) of ``points``."""
    import freud

    freud.parallel.set_num_threads(threads)
    # a periodic box a little larger than the cube: points on opposite faces of the cube
    # would otherwise be periodic images of each other (voro++ aborts on duplicates)
    margin = 0.5 * len(points) ** (-1 / 3)
    box = freud.box.Box.cube(1.0 + 2 * margin)
    centred = points - 0.5  # freud's box is centred on the origin
    voronoi = freud.locality.Voronoi()
    start = time.perf_counter()
    voronoi.compute((box, centred))
    _ = voronoi.volumes, voronoi.polytopes
    return time.perf_counter() - start


def run(args: argparse.Namespace, comm: MPI.Comm) -> dict[str, Any]:
    """Build the block sets; print the table (rank 0); return the JSON report."""
    import dolfinx_solver  # noqa: F401

    import numpy as np
    from mpi4py import MPI

    from geofrac.bench.report import format_table
    from geofrac.blocks.distributed import build_blocks
    from geofrac.io.summary import versions, write_json
    from geofrac.log import echo
    from geofrac.meshing.distribute import build_mesh
    from geofrac.model.scene import Geometry

    records = []
    for target in args.blocks:
        h = (_DENSITY / target) ** (1 / 3)
        geometry = Geometry(None, {}, None, 3, {"domain": 3}, _CubeBuilder(h))
        comm.Barrier()
        start = time.perf_counter()
        mesh = build_mesh(geometry, comm).mesh
        time_mesh = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
        comm.Barrier()
        start = time.perf_counter()
        blocks = build_blocks(mesh)
        time_blocks = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
        count = comm.allreduce(blocks.num_blocks)
        peak = comm.allreduce(peak_rss_mb(), op=MPI.MAX)
        seeds = comm.gather(blocks.seeds, root=0)
        record: dict[str, Any] = {
            "dim": 3,
            "target": target,
            "blocks": count,
            "cells": mesh.topology.index_map(3).size_global,
            "ranks": comm.size,
            "time_mesh_s": time_mesh,
            "time_blocks_s": time_blocks,
            "blocks_per_s": count / time_blocks,
            "peak_memory_mb": peak,
            "volume_rel_error": None,
            "invalid_blocks": None,
        }
        if count <= args.check_max:
            record |= _check(blocks, mesh, args.validate, comm)
        del blocks, mesh
        if comm.rank == 0:
            assert seeds is not None  # gathered on rank 0
            seconds = _voronoi(np.concatenate(seeds), comm.size)
            record |= {
                "reference": "freud.locality.Voronoi (voro++), periodic box around the cube",
                "reference_threads": comm.size,
                "reference_seconds": seconds,
                "reference_blocks_per_s": count / seconds,
            }
        record = comm.bcast(record, root=0)
        records.append(record)
        echo(
            comm,
            f"bench blocks: {count} blocks, mesh {time_mesh:.2f} s, blocks {time_blocks:.2f} s "
            f"({record['blocks_per_s']:.3g}/s), Voronoi {record['reference_blocks_per_s']:.3g}/s",
        )
    report = {"bench": "blocks", "versions": versions(), "records": records}
    if comm.rank == 0:
        print(format_table(records, COLUMNS))
        if args.json is not None:
            write_json(args.json, report)
    return report


def _check(blocks: Blocks, mesh: Mesh, validate: int, comm: MPI.Comm) -> dict[str, Any]:
    """Volume error and invalid blocks of the gathered set (collective)."""
    from mpi4py import MPI

    from geofrac.blocks import quality
    from geofrac.blocks.distributed import gather_blocks, owned_measure

    domain = comm.allreduce(owned_measure(mesh), op=MPI.SUM)
    whole = gather_blocks(blocks, comm)
    out = None
    if comm.rank == 0:
        assert whole is not None  # gathered on rank 0
        report = quality.summarize(whole, domain, validate=True, sample=validate)
        bad_pairs = 0 if report["pairing"]["ok"] else report["pairing"]["bad_blocks"]
        out = {
            "volume_rel_error": report["volume_rel_error"],
            "invalid_blocks": report["invalid_blocks"] + bad_pairs,
            "validated": report["validator"]["checked"] if report["validator"] else 0,
        }
    return comm.bcast(out, root=0)
