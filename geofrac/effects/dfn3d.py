"""Effect ``dfn3d``: a 3D disc fracture network cutting a box of rock, meshed conformingly.

The effect builds the scene's geometry (a scene with ``dfn3d`` has no ``[geometry]``
table): a box, disc fracture sets drawn from seeded laws (:mod:`geofrac.dfn3d.sampling`:
Fisher poles, truncated power-law radii, uniform centres, P32 or a count) or a network
read from a file (:mod:`geofrac.dfn3d.io`), cleaned and meshed by gmsh's OpenCASCADE
kernel so that every fracture is a surface of triangles inside the tetrahedral mesh
(:mod:`geofrac.meshing.dfn3d`). The groups are ``rock`` (the volume), ``xmin``, ``xmax``,
``ymin``, ``ymax``, ``zmin``, ``zmax`` (the box's faces), ``fractures`` (every fracture)
and one surface group per set, named by the set: a ``[plasticity.joints.NAME]`` table on
a set's group (or on ``fractures``) makes those fractures joints with Coulomb springs
(docs/dfn3d.md).

Scene table ``[dfn3d]``:

- ``box``: ``[xmin, ymin, zmin, xmax, ymax, zmax]``, required;
- ``[[dfn3d.sets]]``: ``name``, ``trend`` and ``plunge`` (degrees) of the mean pole,
  ``kappa`` (Fisher's κ, > 0; default: every pole the mean), ``radius_min``,
  ``radius_max``, ``alpha`` (the power law's exponent, default 2.5), exactly one of
  ``p32`` (fracture area per unit volume in the box) and ``count``, and ``region`` (a box
  for the centres, default the box); or ``file``: a network file (CSV, JSON, or a
  ``.dat``/``.txt`` list of ``x y z nx ny nz r``);
- ``seed`` (default 0);
- ``mesh_size`` (required), ``fracture_mesh_size`` (default ``mesh_size``), ``transition``
  (default ``mesh_size``), ``tolerance`` (default a quarter of ``fracture_mesh_size``),
  ``algorithm3d`` (``delaunay``, default, or ``hxt``; gmsh's Frontal ignores embedded
  surfaces, so it is not offered).

Validation (:func:`configure`) is cheap and imports no gmsh; a network file is read then.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from geofrac.dfn.errors import DfnError
from geofrac.dfn3d.network import DiscNetwork
from geofrac.dfn3d.sampling import DiscSet
from geofrac.model.errors import SceneError, did_you_mean
from geofrac.model.table import MAX_INTEGER, finite, short

if TYPE_CHECKING:
    from geofrac.effects import ConfigureContext

__all__ = [
    "ALGORITHMS",
    "FACES",
    "SET_KEYS",
    "TABLE_KEYS",
    "Dfn3dConfig",
    "Dfn3dGeometry",
    "configure",
    "geometry",
    "result",
]

#: Keys of the ``[dfn3d]`` table and of each ``[[dfn3d.sets]]`` entry.
TABLE_KEYS = (
    "box",
    "sets",
    "file",
    "seed",
    "mesh_size",
    "fracture_mesh_size",
    "transition",
    "tolerance",
    "algorithm3d",
)
SET_KEYS = (
    "name",
    "trend",
    "plunge",
    "kappa",
    "radius_min",
    "radius_max",
    "alpha",
    "p32",
    "count",
    "region",
)
#: The box faces' groups, and the other groups the mesher makes.
FACES = ("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")
#: The 3D algorithms a scene may name.
ALGORITHMS = ("delaunay", "hxt")
#: Most elements across the box at ``mesh_size`` (beyond: refused as too fine).
MAX_ACROSS = 2000


@dataclass(frozen=True)
class Dfn3dConfig:
    """Validated ``[dfn3d]`` settings.

    Attributes:
        box: the domain, shape=(6,).
        sets: the sets to draw (empty with a file).
        network: the network read from ``file``, or None.
        file: the network file, or None.
        seed: the random seed.
        mesh_size: element size away from the fractures.
        fracture_mesh_size: element size on the fractures.
        transition: distance over which the size grows back to ``mesh_size``.
        tolerance: the cleaning tolerance (length).
        algorithm3d: gmsh's 3D algorithm.
    """

    box: np.ndarray
    sets: tuple[DiscSet, ...]
    network: DiscNetwork | None
    file: Path | None
    seed: int
    mesh_size: float
    fracture_mesh_size: float
    transition: float
    tolerance: float
    algorithm3d: str

    def make_network(self) -> DiscNetwork:
        """The network: read from the file, or drawn (seeded, deterministic)."""
        from geofrac.dfn3d.sampling import sample_network

        if self.network is not None:
            return self.network
        return sample_network(self.sets, box=self.box, seed=self.seed)

    @property
    def set_names(self) -> tuple[str, ...]:
        """The sets' names (a file's: those it names)."""
        if self.network is not None:
            return self.network.set_names
        return tuple(s.name for s in self.sets)


@dataclass(frozen=True)
class Dfn3dGeometry:
    """Builds the gmsh model of a ``dfn3d`` scene (called on one rank by the mesher).

    Attributes:
        settings: the validated settings.
    """

    settings: Dfn3dConfig

    @property
    def name(self) -> str:
        """Name used in messages."""
        return "dfn3d"

    @property
    def size_key(self) -> str:
        """The scene key that sets the cell count."""
        return "dfn3d.fracture_mesh_size"

    def describe(self, report: dict[str, Any]) -> str:
        """One progress line from a :meth:`build` report."""
        cleaning = report.get("cleaning") or {}
        counts = cleaning.get("counts", {}) if isinstance(cleaning, dict) else {}
        cleaned = ", ".join(f"{k} {v}" for k, v in counts.items() if v)
        return (
            f"dfn3d: {report['fractures']} fractures ({report['fractures_inside']} in the box, "
            f"{report['pieces']} pieces), P32 {report['p32']:.4g}; cleaning: "
            f"{cleaned or 'nothing'}; gmsh: {report['nodes']} nodes, {report['tetrahedra']} "
            f"tetrahedra, {report['fracture_triangles']} fracture triangles, min dihedral "
            f"{report['min_dihedral_deg']:.1f}°, max aspect ratio "
            f"{report['max_aspect_ratio']:.3g} ({report['time_mesh_s']:.1f} s)"
        )

    def build(self, gmsh: ModuleType) -> tuple[dict[str, Any], Any]:
        """Draw (or read), clean and mesh the network in an initialised gmsh session.

        Returns:
            (report, None): the mesher's report (counts, cleaning, quality, times) with
            the network's statistics per set (``sets``, :func:`geofrac.dfn3d.stats.network_summary`)
            and its P32 in the box.

        Raises:
            DfnError: the network cannot be drawn.
            ValueError: gmsh failed (the step and the fractures it named).
        """
        import time

        from geofrac.dfn3d.sampling import network_p32
        from geofrac.dfn3d.stats import network_summary
        from geofrac.meshing.dfn3d import mesh_discs

        cfg = self.settings
        t0 = time.perf_counter()
        network = cfg.make_network()
        t1 = time.perf_counter()
        report = mesh_discs(
            gmsh,
            network,
            box=cfg.box.reshape(2, 3),
            mesh_size=cfg.mesh_size,
            fracture_mesh_size=cfg.fracture_mesh_size,
            algorithm3d=cfg.algorithm3d,
            tolerance=cfg.tolerance,
            transition=cfg.transition,
        )
        report["time_generate_s"] = t1 - t0
        report["p32"] = network_p32(network, cfg.box)
        report["sets"] = network_summary(network, cfg.box, cfg.sets)
        return report, None

    def estimate_cells(self) -> float:
        """Tetrahedra expected: 6√2 per h³, with the fractures' band at the finer sizes.

        The mesher's size (:mod:`geofrac.meshing.dfn3d`) is h_f within h_f of a fracture,
        growing linearly to h over the transition t beyond: per unit of fracture area
        (A: the sets' P32 times the volume, or the discs' area) that band holds
        2/h_f² + t (1/h_f² − 1/h²)/(h − h_f) cells per 6√2 on its two sides, in place
        of the 2 (h_f + t)/h³ the coarse size would give.
        """
        cfg = self.settings
        lo, hi = cfg.box[:3], cfg.box[3:]
        volume = float(np.prod(hi - lo))
        h, hf, t = cfg.mesh_size, cfg.fracture_mesh_size, cfg.transition
        area = 0.0
        for s in cfg.sets:
            if s.p32 is not None:
                area += s.p32 * volume
            else:
                area += (s.count or 0) * math.pi * _mean_square_radius(s)
        if cfg.network is not None:
            area = float(np.sum(cfg.network.area()))
        growth = 2.0 * t / h**2 if h - hf <= 1e-12 * h else t * (1 / hf**2 - 1 / h**2) / (h - hf)
        band = 2.0 / hf**2 + growth - 2.0 * (hf + t) / h**3
        return 6.0 * math.sqrt(2.0) * max(volume / h**3 + area * band, 1.0)


def _mean_square_radius(s: DiscSet) -> float:
    """E[r²] of the truncated power law P(R > r) ∝ r^−α − rmax^−α on [rmin, rmax]."""
    from geofrac.dfn3d.stats import power_law_radius_moment

    return float(power_law_radius_moment(2, rmin=s.radius_min, rmax=s.radius_max, alpha=s.alpha))


def result(config: Dfn3dConfig, scene: Any, results: dict[str, Any]) -> list[str]:
    """The result block's lines: the fractures, and each set's P32, κ̂ and mean pole.

    Each against the set's targets and sampling bands (:func:`geofrac.dfn3d.stats.network_summary`).
    """
    from geofrac.headline import quantity, versus

    report = results.get("geometry")
    if report is None or "sets" not in report or "pieces" not in report:
        return []
    length = scene.units.of("length")
    per_length = f"1/{length}" if length else ""
    lines = [
        f"dfn3d: {report['fractures']} fractures ({report['fractures_inside']} in the box), "
        f"P32 {quantity(report['p32'], per_length)}; mesh: {report['tetrahedra']} tetrahedra, "
        f"min dihedral angle {report['min_dihedral_deg']:.1f} deg, max aspect ratio "
        f"{report['max_aspect_ratio']:.3g}"
    ]
    for name, got in report["sets"].items():
        text = f"set {name}: {got['count']} fractures, P32 {quantity(got['p32'], per_length)}"
        if got.get("p32_target") is not None:
            text += f" ({versus(got['p32'], got['p32_target'], per_length)} from the target)"
        lines.append(text)
        if got.get("kappa_hat") is not None and got.get("kappa_band") is not None:
            low, high = got["kappa_band"]
            inside = "inside" if got.get("kappa_in_band") else "OUTSIDE"
            cone = "inside" if got.get("mean_in_band") else "OUTSIDE"
            lines.append(
                f"set {name}: Fisher κ̂ {got['kappa_hat']:.4g} (set's κ {got['kappa']:.4g}, "
                f"99 % sampling band {low:.4g} to {high:.4g}: {inside}); mean pole "
                f"{got['mean_angle_deg']:.3g} deg from the set's (band "
                f"{got['mean_band_deg']:.3g} deg: {cone})"
            )
    return lines


def _error(file: str, key: str, message: str) -> SceneError:
    return SceneError(file, f"dfn3d.{key}" if key else "dfn3d", message)


def _number(file: str, key: str, value: Any, *, positive: bool = False) -> float:
    if not isinstance(value, int | float) or isinstance(value, bool) or not finite(value):
        raise _error(file, key, f"must be a finite number, got {short(value)}")
    if positive and value <= 0:
        raise _error(file, key, f"must be > 0, got {value!r}")
    return float(value)


def _box(file: str, key: str, value: Any) -> np.ndarray:
    if not isinstance(value, list) or len(value) != 6:
        raise _error(file, key, f"must be [xmin, ymin, zmin, xmax, ymax, zmax], got {short(value)}")
    box = np.array([_number(file, f"{key}[{i}]", v) for i, v in enumerate(value)])
    if np.any(box[3:] <= box[:3]):
        raise _error(file, key, f"needs xmin < xmax, ymin < ymax, zmin < zmax, got {value}")
    return box


def _check_keys(file: str, prefix: str, table: Any, allowed: tuple[str, ...]) -> dict[str, Any]:
    if not isinstance(table, dict):
        raise _error(file, prefix, f"must be a table, got {type(table).__name__}")
    for key in table:
        if key not in allowed:
            where = f"{prefix}.{key}" if prefix else key
            raise _error(file, where, "unknown key" + did_you_mean(key, allowed))
    return table


def _disc_set(file: str, i: int, raw: Any) -> DiscSet:
    key = f"sets[{i}]"
    t = _check_keys(file, key, raw, SET_KEYS)
    for required in ("name", "trend", "plunge", "radius_min"):
        if required not in t:
            raise _error(file, f"{key}.{required}", "missing (required)")
    if ("p32" in t) == ("count" in t):
        raise _error(file, key, "give exactly one of 'p32' and 'count'")
    rmin = _number(file, f"{key}.radius_min", t["radius_min"], positive=True)
    count = t.get("count")
    if count is not None and (
        not isinstance(count, int) or isinstance(count, bool) or not 0 <= count <= 10**6
    ):
        raise _error(
            file, f"{key}.count", f"must be an integer in [0, 1000000], got {short(count)}"
        )
    region = t.get("region")
    try:
        return DiscSet(
            name=t["name"],
            trend=_number(file, f"{key}.trend", t["trend"]),
            plunge=_number(file, f"{key}.plunge", t["plunge"]),
            kappa=_number(file, f"{key}.kappa", t["kappa"], positive=True)
            if "kappa" in t
            else math.inf,
            radius_min=rmin,
            radius_max=_number(file, f"{key}.radius_max", t.get("radius_max", rmin), positive=True),
            alpha=_number(file, f"{key}.alpha", t.get("alpha", 2.5), positive=True),
            p32=None if "p32" not in t else _number(file, f"{key}.p32", t["p32"]),
            count=count,
            region=None if region is None else tuple(_box(file, f"{key}.region", region)),
        )
    except DfnError as exc:
        raise _error(file, key, str(exc)) from None


def _configure(table: dict[str, Any], file: str) -> Dfn3dConfig:
    t = _check_keys(file, "", table, TABLE_KEYS)
    if "box" not in t:
        raise _error(file, "box", "missing (required)")
    box = _box(file, "box", t["box"])
    if "mesh_size" not in t:
        raise _error(file, "mesh_size", "missing (required)")
    size = _number(file, "mesh_size", t["mesh_size"], positive=True)
    fracture = _number(file, "fracture_mesh_size", t.get("fracture_mesh_size", size), positive=True)
    if fracture > size:
        raise _error(
            file, "fracture_mesh_size", f"must not exceed mesh_size ({size}), got {fracture}"
        )
    if float(np.max(box[3:] - box[:3])) / fracture > MAX_ACROSS:
        raise _error(
            file,
            "fracture_mesh_size",
            f"{fracture} gives over {MAX_ACROSS} elements across the box; too fine",
        )
    transition = _number(file, "transition", t.get("transition", size), positive=True)
    tolerance = _number(file, "tolerance", t.get("tolerance", fracture / 4), positive=True)
    if tolerance >= fracture:
        raise _error(
            file,
            "tolerance",
            f"must be smaller than fracture_mesh_size ({fracture}), got {tolerance}",
        )
    algorithm = t.get("algorithm3d", "delaunay")
    if algorithm not in ALGORITHMS:
        raise _error(
            file, "algorithm3d", f"unknown {algorithm!r}" + did_you_mean(str(algorithm), ALGORITHMS)
        )
    seed = t.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or not 0 <= seed <= MAX_INTEGER:
        raise _error(file, "seed", f"must be an integer in [0, 2^63), got {short(seed)}")
    network: DiscNetwork | None = None
    path: Path | None = None
    sets: tuple[DiscSet, ...] = ()
    if "file" in t:
        if "sets" in t:
            raise _error(file, "file", "give either 'file' or 'sets', not both")
        if not isinstance(t["file"], str):
            raise _error(file, "file", f"must be a path string, got {short(t['file'])}")
        from geofrac.dfn3d.io import load_discs

        path = (Path(file).resolve().parent / t["file"]).resolve()
        try:
            network = load_discs(path)
        except DfnError as exc:
            raise _error(file, "file", str(exc)) from None
        names = network.set_names
    else:
        raw = t.get("sets")
        if not isinstance(raw, list) or not raw:
            raise _error(file, "sets", "missing: give at least one [[dfn3d.sets]] or a 'file'")
        sets = tuple(_disc_set(file, i, s) for i, s in enumerate(raw))
        names = tuple(s.name for s in sets)
        if len(set(names)) != len(names):
            raise _error(file, "sets", f"set names must differ, got {list(names)}")
    clash = set(names) & {"rock", "fractures", *FACES}
    if clash:
        raise _error(file, "sets", f"the set name {sorted(clash)[0]!r} is a group name of the box")
    return Dfn3dConfig(
        box=box,
        sets=tuple(sets),
        network=network,
        file=path,
        seed=seed,
        mesh_size=size,
        fracture_mesh_size=fracture,
        transition=transition,
        tolerance=tolerance,
        algorithm3d=str(algorithm),
    )


def geometry(table: dict[str, Any], file: str) -> tuple[Dfn3dConfig, Any]:
    """Validate ``[dfn3d]`` and return (config, :class:`~geofrac.model.scene.Geometry`).

    The geometry is 3D with the groups ``rock``, the box's faces, ``fractures`` and one
    per set; its builder is a :class:`Dfn3dGeometry`.

    Raises:
        SceneError: naming the offending ``dfn3d.*`` key.
    """
    from geofrac.model.scene import Geometry

    config = _configure(table, file)
    groups = {"rock": 3, "fractures": 2} | dict.fromkeys(FACES, 2)
    groups |= dict.fromkeys(config.set_names, 2)
    return config, Geometry(
        file=None,
        parameters={},
        mesh_size=config.mesh_size,
        dim=3,
        groups=groups,
        builder=Dfn3dGeometry(config),
    )


def configure(table: dict[str, Any], ctx: ConfigureContext) -> Dfn3dConfig:
    """Validate ``[dfn3d]`` (the scene loader calls :func:`geometry` instead)."""
    return _configure(table, ctx.file)
