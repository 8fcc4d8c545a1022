"""Owned output directories: one run at a time, staging, publication, kept results."""

from __future__ import annotations

import json
import signal
import subprocess
import sys

import numpy as np
import pytest
from mpi4py import MPI

from geofrac import interrupt
from geofrac.errors import RunError
from geofrac.io.checkpoint import KEEP, CheckpointPolicy, RunControl, latest
from geofrac.io.outdir import INCOMPLETE, claim
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene, load_scene_collective
from tests.conftest import JOBS, subprocess_env

SINGULAR = ["bc.0.value=[0.0]", 'bc.0.components=["x"]']


def _summary(path):
    return json.loads(path.read_text())


def test_a_second_run_into_a_directory_in_use_is_refused(tmp_path):
    first = claim(tmp_path, MPI.COMM_SELF)
    try:
        with pytest.raises(RunError, match=r"is in use by another run \(pid \d+"):
            claim(tmp_path, MPI.COMM_SELF)
    finally:
        first.release()
    claim(tmp_path, MPI.COMM_SELF).release()  # free again once released


def test_the_cli_refuses_a_directory_another_process_holds(tmp_path):
    held = claim(tmp_path / "out", MPI.COMM_SELF)
    try:
        scene = str(JOBS / "quickstart.toml")
        proc = subprocess.run(
            [sys.executable, "-m", "geofrac.cli", "run", scene, "--out", str(tmp_path / "out")],
            capture_output=True,
            text=True,
            cwd=tmp_path,
            timeout=300,
            check=False,
            env=subprocess_env(),
        )
    finally:
        held.release()
    assert proc.returncode == 1
    assert "is in use by another run" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "out" / "summary.json").exists()


def test_a_failed_rerun_keeps_the_previous_complete_results(tmp_path):
    run_scene(load_scene(JOBS / "cantilever.toml", out=tmp_path), MPI.COMM_SELF, verbose=False)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.name != ".lock"}
    assert _summary(tmp_path / "summary.json")["status"] == "ok"
    bad = load_scene(JOBS / "cantilever.toml", SINGULAR, out=tmp_path)
    with pytest.raises(RunError, match="singular") as info:
        run_scene(bad, MPI.COMM_SELF, verbose=False)
    assert info.value.partial == tmp_path / INCOMPLETE
    after = {
        p.name: p.read_bytes() for p in tmp_path.iterdir() if p.name not in (".lock", INCOMPLETE)
    }
    assert after == before  # the complete results are untouched, byte for byte
    failed = _summary(tmp_path / INCOMPLETE / "summary.json")
    assert failed["status"].startswith("error: linear solver")
    assert failed["scene"]["sha256"] == bad.sha256


def test_a_run_of_another_kind_leaves_no_file_of_the_previous_one(tmp_path):
    run_scene(load_scene(JOBS / "quickstart.toml", out=tmp_path), MPI.COMM_SELF, verbose=False)
    assert (tmp_path / "results.xdmf").exists()
    scene = load_scene(JOBS / "blocks_square.toml", ["geometry.parameters.h=0.3"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_SELF, verbose=False)
    names = sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("."))
    assert names == sorted([*summary["files"], "summary.json"])
    assert "results.xdmf" not in names and "blocks.vtu" in names
    assert not (tmp_path / INCOMPLETE).exists()


BEAM = (
    "geometry.parameters.h_fine=8",
    "geometry.parameters.h=30",
    "cracking.max_events=6",
    "output.checkpoint_minutes=0",
)


def test_a_signal_stops_a_loop_keeps_the_previous_results_and_says_interrupted(tmp_path):
    beam = JOBS / "notched_beam.toml"
    run_scene(load_scene(beam, BEAM, out=tmp_path), MPI.COMM_SELF, verbose=False)
    before = (tmp_path / "events.csv").read_text()
    interrupt.reset()
    interrupt._received.append(signal.SIGTERM)  # as the handler does on SIGTERM
    try:
        with pytest.raises(interrupt.Interrupted, match="SIGTERM after event 1"):
            run_scene(load_scene(beam, BEAM, out=tmp_path), MPI.COMM_SELF, verbose=False)
    finally:
        interrupt.reset()
    assert _summary(tmp_path / "summary.json")["status"] == "ok"
    assert (tmp_path / "events.csv").read_text() == before
    stopped = _summary(tmp_path / INCOMPLETE / "summary.json")
    assert stopped["status"] == "interrupted" and stopped["interrupted"]["signal"] == 15
    assert stopped["interrupted"]["checkpoint"].endswith("ckpt-000000001")
    assert len((tmp_path / INCOMPLETE / "events.csv").read_text().splitlines()) == 2


def test_a_signal_after_the_work_is_done_publishes_it(tmp_path):
    """A run without a loop has nothing to stop: its finished results are published."""
    interrupt._received.append(signal.SIGTERM)
    try:
        summary = run_scene(load_scene(JOBS / "quickstart.toml", out=tmp_path), MPI.COMM_SELF)
    finally:
        interrupt.reset()
    assert summary["status"] == "ok" and (tmp_path / "results.xdmf").exists()


