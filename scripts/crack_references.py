"""Reference crack paths (tests/fracture/reference/<case>.json): check or regenerate them.

    PYTHONPATH=$PWD python scripts/crack_references.py              # compare all, print diffs
    PYTHONPATH=$PWD python scripts/crack_references.py plate_hole   # one case
    PYTHONPATH=$PWD python scripts/crack_references.py --update     # rewrite files + pictures

Each case is a scene of jobs/ with ``--set`` overrides that coarsen it so that it runs in
seconds (:data:`CASES`). ``--update`` writes the JSON (with the commit it was made
from) and draws the path into docs/img/paths_<case>.png; review the picture against
docs/cracking_paths.md before committing a new reference. Without ``--update`` the
script reruns each case and prints how it departs from the stored one (exit code 1 if
any does), with the tolerances of tests/fracture/test_paths.py.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.fracture.reference import (
    R_RTOL,
    REPO,
    XY_RTOL,
    Events,
    differences,
    domain_size,
    load,
    run_case,
    save,
)

__all__ = ["CASES", "Case", "main"]


@dataclass(frozen=True)
class Case:
    """One reference case: a jobs/ scene, its overrides and what the path should show."""

    scene: str
    overrides: tuple[str, ...]
    mesh_size: float  # mm, the (finest) element size of the coarsened mesh
    description: str
    view: tuple[float, float, float, float] | None = None  # picture box x0, x1, y0, y1


CASES: dict[str, Case] = {
    "notched_beam": Case(
        "jobs/notched_beam.toml",
        (
            "geometry.parameters.h_fine=4",
            "geometry.parameters.h=20",
            "cracking.max_events=45",
            "cracking.criterion=principal",
        ),
        4.0,
        "Edo (2016) 2.4.3, Galvez et al.: the crack starts at the notch tip (0, 75) and "
        "curves towards the load point (150, 150), meeting the top about 30 mm right of "
        "the centre.",
        (-120.0, 200.0, 0.0, 150.0),
    ),
    "plate_hole": Case(
        "jobs/plate_hole.toml",
        ("geometry.parameters.h=3", "cracking.max_events=60", "cracking.criterion=principal"),
        3.0,
        "Edo (2016) 2.4.4, Tang et al.: tensile cracks start at the top (25, 95) and bottom "
        "(25, 75) of the hole and run straight up and down, parallel to the compression.",
    ),
    "dcn_plate": Case(
        "jobs/dcn_plate.toml",
        ("geometry.parameters.h=4", "cracking.max_events=80", "cracking.criterion=principal"),
        4.0,
        "Edo (2016) 2.4.5, Zhu and Tang: seeds at the notch tips, then the crack of one "
        "notch dominates and runs towards the top and bottom faces, parallel to the load.",
    ),
    "dfn_model1": Case(
        "jobs/crack_model1.toml",
        ("dfn.mesh_size=6", "cracking.max_events=40", "cracking.criterion=principal"),
        6.0,
        "Edo (2016) 2.5.1, Model 1 coarsened: new cracks start at the tips of pre-existing "
        "fractures (DFN set 1, seed 1) and run parallel to the compression.",
    ),
    "grain_notched_beam": Case(
        "jobs/grain_notched_beam.toml",
        (
            "geometry.parameters.h=12",
            "geometry.parameters.h_fine=12",
            "cracking.max_events=40",
        ),
        12.0,
        "Edo (2016) 3.5.1: the notched beam cracked along EFMM grain interfaces (grain size "
        "12 mm): the crack runs from the notch tip towards the load point and meets the top "
        "within two grain sizes of the edge crack (tests/fracture/test_grain_edge_path.py).",
        (-120.0, 200.0, 0.0, 150.0),
    ),
}


def _direction(name: str) -> Case:
    """The thesis's case ``name`` with the default criterion (``"direction"``)."""
    case = CASES[name]
    overrides = tuple(o for o in case.overrides if o != "cracking.criterion=principal")
    return Case(
        case.scene,
        overrides,
        case.mesh_size,
        case.description.split(":")[0]
        + ", the default criterion ('direction', docs/cracking.md \"Mesh dependence\")"
        + ":"
        + case.description.split(":", 1)[1],
        case.view,
    )


