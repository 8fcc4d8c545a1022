"""Effect ``dfn``: a discrete fracture network embedded in a meshed 2D rock mass.

The effect builds the scene's geometry (a scene with ``dfn`` has no ``[geometry]``
table): a rectangle or polygon, fracture sets generated from seeded statistical laws (or
a network read from a CSV/JSON file), cleaned by the tolerance rules of
:mod:`geofrac.dfn.clean` and meshed by gmsh so that every fracture is a chain of element
edges (:mod:`geofrac.meshing.dfn`). Edo (2016), §2.5, eq. (2.28), Table 2.1. The full table
reference is in docs/dfn.md and docs/scenes.md.

Validation (:func:`configure`) is cheap and imports no gmsh; a network file is read and
checked then, so a malformed file fails before any heavy work.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from geofrac.dfn.errors import DfnError
from geofrac.dfn.io import load_network
from geofrac.dfn.polygon import (
    as_polygon,
    clip_segments,
    point_segment_distance,
    points_in_polygon,
    polygon_area,
    rectangle,
)
from geofrac.dfn.regions import (
    Region,
    RegionLayout,
    circle_polygon,
    cut_polygon,
    horseshoe_polygon,
    layout_regions,
)
from geofrac.dfn.sampling import FractureSet, Network, generate_network
from geofrac.meshing.dfn import ALGORITHMS, DOMAIN_GROUP, FRACTURE_GROUP, OUTLINE_SUFFIX, MeshSpec
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.table import MAX_INTEGER, finite, short

if TYPE_CHECKING:
    from geofrac.effects import ConfigureContext

__all__ = [
    "CIRCLE_KEYS",
    "HORSESHOE_KEYS",
    "RECTANGLE_CORNERS",
    "RECTANGLE_SIDES",
    "REGION_KEYS",
    "SET_KEYS",
    "TABLE_KEYS",
    "DfnConfig",
    "DfnGeometry",
    "configure",
    "geometry",
    "result",
]

#: Keys of the ``[dfn]`` table and of each ``[[dfn.sets]]`` entry.
TABLE_KEYS = (
    "domain",
    "polygon",
    "region",
    "seed",
    "sets",
    "file",
    "mesh_size",
    "fracture_mesh_size",
    "transition",
    "tolerance",
    "algorithm",
    "regions",
)
#: Keys of each ``[dfn.regions.NAME]`` table and of its ``circle`` / ``horseshoe`` shape.
REGION_KEYS = ("polygon", "circle", "horseshoe", "mesh_size")
CIRCLE_KEYS = ("centre", "radius", "segments", "above", "below")
HORSESHOE_KEYS = ("centre", "width", "wall_height", "segments", "above", "below")
SET_KEYS = (
    "name",
    "mean",
    "variance",
    "std",
    "kappa",
    "distribution",
    "lmin",
    "lmax",
    "exponent",
    "count",
    "p21",
)
#: Physical group names of a rectangular domain's sides and corners (counter-clockwise
#: from the lower-left corner); a polygon's are ``side_<k>`` and ``corner_<k>``.
RECTANGLE_SIDES = ("bottom", "right", "top", "left")
RECTANGLE_CORNERS = ("lower_left", "lower_right", "upper_right", "upper_left")


@dataclass(frozen=True)
class DfnConfig:
    """Validated ``[dfn]`` settings.

    Attributes:
        domain: rock mass polygon, counter-clockwise, shape=(m, 2).
        region: polygon in which fracture centres are drawn, shape=(k, 2).
        sides: physical group name of each domain side, shape=(m,).
        corners: physical group name of each domain corner, shape=(m,).
        sets: fracture sets to generate (empty when ``network`` is given).
        seed: random seed.
        network: a network read from ``file``, or None.
        file: the network file, or None.
        mesh: element sizes and algorithm.
        tolerance: cleaning tolerance (length).
        regions: named cell regions (``[dfn.regions]``), or None.
    """

    domain: np.ndarray
    region: np.ndarray
    sides: tuple[str, ...]
    corners: tuple[str, ...]
    sets: tuple[FractureSet, ...]
    seed: int
    network: Network | None
    file: Path | None
    mesh: MeshSpec
    tolerance: float
    regions: RegionLayout | None = None

    def make_network(self) -> Network:
        """The network: read from the file, or generated (seeded, deterministic)."""
        if self.network is not None:
            return self.network
        return generate_network(self.sets, self.region, self.seed, domain=self.domain)


@dataclass(frozen=True)
class DfnGeometry:
    """Builds the gmsh model of a ``dfn`` scene (called on one rank by the mesher).

    Attributes:
        config: the validated settings.
    """

    config: DfnConfig

    @property
    def name(self) -> str:
        """Name used in messages."""
        return "dfn"

    def describe(self, report: dict[str, Any]) -> str:
        """One progress line from a :meth:`build` report (plus the cover check)."""
        cleaning = ", ".join(
            f"{k} {v}" for k, v in report["cleaning"].items() if v and k != "passes"
        )
        regions = ", ".join(f"{k} {v}" for k, v in report.get("region_cells", {}).items())
        return (
            f"dfn: {report['fractures']} fractures ({report['fractures_meshed']} meshed), "
            f"P21 {report['p21']:.4g}; cleaning: {cleaning or 'nothing'}; "
            f"gmsh: {report['nodes']} nodes, {report['cells']} triangles, "
            f"{report.get('fracture_facets', report['fracture_edges'])} fracture edges, "
            f"min angle {report['min_angle_deg']:.1f}°, shortest edge "
            f"{report['shortest_edge']:.3g} ({report['time_mesh_s']:.1f} s)"
            + (f"; region triangles: {regions}" if regions else "")
        )

    def build(self, gmsh: ModuleType) -> tuple[dict[str, Any], Any]:
        """Generate, clean and mesh the network in an initialised gmsh session.

        Returns:
            (report, clean network): mesh counts and quality, network statistics and
            cleaning events (JSON-ready), and the :class:`~geofrac.dfn.clean.CleanNetwork`.

        Raises:
            DfnError: the network cannot be cleaned.
            RuntimeError: gmsh failed.
        """
        import time

        from geofrac.meshing.dfn import mesh_network

        cfg = self.config
        network, clean, times = self._network()
        t2 = time.perf_counter()
        quality = mesh_network(
            gmsh, clean, cfg.sides, corners=cfg.corners, spec=cfg.mesh, regions=cfg.regions
        )
        t3 = time.perf_counter()
        area = polygon_area(cfg.domain)
        report = {
            "fractures": len(network),
            "fractures_meshed": int(np.count_nonzero(clean.length > 0)),
            "p21": float(clean.clipped_length.sum() / area),
            "p21_meshed": float(clean.length.sum() / area),
            "cleaning": clean.report.counts(),
            "max_moved": float(clean.moved[np.isfinite(clean.moved)].max(initial=0.0)),
            "min_junction_angle_deg": clean.min_junction_angle(),
            **times,
            "time_mesh_s": t3 - t2,
            "sets": _set_report(clean, area),
            **quality,
        }
        return report, clean

    def trial(self, gmsh: ModuleType, factor: float, *, cells: float) -> list[tuple[float, int]]:
        """Triangles of coarse trial meshes of the model :meth:`build` makes (the size estimate).

        The network is generated and cleaned as by :meth:`build` (the same seed or file),
        the model built with the same sizes, fields and algorithm, and meshed with every
        size multiplied by k >= 1 (:func:`geofrac.meshing.dfn.trial_network`): first
        k = ``factor``, then finer until a mesh has about ``cells`` / 2 triangles or more.

        Returns:
            (k, triangles) of every mesh made, in order.

        Raises:
            DfnError: the network cannot be cleaned.
            RuntimeError: gmsh failed.
        """
        from geofrac.meshing.dfn import trial_network
        from geofrac.meshing.geo import failure_message

        cfg = self.config
        _, clean, _ = self._network()
        try:
            return trial_network(
                gmsh,
                clean,
                cfg.sides,
                corners=cfg.corners,
                spec=cfg.mesh,
                regions=cfg.regions,
                factor=factor,
                cells=cells,
            )
        except Exception as exc:
            if type(exc) is not Exception:  # gmsh raises bare Exceptions; a bug stays a bug
                raise
            raise RuntimeError(failure_message(exc, gmsh) or "gmsh failed") from exc

    def _network(self) -> tuple[Network, Any, dict[str, float]]:
        """The network, cleaned (a ``CleanNetwork``), and the seconds each step took.

        Raises:
            DfnError: the network cannot be cleaned, or nothing of it is left in the domain.
        """
        import time

        from geofrac.dfn.clean import clean_network

        cfg = self.config
        t0 = time.perf_counter()
        network = cfg.make_network()
        t1 = time.perf_counter()
        constraints = cfg.regions.segments if cfg.regions is not None else None
        clean = clean_network(network, cfg.domain, cfg.tolerance, constraints=constraints)
        t2 = time.perf_counter()
        if len(clean.edges) == 0:
            raise DfnError(
                f"no fracture of the network ({len(network)} fractures) is left inside the "
                f"domain after cleaning ({clean.report.summary()}); check the domain, region "
                "and density"
            )
        return network, clean, {"time_generate_s": t1 - t0, "time_clean_s": t2 - t1}


def _set_report(clean: Any, area: float) -> dict[str, dict[str, float | int | None]]:
    """Per fracture set: its fractures, P21 (clipped to the domain) and mean orientation.

    ``clean``: the :class:`~geofrac.dfn.clean.CleanNetwork`; ``area``: the domain's. The
    mean is the axial mean of the traces' directions in degrees (None for a set without
    fractures); what the result block compares with the set's ``p21`` and ``mean``.
    """
    from geofrac.dfn.stats import axial_mean_deg

    network = clean.network
    out: dict[str, dict[str, float | int | None]] = {}
    for k, name in enumerate(network.set_names):
        mine = network.set_index == k
        angles = network.angles_deg[mine]
        out[name] = {
            "fractures": int(mine.sum()),
            "p21": float(clean.clipped_length[mine].sum() / area),
            "mean_deg": axial_mean_deg(angles) if len(angles) else None,
        }
    return out


def result(config: DfnConfig, scene: Any, results: dict[str, Any]) -> list[str]:
    """The result block's lines: the fractures, and each set's P21 and mean orientation.

    Each set's achieved values (the geometry report's ``sets``) against the set's
    ``p21`` and ``mean`` when the scene gives them (a network read from a file has
    none); P21 in 1/length of the scene's units.
    """
    from geofrac.headline import quantity, versus

    geometry = results.get("geometry")
    if geometry is None or "sets" not in geometry:
        return []
    length = scene.units.of("length")
    per_length = f"1/{length}" if length else ""
    lines = [
        f"dfn: {geometry['fractures']} fractures ({geometry['fractures_meshed']} meshed), "
        f"P21 {quantity(geometry['p21'], per_length)}"
    ]
    targets = {s.name: s for s in config.sets}
    for name, got in geometry["sets"].items():
        target = targets.get(name)
        text = f"set {name}: {got['fractures']} fractures, P21 {quantity(got['p21'], per_length)}"
        if target is not None and target.p21 is not None:
            text += f" (target {target.p21:g}; {versus(got['p21'], target.p21, per_length)})"
        lines.append(text)
        if got["mean_deg"] is None:
            continue
        text = f"set {name}: mean orientation {quantity(got['mean_deg'], 'deg')}"
        if target is not None:
            # axial: the achieved mean taken to within 90° of the set's
            mean = target.mean_deg + (got["mean_deg"] - target.mean_deg + 90.0) % 180.0 - 90.0
            text += f" (set's {target.mean_deg:g} deg; {versus(mean, target.mean_deg, 'deg')})"
        lines.append(text)
    return lines


def _error(file: str, key: str, message: str) -> SceneError:
    return SceneError(file, f"dfn.{key}" if key else "dfn", message)


def _check_keys(file: str, prefix: str, table: Any, allowed: tuple[str, ...]) -> dict[str, Any]:
    if not isinstance(table, dict):
        raise _error(file, prefix, f"must be a table, got {type(table).__name__}")
    for key in table:
        if key not in allowed:
            where = f"{prefix}.{key}" if prefix else key
            raise _error(file, where, "unknown key" + did_you_mean(key, allowed))
    return table


def _number(file: str, key: str, value: Any, positive: bool = False) -> float:
    if not isinstance(value, int | float) or isinstance(value, bool) or not finite(value):
        raise _error(file, key, f"must be a finite number, got {short(value)}")
    if positive and value <= 0:
        raise _error(file, key, f"must be > 0, got {value!r}")
    return float(value)


def _polygon(file: str, key: str, value: Any, kinds: tuple[str, ...]) -> np.ndarray:
    """A rectangle ``[x0, y0, x1, y1]`` and/or a polygon ``[[x, y], ...]`` (``kinds``)."""
    four_numbers = (
        isinstance(value, list)
        and len(value) == 4
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    )
    expected = " or ".join(
        {"rectangle": "a rectangle [x0, y0, x1, y1]", "polygon": "a list of [x, y] corners"}[k]
        for k in kinds
    )
    try:
        if four_numbers and "rectangle" in kinds:
            x0, y0, x1, y1 = (float(v) for v in value)
            return rectangle((x0, y0), (x1, y1))
        if "polygon" in kinds and not four_numbers:
            return as_polygon(np.asarray(value, dtype=float))
    except (DfnError, ValueError, TypeError, OverflowError) as exc:
        raise _error(file, key, f"must be {expected}: {short(str(exc))}") from None
    raise _error(file, key, f"must be {expected}, got {short(value)}")


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    """Distance between polygons ``a`` and ``b`` (each shape=(m, 2)); 0 when they meet."""
    edges_a = np.stack([a, np.roll(a, -1, axis=0)], axis=1)
    edges_b = np.stack([b, np.roll(b, -1, axis=0)], axis=1)
    if points_in_polygon(a, b).any() or points_in_polygon(b, a).any():
        return 0.0
    if len(clip_segments(edges_a, b)[0]):
        return 0.0
    d_ab, _ = point_segment_distance(a[:, None, :], edges_b[None, :, 0], edges_b[None, :, 1])
    d_ba, _ = point_segment_distance(b[:, None, :], edges_a[None, :, 0], edges_a[None, :, 1])
    return float(min(d_ab.min(), d_ba.min()))


def _fracture_set(file: str, i: int, raw: Any) -> FractureSet:
    key = f"sets[{i}]"
    t = _check_keys(file, key, raw, SET_KEYS)
    for required in ("mean", "lmin", "lmax", "exponent"):
        if required not in t:
            raise _error(file, f"{key}.{required}", "missing (required)")
    distribution = t.get("distribution", "normal")
    if distribution not in ("normal", "von_mises"):
        raise _error(
            file,
            f"{key}.distribution",
            f"unknown value {distribution!r}"
            + did_you_mean(str(distribution), ["normal", "von_mises"]),
        )
    spread_keys = ("variance", "std") if distribution == "normal" else ("kappa",)
    given = [k for k in ("variance", "std", "kappa") if k in t]
    if len(given) != 1 or given[0] not in spread_keys:
        raise _error(
            file,
            key,
            f"a {distribution} set needs exactly one of {', '.join(spread_keys)}, got {given}",
        )
    spread = _number(file, f"{key}.{given[0]}", t[given[0]])
    if spread < 0:
        raise _error(file, f"{key}.{given[0]}", f"must be >= 0, got {spread!r}")
    if given[0] == "variance":
        spread = math.sqrt(spread)
    density = [k for k in ("count", "p21") if k in t]
    if len(density) != 1:
        raise _error(file, key, f"give exactly one density, 'count' or 'p21', got {density}")
    count = t.get("count")
    if count is not None and (
        not isinstance(count, int) or isinstance(count, bool) or not 0 <= count <= MAX_INTEGER
    ):
        raise _error(file, f"{key}.count", f"must be an integer >= 0, got {short(count)}")
    p21 = None if "p21" not in t else _number(file, f"{key}.p21", t["p21"])
    name = t.get("name", f"set{i + 1}")
    if not isinstance(name, str) or not name or "," in name:
        raise _error(
            file, f"{key}.name", f"must be a non-empty string without commas, got {name!r}"
        )
    try:
        return FractureSet(
            name=name,
            mean_deg=_number(file, f"{key}.mean", t["mean"]),
            spread=spread,
            lmin=_number(file, f"{key}.lmin", t["lmin"]),
            lmax=_number(file, f"{key}.lmax", t["lmax"]),
            exponent=_number(file, f"{key}.exponent", t["exponent"]),
            distribution=distribution,
            count=count,
            p21=p21,
        )
    except DfnError as exc:
        raise _error(file, key, str(exc)) from None


def _integer(file: str, key: str, value: Any, low: int, high: int) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
        raise _error(file, key, f"must be an integer in [{low}, {high}], got {short(value)}")
    return value


def _point(file: str, key: str, value: Any) -> tuple[float, float]:
    if not isinstance(value, list) or len(value) != 2:
        raise _error(file, key, f"must be [x, y], got {short(value)}")
    return _number(file, f"{key}[0]", value[0]), _number(file, f"{key}[1]", value[1])


def _shape(file: str, key: str, kind: str, raw: Any, side: float) -> np.ndarray:
    """A ``circle`` or ``horseshoe`` table as a polygon (``side``: the default side length)."""
    t = _check_keys(file, key, raw, CIRCLE_KEYS if kind == "circle" else HORSESHOE_KEYS)
    needed = ("centre", "radius") if kind == "circle" else ("centre", "width", "wall_height")
    for name in needed:
        if name not in t:
            raise _error(file, f"{key}.{name}", "missing (required)")
    centre = _point(file, f"{key}.centre", t["centre"])
    cuts = [k for k in ("above", "below") if k in t]
    if len(cuts) > 1:
        raise _error(file, key, "give at most one of 'above', 'below'")
    level = _number(file, f"{key}.{cuts[0]}", t[cuts[0]]) if cuts else None
    try:
        if kind == "circle":
            radius = _number(file, f"{key}.radius", t["radius"], positive=True)
            default = min(1000, max(32, 4 * math.ceil(2 * math.pi * radius / (4 * side))))
            segments = _integer(file, f"{key}.segments", t.get("segments", default), 3, 1000)
            poly = circle_polygon(centre, radius, segments, level=level)
        else:
            width = _number(file, f"{key}.width", t["width"], positive=True)
            wall = _number(file, f"{key}.wall_height", t["wall_height"], positive=True)
            default = min(1000, max(16, 2 * math.ceil(math.pi * width / (4 * side))))
            segments = _integer(file, f"{key}.segments", t.get("segments", default), 2, 1000)
            poly = horseshoe_polygon(centre, width, wall, segments=segments, level=level)
        if cuts:
            poly = cut_polygon(poly, float(level), keep=cuts[0])  # type: ignore[arg-type]
    except DfnError as exc:
        raise _error(file, f"{key}.{cuts[0]}" if cuts else key, str(exc)) from None
    return poly


def _regions(
    file: str, raw: Any, reserved: set[str], *, mesh: MeshSpec, tolerance: float
) -> list[Region]:
    """The ``[dfn.regions.NAME]`` tables, in the order given.

    A circle's or horseshoe's default number of sides makes each side about the outline's
    mesh size, but at least 4 × the cleaning tolerance: a fracture crossing the outline
    is bent through an outline vertex within the tolerance of it, so short sides would
    bend (and shorten) more fractures.
    """
    if not isinstance(raw, dict) or not raw:
        raise _error(file, "regions", f"must be a table of named regions, got {short(raw)}")
    out = []
    for name, spec in raw.items():
        key = f"regions.{name}"
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", name) or name in reserved:
            raise _error(
                file,
                key,
                f"region name {name!r} must be an identifier and differ from the groups "
                f"{sorted(reserved)} and the fracture sets",
            )
        t = _check_keys(file, key, spec, REGION_KEYS)
        size = mesh.fracture_size
        if "mesh_size" in t:
            size = _number(file, f"{key}.mesh_size", t["mesh_size"], positive=True)
            if size > mesh.size:
                raise _error(
                    file, f"{key}.mesh_size", f"must not exceed mesh_size ({mesh.size}), got {size}"
                )
        shapes = [k for k in ("polygon", "circle", "horseshoe") if k in t]
        if len(shapes) != 1:
            raise _error(file, key, "give exactly one of 'polygon', 'circle', 'horseshoe'")
        if shapes[0] == "polygon":
            poly = _polygon(file, f"{key}.polygon", t["polygon"], ("polygon",))
        else:
            side = max(size, 4.0 * tolerance)
            poly = _shape(file, f"{key}.{shapes[0]}", shapes[0], t[shapes[0]], side)
        out.append(Region(name, poly, size))
    return out


def _configure(table: dict[str, Any], file: str) -> DfnConfig:
    t = _check_keys(file, "", table, TABLE_KEYS)
    shapes = [k for k in ("domain", "polygon") if k in t]
    if len(shapes) != 1:
        raise _error(file, "domain", "give exactly one of 'domain' (rectangle) or 'polygon'")
    if shapes[0] == "domain":
        domain = _polygon(file, "domain", t["domain"], ("rectangle",))
        sides: tuple[str, ...] = RECTANGLE_SIDES
        corners: tuple[str, ...] = RECTANGLE_CORNERS
    else:
        domain = _polygon(file, "polygon", t["polygon"], ("polygon",))
        m = len(domain)
        sides = tuple(f"side_{k + 1}" for k in range(m))
        corners = tuple(f"corner_{k + 1}" for k in range(m))
    region = (
        _polygon(file, "region", t["region"], ("rectangle", "polygon")) if "region" in t else domain
    )
    if "mesh_size" not in t:
        raise _error(file, "mesh_size", "missing (required)")
    size = _number(file, "mesh_size", t["mesh_size"], positive=True)
    fracture_size = _number(
        file, "fracture_mesh_size", t.get("fracture_mesh_size", size), positive=True
    )
    if fracture_size > size:
        raise _error(
            file, "fracture_mesh_size", f"must not exceed mesh_size ({size}), got {fracture_size}"
        )
    transition = _number(file, "transition", t.get("transition", 10.0 * size), positive=True)
    tolerance = _number(file, "tolerance", t.get("tolerance", fracture_size / 4), positive=True)
    if tolerance >= fracture_size:
        raise _error(
            file,
            "tolerance",
            f"must be smaller than the element size on fractures ({fracture_size}), got "
            f"{tolerance}",
        )
    algorithm = t.get("algorithm", "frontal-delaunay")
    if algorithm not in ALGORITHMS:
        raise _error(
            file, "algorithm", f"unknown {algorithm!r}" + did_you_mean(str(algorithm), ALGORITHMS)
        )
    diameter = float(np.hypot(*np.ptp(domain, axis=0)))
    if diameter / size > 5000:
        raise _error(
            file, "mesh_size", f"{size} gives over 5000 elements across the domain; too fine"
        )
    network, path = None, None
    sets: tuple[FractureSet, ...] = ()
    if "file" in t:
        if "sets" in t:
            raise _error(file, "file", "give either 'file' (a saved network) or 'sets', not both")
        if not isinstance(t["file"], str):
            raise _error(file, "file", f"must be a path string, got {t['file']!r}")
        path = (Path(file).resolve().parent / t["file"]).resolve()
        try:
            network = load_network(path)
        except DfnError as exc:
            raise _error(file, "file", str(exc)) from None
    else:
        raw_sets = t.get("sets")
        if not isinstance(raw_sets, list) or not raw_sets:
            raise _error(file, "sets", "missing: give at least one [[dfn.sets]] or a 'file'")
        sets = tuple(_fracture_set(file, i, s) for i, s in enumerate(raw_sets))
        names = [s.name for s in sets]
        if len(set(names)) != len(names):
            raise _error(file, "sets", f"set names must differ, got {names}")
        gap = _distance(region, domain)
        if gap >= max(s.lmax for s in sets) / 2:
            raise _error(
                file,
                "region",
                f"lies {gap:g} from the domain, farther than half the longest fracture: "
                "no fracture centred in it can reach the domain",
            )
    seed = t.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed <= MAX_INTEGER:
        raise _error(file, "seed", f"must be an integer in [0, 2^63), got {short(seed)}")
    spec = MeshSpec(size, fracture_size, transition, algorithm)
    layout = None
    if "regions" in t:
        reserved = {DOMAIN_GROUP, FRACTURE_GROUP, *sides, *corners, *(s.name for s in sets)}
        regions = _regions(file, t["regions"], reserved, mesh=spec, tolerance=tolerance)
        outlines = {r.name + OUTLINE_SUFFIX for r in regions}
        clash = outlines & (reserved | {r.name for r in regions})
        if clash:
            raise _error(file, "regions", f"the outline group {sorted(clash)[0]!r} is taken")
        try:
            layout = layout_regions(regions, domain, tol=tolerance, margin=size)
        except DfnError as exc:
            raise _error(file, "regions", str(exc)) from None
    return DfnConfig(
        domain=domain,
        region=region,
        sides=sides,
        corners=corners,
        sets=sets,
        seed=seed,
        network=network,
        file=path,
        mesh=spec,
        tolerance=tolerance,
        regions=layout,
    )


def geometry(table: dict[str, Any], file: str) -> tuple[DfnConfig, Any]:
    """Validate ``[dfn]`` and return (config, :class:`~geofrac.model.scene.Geometry`).

    The geometry is 2D with physical groups ``domain``, the sides, the corners and
    ``fractures``, and per region its name (cells) and ``<name>_outline`` (curves); its
    builder is a :class:`DfnGeometry`.

    Raises:
        SceneError: naming the offending ``dfn.*`` key.
    """
    from geofrac.model.scene import Geometry

    config = _configure(table, file)
    groups = {DOMAIN_GROUP: 2, FRACTURE_GROUP: 1}
    groups |= dict.fromkeys(config.sides, 1) | dict.fromkeys(config.corners, 0)
    for name in config.regions.names if config.regions is not None else ():
        groups |= {name: 2, name + OUTLINE_SUFFIX: 1}
    return config, Geometry(
        file=None,
        parameters={},
        mesh_size=config.mesh.size,
        dim=2,
        groups=groups,
        builder=DfnGeometry(config),
    )


def configure(table: dict[str, Any], ctx: ConfigureContext) -> DfnConfig:
    """Validate ``[dfn]`` (the scene loader calls :func:`geometry` instead)."""
    return _configure(table, ctx.file)