def test_publication_deletes_only_plain_names_the_previous_summary_lists(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    keep = tmp_path / "precious.txt"
    keep.write_text("x")
    (out / "mine.txt").write_text("y")
    files = ["../precious.txt", str(keep), "sub/x", ".lock", "mine.txt"]
    (out / "summary.json").write_text(json.dumps({"status": "ok", "files": files}))
    run_scene(load_scene(JOBS / "quickstart.toml", out=out), MPI.COMM_SELF, verbose=False)
    assert keep.read_text() == "x"
    assert not (out / "mine.txt").exists()


def test_resume_without_a_checkpoint_is_refused_and_a_new_run_discards_the_old_stage(tmp_path):
    with pytest.raises(RunError, match="no complete checkpoint"):
        claim(tmp_path, MPI.COMM_SELF, resume=True)
    stage = tmp_path / INCOMPLETE
    (stage / "checkpoint" / "ckpt-000000007").mkdir(parents=True)
    (stage / "checkpoint" / "ckpt-000000007" / "meta.json").write_text(
        json.dumps({"k": 7, "kind": "mpm", "data": {}, "ranks": 1})
    )
    (stage / "summary.json").write_text(json.dumps({"status": "running"}))
    out = claim(tmp_path, MPI.COMM_SELF)
    out.release()
    assert any("was killed" in n for n in out.notes)
    assert any("discarding" in n and "7" in n for n in out.notes)
    assert list(stage.iterdir()) == []


def test_checkpoints_are_complete_or_ignored_and_only_the_newest_are_kept(tmp_path):
    control = RunControl(MPI.COMM_SELF, tmp_path, "abc", "test", CheckpointPolicy(every=2))
    assert control.poll(1) == (False, False)
    assert control.poll(2) == (True, False)
    for k in (2, 4, 6):
        control.save(k, {"k": k}, shared={"a": np.arange(k, dtype=float)})
    assert len([p for p in tmp_path.iterdir()]) == KEEP
    (tmp_path / "ckpt-000000008.tmp").mkdir()  # a save killed half-way
    ck = latest(tmp_path)
    assert ck is not None and ck.k == 6 and ck.data == {"k": 6}
    assert np.array_equal(ck.shared()["a"], np.arange(6.0))
    interrupt._received.append(signal.SIGINT)
    try:
        assert control.poll(7) == (True, True)
        with pytest.raises(interrupt.Interrupted, match="SIGINT after step 7"):
            control.interrupt("step 7")
    finally:
        interrupt.reset()
    control.resume = ck
    control.check_resume()
    control.sha256 = "other"
    with pytest.raises(RunError, match="another scene"):
        control.check_resume()


@pytest.mark.mpi(min_size=2)
def test_ranks_agree_on_ownership_and_publish_once(mpi_tmp_path):
    comm = MPI.COMM_WORLD
    out = mpi_tmp_path / "owned"
    held = claim(out, comm)
    try:
        with pytest.raises(RunError, match="in use"):
            claim(out, comm)
    finally:
        held.release()
    comm.barrier()
    scene = load_scene_collective(comm, JOBS / "quickstart.toml", out=out)
    summary = run_scene(scene, comm, verbose=False)
    comm.barrier()
    assert comm.allgather(summary["status"]) == ["ok"] * comm.size
    if comm.rank == 0:
        assert _summary(out / "summary.json")["files"] == ["results.h5", "results.xdmf"]
        assert not (out / INCOMPLETE).exists()
    if comm.rank == 1:  # the signal reaches one rank only: every rank must stop
        interrupt._received.append(signal.SIGTERM)
    try:
        with pytest.raises(interrupt.Interrupted, match="after event 1"):
            beam = load_scene_collective(comm, JOBS / "notched_beam.toml", BEAM, out=out)
            run_scene(beam, comm, False)
    finally:
        interrupt.reset()
    comm.barrier()
    if comm.rank == 0:
        assert _summary(out / "summary.json")["status"] == "ok"
        assert _summary(out / INCOMPLETE / "summary.json")["status"] == "interrupted"


def test_resume_refuses_a_checkpoint_of_another_scene_before_any_work(tmp_path):
    ck = tmp_path / INCOMPLETE / "checkpoint" / "ckpt-000000003"
    ck.mkdir(parents=True)
    meta = {"k": 3, "kind": "cracking", "sha256": "0" * 64, "ranks": 1, "data": {}}
    (ck / "meta.json").write_text(json.dumps(meta))
    scene = load_scene(JOBS / "quickstart.toml", out=tmp_path)
    with pytest.raises(RunError, match="another scene"):
        run_scene(scene, MPI.COMM_SELF, verbose=False, resume=True)
    assert (ck / "meta.json").exists()  # the refused resume leaves the checkpoint alone
    assert not (tmp_path / INCOMPLETE / "summary.json").exists()
