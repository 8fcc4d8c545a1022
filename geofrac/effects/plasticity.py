"""Effect ``plasticity``: Drucker-Prager perfect plasticity of MPM particles (Edo (2016), §4.3.2).

Yield function f = β I₁ + √J₂ − k (eqs. 4.39-4.43) with return mapping, the Jaumann rate
(D.30-D.31) applied before each increment: the model :mod:`geofrac.mpm.plasticity` (registry
:data:`geofrac.mpm.constitutive.MODELS`) built from this table. MPM scenes
in 2D (plane strain) and 3D only; the plasticity code is imported only when a scene
declares this effect.

Scene table ``[plasticity]``:

- ``friction_angle``: internal friction angle φ in degrees, required (the landslide of
  Edo (2016) sweeps 8 ... 25);
- ``cohesion``: c >= 0 (default 0, the rain-softened landslide of Edo (2016));
- ``dilatancy_angle``: ψ in degrees, 0 <= ψ <= φ (default 0: no plastic volume change).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from geofrac.effects import ConfigureContext
from geofrac.model.errors import SceneError
from geofrac.model.table import Table

__all__ = ["KEYS", "MAX_COHESION", "METHODS", "PlasticityConfig", "configure"]

#: Methods this effect serves.
METHODS = ("mpm",)
#: Keys of ``[plasticity]``.
KEYS = ("friction_angle", "cohesion", "dilatancy_angle")
#: Largest cohesion (stress units; the bound of ``material.E``).
MAX_COHESION = 1e15


@dataclass(frozen=True)
class PlasticityConfig:
    """Validated Drucker-Prager settings.

    Attributes:
        friction_angle: φ in degrees.
        cohesion: c.
        dilatancy_angle: ψ in degrees.
    """

    friction_angle: float
    cohesion: float
    dilatancy_angle: float


def configure(table: dict[str, Any], ctx: ConfigureContext) -> PlasticityConfig:
    """Validate ``[plasticity]``."""
    if ctx.gdim == 1:
        raise SceneError(ctx.file, "effects", "'plasticity' needs a 2D or 3D scene")
    t = Table(ctx.file, "plasticity", table, allowed=KEYS)
    phi = float(t.number("friction_angle", required=True))  # type: ignore[arg-type]
    if not 0 <= phi < 90:
        raise t.error("friction_angle", f"must lie in [0, 90) degrees, got {phi}")
    c = float(t.number("cohesion", default=0.0, minimum=0.0, maximum=MAX_COHESION))
    psi = float(t.number("dilatancy_angle", default=0.0))
    if not 0 <= psi <= phi:
        raise t.error("dilatancy_angle", f"must lie in [0, friction_angle = {phi}], got {psi}")
    return PlasticityConfig(phi, c, psi)
