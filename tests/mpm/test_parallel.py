"""Domain decomposition of the MPM (geofrac.mpm.parallel): decomposed runs equal serial ones.

The MPI tests run under ``mpiexec -n 2 python -m mpi4py -m pytest --only-mpi``: every rank
runs the serial scene itself and the decomposed one over COMM_WORLD, and rank 0 compares
the gathered particles. Without MLS smoothing the nodal sums are exact
(geofrac.mpm.fixedpoint), so the decomposed run equals the serial one to the last bit,
also over long runs (the full-length runs: ``bench mpm --cases ranks``).
"""

import copy
from types import SimpleNamespace

import numpy as np
import pytest

from geofrac.errors import RunError
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.friction import friction
from geofrac.mpm.grid import grid
from geofrac.mpm.invariance import compare_ranks
from geofrac.mpm.parallel import decompose
from geofrac.mpm.particles import lattice
from geofrac.mpm.plasticity import DruckerPrager
from geofrac.mpm.schemes import (
    SCHEMES,
    ParticlesLeftGrid,
    StepSettings,
    step,
    time_step,
)
from geofrac.mpm.shapes import REGISTRY


def _settings(g, scheme, shape, smoothing, dt, backend="numba", domain=None, kind="standard"):
    """Gravity, the ground below y = 0.5 held, a wall at x < 0.5, friction on the floor."""
    X = g.nodes()
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[(X[:, 1] < 0.5 - 1e-9) | (X[:, 0] < 0.5 - 1e-9)] = True
    floor = np.flatnonzero(np.isclose(X[:, 1], 0.5))
    fr = friction(floor, np.tile([0.0, -1.0], (len(floor), 1)), 0.3)
    gravity = np.array([0.0, -9.81])
    return StepSettings(
        scheme, shape, dt, gravity, fixed, smoothing, fr, backend, domain, smoothing_kind=kind
    )


def _scene(material):
    """A 2 m × 1 m block sliding at 2 m/s on a floor, across the middle of a 24-cell grid."""
    g = grid([0.0, 0.0], 0.25, [24, 12])
    p = lattice([1.5, 0.5], [16, 8], 0.125, density=1000.0)
    p.v[:, 0] = 2.0
    p.v[:, 1] = 0.3 * np.sin(3.0 * p.x[:, 0])  # some shear, so stresses vary
    dt = time_step(0.2, g.spacing, material, density=1000.0, dim=2)
    return g, p, dt


#: Steps of the sliding block in pytest.
SLIDING_STEPS = 1000

CASES = [
    ("musl", "mpm", None, "elastic"),
    ("usf", "cpgimp", None, "elastic"),
    ("musl", "cpgimp", 2.0, "elastic"),
    ("usf", "mpm", 2.0, "elastic"),
    ("usavg", "ugimp", None, "elastic"),
    ("musl", "cpgimp", None, "drucker-prager"),
]


def _material(name):
    if name == "elastic":
        return Elastic(1e5, 0.3)
    return DruckerPrager(1e5, 0.3, friction_angle=20.0, cohesion=5000.0)


def _run(comm, scheme, shape, smoothing, material_name, steps, backend="numba", kind="standard"):
    """The scene serially (on this rank) and decomposed over comm: (serial, gathered, totals)."""
    mat = _material(material_name)
    g, whole, dt = _scene(mat)
    serial = copy.deepcopy(whole)
    s = _settings(g, scheme, shape, smoothing, dt, backend, kind=kind)
    dom = decompose(g, comm)
    mine = dom.distribute(whole)
    sd = _settings(dom.local, scheme, shape, smoothing, dt, backend, dom, kind)
    crossed = set()
    start_owner = dom.owner(whole.x)
    for _ in range(steps):
        step(g, serial, mat, settings=s)
        step(dom.local, mine, mat, settings=sd)
        crossed.update(mine.ids[start_owner[mine.ids] != comm.rank].tolist())
    totals = (dom.allsum(float(mine.mass.sum())), dom.allsum(mine.momentum()))
    crossed = dom.allsum(len(crossed))
    return serial, dom.gather(mine), totals, crossed


