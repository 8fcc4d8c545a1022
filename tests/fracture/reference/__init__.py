"""Reference crack paths: stored event sequences and how to run and compare them.

Each ``<case>.json`` here holds the scene and ``--set`` overrides that produced it, the
first events of the run (crack-site midpoint x, y and load factor r of eq. 2.20 per
event) and how the run ended. ``tests/fracture/test_paths.py`` reruns every case and
compares with :func:`differences`; ``scripts/crack_references.py`` writes the files
(``--update``) or prints the differences. docs/cracking_paths.md says what each case
is, why its path is believed right and how to regenerate it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from mpi4py import MPI

__all__ = [
    "CASES",
    "REFERENCE_DIR",
    "REPO",
    "R_RTOL",
    "XY_RTOL",
    "Events",
    "differences",
    "domain_size",
    "load",
    "run_case",
    "save",
]

REFERENCE_DIR = Path(__file__).resolve().parent
REPO = REFERENCE_DIR.parents[2]

#: Crack-site midpoints agree to this fraction of the domain's size, per coordinate. The
#: mesh is deterministic (gmsh, one thread, the same geometry and parameters) and the
#: midpoint is the mean of two node coordinates read from it, so the same site gives the
#: same numbers up to round-off; any other site is at least half an element away.
XY_RTOL = 1e-9
#: Load factors r (eq. 2.20) agree to this relative tolerance: the direct solver's
#: round-off (MUMPS on 1 or 2 ranks, the update solver's corrections) is below 1e-9, and a
#: change of the physics moves r by far more than 1e-6.
R_RTOL = 1e-6


def _cases() -> list[str]:
    return sorted(p.stem for p in REFERENCE_DIR.glob("*.json"))


#: The stored cases (file stems).
CASES: list[str] = _cases()


@dataclass(frozen=True)
class Events:
    """The event sequence of one run.

    Attributes:
        xy: crack-site midpoint of each event's first cracked site, shape=(num_events, 2).
        load_factor: r = f_t / σ1 of each event (eq. 2.20), shape=(num_events,).
        end_reason: why the run ended (``max_events``, ``separated``, ...).
        sites: segments drawing each event's first cracked site (an edge: one segment; a
            grain interface: its two), shape=(k, 2, 2) (drawing only; None unless asked).
        site_event: the event (1, 2, ...) of each of those segments, shape=(k,).
        outline: the boundary edges and the pre-cracked sites, shape=(m, 2, 2) (drawing
            only).
    """

    xy: np.ndarray
    load_factor: np.ndarray
    end_reason: str
    sites: np.ndarray | None = None
    site_event: np.ndarray | None = None
    outline: np.ndarray | None = None

    @property
    def count(self) -> int:
        """Number of events."""
        return len(self.load_factor)


def run_case(
    scene: str, overrides: list[str], comm: MPI.Comm = MPI.COMM_WORLD, drawing: bool = False
) -> Events:
    """Run ``scene`` (a path relative to the repository) with ``overrides``; no output files.

    Collective on ``comm``. ``drawing`` also returns the cracked edges and the outline
    (:attr:`Events.sites`, :attr:`Events.outline`).
    """
    from geofrac.effects.cracking import scene_driver
    from geofrac.scene import load_scene_collective

    driver = scene_driver(load_scene_collective(comm, REPO / scene, overrides), comm)
    try:
        result = driver.run()
    finally:
        driver.problem.destroy()
    rows = driver.rows
    xy = np.array([[row["x"], row["y"]] for row in rows], dtype=float).reshape(-1, 2)
    r = np.array([row["load_factor"] for row in rows], dtype=float)
    events = Events(xy, r, str(result["end_reason"]))
    if not drawing:
        return events
    mesh = driver.state.mesh
    segments = [driver.drawing.segments(np.array([row["edge"]])) for row in rows]
    sites = np.concatenate(segments).reshape(-1, 2, 2) if rows else np.zeros((0, 2, 2))
    site_event = np.repeat(np.arange(1, len(rows) + 1), [len(s) for s in segments])
    boundary = mesh.coords[mesh.edges[mesh.boundary_edges]]
    outline = np.concatenate([boundary, driver.drawing.segments(driver.precracked)])
    return Events(xy, r, events.end_reason, sites, site_event, outline.reshape(-1, 2, 2))


def domain_size(ref: dict) -> float:
    """Largest extent of the reference's domain, mm (the unit of :data:`XY_RTOL`)."""
    return float(ref["domain_size_mm"])


def load(case: str) -> dict:
    """The stored reference ``case`` (its JSON as a dict; ``events`` rows are [x, y, r])."""
    return json.loads((REFERENCE_DIR / f"{case}.json").read_text())


def reference_events(ref: dict) -> Events:
    """The :class:`Events` of a loaded reference."""
    ev = np.array(ref["events"], dtype=float).reshape(-1, 3)
    return Events(ev[:, :2], ev[:, 2], ref["end_reason"])


def save(case: str, ref: dict, events: Events) -> Path:
    """Write ``<case>.json``: ``ref`` (scene, overrides, notes) plus the events, one per line."""
    head = dict(ref, end_reason=events.end_reason, num_events=events.count)
    head.pop("events", None)
    text = json.dumps(head, indent=1, ensure_ascii=False)[:-2]
    rows = [
        f"  [{x!r}, {y!r}, {float(f'{r:.15g}')!r}]"
        for (x, y), r in zip(events.xy.tolist(), events.load_factor.tolist(), strict=True)
    ]
    text += ',\n "events": [\n' + ",\n".join(rows) + "\n ]\n}\n"
    path = REFERENCE_DIR / f"{case}.json"
    path.write_text(text)
    return path


def differences(ref: dict, got: Events, xy_atol: float, rtol: float) -> list[str]:
    """How ``got`` departs from the reference ``ref``: empty when it matches.

    The events must come in the same order; event i matches when its midpoint is within
    ``xy_atol`` (mm, per coordinate) of the reference's and its load factor within
    ``rtol`` relative. The end reason and the number of events must be equal.
    """
    want = reference_events(ref)
    out = []
    if got.end_reason != want.end_reason or got.count != want.count:
        out.append(
            f"end: {got.count} events, {got.end_reason!r}; "
            f"reference {want.count}, {want.end_reason!r}"
        )
    for i in range(min(got.count, want.count)):
        dxy = np.abs(got.xy[i] - want.xy[i]).max()
        dr = abs(got.load_factor[i] - want.load_factor[i]) / abs(want.load_factor[i])
        if dxy > xy_atol or dr > rtol:
            out.append(
                f"event {i + 1}: site ({got.xy[i][0]:.6g}, {got.xy[i][1]:.6g}) r "
                f"{got.load_factor[i]:.9g}; reference ({want.xy[i][0]:.6g}, "
                f"{want.xy[i][1]:.6g}) r {want.load_factor[i]:.9g}"
            )
            break  # the rest of a diverged path says nothing new
    return out
