"""Read a scene TOML file, apply ``--set`` overrides, validate everything, return a Scene.

Runs on one process and touches neither MPI nor DOLFINx; the geometry file is opened in
gmsh (no meshing) to learn its dimension and physical groups, so that every name a
scene uses is checked before any mesh or solve. See ``docs/scenes.md`` for the schema.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
import tomllib
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from geofrac import analytic, effects, elements
from geofrac.meshing.geo import ALGORITHMS, define_constants, inspect_geometry
from geofrac.model import expr
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.scene import (
    SCHEMA_VERSION,
    BoundaryCondition,
    Discretization,
    EffectSpec,
    ExactSpec,
    Geometry,
    Line,
    Load,
    Material,
    Output,
    Scene,
    Solver,
    Stage,
    Units,
    effect_config,
)
from geofrac.model.table import (
    MAX_DEPTH,
    check_name,
    checkpoint_keys,
    first_too_deep,
    is_name,
    is_number,
    short,
)
from geofrac.model.table import Table as _Table
from geofrac.model.table import output_directory as _output_directory
from geofrac.scene.insitu import INITIAL_STRESS_KEYS, STAGE_KEYS
from geofrac.scene.insitu import cracking_variable as _cracking_variable
from geofrac.scene.insitu import initial_stress as _initial_stress
from geofrac.scene.insitu import stages as _stages
from geofrac.scene.size import TRIAL_CELLS, Extent, check_size, estimate, trial_factor
from geofrac.scene.switches import SWITCH_KEYS
from geofrac.scene.switches import stage_names as _stage_names
from geofrac.scene.switches import switch_keys as _switch_keys
from geofrac.scene.switches import switched as _switched
from geofrac.scene.switches import switches as _switches

__all__ = [
    "DEFAULT_OUTPUT_FIELDS",
    "LOAD_TYPES",
    "METHODS",
    "OUTPUT_FIELDS",
    "PROBE_FIELDS",
    "SECTION_KEYS",
    "TOP_LEVEL_KEYS",
    "apply_overrides",
    "load_scene",
    "marked_description",
]

#: Keys a scene may have at the top level (besides one table per declared effect).
TOP_LEVEL_KEYS = (
    "schema",
    "name",
    "description",
    "method",
    "effects",
    "geometry",
    "material",
    "discretization",
    "exact",
    "bc",
    "load",
    "solver",
    "output",
    "mpm",
    "blocks",
    "allow_large",
    "units",
    "initial_stress",
    "stages",
)
#: ``[discretization]`` keys that every element takes (the others are element options).
ELEMENT_INDEPENDENT = ("renumber",)

#: Simulation methods a scene may name (``method``).
METHODS = ("fem", "mpm", "blocks")
#: Keys each table accepts (the single source for validation and for docs/scenes.md).
SECTION_KEYS: dict[str, tuple[str, ...]] = {
    "units": ("length", "force", "stress", "time"),
    "geometry": ("file", "parameters", "mesh_size", "algorithm", "trusted", "time_limit"),
    "material": (
        "E",
        "nu",
        "plane",
        "thickness",
        "density",
        "tensile_strength",
        "cohesion",
        "friction_angle",
        "fracture_energy",
    ),
    "discretization": (
        "element",
        "quadrature_degree",
        "zero_mode_penalty",
        "gradient_bc",
        "q_rand",
        "domain_seed",
        "renumber",
    ),
    "bc": ("group", "value", "components", "symmetry", *SWITCH_KEYS),
    "load": ("type", "group", "value", *SWITCH_KEYS),
    "solver": ("preset", "options"),
    "output": (
        "dir",
        "fields",
        "xdmf",
        "probes",
        "probe_fields",
        "lines",
        "nominal_stress",
        "checkpoint_every",
        "checkpoint_minutes",
    ),
    "initial_stress": INITIAL_STRESS_KEYS,
    "stages": STAGE_KEYS,
}
#: Field names ``output.fields`` may list.
OUTPUT_FIELDS = ("displacement", "stress", "strain", "von_mises", "stress_nodal", "strain_nodal")
#: Fields written when ``output.fields`` is not given.
DEFAULT_OUTPUT_FIELDS = ("displacement", "stress", "von_mises")
#: Fields ``output.probe_fields`` and ``output.lines.NAME.fields`` may list (the value of
#: the element's own field at the point: docs/output.md, "Probes and lines").
PROBE_FIELDS = ("displacement", "stress", "strain", "von_mises", "principal_stress")
#: Keys of one ``[output.lines.NAME]`` table.
LINE_KEYS = ("start", "end", "points", "fields")
#: Most sample points of one line.
MAX_LINE_POINTS = 10000
_AXES = ("x", "y", "z")
#: Upper limits of material constants (any unit system: E of diamond is 1.2e12 Pa).
MAX_MODULUS = 1e15
MAX_LENGTH = 1e9
MAX_DENSITY = 1e6
#: Highest forced quadrature degree (a degree-20 rule in 3D already has ~1800 points).
MAX_QUADRATURE_DEGREE = 20


def apply_overrides(data: dict[str, Any], overrides: Sequence[str], file: Path) -> None:
    """Apply ``key.sub=value`` overrides in place; values are TOML (bare words are strings).

    A list index is written as ``bc.0.group=...``.
    """
    for item in overrides:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            message = f"--set expects KEY=VALUE, got {short(item)}"
            raise SceneError(file, short(key or item), message)
        parts = key.split(".")
        if len(parts) > MAX_DEPTH:
            raise SceneError(
                file, short(key), f"--set key is nested deeper than {MAX_DEPTH} levels"
            )
        try:
            value = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            value = text.strip()
        except (RecursionError, MemoryError):
            raise SceneError(file, key, "--set value is nested too deeply") from None
        node: Any = data
        for depth, part in enumerate(parts[:-1]):
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise SceneError(file, ".".join(parts[: depth + 1]), "no such list entry")
                node = node[int(part)]
            else:
                node = node.setdefault(part, {})
            if not isinstance(node, dict | list):
                raise SceneError(file, ".".join(parts[: depth + 1]), "is not a table")
        if isinstance(node, list):
            raise SceneError(file, key, "cannot replace a whole list entry; set one of its keys")
        node[parts[-1]] = value


#: ``--set`` keys that do not change what a scene describes (where its output goes).
UNMARKED_KEYS = ("description", "output.dir")
#: Longest override quoted in full in a marked description.
MAX_OVERRIDE_TEXT = 200


#: A unit label: letters, digits and a few signs; no "$" or "\\" (matplotlib would read
#: them as mathematics), at most 12 characters.
_UNIT = re.compile(r"[\w ./^·²³µ%()-]{1,12}")


def _units(file: Path, raw: Any) -> Units:
    """``[units]``: the labels of the scene's units on the pictures' axes.

    A key the scene does not give stays empty: its quantity is labelled without a unit.
    """
    t = _Table(file, "units", raw, allowed=SECTION_KEYS["units"])
    labels = {}
    for key in SECTION_KEYS["units"]:
        if not t.has(key):
            continue
        value = t.string(key)
        if not _UNIT.fullmatch(value):
            raise t.error(
                key,
                f"{short(value)} is not a unit label (letters, digits, . / ^ ² ³ "
                "µ % ( ) -, at most 12 characters)",
            )
        labels[key] = value
    return Units(**labels)


def marked_description(description: str, overrides: Sequence[str]) -> str:
    """``description``, followed by ``(modified by --set K=V, ...)`` after overrides.

    A scene's description speaks of the file; once ``--set`` changed the scene it no
    longer describes it alone. Overrides of ``description`` itself and of ``output.dir``
    are not listed (they change no physics).
    """
    changed = [o.strip() for o in overrides if o.partition("=")[0].strip() not in UNMARKED_KEYS]
    if not changed:
        return description
    cut = [
        o if len(o) <= MAX_OVERRIDE_TEXT else o[: MAX_OVERRIDE_TEXT - 3] + "..." for o in changed
    ]
    note = "(modified by " + ", ".join(f"--set {o}" for o in cut) + ")"
    return f"{description} {note}" if description else note


def _geometry(file: Path, raw: Any) -> Geometry:
    from geofrac.meshing.geo import MAX_TIME_LIMIT, GmshTimeout
    from geofrac.meshing.geo_guard import (
        GeoRefused,
        check_parameters,
        count_parameters,
        parameter_specs,
    )

    t = _Table(file, "geometry", raw, allowed=SECTION_KEYS["geometry"])
    name = t.string("file")
    path = (file.resolve().parent / name).resolve()  # beside the scene (a link's target)
    if not path.is_file():
        raise t.error("file", f"cannot read mesh file '{name}' (looked for {path})")
    if path.suffix not in (".geo", ".msh"):
        raise t.error("file", f"must be a gmsh .geo or .msh file, got '{path.name}'")
    trusted = t.boolean("trusted", default=False)
    time_limit = t.number("time_limit", positive=True, maximum=MAX_TIME_LIMIT)
    params_raw = t.data.get("parameters", {})
    p = _Table(file, "geometry.parameters", params_raw, allowed=list(params_raw))
    parameters = {k: float(p.number(k, required=True)) for k in params_raw}  # type: ignore[arg-type]
    if parameters:
        if path.suffix != ".geo":
            raise t.error("parameters", "parameters apply only to .geo files")
        text = path.read_text(errors="replace")
        declared = define_constants(text)
        for k in parameters:
            if k not in declared:
                raise p.error(
                    k, f"'{path.name}' declares no DefineConstant '{k}'" + did_you_mean(k, declared)
                )
        try:
            specs, counts = parameter_specs(text), count_parameters(text)
        except GeoRefused as exc:
            if not trusted:
                raise t.error("file", str(exc)) from None
            specs, counts = {}, {}
        for k, message in check_parameters(parameters, specs, counts):
            raise p.error(k, message)
    mesh_size = t.number("mesh_size", positive=True)
    algorithm = None
    if t.has("algorithm"):
        algorithm = t.string("algorithm", choices=tuple(ALGORITHMS))
        if path.suffix != ".geo":
            raise t.error("algorithm", "applies only to .geo files (a .msh file is meshed)")
    try:
        info = inspect_geometry(path, parameters, time_limit, trusted=trusted)
    except (GeoRefused, GmshTimeout) as exc:
        raise t.error("file", str(exc)) from None
    except RuntimeError as exc:
        raise t.error("file", f"gmsh cannot read '{path.name}': {exc}") from None
    if info.dim not in (2, 3):
        raise t.error("file", f"'{path.name}' has no 2D or 3D entity (dimension {info.dim})")
    if info.dim not in info.groups.values():
        raise t.error(
            "file",
            f"'{path.name}' has no physical group of dimension {info.dim}; "
            "DOLFINx meshes only the cells of physical groups",
        )
    for dim, a, b, entity in info.overlaps:
        if dim == info.dim:
            kind = {2: "surface", 3: "volume"}[dim]
            raise t.error(
                "file",
                f"physical groups '{a}' and '{b}' of '{path.name}' share {kind} {entity}; "
                "DOLFINx gives each cell one group, so cell groups must not overlap "
                "(groups of lower dimension may)",
            )
    return Geometry(
        path,
        parameters,
        mesh_size,
        info.dim,
        info.groups,
        trusted=trusted,
        time_limit=time_limit,
        order=info.order,
        algorithm=algorithm,
    )


def _material(file: Path, raw: Any, dim: int) -> Material:
    t = _Table(file, "material", raw, allowed=SECTION_KEYS["material"])
    E = t.number("E", required=True, positive=True, maximum=MAX_MODULUS)
    nu = t.number("nu", required=True)
    assert E is not None and nu is not None
    if not -1.0 < nu < 0.5:
        raise t.error("nu", f"must lie in (-1, 0.5), got {nu!r}")
    plane = t.string("plane", default="stress", choices=("stress", "strain"))
    if dim == 3 and t.has("plane"):
        raise t.error("plane", "applies to 2D geometries only")
    cohesion = t.number("cohesion", positive=True, maximum=MAX_MODULUS)
    friction_angle = float(t.number("friction_angle", default=0.0, minimum=0.0, maximum=89.0))
    if t.has("friction_angle") and cohesion is None:
        raise t.error("friction_angle", "needs material.cohesion (the Mohr-Coulomb shear strength)")
    return Material(
        E=float(E),
        nu=float(nu),
        plane=plane,  # type: ignore[arg-type]
        thickness=float(t.number("thickness", default=1.0, positive=True, maximum=MAX_LENGTH)),
        density=t.number("density", positive=True, maximum=MAX_DENSITY),
        tensile_strength=t.number("tensile_strength", positive=True, maximum=MAX_MODULUS),
        cohesion=cohesion,
        friction_angle=friction_angle,
        fracture_energy=t.number("fracture_energy", positive=True, maximum=MAX_MODULUS),
    )


def _discretization(file: Path, raw: Any, dim: int) -> Discretization:
    t = _Table(file, "discretization", raw, allowed=SECTION_KEYS["discretization"])
    element = t.string("element", choices=elements.available())
    spec = elements.get(element)
    if dim not in spec.dims:
        raise t.error(
            "element", f"'{element}' supports dimensions {spec.dims}, the geometry is {dim}D"
        )
    for key in SECTION_KEYS["discretization"][1:]:
        if t.has(key) and key not in spec.options and key not in ELEMENT_INDEPENDENT:
            takers = [n for n, s in elements.REGISTRY.items() if key in s.options]
            raise t.error(key, f"applies only to elements {', '.join(takers)}, not '{element}'")
    q = t.number("quadrature_degree", positive=True, integer=True, maximum=MAX_QUADRATURE_DEGREE)
    q_rand = t.number("q_rand", default=0.0)
    if not 0.0 <= q_rand <= 1.0:
        raise t.error("q_rand", f"must lie in [0, 1], got {q_rand!r}")
    domain_seed = t.number("domain_seed", default=0, integer=True, maximum=2**32 - 1)
    if domain_seed < 0:
        raise t.error("domain_seed", f"must be >= 0, got {domain_seed!r}")
    renumber = t.number("renumber", integer=True, maximum=2**32 - 1)
    if renumber is not None and renumber < 0:
        raise t.error("renumber", f"must be >= 0, got {renumber!r}")
    alpha_default = 0.0 if spec.zero_mode_penalty is None else spec.zero_mode_penalty
    alpha = t.number("zero_mode_penalty", default=alpha_default, positive=True, maximum=1e6)
    gradient_bc = t.string(
        "gradient_bc", default="consistent", choices=("consistent", "fixed", "free")
    )
    return Discretization(
        element,
        None if q is None else int(q),
        float(alpha),
        gradient_bc,  # type: ignore[arg-type]
        float(q_rand),
        int(domain_seed),
        None if renumber is None else int(renumber),
    )


def _exact(file: Path, raw: Any, geometry: Geometry) -> ExactSpec:
    """Parameters missing from ``[exact]`` are taken from same-named geometry parameters."""
    head = _Table(file, "exact", raw, allowed=list(raw) if isinstance(raw, dict) else ())
    name = head.string("name", choices=tuple(analytic.EXACT_SOLUTIONS))
    sol_dim, required, _ = analytic.EXACT_SOLUTIONS[name]
    optional = analytic.OPTIONAL_PARAMETERS.get(name, {})
    t = _Table(file, "exact", raw, allowed=("name", *required, *optional))
    if sol_dim != geometry.dim:
        raise t.error("name", f"'{name}' is a {sol_dim}D solution, the geometry is {geometry.dim}D")
    params = {}
    for k in (*required, *optional):
        if t.has(k):
            params[k] = float(t.number(k))  # type: ignore[arg-type]
        elif k in geometry.parameters:
            params[k] = geometry.parameters[k]
        elif k in optional:
            params[k] = optional[k]
        else:
            raise t.error(k, f"missing (required by '{name}'; not in geometry.parameters either)")
    try:  # the solution's own parameter checks (material constants do not enter them)
        analytic.make_exact(name, params, E=1.0, nu=0.25, plane="strain")
    except ValueError as exc:
        raise t.error("name", f"'{name}' {exc}") from None
    return ExactSpec(name, params)


def _value(
    t: _Table, n: int, exact: ExactSpec | None, names: Sequence[str] = ()
) -> tuple[float | str, ...] | str:
    """``value``: ``n`` numbers, or ``"exact"``.

    With ``names``, each entry may also be an expression text of those coordinate names
    (:mod:`geofrac.model.expr`), checked here and kept as text.
    """
    if not t.has("value"):
        raise t.error("value", "missing (required)")
    value = t.data["value"]
    if value == "exact":
        if exact is None:
            raise t.error("value", "'exact' needs an [exact] table naming the analytical solution")
        return "exact"
    if not names or not isinstance(value, list) or not any(isinstance(c, str) for c in value):
        return t.vector("value", n)
    if len(value) != n:
        raise t.error("value", f"must be a list of {n} numbers or expressions, got {short(value)}")
    out: list[float | str] = []
    for i, c in enumerate(value):
        if isinstance(c, str):
            out.append(_expression(t, c, names, f"entry {i} "))
        else:
            out.append(t.vector("value", 1, [c])[0])
    return tuple(out)


def _expression(t: _Table, text: str, names: Sequence[str], where: str = "") -> str:
    """``text`` if it is an expression of the coordinate ``names``; else the ``value`` error."""
    try:
        expr.parse(text, names)
    except expr.ExpressionError as exc:
        raise t.error("value", f"{where}{short(text)} {exc}") from None
    return text


def _pressure(t: _Table, names: Sequence[str]) -> tuple[float | str]:
    """A pressure's ``value``: one number or one expression text (or a list of one)."""
    if not t.has("value"):
        raise t.error("value", "missing (required)")
    value = t.data["value"]
    if isinstance(value, list) and len(value) == 1:
        value = value[0]
    if isinstance(value, str):
        return (_expression(t, value, names),)
    if not is_number(value):
        axes = ", ".join(names)
        raise t.error(
            "value", f"must be one number or one expression of {axes}, got {short(value)}"
        )
    return (t.vector("value", 1, [value])[0],)