def _compare(serial, gathered, rtol=1e-10):
    np.testing.assert_array_equal(gathered.ids, serial.ids)
    for name in ("x", "v", "stress", "stress_zz", "volume", "F", "lp", "plastic"):
        a, b = getattr(serial, name), getattr(gathered, name)
        scale = max(float(np.abs(a).max()), 1e-300)
        np.testing.assert_allclose(b, a, rtol=rtol, atol=rtol * scale, err_msg=name)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize(("scheme", "shape", "smoothing", "material"), CASES)
def test_decomposed_run_equals_the_serial_one(scheme, shape, smoothing, material):
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    serial, gathered, (mass, momentum), crossed = _run(
        comm, scheme, shape, smoothing, material, steps=250
    )
    assert crossed > 10  # particles changed ranks
    assert mass == pytest.approx(serial.mass.sum(), rel=1e-14)
    np.testing.assert_allclose(momentum, serial.momentum(), rtol=1e-10, atol=1e-10)
    if comm.rank == 0:
        assert serial.x[:, 0].max() > 4.0  # the block slid across the slab boundary
        if material == "drucker-prager":
            assert serial.plastic.max() > 0
        _compare(serial, gathered)
    else:
        assert gathered is None


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("material", ["elastic", "drucker-prager"])
@pytest.mark.parametrize("shape", REGISTRY)
@pytest.mark.parametrize("scheme", SCHEMES)
def test_decomposed_run_without_smoothing_is_bitwise_the_serial_one(scheme, shape, material):
    """Exact nodal sums: 300 steps of the sliding block across the slabs, no bit differs.

    The front passes x = 4 (from 3.5). The quadratic B-spline's lowest particle row
    (1.25 cells above the held ground nodes, inside its 1.5-cell support) is braked by
    them, so its elastic block's front reaches 3.97-3.98 only: 3.9 for it.
    """
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    serial, gathered, _, crossed = _run(comm, scheme, shape, None, material, steps=300)
    assert crossed > 10
    if comm.rank == 0:
        assert serial.x[:, 0].max() > (3.9 if shape == "bspline2" else 4.0)
        _compare(serial, gathered, rtol=0.0)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize(
    ("scheme", "shape", "material"),
    [("musl", "cpgimp", "elastic"), ("usavg", "mpm", "drucker-prager")],
)
def test_consistent_smoothing_on_two_ranks_is_bitwise_the_serial_one(scheme, shape, material):
    """The consistent kind's rows with ghosts and its adjoint's terms sent to their owners.

    Every sum runs in global-id order, so 150 steps of the block sliding across the
    slabs give the serial particles to the last bit.
    """
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    serial, gathered, _, crossed = _run(
        comm, scheme, shape, 2.0, material, steps=150, kind="consistent"
    )
    assert crossed > 0
    if comm.rank == 0:
        _compare(serial, gathered, rtol=0.0)


@pytest.mark.mpi(min_size=2)
def test_translating_bar_stays_rank_invariant():
    """The translating bar (Edo 2016, sec. 4.5.3) on 1 and 2 ranks to t = 15: bitwise.

    The bar starts across the slab boundary at x = 25 and crosses it on every pass
    between the walls; with sums in particle order the runs part at t = 11.2 (1e-12 at
    t = 20, sign-flipped velocities by t ≈ 90). The full t = 100: ``bench mpm --cases
    ranks``.
    """
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    d = compare_ranks(comm, "translating", "mpm", scheme="musl", steps=6800, samples=30)
    if comm.rank == 0:
        assert d.t[-1] > 15.0 and d.crossed >= 10  # one half crossed to the other rank
        assert d.worst == 0.0, f"1 and 2 ranks part at t = {d.first_above(0.0)}"


@pytest.mark.mpi(min_size=2)
def test_sliding_block_stays_rank_invariant():
    """A block sliding on a frictional floor into a wall, under gravity: bitwise.

    SLIDING_STEPS steps here; 1e5 in ``bench mpm --cases ranks``.
    """
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    d = compare_ranks(comm, "sliding", "cpgimp", scheme="musl", steps=SLIDING_STEPS, samples=30)
    if comm.rank == 0:
        assert d.crossed > 10
        assert d.worst == 0.0, f"1 and 2 ranks part at t = {d.first_above(0.0)}"


