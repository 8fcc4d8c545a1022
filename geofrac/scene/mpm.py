"""Validation of ``method = "mpm"`` scenes: ``[mpm]``, the material, particles, output.

Called by :func:`geofrac.scene.load.load_scene` once the top level, the ``effects`` list
and the schema are checked. Pure Python (gmsh is opened only to read a geometry's
physical groups); nothing here imports numpy's MPM engine, numba or MPI.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np

from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.expr import ExpressionError, evaluate, parse
from geofrac.model.scene import (
    BED_REPRESENTATIONS,
    Body,
    Geometry,
    Material,
    MpmSpec,
    Output,
    ParticleSource,
)
from geofrac.model.table import (
    Table,
    checkpoint_keys,
    finite,
    is_number,
    output_directory,
    short,
)
from geofrac.mpm.constitutive import model_effects

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
        "bed_representation",
        "particles",
        "courant",
        "dt",
        "t_end",
        "frames",
        "velocity",
        "initial_stress",
        "damping",
        "bodies",
    ),
    "mpm.grid": ("lower", "upper", "spacing", "padding"),
    "mpm.damping": ("kind", "alpha"),
    "mpm.particles": ("lower", "counts", "spacing", "density"),
    "mpm.bodies": (
        "name",
        "lower",
        "upper",
        "counts",
        "spacing",
        "group",
        "density",
        "velocity",
    ),
}
#: Coordinate names a velocity expression may use, by dimension.
AXES = ("x", "y", "z")
#: Grid box sides a wall (or friction) may name.
SIDES = ("x_min", "x_max", "y_min", "y_max", "z_min", "z_max")
#: Particle fields an MPM scene's ``output.fields`` may list (all by default).
MPM_OUTPUT_FIELDS = (
    "displacement",
    "velocity",
    "stress",
    "plastic_strain",
    "density",
    "mass",
    "volume",
)
#: Effects an MPM scene may declare (a material model's effect from the model registry).
MPM_EFFECTS = ("gravity", "mls_smoothing", *model_effects(), "friction")
#: Tables of finite-element scenes that an MPM scene must not have.
FEM_ONLY_TABLES = ("discretization", "exact", "bc", "load", "solver", "initial_stress", "stages")
#: Kinds of ``mpm.damping``: Cundall's local (non-viscous) damping of the nodal forces.
DAMPING_KINDS = ("local",)
#: Default Courant number (the benchmarks of Edo (2016) use 0.1, eq. 4.72).
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
#: Most entries of ``[[mpm.bodies]]``; longest body name.
MAX_BODIES = 1000
MAX_BODY_NAME = 100


def mpm_material(file: Path, raw: Any, dim: int) -> Material:
    """``[material]`` of an MPM scene: E, ν (not in 1D), density; 2D is plane strain."""
    t = Table(file, "material", raw, allowed=("E", "nu", "plane", "density"))
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
    t = Table(file, "mpm.grid", raw, allowed=MPM_KEYS["mpm.grid"])
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
    padding = int(t.number("padding", default=2, integer=True, minimum=0, maximum=MAX_PADDING))
    for a, (lo, u) in enumerate(zip(lower, upper, strict=True)):
        if not (u - lo) / spacing <= MAX_AXIS_CELLS:  # also an overflow to inf
            raise t.error("spacing", f"gives over {MAX_AXIS_CELLS:.0e} cells along axis {a}")
        if (u - lo) / spacing < 1:
            raise t.error("spacing", f"is larger than the box along axis {a}")
    return lower, upper, spacing, padding


def _particles(
    file: Path, raw: Any, dim: int | None, geometry: Geometry | None
) -> tuple[ParticleSource, int]:
    t = Table(file, "mpm.particles", raw, allowed=MPM_KEYS["mpm.particles"])
    lattice_keys = [k for k in ("lower", "counts", "spacing") if t.has(k)]
    if geometry is not None:
        if lattice_keys:
            raise t.error(
                lattice_keys[0], "particles come from [geometry]; remove the lattice keys"
            )
        dens = t.data.get("density", {})
        d = Table(file, "mpm.particles.density", dens, allowed=list(dens))
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
    lower, counts, spacing = _lattice(t, n)
    return ParticleSource("lattice", lower, counts, spacing), n


def _lattice(t: Table, n: int) -> tuple[tuple[float, ...], tuple[int, ...], float]:
    """``lower``, ``spacing`` and ``counts`` (or ``upper``, a whole number of spacings)."""
    lower = t.vector("lower", n)
    spacing = float(t.number("spacing", required=True, positive=True))  # type: ignore[arg-type]
    if t.has("upper"):
        upper = t.vector("upper", n)
        cells = [(u - lo) / spacing for lo, u in zip(lower, upper, strict=True)]
        for a, c in enumerate(cells):
            if not 0.5 <= c <= MAX_AXIS_PARTICLES:  # also an overflow to inf
                raise t.error("upper", f"gives {c:.3g} particles along axis {a}; must be 1 ... 1e9")
            if abs(c - round(c)) > 1e-6 * max(1.0, c):
                raise t.error(
                    "upper",
                    f"upper - lower along axis {a} is {c:.6g} spacings; make it a whole "
                    "number (the lattice fills the box, one particle per spacing)",
                )
        return lower, tuple(round(c) for c in cells), spacing
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
    return lower, tuple(counts), spacing


def _corners(lower: tuple[float, ...], upper: tuple[float, ...]) -> np.ndarray:
    """The corners and centre of a box, shape=(2**dim + 1, dim)."""
    corners = list(itertools.product(*zip(lower, upper, strict=True)))
    centre = tuple((lo + u) / 2 for lo, u in zip(lower, upper, strict=True))
    return np.array([*corners, centre], dtype=float)


def _velocity(t: Table, name: str, dim: int, points: np.ndarray) -> tuple[float | str, ...]:
    """An initial velocity: ``dim`` numbers or expressions of the position.

    Each expression is parsed (:func:`geofrac.model.expr.parse`) and evaluated at
    ``points`` (shape=(k, dim): the corners and centre of the grid box and of the body);
    the run evaluates it at every particle again.
    """
    names = AXES[:dim]
    raw = t.data[name]
    if (
        not isinstance(raw, list)
        or len(raw) != dim
        or not all(is_number(c) or isinstance(c, str) for c in raw)
    ):
        raise t.error(
            name,
            f"must be a list of {dim} numbers or expressions of {', '.join(names)} "
            f'(e.g. "-0.5*{names[-1]}"), got {short(raw)}',
        )
    out: list[float | str] = []
    for i, c in enumerate(raw):
        if isinstance(c, str):
            try:
                evaluate(parse(c, names), points)
            except ExpressionError as exc:
                raise t.error(name, f"entry {i}: expression {short(c, 40)} {exc}") from None
            out.append(c)
        elif not finite(c):
            raise t.error(name, f"entry {i} must be finite, got {short(c)}")
        else:
            out.append(float(c))
    return tuple(out)


def _bodies(
    file: Path,
    raw: Any,
    dim: int,
    geometry: Geometry | None,
    box: np.ndarray,
) -> tuple[Body, ...]:
    """``[[mpm.bodies]]``: lattice boxes or physical groups, none overlapping.

    ``box``: the grid box's corners and centre (where velocity expressions are tried).
    """
    if not isinstance(raw, list) or not raw:
        raise SceneError(file, "mpm.bodies", "must be a non-empty array of tables ([[mpm.bodies]])")
    if len(raw) > MAX_BODIES:
        raise SceneError(file, "mpm.bodies", f"has {len(raw)} entries; at most {MAX_BODIES}")
    bodies: list[Body] = []
    for i, entry in enumerate(raw):
        key = f"mpm.bodies[{i}]"
        t = Table(file, key, entry, allowed=MPM_KEYS["mpm.bodies"])
        name = t.string("name", default=f"body{i}")
        if not 1 <= len(name) <= MAX_BODY_NAME or not name.isprintable():
            raise t.error("name", f"must be 1 to {MAX_BODY_NAME} printable characters")
        if any(b.name == name for b in bodies):
            raise t.error("name", f"'{name}' names an earlier body too; names must be unique")
        density = t.number("density", positive=True, maximum=MAX_DENSITY)
        lattice_keys = [k for k in ("lower", "upper", "counts", "spacing") if t.has(k)]
        if t.has("group"):
            if lattice_keys:
                raise t.error(lattice_keys[0], "a body is a 'group' or a lattice box, not both")
            group = t.string("group")
            if geometry is None:
                raise t.error("group", "a group body needs particles from a [geometry]")
            if group not in geometry.groups:
                raise t.error(
                    "group",
                    f"unknown physical group '{group}' in {geometry.file.name}"  # type: ignore[union-attr]
                    + did_you_mean(group, geometry.groups),
                )
            if geometry.groups[group] != geometry.dim or geometry.dim != dim:
                raise t.error("group", f"group '{group}' is not a {dim}D region")
            for b in bodies:
                if b.group == group:
                    raise t.error("group", f"'{group}' is body '{b.name}' already")
            velocity = _velocity(t, "velocity", dim, box) if t.has("velocity") else None
            bodies.append(
                Body(name, "group", group=group, density=density, velocity=velocity, key=key)
            )
            continue
        if "spacing" not in lattice_keys or "lower" not in lattice_keys:
            missing = "lower" if "lower" not in lattice_keys else "spacing"
            raise t.error(missing, "missing (a body needs 'group', or lower, spacing and counts)")
        if t.has("counts") == t.has("upper"):
            raise t.error("counts", "give either 'counts' or 'upper' (not both, not neither)")
        lower, counts, spacing = _lattice(t, dim)
        upper = tuple(lo + c * spacing for lo, c in zip(lower, counts, strict=True))
        for b in bodies:
            if b.kind != "lattice":
                continue
            b_upper = tuple(lo + c * b.spacing for lo, c in zip(b.lower, b.counts, strict=True))
            gaps = [
                min(u, bu) - max(lo, bl)
                for lo, u, bl, bu in zip(lower, upper, b.lower, b_upper, strict=True)
            ]
            scale = max(spacing, b.spacing)
            if all(g > 1e-9 * scale for g in gaps):
                raise t.error(
                    "lower",
                    f"box {list(lower)} ... {list(upper)} overlaps body '{b.name}' "
                    f"({list(b.lower)} ... {list(b_upper)}); bodies must not overlap",
                )
        points = np.concatenate([box, _corners(lower, upper)])
        velocity = _velocity(t, "velocity", dim, points) if t.has("velocity") else None
        bodies.append(Body(name, "lattice", lower, counts, spacing, None, density, velocity, key))
    kinds = {b.kind for b in bodies}
    if len(kinds) > 1:
        raise SceneError(
            file,
            "mpm.bodies",
            "mixes lattice boxes and geometry groups; give bodies of one kind (their "
            "overlap could not be checked before meshing)",
        )
    return tuple(bodies)


def _walls(file: Path, raw: Any, dim: int) -> dict[str, str]:
    sides = SIDES[: 2 * dim]
    t = Table(file, "mpm.walls", raw, allowed=sides)
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
    t = Table(file, "mpm.damping", raw, allowed=MPM_KEYS["mpm.damping"])
    t.string("kind", default="local", choices=DAMPING_KINDS)
    alpha = float(t.number("alpha", required=True, minimum=0.0))  # type: ignore[arg-type]
    if not alpha < 1:
        raise t.error(
            "alpha", f"must be < 1 (1 would cancel every unbalanced force), got {alpha!r}"
        )
    return alpha


def mpm_spec(file: Path, raw: Any, geometry: Geometry | None) -> MpmSpec:
    """Validate ``[mpm]`` (with the geometry, when particles come from one)."""
    t = Table(file, "mpm", raw, allowed=MPM_KEYS["mpm"])
    from geofrac.mpm.schemes import SCHEMES
    from geofrac.mpm.shapes import REGISTRY

    scheme = t.string("scheme", default="musl", choices=SCHEMES)
    shape = t.string("shape", default="mpm", choices=tuple(REGISTRY))
    if not t.has("grid"):
        raise t.error("grid", "missing (required table: lower, upper, spacing)")
    lower, upper, spacing, padding = _grid(file, t.data["grid"])
    dim = len(lower)
    box = _corners(lower, upper)
    bodies: tuple[Body, ...] = ()
    if t.has("bodies"):
        if t.has("particles"):
            raise t.error("particles", "give [[mpm.bodies]] or [mpm.particles], not both")
        bodies = _bodies(file, t.data["bodies"], dim, geometry, box)
        source = ParticleSource("bodies")
    else:
        source, pdim = _particles(file, t.data.get("particles", {}), dim, geometry)
        if pdim != dim:
            raise t.error("grid", f"is {dim}D but the particles are {pdim}D")
    if t.has("courant") and t.has("dt"):
        raise t.error("dt", "give either 'courant' or 'dt', not both")
    dt = t.number("dt", positive=True)
    courant = None
    if dt is None:
        courant = float(t.number("courant", default=DEFAULT_COURANT))
        if not 0 < courant < 1:
            raise t.error("courant", f"must lie in (0, 1) (eq. 4.72), got {courant}")
    t_end = float(t.number("t_end", required=True, positive=True))  # type: ignore[arg-type]
    frames = int(
        t.number("frames", default=DEFAULT_FRAMES, positive=True, integer=True, maximum=MAX_FRAMES)
    )
    points = np.concatenate(
        [box, *(_corners(b.lower, _upper(b)) for b in bodies if b.kind == "lattice")]
    )
    if source.kind == "lattice":
        upper_p = tuple(
            lo + c * source.spacing for lo, c in zip(source.lower, source.counts, strict=True)
        )
        points = np.concatenate([points, _corners(source.lower, upper_p)])
    velocity = _velocity(t, "velocity", dim, points) if t.has("velocity") else (0.0,) * dim
    initial_stress = t.string("initial_stress", default="none", choices=("none", "geostatic"))
    if initial_stress == "geostatic" and dim == 1:
        raise t.error("initial_stress", "'geostatic' applies to 2D and 3D scenes")
    damping = _damping(file, t.data["damping"]) if t.has("damping") else 0.0
    walls = _walls(file, t.data.get("walls", {}), dim)
    bed = _bed(file, t.data["bed"], dim, geometry) if t.has("bed") else ()
    bed_representation = t.string(
        "bed_representation", default=BED_REPRESENTATIONS[0], choices=BED_REPRESENTATIONS
    )
    if t.has("bed_representation") and not t.has("bed"):
        raise t.error("bed_representation", "applies to a scene with an 'mpm.bed'")
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
        bodies=bodies,
        bed_representation=bed_representation,
    )


def _upper(b: Body) -> tuple[float, ...]:
    """A lattice body's highest corner, shape=(dim,)."""
    return tuple(lo + c * b.spacing for lo, c in zip(b.lower, b.counts, strict=True))


def mpm_output(
    file: Path, raw: Any, name: str, *, dim: int, out: Path | None, trusted: bool = False
) -> Output:
    """``[output]`` of an MPM scene: particle fields; probes are particles nearest a point.

    ``trusted``: ``output.dir`` was set on the command line (see
    :func:`~geofrac.model.table.output_directory`).
    """
    t = Table(
        file,
        "output",
        raw,
        allowed=("dir", "fields", "xdmf", "probes", "checkpoint_every", "checkpoint_minutes"),
    )
    directory = output_directory(t, name, out, trusted=trusted)
    fields = t.names("fields", MPM_OUTPUT_FIELDS, MPM_OUTPUT_FIELDS, kind="particle field")
    probes_raw = t.data.get("probes", {})
    p = Table(file, "output.probes", probes_raw, allowed=list(probes_raw))
    probes = {k: p.vector(k, dim) for k in probes_raw}
    every, minutes = checkpoint_keys(t)
    return Output(directory, tuple(fields), t.boolean("xdmf", default=True), probes, every, minutes)
