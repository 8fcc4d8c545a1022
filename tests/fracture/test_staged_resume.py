"""Checkpoints of a staged cracking run: stop at event k, resume, compare with a whole run.

The plate of scenes/plate_hole_staged.toml with its opening excavated as a heading (share
0.45: one crack, at λ = 0.403) and a bench (the rest: five more), as
tests/fracture/test_staged_cracking.py, meshed once per test (a ``.msh``: the runs then
take about 0.5 s each). A run stopped (SIGTERM through the run control, as
tests/fracture/test_resume.py) after event 1, the heading's last (the stage boundary comes
in event 2), after event 2 or after event 3 (the bench running: the restored crack state
has the heading's crack, then the bench's removal, then its cracks), and resumed, must
give the whole run's events (the same edges, modes and numbers to 1e-10), the same
``stages`` entries of ``summary.json``, the same ``results.xdmf`` steps and the same final
state; also with contact on the new cracks (the pairs' states and contact.csv), for a
stage without a removal (the share of the release applied before it) and on 2 ranks.
A checkpoint of other stages, or of a run without stages, is refused naming the problem.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.io import checkpoint
from geofrac.io.checkpoint import CheckpointPolicy, RunControl
from geofrac.meshing.geo import meshed_model
from tests.fracture.test_resume import StopAt, check_resumed, read_log, run, shared_dir
from tests.fracture.test_resume import path_driver as driver
from tests.fracture.test_staged_cracking import HEADING_BENCH, _staged

#: the heading's share: it cracks once, then the bench five times.
SHARE = 0.45
OVERRIDES = ("cracking.max_events=6", "cracking.output_every=2")
RTOL = 1e-10


def scene(
    tmp: Path, comm: MPI.Comm, share: float = SHARE, *, mesh: Path | None = None, stages: str = ""
) -> Path:
    """The heading-and-bench plate in rank 0's ``tmp``, on its mesh meshed once (``.msh``).

    ``mesh``: a ``.msh`` already written (another share of the same plate); ``stages``:
    other ``[[stages]]`` than the heading's (``share``) and the bench's.
    """
    path = None
    if comm.rank == 0:
        tmp.mkdir(parents=True, exist_ok=True)
        stages = stages or HEADING_BENCH.format(share=share)
        text = _staged(tmp, stages, split=True).read_text()
        found = re.search(r'file = "(.*)"\nparameters = \{(.*)\}', text)
        assert found is not None
        if mesh is None:
            mesh = tmp / "plate.msh"
            pairs = (kv.split("=") for kv in found.group(2).split(","))
            with meshed_model(
                Path(found.group(1)), {k.strip(): float(v) for k, v in pairs}, None, dim=2
            ) as gmsh:
                gmsh.write(str(mesh))
        path = tmp / "plate.toml"
        path.write_text(text.replace(found.group(0), f'file = "{mesh}"'))
    return Path(comm.bcast(str(path) if path else None, root=0))


def stop_at(directory: Path, comm: MPI.Comm, at: int, resume: Any = None) -> RunControl:
    return StopAt(
        comm, directory, "sha", "cracking", CheckpointPolicy(0, 0.0), at=at, resume=resume
    )


def frames(d: Any) -> list[tuple[int, str, list[np.ndarray]]]:
    """The ``results.xdmf`` steps: (index, name, this rank's arrays of each field)."""
    return [(f.index, f.name, [g.x.array.copy() for g in f.functions]) for f in d.loop.frames]


def same(x: Any, y: Any, where: str = "stages") -> None:
    """JSON values alike: the same structure and strings, numbers to RTOL."""
    if isinstance(x, dict):
        assert isinstance(y, dict) and x.keys() == y.keys(), where
        for key in x:
            same(x[key], y[key], f"{where}.{key}")
    elif isinstance(x, list):
        assert isinstance(y, list) and len(x) == len(y), where
        for i, (a, b) in enumerate(zip(x, y, strict=True)):
            same(a, b, f"{where}[{i}]")
    elif isinstance(x, float):
        assert y == pytest.approx(x, rel=RTOL, abs=0), where
    else:
        assert x == y, where


def whole(base: Path, path: Path, overrides: tuple[str, ...], comm: MPI.Comm) -> Any:
    d = driver(path, overrides, base / "whole", comm)
    res, u = run(d)
    assert res is not None
    return d, res, u, frames(d)


def stopped(base: Path, path: Path, overrides: tuple[str, ...], k: int, comm: MPI.Comm) -> Path:
    """Run ``path`` into ``base / "stopped"``, checkpoints after every event, stop after k."""
    ck = base / "stopped" / "checkpoint"
    control = StopAt(comm, ck, "sha", "cracking", CheckpointPolicy(1, 0.0), at=k)
    res, _ = run(driver(path, overrides, base / "stopped", comm, control))
    assert res is None
    return ck


def resumed(
    base: Path, path: Path, overrides: tuple[str, ...], saved: Any, ref: Any, comm: MPI.Comm
) -> dict[str, float]:
    """Resume from ``saved`` in ``base / "stopped"``; it agrees with ``ref`` (the whole run)."""
    out = base / "stopped"
    d = driver(path, overrides, out, comm, stop_at(saved.path.parent, comm, -1, resume=saved))
    res, u = run(d)
    assert res is not None and res["resumed_after_event"] == saved.k
    d_a, res_a, _, frames_a = ref
    got = check_resumed(base, out, ref[:3], d, res, u, comm)
    assert [r["mode"] for r in d.rows] == [r["mode"] for r in d_a.rows]
    same(res["stages"], res_a["stages"])
    steps = frames(d)
    assert [f[:2] for f in steps] == [f[:2] for f in frames_a]
    got["steps"] = 0.0
    for (_, name, fields), (_, _, fields_a) in zip(steps, frames_a, strict=True):
        for f, f_a in zip(fields, fields_a, strict=True):
            scale = comm.allreduce(float(np.max(np.abs(f_a), initial=0.0)), op=MPI.MAX)
            np.testing.assert_allclose(f, f_a, rtol=0, atol=RTOL * scale, err_msg=name)
            diff = comm.allreduce(float(np.max(np.abs(f - f_a), initial=0.0)), op=MPI.MAX)
            got["steps"] = max(got["steps"], diff / scale if scale else diff)
    return got


def saved(ck: Path, k: int) -> checkpoint.Checkpoint:
    """Checkpoint k of the directory ``ck``."""
    path = ck / f"ckpt-{k:09d}"
    return checkpoint.Checkpoint(path, json.loads((path / "meta.json").read_text()))


def test_staged_cracking_resumes_at_a_stage_boundary_and_within_a_stage(tmp_path, monkeypatch):
    """Stopped after event 3, resumed from its checkpoints after events 1, 2 and 3.

    After event 1 the heading is running (its end and the bench's removal come in event
    2); after event 3 the bench is, and its first solve (event 2) is the replay's start.
    """
    monkeypatch.setattr(checkpoint, "KEEP", 3)  # keep the checkpoints of events 1-3
    comm = MPI.COMM_SELF
    path = scene(tmp_path / "scene", comm)
    ref = whole(tmp_path, path, OVERRIDES, comm)
    assert [s["events"] for s in ref[1]["stages"]] == [1, 5]
    ck = stopped(tmp_path, path, OVERRIDES, 3, comm)
    for k, stage, replay_from in ((1, 0, 1), (2, 1, 2), (3, 1, 2)):
        ckpt = saved(ck, k)
        assert ckpt.data["loop"]["stage"] == stage and ckpt.data["replay_from"] == replay_from
        print(f"resumed after event {k}: {resumed(tmp_path, path, OVERRIDES, ckpt, ref, comm)}")

    # a checkpoint of other stages, or of a run without stages, is refused
    other = scene(tmp_path / "other", comm, 0.5, mesh=tmp_path / "scene" / "plate.msh")
    ckpt = saved(ck, 3)
    d = driver(other, OVERRIDES, tmp_path / "other", comm, stop_at(ck, comm, -1, resume=ckpt))
    with pytest.raises(
        RunError,
        match=r"other \[\[stages\]\] \('heading' \(removes heading, 0.45\); 'bench' \(removes "
        r"bench, all that remains\)\); this scene's are 'heading' \(removes heading, 0.5\)",
    ):
        d.run()
    d.problem.destroy()
    ckpt.meta["data"].pop("loop")
    d = driver(path, OVERRIDES, tmp_path / "other", comm, stop_at(ck, comm, -1, resume=ckpt))
    with pytest.raises(RunError, match="without \\[\\[stages\\]\\]; this scene has 2 stages"):
        d.run()
    d.problem.destroy()


def test_staged_cracking_with_contact_resumes(tmp_path):
    """Contact on the new cracks (share 0.3: the bench cracks, its pairs stick and slip).

    Stopped after event 4 of 6: the pairs' states, held pairs and counters come back with
    the crack state, both removals replayed before it.
    """
    comm = MPI.COMM_SELF
    overrides = ("cracking.max_events=6", "cracking.contact=true")
    path = scene(tmp_path / "scene", comm, 0.3)
    ref = whole(tmp_path, path, overrides, comm)
    assert [s["events"] for s in ref[1]["stages"]] == [0, 6]
    assert ref[1]["contact"]["slip"] > 0 and ref[1]["contact"]["frozen_pairs"] > 0
    ck = stopped(tmp_path, path, overrides, 4, comm)
    ckpt = saved(ck, 4)
    assert ckpt.data["loop"]["stage"] == 1 and ckpt.data["loop"]["starts"] == [0, 0]
    print(f"with contact: {resumed(tmp_path, path, overrides, ckpt, ref, comm)}")
    whole_log, log = (
        read_log(d / "events.csv") for d in (tmp_path / "whole", tmp_path / "stopped")
    )
    for key in ("open", "stick", "slip", "contact_changes"):
        assert [r[key] for r in log] == [r[key] for r in whole_log], key
    changes = [read_log(d / "contact.csv") for d in (tmp_path / "whole", tmp_path / "stopped")]
    assert changes[1] == changes[0] and changes[0]


#: the whole opening at once, 0.4 of its release, then the rest without a removal.
RELAX = """[[stages]]
name = "excavate"
remove = ["heading", "bench"]
relaxation = 0.4

[[stages]]
name = "rest"
"""


def test_a_stage_without_removal_resumes_with_the_share_applied_before_it(tmp_path):
    """The second stage releases the rest of the first stage's release P (a = 0.4).

    The refactor solver factorises every event, so checkpoint 3 restarts at event 3 in the
    second stage: its constant load F0 − (1 − a) P needs the stored P and a.
    """
    comm = MPI.COMM_SELF
    overrides = ("cracking.max_events=5", "cracking.solver=refactor")
    path = scene(tmp_path / "scene", comm, stages=RELAX)
    ref = whole(tmp_path, path, overrides, comm)
    assert [s["events"] for s in ref[1]["stages"]] == [0, 5]
    ck = stopped(tmp_path, path, overrides, 3, comm)
    ckpt = saved(ck, 3)
    loop = ckpt.data["loop"]
    assert loop["stage"] == 1 and loop["applied"] == 0.4 and ckpt.data["replay_from"] == 3
    print(f"without removal: {resumed(tmp_path, path, overrides, ckpt, ref, comm)}")


@pytest.mark.mpi(min_size=2)
def test_staged_cracking_resumes_on_2_ranks(tmp_path):
    """Stopped after event 3 (the bench running), resumed: as the whole run on 2 ranks."""
    comm = MPI.COMM_WORLD
    base = shared_dir(tmp_path, comm)
    path = scene(base / "scene", comm)
    ref = whole(base, path, OVERRIDES, comm)
    assert [s["events"] for s in ref[1]["stages"]] == [1, 5]
    ck = stopped(base, path, OVERRIDES, 3, comm)
    ckpt = saved(ck, 3)
    assert ckpt.data["loop"]["stage"] == 1
    print(f"on {comm.size} ranks: {resumed(base, path, OVERRIDES, ckpt, ref, comm)}")
