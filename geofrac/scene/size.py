"""How big a validated scene is, before any mesh is built: estimates and caps.

Pure Python (no gmsh, numpy, MPI). :func:`estimate` turns a validated scene (plus what
the loader read from its geometry file, an :class:`Extent`) into a :class:`SizeEstimate`
of the work it asks for; :func:`check_size` refuses an estimate far beyond the caps of
:data:`CAPS` unless the user allows it (``--allow-large``, scene key ``allow_large``).
The formulas are in docs/scenes.md ("Size estimate and caps"); they are approximate
(a factor of two either way is expected) but never ignore a knob that multiplies the
work.

- FEM cells: the smallest mesh size h the scene or file asks for (``geometry.mesh_size``,
  gmsh's ``Mesh.MeshSizeMax``, the smallest point size, parameters named ``h``,
  ``h_*``, ``lc``, ``lc_*``) over the bounding box: ``2.31 A / h²`` triangles (equilateral)
  in 2D, ``8.49 V / h³`` tetrahedra in 3D; and, where the file takes counts
  (parameters named ``n``, ``nx``, ``ny``, ``nz``, ``n_*``), the structured count
  ``2 · Π n`` (2D) or ``6 · Π n`` (3D; a single ``n`` counts per direction). The larger
  wins. A ``.msh`` file gives its real count. A DFN domain: ``2.31 A / mesh_size²``.
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
    "RATES",
    "Extent",
    "SizeEstimate",
    "check_size",
    "estimate",
    "format_count",
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


@dataclass(frozen=True)
class Extent:
    """What the loader reads from a geometry file in gmsh (no meshing).

    Attributes:
        lower: bounding box's lowest corner, shape=(3,).
        upper: its highest corner, shape=(3,).
        point_size: smallest positive mesh size set at a point, or None.
        size_max: gmsh ``Mesh.MeshSizeMax`` when the file sets it, or None.
        size_factor: gmsh ``Mesh.MeshSizeFactor``.
        cells: a ``.msh`` file's real count of top-dimensional elements, or None.
        variables: the ``.geo`` file's numeric parser variables after the scene's
            parameters were applied (``DefineConstant`` defaults included).
    """

    lower: tuple[float, ...]
    upper: tuple[float, ...]
    point_size: float | None = None
    size_max: float | None = None
    size_factor: float = 1.0
    cells: int | None = None
    variables: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class SizeEstimate:
    """Estimated size of a scene's work.

    Attributes:
        quantities: quantity name (a key of :data:`CAPS`, or ``steps``) -> estimate.
        keys: quantity name -> the scene key that sets it (named in a refusal).
    """

    quantities: dict[str, float] = field(default_factory=dict)
    keys: dict[str, str] = field(default_factory=dict)

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
    """The scene key that sets the cell count."""
    if getattr(scene.geometry, "builder", None) is not None:
        return "dfn.mesh_size"
    if extent is None or extent.cells is not None:
        return "geometry.file"
    h_key = _mesh_size(scene, extent)[1]
    assert scene.geometry is not None  # the extent is its file's
    counts = [k for k in scene.geometry.parameters if _COUNT_NAME.match(k)]
    return "geometry.parameters" if counts and h_key == "geometry.file" else h_key


def _fem_cells(scene: Scene, extent: Extent | None) -> float:
    """Cells of the mesh of ``scene.geometry`` (see the module docstring)."""
    geometry = scene.geometry
    assert geometry is not None  # a scene meshed from a geometry
    dim = geometry.dim
    builder = getattr(geometry, "builder", None)
    if builder is not None and hasattr(builder, "config"):  # dfn
        from geofrac.dfn.polygon import polygon_area  # numpy only

        cfg = builder.config
        return _PER_CELL[2] * (math.sqrt(float(polygon_area(cfg.domain))) / cfg.mesh.size) ** 2
    if extent is None:
        return 0.0
    if extent.cells is not None:
        return float(extent.cells)
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
    return max(by_size, by_count, 1.0)


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


def _mpm(scene: Scene, extent: Extent | None, q: dict[str, float], keys: dict[str, str]) -> None:
    m = scene.mpm
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
        q["particles"] = _fem_cells(scene, extent)
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
        extent: what gmsh reported of the scene's geometry file, or None (no file).
    """
    q: dict[str, float] = {}
    keys: dict[str, str] = {}
    if scene.method == "mpm":
        _mpm(scene, extent, q, keys)
    elif scene.method == "blocks":
        assert scene.blocks is not None
        if scene.blocks.terrain is not None:
            q["blocks"] = _terrain_blocks(scene.blocks.terrain)
            keys["blocks"] = "blocks.terrain.h"
        else:
            cells = _fem_cells(scene, extent)
            q["cells"], keys["cells"] = cells, _cells_key(scene, extent)
            assert scene.geometry is not None  # _fem_cells has read it
            q["blocks"] = cells * _VERTICES_PER_CELL[scene.geometry.dim]
            keys["blocks"] = keys["cells"]
    else:
        cells = _fem_cells(scene, extent)
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
    return SizeEstimate(q, keys)


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
