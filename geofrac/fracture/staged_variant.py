"""The edge variant of a cracking scene with ``[[stages]]`` (docs/insitu.md).

Its units carry a :class:`~geofrac.fracture.staged_state.StagedCrackState`, whose cells
removed by a stage stay void; the effect chooses it for a scene with stages
(:func:`geofrac.effects.cracking.make_driver`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

from geofrac.fracture.context import CrackContext
from geofrac.fracture.driver import EdgeVariant
from geofrac.fracture.staged_state import StagedCrackState
from geofrac.fracture.units import EdgeUnits, Units

__all__ = ["STAGED_EDGES", "StagedEdgeVariant"]


@dataclass(frozen=True)
class StagedEdgeVariant(EdgeVariant):
    """Element edges with cells that stages remove (:class:`StagedCrackState`)."""

    def units(self, ctx: CrackContext) -> Units:
        """:class:`~geofrac.fracture.units.EdgeUnits` on a :class:`StagedCrackState`."""
        units = cast(EdgeUnits, super().units(ctx))
        old = units.state
        units.state = StagedCrackState(
            old.mesh, old.frozen, old.forced, old.settings, old.mapper, cut=old.cut
        )
        return cast(Units, units)  # (EdgeUnits' state is the protocol's CrackState)


#: The edge variant of a staged cracking scene.
STAGED_EDGES = StagedEdgeVariant()
