"""Validation of ``method = "mpm"`` scenes: ``[mpm]``, the material, particles, output.

Called by :func:`geofrac.scene.load.load_scene` once the top level, the ``effects`` list
and the schema are checked. Pure Python (gmsh is opened only to read a geometry's
physical groups); nothing here imports numpy's MPM engine, numba or MPI.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

from geofrac.scene.errors import SceneError, did_you_mean
from geofrac.scene.model import Geometry, Material, MpmSpec, Output, ParticleSource
from geofrac.scene.table import (
    Table,
    checkpoint_keys,
    finite,
    is_number,
    output_directory,
    short,
)

__all__ = [
    "FEM_ONLY_TABLES",
    "MPM_EFFECTS",
    "MPM_KEYS",
    "MPM_OUTPUT_FIELDS",
    "SIDES",
    "mpm_material",
    "mpm_output",
    "mpm_spec",
]

#: Keys of ``[mpm]`` and of its sub-tables (the single source for docs/scenes.md).
MPM_KEYS: dict[str, tuple[str, ...]] = {
    "mpm": (
        "scheme",
        "shape",
        "grid",
        "walls",
        "bed",
        "particles",
        "courant",
        "dt",
        "t_end",
        "frames",
        "velocity",
        "initial_stress",
        "damping",
    ),
    "mpm.grid": ("lower", "upper", "spacing", "padding"),
    "mpm.damping": ("kind", "alpha"),
    "mpm.particles": ("lower", "counts", "spacing", "density"),
}
#: Grid box sides a wall (or friction) may name.
SIDES = ("x_min", "x_max", "y_min", "y_max", "z_min", "z_max")
#: Particle fields an MPM scene's ``output.fields`` may list (all by default).
MPM_OUTPUT_FIELDS = ("displacement", "velocity", "stress", "plastic_strain", "density")
#: Effects an MPM scene may declare.
MPM_EFFECTS = ("gravity", "mls_smoothing", "plasticity", "friction")
#: Tables of finite-element scenes that an MPM scene must not have.
FEM_ONLY_TABLES = ("discretization", "exact", "bc", "load", "solver")
#: Kinds of ``mpm.damping``: Cundall's local (non-viscous) damping of the nodal forces.
DAMPING_KINDS = ("local",)
#: Default Courant number (the seed's benchmarks use 0.1, eq. 4.72).
DEFAULT_COURANT = 0.1
#: Default number of output frames.
DEFAULT_FRAMES = 50
#: Upper limits: grid cells along one axis, padding cells, frames, bed points,
#: E (any unit system), density.
MAX_AXIS_CELLS = 10**7
MAX_AXIS_PARTICLES = 10**9
MAX_PADDING = 100
MAX_FRAMES = 100_000
MAX_BED_POINTS = 100_000
MAX_MODULUS = 1e15
MAX_DENSITY = 1e6


def mpm_material(file: Path, raw: Any, dim: int) -> Material:
    """``[material]`` of an MPM scene: E, ν (not in 1D), density; 2D is plane strain."""
    t = Table(file, "material", raw, ("E", "nu", "plane", "density"))
    E = t.number("E", required=True, positive=True, maximum=MAX_MODULUS)
    nu = t.number("nu", required=dim > 1, default=0.0)
    assert E is not None and nu is not None
    if dim == 1 and t.has("nu"):
        raise t.error("nu", "a 1D bar has no Poisson's ratio; remove it")
    if not -1.0 < nu < 0.5:
        raise t.error("nu", f"must lie in (-1, 0.5), got {nu!r}")
    if t.has("plane") and (dim != 2 or t.data["plane"] != "strain"):
        raise t.error("plane", "MPM in 2D is plane strain; only 'strain' is accepted, in 2D")
    density = t.number("density", required=True, positive=True, maximum=MAX_DENSITY)
    return Material(E=float(E), nu=float(nu), plane="strain", density=density)


def _grid(file: Path, raw: Any) -> tuple[tuple[float, ...], tuple[float, ...], float, int]:
    t = Table(file, "mpm.grid", raw, MPM_KEYS["mpm.grid"])
    for key in ("lower", "upper", "spacing"):
        if not t.has(key):
            raise t.error(key, "missing (required)")
    lower_raw = t.data["lower"]
    if not isinstance(lower_raw, list) or not 1 <= len(lower_raw) <= 3:
        raise t.error("lower", f"must be a list of 1 to 3 numbers, got {short(lower_raw)}")
    dim = len(lower_raw)
    lower, upper = t.vector("lower", dim), t.vector("upper", dim)
    if any(u <= lo for lo, u in zip(lower, upper, strict=True)):
        raise t.error("upper", f"must exceed lower {list(lower)} in every direction")
    spacing = float(t.number("spacing", positive=True))  # type: ignore[arg-type]
    padding = int(t.number("padding", default=2, integer=True, minimum=0, maximum=MAX_PADDING))  # type: ignore[arg-type]
    for a, (lo, u) in enumerate(zip(lower, upper, strict=True)):
        if not (u - lo) / spacing <= MAX_AXIS_CELLS:  # also an overflow to inf
            raise t.error("spacing", f"gives over {MAX_AXIS_CELLS:.0e} cells along axis {a}")
        if (u - lo) / spacing < 1:
            raise t.error("spacing", f"is larger than the box along axis {a}")
    return lower, upper, spacing, padding


def _particles(
    file: Path, raw: Any, dim: int | None, geometry: Geometry | None
) -> tuple[ParticleSource, int]:
    t = Table(file, "mpm.particles", raw, MPM_KEYS["mpm.particles"])
    lattice_keys = [k for k in ("lower", "counts", "spacing") if t.has(k)]
    if geometry is not None:
        if lattice_keys:
            raise t.error(
                lattice_keys[0], "particles come from [geometry]; remove the lattice keys"
            )
        dens = t.data.get("density", {})
        d = Table(file, "mpm.particles.density", dens, list(dens))
        for group in dens:
            if group not in geometry.groups:
                raise d.error(
                    group,
                    f"unknown physical group '{group}' in {geometry.file.name}"  # type: ignore[union-attr]
                    + did_you_mean(group, geometry.groups),
                )
            if geometry.groups[group] != geometry.dim:
                raise d.error(group, f"group '{group}' is not a {geometry.dim}D region")
        densities = {g: float(d.number(g, positive=True, maximum=MAX_DENSITY)) for g in dens}  # type: ignore[arg-type]
        return ParticleSource("geometry", densities=densities), geometry.dim
    if t.has("density"):
        raise t.error("density", "per-group densities need particles from a [geometry]")
    for key in ("lower", "counts", "spacing"):
        if not t.has(key):
            raise t.error(key, "missing (required without a [geometry] table)")
    n = dim or (len(t.data["lower"]) if isinstance(t.data["lower"], list) else 0)
    lower = t.vector("lower", n)
    counts = t.data["counts"]
    if (
        not isinstance(counts, list)
        or len(counts) != n
        or not all(isinstance(c, int) and not isinstance(c, bool) and c > 0 for c in counts)
    ):
        raise t.error("counts", f"must be a list of {n} positive integers, got {short(counts)}")
    for i, c in enumerate(counts):
        if c > MAX_AXIS_PARTICLES:
            raise t.error("counts", f"entry {i} must be <= 1e9, got {short(c)}")
    spacing = float(t.number("spacing", positive=True))  # type: ignore[arg-type]
    return ParticleSource("lattice", lower, tuple(counts), spacing), n


def _walls(file: Path, raw: Any, dim: int) -> dict[str, str]:
    sides = SIDES[: 2 * dim]
    t = Table(file, "mpm.walls", raw, sides)
    return {
        side: t.string(side, choices=("fixed", "roller", "free"))
        for side in sides
        if t.has(side) and t.data[side] != "free"
    }


def _bed(
    file: Path, raw: Any, dim: int, geometry: Geometry | None
) -> tuple[tuple[float, float], ...] | str:
    if dim != 2:
        raise SceneError(file, "mpm.bed", "a bed polyline y(x) applies to 2D scenes only")
    if isinstance(raw, str):
        if geometry is None:
            raise SceneError(file, "mpm.bed", "a group name needs particles from a [geometry]")
        if raw not in geometry.groups:
            raise SceneError(
                file,
                "mpm.bed",
                f"unknown physical group '{raw}' in {geometry.file.name}"  # type: ignore[union-attr]
                + did_you_mean(raw, geometry.groups),
            )
        if geometry.groups[raw] != 1:
            raise SceneError(file, "mpm.bed", f"group '{raw}' is not a curve")
        return raw
    if (
        not isinstance(raw, list)
        or not 2 <= len(raw) <= MAX_BED_POINTS
        or not all(isinstance(p, list) and len(p) == 2 and all(map(is_number, p)) for p in raw)
    ):
        raise SceneError(
            file,
            "mpm.bed",
            f"must be a physical curve group or a list of 2 to {MAX_BED_POINTS} [x, y] points, "
            f"got {short(raw)}",
        )
    for i, point in enumerate(raw):
        for j, c in enumerate(point):
            if not finite(c):
                raise SceneError(file, "mpm.bed", f"entry [{i}][{j}] must be finite, got {c!r}")
    xs = [float(p[0]) for p in raw]
    if any(b <= a for a, b in itertools.pairwise(xs)):
        raise SceneError(file, "mpm.bed", "x must increase strictly along the polyline")
    return tuple((float(p[0]), float(p[1])) for p in raw)


def _damping(file: Path, raw: Any) -> float:
    """``mpm.damping = { kind = "local", alpha = α }``: Cundall's local damping, α in [0, 1)."""
    t = Table(file, "mpm.damping", raw, MPM_KEYS["mpm.damping"])
    t.string("kind", default="local", choices=DAMPING_KINDS)
    alpha = float(t.number("alpha", required=True, minimum=0.0))  # type: ignore[arg-type]
    if not alpha < 1:
        raise t.error(
            "alpha", f"must be < 1 (1 would cancel every unbalanced force), got {alpha!r}"
        )
    return alpha


