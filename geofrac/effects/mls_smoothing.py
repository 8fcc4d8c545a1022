"""Effect ``mls_smoothing``: MLS smoothing of the MPM strain increments (Edo (2016), §4.4).

Each particle's strain increment is replaced by the moving-least-squares fit of its
neighbours' increments (eqs. 4.50-4.58: cubic basis, cubic spline weight 4.51); a
particle with fewer neighbours than basis terms keeps its own (Edo (2016): "fewer than 4").
The influence radius is a multiple of the grid cell size (Edo (2016): "the cell size times
an arbitrary constant"). MPM scenes only; the smoothing code is imported only when a
scene declares this effect.

Scene table ``[mls_smoothing]``: ``radius`` = influence radius in cells (default 2.0);
``kind`` = ``"standard"`` (default: the fitted increments change the stresses, eqs. 4.66-4.67)
or ``"consistent"`` (the same, with the grid forces from the fit's adjoint applied to the
stresses, so the smoothing does no net work; docs/mpm_energy.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from geofrac.effects import ConfigureContext
from geofrac.model.table import Table

__all__ = ["DEFAULT_RADIUS", "KEYS", "MAX_RADIUS", "METHODS", "SmoothingConfig", "configure"]

#: Methods this effect serves.
METHODS = ("mpm",)
#: Keys of ``[mls_smoothing]``.
KEYS = ("radius", "kind")
#: Default influence radius in cells.
DEFAULT_RADIUS = 2.0
#: Largest influence radius in cells (a particle's neighbours grow as radius^dim).
MAX_RADIUS = 20.0


@dataclass(frozen=True)
class SmoothingConfig:
    """Validated smoothing settings.

    Attributes:
        radius: influence radius h as a multiple of the grid cell size.
        kind: ``standard`` (Edo (2016)) or ``consistent`` (:data:`geofrac.mpm.schemes.SMOOTHINGS`).
    """

    radius: float
    kind: str = "standard"


def configure(table: dict[str, Any], ctx: ConfigureContext) -> SmoothingConfig:
    """Validate ``[mls_smoothing]``."""
    t = Table(ctx.file, "mls_smoothing", table, allowed=KEYS)
    radius = float(t.number("radius", default=DEFAULT_RADIUS, positive=True, maximum=MAX_RADIUS))
    kind = str(t.string("kind", default="standard", choices=("standard", "consistent")))
    return SmoothingConfig(radius, kind)
