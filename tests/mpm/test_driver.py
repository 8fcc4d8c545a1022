"""MPM scenes run end to end (geofrac.mpm.driver): small versions of the jobs/ scenes."""

import csv
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.mpm.bar import impact_bar, self_weight_stress
from geofrac.mpm.driver import run_mpm_scene, simulate
from geofrac.scene import load_scene
from tests.conftest import JOBS, run_and_list_modules


def _last_frame(out):
    with h5py.File(out / "particles.h5") as f:
        last = max(int(k.split("_")[1]) for k in f if k.startswith("frame_"))
        frame = f[f"frame_{last}"]
        return {k: frame[k][()] for k in frame}


def test_the_quasi_static_bar_scene_matches_eq_4_73(tmp_path):
    """W = 1000: RMS stress error within 2 % of ρ₀|b|L₀ (the issue's acceptance)."""
    scene = load_scene(JOBS / "mpm_bar_w1000.toml", out=tmp_path)
    summary = run_mpm_scene(scene, MPI.COMM_SELF, verbose=False)
    assert summary["status"] == "ok"
    frame = _last_frame(tmp_path)
    x, stress = frame["geometry"][:, 0], frame["stress"][:, 0]
    exact = self_weight_stress(x, 1e6, 1.0, 20.0, 50.0)
    assert np.sqrt(np.mean((stress - exact) ** 2)) / 1000.0 < 0.02
    # the top particle has moved down by about the bar's static shortening ρ b L0²/(2E)
    assert summary["results"]["runout_m"] == pytest.approx(-0.025, rel=0.1)


def test_the_translating_bar_scene_writes_consistent_energies(tmp_path):
    scene = load_scene(JOBS / "mpm_translating_bar.toml", ["mpm.t_end=15"], out=tmp_path)
    summary = run_mpm_scene(scene, MPI.COMM_SELF, verbose=False)
    results = summary["results"]
    with (tmp_path / "energies.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == results["steps"] + 1
    last = {k: float(v) for k, v in rows[-1].items()}
    assert last["t"] == pytest.approx(15.0)
    assert last["total"] == pytest.approx(last["kinetic"] + last["strain"] + last["gravity"])
    assert last["dissipated"] == pytest.approx(10.0 - last["total"])
    # the bar has hit the wall at x = 50 (t = 11.25) and turned back
    assert results["probes"]["front"][-1]["v"][0] < 0
    assert 0 <= results["energy_drift_max"] < 0.5
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "ok"


def test_a_particle_leaving_the_grid_stops_the_run_and_says_so(tmp_path):
    scene = load_scene(
        JOBS / "mpm_translating_bar.toml", ["mpm.t_end=20", "mpm.walls.x_max=free"], out=tmp_path
    )
    with pytest.raises(RunError, match="left the background grid"):
        run_mpm_scene(scene, MPI.COMM_SELF, verbose=False)
    summary = json.loads((tmp_path / "incomplete" / "summary.json").read_text())
    assert (
        summary["status"].startswith("error: ") and "left the background grid" in summary["status"]
    )
    assert not (tmp_path / "summary.json").exists()
    assert not (tmp_path / "particles.xdmf").exists()
    assert not (tmp_path / "energies.csv").exists()


def test_the_impact_bar_scene_reaches_eq_4_75_behind_the_wave(tmp_path):
    scene = load_scene(JOBS / "mpm_impact_bar.toml", out=tmp_path)
    run_mpm_scene(scene, MPI.COMM_SELF, verbose=False)
    frame = _last_frame(tmp_path)
    x0 = frame["geometry"][:, 0] - frame["displacement"][:, 0]
    behind = x0 < 0.7 * 50.0
    ratio = frame["stress"][behind, 0] / -20000.0
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.03)  # docs/mpm.md: 1.018-1.020
    # the scene is the library's benchmark set-up (geofrac.mpm.bar.impact_bar), step for step
    error = np.sqrt(np.mean((ratio - 1) ** 2))
    assert error == pytest.approx(impact_bar("mpm", "musl").error, rel=1e-9)


COARSE_SLIDE = [
    "geometry.parameters.h=1.5",
    "mpm.grid.spacing=2.0",
    "mpm.t_end=4.0",
    "mpm.frames=2",
]


