"""Checkpoints of the crack event loops: stop at event k, resume, compare with a whole run.

The stop goes through the production path: a :class:`RunControl` whose poll finds
SIGTERM in :mod:`geofrac.interrupt`'s flag at the chosen event (on rank 0 only, so the
flag must reach the other ranks through the poll's reduction). A fresh driver then
resumes from the newest checkpoint; its events, the event log, the XDMF series and the
final displacement must match the uninterrupted run's: the same edges in the same order,
the numbers to 1e-10 relative.
"""

from __future__ import annotations

import csv
import signal
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from mpi4py import MPI

from geofrac import interrupt
from geofrac.effects.cracking import make_driver
from geofrac.fracture.driver import EDGES
from geofrac.fracture.grain_driver import GRAINS as GRAIN_VARIANT
from geofrac.io.checkpoint import CheckpointPolicy, RunControl, latest
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

#: A coarse notched beam (about 740 nodes), as tests/fracture/test_driver.py.
BEAM = ("notched_beam", ("geometry.parameters.h_fine=8", "geometry.parameters.h=30"))
#: The grain beam on a coarse uniform mesh (about 330 nodes), as test_grains.py.
GRAINS = ("grain_notched_beam", ("geometry.parameters.h=16", "geometry.parameters.h_fine=16"))
#: The DCN plate, coarse, with crack-face contact (its flaws close, stick and slip).
CONTACT = (
    "dcn_plate",
    ("geometry.parameters.h=4", "cracking.contact=true", "cracking.contact_iterations=100"),
)
#: The checkpoint kind of each case's driver class.
KINDS = {BEAM: EDGES.kind, GRAINS: GRAIN_VARIANT.kind, CONTACT: EDGES.kind}
#: Fields of an event row that are the answer (``iterations`` is the solver's work).
FIELDS = ("r", "load_factor", "control_displacement", "reaction", "strain_energy", "x", "y")
RTOL = 1e-10


class StopAt(RunControl):
    """A run control that receives SIGTERM (on rank 0) when event ``at`` completes."""

    def __init__(self, *args: Any, at: int = 0, **kw: Any) -> None:
        super().__init__(*args, **kw)
        self.at = at

    def poll(self, k: int) -> tuple[bool, bool]:
        if k == self.at and self.comm.rank == 0:
            interrupt._received.append(signal.SIGTERM)
        return super().poll(k)


class KilledAt(RunControl):
    """A run control whose process "dies" (an exception, no checkpoint) after event ``at``."""

    def __init__(self, *args: Any, at: int = 0, **kw: Any) -> None:
        super().__init__(*args, **kw)
        self.at = at

    def poll(self, k: int) -> tuple[bool, bool]:
        if k == self.at:
            raise KeyboardInterrupt("killed")
        return super().poll(k)


def shared_dir(tmp_path: Path, comm: MPI.Comm) -> Path:
    """Rank 0's tmp_path on every rank."""
    return Path(comm.bcast(str(tmp_path) if comm.rank == 0 else None, root=0))


def driver(
    case: tuple[str, tuple[str, ...]],
    overrides: tuple[str, ...],
    out: Path,
    comm: MPI.Comm,
    control: RunControl | None = None,
) -> Any:
    """The driver of ``case`` writing into ``out``, with ``control`` (not run)."""
    job, small = case
    return path_driver(JOBS / f"{job}.toml", small + overrides, out, comm, control)


def path_driver(
    path: Path,
    overrides: tuple[str, ...],
    out: Path,
    comm: MPI.Comm,
    control: RunControl | None = None,
) -> Any:
    """The crack driver of the scene ``path`` writing into ``out``, with ``control`` (not run)."""
    from geofrac.elements import make_element
    from geofrac.fem.elastic import make_problem
    from geofrac.fem.solution import Solution
    from geofrac.meshing.distribute import build_mesh

    scene = load_scene_collective(comm, path, list(overrides), out=out)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    config = next(s.config for s in scene.effects if s.name == "cracking")
    tagged = build_mesh(scene.geometry, comm)
    problem = make_problem(tagged, make_element(scene.discretization.element, tagged.mesh), scene)
    problem.compile()
    solution = Solution(scene, tagged, problem, control=control)
    return make_driver(config, solution, lambda msg: None, write=True)


def control(
    cls: type[RunControl],
    case: tuple[str, tuple[str, ...]],
    directory: Path,
    comm: MPI.Comm,
    at: int,
    every: int = 0,
    **kw: Any,
) -> RunControl:
    """A run control of class ``cls`` for ``case`` saving into ``directory``."""
    return cls(comm, directory, "sha", KINDS[case], CheckpointPolicy(every, 0.0), at=at, **kw)


