"""The event loop's JSON results (``summary.json``'s ``cracking`` entry)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from geofrac.fracture.assembly import Assembler
from geofrac.fracture.context import CrackContext, JsonValue, Sites
from geofrac.fracture.faces import Faces, contact_summary
from geofrac.fracture.linear import Timing
from geofrac.fracture.output import Row
from geofrac.fracture.units import Units
from geofrac.timing import peak_rss_mb

__all__ = ["FaceReport", "Summary"]


@dataclass(frozen=True)
class FaceReport:
    """Where the crack is reported to reach a boundary group (``cracking.face``).

    Attributes:
        group: the group's name.
        origin: x is reported from this abscissa (``face_origin``).
    """

    group: str
    origin: float


class Summary:
    """Writes the loop's results from its parts.

    Args:
        ctx: the shared set-up data.
        units: the units (their own entries: :meth:`~geofrac.fracture.units.Units.results`).
        sites: the pre-cracked sites.
        timing: the phases and solver counts.
        assembler: the held and pinned DOFs.
        contact: the crack faces, or None.
        contact_on: report the faces' contact (``cracking.contact``).
        modes: the event modes counted (``events_by_mode``).
        face: where the crack is reported to reach a group, or None.
        solver: the solver strategy's name (``cracking.solver``).
    """

    def __init__(
        self,
        ctx: CrackContext,
        units: Units,
        sites: Sites,
        *,
        timing: Timing,
        assembler: Assembler,
        contact: Faces | None,
        contact_on: bool,
        modes: tuple[str, ...],
        face: FaceReport | None,
        solver: str,
    ) -> None:
        self.ctx, self.units, self.sites = ctx, units, sites
        self.timing, self.assembler = timing, assembler
        self.contact, self.contact_on, self.modes = contact, contact_on, modes
        self.face, self.solver = face, solver

    def results(
        self,
        rows: list[Row],
        *,
        end: str,
        elapsed: float,
        face_hit: tuple[int, float] | None,
        done: int,
    ) -> dict[str, JsonValue]:
        """The loop's JSON results; ``done``: events this run computed (collective)."""
        ctx, state, t, held = self.ctx, self.units.state, self.timing, self.assembler
        n_pre = len(self.sites.precracked)
        out: dict[str, JsonValue] = {
            "events": len(rows),
            "end_reason": end,
            "cracked_edges": int(state.cracked.sum()),
            "new_cracked_edges": int(state.cracked.sum()) - n_pre,
            "precracked_edges": n_pre,
            "mls_cells": len(state.fits),
            "void_cells": len(state.void_cells()),
            "fragment_nodes": len(held.fragment_nodes),
            "pinned_dofs": len(held.pinned_dofs),
            "edges": len(state.mesh.edges),
            "dofs": ctx.n_global,
            "events_per_s": done / elapsed if elapsed > 0 else float("nan"),
            "phase_s": {k: ctx.comm.allreduce(v, op=MPI.MAX) for k, v in t.seconds.items()},
            # every rank's seconds per phase and per part of the work (rank order)
            "phase_s_per_rank": {k: ctx.comm.allgather(v) for k, v in t.seconds.items()},
            "part_s_per_rank": {k: ctx.comm.allgather(v) for k, v in t.parts.items()},
            "peak_rss_mb_per_rank": ctx.comm.allgather(peak_rss_mb()),
            "factorizations": t.factorizations,
            "refactor_reasons": dict(sorted(t.stale.items())),
            "refinement_solves": t.refinements,
            "cg_iterations": t.iterations,
            "solver": self.solver,
        }
        if rows:
            peak = max(rows, key=lambda r: r["reaction"])
            out |= {
                "peak_reaction": peak["reaction"],
                "peak_event": peak["event"],
                "peak_load_factor": peak["load_factor"],
                "final_strain_energy": rows[-1]["strain_energy"],
            }
        if self.face is not None:
            self._face(out, face_hit)
        out["control"] = ctx.control.describe(ctx.gm.input_ids, ctx.gm.coords)  # type: ignore[assignment]
        self.units.results(out, n_pre, len(self.sites.random))
        out["events_by_mode"] = {m: sum(1 for r in rows if r.get("mode") == m) for m in self.modes}
        self._contact(out, rows)
        return out

    def _face(self, out: dict[str, JsonValue], face_hit: tuple[int, float] | None) -> None:
        """``crack_face``: the event and x at which the crack reached the face group."""
        assert self.face is not None
        x = None if face_hit is None else face_hit[1] - self.face.origin
        out["crack_face"] = {
            "group": self.face.group,
            "event": None if face_hit is None else face_hit[0],
            "x_from_origin": x,
        }
        if self.face.group == "top":
            out["crack_top_x_mm"] = x

    def _contact(self, out: dict[str, JsonValue], rows: list[Row]) -> None:
        """The crack faces' entries: ``contact`` and ``dissipated_energy``."""
        if self.contact is not None and self.contact_on:
            control = max((abs(r["control_displacement"]) for r in rows), default=0.0)
            out["contact"] = contact_summary(self.contact, len(rows), control)  # type: ignore[assignment]
        if self.contact is not None and self.contact.softening:
            out["dissipated_energy"] = self.contact.dissipated

    def unit_load(self, energy: float, delta: float, reaction: float) -> dict[str, JsonValue]:
        """The last solved unit-load state (the results' ``unit_load``).

        What the body carries at the end under the scene's loads and prescribed
        displacements as given (before any scaling by r): also when the run ends before
        its first event (a crack pulled open, a specimen in which no edge reaches
        tension). ``delta``, ``reaction``: the control displacement and force
        (:meth:`~geofrac.fracture.control.Control.measure`); the stiffness is their ratio.
        """
        out: dict[str, JsonValue] = {
            "control_displacement": delta,
            "reaction": reaction,
            "strain_energy": energy,
            "stiffness": reaction / delta if delta != 0.0 else None,  # a held control point
        }
        if self.contact is not None and self.contact_on:
            pairs = self.contact.pairs
            act = pairs.active()
            out["min_gap"] = min(float(pairs.gap[act].min()), 0.0) if len(act) else 0.0
        return out

    def face_states(self) -> np.ndarray | None:
        """Each edge's face-pair state in the last state, shape=(num_edges,) int8.

        :data:`~geofrac.fracture.contact.NO_PAIR` where an edge has no pair, else one of
        OPEN, STICK, SLIP; None without crack-face contact.
        """
        if self.contact is None or not self.contact_on:
            return None
        return self.contact.pairs.state.copy()