def mpm_spec(file: Path, raw: Any, geometry: Geometry | None) -> MpmSpec:
    """Validate ``[mpm]`` (with the geometry, when particles come from one)."""
    t = Table(file, "mpm", raw, MPM_KEYS["mpm"])
    from geofrac.mpm.schemes import SCHEMES
    from geofrac.mpm.shapes import SHAPES

    scheme = t.string("scheme", default="musl", choices=SCHEMES)
    shape = t.string("shape", default="mpm", choices=SHAPES)
    if not t.has("grid"):
        raise t.error("grid", "missing (required table: lower, upper, spacing)")
    lower, upper, spacing, padding = _grid(file, t.data["grid"])
    dim = len(lower)
    source, pdim = _particles(file, t.data.get("particles", {}), dim, geometry)
    if pdim != dim:
        raise t.error("grid", f"is {dim}D but the particles are {pdim}D")
    if t.has("courant") and t.has("dt"):
        raise t.error("dt", "give either 'courant' or 'dt', not both")
    dt = t.number("dt", positive=True)
    courant = None
    if dt is None:
        courant = float(t.number("courant", default=DEFAULT_COURANT))  # type: ignore[arg-type]
        if not 0 < courant < 1:
            raise t.error("courant", f"must lie in (0, 1) (eq. 4.72), got {courant}")
    t_end = float(t.number("t_end", required=True, positive=True))  # type: ignore[arg-type]
    frames = int(
        t.number("frames", default=DEFAULT_FRAMES, positive=True, integer=True, maximum=MAX_FRAMES)  # type: ignore[arg-type]
    )
    velocity = t.vector("velocity", dim) if t.has("velocity") else (0.0,) * dim
    initial_stress = t.string("initial_stress", default="none", choices=("none", "geostatic"))
    if initial_stress == "geostatic" and dim == 1:
        raise t.error("initial_stress", "'geostatic' applies to 2D and 3D scenes")
    damping = _damping(file, t.data["damping"]) if t.has("damping") else 0.0
    walls = _walls(file, t.data.get("walls", {}), dim)
    bed = _bed(file, t.data["bed"], dim, geometry) if t.has("bed") else ()
    return MpmSpec(
        dim=dim,
        scheme=scheme,
        shape=shape,
        lower=lower,
        upper=upper,
        spacing=spacing,
        padding=padding,
        walls=walls,
        bed=() if isinstance(bed, str) else bed,
        bed_group=bed if isinstance(bed, str) else None,
        courant=courant,
        dt=None if dt is None else float(dt),
        t_end=t_end,
        frames=frames,
        velocity=velocity,
        particles=source,
        initial_stress=initial_stress,
        damping=damping,
    )


