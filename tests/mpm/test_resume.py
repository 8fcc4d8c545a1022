"""MPM checkpoints and resume (geofrac.mpm.driver.simulate with a RunControl).

A run is stopped after step k (a control whose poll says stop there, as a signal would)
and resumed by a fresh ``simulate`` call from the checkpoint it wrote; the resumed run
must end in the particle state of the uninterrupted run (bit for bit on the same number
of ranks: each rank keeps its particles in their local order), with the same results,
each frame time once in particles.xdmf and each step once in energies.csv.

The MPI tests run under ``mpiexec -n 2 python -m mpi4py -m pytest --only-mpi``.
"""

import csv
import signal
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from geofrac import interrupt
from geofrac.errors import RunError
from geofrac.interrupt import Interrupted
from geofrac.io.checkpoint import CheckpointPolicy, RunControl, latest
from geofrac.mpm import driver
from geofrac.mpm.particles import Particles
from geofrac.scene import load_scene
from tests.conftest import JOBS

#: Every array of the particle state.
STATE = [f for f in Particles.__dataclass_fields__]

COARSE_SLIDE = [
    "geometry.parameters.h=1.5",
    "mpm.grid.spacing=2.0",
    "mpm.grid.upper=[250.0, 100.0]",  # so that 2 ranks both hold particles
    "mpm.frames=5",
    "plasticity.friction_angle=8",
]

#: Small scenes: (job, overrides). The landslide has plasticity, friction and gravity.
SCENES = {
    "bar": ("mpm_bar_w1000.toml", ["mpm.t_end=0.02", "mpm.frames=7"]),
    "slide": ("landslide_kita_uebaru.toml", [*COARSE_SLIDE, "mpm.t_end=0.6"]),
    # USF: its strain reads the contact's memory of the previous step (friction.held_vn)
    "slide_usf": ("landslide_kita_uebaru.toml", [*COARSE_SLIDE, "mpm.t_end=0.6", "mpm.scheme=usf"]),
    "mls": (
        "mpm_translating_bar.toml",
        ["mpm.t_end=12", "mpm.frames=9", 'effects=["mls_smoothing"]', "mpm.shape=cpgimp"],
    ),
    "moving": ("mpm_translating_bar.toml", ["mpm.t_end=2", "mpm.frames=4", "mpm.shape=ugimp"]),
    "slide_mls": (
        "landslide_kita_uebaru.toml",
        [
            *COARSE_SLIDE,
            "mpm.t_end=0.3",
            'effects=["gravity", "plasticity", "friction", "mls_smoothing"]',
        ],
    ),
}

#: Where the runs stop, as a fraction of their steps: the MLS bar after the peak of its
#: energy drift (step 5085 of 5367), so that its result is the restored drift.
STOP_AT = {"mls": 0.97}


class StopAt(RunControl):
    """A control that stops the run after step ``at``, as SIGTERM would."""

    def __init__(self, *args, at: int, signal_hook: bool = False, **kwargs):
        super().__init__(*args, **kwargs)
        self.at, self.signal_hook = at, signal_hook

    def poll(self, k):
        if k == self.at:
            if self.signal_hook:  # the real path: the signal handler's flag
                interrupt._received.append(signal.SIGTERM)
            else:
                return self.directory is not None, True
        return super().poll(k)


@pytest.fixture(autouse=True)
def _no_signal():
    interrupt.reset()
    yield
    interrupt.reset()


def _control(comm, directory, cls=RunControl, resume=None, every=0, **kwargs):
    return cls(
        comm,
        directory,
        "sha-of-the-scene",
        "mpm",
        CheckpointPolicy(every=every, minutes=0.0),
        resume,
        **kwargs,
    )


def _simulate(name, out, comm, control=None, monkeypatch=None):
    """Run scene ``name`` into ``out``.

    Returns:
        The results, the final particles gathered in id order (rank 0; None elsewhere)
        and this rank's final particles in their local order.
    """
    job, overrides = SCENES[name]
    out.mkdir(parents=True, exist_ok=True)
    scene = load_scene(JOBS / job, overrides, out=out)
    runs = []
    original = driver.prepare

    def prepare(*args, **kwargs):
        runs.append(original(*args, **kwargs))
        return runs[-1]

    monkeypatch.setattr(driver, "prepare", prepare)
    try:
        results = driver.simulate(scene, comm, verbose=False, write=True, control=control)
    finally:
        monkeypatch.setattr(driver, "prepare", original)
    run = runs[-1]
    gathered = run.particles if run.domain is None else run.domain.gather(run.particles)
    return results, gathered, run.particles


