"""Distributed vectors: ghost updates, copies on every rank, setting entries.

DOLFINx functions hold ghosted PETSc vectors (:func:`function_vector`); after a solve
their ghosts are refreshed from the owners (:func:`update_ghosts`), after an assembly
the ghosts' contributions are summed into the owners (:func:`accumulate_ghosts`).
"""

from __future__ import annotations

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

__all__ = [
    "Gather",
    "accumulate_ghosts",
    "add_values",
    "function_vector",
    "ghosted_vector",
    "update_ghosts",
]


def function_vector(u: dolfinx.fem.Function) -> PETSc.Vec:
    """The ghosted PETSc vector that shares ``u``'s values (no copy; not to be destroyed)."""
    return u.x.petsc_vec


def ghosted_vector(comm: MPI.Comm, sizes: tuple[int, int]) -> PETSc.Vec:
    """A new ghosted vector without ghosts of (owned, global) size (the caller destroys it)."""
    return PETSc.Vec().createGhost([], sizes, comm=comm)


def update_ghosts(x: PETSc.Vec) -> None:
    """Copy the owners' values into the ghost entries of ``x`` (collective)."""
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)


def accumulate_ghosts(b: PETSc.Vec) -> None:
    """Add the ghost entries of an assembled ``b`` into their owners (collective)."""
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)


def add_values(v: PETSc.Vec, rows: np.ndarray, values: np.ndarray) -> None:
    """v[rows] += values and assemble ``v`` (collective).

    Args:
        v: the vector.
        rows: global indices (any rank's), shape=(k,).
        values: what is added at each, shape=(k,).
    """
    v.setValues(rows.astype(PETSc.IntType), values, addv=PETSc.InsertMode.ADD_VALUES)
    v.assemble()


class Gather:
    """Copies of distributed vectors of one layout on every rank (a cached scatter).

    Args:
        x: a vector of the layout.
    """

    def __init__(self, x: PETSc.Vec) -> None:
        self.scatter, self.full = PETSc.Scatter.toAll(x)

    def __call__(self, x: PETSc.Vec) -> np.ndarray:
        """The whole of ``x``, shape=(n_global,)."""
        self.scatter.scatter(
            x, self.full, addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD
        )
        return self.full.getArray().copy()

    def destroy(self) -> None:
        """Free the scatter and the copy."""
        self.scatter.destroy()
        self.full.destroy()
