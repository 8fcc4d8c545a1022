"""Validate ``[initial_stress]`` and ``[[stages]]`` of an FEM scene (docs/scenes.md).

Every key is checked here, before any mesh is built; the physics is in
:mod:`geofrac.geometry.insitu` (the field) and :mod:`geofrac.fem.stages` (the run).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from pathlib import Path
from typing import Any

from geofrac import effects, elements
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.scene import EffectSpec, Geometry, InitialStress, Material, Stage, effect_config
from geofrac.model.table import Table, check_name, is_number, short

__all__ = [
    "INITIAL_STRESS_KEYS",
    "KINDS",
    "MAX_K0",
    "STAGE_KEYS",
    "STAGE_MATERIAL_KEYS",
    "cracking_variable",
    "initial_stress",
    "stages",
]

#: Keys of ``[initial_stress]``.
INITIAL_STRESS_KEYS = ("kind", "stress", "surface", "density", "K0", "tectonic", "loaded")
#: Keys of one ``[[stages]]`` entry.
STAGE_KEYS = ("name", "remove", "relaxation", "add", "material")
#: Keys of a stage's ``material`` (the added groups').
STAGE_MATERIAL_KEYS = ("E", "nu", "density", "tensile_strength")
#: Kinds of initial stress.
KINDS = ("constant", "geostatic")
#: Largest K0 accepted (the horizontal stress at most this many times the vertical).
MAX_K0 = 10.0
#: Largest stress magnitude accepted (any unit system).
MAX_STRESS = 1e15
#: Most stages of one scene.
MAX_STAGES = 1000
#: Slack on the cumulative relaxation share (a sum of decimal fractions such as 0.4 + 0.6
#: is not exactly 1 in floating point).
SHARE_SLACK = 1e-9
#: The problem class of the elements that take an initial stress and stages.
_LAGRANGE = "geofrac.fem.elastic:ElasticProblem"


def _tensor(t: Table, key: str, dim: int) -> tuple[float, ...]:
    """A stress in Voigt order: 3 numbers in 2D (xx, yy, xy), 6 in 3D."""
    names = "[xx, yy, xy]" if dim == 2 else "[xx, yy, zz, xy, yz, xz]"
    value = t.data[key]
    n = 3 if dim == 2 else 6
    if not isinstance(value, list) or len(value) != n or not all(map(is_number, value)):
        raise t.error(key, f"must be a list of {n} numbers {names} (tension positive)")
    out = t.vector(key, n)
    for i, c in enumerate(out):
        if abs(c) > MAX_STRESS:
            raise t.error(key, f"entry {i} must be at most {MAX_STRESS:g} in magnitude, got {c!r}")
    return out


def _surface(t: Table, dim: int) -> float | tuple[tuple[float, float], ...]:
    """A level, or in 2D a polyline of [x, y] points with x strictly increasing."""
    if not t.has("surface"):
        raise t.error("surface", "missing (required by kind 'geostatic': the ground surface)")
    value = t.data["surface"]
    if is_number(value):
        return float(t.number("surface"))  # type: ignore[arg-type]
    if dim == 3:
        raise t.error(
            "surface", f"must be a number (the level z of the ground), got {short(value)}"
        )
    if (
        not isinstance(value, list)
        or len(value) < 2
        or not all(isinstance(p, list) and len(p) == 2 and all(map(is_number, p)) for p in value)
    ):
        raise t.error(
            "surface",
            f"must be a number (the level y of the ground) or a list of at least two [x, y] "
            f"points, got {short(value)}",
        )
    points = [t.vector("surface", 2, p) for p in value]
    for i in range(1, len(points)):
        if not points[i][0] > points[i - 1][0]:
            raise t.error(
                "surface", f"point {i}: x must increase strictly along the polyline, got {points}"
            )
    return tuple((p[0], p[1]) for p in points)


def _group_numbers(
    t: Table, key: str, geometry: Geometry, *, maximum: float, positive: bool
) -> dict[str, float]:
    """A table cell group -> number."""
    raw = t.data.get(key, {})
    sub = Table(t.file, t.path(key), raw, allowed=list(raw) if isinstance(raw, dict) else ())
    out = {}
    for group in raw:
        _cell_group(sub, group, geometry)
        value = sub.number(group, required=True, positive=positive, minimum=0.0, maximum=maximum)
        out[group] = float(value)  # type: ignore[arg-type]
    return out


def _cell_group(t: Table, group: str, geometry: Geometry, key: str | None = None) -> None:
    """``group`` must be a cell group (dimension gdim) of the geometry."""
    where = group if key is None else key
    if group not in geometry.groups:
        raise t.error(
            where,
            f"unknown physical group '{group}'" + did_you_mean(group, list(geometry.groups)),
        )
    if geometry.groups[group] != geometry.dim:
        raise t.error(
            where,
            f"group '{group}' has dimension {geometry.groups[group]}; a cell group "
            f"(dimension {geometry.dim}) is needed",
        )


def _gravity(file: Path, specs: Sequence[EffectSpec[object]], dim: int) -> float:
    """The magnitude g of the ``gravity`` effect, which must point down the vertical axis."""
    gravity = None
    if any(s.name == "gravity" for s in specs):
        from geofrac.effects.gravity import GravityConfig

        gravity = effect_config(specs, "gravity", GravityConfig)
    if gravity is None:
        raise SceneError(
            file,
            "initial_stress.kind",
            "'geostatic' needs the gravity effect (effects = [\"gravity\"]): its body force "
            "ρ g is what the geostatic stress balances",
        )
    g = gravity.acceleration
    axis = "yz"[dim - 2]
    if any(c != 0 for c in g[:-1]) or not g[-1] < 0:
        raise SceneError(
            file,
            "gravity.acceleration",
            f"'initial_stress.kind = geostatic' needs gravity along -{axis}, got {list(g)}",
        )
    return -g[-1]


def _element(file: Path, key: str, element: str) -> None:
    """Initial stress and stages are assembled for the Lagrange elements only."""
    if elements.get(element).problem != _LAGRANGE:
        able = [n for n, s in elements.REGISTRY.items() if s.problem == _LAGRANGE]
        raise SceneError(
            file,
            key,
            f"needs a Lagrange element ({', '.join(able)}); element '{element}' is not "
            "supported with an initial stress or stages yet",
        )


def _no_driver(file: Path, key: str, declared: Sequence[str]) -> None:
    """Initial stress and stages are elastic analyses: no effect may own the run."""
    owners = [n for n in declared if effects.drives(n)]
    if owners:
        raise SceneError(
            file,
            key,
            f"effect '{owners[0]}' drives the run with its own loop, which "
            + (
                "does not run construction stages yet"
                if key == "stages"
                else "does not start from an initial stress yet"
            )
            + "; remove one of them",
        )


def _cracking(file: Path, element: str, specs: Sequence[EffectSpec[object]]) -> None:
    """A cracking scene takes an initial stress at element edges (with contact too).

    The initial stress joins the constant load of the event loop (docs/cracking.md,
    "An initial stress"); the other effects that drive a run do not take it.
    """
    from geofrac.fracture.config import CrackingConfig

    others = [s.name for s in specs if s.name != "cracking"]
    _no_driver(file, "initial_stress", others)
    spec = elements.get(element)
    if spec.cracking != "edges":
        able = [n for n, s in elements.REGISTRY.items() if s.cracking == "edges"]
        raise SceneError(
            file,
            "initial_stress",
            f"cracking with an initial stress needs an element cracked at its edges "
            f"({', '.join(able)}); '{element}' cracks grain interfaces, which do not take "
            "an initial stress yet",
        )
    config = effect_config(specs, "cracking", CrackingConfig)
    assert config is not None
    if config.fracture_energy is not None:
        raise SceneError(
            file,
            "initial_stress",
            "cohesive faces (material.fracture_energy) do not take an initial stress yet",
        )


def cracking_variable(
    file: Path, declared: Sequence[str], *, bcs: Sequence[Any], loads: Sequence[Any]
) -> None:
    """A cracking scene with an initial stress needs a load that scales.

    The initial stress (and gravity) stay constant through the events; each event scales
    the control group's load, a non-zero prescribed displacement or a traction, pressure
    or point load. Called before the effects are configured, so that the message names
    the initial stress.
    """
    if "cracking" not in declared:
        return
    moving = any(bc.value == "exact" or any(v != 0 for v in bc.value) for bc in bcs)
    forces = any(ld.type in ("traction", "pressure", "point") for ld in loads)
    if not moving and not forces:
        raise SceneError(
            file,
            "initial_stress",
            "a cracking scene with an initial stress needs a variable load: the initial "
            "stress (and gravity) is held constant and each event scales the control "
            "group's load; add a [[bc]] with a non-zero displacement or a traction, "
            "pressure or point [[load]], or excavate with [[stages]] (the release drives "
            "the events)",
        )


def initial_stress(
    file: Path,
    raw: Any,
    *,
    geometry: Geometry,
    material: Material,
    element: str,
    specs: Sequence[EffectSpec[object]],
) -> InitialStress:
    """The validated ``[initial_stress]`` table.

    Raises:
        SceneError: naming the key, for any bad entry.
    """
    t = Table(file, "initial_stress", raw, allowed=INITIAL_STRESS_KEYS)
    dim = geometry.dim
    if any(s.name == "cracking" for s in specs):
        _cracking(file, element, specs)
    else:
        _element(file, "initial_stress", element)
        # the FEM plasticity loop starts from the initial stress (docs/plasticity.md)
        _no_driver(file, "initial_stress", [s.name for s in specs if s.name != "plasticity"])
    kind = t.string("kind", choices=KINDS)
    loaded = _loaded(t, geometry)
    tectonic = _tensor(t, "tectonic", dim) if t.has("tectonic") else None
    if kind == "constant":
        for key in ("surface", "density", "K0"):
            if t.has(key):
                raise t.error(key, "applies to kind 'geostatic' only")
        if tectonic is not None:
            raise t.error("tectonic", "applies to kind 'geostatic'; add it to 'stress'")
        if not t.has("stress"):
            raise t.error("stress", "missing (required by kind 'constant')")
        return InitialStress("constant", stress=_tensor(t, "stress", dim), loaded=loaded)
    if t.has("stress"):
        raise t.error("stress", "applies to kind 'constant' only (use 'tectonic' to add one)")
    surface = _surface(t, dim)
    densities = _group_numbers(t, "density", geometry, maximum=1e6, positive=True)
    k0 = material.nu / (1.0 - material.nu)
    if isinstance(t.data.get("K0"), int | float) and not isinstance(t.data.get("K0"), bool):
        k0s: dict[str, float] = {}  # one K0 for every group
        k0 = float(t.number("K0", required=True, minimum=0.0, maximum=MAX_K0))  # type: ignore[arg-type]
    else:
        k0s = _group_numbers(t, "K0", geometry, maximum=MAX_K0, positive=False)
    cells = [g for g, d in geometry.groups.items() if d == dim]
    if material.density is None and any(g not in densities for g in cells):
        raise SceneError(
            file,
            "material.density",
            "kind 'geostatic' needs the density: material.density, or "
            "initial_stress.density for every cell group",
        )
    density = material.density if material.density is not None else 0.0
    if dim == 3 and any(v != density for v in densities.values()):
        raise t.error(
            "density", "a density per group is supported in 2D only; in 3D use one density"
        )
    return InitialStress(
        "geostatic",
        surface=surface,
        gravity=_gravity(file, specs, dim),
        density=float(density),
        densities=densities,
        k0=k0,
        k0s=k0s,
        tectonic=tectonic,
        loaded=loaded,
    )


def _loaded(t: Table, geometry: Geometry) -> tuple[str, ...]:
    """``loaded``: distinct side groups (dimension gdim - 1)."""
    value = t.data.get("loaded", [])
    if (
        not isinstance(value, list)
        or not all(isinstance(g, str) for g in value)
        or len(set(value)) != len(value)
    ):
        raise t.error("loaded", f"must be a list of distinct side group names, got {short(value)}")
    for group in value:
        if group not in geometry.groups:
            raise t.error(
                "loaded",
                f"unknown physical group '{group}'" + did_you_mean(group, list(geometry.groups)),
            )
        if geometry.groups[group] != geometry.dim - 1:
            raise t.error(
                "loaded",
                f"group '{group}' has dimension {geometry.groups[group]}; a side group "
                f"(dimension {geometry.dim - 1}) is needed",
            )
    return tuple(value)


def _staged_cracking(
    file: Path, raw: list[Any], *, initial: bool, bcs: Sequence[Any], loads: Sequence[Any]
) -> None:
    """A cracking scene takes stages that remove cells, and add them back, from an initial stress.

    The stages' release is the only load that varies (docs/insitu.md, "Stages in a
    cracking scene"); the element and the crack settings were checked with
    ``[initial_stress]``. Added groups must have been removed first, and their material
    is weightless.
    """
    if not initial:
        raise SceneError(
            file,
            "stages",
            "a cracking scene with [[stages]] needs an [initial_stress]: the events are "
            "driven by the release of the stress that the removed cells carried",
        )
    moving = [bc.group for bc in bcs if bc.value == "exact" or any(v != 0 for v in bc.value)]
    fixed = [ld for ld in loads if ld.switch_on is None]
    if moving or fixed:
        what = (
            f"[[bc]] '{moving[0]}' prescribes a displacement"
            if moving
            else "[[load]] acting from the initial state (switch it on at a stage: 'from')"
        )
        raise SceneError(
            file,
            "stages",
            f"a cracking scene with [[stages]] is driven by the stages' release only; its {what}, "
            "which staged cracking does not take yet (hold the far sides or load them by "
            "σ0·n with initial_stress.loaded)",
        )
    for i, ld in enumerate(loads):
        if ld.type not in ("traction", "pressure") or ld.value == "exact":
            raise SceneError(
                file,
                f"load[{i}].type",
                f"a cracking scene's stages switch traction or pressure loads with a number "
                f"value only, got type '{ld.type}'"
                + (" with value 'exact'" if ld.value == "exact" else ""),
            )
    absent = _absent_at_start(raw)
    for i, entry in enumerate(raw):
        if not isinstance(entry, dict):
            continue
        for group in entry.get("add", []) if isinstance(entry.get("add"), list) else []:
            if group in absent:
                raise SceneError(
                    file,
                    f"stages[{i}].add",
                    f"group '{group}' is added before any stage removed it; a cracking "
                    "scene installs support only where a stage excavated (the initial "
                    "stress is that of the whole mesh): remove it in an earlier stage",
                )
        material = entry.get("material")
        if isinstance(material, dict) and "density" in material:
            raise SceneError(
                file,
                f"stages[{i}].material.density",
                "a cracking scene's installed support is weightless (its weight would "
                "be a load the staged loop does not take yet): leave density out",
            )


def _staged_plastic(
    file: Path, raw: list[Any], *, bcs: Sequence[Any], loads: Sequence[Any]
) -> None:
    """What the plastic stages do not run yet: ``add`` and switched loads or supports."""
    for i, entry in enumerate(raw):
        if isinstance(entry, dict) and "add" in entry:
            raise SceneError(
                file,
                f"stages[{i}].add",
                "the plastic stages only remove cell groups (and release a share); adding "
                "groups (a lining) is not supported with plasticity yet",
            )
    for kind, entries in (("bc", bcs), ("load", loads)):
        for i, e in enumerate(entries):
            if e.switch_on is not None or e.switch_off is not None:
                raise SceneError(
                    file,
                    f"{kind}[{i}].{'from' if e.switch_on is not None else 'until'}",
                    "loads and supports switched at stages are not supported with "
                    "plasticity yet: they act throughout (the loads ramped before the stages)",
                )


def stages(
    file: Path,
    raw: Any,
    *,
    geometry: Geometry,
    element: str,
    declared: Sequence[str],
    material: Material | None = None,
    switched: Collection[str] = (),
    initial: bool = False,
    bcs: Sequence[Any] = (),
    loads: Sequence[Any] = (),
) -> tuple[Stage, ...]:
    """The validated ``[[stages]]`` entries.

    The relaxation shares are checked in order: a removal starts a new release (share
    0); each stage applies ``relaxation`` of it, or, without ``relaxation``, all that
    remains; the shares of one release must not add up to more than 1. A stage that
    only adds groups, or only switches loads or supports (its name is in ``switched``,
    :mod:`geofrac.scene.switches`), may apply nothing. A cracking scene (``declared``
    has ``cracking``) needs ``initial`` (an ``[initial_stress]``), no ``bcs`` that move
    and only traction or pressure ``loads`` switched on at a stage (``from``); the
    groups its stages add must have been removed by an earlier stage, and their
    ``material`` has no density (the support is weightless) and may have a
    ``tensile_strength`` (only a cracking scene's may).

    Raises:
        SceneError: naming the stage and key.
    """
    if not isinstance(raw, list) or not raw:
        raise SceneError(file, "stages", "must be a non-empty array of tables ([[stages]])")
    if len(raw) > MAX_STAGES:
        raise SceneError(file, "stages", f"at most {MAX_STAGES} stages, got {len(raw)}")
    if "cracking" in declared:
        _staged_cracking(file, raw, initial=initial, bcs=bcs, loads=loads)
    else:
        _element(file, "stages", element)
        # the FEM plasticity loop runs the stages (docs/plasticity.md, "Construction stages")
        _no_driver(file, "stages", [d for d in declared if d != "plasticity"])
    if "plasticity" in declared:
        _staged_plastic(file, raw, bcs=bcs, loads=loads)
    cells = [g for g, d in geometry.groups.items() if d == geometry.dim]
    absent = _absent_at_start(raw)
    removed: set[str] = set(absent)
    names: set[str] = set()
    share: float | None = None  # of the pending release; None: nothing removed yet
    out = []
    for i, entry in enumerate(raw):
        t = Table(file, f"stages[{i}]", entry, allowed=STAGE_KEYS)
        name = check_name(file, t.string("name"), given=True)
        if name in names:
            raise t.error("name", f"stage '{name}' is named twice")
        names.add(name)
        remove = _removed(t, geometry, removed)
        removed.update(remove)
        add = _added(t, geometry, removed)
        removed.difference_update(add)
        if all(g in removed for g in cells):
            raise t.error("remove", "removes every cell group: no body would be left")
        support = _stage_material(t, material, cracking="cracking" in declared) if add else None
        if t.has("material") and not add:
            raise t.error("material", "is the material of the groups in 'add'; add some")
        if remove:
            share = 0.0
        relaxation = t.number("relaxation", minimum=0.0, maximum=1.0)
        if share is None:
            if relaxation is not None or not (add or name in switched):
                raise t.error(
                    "relaxation" if relaxation is not None else "remove",
                    "no cells have been removed yet: a stage releases the forces of removed cells",
                )
        elif relaxation is None:
            if share >= 1.0 - SHARE_SLACK and not (remove or add or name in switched):
                raise t.error(
                    "relaxation", "the release of the last removal is already fully applied"
                )
            share = 1.0
        else:
            if relaxation <= 0.0:
                raise t.error("relaxation", f"must be > 0, got {relaxation!r}")
            share += relaxation
            if share > 1.0 + SHARE_SLACK:
                raise t.error(
                    "relaxation",
                    f"the shares of the release since the last removal add up to {share:.6g} > 1",
                )
        rel = None if relaxation is None else float(relaxation)
        out.append(Stage(name, remove, rel, add, support))
    return tuple(out)


def _absent_at_start(raw: list[Any]) -> set[str]:
    """Groups a stage adds before any stage removed them: absent until they are added."""
    seen: set[str] = set()
    absent: set[str] = set()
    for entry in raw:
        if not isinstance(entry, dict):
            continue
        for group in entry.get("remove", []) if isinstance(entry.get("remove"), list) else []:
            seen.add(group)
        for group in entry.get("add", []) if isinstance(entry.get("add"), list) else []:
            if group not in seen and isinstance(group, str):
                absent.add(group)
            seen.add(group)
    return absent


def _added(t: Table, geometry: Geometry, removed: set[str]) -> tuple[str, ...]:
    """``add``: distinct cell groups not in the body at this stage."""
    value = t.data.get("add", [])
    if (
        not isinstance(value, list)
        or not all(isinstance(g, str) for g in value)
        or len(set(value)) != len(value)
    ):
        raise t.error("add", f"must be a list of distinct cell group names, got {short(value)}")
    for group in value:
        _cell_group(t, group, geometry, key="add")
        if group not in removed:
            raise t.error("add", f"group '{group}' is in the body already (remove it first)")
    return tuple(value)


def _stage_material(t: Table, scene_material: Material | None, *, cracking: bool) -> Material:
    """A stage's ``material``: E and ν required, density optional (0: weightless).

    ``tensile_strength`` (a cracking scene only): the support's edges are crack sites.
    """
    if not t.has("material"):
        raise t.error("material", "missing (required with 'add': the added groups' E and nu)")
    m = Table(t.file, t.path("material"), t.data["material"], allowed=STAGE_MATERIAL_KEYS)
    E = m.number("E", required=True, positive=True, maximum=1e15)
    nu = m.number("nu", required=True)
    assert E is not None and nu is not None
    if not -1.0 < nu < 0.5:
        raise m.error("nu", f"must lie in (-1, 0.5), got {nu!r}")
    plane = scene_material.plane if scene_material is not None else "stress"
    thickness = scene_material.thickness if scene_material is not None else 1.0
    density = m.number("density", positive=True, maximum=1e6)
    strength = m.number("tensile_strength", positive=True, maximum=1e15)
    if strength is not None and not cracking:
        raise m.error(
            "tensile_strength",
            "applies to a cracking scene (the support's edges crack at it); an elastic "
            "scene has no crack sites",
        )
    return Material(
        E=float(E),
        nu=float(nu),
        plane=plane,
        thickness=thickness,
        density=density,
        tensile_strength=strength,
    )


def _removed(t: Table, geometry: Geometry, removed: set[str]) -> tuple[str, ...]:
    """``remove``: distinct cell groups not removed by an earlier stage."""
    value = t.data.get("remove", [])
    if (
        not isinstance(value, list)
        or not all(isinstance(g, str) for g in value)
        or len(set(value)) != len(value)
    ):
        raise t.error("remove", f"must be a list of distinct cell group names, got {short(value)}")
    for group in value:
        _cell_group(t, group, geometry, key="remove")
        if group in removed:
            raise t.error("remove", f"group '{group}' was removed by an earlier stage")
    return tuple(value)
