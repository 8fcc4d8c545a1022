"""Choose the event (Edo (2016), Fig. 2.6, "choose"): the least load factor over the modes.

The event criterion (:class:`~geofrac.fracture.event_criterion.EventCriterion`) gives the
sites that crack in tension and their r = f_t/σ1 (2.20); :class:`ModeChooser` sets the
other modes against it: Mohr-Coulomb shear of intact edges (``cohesion`` and
``friction_angle`` of the material), slip of bonded joints and the next tooth of
cohesive faces (:mod:`geofrac.fracture.contact`). The event is the mode of least r.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geofrac.fracture.contact import (
    edge_frames,
    edge_tractions,
    shear_factors,
    slip_factors,
    soften_factors,
)
from geofrac.fracture.criterion import TIE_TOLERANCE, edge_means, least
from geofrac.fracture.event_criterion import EventCriterion
from geofrac.fracture.faces import Faces
from geofrac.fracture.units import Units

__all__ = ["MODES", "Choice", "ModeChooser", "ShearStrength"]

#: Event modes (``events.csv`` column ``mode``): an edge cracks in tension (2.20) or in
#: shear (Mohr-Coulomb), a bonded joint starts to slip, or the cohesive faces of a crack
#: drop to their next tooth (fracture energy, docs/cracking.md "Fracture energy").
MODES = ("tension", "shear", "slip", "soften")


@dataclass(frozen=True)
class ShearStrength:
    """Mohr-Coulomb strength of intact edges: cohesion c > 0 and friction angle φ (degrees)."""

    cohesion: float
    friction_angle: float


@dataclass(frozen=True)
class Choice:
    """The event: the sites that change, shape=(k,), its load factor r and its mode."""

    sites: np.ndarray
    r: float
    mode: str


class ModeChooser:
    """The event of least r over tension, shear, joint slip and softening.

    Args:
        criterion: the tension criterion (its ``points`` break ties between sites).
        units: the units (``midpoint_stress`` of the edge units for shear).
        contact: the crack faces (joint slip, cohesive teeth), or None.
        shear: the shear strength of intact edges, or None (tension only).
    """

    def __init__(
        self,
        criterion: EventCriterion,
        units: Units,
        *,
        contact: Faces | None = None,
        shear: ShearStrength | None = None,
    ) -> None:
        self.criterion, self.units = criterion, units
        self.contact, self.shear = contact, shear
        # unit tangents and normals of the edges (shear events), computed once
        self._frames: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def modes(self) -> tuple[str, ...]:
        """The modes this chooser can return (``soften`` with cohesive faces only)."""
        return MODES if self.contact is not None and self.contact.softening else MODES[:3]

    def choose(self, sigma1: np.ndarray, *, floor: float) -> Choice:
        """The event from the sites' drive ``sigma1`` (the criterion's ``site_stress``).

        A drive counts only above ``floor`` (the stress floor of the tension criterion).
        Ties within :data:`~geofrac.fracture.criterion.TIE_TOLERANCE` keep the earlier
        mode of :data:`MODES`, then the site that comes first by position
        (:func:`~geofrac.fracture.criterion.tie_order`). No site: an empty choice.
        """
        edges, r = self.criterion.select(sigma1, floor=floor)
        mode = "tension"
        points = self.criterion.points
        for name, candidates in self._candidates(floor):
            sites, factors = candidates
            e, re = least(sites, factors, points)
            if re < r * (1.0 - TIE_TOLERANCE):
                edges, r, mode = np.array([e]), re, name
        return Choice(edges, r, mode)

    def _candidates(self, floor: float) -> list[tuple[str, tuple[np.ndarray, np.ndarray]]]:
        """(mode, (sites, r)) of the modes besides tension, in the order of :data:`MODES`."""
        out = []
        if self.shear is not None:
            out.append(("shear", self._shear(floor)))
        if self.contact is not None:
            out.append(("slip", slip_factors(self.contact.pairs, floor=floor)))
        if self.contact is not None and self.contact.softening:
            out.append(("soften", soften_factors(self.contact.pairs, floor=floor)))
        return out

    def _shear(self, floor: float) -> tuple[np.ndarray, np.ndarray]:
        """Uncracked crackable edges and the r of their Mohr-Coulomb failure."""
        assert self.shear is not None
        state = self.units.state
        sigma = edge_means(state.mesh, self.units.midpoint_stress)  # type: ignore[attr-defined]
        cand = np.flatnonzero(~state.cracked & state.crackable)
        if self._frames is None:
            self._frames = edge_frames(state.mesh)
        t, n = self._frames
        sn, tau = edge_tractions(sigma[cand], t[cand], n[cand])
        s = self.shear
        return cand, shear_factors(
            sn, tau, s.cohesion, friction_angle=s.friction_angle, floor=floor
        )
