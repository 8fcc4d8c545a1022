"""Elasto-plastic runs stopped by SIGTERM resume from the last converged load step.

geofrac/fem/plastic_checkpoint.py. The stop goes through the production path, as
tests/fem/test_stage_resume.py: the run control's poll finds SIGTERM in
:mod:`geofrac.interrupt`'s flag at the chosen poll (on rank 0 only, so the flag must reach
the other ranks through the poll's reduction); the run writes a checkpoint and stops with
``status = "interrupted"``; ``resume`` continues from it. The resumed run must equal the
uninterrupted one: every number of the summary's results (the load steps' factors, SNES
reasons, iterations and residuals, the plastic points, the probes; the factor of safety
and every trial's verdict, load factor, monitor and iterations) and every dataset of
``results.h5`` (u). The arithmetic after a resume is the same (the same state, matrix and
solver), so they agree bit for bit on one rank; on 2 ranks MUMPS's parallel factorisation
is not bitwise repeatable (tests/test_kill_resume.py), so 1e-10 relative is allowed there.

Load-stepped run: jobs/opening_mohr_coulomb.toml (5 steps, seconds). Strength reduction:
the coarse Griffiths-Lane slope (h = 2, 145 cells, max_cuts 1, bracket [1.3, 1.6] to 0.2:
trials 1.3 stable, 1.6 and 1.45 failed, then the re-solve of 1.3), stopped between trials,
inside a trial and inside the final re-solve; the resumed run solves only what is left
(the solves counted).
"""

from __future__ import annotations

import json
import signal
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mpi4py import MPI

import geofrac.fem.strength_reduction as sr
from geofrac import interrupt
from geofrac.errors import RunError
from geofrac.io.checkpoint import RunControl
from geofrac.pipeline import run_scene
from geofrac.plasticity.strength_reduction import bisect_factor, trials_left
from geofrac.scene import load_scene_collective
from geofrac.solvers.snes import NewtonSolver
from tests.conftest import JOBS
from tests.fem.helpers import check_interrupted, h5_datasets

OPENING = JOBS / "opening_mohr_coulomb.toml"
SLOPE = JOBS / "slope_griffiths_lane.toml"
#: output.xdmf: results.h5 holds u for the comparison.
OPENING_SETS = ("output.xdmf=true",)
SLOPE_SETS = (
    "geometry.parameters.h=2.0",
    "plasticity.max_cuts=1",
    "plasticity.max_iterations=15",
    "plasticity.reduction_tolerance=0.2",
    "output.xdmf=true",
)


#: the Newton solver's absolute tolerance on ||F|| (geofrac/solvers/snes.py default).
NEWTON_ATOL = 1e-10


def _on_root(check: Any, *args: Any, **kw: Any) -> None:
    """``check`` on rank 0; its failure raised on every rank (no rank left waiting)."""
    comm = MPI.COMM_WORLD
    error = None
    if comm.rank == 0:
        try:
            check(*args, **kw)
        except AssertionError as exc:
            error = repr(exc)
    error = comm.bcast(error, root=0)
    assert error is None, error


def _shared(tmp_path: Path, comm: MPI.Comm) -> Path:
    """Rank 0's tmp_path on every rank."""
    return Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))


def _run(
    job: Path,
    sets: tuple[str, ...],
    out: Path,
    comm: MPI.Comm,
    *,
    resume: bool = False,
) -> dict[str, Any]:
    scene = load_scene_collective(comm, job, sets, out=out)
    return run_scene(scene, comm, verbose=False, resume=resume)


