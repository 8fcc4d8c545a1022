"""Friction from natural starts: stress-free, at rest, gravity brought on, 3 s (issue 47).

The block of test_friction (1 m × 0.5 m, 20 × 10 particles on 0.1 m cells, E = 1e7,
ν = 0.3, ρ = 1000) starts stress-free and at rest; gravity rises linearly over its first
0.1 s (``[gravity] ramp``: three periods of the block's lowest vibration), and the runs
last 3 s, long enough for a creep or an energy drift to show. The references are the
rigid block's closed forms with the ramp (geofrac/analytic_sliding.py).

Released with its whole weight at once instead, the undamped block rings for ever (its
base force swings between 0 and twice the weight) and creeps down a slope it should
hold in the low phases: that is the elastic block's answer, not the rigid one's
(docs/mpm_friction.md, "Natural starts").

Here: representative (shape, scheme) pairs covering every shape and scheme; all nine
pairs run in ``geofrac validate`` (cases ``incline_stick_*``, ``incline_slip_*``).
"""

import dataclasses
import itertools

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.analytic_sliding import incline_acceleration, ramped_motion, stop_distance
from geofrac.mpm.boundaries import scene_grid
from geofrac.mpm.driver import ramp_factor
from geofrac.mpm.energy import StepBudget
from geofrac.mpm.parallel import decompose
from geofrac.mpm.schemes import StepSettings, step
from tests.mpm.test_friction import CELL, COVER, G0, MAT, _bed_block, _block, _settings

RAMP, T_END = 0.1, 3.0
#: Settled and stays: within 5 mm of its start all along (the issue's bound), and no
#: creep after the first second beyond 0.5 mm (measured: 0.17 mm settling, then < 1 µm).
SETTLE, CREEP = 0.005, 0.0005


def _ramped(s: StepSettings, k: int) -> StepSettings:
    """Step ``k``'s settings: gravity times the ramp's mean over the step (as the driver)."""
    factor = ramp_factor(RAMP, k * s.dt, (k + 1) * s.dt)
    return s if factor == 1.0 else dataclasses.replace(s, gravity=factor * s.gravity)


def _run(g, p, s, along, *, total=float):
    """Step to T_END: {t: (displacement, velocity) along ``along``}, numerical and gravity work.

    ``along``: the downhill unit vector, shape=(2,). ``total`` sums over the ranks.
    """
    m = total(float(p.mass.sum()))

    def mean(q):
        return np.array([total(float(p.mass @ q[:, a])) for a in range(2)]) / m

    x0 = mean(p.x)
    out, numerical, gravity = {}, 0.0, 0.0
    steps = round(T_END / s.dt)
    marks = {round(t / s.dt): t for t in (0.5, 1.0, 2.0, 3.0)}
    worst = 0.0
    for k in range(steps):
        b = StepBudget()
        step(g, p, MAT, settings=_ramped(s, k), budget=b)
        numerical += total(b.numerical())
        gravity -= total(b.potential)
        worst = max(worst, abs(float((mean(p.x) - x0) @ along)))
        if k + 1 in marks:
            out[marks[k + 1]] = (float((mean(p.x) - x0) @ along), float(mean(p.v) @ along))
    return out, numerical, gravity, worst


def _tilted(mu, scheme, shape, *, upper=(4.0, 1.5), v0=0.0, domain=None):
    """The block on the floor y = 0, gravity tilted by 30°; (grid, particles, settings)."""
    p, gravity = _block(30.0, prestress=False, v0=v0)
    g = scene_grid((0.0, 0.0), upper, CELL, padding=2)
    if domain is not None:
        p, g = domain.distribute(p), domain.local
    return g, p, _settings(g, gravity, mu, scheme, shape, domain=domain)


@pytest.mark.parametrize(("shape", "scheme"), COVER)
def test_a_stress_free_block_on_a_30_degree_plane_with_mu_07_settles_and_stays(shape, scheme):
    """μ 0.7 > tan 30°: it settles (elastically, 0.17 mm) and stays, for 3 s.

    Energy: the scheme creates (``numerical`` work, which no physical term explains) at
    most 1 % of gravity's work. Before issue 47 the strain at its floor nodes took a
    velocity the contact clipped one way and the block gained energy (a dropped one
    rose). The scheme's numerical work is a dissipation here: measured −2.6 % of the
    0.39 J gravity does in the settlement (the MPM transfer damps the settled block's
    ringing), so it is not within 1 % both ways.
    """
    g, p, s = _tilted(0.7, scheme, shape)
    at, numerical, gravity, worst = _run(g, p, s, np.array([1.0, 0.0]))
    assert worst <= SETTLE
    assert abs(at[3.0][0] - at[1.0][0]) <= CREEP
    assert gravity > 0 and numerical <= 0.01 * gravity  # created: within 1 %


