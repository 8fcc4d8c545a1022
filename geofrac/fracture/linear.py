"""The linear-solver strategies of the event loop (``cracking.solver``), one protocol.

Every event solves the unit-load problem of the current crack state. A
:class:`SolverStrategy` decides how:

- :class:`UpdateSolver` (``"update"``, the default) keeps one factorisation for many
  events and corrects its solution exactly for the units changed since
  (:mod:`geofrac.fracture.incremental`: Woodbury on the touched DOFs, with entries of the
  inverse from MUMPS's sparse solves), refactorising when the touched DOFs exceed
  ``update_dofs`` or a piece is cut free;
- :class:`ReuseSolver` (``"reuse"``) uses the factorisation as the preconditioner of CG,
  renewed when CG needs more than ``reuse_iterations`` iterations;
- :class:`RefactorSolver` (``"refactor"``) factorises every event (the reference).

All three hold the nodes of cut-free pieces when the system turns singular
(:meth:`~geofrac.fracture.assembly.Assembler.find_fragments`) and raise
:class:`~geofrac.errors.RunError` when it stays singular.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.assembly import Assembler, LoadCase
from geofrac.fracture.context import CrackContext
from geofrac.fracture.incremental import Gather, IncrementalSolver, Stale
from geofrac.fracture.units import Block, Fit
from geofrac.solvers import LinearSolver, Matrix, PreconditionedCG, Vector, transposed

__all__ = [
    "PARTS",
    "PREFIX",
    "PiecesHeld",
    "RefactorSolver",
    "ReuseSolver",
    "SolverStrategy",
    "Timing",
    "UpdateSolver",
    "make_strategy",
]

#: Options prefix of the crack solver.
PREFIX = "geofrac_crack_"

#: The parts of an event's work that :class:`Timing` measures inside its phases:
#: ``factorise`` (a new reference: assembly, factorisation, its solve), and with the
#: ``update`` solver ``inverse_entries`` (MUMPS's selected entries of A₀⁻¹ for new DOFs
#: of T), ``dense_update`` (N⁻¹ and the correction g on T, rows shared among the ranks),
#: ``substitution`` (the solve x = y + A₀⁻¹ E g) and ``residual`` (gathering x, the
#: residual check and refinement); ``stresses`` (σ1, energy and reaction of the
#: units), ``choose`` (the criterion and the event's sites) and ``crack`` (crack the
#: sites, refit the MLS cells).
PARTS = (
    "factorise",
    "inverse_entries",
    "dense_update",
    "substitution",
    "residual",
    "stresses",
    "choose",
    "crack",
)


class PiecesHeld(RunError):
    """Pieces cut free were held while solving another right-hand side.

    :meth:`UpdateSolver.solve_again` found its matrix singular: the system changed, so
    every right-hand side of the event must be solved again.
    """


@dataclass
class Timing:
    """Seconds per phase of the event loop on this rank, and the solver's counts."""

    seconds: dict[str, float] = field(
        default_factory=lambda: dict.fromkeys(("assemble", "solve", "criterion", "update"), 0.0)
    )
    factorizations: int = 0
    iterations: int = 0
    #: why the ``update`` solver factorised afresh: kind -> count.
    stale: dict[str, int] = field(default_factory=dict)
    #: refinement steps of the ``update`` solver that needed solves with the factor.
    refinements: int = 0
    #: seconds of the work inside the phases, by what it is (:data:`PARTS`): the parts
    #: lie within the phases' time (``factorise`` spans assemble and solve), and need
    #: not cover it.
    parts: dict[str, float] = field(default_factory=lambda: dict.fromkeys(PARTS, 0.0))

    def add(self, phase: str, t0: float, *, part: tuple[str, float] | None = None) -> float:
        """Add the time since ``t0`` to ``phase``; returns now.

        ``part``: (name, start) also adds the time since start to that part.
        """
        t1 = time.perf_counter()
        self.seconds[phase] += t1 - t0
        if part is not None:
            self.parts[part[0]] += t1 - part[1]
        return t1

    def part(self, name: str, t0: float) -> float:
        """Add the time since ``t0`` to the part ``name`` (:data:`PARTS`); returns now."""
        t1 = time.perf_counter()
        self.parts[name] += t1 - t0
        return t1


