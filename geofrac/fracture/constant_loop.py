"""The event loop with loads that stay constant (DeJong, Hendriks and Rots (2008)).

:class:`ConstantEventLoop` is :class:`~geofrac.fracture.loop.EventLoop` with two
right-hand sides per event (:mod:`~geofrac.fracture.constant`): it solves the variable
load u_v (the loop's unit solution) and the constant load u_c with one factorisation,
chooses the event by :class:`~geofrac.fracture.constant.ConstantChooser` (λ, or 0 for a
site over its strength under the constant load alone) and logs the state
u = u_c + λ u_v: its strain energy E_c + λ u_cᵀ K u_v + λ² E_v (the cross term by
polarisation, E(u_c + u_v) − E_c − E_v), the control group's displacement (λ δ under
displacement control; that of u_c plus λ that of u_v, f·u / F or the control point's,
under force control) and force (the control DOFs' reaction of u_c plus λ that of u_v
under displacement control; λ F under force control). With u_c = 0 (a zero constant
load) every number is the proportional run's, bit for bit.
The scene without ``cracking.constant`` never reaches this module.

With crack-face contact (``cracking.contact``) the pairs' tractions are not proportional
to λ: each event solves both loads with the current states, chooses λ (the sites and the
slip of bonded pairs, :class:`~geofrac.fracture.constant_contact.ConstantFaces`), judges
the states at u_c + λ u_v and, if any changed, solves and chooses again, until none
changes (at most ``contact_iterations`` times; cycling pairs are held as
:meth:`~geofrac.fracture.equilibrium.ContactEquilibrium.settle` holds them).
"""

from __future__ import annotations

import time

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import dolfinx
import numpy as np

from geofrac.errors import RunError
from geofrac.fracture.config import LoopSettings
from geofrac.fracture.constant import ConstantChooser, ConstantLoad
from geofrac.fracture.constant_contact import ConstantFaces
from geofrac.fracture.context import CrackContext, JsonValue, Sites
from geofrac.fracture.equilibrium import ContactEquilibrium, LinearEquilibrium, Solved, Visited
from geofrac.fracture.linear import PiecesHeld
from geofrac.fracture.loop import EventLoop, LoopParts, _Run
from geofrac.fracture.modes import Choice
from geofrac.fracture.scales import TENSION_FLOOR
from geofrac.io.checkpoint import RunControl

__all__ = ["ConstantEventLoop"]