def _groups(file: Path, key: str, group: str, geometry: Geometry, dims: Sequence[int]) -> None:
    if group not in geometry.groups:
        raise SceneError(
            file,
            key,
            # a builder's geometry has no file: this line would fail (AttributeError)
            f"unknown physical group '{group}' in {geometry.file.name}"  # type: ignore[union-attr]
            + did_you_mean(group, geometry.groups),
        )
    if geometry.groups[group] not in dims:
        raise SceneError(
            file,
            key,
            f"group '{group}' has dimension {geometry.groups[group]}, "
            f"expected one of {tuple(dims)}",
        )


def _bcs(
    file: Path, raw: Any, geometry: Geometry, exact: ExactSpec | None
) -> tuple[BoundaryCondition, ...]:
    if not isinstance(raw, list):
        raise SceneError(file, "bc", "must be an array of tables ([[bc]])")
    out = []
    for i, entry in enumerate(raw):
        t = _Table(file, f"bc[{i}]", entry, allowed=SECTION_KEYS["bc"])
        group = t.string("group")
        _groups(file, t.path("group"), group, geometry, range(geometry.dim))
        axes = _AXES[: geometry.dim]
        comps = t.data.get("components", list(axes))
        if (
            not isinstance(comps, list)
            or not comps
            or any(c not in axes for c in comps)
            or len(set(comps)) != len(comps)
        ):
            raise t.error(
                "components", f"must be a list of distinct axes from {list(axes)}, got {comps!r}"
            )
        value = _value(t, len(comps), exact)
        if value == "exact" and len(comps) != geometry.dim:
            raise t.error("components", "value 'exact' constrains all components")
        symmetry = t.boolean("symmetry", default=False)
        if symmetry and len(comps) != 1:
            raise t.error(
                "symmetry",
                f"a symmetry condition holds exactly one component (the normal), got {comps!r}",
            )
        if symmetry and geometry.groups[group] != geometry.dim - 1:
            raise t.error(
                "symmetry",
                f"a symmetry condition needs a {'line' if geometry.dim == 2 else 'surface'} "
                f"group (dimension {geometry.dim - 1}); '{group}' has dimension "
                f"{geometry.groups[group]}",
            )
        components = tuple(axes.index(c) for c in comps)
        on, off = _switch_keys(t)
        out.append(BoundaryCondition(group, value, components, bool(symmetry), on, off))  # type: ignore[arg-type]
    return tuple(out)