class SolverStrategy(Protocol):
    """How the event loop solves the unit-load problem of each crack state."""

    timing: Timing

    def solve(self, u_prev: np.ndarray, x: Vector, gather: Gather) -> tuple[np.ndarray, int]:
        """Unit-load solution on every rank, shape=(n_global,), and CG iterations.

        ``u_prev``: the previous solution (held DOFs keep it), shape=(n_global,); ``x``
        a work vector of the layout; ``gather`` copies it to every rank. Collective.
        """
        ...

    def solve_system(self, A: Matrix, b: Vector, x: Vector) -> int:
        """Solve one assembled system A x = b; returns CG iterations (0: direct)."""
        ...

    def solve_again(
        self, u_prev: np.ndarray, x: Vector, gather: Gather, *, case: LoadCase
    ) -> np.ndarray:
        """The solution of another right-hand side ``case`` of the state just solved.

        Called after :meth:`solve`, before any change: the same matrix, held DOFs and
        factorisation; held DOFs keep ``u_prev``, shape=(n_global,). Returns the
        solution on every rank, shape=(n_global,). Collective.
        """
        ...

    def changed(self, units: np.ndarray) -> None:
        """Units whose field the last event changed, shape=(k,)."""
        ...

    def contact_changed(self, blocks: list[Block]) -> None:
        """Signed changes (new +, old −) of crack-face contact blocks since the last solve."""
        ...

    def reset(self) -> None:
        """Forget the changed units (the state was rebuilt from a checkpoint)."""
        ...

    def drop(self) -> None:
        """Free the factorisation the strategy keeps between events."""
        ...

    def destroy(self) -> None:
        """Free everything."""
        ...


class RefactorSolver:
    """Assemble and factorise every event (``"refactor"``).

    Args:
        ctx: the shared set-up data.
        assembler: the crack state's assembly and holds.
        timing: where the phases and counts go.
    """

    def __init__(self, ctx: CrackContext, assembler: Assembler, timing: Timing) -> None:
        self.ctx, self.assembler, self.timing = ctx, assembler, timing
        self.solver: LinearSolver | None = None
        self._looked = False

    def _first_look(self) -> None:
        """Hold cut-free pieces before the run's first factorisation (collective).

        Pre-cracked networks often leave pieces free from the start; finding them
        first spares the factorisation of a singular system that would find them too.
        """
        if not self._looked:
            self._looked = True
            self.assembler.find_fragments()

    def _refactor(self, A: Matrix) -> LinearSolver:
        """A new direct factorisation of A (the previous one freed)."""
        self._free()
        s = self.ctx.scene.solver
        self.solver = LinearSolver(
            A, PREFIX, "direct", options=dict(s.options), num_dofs=self.ctx.n_global
        )
        self.timing.factorizations += 1
        return self.solver

    def solve_system(self, A: Matrix, b: Vector, x: Vector) -> int:
        """Factorise A and solve; returns 0."""
        self._refactor(A).solve(b, x)
        return 0

    def solve(self, u_prev: np.ndarray, x: Vector, gather: Gather) -> tuple[np.ndarray, int]:
        """Assemble and solve; hold cut-free pieces once when the system is singular."""
        t = time.perf_counter()
        assembler = self.assembler
        self._first_look()
        A, b, _ = assembler.assemble(u_prev)
        t = self.timing.add("assemble", t)
        try:
            try:
                its = self.solve_system(A, b, x)
            except RunError:
                if not assembler.find_fragments():
                    raise
                A.destroy()
                b.destroy()
                A, b, _ = assembler.assemble(u_prev)
                its = self.solve_system(A, b, x)
        finally:
            A.destroy()  # a KSP that still uses it holds its own reference
            b.destroy()
        u = gather(x)
        self.timing.add("solve", t)
        return u, its

    def solve_again(
        self, u_prev: np.ndarray, x: Vector, gather: Gather, *, case: LoadCase
    ) -> np.ndarray:
        """Assemble ``case``'s right-hand side and solve it with the current factorisation."""
        t = time.perf_counter()
        A, b, _ = self.assembler.assemble(u_prev, case)
        t = self.timing.add("assemble", t)
        try:
            self._again(A, b, x)
        finally:
            A.destroy()
            b.destroy()
        u = gather(x)
        self.timing.add("solve", t)
        return u

    def _again(self, A: Matrix, b: Vector, x: Vector) -> None:
        """Solve A x = b with the factorisation of the last :meth:`solve` (A: its matrix)."""
        if self.solver is None:  # no factorisation kept: make one
            self.solve_system(A, b, x)
        else:
            self.solver.solve(b, x)

    def changed(self, units: np.ndarray) -> None:
        """Nothing to note: every event assembles afresh."""

    def contact_changed(self, blocks: list[Block]) -> None:
        """Nothing to note: the assembly reads the contact blocks afresh."""

    def reset(self) -> None:
        """Nothing to forget."""

    def _free(self) -> None:
        """Free the factorisation."""
        if self.solver is not None:
            self.solver.destroy()
        self.solver = None

    def drop(self) -> None:
        """Free the factorisation."""
        self._free()

    def destroy(self) -> None:
        """Free the factorisation."""
        self.drop()