def mpm_output(
    file: Path, raw: Any, name: str, dim: int, out: Path | None, trusted: bool = False
) -> Output:
    """``[output]`` of an MPM scene: particle fields; probes are particles nearest a point.

    ``trusted``: ``output.dir`` was set on the command line (see
    :func:`~geofrac.scene.table.output_directory`).
    """
    t = Table(
        file,
        "output",
        raw,
        ("dir", "fields", "xdmf", "probes", "checkpoint_every", "checkpoint_minutes"),
    )
    directory = output_directory(t, name, out, trusted)
    fields = t.data.get("fields", list(MPM_OUTPUT_FIELDS))
    if (
        not isinstance(fields, list)
        or not all(isinstance(f, str) for f in fields)
        or len(set(fields)) != len(fields)
    ):
        raise t.error("fields", f"must be a list of distinct names from {list(MPM_OUTPUT_FIELDS)}")
    for f in fields:
        if f not in MPM_OUTPUT_FIELDS:
            raise t.error(
                "fields", f"unknown particle field {f!r}" + did_you_mean(str(f), MPM_OUTPUT_FIELDS)
            )
    probes_raw = t.data.get("probes", {})
    p = Table(file, "output.probes", probes_raw, list(probes_raw))
    probes = {k: p.vector(k, dim) for k in probes_raw}
    every, minutes = checkpoint_keys(t)
    return Output(directory, tuple(fields), t.boolean("xdmf", True), probes, every, minutes)
