"""Checkpoints of elasto-plastic runs: stop after a converged load step, resume from it.

Both loops of :mod:`geofrac.fem.plastic_driver` ask the run's
:class:`~geofrac.io.checkpoint.RunControl` (kind ``fem``) after every converged load
step short of factor 1 (:meth:`geofrac.fem.plastic.PlasticProblem.solve_steps`'s hooks),
and the strength reduction also after every finished trial. A checkpoint holds:

- per rank (``rank-<r>.npz``, this rank's local arrays with ghosts, as the staged runs'):
  the displacement ``u`` and, at every local quadrature point, the converged stress
  ``stress_n``, strain ``strain_n`` and accumulated plastic strain ``plastic_strain``
  (shape=(n, 3, 3)) of the solve in progress; with joints their slips (and with a
  gravity phase the jump kept at the reset);
- ``meta.json`` data: ``loop`` (``"plastic"`` or ``"strength_reduction"``), the load
  factor reached ``done``, the current increment ``inc`` (halved by earlier cuts) and
  every attempted step's record (factor, SNES reason, iterations, residuals, plastic
  points) of the ``phase`` in progress (``"gravity"`` or ``"analysis"``), and in the
  analysis after a gravity phase that phase's record (``gravity``: its steps, its
  largest |u| before the reset, its plastic points); for the strength reduction also
  the finished trials (F, verdict, load factor, monitor, iterations, time) and which
  solve was in progress (a trial F, or the final re-solve of the last stable F), or
  none between trials.

A resume rebuilds the problem from the scene, puts the arrays back and continues the
same arithmetic, so on the same number of ranks it repeats the uninterrupted run bit for
bit (a checkpoint of another scene, loop, rank count or mesh is refused). The bisection
replays the finished trials' verdicts without solving them again.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from geofrac.errors import RunError
from geofrac.fem.plastic import GravityRecord, LoadState, PlasticProblem, StepRecord
from geofrac.fem.strength_reduction import Trial
from geofrac.io.checkpoint import Checkpoint, RunControl
from geofrac.solvers.snes import NewtonReport

__all__ = ["LoadHooks", "ReductionHooks", "TrialHooks", "load_data", "load_state"]

_LOAD = "plastic"
_REDUCTION = "strength_reduction"


def _records(records: list[StepRecord]) -> list[dict[str, Any]]:
    """JSON-ready step records."""
    return [
        {
            "factor": r.factor,
            "accepted": r.accepted,
            "plastic_points": r.plastic_points,
            "reason": r.report.reason,
            "reason_name": r.report.reason_name,
            "iterations": r.report.iterations,
            "residuals": list(r.report.residuals),
            "watchdog_steps": r.report.watchdog_steps,
            "observed": r.observed,
        }
        for r in records
    ]


def _read_records(rows: list[dict[str, Any]]) -> list[StepRecord]:
    """The step records of :func:`_records`'s rows."""
    return [
        StepRecord(
            float(r["factor"]),
            NewtonReport(
                int(r["reason"]),
                str(r["reason_name"]),
                int(r["iterations"]),
                [float(x) for x in r["residuals"]],
                int(r.get("watchdog_steps", 0)),
            ),
            bool(r["accepted"]),
            int(r["plastic_points"]),
            r.get("observed"),
        )
        for r in rows
    ]


def load_data(state: LoadState) -> dict[str, Any]:
    """The JSON-ready ``done``, ``inc``, step records, phase and gravity phase's record."""
    g = state.gravity
    gravity = None
    if g is not None:
        gravity = {
            "records": _records(g.records),
            "converged": g.converged,
            "factor": g.factor,
            "max_displacement": g.max_displacement,
            "plastic_points": g.plastic_points,
        }
    return {
        "done": state.done,
        "inc": state.inc,
        "records": _records(state.records),
        "phase": state.phase,
        "gravity": gravity,
    }


def load_state(data: dict[str, Any]) -> LoadState:
    """The :class:`~geofrac.fem.plastic.LoadState` of :func:`load_data`'s dictionary."""
    g = data.get("gravity")
    gravity = None
    if g is not None:
        gravity = GravityRecord(
            _read_records(g["records"]),
            bool(g["converged"]),
            float(g["factor"]),
            float(g["max_displacement"]),
            int(g["plastic_points"]),
        )
    records = _read_records(data["records"])
    phase = str(data.get("phase", "analysis"))
    return LoadState(float(data["done"]), float(data["inc"]), records, phase, gravity)


def _steps_done(state: LoadState) -> int:
    """Converged steps of both phases (the poll count)."""
    earlier = [] if state.gravity is None else state.gravity.records
    return sum(r.accepted for r in earlier + state.records)


def _restore(problem: PlasticProblem, ck: Checkpoint, data: dict[str, Any]) -> LoadState:
    """Put the checkpoint's arrays into ``problem`` (collective; refuses another mesh)."""
    comm = problem.comm
    arrays = ck.local(comm.rank)
    error = None
    if any(
        name not in arrays or arrays[name].shape != value.shape
        for name, value in problem.state().items()
    ):
        error = f"--resume: the checkpoint {ck.path} is of another mesh or distribution"
    errors = comm.allgather(error)
    if any(errors):
        raise RunError(next(e for e in errors if e))
    state = load_state(data)
    problem.set_state(arrays, state.done)
    return state


def _check_loop(ck: Checkpoint, loop: str, what: str) -> None:
    """Refuse a checkpoint of another loop of the ``fem`` kind (same on every rank)."""
    if ck.data.get("loop") != loop:
        raise RunError(
            f"--resume: the checkpoint {ck.path} is not of {what} (its loop is "
            f"'{ck.data.get('loop')}')"
        )


