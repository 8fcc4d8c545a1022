"""A staged elastic run stopped by SIGTERM resumes at the next stage (docs/insitu.md).

The stop goes through the production path, as tests/fracture/test_resume.py: the run
control's poll finds SIGTERM in :mod:`geofrac.interrupt`'s flag after the chosen step (on
rank 0 only, so the flag must reach the other ranks through the poll's reduction); the
run writes a checkpoint and stops with ``status = "interrupted"``; ``resume`` continues
from it. The resumed run's summary rows and every dataset of ``results.h5`` must equal
the uninterrupted run's: the arithmetic after the resume is the same (the same matrix,
right-hand side and solver), so they agree bit for bit (1e-13 relative allowed on 2
ranks). A checkpoint of another scene or another number of ranks is refused.
"""

from __future__ import annotations

import json
import signal
from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac import interrupt
from geofrac.errors import RunError
from geofrac.io.checkpoint import RunControl
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS
from tests.fem.helpers import check_interrupted, h5_datasets

KIRSCH = JOBS / "kirsch_stages.toml"
#: The coarse Kirsch scene of tests/fem/test_insitu.py (stages: excavate 0.4, support).
COARSE = ("geometry.parameters.L=20.0", "geometry.parameters.h_wall=0.15")
COARSE += ("geometry.parameters.h_far=3.0", "output.lines={}")


def _shared(tmp_path: Path, comm: MPI.Comm) -> Path:
    """Rank 0's tmp_path on every rank."""
    return Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))


def _run(out: Path, comm: MPI.Comm, *, resume: bool = False, extra: tuple[str, ...] = ()):
    scene = load_scene_collective(comm, KIRSCH, COARSE + extra, out=out)
    return run_scene(scene, comm, verbose=False, resume=resume)


def _stop_after(monkeypatch: pytest.MonkeyPatch, at: int) -> None:
    """SIGTERM (on rank 0) when step ``at`` completes."""
    poll = RunControl.poll

    def stopping(self: RunControl, k: int) -> tuple[bool, bool]:
        if k == at and self.comm.rank == 0:
            interrupt._received.append(signal.SIGTERM)
        return poll(self, k)

    monkeypatch.setattr(RunControl, "poll", stopping)


def _interrupted(out: Path, comm: MPI.Comm, monkeypatch: pytest.MonkeyPatch, at: int) -> None:
    """Run until the stop after step ``at``; check the status and the checkpoint."""
    _stop_after(monkeypatch, at)
    try:
        with pytest.raises(interrupt.Interrupted, match=f"after stage {at}"):
            _run(out, comm)
    finally:
        interrupt.reset()
        monkeypatch.undo()
    comm.barrier()  # rank 0 writes the status
    check_interrupted(out, at)


def _same(resumed: Path, whole: Path, rtol: float) -> None:
    a = json.loads((resumed / "summary.json").read_text())
    b = json.loads((whole / "summary.json").read_text())
    assert a["status"] == "ok" and a["resumed_from"]["k"] >= 0
    ra, rb = a["results"], b["results"]
    assert [s["name"] for s in ra["stages"]] == ["initial", "excavate", "support"]
    assert sorted(ra) == sorted(rb)
    for key in ra:
        if key != "solver":  # the solver's timing and iteration record
            np.testing.assert_allclose(_flat(ra[key]), _flat(rb[key]), rtol=rtol, atol=0.0)
    da, db = h5_datasets(resumed / "results.h5"), h5_datasets(whole / "results.h5")
    assert sorted(da) == sorted(db) and len(da) >= 3
    for name in da:
        x, y = np.asarray(da[name], dtype=float), np.asarray(db[name], dtype=float)
        scale = float(np.abs(y).max(initial=0.0))
        assert float(np.abs(x - y).max(initial=0.0)) <= rtol * scale, name


def _flat(value: object) -> list[float]:
    """The numbers of a JSON value in order (strings as their length, to compare names)."""
    if isinstance(value, dict):
        return [x for k in sorted(value) for x in [float(len(k)), *_flat(value[k])]]
    if isinstance(value, list):
        return [x for v in value for x in _flat(v)]
    if isinstance(value, str):
        return [float(sum(map(ord, value)))]
    return [float(value)]  # type: ignore[arg-type]


@pytest.mark.parametrize("at", [0, 1])
def test_a_stopped_staged_run_resumes_to_the_whole_run(tmp_path, monkeypatch, at):
    comm = MPI.COMM_WORLD
    whole = tmp_path / "whole"
    _run(whole, comm)
    out = tmp_path / "stopped"
    _interrupted(out, comm, monkeypatch, at)
    _run(out, comm, resume=True)
    _same(out, whole, rtol=0.0)


def test_resuming_another_scene_is_refused(tmp_path, monkeypatch):
    comm = MPI.COMM_WORLD
    out = tmp_path / "stopped"
    _interrupted(out, comm, monkeypatch, 1)
    with pytest.raises(RunError, match="another scene"):
        _run(out, comm, resume=True, extra=("material.E=20000.0",))


@pytest.mark.mpi(min_size=2)
def test_two_ranks_resume_to_the_whole_run_and_refuse_one_rank(tmp_path, monkeypatch):
    comm = MPI.COMM_WORLD
    root = _shared(tmp_path, comm)
    whole = root / "whole"
    _run(whole, comm)
    out = root / "stopped"
    _interrupted(out, comm, monkeypatch, 1)
    _run(out, comm, resume=True)
    comm.barrier()
    if comm.rank == 0:
        _same(out, whole, rtol=1e-13)
    # a 2-rank checkpoint resumed on one rank is refused
    again = root / "again"
    _interrupted(again, comm, monkeypatch, 1)
    comm.barrier()
    error = None
    if comm.rank == 0:
        with pytest.raises(RunError, match="written on 2 rank") as caught:
            _run(again, MPI.COMM_SELF, resume=True)
        error = str(caught.value)
    assert comm.bcast(error, root=0)
