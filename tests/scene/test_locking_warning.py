"""Locking warnings: every element with a measured ``locking_nu`` warns from it on.

The thresholds come from the table in docs/stability.md ("Locking", ``docs/locking.py``);
tests/elements/test_registry.py re-measures them. Here: the warning fires at the
threshold and not below it, in plane strain (Cook's membrane) and in 3D, never in plane
stress, names as the remedy the elements that do not lock, and a run on 2 ranks prints it
exactly once.
"""

import dolfinx_solver  # noqa: F401

import pytest
from mpi4py import MPI

from geofrac import elements
from geofrac.scene import load_scene
from tests.conftest import JOBS

#: dimension -> (job, overrides keeping it small and constrained)
JOBS_BY_DIM = {
    2: ("cook_membrane", ("geometry.parameters.n=2", "material.plane=strain")),
    3: ("mms3d", ("geometry.parameters.n=1",)),
}
LOCKING = [
    (n, d) for n in elements.available() for d in elements.get(n).dims if elements.get(n).locking_nu
]


def _warnings(name: str, dim: int, nu: float, *extra: str) -> tuple[str, ...]:
    job, overrides = JOBS_BY_DIM[dim]
    scene = load_scene(
        JOBS / f"{job}.toml",
        [*overrides, f"discretization.element={name}", f"material.nu={nu}", *extra],
    )
    return tuple(w for w in scene.warnings if "locks volumetrically" in w)


@pytest.mark.parametrize(("name", "dim"), LOCKING)
def test_warned_from_the_threshold_on_and_not_below(name, dim):
    nu = elements.get(name).locking_nu
    assert len(_warnings(name, dim, nu)) == 1
    assert len(_warnings(name, dim, 0.5 - 0.5 * (0.5 - nu))) == 1
    assert not _warnings(name, dim, nu - 1e-6)


@pytest.mark.parametrize(("name", "dim"), LOCKING)
def test_the_message_names_the_element_and_the_remedy(name, dim):
    (message,) = _warnings(name, dim, 0.49999)
    assert f"element '{name}'" in message
    assert message.endswith("use element 'p2' or 'p3'")
    assert ("3D" if dim == 3 else "plane strain") in message


@pytest.mark.parametrize("name", [n for n, d in LOCKING if d == 2])
def test_plane_stress_is_never_warned(name):
    assert not _warnings(name, 2, 0.49999, "material.plane=stress")


@pytest.mark.parametrize("name", ["p2", "p3"])
def test_an_element_that_does_not_lock_is_never_warned(name):
    assert not _warnings(name, 2, 0.49999)
    assert not _warnings(name, 3, 0.49999)


@pytest.mark.mpi(min_size=2)
def test_a_run_on_n_ranks_prints_the_warning_once(cli, mpi_tmp_path):
    code, out, err = cli(
        "run",
        JOBS / "cook_membrane.toml",
        "--out",
        mpi_tmp_path,
        "--set",
        "geometry.parameters.n=2",
        "--set",
        "discretization.element=cst",
    )
    assert code == 0, err
    count = MPI.COMM_WORLD.allreduce((out + err).count("locks volumetrically"), op=MPI.SUM)
    assert count == 1