CASES |= {
    f"{name}_direction": _direction(name)
    for name in ("notched_beam", "plate_hole", "dcn_plate", "dfn_model1")
}


def commit() -> str:
    """The last commit that changed the code a case runs, ``+dirty`` if it has changes.

    The code is geofrac/, meshes/ and jobs/ (not the tests or these scripts).
    """
    git = ["git", "-C", str(REPO)]
    code = ["--", "geofrac", "meshes", "jobs"]
    head = subprocess.run(
        [*git, "log", "-1", "--format=%h", *code], check=False, capture_output=True, text=True
    )
    dirty = subprocess.run(
        [*git, "status", "--porcelain", *code], check=False, capture_output=True, text=True
    )
    return head.stdout.strip() + ("+dirty" if dirty.stdout.strip() else "")


def outline_size(events: Events) -> float:
    """Largest extent of the outline, mm."""
    pts = events.outline.reshape(-1, 2)  # type: ignore[union-attr]
    return float((pts.max(axis=0) - pts.min(axis=0)).max())


def draw(case: str, events: Events, path: Path, view: tuple[float, ...] | None) -> None:
    """The crack path: cracked edges coloured by event, outline and pre-cracks in grey."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    pts = events.outline.reshape(-1, 2)  # type: ignore[union-attr]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if view is not None:
        lo, hi = np.array(view[::2]), np.array(view[1::2])
    span = hi - lo
    height = min(5.0, max(2.0, 4.0 * span[1] / span[0] + 0.8))
    fig, ax = plt.subplots(figsize=(min(6.0, 0.9 * height * span[0] / span[1] + 1.6), height))
    lines = LineCollection(events.sites, cmap="viridis", linewidths=2.0)
    lines.set_array(events.site_event)
    ax.add_collection(lines)
    ax.add_collection(LineCollection(events.outline, colors="0.3", linewidths=0.6))
    fig.colorbar(lines, ax=ax, label="event", shrink=0.8)
    ax.set_aspect("equal")
    pad = 0.03 * span.max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_title(f"{case}: {events.count} events, end {events.end_reason}", fontsize=9)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """Command line (see the module docstring); exit code 1 if a case departs."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("cases", nargs="*", help=f"cases (default: all of {', '.join(CASES)})")
    p.add_argument("--update", action="store_true", help="rewrite the files and pictures")
    args = p.parse_args(argv)
    bad = 0
    for name in args.cases or list(CASES):
        case = CASES[name]
        events = run_case(case.scene, list(case.overrides), drawing=True)
        size = outline_size(events)
        if args.update:
            ref = {
                "case": name,
                "description": case.description,
                "scene": case.scene,
                "overrides": list(case.overrides),
                "mesh_size_mm": case.mesh_size,
                "domain_size_mm": size,
                "tolerance": {"xy_mm": XY_RTOL * size, "load_factor_rtol": R_RTOL},
                "generated": {
                    "commit": commit(),
                    "command": "PYTHONPATH=$PWD python scripts/crack_references.py "
                    f"--update {name}",
                },
            }
            path = save(name, ref, events)
            picture = REPO / "docs" / "img" / f"paths_{name}.png"
            draw(name, events, picture, case.view)
            print(f"{name}: {events.count} events, end {events.end_reason}: {path}, {picture}")
            continue
        ref = load(name)
        diff = differences(ref, events, XY_RTOL * domain_size(ref), R_RTOL)
        print(f"{name}: " + ("matches" if not diff else "DIFFERS"))
        for line in diff:
            print(f"  {line}")
        bad += bool(diff)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