def run(d: Any) -> tuple[dict[str, Any] | None, np.ndarray]:
    """Run a driver; (results, or None when interrupted; this rank's final displacement)."""
    try:
        results = d.run()
    except interrupt.Interrupted:
        results = None
    finally:
        interrupt.reset()
    u = d.unknown.x.array.copy()
    d.problem.destroy()
    return results, u


def read_log(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def series_times(path: Path) -> list[float]:
    """The time values of an XDMF temporal collection, in order."""
    return [float(t.get("Value")) for t in ET.parse(path).getroot().iter("Time")]


def rel(a: np.ndarray, b: np.ndarray, comm: MPI.Comm) -> float:
    """The largest |a - b| over the largest |b|, over all ranks."""
    num = comm.allreduce(float(np.max(np.abs(a - b), initial=0.0)), op=MPI.MAX)
    den = comm.allreduce(float(np.max(np.abs(b), initial=0.0)), op=MPI.MAX)
    return num / den


def compare_rows(a: list[dict[str, Any]], b: list[dict[str, Any]]) -> float:
    """Same events and edges in the same order; returns the largest relative difference."""
    assert [(r["event"], r["edge"], r["edges_cracked"]) for r in a] == [
        (r["event"], r["edge"], r["edges_cracked"]) for r in b
    ]
    worst = 0.0
    for key in FIELDS:
        x = np.array([float(r[key]) for r in a])
        y = np.array([float(r[key]) for r in b])
        np.testing.assert_allclose(x, y, rtol=RTOL, atol=0, err_msg=key)
        worst = max(worst, float(np.max(np.abs(x - y) / np.maximum(np.abs(y), 1e-300))))
    return worst


def on_rank0(comm: MPI.Comm, check: Any) -> None:
    """Run ``check()`` on rank 0 and raise its failure on every rank (no rank hangs)."""
    failure = None
    if comm.rank == 0:
        try:
            check()
        except AssertionError as exc:
            failure = str(exc) or "assertion failed"
    failure = comm.bcast(failure, root=0)
    assert failure is None, failure


def whole_run(
    base: Path, case: tuple[str, tuple[str, ...]], overrides: tuple[str, ...], comm: MPI.Comm
) -> tuple[Any, dict[str, Any], np.ndarray]:
    """The uninterrupted run into ``base / "whole"`` (no run control)."""
    d = driver(case, overrides, base / "whole", comm)
    res, u = run(d)
    assert res is not None
    return d, res, u


def check_resumed(
    base: Path,
    out: Path,
    whole: tuple[Any, dict[str, Any], np.ndarray],
    resumed: Any,
    res: dict[str, Any] | None,
    u: np.ndarray,
    comm: MPI.Comm,
    noise: float = 0.0,
) -> dict[str, float]:
    """The resumed run in ``out`` agrees with the whole run in ``base / "whole"``.

    ``noise``: how far another uninterrupted run's final displacement is from it (see
    :func:`stop_and_resume`); the resumed run may differ by as much, not more.
    """
    d_a, res_a, u_a = whole
    assert res is not None
    assert res["events"] == res_a["events"] and res["end_reason"] == res_a["end_reason"]
    worst = compare_rows(resumed.rows, d_a.rows)
    for key in ("factorizations", "refactor_reasons", "cg_iterations", "pinned_dofs"):
        assert res[key] == res_a[key], key  # the same solver path, counted once
    du = rel(u, u_a, comm)
    assert du <= max(RTOL, noise), (du, noise)
    # how each site cracked (cracks.h5's mode), the sites cracked before the replay too
    assert np.array_equal(resumed.loop.modes, d_a.loop.modes)

    def files() -> None:
        log_a, log_b = read_log(base / "whole" / "events.csv"), read_log(out / "events.csv")
        compare_rows(log_b, log_a)
        for name in ("cracks.xdmf", "damage.xdmf"):
            t_a, t_b = series_times(base / "whole" / name), series_times(out / name)
            assert t_b == t_a and len(set(t_b)) == len(t_b), (name, t_a, t_b)
        assert not list(out.glob("*.tmp")) and not list(out.glob(".*.tmp"))

    on_rank0(comm, files)
    return {"rows": worst, "u": du}


def stop_and_resume(
    tmp_path: Path,
    case: tuple[str, tuple[str, ...]],
    overrides: tuple[str, ...],
    k: int,
    comm: MPI.Comm = MPI.COMM_WORLD,
) -> dict[str, Any]:
    """Whole run vs stop after event k + resume; asserts the agreement, returns measures."""
    base = shared_dir(tmp_path, comm)
    whole = whole_run(base, case, overrides, comm)
    assert whole[1]["events"] > k
    noise = 0.0
    if comm.size > 1:
        # Two uninterrupted runs on 2 ranks are not always bit for bit alike (the first
        # run in a process may differ from later ones): the event rows by about 1e-14,
        # the final displacement by up to 1e-6 of its largest value on a few poorly
        # determined DOFs. A second whole run measures it; the resumed run may differ
        # from the first by as much as that one does, and its rows by 1e-10.
        again = whole_run(base / "again", case, overrides, comm)
        compare_rows(again[0].rows, whole[0].rows)
        noise = rel(again[2], whole[2], comm)

    out = base / "stopped"
    ck = out / "checkpoint"
    d = driver(case, overrides, out, comm, control(StopAt, case, ck, comm, at=k))
    res, _ = run(d)
    assert res is None  # interrupted
    assert len(d.rows) == 0  # the loop never reached its end
    saved = latest(ck)
    assert saved is not None and saved.k == k

    def streamed() -> None:
        log = read_log(out / "events.csv")
        assert [int(r["event"]) for r in log] == list(range(1, k + 1))
        assert not list(out.glob("*.tmp")) and not list(out.glob(".*.tmp"))
        for name in ("cracks.xdmf", "damage.xdmf"):
            times = series_times(out / name)
            assert times and max(times) <= k and len(set(times)) == len(times)

    on_rank0(comm, streamed)
    resumed = driver(
        case, overrides, out, comm, control(StopAt, case, ck, comm, at=-1, resume=saved)
    )
    res_b, u_b = run(resumed)
    assert res_b is not None and res_b["resumed_after_event"] == k
    got = check_resumed(base, out, whole, resumed, res_b, u_b, comm, noise)
    return got | {"replay_from": saved.data["replay_from"], "noise": noise}


SOLVERS = [
    ("update",),
    ("update", "cracking.update_dofs=40"),  # factorises afresh every few events
    ("refactor",),
    ("reuse",),
]


@pytest.mark.parametrize("solver", SOLVERS, ids="-".join)
def test_edge_cracking_resumes_exactly(tmp_path, solver):
    overrides = (
        "cracking.max_events=30",
        "cracking.output_every=4",
        f"cracking.solver={solver[0]}",
    )
    got = stop_and_resume(tmp_path, BEAM, overrides + solver[1:], k=9, comm=MPI.COMM_SELF)
    print(f"edge cracking {solver}: {got}")


def contact_stop_and_resume(tmp_path: Path, comm: MPI.Comm) -> dict[str, Any]:
    """:func:`stop_and_resume` of :data:`CONTACT`, and the contact columns and changes."""
    overrides = ("cracking.max_events=30", "cracking.output_every=4", "cracking.update_dofs=300")
    got = stop_and_resume(tmp_path, CONTACT, overrides, k=17, comm=comm)
    base = shared_dir(tmp_path, comm)

    def logs() -> None:
        whole, out = base / "whole", base / "stopped"
        a, b = read_log(whole / "events.csv"), read_log(out / "events.csv")
        for key in ("open", "stick", "slip", "contact_changes"):
            assert [r[key] for r in b] == [r[key] for r in a], key
        gaps_a, gaps_b = ([float(r["min_gap"]) for r in log] for log in (a, b))
        np.testing.assert_allclose(gaps_b, gaps_a, rtol=RTOL, atol=0)
        changes_a, changes_b = read_log(whole / "contact.csv"), read_log(out / "contact.csv")
        assert any(r["to"] == "slip" for r in changes_a)
        # state changes in the replayed events and after the stop
        assert {int(r["event"]) for r in changes_a} & set(range(got["replay_from"], 18))
        assert {int(r["event"]) for r in changes_a} & set(range(18, 31))
        key = ("event", "edge", "from", "to")
        assert [tuple(r[k] for k in key) for r in changes_b] == [
            tuple(r[k] for k in key) for r in changes_a
        ]

    on_rank0(comm, logs)
    assert got["replay_from"] < 17  # events were recomputed from the checkpoint's states
    return got


def test_cracking_with_contact_resumes_exactly(tmp_path):
    """The face pairs' states come back with the crack state.

    Stick, slip, open, bonds and held pairs: the resumed run's events, contact columns
    and state changes are the whole run's.
    """
    got = contact_stop_and_resume(tmp_path, MPI.COMM_SELF)
    print(f"cracking with contact: {got}")


@pytest.mark.parametrize("solver", ["update", "refactor"])
def test_grain_cracking_resumes_exactly(tmp_path, solver):
    overrides = (
        "cracking.max_events=24",
        "cracking.output_every=5",
        "cracking.precracked_fraction=0.04",
        f"cracking.solver={solver}",
    )
    got = stop_and_resume(tmp_path, GRAINS, overrides, k=13, comm=MPI.COMM_SELF)
    print(f"grain cracking {solver}: {got}")


def test_killed_run_resumes_from_its_last_checkpoint(tmp_path):
    """A run that died after event 13 is resumed from its last checkpoint (event 10).

    It had written rows and frames past that checkpoint: the resumed run cuts both back
    and computes those events again.
    """
    comm = MPI.COMM_SELF
    case = BEAM
    overrides = ("cracking.max_events=24", "cracking.output_every=3")
    whole = whole_run(tmp_path, case, overrides, comm)
    out, ck = tmp_path / "killed", tmp_path / "killed" / "checkpoint"
    d = driver(case, overrides, out, comm, control(KilledAt, case, ck, comm, at=13, every=5))
    with pytest.raises(KeyboardInterrupt):
        d.run()
    d.destroy()
    d.problem.destroy()
    assert [int(r["event"]) for r in read_log(out / "events.csv")] == list(range(1, 14))
    assert series_times(out / "cracks.xdmf") == [1.0, 3.0, 6.0, 9.0, 12.0]
    saved = latest(ck)
    assert saved is not None and saved.k == 10
    assert sorted(p.name for p in ck.iterdir()) == ["ckpt-000000005", "ckpt-000000010"]
    resumed = driver(
        case, overrides, out, comm, control(StopAt, case, ck, comm, at=-1, resume=saved)
    )
    res, u = run(resumed)
    check_resumed(tmp_path, out, whole, resumed, res, u, comm)


def test_resume_refuses_another_loop_and_rank_count(tmp_path):
    comm = MPI.COMM_SELF
    overrides = ("cracking.max_events=8",)
    ck = tmp_path / "checkpoint"
    run(driver(BEAM, overrides, tmp_path, comm, control(StopAt, BEAM, ck, comm, at=4)))
    saved = latest(ck)
    assert saved is not None and saved.k == 4
    from geofrac.errors import RunError

    grains = control(StopAt, GRAINS, ck, comm, at=-1, resume=saved)
    with pytest.raises(RunError, match="'cracking' loop, this run is 'grains'"):
        grains.check_resume()
    saved.meta["ranks"] = 2
    d = driver(
        BEAM, overrides, tmp_path, comm, control(StopAt, BEAM, ck, comm, at=-1, resume=saved)
    )
    with pytest.raises(RunError, match="written on 2 rank"):
        d.run()
    d.problem.destroy()
    assert [int(r["event"]) for r in read_log(tmp_path / "events.csv")] == [1, 2, 3, 4]


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("solver", ["update", "refactor"])
def test_edge_cracking_resumes_exactly_on_2_ranks(tmp_path, solver):
    overrides = (
        "cracking.max_events=30",
        "cracking.output_every=4",
        "cracking.update_dofs=60",
        f"cracking.solver={solver}",
    )
    got = stop_and_resume(tmp_path, BEAM, overrides, k=11, comm=MPI.COMM_WORLD)
    print(f"edge cracking {solver} on {MPI.COMM_WORLD.size} ranks: {got}")


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("solver", ["update", "refactor"])
def test_grain_cracking_resumes_exactly_on_2_ranks(tmp_path, solver):
    # 13 events: the crack now crosses the coarse beam at about event 14, after which the
    # nearly separated system leaves the 2-rank refactor 1.4e-10 apart (RTOL 1e-10)
    overrides = (
        "cracking.max_events=13",
        "cracking.output_every=5",
        "cracking.precracked_fraction=0.04",
        f"cracking.solver={solver}",
    )
    got = stop_and_resume(tmp_path, GRAINS, overrides, k=7, comm=MPI.COMM_WORLD)
    print(f"grain cracking {solver} on {MPI.COMM_WORLD.size} ranks: {got}")


def test_final_crack_pattern_is_one_frame_that_vtk_opens(tmp_path):
    """jobs/plate_hole.toml (coarse): the last event is a frame event; it appears once."""
    import pyvista as pv

    case = ("plate_hole", ("geometry.parameters.h=4",))
    overrides = ("cracking.max_events=10", "cracking.output_every=5")
    d = driver(case, overrides, tmp_path, MPI.COMM_SELF)
    try:
        res = d.run()
        cracked = d.state.cracked.astype(float)
        edges, cells = len(d.state.mesh.edges), len(d.gm.cells)
    finally:
        d.problem.destroy()
    assert res["events"] == 10
    for name, n in (("cracks.xdmf", edges), ("damage.xdmf", cells)):
        assert series_times(tmp_path / name) == [1.0, 5.0, 10.0]
        reader = pv.get_reader(str(tmp_path / name))
        assert isinstance(reader, pv.XdmfReader) and reader.time_values == [1.0, 5.0, 10.0]
        reader.set_active_time_value(10.0)
        mesh = reader.read()
        assert mesh.n_cells == n, name
        if name == "cracks.xdmf":
            assert np.array_equal(mesh.cell_data["crack"], cracked)
            assert cracked.sum() == 10 + res["precracked_edges"]
        else:
            assert mesh.cell_data["damage"].max() > 0 and "displacement" in mesh.point_data
