"""The scales that every decision of the event loop is judged against (pure numpy).

A sequentially linear run solves the *unit load* (the scene's loads and prescribed
displacements as given) and scales it by r (Edo (2016), eqs. 2.20-2.21). Whether the body still
carries load, whether an edge is in tension, whether a pair of crack faces is shut:
each is a comparison of a computed number with zero, and a computed zero is round-off
whose sign and size depend on the BLAS kernel, the number of ranks and the numbering of
the mesh. So each comparison is made against a stated scale with a stated tolerance:

- a priori, from the scene alone (:class:`Scales`): the specimen's size L (diagonal of
  the mesh's bounding box), the unit load's displacement δ (the control group's mean
  prescribed |u|; under force control F/(E t), F the control load's resultant,
  :mod:`~geofrac.fracture.control`), E and the volume V = t·area; from them the stress
  E δ / L and the energy ½ E V (δ / L)² of a uniform strain δ / L;
- from the solution being judged: its root-mean-square stress √(2 E W / V), W its
  strain energy.

The table of decisions is in docs/cracking.md ("Decisions and their scales").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "MAX_LOAD_RATIO",
    "SEPARATED",
    "TENSION_FLOOR",
    "Scales",
]

#: The body is *separated* when the unit-load strain energy falls below this fraction of
#: its scale: the first event's unit-load energy, or at the first event the a-priori
#: energy ½ E V (δ/L)² (no load path is left between the control group and the supports,
#: the "unstable" end of Edo (2016), reached without a singular matrix when both pieces
#: are held by Dirichlet conditions). Round-off leaves about 1e-13 of the a-priori
#: energy in a specimen that carries nothing; any load path, down to a ligament of a
#: millionth of the specimen's width, keeps far more than 1e-9.
SEPARATED = 1e-9

#: An event needing a load factor beyond this multiple of the first event's ends the
#: run as ``separated``: the unit-load solution that gave it has lost its load path
#: (a sequentially linear run's load factor varies by a few decades at most).
MAX_LOAD_RATIO = 1e6

#: A site counts as in tension (a face as sliding, a joint as driven to slip) only when
#: its stress exceeds this fraction of the unit solution's root-mean-square stress: a
#: stress that is zero in exact arithmetic (σ_xx of uniaxial compression) is round-off
#: of either sign, and an event at r > 10⁶ f_t / σ_rms would need every other point to
#: carry a million times the strength.
TENSION_FLOOR = 1e-6


@dataclass(frozen=True)
class Scales:
    """The unit load's a-priori scales.

    Attributes:
        length: L, the diagonal of the mesh's bounding box.
        displacement: δ, the control group's mean |prescribed displacement|, or F/(E t)
            under force control (F the control load's resultant), > 0.
        modulus: E.
        volume: V, thickness × area of the mesh.
    """

    length: float
    displacement: float
    modulus: float
    volume: float

    @classmethod
    def of_mesh(
        cls,
        coords: np.ndarray,
        cells: np.ndarray,
        *,
        displacement: float,
        modulus: float,
        thickness: float,
    ) -> Scales:
        """The scales of a triangle mesh.

        Args:
            coords: node coordinates, shape=(num_nodes, 2).
            cells: node ids of each triangle, shape=(num_cells, 3).
            displacement: δ.
            modulus: E.
            thickness: t.
        """
        x = np.asarray(coords, dtype=float)[:, :2]
        length = float(np.hypot(*(x.max(axis=0) - x.min(axis=0))))
        p = x[np.asarray(cells)]
        d1, d2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
        area = 0.5 * float(np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum())
        return cls(length, float(displacement), float(modulus), thickness * area)

    @property
    def stress(self) -> float:
        """E δ / L: the stress of a uniform strain δ / L."""
        return self.modulus * self.displacement / self.length

    @property
    def energy(self) -> float:
        """½ E V (δ / L)²: the energy of a uniform strain δ / L."""
        return 0.5 * self.modulus * self.volume * (self.displacement / self.length) ** 2

    def rms_stress(self, energy: float) -> float:
        """√(2 E W / V): the root-mean-square stress of a solution of strain energy W."""
        return math.sqrt(max(2.0 * self.modulus * energy / self.volume, 0.0))

    def separated(self, energy: float, first_energy: float | None) -> str | None:
        """Why a unit solution of strain energy ``energy`` carries nothing, or None.

        Args:
            energy: the unit solution's strain energy (round-off may make it negative).
            first_energy: the first event's unit-load energy; None at the first event,
                which is judged against :attr:`energy`.

        Returns:
            the reason, for the run's ``end_detail``; None when it carries load.
        """
        scale, of = (
            (self.energy, "½ E V (δ/L)²")
            if first_energy is None
            else (first_energy, "the first event's unit-load energy")
        )
        if energy > SEPARATED * scale:
            return None
        return (
            f"the unit-load strain energy {energy:.3g} is below {SEPARATED:g} of {of} ({scale:.3g})"
        )

    def beyond(
        self,
        load_factor: float,
        first_load_factor: float | None,
        *,
        control_displacement: float | None = None,
    ) -> str | None:
        """Why an event at ``load_factor`` would be an artefact of a lost load path, or None.

        The event's control displacement must stay within the specimen's size L, and r
        within :data:`MAX_LOAD_RATIO` times the first event's (None at the first event).
        ``control_displacement``: the event's |control displacement| as measured (force
        control: r |δ_u|, :meth:`~geofrac.fracture.control.Control.measure`); default
        r δ, the control displacement of displacement control.
        """
        control = (
            load_factor * self.displacement
            if control_displacement is None
            else abs(control_displacement)
        )
        if not control <= self.length:
            return (
                f"the next event would need a control displacement of {control:.3g}, beyond "
                f"the specimen's size {self.length:.3g}"
            )
        if first_load_factor is not None and not load_factor <= MAX_LOAD_RATIO * first_load_factor:
            return (
                f"the next event would need a load factor of {load_factor:.3g}, more than "
                f"{MAX_LOAD_RATIO:g} times the first event's {first_load_factor:.3g}"
            )
        return None
