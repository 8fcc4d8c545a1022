"""Validated ``[cracking]`` settings: what the crack driver's parts read.

The scene table is validated by :func:`geofrac.effects.cracking.configure` (its module
docstring gives each key); the dataclass lives here so that the driver does not import
the effects layer above it.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["CrackingConfig"]


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