class LoadHooks:
    """Checkpoint and resume of the load-stepped run (:func:`geofrac.fem.plastic_driver.run`).

    Args:
        control: the run's control (``control.resume``: the checkpoint to continue from).
        say: progress (rank 0).
    """

    def __init__(self, control: RunControl, say: Callable[[str], None]) -> None:
        self.control, self.say = control, say

    def restore(self, problem: PlasticProblem) -> LoadState | None:
        """The checkpoint's state put into ``problem``, or None without ``--resume``."""
        ck = self.control.resume
        if ck is None:
            return None
        self.control.check_resume()  # the same scene, kind and number of ranks
        _check_loop(ck, _LOAD, "a load-stepped plastic run")
        state = _restore(problem, ck, ck.data)
        phase = "" if problem.gravity is None else f" of the {state.phase} phase"
        self.say(f"plastic: resuming after load factor {state.done:.4f}{phase} from {ck.path}")
        return state

    def after_step(self, problem: PlasticProblem, state: LoadState) -> None:
        """Poll; checkpoint when due or signalled; stop on a signal (collective)."""
        k = _steps_done(state)
        save, stop = self.control.poll(k)
        if save:
            data = {"loop": _LOAD} | load_data(state)
            self.control.save(k, data, local=problem.state())
        if stop:
            phase = "" if problem.gravity is None else f"{state.phase} phase, "
            self.control.interrupt(f"load step {k} ({phase}factor {state.done:.4f})")


@dataclass
class TrialHooks:
    """The hooks of one solve of a strength reduction (a trial F, or the final re-solve)."""

    owner: ReductionHooks
    factor: float
    final: bool
    trials: list[Trial]

    def restore(self, problem: PlasticProblem) -> LoadState | None:
        """The checkpoint's state if it stopped inside this very solve, else None."""
        partial = self.owner.partial
        if partial is None or partial["factor"] != self.factor:
            return None
        if bool(partial["final"]) != self.final:
            return None
        ck = self.owner.control.resume
        assert ck is not None  # a partial solve comes from a checkpoint
        self.owner.partial = None
        state = _restore(problem, ck, partial)
        what = "the re-solve of" if self.final else "the trial"
        phase = "" if problem.gravity is None else f" of the {state.phase} phase"
        self.owner.say(
            f"strength reduction: resuming {what} F = {self.factor:.4f} after load factor "
            f"{state.done:.4f}{phase}"
        )
        return state

    def after_step(self, problem: PlasticProblem, state: LoadState) -> None:
        """Poll; checkpoint the finished trials and this solve's state; stop on a signal."""
        partial = {"factor": self.factor, "final": self.final} | load_data(state)
        phase = "" if problem.gravity is None else f"{state.phase} phase, "
        where = f"F = {self.factor:.4f}, {phase}load factor {state.done:.4f}"
        self.owner.poll(self.trials, partial, problem.state(), where=where)


@dataclass
class ReductionHooks:
    """Checkpoint and resume of the strength reduction (``plastic_driver.run_reduction``).

    Args:
        control: the run's control (``control.resume``: the checkpoint to continue from).
        say: progress (rank 0).
    """

    control: RunControl
    say: Callable[[str], None]
    #: the finished trials of the checkpoint, replayed by the bisection.
    known: list[Trial] = field(default_factory=list)
    #: the solve in progress at the checkpoint (``factor``, ``final``, ``done``...), or None.
    partial: dict[str, Any] | None = None
    _k: int = field(default=0, init=False)

    def __post_init__(self) -> None:
        """Read the resume checkpoint, if any (refuses another scene, loop or rank count)."""
        ck = self.control.resume
        if ck is None:
            return
        self.control.check_resume()  # the same scene, kind and number of ranks
        _check_loop(ck, _REDUCTION, "a strength-reduction run")
        self.known = [Trial(**t) for t in ck.data["trials"]]
        self.partial = ck.data.get("partial")
        self._k = ck.k
        self.say(
            f"strength reduction: resuming from {ck.path}: {len(self.known)} finished "
            "trial(s) replayed"
            + ("" if self.partial is None else f", F = {self.partial['factor']:.4f} continued")
        )

    def replay(self, factor: float) -> Trial | None:
        """The finished trial of the checkpoint at ``factor``, or None."""
        return next((t for t in self.known if t.factor == factor), None)

    def trial(self, factor: float, trials: list[Trial], *, final: bool = False) -> TrialHooks:
        """The hooks of the solve at ``factor`` (``final``: the re-solve after the bisection)."""
        return TrialHooks(self, factor, final, trials)

    def finished(self, trials: list[Trial]) -> None:
        """After a finished trial: poll, checkpoint, stop on a signal (collective)."""
        self.poll(trials, None, None, where=f"trial F = {trials[-1].factor:.4f}")

    def poll(
        self,
        trials: list[Trial],
        partial: dict[str, Any] | None,
        arrays: dict[str, Any] | None,
        *,
        where: str,
    ) -> None:
        """Poll k + 1; save the trials (and a solve in progress); stop on a signal."""
        self._k += 1
        save, stop = self.control.poll(self._k)
        if save:
            data: dict[str, Any] = {"loop": _REDUCTION, "partial": partial}
            data["trials"] = [dict(vars(t)) for t in trials]
            self.control.save(self._k, data, local=arrays)
        if stop:
            self.control.interrupt(where)