#: Load types a ``[[load]]`` may name (docs/scenes.md, "Loads").
LOAD_TYPES = ("traction", "body_force", "pressure", "point")


def _loads(file: Path, raw: Any, geometry: Geometry, exact: ExactSpec | None) -> tuple[Load, ...]:
    """``[[load]]`` entries (docs/scenes.md, "Loads").

    traction and body force: gdim numbers or expression texts of x, y[, z], or
    ``"exact"``; pressure: one number or expression on a group of dimension gdim - 1;
    point: gdim numbers on a physical point (dimension 0).
    """
    if not isinstance(raw, list):
        raise SceneError(file, "load", "must be an array of tables ([[load]])")
    out = []
    dim = geometry.dim
    names = _AXES[:dim]
    for i, entry in enumerate(raw):
        t = _Table(file, f"load[{i}]", entry, allowed=SECTION_KEYS["load"])
        kind = t.string("type", choices=LOAD_TYPES)
        group = None
        if kind == "body_force":
            if t.has("group"):
                raise t.error("group", "a body force acts on the whole domain; remove 'group'")
        else:
            group = t.string("group")
            dims = (0,) if kind == "point" else (dim - 1,)
            _groups(file, t.path("group"), group, geometry, dims)
        value: tuple[float | str, ...] | str
        if kind == "pressure":
            value = _pressure(t, names)
        elif kind == "point":
            if t.data.get("value") == "exact":
                raise t.error("value", "'exact' applies to traction and body_force loads")
            value = _value(t, dim, None)
        else:
            value = _value(t, dim, exact, names)
        out.append(Load(kind, value, group, *_switch_keys(t)))  # type: ignore[arg-type]
    return tuple(out)


