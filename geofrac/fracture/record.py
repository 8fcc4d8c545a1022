"""What the event loop records of an event: its row of ``events.csv`` and its frame fields."""

from __future__ import annotations

import numpy as np

from geofrac.fracture.context import CrackContext
from geofrac.fracture.equilibrium import Solved
from geofrac.fracture.faces import Faces, contact_frame
from geofrac.fracture.modes import Choice
from geofrac.fracture.output import OutputWriter, Row
from geofrac.fracture.units import Units

__all__ = ["Recorder"]


class Recorder:
    """Rows of the event log and per-site fields of the crack series.

    Args:
        ctx: the shared set-up data (the input node numbers).
        units: the units (the sites' nodes and points).
        output: the writer (the contact changes file).
        contact: the crack faces, or None.
        contact_on: record the faces' contact (``cracking.contact``).
    """

    def __init__(
        self,
        ctx: CrackContext,
        units: Units,
        output: OutputWriter,
        *,
        contact: Faces | None,
        contact_on: bool,
    ) -> None:
        self.ctx, self.units, self.output = ctx, units, output
        self.contact, self.contact_on = contact, contact_on
        #: the faces' gaps, slips and tractions are those of the unit load, scaled by r
        #: (False: of the event's state itself, the constant-load loop's).
        self.proportional = True

    def row(
        self,
        event: int,
        choice: Choice,
        *,
        solved: Solved,
        control: tuple[float, float],
        energy: float,
    ) -> Row:
        """The event log's row of the event (the first of its sites is reported).

        ``control``: the unit solution's control displacement and force
        (:meth:`~geofrac.fracture.control.Control.measure`); the row holds r times them.
        ``energy``: the event's strain energy. With the faces' contact, their counts and
        worst gap go into the row and the state changes of ``solved`` into the changes
        file.
        """
        gm, units, contact = self.ctx.gm, self.units, self.contact
        r, site = choice.r, int(choice.sites[0])
        a, b = units.state.mesh.edges[site]
        mid = units.site_point(site)
        row: Row = {
            "event": event,
            "edge": site,
            "node_a": int(gm.input_ids[a]),
            "node_b": int(gm.input_ids[b]),
            "x": float(mid[0]),
            "y": float(mid[1]),
            "r": r,
            "load_factor": r,
            "control_displacement": r * control[0],
            "reaction": r * control[1],
            "strain_energy": energy,
            "edges_cracked": len(choice.sites),
            "iterations": solved.iterations,
            "mode": choice.mode,
        }
        if contact is not None and contact.softening:
            row["dissipated_energy"] = 0.0  # set after the event (:meth:`dissipation`)
        if contact is not None and self.contact_on:
            f = r if self.proportional else 1.0
            row |= contact.record(f)
            row["contact_changes"] = len(solved.changes)
            pairs = contact.pairs
            self.output.contact_changes(
                event,
                [(e, a, b, f * pairs.gap[e], f * pairs.slip[e]) for e, a, b in solved.changes],
            )
        return row

    def dissipation(self, row: Row) -> None:
        """The energy the cohesive faces have dissipated, after the event's update."""
        if self.contact is not None and self.contact.softening:
            row["dissipated_energy"] = self.contact.dissipated

    def edge_data(self, r: float, modes: np.ndarray) -> dict[str, np.ndarray]:
        """Per-edge fields of the crack series beside ``crack``: mode, contact at load r."""
        out = {"mode": modes.astype(float)}
        if self.contact is not None and self.contact_on:
            out |= contact_frame(self.contact.pairs, r if self.proportional else 1.0)
        return out