@pytest.mark.parametrize(("shape", "scheme"), [("cpgimp", "musl"), ("mpm", "usf")])
def test_a_stress_free_block_on_a_30_degree_bed_with_mu_07_settles_and_stays(shape, scheme):
    """The same on a real inclined bed: gravity vertical, the bed a 30° polyline.

    (From its weight's stress and without the ramp the bed block creeps: the xfail of
    test_friction.)
    """
    p, g, fixed, fr, dt, down, _ = _bed_block(0.7)
    p.stress[:] = 0.0
    p.stress_zz[:] = 0.0
    s = StepSettings(scheme, shape, dt, np.array([0.0, -G0]), fixed, friction=fr)
    at, numerical, gravity, worst = _run(g, p, s, down)
    assert worst <= SETTLE
    assert abs(at[3.0][0] - at[1.0][0]) <= CREEP
    assert gravity > 0 and numerical <= 0.01 * gravity  # created: within 1 %


@pytest.mark.parametrize(("shape", "scheme"), COVER)
def test_a_stress_free_block_with_mu_03_slides_at_coulombs_rate(shape, scheme):
    """μ 0.3: after the ramp it accelerates at g (sin 30° − 0.3 cos 30°) = 2.40, for 3 s.

    The velocity at 3 s is a (t − 0.05) and the displacement a (t²/2 − 0.05 t + 0.1²/6)
    within 1 % (10.6 m down a 14 m floor); the scheme's numerical work within 1 % of
    gravity's.
    """
    g, p, s = _tilted(0.3, scheme, shape, upper=(14.0, 1.5))
    at, numerical, gravity, _ = _run(g, p, s, np.array([1.0, 0.0]))
    x, v = ramped_motion(incline_acceleration(30.0, 0.3, g=G0), T_END, ramp=RAMP)
    assert at[3.0] == pytest.approx((x, v), rel=0.01)
    assert abs(numerical) <= 0.01 * gravity


@pytest.mark.xfail(
    strict=True,
    reason="the launched block rocks and hops (its back edge lifts, peak normal speed "
    "0.2-0.5 m/s): it slides 0.55-1.0 m in 1.2 s instead of stopping after 0.52 m "
    "(docs/mpm_friction.md, 'A block launched down a slope it should stick to')",
)
def test_a_stress_free_block_launched_down_a_sticking_slope_stops_at_the_rigid_distance():
    """Launched at 1 m/s down 30° with μ 0.7: stops after v₀²/(2 g (μ cos θ − sin θ)).

    With the ramp, 0.520 m (0.471 m without); within 5 %.
    """
    g, p, s = _tilted(0.7, "musl", "cpgimp", upper=(5.0, 1.5), v0=1.0)
    at, _, _, _ = _run(g, p, s, np.array([1.0, 0.0]))
    stop = stop_distance(1.0, incline_acceleration(30.0, 0.7, g=G0), ramp=RAMP)
    assert at[3.0][0] == pytest.approx(stop, rel=0.05)


@pytest.mark.mpi(min_size=2)
def test_a_stress_free_block_settles_on_a_30_degree_plane_on_two_ranks():
    """The settling block decomposed over the ranks (its floor nodes on both): as on one."""
    comm = MPI.COMM_WORLD
    dom = decompose(scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2), comm)
    g, p, s = _tilted(0.7, "usf", "cpgimp", domain=dom)
    at, numerical, gravity, worst = _run(g, p, s, np.array([1.0, 0.0]), total=dom.allsum)
    assert worst <= SETTLE
    assert abs(at[3.0][0] - at[1.0][0]) <= CREEP
    assert gravity > 0 and numerical <= 0.01 * gravity  # created: within 1 %
    g1, p1, s1 = _tilted(0.7, "usf", "cpgimp")
    serial, *_ = _run(g1, p1, s1, np.array([1.0, 0.0]))
    assert at[3.0][0] == pytest.approx(serial[3.0][0], rel=1e-6)


@pytest.mark.parametrize(("shape", "scheme"), [("ugimp", "usavg"), ("mpm", "usf")])
def test_a_block_thrown_in_a_closed_frictional_box_loses_energy(shape, scheme):
    """Thrown at (3, 2) m/s in a 1.5 m box with μ 0.3 on every wall, 3 s, from no stress.

    The walls only stop approaches and slow sliding: K + U + Π never rises above its
    start, and its largest value over each 0.5 s falls from one half-second to the next
    (measured: 1, 0.84, 0.79, 0.75, 0.70, 0.65, 0.53 of the start, uGIMP/USAVG). Step by
    step it is not monotonic: it rises in 42-45 % of the steps, by up to 1.2e-3 of the
    start (the explicit step's oscillating error; U is not its conserved energy), and the
    block still moves after 3 s (kinetic 220-310 J of 2750 J): docs/mpm.md.
    """
    from geofrac.mpm.particles import lattice
    from tests.mpm.test_friction import ALL_SIDES, BOX, RHO, _run_walled

    p = lattice([0.5, 0.2], [10, 10], CELL / 2, density=RHO)
    p.v[:] = [3.0, 2.0]
    sides, gravity = tuple(ALL_SIDES), np.array([0.0, -G0])
    _, energies = _run_walled(p, ALL_SIDES, sides, gravity, scheme, shape, T_END, BOX, mu=0.3)
    assert energies.max() <= energies[0]
    per = len(energies) // 6
    windows = [energies[i : i + per].max() for i in range(0, 6 * per, per)]
    assert all(b < a for a, b in itertools.pairwise(windows))