class ReuseSolver(RefactorSolver):
    """The last factorisation as CG's preconditioner (``"reuse"``).

    CG runs to 1e-10 relative; when it needs more than ``reuse_iterations`` or fails,
    the matrix is factorised afresh.
    """

    def __init__(self, ctx: CrackContext, assembler: Assembler, timing: Timing) -> None:
        super().__init__(ctx, assembler, timing)
        self.cg: PreconditionedCG | None = None

    def solve_system(self, A: Matrix, b: Vector, x: Vector) -> int:
        """CG preconditioned by the last factorisation, else factorise; CG iterations."""
        if self.solver is not None:
            if self.cg is None:
                self.cg = PreconditionedCG(
                    self.ctx.comm,
                    PREFIX + "cg_",
                    self.solver,
                    max_it=self.ctx.config.reuse_iterations,
                )
            iterations = self.cg.solve(A, b, x)
            if iterations is not None:
                return iterations
        return super().solve_system(A, b, x)

    def _again(self, A: Matrix, b: Vector, x: Vector) -> None:
        """CG preconditioned by the factorisation, from the guess in ``x``."""
        self.timing.iterations += self.solve_system(A, b, x)

    def _free(self) -> None:
        """Free the factorisation and the CG solver."""
        super()._free()
        if self.cg is not None:
            self.cg.destroy()
        self.cg = None


#: Marks a unit that uses its element's field (absent from the fits).
_INTACT = "intact"


