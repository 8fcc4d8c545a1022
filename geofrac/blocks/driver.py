"""Run a ``method = "blocks"`` scene: mesh, blocks, checks, output (collective).

Data flow: scene -> gmsh on rank 0 (the scene's geometry, or the terrain builder of Edo
(2016), §5.4) -> distributed DOLFINx mesh -> each rank builds the blocks of its vertices
(:func:`~geofrac.blocks.distributed.build_blocks`) -> rank 0 adds the immobile block ->
quality checks -> VTU, block file, histogram, ``summary.json``.

The validator runs on each rank's own blocks; the other checks and the single-file
outputs need the whole set, which is gathered to rank 0.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from geofrac.blocks.distributed import build_blocks, gather_blocks, owned_measure
from geofrac.blocks.model import Blocks
from geofrac.errors import RunError
from geofrac.io.checkpoint import RunControl
from geofrac.log import echo
from geofrac.model.scene import Geometry, Scene
from geofrac.timing import Timings

__all__ = ["BLOCKS", "OUTPUT_FILES", "BlocksMethod", "build"]

#: Files a block run writes in its output directory (removed first; summary last).
OUTPUT_FILES = (
    "blocks.vtu",
    "blocks.txt",
    "volume_histogram.png",
    "volume_histogram.csv",
    "section.png",
    "summary.json",
)


def _geometry(scene: Scene) -> Geometry:
    spec = scene.blocks
    assert spec is not None
    if spec.source == "geometry":
        assert scene.geometry is not None
        return scene.geometry
    from geofrac.meshing.terrain import TerrainBuilder, TerrainSpec

    groups = {"layer": 3, "top": 2, "slip": 2, "side": 2}
    assert spec.terrain is not None  # the loader sets it with source = "terrain"
    return Geometry(None, {}, None, 3, groups, TerrainBuilder(TerrainSpec(**spec.terrain)))


def _wall(comm: MPI.Comm, start: float) -> float:
    """Wall time since ``start`` of a collective step (its slowest rank)."""
    return comm.allreduce(time.perf_counter() - start, op=MPI.MAX)


def build(
    scene: Scene, comm: MPI.Comm, timings: Timings, *, verbose: bool = True
) -> tuple[Blocks, dict[str, Any]]:
    """Mesh and build the blocks of this rank (rank 0 also holds the immobile block).

    Returns:
        The blocks and a JSON-ready record: ``time_mesh_s``, ``time_blocks_s`` (wall,
        slowest rank), ``domain_volume``, ``mesh`` (the builder's report and counts).
    """
    from geofrac.meshing.distribute import build_mesh

    spec = scene.blocks
    assert spec is not None
    geometry = _geometry(scene)
    comm.Barrier()
    start = time.perf_counter()
    with timings.phase("mesh"):
        tagged = build_mesh(geometry, comm, verbose=False)
    time_mesh = _wall(comm, start)
    mesh = tagged.mesh
    num_vertices = mesh.topology.index_map(0).size_global
    num_cells = mesh.topology.index_map(mesh.topology.dim).size_global
    echo(comm, f"blocks: mesh of {num_cells} cells, {num_vertices} vertices in {time_mesh:.2f} s")
    comm.Barrier()
    start = time.perf_counter()
    with timings.phase("blocks"):
        try:  # the builder's errors come after its last collective: agree, then raise
            blocks = build_blocks(
                mesh, spec.inner_point, spec.radius, convex=spec.convex, seed=spec.seed
            )
            message = None
        except ValueError as exc:
            message = str(exc)
        message = next((m for m in comm.allgather(message) if m), None)
        if message is not None:
            raise RunError(f"cannot build blocks of this mesh: {message}")
    time_blocks = _wall(comm, start)
    domain = comm.allreduce(owned_measure(mesh), op=MPI.SUM)
    record: dict[str, Any] = {
        "time_mesh_s": time_mesh,
        "time_blocks_s": time_blocks,
        "mesh": {"cells": num_cells, "vertices": num_vertices, **(tagged.report or {})},
    }
    if spec.immobile:
        from geofrac.blocks.immobile import surface_block
        from geofrac.blocks.model import join
        from geofrac.meshing.terrain import immobile_volume

        points, triangles = tagged.fractures  # the builder's payload: the surface patch
        domain += immobile_volume(points, triangles)
        if comm.rank == 0:
            blocks = join(blocks, surface_block(points, triangles))
    record["domain_volume"] = domain
    echo(
        comm,
        f"blocks: {comm.allreduce(blocks.num_blocks)} blocks in {time_blocks:.2f} s "
        f"({num_vertices / max(time_blocks, 1e-12):.3g} blocks/s)",
    )
    return blocks, record


class BlocksMethod:
    """The blocks method of the run pipeline (:class:`geofrac.pipeline.Method`).

    A block run has no loop to checkpoint, so ``--resume`` finds nothing to continue.
    """

    name = "blocks"
    output_files = OUTPUT_FILES

    def head(self, scene: Scene) -> dict[str, Any]:
        """The summary head says ``method = "blocks"``."""
        return {"method": "blocks"}

    def run(
        self, scene: Scene, comm: MPI.Comm, timings: Timings, *, verbose: bool, control: RunControl
    ) -> dict[str, Any]:
        """Mesh, blocks, checks, files; the summary entries."""
        blocks, record = build(scene, comm, timings, verbose=verbose)
        with timings.phase("warm-up"):  # compiled checks: numba's compilation or cache load
            from geofrac.blocks.kernels import warm_up

            def compiled(kernel: str, seconds: float) -> None:  # only what takes a while
                if verbose and seconds > 0.5:
                    echo(
                        None,
                        f"checks: compiled {kernel} in {seconds:.1f} s (cached for later runs)",
                    )

            start = time.perf_counter()
            if comm.rank == 0:  # compiles into the disk cache once, the others load it
                warm_up(compiled)
            comm.Barrier()
            if comm.rank != 0:
                warm_up()
            seconds = _wall(comm, start)
            if verbose:
                echo(comm, f"checks: compiled kernels ready in {seconds:.1f} s (warm-up)")
        with timings.phase("checks"):
            validator = _validate(scene, blocks, comm)
            progress = _check_progress(blocks, comm, verbose)
            checked = _block_checks(blocks, comm, progress)
            whole = gather_blocks(blocks, comm)
            del blocks
            record["quality"] = _checks(
                whole, record["domain_volume"], validator, checked, comm, progress
            )
        with timings.phase("output"):
            if comm.rank == 0:
                assert whole is not None and checked is not None
                _write(scene, whole, checked["volume"], verbose)
        return {"results": record}

    def report(self, summary: dict[str, Any]) -> list[str]:
        """Nothing before the result block."""
        return []

    def result(self, scene: Scene, summary: dict[str, Any]) -> list[str]:
        """Count and volumes of the blocks, their sum against the domain's, the checks."""
        from geofrac.headline import quantity, versus

        q = summary["results"]["quality"]
        what = "area" if q["dim"] == 2 else "volume"  # a 2D block's volume is its area
        v, unit = q["volume"], scene.units.of(what)
        checked = q["validator"]["checked"] if q["validator"] else 0
        return [
            f"blocks: {q['count']}, {what} min {quantity(v['min'])} mean {quantity(v['mean'])} "
            f"max {quantity(v['max'], unit)}",
            f"{what} check: the blocks sum to {quantity(q['total_volume'], unit, 10)}, the "
            f"domain {quantity(q['domain_volume'], unit, 10)} "
            f"({versus(q['total_volume'], q['domain_volume'], unit)})",
            f"checks: {q['invalid_blocks']} invalid, faces paired ({q['pairing']['matched']} "
            f"matched), validator on {checked} block(s)",
        ]


#: The blocks method (``method = "blocks"``).
BLOCKS = BlocksMethod()


def _validate(scene: Scene, blocks: Blocks, comm: MPI.Comm) -> dict[str, Any] | None:
    """Run pyvista's cell validator on each rank's blocks, merged on rank 0 (None elsewhere)."""
    from geofrac.blocks import quality

    spec = scene.blocks
    assert spec is not None
    if spec.validate == "none":
        return None
    total = comm.allreduce(blocks.num_blocks)
    sample = None
    if isinstance(spec.validate, int) and spec.validate < total:  # this rank's share
        sample = max(1, round(spec.validate * blocks.num_blocks / total))
    from geofrac.log import Progress

    ticker: Progress | None = None

    def progress(done: int, chunks: int) -> None:  # rank 0's share, printed by rank 0
        nonlocal ticker
        ticker = ticker or Progress(comm, chunks, "validator (rank 0)", unit="chunks")
        if done == 0:  # the clock starts
            return
        checking = blocks.num_blocks if sample is None else sample
        ticker.step(f"{min(done * quality.VALIDATOR_CHUNK, checking)} of {checking} blocks")

    mine = quality.validate_cells(blocks, sample=sample, seed=spec.seed, progress=progress)
    reports = comm.gather(mine, root=0)
    return None if reports is None else _merge_validator(reports)


def _check_progress(blocks: Blocks, comm: MPI.Comm, verbose: bool) -> Callable[[str], None] | None:
    """Rank 0's progress through the quality checks, from 10^4 blocks (collective)."""
    from geofrac.blocks.quality import SUMMARY_PHASES
    from geofrac.log import Progress

    # each check takes up to a second or two on 10^5 blocks
    if not verbose or comm.allreduce(blocks.num_blocks) < 10_000:
        return None
    return Progress(comm, len(SUMMARY_PHASES), "checks (rank 0)", unit="checks").step


def _block_checks(
    blocks: Blocks, comm: MPI.Comm, progress: Callable[[str], None] | None = None
) -> dict[str, np.ndarray] | None:
    """Each rank checks its own blocks; the results of all, in rank order, on rank 0.

    Rank order is the order in which ``gather_blocks`` joins the blocks.
    """
    from geofrac.blocks import quality

    mine = quality.block_checks(blocks, progress)
    parts = comm.gather(mine, root=0)
    if parts is None:
        return None
    return {key: np.concatenate([p[key] for p in parts]) for key in mine}


def _checks(
    whole: Blocks | None,
    domain: float,
    validator: dict[str, Any] | None,
    checked: dict[str, np.ndarray] | None,
    comm: MPI.Comm,
    progress: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """The quality report of the whole set (computed on rank 0, returned on every rank).

    ``checked``: the ``block_checks`` of the whole set on rank 0 (None elsewhere).

    Raises:
        RunError: on every rank, when a check fails (the report is in the message).
    """
    from geofrac.blocks import quality

    report: dict[str, Any] | None = None
    if comm.rank == 0:
        assert whole is not None
        report = quality.summarize(
            whole,
            domain,
            validate=False,
            on_boundary=_everywhere,
            stats_of=whole.kind == 0,  # statistics of the moving blocks
            progress=progress,
            checked=checked,
        )
        report["validator"] = validator
        if validator is not None:
            report["invalid_blocks"] += validator["failed"]
    agreed: dict[str, Any] = comm.bcast(report, root=0)
    problems = _problems(agreed)
    if problems:
        raise RunError("block quality checks failed: " + "; ".join(problems))
    return agreed


def _everywhere(points: np.ndarray) -> np.ndarray:
    """Every unmatched face may be boundary (non-box domains: the closure test decides)."""
    return np.ones(len(points), dtype=bool)


def _merge_validator(reports: list[dict[str, Any]]) -> dict[str, Any]:
    merged: dict[str, Any] = {}
    for r in reports:
        for key, value in r.items():
            if key == "states":
                states = merged.setdefault("states", {})
                for name, count in value.items():
                    states[name] = states.get(name, 0) + count
            elif key == "failed_blocks":
                continue
            elif isinstance(value, int | float) and not isinstance(value, bool):
                merged[key] = merged.get(key, 0) + value
    return merged


def _problems(report: dict[str, Any]) -> list[str]:
    """What failed, in words."""
    problems = []
    if abs(report["volume_rel_error"]) > 1e-12:
        problems.append(
            f"block volumes sum to {report['total_volume']:.15g}, the domain's is "
            f"{report['domain_volume']:.15g} (relative {report['volume_rel_error']:.2e})"
        )
    if report["invalid_blocks"]:
        problems.append(
            f"{report['invalid_blocks']} invalid block(s): {report['not_closed']} not closed, "
            f"{report['wrong_euler']} with a wrong Euler characteristic, "
            f"{report['non_positive_volume']} of non-positive volume"
            + (
                f", {report['validator']['failed']} failing the validator"
                if report["validator"]
                else ""
            )
        )
    if not report["pairing"]["ok"]:
        problems.append(f"faces do not pair up: {report['pairing']}")
    return problems


def _write(scene: Scene, whole: Blocks, volumes: np.ndarray, verbose: bool = True) -> None:
    """The VTU, the block file, the histogram and the section of the whole set (rank 0).

    ``volumes``: the blocks' volumes from the checks, shape=(num_blocks,).
    """
    from geofrac.blocks import output as writers

    assert scene.blocks is not None
    out = scene.output.dir
    fields = scene.output.fields

    def written(path: Path, t0: float) -> None:
        if verbose:
            size = path.stat().st_size / 1e6
            echo(None, f"output: {path.name} ({size:.1f} MB) in {time.perf_counter() - t0:.1f} s")

    if "vtu" in fields:
        t0 = time.perf_counter()
        path = writers.write_vtu(
            out / "blocks.vtu", whole, {"volume": volumes, "id": whole.ids, "kind": whole.kind}
        )
        written(path, t0)
    if "block_file" in fields:
        t0 = time.perf_counter()
        written(writers.write_block_file(out / "blocks.txt", whole), t0)
    if "histogram" in fields:
        moving = whole.kind == 0
        writers.write_histogram(
            out / "volume_histogram.png",
            out / "volume_histogram.csv",
            volumes[moving],
            bins=scene.blocks.histogram_bins,
            unit=scene.units.of("volume" if whole.dim == 3 else "area"),
            name=scene.name,
        )
    if "section" in fields:
        t0 = time.perf_counter()
        from geofrac.io.pictures import save

        save(
            writers.section_figure(whole, volumes, name=scene.name, units=scene.units),
            out / "section.png",
        )
        written(out / "section.png", t0)
