"""Solve the event's unit load (Edo (2016), Fig. 2.6, "solve").

:class:`Equilibrium` is what the event loop asks for the unit-load solution of the
current crack state: :class:`LinearEquilibrium` solves once with the
:class:`~geofrac.fracture.linear.SolverStrategy`; :class:`ContactEquilibrium` then
settles the crack faces' states by an active-set iteration (docs/cracking.md, "Crack
faces in contact"). Both own the work vector and the gather of the solutions.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.fracture.assembly import LoadCase
from geofrac.fracture.faces import Faces
from geofrac.fracture.incremental import Gather
from geofrac.fracture.linear import SolverStrategy
from geofrac.fracture.units import Block

__all__ = [
    "ContactEquilibrium",
    "ContactUnsettled",
    "Equilibrium",
    "LinearEquilibrium",
    "Solved",
    "Visited",
]


#: Per pair, the states it left during an event: state -> (violation, slip direction).
Visited = dict[int, dict[int, tuple[float, float]]]


class ContactUnsettled(Exception):
    """The crack faces' states still changed after ``contact_iterations`` iterations."""


@dataclass
class Solved:
    """A unit-load solution.

    Attributes:
        u: the global solution, shape=(n_global,).
        iterations: the linear solver's iterations of the first solve.
        changes: the crack faces' state changes made to settle it: (edge, old, new).
    """

    u: np.ndarray
    iterations: int
    changes: list[tuple[int, int, int]] = field(default_factory=list)


class Equilibrium(Protocol):
    """The unit-load solution of the current crack state (collective)."""

    def open(self, space: dolfinx.fem.FunctionSpace) -> None:
        """Make the work vector of the unknown's ``space`` and its gather."""
        ...

    def solve(self, u_prev: np.ndarray) -> Solved:
        """Solve from the previous solution ``u_prev`` (held DOFs keep its values).

        Raises:
            RunError: the solve failed.
        """
        ...

    def settle(self, solved: Solved) -> Solved:
        """Bring the state's nonlinear parts (the crack faces) to rest from ``solved``.

        Raises:
            RunError: a solve failed; ContactUnsettled: the faces did not settle.
        """
        ...

    def destroy(self) -> None:
        """Free the gather."""
        ...


class LinearEquilibrium:
    """One solve with the solver strategy.

    Args:
        strategy: the solver strategy (``cracking.solver``).
    """

    def __init__(self, strategy: SolverStrategy) -> None:
        self.strategy = strategy
        self._work: dolfinx.fem.Function | None = None
        self.gather: Gather | None = None

    def open(self, space: dolfinx.fem.FunctionSpace) -> None:
        """Make the work vector (a ghosted vector of ``space``) and its gather."""
        self._work = dolfinx.fem.Function(space)
        self.gather = Gather(self._work.x.petsc_vec)

    def solve(self, u_prev: np.ndarray) -> Solved:
        """The strategy's solution from ``u_prev``."""
        assert self._work is not None and self.gather is not None
        return Solved(*self.strategy.solve(u_prev, self._work.x.petsc_vec, self.gather))

    def settle(self, solved: Solved) -> Solved:
        """Nothing to settle: ``solved`` itself."""
        return solved

    def solve_again(self, u_prev: np.ndarray, case: LoadCase) -> np.ndarray:
        """Another right-hand side of the state just solved (constant loads; collective).

        The work vector starts from ``u_prev`` (CG's guess; held DOFs keep it) and holds
        the last :meth:`solve`'s solution again afterwards (the next guess of that one).
        """
        assert self._work is not None and self.gather is not None
        x = self._work.x.petsc_vec
        r0, r1 = x.getOwnershipRange()
        keep = x.copy()
        try:
            x.setArray(u_prev[r0:r1])
            return self.strategy.solve_again(u_prev, x, self.gather, case=case)
        finally:
            keep.copy(x)
            keep.destroy()

    def destroy(self) -> None:
        """Free the gather."""
        if self.gather is not None:
            self.gather.destroy()
        self.gather = None


class ContactEquilibrium(LinearEquilibrium):
    """A solve, then the active-set iteration of the crack faces' states.

    Args:
        strategy: the solver strategy.
        contact: the crack faces.
        iterations: active-set iterations per event (``contact_iterations``).
    """

    def __init__(self, strategy: SolverStrategy, contact: Faces, iterations: int) -> None:
        super().__init__(strategy)
        self.contact, self.iterations = contact, iterations

    def settle(self, solved: Solved) -> Solved:
        """Active-set iteration on the crack faces from the solution ``solved`` (collective).

        Every pair whose state the solution violates changes at once. A pair that would
        return to a state it left earlier in the event cycles (no set of states
        satisfies every pair's conditions, which penalty friction without load steps
        allows): it is held in the state it violated least (counted, with the largest
        violation, in the results), also in later events until a cell beside it changes
        or the field violates its held state by more than twice as much. So each pair
        changes at most three times per event. Returns the settled solution (with the
        first solve's iterations) and every state change (edge, old, new) made.

        Raises:
            ContactUnsettled: states still change after ``iterations`` solves.
            RunError: a solve failed.
        """
        contact, limit, u = self.contact, self.iterations, solved.u
        made: list[tuple[int, int, int]] = []
        history: Visited = {}
        for it in range(limit + 1):
            changes, blocks = contact.update(u)
            if not changes:
                return Solved(u, solved.iterations, made)
            self.absorb(changes, blocks, history=history, made=made, last=it == limit)
            if it == limit:
                break
            u = self.solve(u).u
            contact.iterations += 1
        raise self.unsettled(changes)

    def absorb(
        self,
        changes: list[tuple[int, int, int]],
        blocks: list[Block],
        *,
        history: Visited,
        made: list[tuple[int, int, int]],
        last: bool,
    ) -> None:
        """Note one active-set step's ``changes``; unless ``last``, put them into the system.

        ``history``: per pair, the states it left in this event (their violation and slip
        direction); a pair that returns to one of them is held (see :meth:`settle`).
        ``made`` gathers every change (edge, old, new). ``blocks``: the step's block
        changes, handed to the solver strategy with those of the held pairs.
        """
        contact, pairs = self.contact, self.contact.pairs
        cycling = []
        for e, old, new in changes:
            left = history.setdefault(e, {})
            left[old] = (float(pairs.violation[e]), float(pairs.sign[e]))
            if new in left:
                cycling.append(e)
        made += changes
        if last:
            return
        if cycling:
            entered = {e: new for e, _, new in changes}
            contact.freeze_least_violated({e: history[e] for e in cycling})
            blocks += contact.resync(cycling)
            made += [
                (e, entered[e], int(pairs.state[e]))
                for e in cycling
                if pairs.state[e] != entered[e]
            ]
        self.strategy.contact_changed(blocks)

    def unsettled(self, changes: list[tuple[int, int, int]]) -> ContactUnsettled:
        """The error of states that still change after ``iterations`` solves."""
        return ContactUnsettled(
            f"the crack faces' contact states did not settle in {self.iterations} "
            f"iterations ({len(changes)} pairs still changed state, e.g. edge "
            f"{changes[0][0]}); raise cracking.contact_iterations or contact_penalty"
        )