class ConstantEventLoop(EventLoop):
    """Events under a constant load plus a scaled one.

    Args:
        ctx, parts, sites, settings, control: as :class:`~geofrac.fracture.loop.EventLoop`
            (``parts.equilibrium`` a :class:`~geofrac.fracture.equilibrium.LinearEquilibrium`,
            a :class:`~geofrac.fracture.equilibrium.ContactEquilibrium` with contact).
        load: the two right-hand sides; the assembler's default is ``load.variable``.
        chooser: the event's sites, λ and mode.
    """

    def __init__(
        self,
        ctx: CrackContext,
        parts: LoopParts,
        sites: Sites,
        *,
        settings: LoopSettings,
        control: RunControl | None,
        load: ConstantLoad,
        chooser: ConstantChooser,
    ) -> None:
        super().__init__(ctx, parts, sites, settings=settings, control=control)
        assert isinstance(parts.equilibrium, LinearEquilibrium)
        self.equilibrium: LinearEquilibrium = parts.equilibrium
        self.load, self.chooser = load, chooser
        #: the constant load's solution of the last solve, shape=(n_global,).
        self.u_const = np.zeros(ctx.n_global)
        #: sites cracked at λ = 0, and how many were over their strength at the start.
        self.over_cracked = 0
        self.over_at_start: int | None = None
        #: the constant load's strain energy, control displacement and force, and the
        #: cross energy u_cᵀ K u_v, of the last solve.
        self._const = (0.0, 0.0, 0.0, 0.0)
        #: the crack faces in contact (``cracking.contact``), or None.
        self.faces: ConstantFaces | None = None
        if settings.contact and parts.contact is not None:
            assert isinstance(parts.equilibrium, ContactEquilibrium)
            self.faces = ConstantFaces(parts.contact, ctx)
            parts.record.proportional = False  # the pairs' values are the event's own

    #: whether checkpoints keep what the loop needs to continue (the constant load's
    #: solution; :class:`~geofrac.fracture.staged.StagedEventLoop`'s do).
    resumable = False

    def run(self, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """Run (a resume is refused: checkpoints keep the variable solution only)."""
        if not self.resumable and self.control is not None and self.control.resume is not None:
            raise RunError(
                "--resume: a run with cracking.constant cannot be resumed yet (its "
                "checkpoints keep the variable load's solution only); run it again"
            )
        if self.load.groups:  # (an initial stress alone has none)
            self.ctx.say(
                f"cracking: constant loads on {', '.join(self.load.groups)}; the other loads "
                "and prescribed displacements scale with λ"
            )
        return super().run(unknown)

    def _event(self, run: _Run, event: int) -> bool:
        """Solve both loads, choose, log the state u_c + λ u_v, crack, update."""
        parts = self.parts
        start = parts.replay.start(event, run.u_unit, run.face_hit)
        solved = self._solve(run, event, replay=False)
        if solved is None:
            return False
        self._keep_reference(run, start)
        parts.timing.iterations += solved.iterations
        run.clock = time.perf_counter()
        choice = self._choose(run, event)
        if choice is None:
            return False
        if self.faces is not None:
            settled = self._settle(run, event, choice, solved)
            if settled is None:
                return False
            choice, solved = settled
        assert run.unit is not None
        r, (energy_c, disp_c, force_c, cross) = choice.r, self._const
        energy = energy_c + r * cross + r * r * run.unit[0]
        row = self._log(run, event, choice, solved=solved, energy=energy)
        if self.ctx.control.kind == "displacement":  # δ r; the reaction of u_c + r u_v
            row["reaction"] = force_c + r * run.unit[2]
        else:  # the displacement of u_c + r u_v; the force r F
            row["control_displacement"] = disp_c + r * run.unit[1]
        if choice.r == 0.0 and choice.mode != "slip":
            self.over_cracked += len(choice.sites)
        parts.crack.apply(choice)
        self._after_crack(run, event, choice, row=row, energy=energy)
        return self._publish(run, event, row=row, energy=energy)

    def _settle(
        self, run: _Run, event: int, choice: Choice, solved: Solved
    ) -> tuple[Choice, Solved] | None:
        """Judge the pair states at u_c + λ u_v; solve and choose again until none changes.

        Returns the event's choice and its solution with every state change made; None
        when the run ends here (states unsettled after ``contact_iterations``, a failed
        solve, no event).
        """
        assert self.faces is not None
        equilibrium, faces = self.parts.equilibrium, self.faces.faces
        assert isinstance(equilibrium, ContactEquilibrium)
        limit = equilibrium.iterations
        history: Visited = {}
        made: list[tuple[int, int, int]] = []
        for it in range(limit + 1):
            changes, blocks = faces.update(self._state(run, choice.r))
            if not changes:
                return choice, Solved(solved.u, solved.iterations, made)
            equilibrium.absorb(changes, blocks, history=history, made=made, last=it == limit)
            if it == limit:
                break
            again = self._solve(run, event, replay=False)
            if again is None:
                return None
            faces.iterations += 1
            solved = Solved(again.u, solved.iterations)
            chosen = self._choose(run, event)
            if chosen is None:
                return None
            choice = chosen
        run.end = "contact"
        self.ctx.say(f"cracking: event {event}: {equilibrium.unsettled(changes)}")
        return None

    def _solve_variable(self, run: _Run, event: int) -> Solved | None:
        """The variable load's solution with the current pair states (no settling)."""
        try:
            solved = self.equilibrium.solve(run.u_unit)
        except RunError as exc:
            run.end = "singular"
            self.ctx.say(f"cracking: event {event}: the system is singular ({exc})")
            return None
        run.u_unit = solved.u
        return solved

    def _solve(self, run: _Run, event: int, *, replay: bool) -> Solved | None:
        """The variable load's solution (the loop's), then the constant load's.

        With contact the states are settled at the event's state (:meth:`_settle`), not
        on the variable load alone.
        """
        for attempt in range(2):  # again once when the constant solve held pieces
            if self.faces is None:
                solved = super()._solve(run, event, replay=replay)
            else:
                solved = self._solve_variable(run, event)
            if solved is None:
                return None
            t = time.perf_counter()
            try:
                self.u_const = self.equilibrium.solve_again(self.u_const, self.load.constant)
            except RunError as exc:
                if isinstance(exc, PiecesHeld) and not attempt:
                    continue
                run.end = "singular"
                self.ctx.say(f"cracking: event {event}: the constant load's system failed ({exc})")
                return None
            self.parts.timing.add("solve", t)
            return solved
        return None

    def _choose(self, run: _Run, event: int) -> Choice | None:
        """The sites' constant and variable stress and the event of least λ; None: the end."""
        ctx, parts, scales = self.ctx, self.parts, self.ctx.scales
        units = parts.units
        _, energy_c, reaction_c = units.measures(self.u_const)
        sc = units.midpoint_stress.copy()  # type: ignore[attr-defined]
        if self.load.extra_stress is not None:
            sc += self.load.extra_stress
        cross = 0.0  # u_cᵀ K u_v: 0 when u_c = 0
        if np.any(self.u_const):
            cross = units.measures(self.u_const + run.u_unit)[1] - energy_c
        _, energy_v, reaction_v = units.measures(run.u_unit)
        sv = units.midpoint_stress.copy()  # type: ignore[attr-defined]
        run.unit = (energy_v, *ctx.control.measure(run.u_unit, reaction_v))
        if cross:
            cross -= energy_v
        self._const = (energy_c, *ctx.control.measure(self.u_const, reaction_c), cross)
        positive = [row["load_factor"] for row in run.rows if row["load_factor"] > 0.0]
        first_r = positive[0] if positive else None
        run.detail = scales.separated(energy_v, run.first_energy if event > 1 else None)
        run.first_energy = energy_v if event == 1 else run.first_energy
        if run.detail is not None:
            run.end = "separated"
            return None
        floor = TENSION_FLOOR * scales.rms_stress(energy_v)
        choice = self.chooser.choose(sc, sv, floor=floor)
        if self.faces is not None:  # the slip of bonded joints
            points = self.chooser.criterion.points
            choice = self.faces.with_slip(
                choice, self.u_const, run.u_unit, floor=floor, points=points
            )
        choice = self._limit(choice)
        self._count_start(len(self.chooser.over_sites))
        run.clock = parts.timing.add("criterion", run.clock)
        if len(choice.sites) == 0:
            run.end = "no_tensile_edge"
            return None
        if choice.r > 0.0:
            run.detail = scales.beyond(
                choice.r, first_r, control_displacement=choice.r * run.unit[1]
            )
            if run.detail is not None:
                run.end = "separated"
                return None
        return choice

    def _limit(self, choice: Choice) -> Choice:
        """The event as chosen (a subclass may refuse events beyond a largest λ)."""
        return choice

    def _count_start(self, over: int) -> None:
        """Note (once) how many sites the constant load alone brings over their strength."""
        if self.over_at_start is None:
            self.over_at_start = over
            if over:
                self.ctx.say(
                    f"cracking: {over} sites are over their strength under the constant "
                    "loads alone; they crack first (λ = 0), most overstressed first"
                )

    def _state(self, run: _Run, r: float) -> np.ndarray:
        """u_c + r u_v of the last solve, shape=(n_global,)."""
        return self.u_const + r * run.u_unit

    def _finish(self, run: _Run, unknown: dolfinx.fem.Function) -> dict[str, JsonValue]:
        """The results, with ``constant``: the groups and the sites cracked at λ = 0."""
        results = super()._finish(run, unknown)
        results["constant"] = {
            "groups": list(self.load.groups),
            "overstressed_at_start": self.over_at_start or 0,
            "cracked_at_zero": self.over_cracked,
        }
        self.ctx.say(
            f"cracking: {self.over_cracked} sites cracked at λ = 0 (over their strength "
            f"under the constant loads; {self.over_at_start or 0} at the start)"
        )
        return results

    def destroy(self) -> None:
        """Free the solvers and the two load vectors."""
        super().destroy()
        self.load.destroy()