def _solver(file: Path, raw: Any) -> Solver:
    t = _Table(file, "solver", raw, allowed=SECTION_KEYS["solver"])
    preset = t.string("preset", default="auto", choices=("auto", "direct", "iterative"))
    opts_raw = t.data.get("options", {})
    o = _Table(file, "solver.options", opts_raw, allowed=list(opts_raw))
    options: dict[str, str] = {}
    for k, v in opts_raw.items():
        if k.startswith("-"):
            raise o.error(k, "write PETSc option names without the leading '-'")
        if not isinstance(v, str | int | float):
            raise o.error(k, f"must be a string, number or boolean, got {short(v)}")
        if isinstance(v, int | float) and not isinstance(v, bool):
            o.number(k)  # finite
        options[k] = ("true" if v else "false") if isinstance(v, bool) else str(v)
    return Solver(preset, options)  # type: ignore[arg-type]


def _output(
    file: Path,
    raw: Any,
    name: str,
    dim: int,
    out: Path | None,
    trusted: bool = False,
    driver: str | None = None,
) -> Output:
    """The ``[output]`` table; ``driver``: the declared effect that drives the run, if any."""
    t = _Table(file, "output", raw, allowed=SECTION_KEYS["output"])
    directory = _output_directory(t, name, out, trusted=trusted)
    fields = t.names("fields", OUTPUT_FIELDS, DEFAULT_OUTPUT_FIELDS)
    probes_raw = t.data.get("probes", {})
    p = _Table(file, "output.probes", probes_raw, allowed=list(probes_raw))
    probes = {k: p.vector(k, dim) for k in probes_raw}
    probe_fields = _probe_fields(t, "probe_fields", driver)
    lines_raw = t.data.get("lines", {})
    lt = _Table(file, "output.lines", lines_raw, allowed=list(lines_raw))
    lines = {k: _line(lt, k, dim, driver) for k in lines_raw}
    nominal = t.number("nominal_stress", positive=True)
    if nominal is not None and driver is not None:
        raise t.error(
            "nominal_stress",
            f"effect '{driver}' drives the run: its probes report displacement only",
        )
    every, minutes = checkpoint_keys(t)
    return Output(
        directory,
        tuple(fields),
        t.boolean("xdmf", default=True),
        probes,
        every,
        minutes,
        probe_fields,
        lines,
        None if nominal is None else float(nominal),
    )


