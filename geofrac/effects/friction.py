"""Effect ``friction``: Coulomb friction where MPM material meets a boundary (Edo (2016), §4.3.3).

On the grid nodes of the named boundaries, motion into the boundary is removed and the
tangential motion is slowed by μ times the normal change (eqs. 4.44-4.47; see
:mod:`geofrac.mpm.friction`); motion away from the boundary is free. Without this
effect those nodes are held (no slip). MPM scenes only; the friction code is imported
only when a scene declares this effect.

Scene table ``[friction]``:

- ``mu``: Coulomb coefficient μ >= 0 (Edo (2016): 0.1), required unless every boundary
  has its own;
- ``boundaries``: walled grid sides (``x_min`` ... ``z_max``, as set in ``mpm.walls``)
  and/or ``"bed"`` (the ``mpm.bed`` polyline), default ``["bed"]``; either a list of
  names (each with ``mu``) or a table name -> μ (``{ bed = 0.1, x_max = 0.5 }``), a
  boundary's own μ; ``mu`` may then be left out.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from geofrac.effects import ConfigureContext
from geofrac.model.errors import did_you_mean
from geofrac.model.table import Table, short

__all__ = ["KEYS", "MAX_MU", "METHODS", "FrictionConfig", "configure"]

#: Methods this effect serves.
METHODS = ("mpm",)
#: Keys of ``[friction]``.
KEYS = ("mu", "boundaries")
#: Largest Coulomb coefficient (rock joints: about 0.6 ... 1; 100 is a glued wall).
MAX_MU = 100.0


@dataclass(frozen=True)
class FrictionConfig:
    """Validated friction settings.

    Attributes:
        mu: the common Coulomb friction coefficient (None when every boundary has its
            own).
        boundaries: names of the frictional boundaries.
        mus: each boundary's μ, in the order of ``boundaries``.
    """

    mu: float | None
    boundaries: tuple[str, ...]
    mus: tuple[float, ...] = ()


def configure(table: dict[str, Any], ctx: ConfigureContext) -> FrictionConfig:
    """Validate ``[friction]``; the boundaries must exist (``ctx.groups``)."""
    t = Table(ctx.file, "friction", table, allowed=KEYS)
    names = t.data.get("boundaries", ["bed"])
    own: dict[str, float] = {}
    if isinstance(names, dict):
        b = Table(ctx.file, "friction.boundaries", names, allowed=list(names))
        if not names:
            raise t.error("boundaries", "must name at least one boundary")
        own = {
            str(n): float(b.number(n, required=True, minimum=0.0, maximum=MAX_MU))  # type: ignore[arg-type]
            for n in names
        }
        names = list(names)
    mu = t.number("mu", required=len(own) < len(names), minimum=0.0, maximum=MAX_MU)
    if (
        not isinstance(names, list)
        or not names
        or not all(isinstance(n, str) for n in names)
        or len(set(names)) != len(names)
    ):
        raise t.error(
            "boundaries",
            "must be a list of distinct boundary names or a table name -> mu, got " + short(names),
        )
    for name in names:
        if name not in ctx.groups:
            where = ", ".join(sorted(ctx.groups)) or "none: set mpm.walls or mpm.bed"
            raise t.error(
                "boundaries",
                f"no boundary {name!r} (walled sides and bed: {where})"
                + did_you_mean(str(name), ctx.groups),
            )
    mus = tuple(own.get(n, mu) for n in names)
    return FrictionConfig(None if mu is None else float(mu), tuple(names), mus)  # type: ignore[arg-type]