def _stop_and_resume(name, out, comm, at, monkeypatch, signal_hook=False, resume_comm=None):
    """Stop ``name`` after step ``at``, then resume it (on ``resume_comm``) to the end."""
    directory = out / "checkpoint"
    stopper = _control(comm, directory, StopAt, at=at, signal_hook=signal_hook)
    with pytest.raises(Interrupted, match=f"after step {at}"):
        _simulate(name, out, comm, stopper, monkeypatch)
    assert stopper.saved is not None and stopper.saved.name == f"ckpt-{at:09d}"
    interrupt.reset()
    comm = resume_comm or comm
    ck = latest(directory)
    assert ck is not None and ck.k == at
    return _simulate(name, out, comm, _control(comm, directory, resume=ck), monkeypatch)


def _energy_rows(out: Path) -> list[dict[str, str]]:
    with (out / "energies.csv").open() as f:
        return list(csv.DictReader(f))


def _frame_times(out: Path) -> list[float]:
    root = ET.parse(out / "particles.xdmf").getroot()
    return [float(t.get("Value")) for t in root.iter("Time")]


def _frames(out: Path) -> list[dict[str, np.ndarray]]:
    with h5py.File(out / "particles.h5") as f:
        n = sum(1 for k in f if k.startswith("frame_"))
        return [{k: f[f"frame_{i}/{k}"][()] for k in f[f"frame_{i}"]} for i in range(n)]


def _same_particles(a: Particles, b: Particles, rtol: float) -> None:
    np.testing.assert_array_equal(a.ids, b.ids)
    for name in STATE:
        x, y = getattr(a, name), getattr(b, name)
        scale = max(float(np.abs(y).max(initial=0.0)), 1e-300)
        assert float(np.abs(x - y).max(initial=0.0)) <= rtol * scale, name


def _same_outputs(resumed: Path, reference: Path, steps: int) -> None:
    """The resumed run's files equal the reference's; each step and time once."""
    rows, ref = _energy_rows(resumed), _energy_rows(reference)
    assert [int(r["step"]) for r in rows] == list(range(steps + 1))
    assert rows == ref  # the same numbers, printed with repr: the same bits
    times = _frame_times(resumed)
    assert times == _frame_times(reference)
    assert len(set(times)) == len(times) and times == sorted(times)
    frames, ref_frames = _frames(resumed), _frames(reference)
    assert len(frames) == len(ref_frames) == len(times)
    for a, b in zip(frames, ref_frames, strict=True):
        assert sorted(a) == sorted(b)
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def _same_results(a: dict, b: dict) -> None:
    for key in ("runout_m", "energy_drift_max", "history", "probes", "steps", "particles"):
        assert a[key] == b[key], key


@pytest.mark.parametrize("name", list(SCENES))
def test_a_stopped_run_resumes_to_the_uninterrupted_result(tmp_path, monkeypatch, name):
    comm = MPI.COMM_SELF
    reference, ref_p, _ = _simulate(name, tmp_path / "ref", comm, None, monkeypatch)
    steps = reference["steps"]
    at = int(STOP_AT.get(name, 0.4) * steps) + 1  # not a frame step
    results, p, _ = _stop_and_resume(name, tmp_path / "run", comm, at, monkeypatch)
    assert results["resumed_at_step"] == at
    _same_particles(p, ref_p, rtol=0.0)  # bit for bit (the tests' bound is 1e-12)
    _same_results(results, reference)
    _same_outputs(tmp_path / "run", tmp_path / "ref", steps)