def _probe_fields(t: _Table, key: str, driver: str | None) -> tuple[str, ...]:
    """A distinct list of :data:`PROBE_FIELDS` (default displacement only).

    A run driven by an effect's loop (cracking) reports displacement only: its cracked
    cells carry no element stress field.
    """
    value = t.names(key, PROBE_FIELDS, ("displacement",), empty=False)
    if driver is not None and value != ("displacement",):
        raise t.error(
            key,
            f"effect '{driver}' drives the run: only ['displacement'] can be probed "
            "(its cracked cells have no element stress)",
        )
    return value


def _line(lines: _Table, name: str, dim: int, driver: str | None) -> Line:
    """One ``[output.lines.NAME]`` table: a segment of distinct end points."""
    if not is_name(name):
        raise lines.error(
            name,
            "is not a line name: use 1 to 100 letters, digits, '-', '_' or '.', not starting "
            "with '.' (the name becomes lines/<name>.csv)",
        )
    t = _Table(lines.file, lines.path(name), lines.data[name], allowed=LINE_KEYS)
    for key in ("start", "end"):
        if not t.has(key):
            raise t.error(key, "missing (required)")
    start, end = t.vector("start", dim), t.vector("end", dim)
    if start == end:
        raise t.error("end", f"must differ from start, both are {list(start)}")
    points = t.number("points", default=101, integer=True, minimum=2, maximum=MAX_LINE_POINTS)
    return Line(start, end, int(points), _probe_fields(t, "fields", driver))


def _declared(file: Path, data: dict[str, Any]) -> list[str]:
    """The validated ``effects`` list."""
    declared = data.get("effects", [])
    if not isinstance(declared, list) or not all(isinstance(e, str) for e in declared):
        raise SceneError(file, "effects", f"must be a list of effect names, got {declared!r}")
    if len(set(declared)) != len(declared):
        raise SceneError(file, "effects", f"lists an effect twice: {declared}")
    for name in declared:
        if name not in effects.REGISTRY:
            raise SceneError(
                file,
                "effects",
                f"unknown effect '{name}'" + did_you_mean(name, effects.available()),
            )
    return declared


def _effect_table(file: Path, data: dict[str, Any], name: str) -> dict[str, Any]:
    table = data.get(name, {})
    if not isinstance(table, dict):
        raise SceneError(file, name, "must be a table")
    return table


def _effects(
    file: Path,
    data: dict[str, Any],
    declared: list[str],
    geometry: Geometry,
    material: Material,
    discretization: Discretization,
    bcs: tuple[BoundaryCondition, ...],
    configured: dict[str, Any],
    loads: tuple[Load, ...] = (),
    *,
    staged: bool = False,
) -> tuple[EffectSpec, ...]:
    """Configure each declared effect (``configured``: those already done, by name)."""
    ctx = effects.ConfigureContext(
        str(file),
        geometry.dim,
        material,
        discretization.element,
        dict(geometry.groups),
        bcs,
        gradient_bc=discretization.gradient_bc,
        loads=loads,
        staged=staged,
    )
    _check_methods(file, declared, "fem")
    _check_drivers(file, declared)
    specs = []
    for name in declared:
        if name in configured:  # (dfn: configured with the geometry)
            specs.append(EffectSpec(name, configured[name]))
            ctx.previous[name] = configured[name]
            continue
        config = effects.load(name).configure(_effect_table(file, data, name), ctx)
        specs.append(EffectSpec(name, config))
        ctx.previous[name] = config
    return tuple(specs)


def _check_methods(file: Path, declared: Sequence[str], method: str) -> None:
    """Each declared effect must serve ``method`` (its module's ``METHODS``, default fem)."""
    for name in declared:
        methods = getattr(effects.load(name), "METHODS", ("fem",))
        if method not in methods:
            raise SceneError(
                file,
                "effects",
                f"effect '{name}' applies to method {' or '.join(map(repr, methods))}, "
                f"not '{method}'",
            )


def _check_drivers(file: Path, declared: Sequence[str]) -> None:
    """At most one declared effect may bring its own ``driver`` loop.

    Such a loop replaces the single solve: two would each want to be the run.
    """
    owners = [name for name in declared if effects.drives(name)]
    if len(owners) > 1:
        raise SceneError(
            file,
            "effects",
            f"effects {' and '.join(map(repr, owners))} each drive the run with their own "
            "loop; declare only one of them",
        )


def _reject_tables(file: Path, data: dict[str, Any], keys: Sequence[str], message: str) -> None:
    """A SceneError naming the first of ``keys`` present in ``data``."""
    for key in keys:
        if key in data:
            raise SceneError(file, key, message)


def _mpm_scene(
    file: Path,
    data: dict[str, Any],
    declared: list[str],
    common: dict[str, Any],
    out: str | Path | None,
    trusted: bool = False,
) -> Scene:
    """The rest of an ``method = "mpm"`` scene (see :mod:`geofrac.scene.mpm`)."""
    from geofrac.scene.mpm import FEM_ONLY_TABLES, mpm_material, mpm_output, mpm_spec

    _reject_tables(file, data, FEM_ONLY_TABLES, "applies to method 'fem' only; remove it")
    _check_methods(file, declared, "mpm")
    if "mpm" not in data:
        raise SceneError(file, "mpm", "missing (required table for method 'mpm')")
    geometry = _geometry(file, data["geometry"]) if "geometry" in data else None
    spec = mpm_spec(file, data["mpm"], geometry)
    if "material" not in data:
        raise SceneError(file, "material", "missing (required table)")
    material = mpm_material(file, data["material"], spec.dim)
    output = mpm_output(
        file,
        data.get("output", {}),
        common["name"],
        dim=spec.dim,
        out=None if out is None else Path(out),
        trusted=trusted,
    )
    has_bed = bool(spec.bed) or spec.bed_group is not None
    sides = {side: 1 for side in spec.walls} | ({"bed": 1} if has_bed else {})
    ctx = effects.ConfigureContext(str(file), spec.dim, material, "", sides, (), "mpm")
    specs = tuple(
        EffectSpec(n, effects.load(n).configure(_effect_table(file, data, n), ctx))
        for n in declared
    )
    if spec.initial_stress == "geostatic":
        gravity = None
        if "gravity" in declared:  # then its module is already imported
            from geofrac.effects.gravity import GravityConfig

            gravity = effect_config(specs, "gravity", GravityConfig)
        if gravity is None:
            raise SceneError(file, "mpm.initial_stress", "'geostatic' needs the gravity effect")
        g = gravity.acceleration
        if gravity.ramp > 0:
            raise SceneError(
                file,
                "gravity.ramp",
                "'mpm.initial_stress = geostatic' starts with the stress of full gravity; "
                "a ramp would start from none (remove one of them)",
            )
        if any(c != 0 for c in g[:-1]) or not g[-1] < 0:
            raise SceneError(
                file,
                "mpm.initial_stress",
                f"'geostatic' needs gravity along -{'yz'[spec.dim - 2]}, got {list(g)}",
            )
    return Scene(
        **common,
        effects=specs,
        geometry=geometry,
        material=material,
        discretization=None,
        bcs=(),
        loads=(),
        exact=None,
        solver=Solver(),
        output=output,
        raw=data,
        method="mpm",
        mpm=spec,
    )