class Counts:
    """Polls, trial solves and Newton solves of one run (monkeypatched, this rank)."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch, *, stop_at: int = 0) -> None:
        self.polls = self.trials = self.newton = 0
        poll, solve, trial = RunControl.poll, NewtonSolver.solve, sr.solve_plastic

        def polling(control: RunControl, k: int) -> tuple[bool, bool]:
            self.polls += 1
            if self.polls == stop_at and control.comm.rank == 0:
                interrupt._received.append(signal.SIGTERM)
            return poll(control, k)

        def solving(newton: NewtonSolver) -> Any:
            self.newton += 1
            return solve(newton)

        def trying(*args: Any, **kw: Any) -> Any:
            self.trials += 1
            return trial(*args, **kw)

        monkeypatch.setattr(RunControl, "poll", polling)
        monkeypatch.setattr(NewtonSolver, "solve", solving)
        monkeypatch.setattr(sr, "solve_plastic", trying)


def _whole(job: Path, sets: tuple[str, ...], out: Path, monkeypatch: pytest.MonkeyPatch) -> Counts:
    counts = Counts(monkeypatch)
    try:
        _run(job, sets, out, MPI.COMM_WORLD)
    finally:
        monkeypatch.undo()
    return counts


def _stopped(
    job: Path,
    sets: tuple[str, ...],
    out: Path,
    monkeypatch: pytest.MonkeyPatch,
    at: int,
    *,
    checkpoint: int | None = None,
) -> Counts:
    """Run until SIGTERM at poll ``at``; check the status and the checkpoint.

    ``checkpoint``: the checkpoint's number when it is not ``at`` (a gravity phase's
    last step converges without a poll).
    """
    comm = MPI.COMM_WORLD
    counts = Counts(monkeypatch, stop_at=at)
    try:
        with pytest.raises(interrupt.Interrupted):
            _run(job, sets, out, comm)
    finally:
        interrupt.reset()
        monkeypatch.undo()
    comm.barrier()  # rank 0 writes the status
    check_interrupted(out, at if checkpoint is None else checkpoint)
    assert counts.polls == at
    return counts


def _resumed(
    job: Path, sets: tuple[str, ...], out: Path, monkeypatch: pytest.MonkeyPatch
) -> Counts:
    counts = Counts(monkeypatch)
    try:
        _run(job, sets, out, MPI.COMM_WORLD, resume=True)
    finally:
        monkeypatch.undo()
    return counts


def _numbers(value: object, path: str = "") -> dict[str, object]:
    """The leaves of a JSON value by path, without the timings (``seconds``, ``solver``)."""
    if isinstance(value, dict):
        out: dict[str, object] = {}
        for k, v in value.items():
            if k not in ("seconds", "solver"):
                out |= _numbers(v, f"{path}/{k}")
        return out
    if isinstance(value, list):
        out = {}
        for i, v in enumerate(value):
            out |= _numbers(v, f"{path}/{i}")
        return out
    return {path: value}


def _same(resumed: Path, whole: Path, rtol: float, *, newton: bool = True) -> dict[str, Any]:
    """The resumed run's summary and results.h5 equal the whole run's (to ``rtol``).

    ``newton = False`` leaves out the Newton iteration counts and final residuals, and
    compares the SNES reasons by their verdict only (CONVERGED or DIVERGED): on 2
    ranks MUMPS's parallel factorisation is not bitwise repeatable, and a step whose
    residual after k iterations lies near the tolerance then takes k or k + 1 (measured:
    11 against 12 in 1 of 4 resumed runs), or meets the relative tolerance before the
    absolute one or after it (FNORM_RELATIVE against FNORM_ABS: the gravity phase's
    layer, 3 of 4 runs), while the converged state agrees to round-off.
    """
    a = json.loads((resumed / "summary.json").read_text())
    b = json.loads((whole / "summary.json").read_text())
    assert a["status"] == "ok" and a["resumed_from"]["k"] >= 1
    na, nb = _numbers(a["results"]), _numbers(b["results"])
    assert sorted(na) == sorted(nb)
    for key, x in na.items():
        if not newton and key.endswith(("/iterations", "/residual")):
            continue
        y = nb[key]
        if not newton and key.endswith("/reason"):
            assert str(x).split("_")[0] == str(y).split("_")[0], (key, x, y)
            continue
        if isinstance(x, float) and isinstance(y, float):
            # a converged step's final |F| is round-off below the Newton atol
            slack = NEWTON_ATOL if rtol and key.endswith("/residual") else 0.0
            assert abs(x - y) <= rtol * abs(y) + slack, (key, x, y)
        else:
            assert x == y, (key, x, y)
    da, db = h5_datasets(resumed / "results.h5"), h5_datasets(whole / "results.h5")
    assert sorted(da) == sorted(db) and da
    for name in da:
        x, y = np.asarray(da[name], dtype=float), np.asarray(db[name], dtype=float)
        scale = float(np.abs(y).max(initial=0.0))
        assert float(np.abs(x - y).max(initial=0.0)) <= rtol * scale, name
    results: dict[str, Any] = a["results"]
    return results


@pytest.mark.parametrize("at", [2, 4])
def test_a_stopped_plastic_run_resumes_to_the_whole_run(tmp_path, monkeypatch, at):
    """Stopped after load step ``at`` of 5, resumed: the same steps, u and plastic points."""
    whole = tmp_path / "whole"
    counts = _whole(OPENING, OPENING_SETS, whole, monkeypatch)
    assert counts.polls == 4  # after every converged step but the last
    out = tmp_path / "stopped"
    _stopped(OPENING, OPENING_SETS, out, monkeypatch, at)
    again = _resumed(OPENING, OPENING_SETS, out, monkeypatch)
    assert again.polls == 4 - at
    results = _same(out, whole, rtol=0.0)
    plastic = results["plasticity"]
    assert plastic["converged"] and len(plastic["steps"]) == 5
    assert plastic["plastic_points"] > 0  # the comparison covers the plastic state
    # every step row counts its watchdog steps: none without joints (the checkpoint too)
    assert [s["watchdog_steps"] for s in plastic["steps"]] == [0] * 5


def test_resuming_another_scene_or_loop_is_refused(tmp_path, monkeypatch):
    """A checkpoint of other parameters, or of the other plastic loop, is refused."""
    out = tmp_path / "stopped"
    _stopped(OPENING, OPENING_SETS, out, monkeypatch, 2)
    with pytest.raises(RunError, match="another scene"):
        _run(OPENING, (*OPENING_SETS, "plasticity.cohesion=1.1"), out, MPI.COMM_WORLD, resume=True)
    # the same scene file, but the checkpoint names another loop: refused, not misread
    meta = out / "incomplete" / "checkpoint" / f"ckpt-{2:09d}" / "meta.json"
    data = json.loads(meta.read_text())
    data["data"]["loop"] = "strength_reduction"
    meta.write_text(json.dumps(data))
    with pytest.raises(RunError, match="not of a load-stepped plastic run"):
        _run(OPENING, OPENING_SETS, out, MPI.COMM_WORLD, resume=True)


@pytest.fixture(scope="module")
def slope_whole(tmp_path_factory):
    """The uninterrupted strength reduction, its polls and solves (run once)."""
    mp = pytest.MonkeyPatch()
    out = _shared(tmp_path_factory.mktemp("slope"), MPI.COMM_WORLD) / "whole"
    counts = _whole(SLOPE, SLOPE_SETS, out, mp)
    return out, counts


#: where the stop comes: after trial 1's 4 polls and its finish (poll 5), inside trial 2
#: (poll 7: its second load step), inside the final re-solve (its last poll).
STOPS = {"between_trials": 5, "inside_trial": 7, "inside_resolve": -1}


@pytest.mark.parametrize("where", list(STOPS))
def test_a_stopped_strength_reduction_resumes_without_redoing_trials(
    tmp_path, monkeypatch, slope_whole, where
):
    whole, counts = slope_whole
    at = STOPS[where] % counts.polls if STOPS[where] < 0 else STOPS[where]
    out = tmp_path / "stopped"
    before = _stopped(SLOPE, SLOPE_SETS, out, monkeypatch, at)
    again = _resumed(SLOPE, SLOPE_SETS, out, monkeypatch)
    results = _same(out, whole, rtol=0.0)
    trials = results["plasticity"]["trials"]
    assert [t["stable"] for t in trials] == [True, False, False]
    # nothing solved twice: the finished trials are replayed, the trial in progress
    # continues after its last converged step
    assert before.newton + again.newton == counts.newton
    assert before.polls + again.polls == counts.polls
    finished = {"between_trials": 1, "inside_trial": 1, "inside_resolve": 3}[where]
    assert before.trials == finished + (where == "inside_trial")
    assert again.trials == len(trials) - finished


@pytest.mark.mpi(min_size=2)
def test_two_ranks_resume_to_the_whole_run_and_refuse_one_rank(tmp_path, monkeypatch):
    comm = MPI.COMM_WORLD
    root = _shared(tmp_path, comm)
    whole = root / "whole"
    _whole(OPENING, OPENING_SETS, whole, monkeypatch)
    out = root / "stopped"
    _stopped(OPENING, OPENING_SETS, out, monkeypatch, 2)
    _resumed(OPENING, OPENING_SETS, out, monkeypatch)
    comm.barrier()
    _on_root(_same, out, whole, rtol=1e-10, newton=False)
    again = root / "again"
    _stopped(OPENING, OPENING_SETS, again, monkeypatch, 2)
    comm.barrier()
    error = None
    if comm.rank == 0:
        with pytest.raises(RunError, match="written on 2 rank") as caught:
            _run(OPENING, OPENING_SETS, again, MPI.COMM_SELF, resume=True)
        error = str(caught.value)
    assert comm.bcast(error, root=0)


@pytest.mark.mpi(min_size=2)
def test_two_ranks_strength_reduction_stopped_inside_a_trial_resumes_to_the_whole_run(
    tmp_path, monkeypatch
):
    """2 ranks, the trial solvers built one after another (the hang of the SNES garbage fix)."""
    root = _shared(tmp_path, MPI.COMM_WORLD)
    counts = _whole(SLOPE, SLOPE_SETS, root / "whole", monkeypatch)
    out = root / "stopped"
    before = _stopped(SLOPE, SLOPE_SETS, out, monkeypatch, STOPS["inside_trial"])
    again = _resumed(SLOPE, SLOPE_SETS, out, monkeypatch)
    MPI.COMM_WORLD.barrier()
    _on_root(_same, out, root / "whole", rtol=1e-10, newton=False)
    assert before.trials + again.trials == counts.trials + 1  # the stopped trial, continued
    assert before.polls + again.polls == counts.polls


@pytest.mark.parametrize("threshold", [1.2345, 1.0001, 1.9999, 0.7, 3.1])
def test_trials_left_counts_the_bisections_to_come(threshold: float) -> None:
    """The per-trial estimate of the trials left, against bisect_factor's actual calls.

    Exact while the bracket [1, 2] holds (the threshold inside); when the bracket moves
    (0.7, 3.1) it never claims fewer trials than one more move needs.
    """
    tried: list[tuple[float, bool]] = []
    estimates: list[int] = []

    def is_stable(f: float) -> bool:
        tried.append((f, f < threshold))
        estimates.append(trials_left(tried, low=1.0, high=2.0, tolerance=0.01))
        return f < threshold

    bisect_factor(is_stable, low=1.0, high=2.0, tolerance=0.01)
    actual = [len(tried) - 1 - i for i in range(len(tried))]
    assert estimates[-1] == 0
    if 1.0 < threshold <= 2.0:
        assert estimates == actual
    else:
        assert all(e >= 1 for e in estimates[:-1])


JOINT = JOBS / "slope_planar_joint.toml"
JOINT_SETS = ("geometry.parameters.h=2.0", "plasticity.reduction_tolerance=0.2", "output.xdmf=true")


def test_a_stopped_joint_reduction_resumes_to_the_whole_run(tmp_path, monkeypatch):
    """The joints' slip is part of the checkpointed state.

    The planar joint slope (h = 2, trials F = 1.4, 1.7, 1.55) stopped at poll 13: the
    third trial's fourth load step, F = 1.55 just above the FoS, its joint slipping;
    resumed: the same trials, bracket and joint summary, bit for bit.
    """
    whole = tmp_path / "whole"
    _whole(JOINT, JOINT_SETS, whole, monkeypatch)
    out = tmp_path / "stopped"
    _stopped(JOINT, JOINT_SETS, out, monkeypatch, 13)
    _resumed(JOINT, JOINT_SETS, out, monkeypatch)
    results = _same(out, whole, rtol=0.0)
    joints = results["plasticity"]["last_stable"]["joints"]
    assert joints["slipping"] > 0 and joints["max_slip"] > 0.0
