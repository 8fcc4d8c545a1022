"""Validated ``[cracking]`` settings: what the crack driver's parts read.

The scene table is validated by :func:`geofrac.effects.cracking.configure` (its module
docstring gives each key); the dataclass lives here so that the driver does not import
the effects layer above it.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CrackingConfig", "JointProperties", "LoopSettings"]


@dataclass(frozen=True)
class JointProperties:
    """Coulomb friction coefficient μ and cohesion c of crack faces in contact.

    Attributes:
        friction: μ ≥ 0.
        cohesion: c ≥ 0, in stress units; lost when the faces first slip or open.
    """

    friction: float
    cohesion: float = 0.0


@dataclass(frozen=True)
class CrackingConfig:
    """Validated ``[cracking]`` settings (:mod:`geofrac.effects.cracking` gives each key)."""

    method: str
    max_events: int
    energy_drop: float | None
    neighbours: int
    margin: float
    max_radius_factor: float
    precracked: tuple[str, ...]
    mls_region: tuple[float, float, float, float] | None
    control: str
    edges_per_event: int
    batch_tolerance: float
    solver: str
    reuse_iterations: int
    update_dofs: int
    output_every: int
    face: str | None
    face_origin: float
    tensile_strength: float
    precracked_fraction: float = 0.0
    precrack_seed: int = 0
    switch: str = "patch"
    #: the MLS cells' strain (:data:`~geofrac.fracture.consistent.GRADIENTS`).
    mls_gradient: str = "fit"
    #: crack faces in contact (docs/cracking.md, "Crack faces in contact").
    contact: bool = False
    #: the faces of new cracks (and of pre-existing ones without a ``joints`` entry).
    crack_faces: JointProperties = JointProperties(0.6, 0.0)
    #: per ``precracked`` group or DFN fracture set name.
    joints: tuple[tuple[str, JointProperties], ...] = ()
    #: normal and tangential stiffness of closed faces, in units of E / (edge length).
    contact_penalty: float = 100.0
    #: active-set iterations per event before the run ends (``contact``).
    contact_iterations: int = 30
    #: Mohr-Coulomb shear strength of intact edges (material ``cohesion``,
    #: ``friction_angle`` in degrees): None for tension-only cracking.
    shear_cohesion: float | None = None
    shear_friction_angle: float = 0.0
    #: the edge criterion (:data:`~geofrac.fracture.event_criterion.CRITERIA`).
    criterion: str = "direction"
    #: the radius R of a crack tip's zone and averaged stress (``"direction"``); None:
    #: :data:`~geofrac.fracture.direction.RADIUS_FACTOR` mean lengths of the tip's edges.
    averaging_radius: float | None = None
    #: how ``control`` drives the events: "displacement" (a [[bc]] group) or "force"
    #: (a traction, pressure or point [[load]] group).
    control_kind: str = "displacement"
    #: force control: read the displacement at the mesh node nearest to this point.
    control_point: tuple[float, float] | None = None
    #: ``[low, high]`` of the x where the crack reaches ``face`` that a reference gives
    #: (``cracking.face_band``; the result block only), or None.
    face_band: tuple[float, float] | None = None
    #: fracture energy G_f (material ``fracture_energy``): cracked edges soften over
    #: ``teeth`` saw-tooth steps (docs/cracking.md, "Fracture energy"); None: brittle.
    fracture_energy: float | None = None
    #: teeth of the saw-tooth (with ``fracture_energy``).
    teeth: int = 10
    #: ``[[load]]`` and ``[[bc]]`` groups (``"body_force"``: the body-force loads) whose
    #: loads and prescribed displacements stay at their full value while the others
    #: scale (docs/cracking.md, "Loads that do not scale together"); () scales all.
    constant: tuple[str, ...] = ()


@dataclass(frozen=True)
class LoopSettings:
    """What the event loop itself reads of ``[cracking]`` (the driver makes it).

    Attributes:
        max_events: the last event.
        output_every: a frame of the series every so many events (and the first).
        energy_drop: end when an event's energy falls below (1 − it) × the peak; None:
            never.
        contact: the crack faces' contact is logged (``cracking.contact``).
    """

    max_events: int
    output_every: int
    energy_drop: float | None
    contact: bool