def _blocks_scene(
    file: Path,
    data: dict[str, Any],
    declared: list[str],
    common: dict[str, Any],
    out: str | Path | None,
    trusted: bool = False,
) -> Scene:
    """The rest of a ``method = "blocks"`` scene (see :mod:`geofrac.scene.blocks`)."""
    from geofrac.scene.blocks import FEM_ONLY_TABLES, blocks_output, blocks_spec

    _reject_tables(file, data, FEM_ONLY_TABLES, "does not apply to method 'blocks'; remove it")
    if declared:
        raise SceneError(file, "effects", "method 'blocks' builds a model and runs no effects")
    if "blocks" not in data:
        raise SceneError(file, "blocks", "missing (required table for method 'blocks')")
    geometry = _geometry(file, data["geometry"]) if "geometry" in data else None
    warnings: list[str] = []
    spec = blocks_spec(file, data["blocks"], geometry, warnings=warnings)
    output = blocks_output(
        file,
        data.get("output", {}),
        common["name"],
        out=None if out is None else Path(out),
        trusted=trusted,
    )
    return Scene(
        **common,
        effects=(),
        geometry=geometry,
        material=None,
        discretization=None,
        bcs=(),
        loads=(),
        exact=None,
        solver=Solver(),
        output=output,
        raw=data,
        warnings=tuple(warnings),
        method="blocks",
        blocks=spec,
    )


def _geometry_from_effect(
    file: Path, data: dict[str, Any], declared: list[str]
) -> tuple[Geometry, dict[str, Any]] | None:
    """The geometry built by a declared effect (one with a ``geometry`` hook), if any."""
    providers = [n for n in declared if hasattr(effects.load(n), "geometry")]
    if not providers:
        return None
    if len(providers) > 1:
        raise SceneError(file, "effects", f"effects {providers} both build the geometry")
    name = providers[0]
    if "geometry" in data:
        raise SceneError(
            file, "geometry", f"effect '{name}' builds the geometry; remove the [geometry] table"
        )
    config, geometry = effects.load(name).geometry(_effect_table(file, data, name), str(file))
    return geometry, {name: config}


def _check_curved(file: Path, geometry: Geometry, element: str, declared: Sequence[str]) -> None:
    """Curved cells (``geometry.order > 1``) need an element that represents them.

    An element represents cells of order k when it is isoparametric or of higher degree
    (``ElementSpec.curved`` and ``degree >= k``): P2 for k = 2, P3 for k <= 3; any other
    fails the patch test there. An effect whose module sets ``STRAIGHT_CELLS`` (cracking:
    MLS-cracked cells assume straight edges) is refused too.

    Raises:
        SceneError: one line naming the element or effect and the fix.
    """
    order = geometry.order
    if order == 1:
        return
    able = [
        n
        for n, spec in elements.REGISTRY.items()
        if spec.curved and spec.degree >= order and geometry.dim in spec.dims
    ]
    name = geometry.file.name if geometry.file is not None else "the geometry"
    curved = f"the curved cells of '{name}' (Mesh.ElementOrder = {order})"
    if not able:
        raise SceneError(file, "geometry.file", f"no element represents {curved}; lower the order")
    if element not in able:
        raise SceneError(
            file,
            "discretization.element",
            f"element '{element}' cannot represent {curved}; use element "
            f"{' or '.join(map(repr, able))}, or Mesh.ElementOrder = 1",
        )
    for effect in declared:
        if getattr(effects.load(effect), "STRAIGHT_CELLS", False):
            raise SceneError(
                file,
                "effects",
                f"effect '{effect}' assumes straight cells, not {curved}; "
                "use Mesh.ElementOrder = 1",
            )


def _warnings(file: Path, material: Material, disc: Discretization, dim: int) -> tuple[str, ...]:
    """Load-time warnings of a valid scene.

    Volumetric locking: in plane strain and 3D, at or above the element's measured
    ``locking_nu`` (docs/stability.md, "Locking"), naming the elements that do not lock
    in that dimension (``locking_nu`` None: P2, P3) as the remedy. The CLI prints them
    once, on rank 0.
    """
    out = []
    constrained = dim == 3 or material.plane == "strain"
    threshold = elements.get(disc.element).locking_nu
    if threshold is not None and constrained and material.nu >= threshold:
        free = [n for n, s in elements.REGISTRY.items() if s.locking_nu is None and dim in s.dims]
        out.append(
            f"{file}: material.nu: {material.nu} with element '{disc.element}' in "
            f"{'3D' if dim == 3 else 'plane strain'} locks volumetrically from nu = "
            f"{threshold} (displacements far too small; docs/stability.md, Locking); use "
            f"element {' or '.join(repr(n) for n in free)}"
        )
    return tuple(out)


