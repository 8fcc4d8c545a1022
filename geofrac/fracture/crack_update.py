"""Apply an event to the parts (Edo (2016), Fig. 2.6, "crack" and "update").

A tension or shear event cracks its sites: the crack state refits the changed units
(:meth:`~geofrac.fracture.state.CrackState.crack_many`), and the criterion, the solver
strategy, the units' caches and the crack faces learn which changed. A slip event
breaks a joint's bond; a soften event drops a cohesive pair to its next tooth.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from geofrac.fracture.event_criterion import EventCriterion
from geofrac.fracture.faces import Faces
from geofrac.fracture.linear import SolverStrategy
from geofrac.fracture.modes import MODES, Choice
from geofrac.fracture.units import Units

__all__ = ["CrackUpdate"]


class CrackUpdate:
    """Cracks the chosen sites and brings the parts that depend on them up to date.

    Args:
        units: the units (their state is the crack state).
        criterion: the event criterion (its own state follows the cracked sites).
        strategy: the solver strategy (its factorisation follows the changed units).
        contact: the crack faces, or None.

    Attributes:
        modes: how each site cracked: 0 not (or before loading), 1 + index in
            :data:`~geofrac.fracture.modes.MODES`, shape=(num_sites,) int8.
    """

    def __init__(
        self,
        units: Units,
        criterion: EventCriterion,
        strategy: SolverStrategy,
        *,
        contact: Faces | None,
    ) -> None:
        self.units, self.criterion, self.strategy = units, criterion, strategy
        self.contact = contact
        self.modes = np.zeros(0, dtype=np.int8)

    def start(self, precracked: np.ndarray) -> None:
        """The state before loading: ``precracked`` sites cracked, their face pairs."""
        state = self.units.state
        state.start(precracked)
        if self.contact is not None:
            self.contact.start(np.flatnonzero(state.cracked))
        self.modes = np.zeros(len(state.cracked), dtype=np.int8)

    def replayed(
        self, rows: Sequence[Mapping[str, object]], batches: Sequence[Sequence[int]]
    ) -> None:
        """Set the modes of the sites that a resume's replay cracked again.

        ``rows[i]`` is event i + 1's log row (its ``mode``), ``batches[i]`` its sites;
        slip and soften events leave the modes as they are (as :meth:`apply` does).
        """
        for row, batch in zip(rows, batches, strict=False):
            mode = row.get("mode")
            if mode in ("tension", "shear"):
                self.modes[np.asarray(batch, dtype=np.int64)] = 1 + MODES.index(str(mode))

    def apply(self, choice: Choice) -> None:
        """Apply the event ``choice`` (a slip or soften event has one site)."""
        cracked = [int(e) for e in choice.sites]
        contact = self.contact
        if choice.mode == "slip":
            assert contact is not None
            contact.pairs.unbond(cracked[0])
        elif choice.mode == "soften":
            assert contact is not None
            self.strategy.contact_changed(contact.soften(cracked[0]))
        else:
            self.modes[cracked] = 1 + MODES.index(choice.mode)
            changed = self.units.state.crack_many(cracked)
            self.criterion.cracked(np.array(cracked, dtype=np.int64))
            self.strategy.changed(changed)
            self.units.changed(changed)
            if contact is not None:
                blocks = contact.cracked(choice.sites, changed, cohesive=choice.mode == "tension")
                self.strategy.contact_changed(blocks)
