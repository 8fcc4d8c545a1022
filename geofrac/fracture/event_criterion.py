"""The event criterion: which crack sites crack next, and the load factor of the event.

An :class:`EventCriterion` turns the units' largest principal stresses
(:meth:`~geofrac.fracture.units.Units.measures`) into one σ1 per crack site and picks
the sites with least r = f_t / σ1 (Edo (2016), eq. 2.20; 3.8 for grains). The edge
variant :class:`EdgeCriterion` averages the two cells of an edge at its midpoint; the
grain variant (:class:`~geofrac.fracture.grain_driver.GrainCriterion`) takes the larger
of the two grains at the interface centre. A new criterion is one more class with these
two methods, passed to :class:`~geofrac.fracture.driver.CrackDriver` in its
:class:`~geofrac.fracture.driver.Parts`.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from geofrac.fracture.config import CrackingConfig
from geofrac.fracture.criterion import edge_principal, select_edges
from geofrac.fracture.units import SiteState

__all__ = ["EdgeCriterion", "EventCriterion", "next_sites"]


class EventCriterion(Protocol):
    """Which sites crack in an event, and r.

    Attributes:
        points: where each site lies (ties go by position), shape=(num_sites, 2).
    """

    points: np.ndarray

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """σ1 per crack site from the units' values, shape=(num_sites,)."""
        ...

    def select(self, sigma1: np.ndarray, *, floor: float) -> tuple[np.ndarray, float]:
        """(sites that crack, shape=(k,), k ≥ 1 unless none has σ1 > ``floor``; r)."""
        ...


def next_sites(
    state: SiteState,
    config: CrackingConfig,
    sigma1: np.ndarray,
    *,
    floor: float,
    points: np.ndarray,
) -> tuple[np.ndarray, float]:
    """The uncracked, crackable sites of least r = f_t / σ1, with the batch settings.

    ``edges_per_event`` sites with r ≤ (1 + ``batch_tolerance``) r_min at most
    (:func:`~geofrac.fracture.criterion.select_edges`); none when no site has
    σ1 > ``floor``. Ties go by ``points``, shape=(num_sites, 2).
    """
    candidates = ~state.cracked & state.crackable
    return select_edges(
        sigma1,
        candidates,
        config.tensile_strength,
        config.batch_tolerance,
        config.edges_per_event,
        floor=floor,
        points=points,
    )


class EdgeCriterion:
    """Element edges: σ1 of an edge is the mean of its cells' values at its midpoint.

    Args:
        state: the edge crack state.
        config: the ``[cracking]`` settings.
    """

    def __init__(self, state: SiteState, config: CrackingConfig) -> None:
        self.state, self.config = state, config
        #: the edge midpoints, shape=(num_edges, 2).
        self.points = state.mesh.midpoints()

    def site_stress(self, unit_s1: np.ndarray) -> np.ndarray:
        """σ1 per edge from σ1 per cell at its local edges, shape=(num_cells, 3)."""
        return edge_principal(self.state.mesh, unit_s1)

    def select(self, sigma1: np.ndarray, *, floor: float) -> tuple[np.ndarray, float]:
        """The edges of least r (:func:`next_sites`)."""
        return next_sites(self.state, self.config, sigma1, floor=floor, points=self.points)
