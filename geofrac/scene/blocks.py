"""Validation of ``method = "blocks"`` scenes: ``[blocks]``, ``[blocks.terrain]``, output.

A block scene builds a block model (Edo (2016), chapter 5) from a mesh: either a ``[geometry]``
(any 2D triangle or 3D tetrahedral gmsh geometry) or the landslide terrain of Edo (2016), §5.4
(``source = "terrain"``, a moving layer of blocks over an immobile part that is one
block). Pure Python: nothing here imports gmsh, DOLFINx or MPI.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

from geofrac.model.errors import SceneError
from geofrac.model.scene import BlocksSpec, Geometry, Output
from geofrac.model.table import Table, output_directory, short

__all__ = ["BLOCKS_KEYS", "BLOCKS_OUTPUT_KEYS", "FEM_ONLY_TABLES", "blocks_output", "blocks_spec"]

#: Keys of ``[blocks]`` (the single source for docs/scenes.md; ``terrain`` is a table).
BLOCKS_KEYS = (
    "source",
    "inner_point",
    "radius",
    "convex",
    "seed",
    "immobile",
    "validate",
    "histogram_bins",
    "terrain",
)
#: Keys of ``[output]`` in a block scene.
BLOCKS_OUTPUT_KEYS = ("dir", "vtu", "block_file", "histogram", "section")
#: Tables of other methods that a block scene must not have.
FEM_ONLY_TABLES = (
    "material",
    "discretization",
    "exact",
    "bc",
    "load",
    "solver",
    "mpm",
    "initial_stress",
    "stages",
)
#: ``[blocks.terrain]`` keys that are lists of numbers, with their lengths.
_TERRAIN_VECTORS = {"extent": 4, "footprint_centre": 2, "footprint_axes": 2}
#: Most gmsh threads ``blocks.terrain.threads`` may ask for (0 and negative crash OpenMP).
MAX_THREADS = 256
#: Most ``[blocks.terrain]`` zones, histogram bins and validated sample blocks.
MAX_ZONES = 1000
MAX_BINS = 10_000
MAX_VALIDATE = 10**9


def _terrain(file: Path, raw: Any) -> dict[str, Any]:
    """``[blocks.terrain]``: the keyword arguments of ``TerrainSpec``, checked by it."""
    from geofrac.meshing.terrain import TerrainSpec  # numpy only; gmsh is imported to build

    fields = {f.name: f for f in dataclasses.fields(TerrainSpec)}
    t = Table(file, "blocks.terrain", raw, allowed=tuple(fields))
    values: dict[str, Any] = {}
    for name, value in t.data.items():
        default = fields[name].default
        if name in _TERRAIN_VECTORS:
            values[name] = t.vector(name, _TERRAIN_VECTORS[name])
        elif name == "zones":
            values[name] = _zones(t, value)
        elif isinstance(default, bool):
            values[name] = t.boolean(name, default=default)
        elif name == "threads":
            values[name] = int(t.number(name, integer=True, minimum=1, maximum=MAX_THREADS))  # type: ignore[arg-type]
        elif isinstance(default, int):
            values[name] = int(t.number(name, integer=True))  # type: ignore[arg-type]
        elif isinstance(default, float):
            values[name] = float(t.number(name))  # type: ignore[arg-type]
        else:
            values[name] = t.string(name)
    try:
        TerrainSpec(**values)
    except ValueError as exc:
        raise SceneError(file, "blocks.terrain", str(exc)) from None
    return values


def _zones(t: Table, value: Any) -> tuple[tuple[tuple[float, ...], float, float], ...]:
    """``zones = [{centre = [x, y, z], radius = r, h = size}, ...]``."""
    if not isinstance(value, list) or len(value) > MAX_ZONES:
        raise t.error(
            "zones",
            f"must be a list of at most {MAX_ZONES} tables {{centre = [x, y, z], radius, h}}",
        )
    zones = []
    for i, raw in enumerate(value):
        z = Table(t.file, f"blocks.terrain.zones[{i}]", raw, allowed=("centre", "radius", "h"))
        for key in ("centre", "radius", "h"):
            if not z.has(key):
                raise z.error(key, "missing (required)")
        zones.append(
            (
                z.vector("centre", 3),
                float(z.number("radius", positive=True)),  # type: ignore[arg-type]
                float(z.number("h", positive=True)),  # type: ignore[arg-type]
            )
        )
    return tuple(zones)


def blocks_spec(
    file: Path, raw: Any, geometry: Geometry | None, *, warnings: list[str]
) -> BlocksSpec:
    """``[blocks]`` of a block scene; valid but ignored keys are added to ``warnings``.

    Raises:
        SceneError: naming the file and the key.
    """
    t = Table(file, "blocks", raw, allowed=BLOCKS_KEYS)
    source = t.string("source", default="geometry", choices=("geometry", "terrain"))
    terrain = None
    if source == "terrain":
        if geometry is not None:
            raise SceneError(file, "geometry", "not used with blocks.source = 'terrain'; remove it")
        terrain = _terrain(file, t.data.get("terrain", {}))
        dim = 3
    else:
        if geometry is None:
            raise SceneError(file, "geometry", "missing (blocks.source = 'geometry' needs it)")
        if t.has("terrain"):
            raise t.error("terrain", "applies to source = 'terrain' only")
        dim = geometry.dim
    inner = t.string("inner_point", default="incentre", choices=("incentre", "random"))
    radius = float(t.number("radius", default=1.0))
    if not 0 <= radius <= 1:
        raise t.error(
            "radius", f"the movable region's relative radius must be in [0, 1], got {radius}"
        )
    convex = t.boolean("convex", default=False)
    if dim == 3:
        for key in ("inner_point", "radius", "convex"):
            if t.has(key):
                raise t.error(
                    key, "applies to 2D blocks only (3D faces use centroids, Edo (2016), §5.2.2(b))"
                )
    elif inner == "incentre":
        for key in ("radius", "convex"):
            if t.has(key):
                warnings.append(f"{file}: blocks.{key}: ignored, applies to inner_point = 'random'")
    immobile = t.boolean("immobile", default=source == "terrain")
    if immobile and source != "terrain":
        raise t.error("immobile", "applies to source = 'terrain' only")
    validate = t.data.get("validate", "all")
    if not (
        validate in ("all", "none")
        or (
            isinstance(validate, int)
            and not isinstance(validate, bool)
            and 0 < validate <= MAX_VALIDATE
        )
    ):
        raise t.error(
            "validate",
            f"must be 'all', 'none' or a number of blocks to sample (1 ... {MAX_VALIDATE:.0e}), "
            f"got {short(validate)}",
        )
    bins = t.number("histogram_bins", default=40, integer=True, positive=True, maximum=MAX_BINS)
    bins = int(bins)
    return BlocksSpec(
        source=source,
        dim=dim,
        inner_point=inner,
        radius=radius,
        convex=convex,
        seed=int(t.number("seed", default=0, integer=True, minimum=0, maximum=2**32 - 1)),
        immobile=immobile,
        validate=validate,
        histogram_bins=bins,
        terrain=terrain,
    )


def blocks_output(
    file: Path, raw: Any, name: str, *, out: Path | None, trusted: bool = False
) -> Output:
    """``[output]`` of a block scene: ``vtu``, ``block_file``, ``histogram``, ``section``.

    ``trusted``: ``output.dir`` was set on the command line (see
    :func:`~geofrac.model.table.output_directory`).
    """
    t = Table(file, "output", raw, allowed=BLOCKS_OUTPUT_KEYS)
    directory = output_directory(t, name, out, trusted=trusted)
    # the plain block file is for DEM/DDA codes and large (555 MB for 100k blocks): asked for
    defaults = {"vtu": True, "block_file": False, "histogram": True, "section": True}
    fields = tuple(k for k, default in defaults.items() if t.boolean(k, default=default))
    return Output(directory, fields, "vtu" in fields, {})
