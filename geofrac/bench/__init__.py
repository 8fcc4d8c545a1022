"""Accuracy-cost benchmarks: one module per ``geofrac bench NAME``.

A bench module provides ``add_arguments(parser)`` (cheap: no DOLFINx import) and
``run(args, comm)``; the CLI adds ``--set KEY=VALUE`` (``args.overrides``) to every
bench. Its JSON output has at least ``bench``, ``records`` and ``rates`` (see
docs/output.md).
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["BENCHES", "load_bench"]

#: name -> (module, one-line description)
BENCHES: dict[str, tuple[str, str]] = {
    "blocks": (
        "geofrac.bench.blocks",
        "3D block models (Edo (2016), chapter 5): meshing and block wall times, blocks/s, "
        "against Voronoi",
    ),
    "cantilever": (
        "geofrac.bench.cantilever",
        "Timoshenko cantilever (Edo (2016), §2.4.1, §3.4.1): displacement/energy error "
        "against DOFs and wall time",
    ),
    "cracking": (
        "geofrac.bench.cracking",
        "crack events (Edo (2016), Fig. 2.6): events/s and seconds per phase, notched beam, "
        "DFN Model 2",
    ),
    "dfn": (
        "geofrac.bench.dfn",
        "DFN Models 1 and 2 (Edo (2016), §2.5.1): generation and meshing wall times, "
        "mesh statistics",
    ),
    "dfn3d": (
        "geofrac.bench.dfn3d",
        "3D disc networks in a cube: cleaning, OCC fragment and tetrahedral meshing wall times, "
        "mesh quality",
    ),
    "efmm-qrand": (
        "geofrac.bench.efmm_qrand",
        "EFMM integration domains (Edo (2016), Table 3.1): error mean and spread over q_rand "
        "and seeds",
    ),
    "granular": (
        "geofrac.bench.granular",
        "crack events along EFMM grain interfaces (Edo (2016), §3.5-3.6): events/s, phases, "
        "patterns",
    ),
    "mesh-dependence": (
        "geofrac.bench.mesh_dependence",
        "symmetric notched beam on the three gmsh meshers: how far the crack strays from the axis",
    ),
    "mms3d": (
        "geofrac.bench.mms3d",
        "manufactured smooth 3D displacement on a box: error against DOFs and wall time",
    ),
    "mpm": (
        "geofrac.bench.mpm",
        "MPM quasi-static bar (Edo (2016), §4.5.1): stress error against particle-steps/s "
        "per variant",
    ),
    "stability": (
        "geofrac.bench.stability",
        "distorted meshes (minimum angle down to 5°) and ν up to 0.499: degradation and failures",
    ),
}


def load_bench(name: str) -> ModuleType:
    """Import the module of bench ``name``."""
    return importlib.import_module(BENCHES[name][0])