def _extent(geometry: Geometry | None) -> Extent | None:
    """Bounding box and mesh sizes of a geometry file, read in gmsh without meshing.

    A geometry whose inspection already carries them (an ``extent`` attribute with the
    fields of :class:`Extent`) is not opened again. Otherwise the file is opened once
    more in this process: only after :func:`_geometry` accepted it (its scan and time
    limit passed with the same parameters), so this open ends as that one did.
    """
    if geometry is None or geometry.file is None:
        return None
    known = getattr(geometry, "extent", None)
    if known is not None:
        return known if isinstance(known, Extent) else Extent(**known)
    from geofrac.meshing.geo import gmsh_session

    try:
        with gmsh_session(geometry.file, geometry.parameters) as gmsh:
            model, option = gmsh.model, gmsh.option
            box = model.getBoundingBox(-1, -1)
            points = model.getEntities(0)
            sizes = [float(v) for v in model.mesh.getSizes(points)] if points else []
            size_max = float(option.getNumber("Mesh.MeshSizeMax"))
            factor = float(option.getNumber("Mesh.MeshSizeFactor"))
            variables = {}
            for name in gmsh.parser.getNames():
                value = gmsh.parser.getNumber(name)
                if len(value) == 1 and math.isfinite(value[0]):
                    variables[name] = float(value[0])
            cells = None
            if geometry.file.suffix == ".msh":
                types, _, _ = model.mesh.getElements(geometry.dim)
                cells = sum(len(model.mesh.getElementsByType(int(t))[0]) for t in types)
    except RuntimeError as exc:
        raise SceneError("", "geometry.file", f"gmsh cannot read the file: {exc}") from None
    return Extent(
        lower=tuple(box[:3]),
        upper=tuple(box[3:]),
        point_size=min((v for v in sizes if v > 0), default=None),
        size_max=size_max if size_max < 1e21 else None,
        size_factor=factor if factor > 0 else 1.0,
        cells=cells,
        variables=variables,
    )


def _with_trial(scene: Scene, extent: Extent | None) -> Extent | None:
    """``extent`` with the cells of trial meshes of the scene's ``.geo`` file, if it takes one.

    The trial (:func:`~geofrac.scene.size.trial_factor`,
    :func:`~geofrac.meshing.geo.trial_counts`) runs in gmsh's child process under a time
    limit of at most :data:`~geofrac.meshing.geo.TRIAL_TIME_LIMIT` seconds; when it fails
    or does not finish, the extent says why and the estimate falls back on the bounding box.
    A DFN scene (no file) gets the extent of its trial meshes (:func:`_dfn_trial`).
    """
    factor = trial_factor(scene, extent)
    if factor is not None and hasattr(getattr(scene.geometry, "builder", None), "trial"):
        return _dfn_trial(scene, factor)
    if factor is None or extent is None:
        return extent
    from geofrac.meshing.geo import TRIAL_TIME_LIMIT, GmshTimeout, trial_counts
    from geofrac.meshing.geo_guard import GeoRefused

    geometry = scene.geometry
    assert geometry is not None and geometry.file is not None  # trial_factor checked
    try:
        meshes = trial_counts(
            geometry.file,
            geometry.parameters,
            geometry.mesh_size,
            dim=geometry.dim,
            factor=factor,
            cells=TRIAL_CELLS,
            time_limit=geometry.time_limit,
            trusted=geometry.trusted,
            algorithm=geometry.algorithm,
        )
    except GmshTimeout:
        limit = min(TRIAL_TIME_LIMIT, geometry.time_limit or TRIAL_TIME_LIMIT)
        failure = f"the trial mesh did not finish within {limit:g} s"
        return dataclasses.replace(extent, trial_failure=failure)
    except (RuntimeError, GeoRefused) as exc:
        text = " ".join(str(exc).split())
        failure = "gmsh failed on the trial mesh" + (f": {text[:80]}" if text else "")
        return dataclasses.replace(extent, trial_failure=failure)
    return dataclasses.replace(extent, trial=tuple(meshes))


def _dfn_trial(scene: Scene, factor: float) -> Extent:
    """The DFN domain's box with the cells of trial meshes of the scene's network.

    The DFN builder (geofrac's own code, in this process, in a gmsh session that is
    finalised whatever happens) generates and cleans the network as a run does and
    meshes it coarsely, first at size factor ``factor``
    (:meth:`~geofrac.effects.dfn.DfnGeometry.trial`). When it fails, the extent says why
    and the estimate falls back on the domain's area.
    """
    from geofrac.dfn.errors import DfnError
    from geofrac.meshing.geo import gmsh_session

    geometry = scene.geometry
    assert geometry is not None and geometry.builder is not None  # a DFN scene
    builder: Any = geometry.builder
    domain = builder.config.domain
    extent = Extent(
        lower=(*(float(v) for v in domain.min(axis=0)), 0.0),
        upper=(*(float(v) for v in domain.max(axis=0)), 0.0),
    )
    try:
        with gmsh_session(None, geometry.parameters, geometry.mesh_size) as gmsh:
            meshes = builder.trial(gmsh, factor, cells=TRIAL_CELLS)
    except (DfnError, RuntimeError) as exc:
        text = " ".join(str(exc).split())
        failure = "the trial mesh failed" + (f": {text[:80]}" if text else "")
        return dataclasses.replace(extent, trial_failure=failure)
    return dataclasses.replace(extent, trial=tuple(meshes))


