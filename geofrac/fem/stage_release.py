"""The pending release of a plastic construction stage, added to the Newton residual.

A stage that removes cells (docs/plasticity.md, "Construction stages") computes at its
start r = I_live(σ) − F_live, the out-of-balance force of the remaining body at the
current state (minus the forces the removed cells exerted on it, their stress and
weight). The stage's residual is F(u) − (1 − μ) r: at μ = 0 the current state is in
equilibrium, at μ = 1 the removed cells are gone. μ = ``start`` + ``share`` · λ with
the load factor λ of the stage's steps (0 → 1).
"""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

__all__ = ["StageRelease"]


class StageRelease:
    """−(1 − μ) r on this rank's owned rows (:class:`geofrac.solvers.snes.ExtraTerms`).

    Args:
        V: the displacement space.
        factor: the load factor constant λ of the steps.

    Attributes:
        vector: r on the owned rows, shape=(owned dofs × bs,).
        start: the share of r applied before this stage (μ at λ = 0).
        share: the share this stage applies (μ = start + share at λ = 1).
        active: whether the term is added (False: nothing removed yet).
    """

    def __init__(self, V: dolfinx.fem.FunctionSpace, factor: dolfinx.fem.Constant) -> None:
        imap, bs = V.dofmap.index_map, V.dofmap.index_map_bs
        self.factor = factor
        self.rows = (imap.local_range[0] * bs + np.arange(imap.size_local * bs)).astype(np.int64)
        self.vector = np.zeros(imap.size_local * bs)
        self.start, self.share, self.active = 0.0, 0.0, False

    def released(self) -> float:
        """μ at the current load factor: the share of r applied."""
        return self.start + self.share * float(self.factor.value)

    def values(self) -> np.ndarray:
        """−(1 − μ) r on the owned rows (zero when inactive), shape=(owned dofs × bs,)."""
        if not self.active:
            return np.zeros_like(self.vector)
        return -(1.0 - self.released()) * self.vector

    def residual_entries(self) -> tuple[np.ndarray, np.ndarray]:
        """(global rows, values) of the term."""
        return self.rows, self.values()

    def jacobian_entries(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """None: r is fixed during the stage."""
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, np.zeros(0)

    def jacobian_pattern(self) -> tuple[np.ndarray, np.ndarray]:
        """None: r adds no Jacobian entries."""
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
