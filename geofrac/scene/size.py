"""How big a validated scene is, before any mesh is built: estimates and caps.

Pure Python (no gmsh, numpy, MPI). :func:`estimate` turns a validated scene (plus what
the loader read from its geometry file, an :class:`Extent`) into a :class:`SizeEstimate`
of the work it asks for; :func:`check_size` refuses an estimate far beyond the caps of
:data:`CAPS` unless the user allows it (``--allow-large``, scene key ``allow_large``).
The formulas are in docs/scenes.md ("Size estimate and caps"); they are approximate
(a factor of two either way is expected) but never ignore a knob that multiplies the
work.

- FEM cells of a ``.geo`` file: from trial meshes that the loader has gmsh make with
  every mesh size (points, fields, ``Mesh.MeshSize*``) multiplied by a factor k >= 1
  (``Mesh.MeshSizeFactor``), in a child process under a short time limit
  (:func:`geofrac.meshing.geo.trial_counts`). The first k comes from the bounding-box
  estimate below (:func:`trial_factor`: it aims at :data:`TRIAL_START` cells, so that an
  estimate 100 times too low still gives a small trial, and a scene asking for 1e9 cells
  is trial-meshed at k ≈ 2000 and 200 in a fraction of a second and refused, never
  meshed in full); a trial with fewer than :data:`TRIAL_CELLS` / 2 cells is followed by
  a finer one aimed at :data:`TRIAL_CELLS`, at k = 1 the full mesh. Cells n(k) = S + U k^-dim are
  fitted through the finest trial (k) and one at 2k, S being the part that does not
  scale with the sizes (transfinite or extruded meshes), and the estimate is S + U. This
  follows size fields and graded point sizes, which the bounding box cannot see.
- FEM cells from the bounding box (the fallback: no trial possible, e.g. it did not
  finish in time; and the first k of a trial): the smallest mesh size h the scene or
  file asks for (``geometry.mesh_size``, gmsh's ``Mesh.MeshSizeMax``, the smallest point
  size, parameters named ``h``, ``h_*``, ``lc``, ``lc_*``) over the bounding box:
  ``2.31 A / h²`` triangles (equilateral) in 2D, ``8.49 V / h³`` tetrahedra in 3D; and,
  where the file takes counts (parameters named ``n``, ``nx``, ``ny``, ``nz``, ``n_*``),
  the structured count ``2 · Π n`` (2D) or ``6 · Π n`` (3D; a single ``n`` counts per
  direction). The larger wins. A structured count beyond :data:`MAX_STRUCTURED_TRIAL`
  is not trial-meshed (it does not shrink with the sizes).
- FEM cells of a DFN (the ``dfn`` effect): from trial meshes of the same kind, which the
  loader has the DFN builder make in-process (:meth:`geofrac.effects.dfn.DfnGeometry.trial`
  in a gmsh session): the network generated (or read) and cleaned as for the run, the
  model built with the same size fields (``fracture_mesh_size``, ``transition``, the
  regions' ``mesh_size``) and meshed in 2D with the stepping of the ``.geo`` trial
  (:func:`geofrac.meshing.geo_worker.trial_meshes`), the first k aimed by
  ``2.31 A / h²`` with h the smallest size the table asks for, and the same fit. No
  trial when the fractures are beyond their cap (refused without drawing them); when it
  fails (the network cannot be cleaned, gmsh fails), ``2.31 A / mesh_size²``, which does
  not see the refinement near the fractures.
- A ``.msh`` file gives its real count.
- vertices: cells / 2 (2D), cells / 5.5 (3D); DOFs: vertices × the element's unknowns
  per vertex × degree^dim (:class:`~geofrac.elements.spec.ElementSpec`; P2/P3 carry
  about p^dim nodes per vertex).
- MPM: particles = Π counts (lattice) or the cell estimate (one per simplex); grid
  nodes Π (cells per axis + 2 padding + 1); steps = t_end / Δt with
  Δt = α L / c (c the P-wave speed, as :func:`geofrac.mpm.schemes.time_step`) or the
  given dt.
- blocks: the vertices of the mesh (geometry), or 0.733 · V_layer / h³ for the terrain
  (calibrated: h = 1.95 gives 100,643), V_layer = π a b (rim + (max − rim)/2).
- DFN fractures: Σ count, or P21 · A_region / E[L] per set (E[L] of the truncated power
  law).
- cracking: ``max_events``.

:attr:`SizeEstimate.method` says where the cell count came from (``geofrac check``
prints it), and why there was no trial when one failed.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from geofrac import elements
from geofrac.model.errors import SceneError
from geofrac.model.scene import Material, Scene

if TYPE_CHECKING:
    from geofrac.effects.dfn import DfnConfig

__all__ = [
    "CAPS",
    "HARD_LIMITS",
    "MAX_STRUCTURED_TRIAL",
    "RATES",
    "TRIAL_CELLS",
    "TRIAL_START",
    "Extent",
    "SizeEstimate",
    "check_size",
    "estimate",
    "format_count",
    "trial_factor",
]

#: Cap of each quantity: (value, per rank?). Per-rank caps scale with the ranks of the
#: run (``geofrac check`` counts one). Chosen so every scene of ``jobs/`` passes with
#: a margin of 10 or more, and what is beyond them takes hours to days or more memory
#: than a node has.
CAPS: dict[str, tuple[float, bool]] = {
    "particle_steps": (1e11, True),
    "particles": (5e6, True),
    "grid_nodes": (5e6, True),
    "cells": (5e6, True),
    "dofs": (2e7, True),
    "blocks": (5e6, True),
    "fractures": (1e6, False),
    "events": (1e6, False),
}
#: The mesh is made by gmsh on rank 0: at most this many cells however many ranks.
MAX_CELLS_TOTAL = 5e7
#: Beyond these no machine holds the scene; ``--allow-large`` does not lift them.
HARD_LIMITS: dict[str, float] = {
    "cells": 1e12,
    "dofs": 1e12,
    "particles": 1e12,
    "grid_nodes": 1e12,
    "particle_steps": 1e18,
    "blocks": 1e12,
    "fractures": 1e9,
    "events": 1e9,
}
#: Rough throughput of this code on one core, for the time in a refusal.
RATES: dict[str, tuple[float, str]] = {
    "particle_steps": (1e6, "particle-steps/s"),
    "cells": (2e5, "cells/s (gmsh)"),
    "blocks": (5e4, "blocks/s"),
}
#: Words of each quantity in messages.
_WORDS = {
    "cells": "cells",
    "dofs": "DOFs",
    "particles": "particles",
    "grid_nodes": "grid nodes",
    "steps": "steps",
    "particle_steps": "particle-steps",
    "blocks": "blocks",
    "fractures": "fractures",
    "events": "crack events",
}
_SIZE_NAME = re.compile(r"^(h|lc)(_\w+)?$")
_COUNT_NAME = re.compile(r"^n([xyz]|_\w+)?$")
#: Simplices per h^dim of an equilateral mesh: 4/√3 (2D), 6√2 (3D).
_PER_CELL = {2: 4 / math.sqrt(3), 3: 6 * math.sqrt(2)}
_VERTICES_PER_CELL = {2: 1 / 2, 3: 1 / 5.5}
#: Terrain vertices per h³ of the moving layer (calibrated on the default terrain).
_TERRAIN_DENSITY = 0.733
#: Cells a trial mesh aims at (a fraction of a second of gmsh).
TRIAL_CELLS = 2e4
#: Cells the first trial mesh aims at by the bounding box (the trial then aims at
#: :data:`TRIAL_CELLS`).
TRIAL_START = TRIAL_CELLS / 100
#: Largest structured count (``2 Π n``, ``6 Π n``) that is still trial-meshed.
MAX_STRUCTURED_TRIAL = 2e5


@dataclass(frozen=True)
class Extent:
    """What the loader reads from a geometry file in gmsh (no meshing), or of a DFN.

    A DFN's extent is its domain's box and its trial meshes (or why it has none).

    Attributes:
        lower: bounding box's lowest corner, shape=(3,).
        upper: its highest corner, shape=(3,).
        point_size: smallest positive mesh size set at a point, or None.
        size_max: gmsh ``Mesh.MeshSizeMax`` when the file sets it, or None.
        size_factor: gmsh ``Mesh.MeshSizeFactor``.
        cells: a ``.msh`` file's real count of top-dimensional elements, or None.
        variables: the ``.geo`` file's numeric parser variables after the scene's
            parameters were applied (``DefineConstant`` defaults included).
        trial: (size factor k, cells) of each trial mesh of a ``.geo`` file
            (:func:`geofrac.meshing.geo.trial_counts`) or of a DFN (its domain's box
            above), in the order made; empty without one.
        trial_failure: why a trial was not made or did not finish, or ``""``.
    """

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    point_size: float | None = None
    size_max: float | None = None
    size_factor: float = 1.0
    cells: int | None = None
    variables: dict[str, float] = field(default_factory=dict)
    trial: tuple[tuple[float, int], ...] = ()
    trial_failure: str = ""


@dataclass(frozen=True)
class SizeEstimate:
    """Estimated size of a scene's work.

    Attributes:
        quantities: quantity name (a key of :data:`CAPS`, or ``steps``) -> estimate.
        keys: quantity name -> the scene key that sets it (named in a refusal).
        method: where the cell count came from, e.g. ``estimate from a trial mesh at 4×
            the sizes`` or ``estimate from the bounding box``.
    """

    quantities: dict[str, float] = field(default_factory=dict)
    keys: dict[str, str] = field(default_factory=dict)
    method: str = "estimate"

    def summary(self) -> str:
        """One line, e.g. ``80 cells, 330 DOFs``."""
        parts = [
            f"{format_count(v)} {_WORDS[k]}" for k, v in self.quantities.items() if k in _WORDS
        ]
        return ", ".join(parts) or "nothing to estimate"


def format_count(value: float) -> str:
    """A count as an integer below 1e5, else like ``1.0e9``."""
    if not math.isfinite(value):
        return str(value)
    if value < 1e5:
        return f"{value:.0f}"
    mantissa, exponent = f"{value:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _mesh_size(scene: Scene, extent: Extent) -> tuple[float | None, str]:
    """The smallest element size the geometry asks for (or None), and the key setting it."""
    geometry = scene.geometry
    assert geometry is not None  # a scene meshed from a geometry
    candidates = [
        (geometry.mesh_size, "geometry.mesh_size"),
        (extent.size_max, "geometry.file"),
        (extent.point_size, "geometry.file"),
    ]
    for k, v in (extent.variables | geometry.parameters).items():
        if _SIZE_NAME.match(k):
            where = "geometry.parameters" if k in geometry.parameters else "geometry.file"
            candidates.append((v, where))
    sizes = [(c, key) for c, key in candidates if c is not None and c > 0]
    if not sizes:
        return None, "geometry.file"
    h, key = min(sizes)
    return h * extent.size_factor, key


def _cells_key(scene: Scene, extent: Extent | None) -> str:
    """The scene key that sets the cell count (a DFN: its smallest size, ties to ``mesh_size``)."""
    dfn = _dfn_config(scene)
    if dfn is not None:
        sizes = [(dfn.mesh.size, 0, "dfn.mesh_size")]
        sizes.append((dfn.mesh.fracture_size, 1, "dfn.fracture_mesh_size"))
        for r in dfn.regions.regions if dfn.regions is not None else ():
            if r.mesh_size:
                sizes.append((r.mesh_size, 2, f"dfn.regions.{r.name}.mesh_size"))
        return min(sizes)[2]
    builder = getattr(scene.geometry, "builder", None)
    if builder is not None:
        return str(getattr(builder, "size_key", "dfn.mesh_size"))
    if extent is None or extent.cells is not None:
        return "geometry.file"
    h_key = _mesh_size(scene, extent)[1]
    assert scene.geometry is not None  # the extent is its file's
    counts = [k for k in scene.geometry.parameters if _COUNT_NAME.match(k)]
    return "geometry.parameters" if counts and h_key == "geometry.file" else h_key


def _box_cells(scene: Scene, extent: Extent) -> tuple[float, float]:
    """Cells of a geometry file from its bounding box and sizes, and from its counts."""
    geometry = scene.geometry
    assert geometry is not None  # a scene meshed from a geometry
    dim = geometry.dim
    sides = [u - lo for lo, u in zip(extent.lower, extent.upper, strict=True)]
    sides = sorted((s for s in sides if s > 0), reverse=True)[:dim]
    h = _mesh_size(scene, extent)[0]
    by_size = 0.0
    if h and len(sides) == dim:  # side / h per side: no underflow of h**dim
        by_size = _PER_CELL[dim] * math.prod(s / h for s in sides)
    variables = extent.variables | geometry.parameters
    counts = [v for k, v in variables.items() if _COUNT_NAME.match(k) and v >= 1]
    if len(counts) == 1:
        counts = counts * dim
    by_count = (2.0 if dim == 2 else 6.0) * math.prod(counts) if counts else 0.0
    return by_size, by_count


def _uses_cells(scene: Scene) -> bool:
    """Whether the estimate counts the cells of the geometry (not an MPM lattice's)."""
    m = scene.mpm
    if scene.method != "mpm" or m is None:
        return True
    return m.particles.kind != "lattice" and not any(b.kind == "lattice" for b in m.bodies)


def trial_factor(scene: Scene, extent: Extent | None) -> float | None:
    """The size factor k >= 1 of the first trial mesh, or None when none is to be made.

    None without a ``.geo`` file or a DFN domain, for a ``.msh`` file (its count is
    real), an estimate that does not count the geometry's cells, a structured count
    beyond :data:`MAX_STRUCTURED_TRIAL`, and a DFN whose fractures are beyond their cap
    (refused without generating them). Else k = (cells / :data:`TRIAL_START`)^(1/dim) (at
    least 1), the cells from the bounding box (a DFN: its domain's area at the smallest
    size it asks for): the first trial has about :data:`TRIAL_START` cells, or fewer when
    the bounding box asks for too many (a graded mesh), and a small multiple of
    :data:`TRIAL_CELLS` when it asks for 100 times too few (sizes it cannot see).
    """
    geometry = scene.geometry
    dfn = _dfn_config(scene)
    if dfn is not None:
        if _fractures(dfn) > CAPS["fractures"][0] or not _uses_cells(scene):
            return None
        h = min(dfn.mesh.size, dfn.mesh.fracture_size, *_region_sizes(dfn))
        return max(1.0, math.sqrt(_area_cells(dfn, h) / TRIAL_START))
    if (
        extent is None
        or extent.cells is not None
        or geometry is None
        or geometry.file is None
        or geometry.file.suffix != ".geo"
        or getattr(geometry, "builder", None) is not None
        or not _uses_cells(scene)
    ):
        return None
    by_size, by_count = _box_cells(scene, extent)
    if by_count > max(by_size, MAX_STRUCTURED_TRIAL):
        return None
    return max(1.0, (by_size / TRIAL_START) ** (1.0 / geometry.dim))


def _dfn_config(scene: Scene) -> DfnConfig | None:
    """The ``dfn`` settings of a scene whose geometry the DFN builder makes, or None."""
    builder = getattr(scene.geometry, "builder", None)
    return getattr(builder, "config", None) if builder is not None else None


def _region_sizes(config: DfnConfig) -> list[float]:
    """The mesh sizes of a DFN's regions (``[dfn.regions.*] mesh_size``)."""
    if config.regions is None:
        return []
    return [r.mesh_size for r in config.regions.regions if r.mesh_size]


def _area_cells(config: DfnConfig, h: float) -> float:
    """Triangles of the DFN domain at size ``h`` everywhere: ``2.31 A / h²``."""
    from geofrac.dfn.polygon import polygon_area  # numpy only

    return _PER_CELL[2] * (math.sqrt(float(polygon_area(config.domain))) / h) ** 2


def _trial_cells(trial: tuple[tuple[float, int], ...], dim: int) -> tuple[float, float]:
    """Cells of the full mesh from trial meshes (see the module docstring), and its k."""
    k1, n1 = min(trial)  # the finest
    coarser = [m for m in trial if m[0] > k1]
    if k1 <= 1.0 or not coarser:
        return n1 * k1**dim, k1
    k2, n2 = min(coarser)
    a, b = k1**-dim, k2**-dim
    scaling = max(0.0, (n1 - n2) / (a - b))  # U of n(k) = S + U k^-dim
    fixed = n1 - scaling * a  # S
    if fixed < 0:
        fixed, scaling = 0.0, n1 / a
    return fixed + scaling, k1


def _from_trial(trial: tuple[tuple[float, int], ...], dim: int) -> tuple[float, str]:
    """Cells of the full mesh from trial meshes (a ``.geo`` file or a DFN), and the method."""
    cells, k = _trial_cells(trial, dim)
    if k <= 1.0:
        return max(cells, 1.0), "estimate from a trial mesh at the full sizes"
    return max(cells, 1.0), f"estimate from a trial mesh at {k:.3g}× the sizes"


def _fem_cells(scene: Scene, extent: Extent | None) -> tuple[float, str]:
    """Cells of the mesh of ``scene.geometry`` and where they came from (module docstring)."""
    geometry = scene.geometry
    assert geometry is not None  # a scene meshed from a geometry
    dfn = _dfn_config(scene)
    if extent is not None and extent.trial:  # a .geo file or a DFN
        return _from_trial(extent.trial, geometry.dim)
    if dfn is not None:
        why = f" ({extent.trial_failure})" if extent is not None and extent.trial_failure else ""
        return _area_cells(dfn, dfn.mesh.size), f"estimate from the DFN domain's area{why}"
    builder: Any = getattr(geometry, "builder", None)
    if hasattr(builder, "estimate_cells"):  # a 3D DFN: its box and fracture area
        return float(builder.estimate_cells()), "estimate from the box and the fractures' area"
    if extent is None:
        return 0.0, "estimate"
    if extent.cells is not None:
        return float(extent.cells), "estimate from the mesh file's cells"
    by_size, by_count = _box_cells(scene, extent)
    why = f" ({extent.trial_failure})" if extent.trial_failure else ""
    return max(by_size, by_count, 1.0), f"estimate from the bounding box{why}"


def _dofs(cells: float, dim: int, element: str) -> float:
    spec = elements.get(element)
    return cells * _VERTICES_PER_CELL[dim] * spec.vertex_dofs[dim] * spec.degree**dim


def _mean_length(lmin: float, lmax: float, n: float) -> float:
    """E[L] of the power law F_N = 1/L^n truncated to [lmin, lmax]."""
    if lmax <= lmin:
        return lmin
    r = (lmax / lmin) ** -n
    if abs(n - 1.0) < 1e-12:
        return lmin * math.log(lmax / lmin) / (1.0 - r)
    return lmin * n / (n - 1.0) * (1.0 - (lmax / lmin) ** (1.0 - n)) / (1.0 - r)


def _fractures(config: DfnConfig) -> float:
    from geofrac.dfn.polygon import polygon_area  # numpy only

    if config.network is not None:
        return float(len(config.network))
    area = float(polygon_area(config.region))
    total = 0.0
    for s in config.sets:
        if s.count is not None:
            total += s.count
        else:
            assert s.p21 is not None  # a set gives its count or its p21
            total += s.p21 * area / _mean_length(s.lmin, s.lmax, s.exponent)
    return total


def _wave_speed(material: Material | None, dim: int) -> float:
    from geofrac.materials import p_wave_modulus

    assert material is not None and material.density is not None  # an MPM material

    return math.sqrt(p_wave_modulus(material.E, material.nu, dim) / material.density)


def _mpm(scene: Scene, extent: Extent | None, q: dict[str, float], keys: dict[str, str]) -> str:
    """Fill ``q`` and ``keys`` for an MPM scene; where a particle count from cells came from."""
    m = scene.mpm
    method = "estimate"
    assert m is not None  # method = "mpm"
    lattices = [b for b in m.bodies if b.kind == "lattice"]
    if m.particles.kind == "lattice":
        q["particles"] = float(math.prod(m.particles.counts))
        keys["particles"] = "mpm.particles.counts"
    elif lattices:  # every body a lattice box: their particles add up
        q["particles"] = float(sum(math.prod(b.counts) for b in lattices))
        big = max(lattices, key=lambda b: math.prod(b.counts))
        keys["particles"] = f"{big.key}.counts"
    else:  # the geometry's groups (at most all its cells)
        q["particles"], method = _fem_cells(scene, extent)
        keys["particles"] = _cells_key(scene, extent)
    q["grid_nodes"] = float(
        math.prod(
            math.ceil((u - lo) / m.spacing) + 2 * m.padding + 1
            for lo, u in zip(m.lower, m.upper, strict=True)
        )
    )
    keys["grid_nodes"] = "mpm.grid.spacing"
    if m.dt is not None:
        dt = m.dt
    else:
        assert m.courant is not None  # the loader sets dt or courant
        dt = m.courant * m.spacing / _wave_speed(scene.material, m.dim)
    steps = m.t_end / dt if dt > 0 else math.inf
    q["steps"] = float(math.ceil(steps)) if math.isfinite(steps) else math.inf
    keys["steps"] = "mpm.dt" if m.dt is not None else "mpm.t_end"
    q["particle_steps"] = q["particles"] * q["steps"]
    keys["particle_steps"] = keys["particles"] if q["particles"] > 1e6 else keys["steps"]
    return method


def _terrain_blocks(terrain: dict[str, Any]) -> float:
    from geofrac.meshing.terrain import TerrainSpec  # numpy only

    spec = TerrainSpec(**terrain)
    p, b = spec.footprint_axes
    depth = spec.rim_depth + (spec.max_depth - spec.rim_depth) / 2
    blocks = _TERRAIN_DENSITY * math.pi * (p / spec.h) * (b / spec.h) * (depth / spec.h)
    for _, radius, size in spec.zones:
        if size < spec.h:  # a finer ball adds at most its volume at the finer size
            ball = 4 / 3 * math.pi * (radius * (1 + spec.zone_transition)) ** 3
            blocks += _TERRAIN_DENSITY * ball * ((1 / size) ** 3 - (1 / spec.h) ** 3)
    return blocks


def estimate(scene: Scene, extent: Extent | None) -> SizeEstimate:
    """Estimate the work of a validated scene (see the module docstring).

    Args:
        scene: a :class:`~geofrac.model.scene.Scene` (its ``size`` not yet set).
        extent: what gmsh reported of the scene's geometry file (with the cells of its
            trial meshes, if any), or None (no file).
    """
    q: dict[str, float] = {}
    keys: dict[str, str] = {}
    method = "estimate"
    if scene.method == "mpm":
        method = _mpm(scene, extent, q, keys)
    elif scene.method == "blocks":
        assert scene.blocks is not None
        if scene.blocks.terrain is not None:
            q["blocks"] = _terrain_blocks(scene.blocks.terrain)
            keys["blocks"] = "blocks.terrain.h"
        else:
            cells, method = _fem_cells(scene, extent)
            q["cells"], keys["cells"] = cells, _cells_key(scene, extent)
            assert scene.geometry is not None  # _fem_cells has read it
            q["blocks"] = cells * _VERTICES_PER_CELL[scene.geometry.dim]
            keys["blocks"] = keys["cells"]
    else:
        cells, method = _fem_cells(scene, extent)
        dfn = None
        if "dfn" in scene.effect_names:  # then its module is already imported
            from geofrac.effects.dfn import DfnConfig

            dfn = scene.effect_config("dfn", DfnConfig)
        where = _cells_key(scene, extent)
        q["cells"], keys["cells"] = cells, where
        assert scene.geometry is not None and scene.discretization is not None  # FEM
        q["dofs"] = _dofs(cells, scene.geometry.dim, scene.discretization.element)
        keys["dofs"] = where
        if dfn is not None:
            q["fractures"] = _fractures(dfn)
            keys["fractures"] = "dfn.file" if dfn.network is not None else "dfn.sets"
        crack = None
        if "cracking" in scene.effect_names:
            from geofrac.fracture.config import CrackingConfig

            crack = scene.effect_config("cracking", CrackingConfig)
        if crack is not None:
            q["events"] = float(crack.max_events)
            keys["events"] = "cracking.max_events"
    return SizeEstimate(q, keys, method)


def _duration(seconds: float) -> str:
    for unit, length in (("years", 3.15e7), ("days", 86400.0), ("hours", 3600.0)):
        if seconds >= 2 * length:
            return f"{format_count(seconds / length)} {unit}"
    return f"{seconds / 60:.0f} minutes"


def _sci(value: float) -> str:
    """``1e11`` rather than ``1e+11``."""
    mantissa, exponent = f"{value:.0e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _cap(name: str, ranks: int) -> float:
    value, per_rank = CAPS[name]
    cap = value * max(1, ranks) if per_rank else value
    return min(cap, MAX_CELLS_TOTAL) if name == "cells" else cap


def check_size(
    file: str | Path, size: SizeEstimate, ranks: int = 1, *, allow: bool = False
) -> None:
    """Refuse a scene beyond a cap (unless ``allow``) or beyond a hard limit (always).

    Args:
        file: the scene file, for the message.
        size: the estimate.
        ranks: MPI ranks of the run; per-rank caps scale with it.
        allow: ``--allow-large`` or the scene's ``allow_large``.

    Raises:
        SceneError: naming the key that sets the quantity, the estimate and the cap.
    """
    q = size.quantities
    for name in CAPS:
        if name not in q:
            continue
        value, key = q[name], size.keys.get(name, "")
        what = f"about {format_count(value)} {_WORDS[name]}"
        if name == "particle_steps":
            what = (
                f"about {format_count(q['particles'])} particles and "
                f"{format_count(q['steps'])} steps ({format_count(value)} particle-steps)"
            )
        if not value <= HARD_LIMITS[name]:
            raise SceneError(
                file,
                key,
                f"{what} is beyond what any machine holds (limit {_sci(HARD_LIMITS[name])} "
                f"{_WORDS[name]}; --allow-large does not lift it)",
            )
        cap = _cap(name, ranks)
        if allow or value <= cap:
            continue
        eta = ""
        if name in RATES:
            rate, unit = RATES[name]
            seconds = value / (rate * max(1, ranks))
            eta = f" (about {_duration(seconds)} on this machine at {_sci(rate)} {unit})"
        on = f" on {ranks} ranks" if CAPS[name][1] and ranks > 1 else ""
        raise SceneError(
            file,
            key,
            f"{what} is far beyond the cap of {_sci(cap)} {_WORDS[name]}{on}{eta}; "
            "pass --allow-large to run it anyway",
        )