def test_a_coarse_landslide_runs_and_a_stronger_soil_moves_less(tmp_path):
    runout = {}
    for angle in (5.0, 40.0):
        out = tmp_path / f"phi{angle:g}"
        scene = load_scene(
            JOBS / "landslide_kita_uebaru.toml",
            [*COARSE_SLIDE, f"plasticity.friction_angle={angle}"],
            out=out,
        )
        results = run_mpm_scene(scene, MPI.COMM_SELF, verbose=False)["results"]
        assert results["friction_angle_deg"] == angle
        frame = _last_frame(out)
        assert np.all(np.isfinite(frame["stress"]))
        assert np.max(frame["plastic_strain"]) > 0  # the soil yields somewhere
        runout[angle] = results["runout_m"]
    assert runout[5.0] > 0.5  # the weak soil moves out over the toe
    assert runout[40.0] < 0.5 * runout[5.0]  # a strong one much less


@pytest.mark.mpi(min_size=2)
def test_a_decomposed_landslide_equals_the_serial_one(tmp_path_factory):
    """The same scene on 1 rank (each rank alone) and on all ranks: same particles."""
    comm = MPI.COMM_WORLD
    base = comm.bcast(str(tmp_path_factory.mktemp("ls")) if comm.rank == 0 else None)
    overrides = [*COARSE_SLIDE, "mpm.t_end=1.0", "plasticity.friction_angle=10"]
    serial_out = tmp_path_factory.mktemp(f"serial{comm.rank}")
    serial = run_mpm_scene(
        load_scene(JOBS / "landslide_kita_uebaru.toml", overrides, out=serial_out),
        MPI.COMM_SELF,
        verbose=False,
    )["results"]
    scene = load_scene(JOBS / "landslide_kita_uebaru.toml", overrides, out=f"{base}/par")
    parallel = run_mpm_scene(scene, comm, verbose=False)["results"]
    assert parallel["particles"] == serial["particles"]
    assert parallel["runout_m"] == pytest.approx(serial["runout_m"], rel=1e-9, abs=1e-9)
    for name, history in serial["probes"].items():
        np.testing.assert_allclose(
            parallel["probes"][name][-1]["x"], history[-1]["x"], rtol=1e-9, atol=1e-9
        )
    if comm.rank == 0:
        a, b = _last_frame(serial_out), _last_frame(Path(f"{base}/par"))
        np.testing.assert_allclose(b["geometry"], a["geometry"], rtol=1e-9, atol=1e-8)
        np.testing.assert_allclose(b["stress"], a["stress"], rtol=1e-7, atol=1e-3)


def _modules(tmp_path, *overrides):
    scene = JOBS / "mpm_translating_bar.toml"
    return run_and_list_modules(tmp_path, scene, "mpm.t_end=0.5", *overrides)


def test_an_mpm_run_imports_no_undeclared_effect_and_no_dolfinx(tmp_path):
    modules = _modules(tmp_path)
    assert "geofrac.mpm.driver" in modules  # the run happened in this process
    for name in ("geofrac.mpm.smoothing", "geofrac.mpm.plasticity", "geofrac.mpm.friction"):
        assert name not in modules, name
    assert not [m for m in modules if m.startswith("geofrac.effects.")]
    assert "dolfinx" not in modules and "petsc4py" not in modules


def test_a_declared_smoothing_is_imported(tmp_path):
    modules = _modules(tmp_path, 'effects=["mls_smoothing"]')
    assert "geofrac.mpm.smoothing" in modules
    assert "geofrac.effects.mls_smoothing" in modules


@pytest.mark.mpi(min_size=2)
def test_mls_smoothing_with_a_rank_that_holds_no_particle(tmp_path_factory):
    """MLS smoothing on a rank that holds no particle, then the whole bar.

    The bar starts in rank 0's slab and crosses into rank 1's: the empty rank takes part
    in the ghost exchange and smooths nothing (it crashed in a reshape of zero rows); the
    decomposed run equals the serial one.
    """
    comm = MPI.COMM_WORLD
    overrides = ['effects=["mls_smoothing"]', "mpm.t_end=30", "mpm.particles.lower=[2.5]"]
    base = comm.bcast(str(tmp_path_factory.mktemp("mls")) if comm.rank == 0 else None)
    bar = JOBS / "mpm_translating_bar.toml"
    serial = simulate(load_scene(bar, overrides), MPI.COMM_SELF, verbose=False)
    parallel = simulate(load_scene(bar, overrides, out=f"{base}/par"), comm, verbose=False)
    assert parallel["runout_m"] > 20.0  # the bar crossed the slab boundary at x = 25
    assert parallel["runout_m"] == pytest.approx(serial["runout_m"], rel=1e-10)
    front = parallel["probes"]["front"][-1]["x"]
    np.testing.assert_allclose(front, serial["probes"]["front"][-1]["x"], rtol=1e-10)