class UpdateSolver(RefactorSolver):
    """One factorisation corrected for the changed units (``"update"``).

    The reference (:class:`~geofrac.fracture.incremental.IncrementalSolver`) gets each
    event's changed units as matrix differences (new − old); it raises
    :class:`~geofrac.fracture.incremental.Stale` when a new factorisation is due.
    """

    def __init__(self, ctx: CrackContext, assembler: Assembler, timing: Timing) -> None:
        super().__init__(ctx, assembler, timing)
        self.inc: IncrementalSolver | None = None
        # units changed by the last events, not yet applied to inc, shape=(k,)
        self._pending = np.zeros(0, dtype=np.int64)
        # fits at the reference (units absent use their element), and the field applied
        # since for each unit changed after it (a fit, None or _INTACT)
        self._ref_fits: dict[int, Fit] = {}
        self._applied: dict[int, Fit | str] = {}
        # units giving stiffness to each DOF as applied to inc, shape=(n_global,)
        self._use = np.zeros(0, dtype=np.int64)
        # contact block changes not yet applied to inc
        self._contact: list[Block] = []

    def changed(self, units: np.ndarray) -> None:
        """Apply these units' changes before the next solve."""
        self._pending = np.union1d(self._pending, units)

    def contact_changed(self, blocks: list[Block]) -> None:
        """Apply these contact block changes before the next solve."""
        self._contact += blocks

    def reset(self) -> None:
        """Forget the pending changes."""
        self._pending = np.zeros(0, dtype=np.int64)
        self._contact = []

    def solve(self, u_prev: np.ndarray, x: Vector, gather: Gather) -> tuple[np.ndarray, int]:
        """Correct the reference solution, or start a new reference; 0 iterations."""
        timing = self.timing
        t = time.perf_counter()
        if self.inc is not None and (len(self._pending) or self._contact):
            try:
                self._apply_changes(self._pending, u_prev, self._contact)
            except Stale as exc:
                self._drop_reference(exc)
        self._pending = np.zeros(0, dtype=np.int64)
        self._contact = []
        t = timing.add("assemble", t)
        if self.inc is not None:
            try:
                u = self.inc.solve(x)
                timing.add("solve", t)
                return u, 0
            except Stale as exc:
                self._drop_reference(exc)
        return self._new_reference(u_prev, x, gather), 0

    def solve_again(
        self, u_prev: np.ndarray, x: Vector, gather: Gather, *, case: LoadCase
    ) -> np.ndarray:
        """``case``'s right-hand side, assembled, solved by the corrected reference.

        The current system's matrix is the reference's corrected by the changes applied
        in :meth:`solve` (:meth:`~geofrac.fracture.incremental.IncrementalSolver.solve_rhs`);
        a reference that misses the residual check for it is replaced and both
        right-hand sides are solved again by the caller (:class:`Stale` is not raised
        here: the new reference solves this one directly).
        """
        t = time.perf_counter()
        A, b, _ = self.assembler.assemble(u_prev, case)
        t = self.timing.add("assemble", t)
        try:
            if self.inc is not None:
                try:
                    u = self.inc.solve_rhs(b, x)
                    self.timing.add("solve", t)
                    return u
                except Stale as exc:
                    self._drop_reference(exc)
            try:
                self._refactor(A).solve(b, x)
            except RunError:
                # a piece the corrected reference still held is free in this matrix:
                # hold it (as a new reference does) and let the caller solve both again
                self._drop_reference()
                if not self.assembler.find_fragments():
                    raise
                raise PiecesHeld("pieces cut free are held; solve both loads again") from None
        finally:
            A.destroy()
            b.destroy()
        u = gather(x)
        self.timing.add("solve", t)
        return u

    def _new_reference(self, u_prev: np.ndarray, x: Vector, gather: Gather) -> np.ndarray:
        """Assemble, factorise and solve the current state; it becomes the reference."""
        ctx, assembler = self.ctx, self.assembler
        bc = ctx.bc_mask
        t_ref = time.perf_counter()
        self._first_look()
        self.timing.add("assemble", t_ref)
        for attempt in range(2):
            t = time.perf_counter()
            A, b, held = assembler.assemble(u_prev)
            t = self.timing.add("assemble", t)
            fixed = bc.copy()
            fixed[held] = True
            try:
                solver = self._refactor(A)
                contact = assembler.contact
                unsymmetric = contact is not None and contact.has_slip()
                self.inc = IncrementalSolver(
                    A,
                    b,
                    fixed=fixed,
                    bc_mask=bc,
                    bc_values=assembler.bc_full,
                    solver=solver,
                    x=x,
                    gather=gather,
                    capacity=ctx.config.update_dofs,
                    transposed=partial(self._transposed, A) if unsymmetric else None,
                    parts=self.timing.parts,
                )
                self.solver = None  # the reference owns it now
                break
            except RunError:
                self._drop_reference()
                A.destroy()
                b.destroy()
                if attempt or not assembler.find_fragments():
                    raise
            finally:
                self.timing.add("solve", t)
        self.timing.part("factorise", t_ref)
        state = assembler.units.state
        self._ref_fits = dict(state.fits)
        self._applied = {}
        self._use = assembler.units.use_counts(state.is_mls())
        assert self.inc is not None
        return self.inc.y.copy()

    def _transposed(self, A: Matrix) -> LinearSolver:
        """A factorisation of Aᵀ (the rows of A⁻¹ when friction makes A unsymmetric)."""
        At = transposed(A)
        try:
            s = self.ctx.scene.solver
            return LinearSolver(
                At, PREFIX + "t_", "direct", options=dict(s.options), num_dofs=self.ctx.n_global
            )
        finally:
            At.destroy()  # the solver keeps its own reference

    def _drop_reference(self, why: Stale | None = None) -> None:
        """Free the reference factorisation; count ``why`` in the refactor reasons."""
        if why is not None:
            self.timing.stale[why.kind] = self.timing.stale.get(why.kind, 0) + 1
        if self.inc is not None:
            self.timing.refinements += self.inc.refinements
            self.inc.destroy()
        self.inc = None
        self._free()

    def _apply_changes(
        self, units: np.ndarray, u_prev: np.ndarray, contact: list[Block] | None = None
    ) -> None:
        """Pass the changed units' matrices (new − old) to the reference's correction.

        DOFs that lose their last unit are held at ``u_prev``, as the assembly does.
        ``contact``: signed contact block changes, passed on as they are (they give no
        DOF its only stiffness).

        Raises:
            Stale: the change needs a new factorisation.
        """
        assert self.inc is not None
        parts = self.assembler.units
        fits = parts.state.fits
        pairs: list[tuple[int, Fit | str, Fit | str]] = []
        for c in units.tolist():
            old = self._applied.get(c, self._ref_fits.get(c, _INTACT))
            new = fits.get(c, _INTACT)
            if old is not new:
                pairs.append((c, old, new))
                self._applied[c] = new
        fe = parts.intact_blocks([c for c, old, new in pairs if _INTACT in (old, new)])
        blocks: list[Block] = []
        for c, old, new in pairs:
            for fit, sign in ((old, -1.0), (new, 1.0)):
                block = fe[c] if fit is _INTACT else parts.fit_block(c, fit)  # type: ignore[arg-type]
                if block is None:
                    continue
                dofs, k = block
                self._use[dofs] += int(sign)
                blocks.append((dofs, sign * k))
        blocks += contact or []
        if not blocks:
            return
        inc = self.inc
        touched = np.unique(np.concatenate([d for d, _ in blocks]))
        if np.any(inc.held[touched] & (self._use[touched] > 0)):
            raise Stale("held", "a held DOF carries stiffness again")
        hold = touched[(self._use[touched] == 0) & ~inc.fixed[touched] & ~inc.held[touched]]
        inc.apply(blocks, hold, u_prev[hold])

    def drop(self) -> None:
        """Free the reference (its refinements are counted)."""
        self._drop_reference()


def make_strategy(ctx: CrackContext, assembler: Assembler, timing: Timing) -> SolverStrategy:
    """The strategy of ``cracking.solver``."""
    kinds: dict[str, type[RefactorSolver]] = {
        "update": UpdateSolver,
        "reuse": ReuseSolver,
        "refactor": RefactorSolver,
    }
    return kinds[ctx.config.solver](ctx, assembler, timing)