@pytest.mark.mpi(min_size=2)
def test_decomposed_numpy_reference_equals_the_serial_one():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    serial, gathered, _, _ = _run(comm, "musl", "cpgimp", 2.0, "elastic", 60, "numpy")
    if comm.rank == 0:
        _compare(serial, gathered)


@pytest.mark.mpi(min_size=2)
def test_particle_leaving_the_grid_raises_on_every_rank():
    """A particle flying off the right end (last rank's slab): every rank raises, no hang."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    mat = Elastic(1e5, 0.3)
    g, whole, dt = _scene(mat)
    whole.x[5] = [5.9, 2.0]  # alone, far from the block, near the right end
    whole.v[5] = [50.0, 0.0]
    dom = decompose(g, comm)
    mine = dom.distribute(whole)
    sd = _settings(dom.local, "musl", "mpm", None, dt, domain=dom)
    with pytest.raises(ParticlesLeftGrid) as info:
        for _ in range(100):
            step(dom.local, mine, mat, settings=sd)
    assert info.value.ids.tolist() == [5]
    flags = comm.allgather(True)
    assert all(flags)


@pytest.mark.mpi(min_size=2)
def test_unstable_step_raises_on_every_rank():
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    mat = Elastic(1e5, 0.3)
    g, whole, dt = _scene(mat)
    dom = decompose(g, comm)
    mine = dom.distribute(whole)
    sd = _settings(dom.local, "musl", "mpm", None, 40 * dt, domain=dom)  # Courant 8
    with pytest.raises(RunError):
        for _ in range(50):
            step(dom.local, mine, mat, settings=sd)
    assert all(comm.allgather(True))


def test_slabs_cover_the_grid_with_halos():
    """Cells split evenly by rank; sub-grids are the slab plus the halo, clipped."""
    g = grid([1.0, -2.0], 0.5, [10, 4])
    doms = [decompose(g, SimpleNamespace(rank=r, size=3), halo=2) for r in range(3)]
    np.testing.assert_array_equal(doms[0].cuts, [0, 3, 6, 10])
    assert [d.local.cells for d in doms] == [(5, 4), (7, 4), (6, 4)]
    np.testing.assert_allclose([d.local.origin[0] for d in doms], [1.0, 1.5, 3.0])
    np.testing.assert_allclose(doms[2].local.upper, g.upper)
    # owners by cell along axis 0; the upper boundary belongs to the last slab
    x = np.array([[1.0, 0.0], [2.49, 0.0], [2.5, 0.0], [6.0, 0.0]])
    np.testing.assert_array_equal(doms[1].owner(x), [0, 0, 1, 2])
    with pytest.raises(ValueError, match="cannot feed"):
        decompose(grid([0.0], 1.0, [2]), SimpleNamespace(rank=0, size=3))


def test_one_rank_domain_equals_the_plain_step():
    from mpi4py import MPI

    comm = MPI.COMM_SELF
    serial, gathered, _, _ = _run(comm, "musl", "cpgimp", 2.0, "elastic", 20)
    _compare(serial, gathered, rtol=0.0)  # one rank: the same sums in the same order


@pytest.mark.mpi(min_size=2)
def test_throughput_block_runs_decomposed():
    """``bench mpm --cases block`` under mpiexec: all ranks step their own slabs."""
    from mpi4py import MPI

    from geofrac.mpm.block import gravity_block

    comm = MPI.COMM_WORLD
    tp = gravity_block(1600, "musl", "cpgimp", smoothing=2.0, steps=3, comm=comm)
    assert tp.ranks == comm.size and len(tp.per_rank) == comm.size
    assert tp.particles == 1600
    assert all(r > 0 for r in tp.per_rank)
    assert sum(tp.per_rank) == pytest.approx(tp.particle_steps_per_s, rel=1e-9)