def load_scene(
    path: str | Path,
    overrides: Sequence[str] = (),
    out: str | Path | None = None,
    *,
    allow_large: bool = False,
    ranks: int = 1,
) -> Scene:
    """Read and validate a scene, and estimate its size.

    Args:
        path: scene TOML file.
        overrides: ``KEY=VALUE`` strings applied before validation.
        out: output directory replacing ``output.dir``.
        allow_large: run a scene beyond the size caps (``--allow-large``); the scene's
            own ``allow_large`` does the same.
        ranks: MPI ranks of the run (the per-rank caps scale with it).

    Raises:
        SceneError: on the first problem found, naming the file and key. Malformed input
            never ends in another exception: a nesting, size or number that Python
            cannot handle becomes a SceneError naming the file.
    """
    file = Path(path)
    try:
        raw_bytes = file.read_bytes()
    except OSError as exc:
        raise SceneError(file, "", f"cannot read scene file: {exc.strerror}") from None
    try:
        data = tomllib.loads(raw_bytes.decode("utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(file, "", f"not valid TOML: {exc}") from None
    except (RecursionError, MemoryError):
        raise SceneError(file, "", "not readable: nested too deeply for the TOML reader") from None
    try:
        apply_overrides(data, overrides, file)
        deep = first_too_deep(data)
        if deep is not None:
            raise SceneError(file, short(deep), f"nested deeper than {MAX_DEPTH} levels")
        trusted = any(o.partition("=")[0].strip() == "output.dir" for o in overrides)
        scene = _validate(file, data, raw_bytes, overrides, out, trusted)
        scene = dataclasses.replace(
            scene,
            allow_large=scene.allow_large or allow_large,
            size=estimate(scene, _with_trial(scene, _extent(scene.geometry))),
            overrides=tuple(overrides),
            description=marked_description(scene.description, overrides),
            units=_units(file, data.get("units", {})),
        )
        check_size(file, scene.size, ranks, allow=scene.allow_large)
    except SceneError as exc:
        if not exc.file:  # raised without the file (the gmsh extent)
            raise SceneError(file, exc.key, exc.message) from None
        raise
    except (
        RecursionError,
        MemoryError,
        OverflowError,
        ValueError,
        TypeError,
        LookupError,
    ) as exc:  # malformed input that a check above missed: still one line, exit 2
        kind = type(exc).__name__
        raise SceneError(file, "", f"malformed input ({kind}: {short(str(exc))})") from None
    return scene


def _validate(
    file: Path,
    data: dict[str, Any],
    raw_bytes: bytes,
    overrides: Sequence[str],
    out: str | Path | None,
    trusted: bool,
) -> Scene:
    """Validate parsed ``data`` (see :func:`load_scene`); the size is not yet estimated."""
    digest = hashlib.sha256(raw_bytes + json.dumps(list(overrides)).encode()).hexdigest()

    declared = data.get("effects", [])
    for key in data:
        if key in TOP_LEVEL_KEYS:
            continue
        if key in effects.REGISTRY and isinstance(declared, list) and key not in declared:
            raise SceneError(
                file, key, f"configures effect '{key}', which 'effects' does not declare"
            )
        if key not in effects.REGISTRY:
            raise SceneError(
                file,
                key,
                "unknown key" + did_you_mean(key, [*TOP_LEVEL_KEYS, *effects.available()]),
            )
    top = _Table(
        file, "", {k: v for k, v in data.items() if k in TOP_LEVEL_KEYS}, allowed=TOP_LEVEL_KEYS
    )
    schema = top.number("schema", default=SCHEMA_VERSION, integer=True)
    if schema != SCHEMA_VERSION:
        raise top.error("schema", f"this geofrac reads schema {SCHEMA_VERSION}, got {schema}")
    name = check_name(file, top.string("name", default=file.stem), given=top.has("name"))
    description = top.string("description", default="")
    method = top.string("method", default="fem", choices=METHODS)
    allow_large = top.boolean("allow_large", default=False)
    declared = _declared(file, data)
    if method in ("mpm", "blocks"):
        common = {
            "path": file.resolve(),
            "sha256": digest,
            "name": name,
            "description": description,
            "allow_large": allow_large,
        }
        build = _mpm_scene if method == "mpm" else _blocks_scene
        return build(file, data, declared, common, out, trusted)
    for key in ("mpm", "blocks"):
        if key in data:
            raise SceneError(file, key, f"applies to method '{key}' only; set method = \"{key}\"")
    provided = _geometry_from_effect(file, data, declared)
    for section in ("geometry", "material", "discretization"):
        if section not in data and not (section == "geometry" and provided):
            raise SceneError(file, section, "missing (required table)")

    geometry, configured = provided or (_geometry(file, data["geometry"]), {})
    material = _material(file, data["material"], geometry.dim)
    discretization = _discretization(file, data["discretization"], geometry.dim)
    if discretization.renumber is not None:
        geometry = dataclasses.replace(geometry, renumber=discretization.renumber)
    _check_curved(file, geometry, discretization.element, declared)
    exact = _exact(file, data["exact"], geometry) if "exact" in data else None
    bcs = _bcs(file, data.get("bc", []), geometry, exact)
    if not bcs:
        raise SceneError(
            file, "bc", "no Dirichlet condition: the elastic problem would be singular"
        )
    loads = _loads(file, data.get("load", []), geometry, exact)
    solver = _solver(file, data.get("solver", {}))
    output = _output(
        file,
        data.get("output", {}),
        name,
        geometry.dim,
        None if out is None else Path(out),
        trusted,
        next((e for e in declared if effects.drives(e)), None),
    )
    if "initial_stress" in data and "stages" not in data:
        _cracking_variable(file, declared, bcs=bcs, loads=loads)
    specs = _effects(
        file,
        data,
        declared,
        geometry,
        material,
        discretization,
        bcs,
        configured,
        loads,
        staged="stages" in data,
    )
    initial = None
    if "initial_stress" in data:
        initial = _initial_stress(
            file,
            data["initial_stress"],
            geometry=geometry,
            material=material,
            element=discretization.element,
            specs=specs,
        )
    for spec in specs:  # the plastic ground reaction curve reads the probes and p0
        if spec.name == "plasticity":
            check = effects.load("plasticity").check_scene
            check(
                spec.config,
                file=str(file),
                probes=output.probes,
                initial=initial,
                fields=output.fields,
                effects=tuple(other.name for other in specs),
                staged="stages" in data,
            )
    _switches(file, _stage_names(data.get("stages")), bcs=bcs, loads=loads, declared=declared)
    stages: tuple[Stage, ...] = ()
    if "stages" in data:
        stages = _stages(
            file,
            data["stages"],
            geometry=geometry,
            element=discretization.element,
            declared=declared,
            material=material,
            switched=_switched(bcs, loads),
            initial=initial is not None,
            bcs=bcs,
            loads=loads,
        )
    joints = tuple(
        j.name for e in specs if e.name in ("plasticity", "joints") for j in e.config.joints
    )
    if joints:  # the mesh is cut along the joints before it is distributed
        geometry = dataclasses.replace(geometry, split=joints)
    return Scene(
        initial_stress=initial,
        stages=stages,
        warnings=_warnings(file, material, discretization, geometry.dim),
        path=file.resolve(),
        sha256=digest,
        name=name,
        description=description,
        effects=specs,
        geometry=geometry,
        material=material,
        discretization=discretization,
        bcs=bcs,
        loads=loads,
        exact=exact,
        solver=solver,
        output=output,
        raw=data,
        allow_large=allow_large,
    )