def test_a_signal_at_a_frame_step_after_periodic_checkpoints_resumes_exactly(tmp_path, monkeypatch):
    """The signal flag path (SIGTERM appended by a hook), on a frame step, after periodic saves."""
    comm = MPI.COMM_SELF
    reference, ref_p, _ = _simulate("slide", tmp_path / "ref", comm, None, monkeypatch)
    steps = reference["steps"]
    every = max(1, steps // 5)  # the frame interval of the scene (frames = 5)
    out = tmp_path / "run"
    directory = out / "checkpoint"
    stopper = _control(comm, directory, StopAt, at=2 * every, signal_hook=True, every=7)
    with pytest.raises(Interrupted, match="SIGTERM after step"):
        _simulate("slide", out, comm, stopper, monkeypatch)
    interrupt.reset()
    kept = sorted(p.name for p in directory.iterdir())
    assert kept[-1] == f"ckpt-{2 * every:09d}" and len(kept) == 2  # KEEP = 2
    # the outputs are consistent at the stop: every step so far, the frames so far
    assert int(_energy_rows(out)[-1]["step"]) == 2 * every
    assert _frame_times(out) == _frame_times(tmp_path / "ref")[:3]
    results, p, _ = _simulate(
        "slide", out, comm, _control(comm, directory, resume=latest(directory)), monkeypatch
    )
    _same_particles(p, ref_p, rtol=0.0)
    _same_results(results, reference)
    _same_outputs(out, tmp_path / "ref", steps)


def test_a_killed_run_resumes_from_its_last_checkpoint_and_drops_what_came_after(
    tmp_path, monkeypatch
):
    """A run killed after writing steps and frames past its last checkpoint (SIGKILL)."""
    comm = MPI.COMM_SELF
    reference, ref_p, _ = _simulate("bar", tmp_path / "ref", comm, None, monkeypatch)
    steps = reference["steps"]
    out = tmp_path / "run"
    directory = out / "checkpoint"
    # periodic checkpoints, then "killed" late: the stop writes a checkpoint we throw away
    stopper = _control(comm, directory, StopAt, at=steps - 3, every=steps // 4)
    with pytest.raises(Interrupted):
        _simulate("bar", out, comm, stopper, monkeypatch)
    latest(directory).path.rename(directory / "ignored")  # as if it had never been written
    ck = latest(directory)
    assert ck is not None and ck.k == 3 * (steps // 4)
    assert int(_energy_rows(out)[-1]["step"]) == steps - 3
    with (out / "energies.csv").open("a") as f:
        f.write(f"{steps - 2},0.0,1")  # a torn last line
    results, p, _ = _simulate("bar", out, comm, _control(comm, directory, resume=ck), monkeypatch)
    _same_particles(p, ref_p, rtol=0.0)
    _same_results(results, reference)
    _same_outputs(out, tmp_path / "ref", steps)


def test_a_checkpoint_of_another_scene_is_refused(tmp_path, monkeypatch):
    comm = MPI.COMM_SELF
    out = tmp_path / "run"
    stopper = _control(comm, out / "checkpoint", StopAt, at=5)
    with pytest.raises(Interrupted):
        _simulate("bar", out, comm, stopper, monkeypatch)
    other = RunControl(
        comm, out / "checkpoint", "another-sha", "mpm", resume=latest(out / "checkpoint")
    )
    with pytest.raises(RunError, match="another scene"):
        _simulate("bar", out, comm, other, monkeypatch)


def test_no_control_means_no_checkpoint_and_no_polling(tmp_path, monkeypatch):
    """control=None: the loop never asks; a signal flag does not stop it."""
    interrupt._received.append(signal.SIGTERM)
    results, _, _ = _simulate("bar", tmp_path, MPI.COMM_SELF, None, monkeypatch)
    assert "resumed_at_step" not in results
    assert int(_energy_rows(tmp_path)[-1]["step"]) == results["steps"]
    assert not (tmp_path / "checkpoint").exists()


# --- MPI ------------------------------------------------------------------------------


def _shared_dir(comm, tmp_path_factory, name):
    return Path(comm.bcast(str(tmp_path_factory.mktemp(name)) if comm.rank == 0 else None))


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("name", ["slide", "slide_usf", "slide_mls", "moving"])
def test_a_decomposed_run_resumes_to_the_uninterrupted_result(tmp_path_factory, monkeypatch, name):
    comm = MPI.COMM_WORLD
    base = _shared_dir(comm, tmp_path_factory, f"mpi-{name}")
    reference, ref_p, ref_local = _simulate(name, base / "ref", comm, None, monkeypatch)
    steps = reference["steps"]
    at = steps // 2 + 1
    results, p, local = _stop_and_resume(
        name, base / "run", comm, at, monkeypatch, signal_hook=True
    )
    assert (base / "run" / "checkpoint" / f"ckpt-{at:09d}" / f"rank-{comm.size - 1}.npz").exists()
    _same_results(results, reference)
    # every rank's particles, in their local order, equal the reference's
    same = comm.allreduce(int(_equal(local, ref_local)), op=MPI.MIN)
    assert same == 1
    if name == "moving":  # the bar crosses the slab boundary: particles changed rank
        assert comm.allreduce(int(np.any(np.diff(local.ids) < 0)), op=MPI.MAX) == 1
    if comm.rank == 0:
        _same_particles(p, ref_p, rtol=0.0)
        _same_outputs(base / "run", base / "ref", steps)
    comm.barrier()


def _equal(a, b):
    return all(np.array_equal(getattr(a, n), getattr(b, n)) for n in STATE)


def _differences(a: Particles, b: Particles) -> dict[str, float]:
    """Largest difference of each array relative to the array's largest value."""
    np.testing.assert_array_equal(a.ids, b.ids)
    out = {}
    for name in STATE:
        x, y = getattr(a, name), getattr(b, name)
        scale = max(float(np.abs(y).max(initial=0.0)), 1e-300)
        out[name] = float(np.abs(x - y).max(initial=0.0)) / scale
    return out


#: Agreement asked of a run resumed on another number of ranks (measured: docs/mpm.md).
ROUND_OFF = 1e-9


@pytest.mark.mpi(min_size=2)
def test_a_checkpoint_resumes_on_another_number_of_ranks(tmp_path_factory, monkeypatch):
    """Written on all ranks, resumed on one; written on one, resumed on all: round-off."""
    comm, alone = MPI.COMM_WORLD, MPI.COMM_SELF
    base = _shared_dir(comm, tmp_path_factory, "ranks")
    name = "slide"
    wide, wide_p, _ = _simulate(name, base / "ref-wide", comm, None, monkeypatch)
    steps, at = wide["steps"], wide["steps"] // 3 + 1
    if comm.rank == 0:
        serial, serial_p, _ = _simulate(name, base / "ref-1", alone, None, monkeypatch)
    # stopped on all ranks, resumed on rank 0 alone
    directory = base / "from-wide" / "checkpoint"
    with pytest.raises(Interrupted):
        _simulate(
            name, base / "from-wide", comm, _control(comm, directory, StopAt, at=at), monkeypatch
        )
    if comm.rank == 0:
        ck = latest(directory)
        assert ck.ranks() == comm.size
        results, p, _ = _simulate(
            name, base / "from-wide", alone, _control(alone, directory, resume=ck), monkeypatch
        )
        print("wide -> 1, vs 1 rank:", _differences(p, serial_p))
        print("wide -> 1, vs wide:", _differences(p, wide_p))
        assert max(_differences(p, serial_p).values()) < ROUND_OFF
        assert results["runout_m"] == pytest.approx(serial["runout_m"], rel=ROUND_OFF)
        rows = _energy_rows(base / "from-wide")
        assert [int(r["step"]) for r in rows] == list(range(steps + 1))
        assert _frame_times(base / "from-wide") == _frame_times(base / "ref-1")
    comm.barrier()
    # stopped on rank 0 alone, resumed on all ranks
    directory = base / "from-1" / "checkpoint"
    if comm.rank == 0:
        with pytest.raises(Interrupted):
            _simulate(
                name, base / "from-1", alone, _control(alone, directory, StopAt, at=at), monkeypatch
            )
    comm.barrier()
    ck = latest(directory)
    assert ck.ranks() == 1
    results, p, _ = _simulate(
        name, base / "from-1", comm, _control(comm, directory, resume=ck), monkeypatch
    )
    assert results["runout_m"] == pytest.approx(wide["runout_m"], rel=ROUND_OFF)
    if comm.rank == 0:
        print("1 -> wide, vs wide:", _differences(p, wide_p))
        print("1 -> wide, vs 1 rank:", _differences(p, serial_p))
        assert max(_differences(p, wide_p).values()) < ROUND_OFF
        rows = _energy_rows(base / "from-1")
        assert [int(r["step"]) for r in rows] == list(range(steps + 1))
        assert _frame_times(base / "from-1") == _frame_times(base / "ref-wide")
    comm.barrier()
