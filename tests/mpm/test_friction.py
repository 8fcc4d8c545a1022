"""Contact and Coulomb friction on boundary nodes (Edo (2016), eqs. 4.44-4.47) vs closed forms.

A rigid block on a plane inclined at θ with Coulomb coefficient μ sticks when μ > tan θ
and otherwise accelerates at g (sin θ − μ cos θ); launched at v₀ on a level floor it
stops after v₀² / (2 μ g). The blocks start from the stress of their own weight, so the
elastic settling is small (τ/G over the block's height: about 2 mm here) and the
closed forms hold without a tuned tolerance.

The blocks are stiff enough (E = 1e7, ρ = 1000) that their elastic ringing, of velocity
τ/(ρ c_s) ≈ 0.04 m/s for a base shear τ = μ ρ g H, is small against the motion; with
E = 1e6 it is 0.13 m/s and a launched block chatters (its stop distance is then 7 % long
on the level floor, which is the elastic block's answer, not the rigid one's).
"""

from pathlib import Path

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.mpm.boundaries import boundary_rows, scene_grid
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.friction import FREE, SLIP, STICK, apply_friction, contact_states, friction
from geofrac.mpm.parallel import decompose
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, strain_energy, time_step
from geofrac.scene import load_scene
from tests.conftest import JOBS

G0, RHO, CELL = 10.0, 1000.0, 0.1
MAT = Elastic(1e7, 0.3)


def test_contact_slip_stick_and_separation_on_single_nodes():
    fr = friction(np.arange(4), np.tile([0.0, -2.0], (4, 1)), mu=0.5)  # normal normalised
    v = np.array(
        [
            [1.0, 0.5],  # moving away from the floor: free
            [2.0, -1.0],  # into it, fast slip: tangential 2 - 0.5 * 1
            [0.3, -1.0],  # into it, slow: sticks (0.3 < 0.5 * 1)
            [-2.0, -0.2],  # slip to the left: -2 + 0.1
        ]
    )
    states = np.full(4, -1, dtype=np.int8)
    out = apply_friction(v.copy(), fr, states=states)
    np.testing.assert_allclose(out, [[1.0, 0.5], [1.5, 0.0], [0.0, 0.0], [-1.9, 0.0]])
    # the decisions it took: free, slip, stick, slip (as contact_states decides them)
    np.testing.assert_array_equal(states, [FREE, SLIP, STICK, SLIP])
    np.testing.assert_array_equal(states, contact_states(v, fr))
    # without friction only the approach is removed
    out = apply_friction(v.copy(), fr, sliding_only=True)
    np.testing.assert_allclose(out, [[1.0, 0.5], [2.0, 0.0], [0.3, 0.0], [-2.0, 0.0]])
    # a node whose material is a gap g from the boundary may approach by g in the step:
    # only the excess approach (1 - 0.4) is stopped, and only it brings friction
    out = apply_friction(v.copy(), fr, np.array([0.0, 0.4, 0.0, 0.0]))
    np.testing.assert_allclose(out[1], [2.0 - 0.5 * 0.6, -0.4])
    out = apply_friction(v.copy(), fr, np.array([0.0, 1.5, 0.0, 0.0]))  # far: free
    np.testing.assert_allclose(out[1], v[1])
    with pytest.raises(ValueError, match="mu"):
        friction([0], [[0.0, 1.0]], -0.1)


def test_a_corner_node_stops_both_approaches_and_sums_the_friction():
    """Floor (μ 0.5) and left wall (μ 0.25) at one node: 3D-free test in 2D."""
    fr = friction([7, 7], [[0.0, -1.0], [-1.0, 0.0]], [0.5, 0.25])
    v = np.zeros((8, 2))
    v[7] = [-1.0, -2.0]  # into both
    np.testing.assert_allclose(apply_friction(v.copy(), fr)[7], [0.0, 0.0])
    v[7] = [3.0, -2.0]  # into the floor, away from the wall: slides, slowed by 0.5 * 2
    np.testing.assert_allclose(apply_friction(v.copy(), fr)[7], [2.0, 0.0])


def test_a_roller_wall_keeps_the_frictional_floor_at_the_corner():
    g = scene_grid((0.0, 0.0), (1.0, 1.0), 0.25, padding=2)
    fixed, ids, normals, planes, which = boundary_rows(
        g,
        (0.0, 0.0),
        (1.0, 1.0),
        walls={"x_min": "roller", "y_min": "fixed"},
        bed=(),
        frictional=("y_min",),
    )
    X = g.nodes()
    corner = np.flatnonzero((X[:, 0] <= 0) & (X[:, 1] <= 0))
    assert np.all(fixed[corner, 0]) and not np.any(fixed[corner, 1])
    assert set(corner) <= set(ids.tolist())  # the floor still holds them
    rows = np.isin(ids, corner)
    np.testing.assert_allclose(normals[rows], np.tile([0.0, -1.0], (rows.sum(), 1)))
    np.testing.assert_allclose(planes, 0.0)  # the plane y = 0: x·n = 0
    assert np.all(which == 0)


def _block(theta_deg: float, prestress: bool, v0: float = 0.0):
    """A 1 m × 0.5 m block (20 × 10 particles, 0.1 m cells) on the floor y = 0 of a box.

    Gravity g = 10 tilted by θ (along +x downhill); with ``prestress`` the block starts
    from the stress of its own weight: σ_yy = −ρ g cos θ d, σ_xx = K₀ σ_yy,
    σ_xy = ρ g sin θ d at depth d, which balances the body force in the interior.
    """
    th = np.radians(theta_deg)
    p = lattice([1.0, 0.0], [20, 10], CELL / 2, density=RHO)
    p.v[:, 0] = v0
    if prestress:
        depth = 0.5 - p.x[:, 1]
        k0 = MAT.nu / (1 - MAT.nu)
        p.stress[:, 1, 1] = -RHO * G0 * np.cos(th) * depth
        p.stress[:, 0, 0] = k0 * p.stress[:, 1, 1]
        p.stress_zz[:] = k0 * p.stress[:, 1, 1]
        p.stress[:, 0, 1] = p.stress[:, 1, 0] = RHO * G0 * np.sin(th) * depth
    return p, np.array([G0 * np.sin(th), -G0 * np.cos(th)])


def _settings(g, gravity, mu, scheme, shape, walls=None, frictional=("y_min",), domain=None):
    walls = walls or {"y_min": "fixed"}
    lo, up = (0.0, 0.0), (4.0, 1.5)
    fixed, ids, nrm, planes, _ = boundary_rows(
        g, lo, up, walls=walls, bed=(), frictional=frictional
    )
    fr = friction(ids, nrm, mu, offsets=planes)
    dt = time_step(0.2, CELL, MAT, density=RHO, dim=2)
    return StepSettings(scheme, shape, dt, gravity, fixed, friction=fr, domain=domain)


def _run(p, gravity, mu, scheme, shape, t_end, **kw):
    """Step to t_end: (mean x displacement, mean x velocity, rise of the bottom layer)."""
    g = scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2)
    s = _settings(g, gravity, mu, scheme, shape, **kw)
    m = p.mass.sum()
    x0 = p.mass @ p.x[:, 0] / m
    bottom = p.x[:, 1] < CELL / 2
    y0 = p.x[bottom, 1].mean()
    for _ in range(round(t_end / s.dt)):
        step(g, p, MAT, settings=s)
    return (
        p.mass @ p.x[:, 0] / m - x0,
        p.mass @ p.v[:, 0] / m,
        p.x[bottom, 1].mean() - y0,
    )


# Representative (shape, scheme) pairs per check; every shape and every scheme is in each
# list (each combination was measured: docs/mpm_friction.md).
COVER = [("mpm", "usf"), ("ugimp", "usavg"), ("cpgimp", "musl")]


@pytest.mark.parametrize(("shape", "scheme"), [*COVER, ("cpgimp", "usf")])
def test_a_block_on_a_30_degree_slope_with_mu_07_sticks(shape, scheme):
    """μ = 0.7 > tan 30° = 0.577: the block stays (elastic settling ≈ 2 mm), at rest.

    Before the contact held the mapped velocity too, USF crept off (v = 0.03 at 0.3 s).
    """
    p, gravity = _block(30.0, prestress=True)
    moved, v, rise = _run(p, gravity, 0.7, scheme, shape, 0.3)
    assert abs(moved) < 0.005  # sliding from rest at the slip rate would be 0.11
    assert abs(v) < 0.01
    assert abs(rise) < 0.02 * CELL


@pytest.mark.parametrize(
    ("shape", "scheme"), [("mpm", "musl"), ("ugimp", "usf"), ("cpgimp", "usavg")]
)
def test_a_block_on_a_30_degree_slope_with_mu_03_slides_at_coulombs_rate(shape, scheme):
    """μ = 0.3 < tan 30°: v(t) = g (sin θ − μ cos θ) t = 2.40 t (μ = 0: 5 t)."""
    p, gravity = _block(30.0, prestress=True)
    t = 0.3
    _, v, _ = _run(p, gravity, 0.3, scheme, shape, t)
    a = G0 * (np.sin(np.radians(30.0)) - 0.3 * np.cos(np.radians(30.0)))
    assert v == pytest.approx(a * t, rel=0.02)


@pytest.mark.parametrize(
    ("shape", "scheme"), [("mpm", "musl"), ("ugimp", "usavg"), ("cpgimp", "usf")]
)
def test_a_block_launched_on_a_level_floor_stops_after_v0_squared_over_2_mu_g(shape, scheme):
    """v₀ = 1, μ = 0.5: it stops after 0.1 m (at t = 0.2 s) and stays.

    Its bottom layer stays down, within the block's elastic compression ρ g H² / (2 E):
    with the contact stopping every approach of material within 0.1 cell of the floor
    it ratcheted up 2-3 mm.
    """
    p, gravity = _block(0.0, prestress=True, v0=1.0)
    moved, v, rise = _run(p, gravity, 0.5, scheme, shape, 0.3)
    assert moved == pytest.approx(1.0 / (2 * 0.5 * G0), rel=0.03)
    assert abs(v) < 0.02
    assert abs(rise) < 2 * RHO * G0 * 0.5**2 / (2 * MAT.E)


@pytest.mark.parametrize(
    ("shape", "scheme"), [("cpgimp", "usf"), ("mpm", "usavg"), ("ugimp", "musl")]
)
def test_a_block_dropped_on_a_frictional_floor_does_not_creep_up(shape, scheme):
    """No prestress: the block rings under its weight, its bottom layer stays down.

    The whole block compresses by ρ g H² / (2 E) = 0.125 mm under its weight, which bounds
    any motion of its bottom layer. Before the contact held the mapped velocity, USF's
    bottom layer rose 0.6 mm in 0.3 s (3 mm in 0.6 s).
    """
    p, gravity = _block(0.0, prestress=False)
    _, _, rise = _run(p, gravity, 0.7, scheme, shape, 0.3)
    assert abs(rise) < 2 * RHO * G0 * 0.5**2 / (2 * MAT.E)


def _centroid_rise(scheme: str, shape: str, t_end: float) -> float:
    """Highest centroid above its start of a stress-free block dropped on a level floor."""
    p, gravity = _block(0.0, prestress=False)
    g = scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2)
    s = _settings(g, gravity, 0.7, scheme, shape)
    m = p.mass.sum()
    y0 = p.mass @ p.x[:, 1] / m
    rise = -np.inf
    for _ in range(round(t_end / s.dt)):
        step(g, p, MAT, settings=s)
        rise = max(rise, p.mass @ p.x[:, 1] / m - y0)
    return rise


@pytest.mark.parametrize(
    ("shape", "scheme"),
    [(sh, sc) for sh in ("mpm", "ugimp", "cpgimp") for sc in ("musl", "usf", "usavg")],
)
def test_a_block_dropped_on_a_frictional_floor_never_rises_above_its_start(shape, scheme):
    """A stress-free block released at rest never lifts its centroid above its start.

    Energy: from K = 0, W = 0, K + W + Π can only fall, so Π = −m g ȳ (relative to the
    start) stays ≤ 0. Judged on the elastic settlement ρ g H² / (2 M) = 0.093 mm (M the
    P-wave modulus): allowed 1 % of it. Measured: at most 0.00059 mm (MUSL), 0.00030 mm
    (USAVG), 0.00001 mm (USF). Before issue 47's fix (the strain at floor nodes took a velocity the
    contact clipped one way): 0.085-0.088 mm in 0.5 s for every pair, 0.17-0.18 mm in
    1 s (a fixed floor instead: never above its start).
    """
    modulus = MAT.E * (1 - MAT.nu) / ((1 + MAT.nu) * (1 - 2 * MAT.nu))
    settlement = RHO * G0 * 0.5**2 / (2 * modulus)
    assert _centroid_rise(scheme, shape, 0.5) <= 0.01 * settlement


def test_a_stress_free_block_on_a_sticking_slope_creates_no_energy():
    """A stress-free block on 30° with μ 0.7: the scheme adds under 1 % of gravity's work.

    Released at rest with its whole weight at once (MUSL, cpGIMP, 0.5 s), the budget's
    ``numerical`` work (the energy no physical term explains, docs/mpm_energy.md) stays
    within 1 % of the gravity work. The block slides (the suddenly loaded block rings,
    and its base slips when the ringing unloads it, docs/mpm_friction.md), paid by
    gravity. Measured: +0.55 J of 96 J (+0.58 %; before issue 47's fix +10.3 J of
    113 J, +9 %).
    """
    from geofrac.mpm.energy import StepBudget

    p, gravity = _block(30.0, prestress=False)
    g = scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2)
    s = _settings(g, gravity, 0.7, "musl", "cpgimp")
    numerical = gravity_work = 0.0
    for _ in range(round(0.5 / s.dt)):
        b = StepBudget()
        step(g, p, MAT, settings=s, budget=b)
        numerical += b.numerical()
        gravity_work -= b.potential
    assert gravity_work > 0
    assert numerical <= 0.01 * gravity_work


@pytest.mark.parametrize("shape", ["mpm"])
def test_a_block_launched_down_a_sticking_slope_stays_on_it(shape):
    """μ = 0.7 on 30°, launched at 1 m/s downhill: the bottom layer stays on the floor.

    Before the contact knew how far the material was from the floor it rose 0.08 m (most
    of a cell) and the block lost its grip. (The stop distance, 0.47 m, is not reached:
    the block hops, docs/mpm_friction.md.)
    """
    p, gravity = _block(30.0, prestress=True, v0=1.0)
    _, _, rise = _run(p, gravity, 0.7, "usf", shape, 1.0)
    assert abs(rise) < 0.5 * CELL


def _mean_displacement(out: Path) -> np.ndarray:
    from geofrac.io.points import last_frame

    return last_frame(out / "particles.h5")["displacement"].mean(axis=0)


def _incline_slide(t: float) -> float:
    """The job's closed form: μ = 0.3 on 30°, gravity ramped over 0.1 s (0.2442 at 0.5 s)."""
    from geofrac.analytic_sliding import incline_acceleration, ramped_motion

    return ramped_motion(incline_acceleration(30.0, 0.3, g=G0), t, ramp=0.1)[0]


def test_the_incline_scene_slides_at_coulombs_rate(tmp_path):
    """jobs/mpm_incline_block.toml, from rest and stress-free, μ = 0.3 on 30°.

    Gravity rises over 0.1 s, then the block accelerates at g (sin 30° − 0.3 cos 30°):
    its mean displacement at t = 0.5 is a (t²/2 − 0.1 t/2 + 0.1²/6) = 0.2442 (the front
    moves more: the block stretches).
    """
    from geofrac.pipeline import run_scene

    scene = load_scene(JOBS / "mpm_incline_block.toml", ["mpm.t_end=0.5"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_SELF, verbose=False)
    assert summary["status"] == "ok"
    assert _mean_displacement(tmp_path)[0] == pytest.approx(_incline_slide(0.5), rel=0.01)


@pytest.mark.mpi(min_size=2)
def test_the_incline_scene_slides_at_coulombs_rate_on_two_ranks(tmp_path_factory):
    from geofrac.pipeline import run_scene

    comm = MPI.COMM_WORLD
    base = comm.bcast(str(tmp_path_factory.mktemp("incline")) if comm.rank == 0 else None)
    scene = load_scene(JOBS / "mpm_incline_block.toml", ["mpm.t_end=0.5"], out=Path(base))
    run_scene(scene, comm, verbose=False)
    moved = _mean_displacement(Path(base))[0] if comm.rank == 0 else None
    moved = comm.bcast(moved)
    assert moved == pytest.approx(_incline_slide(0.5), rel=0.01)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("scheme", ["usf"])
def test_a_block_on_a_30_degree_slope_sticks_on_two_ranks(scheme):
    """The sticking block decomposed over the ranks (its nodes shared by both)."""
    comm = MPI.COMM_WORLD
    p, gravity = _block(30.0, prestress=True)
    g = scene_grid((0.0, 0.0), (4.0, 1.5), CELL, padding=2)
    dom = decompose(g, comm)
    mine = dom.distribute(p)
    s = _settings(dom.local, gravity, 0.7, scheme, "cpgimp", domain=dom)
    m = dom.allsum(float(mine.mass.sum()))
    x0 = dom.allsum(float(mine.mass @ mine.x[:, 0])) / m
    for _ in range(round(0.3 / s.dt)):
        step(dom.local, mine, MAT, settings=s)
    moved = dom.allsum(float(mine.mass @ mine.x[:, 0])) / m - x0
    v = dom.allsum(float(mine.mass @ mine.v[:, 0])) / m
    assert abs(moved) < 0.005 and abs(v) < 0.01


@pytest.mark.parametrize(
    ("override", "key", "text"),
    [
        ("friction.boundaries.y_min=-0.1", "friction.boundaries.y_min", ">= 0"),
        ("friction.boundaries.y_min=101", "friction.boundaries.y_min", "<= 100"),
        ("friction.boundaries={}", "friction.boundaries", "at least one"),
        ("friction.boundaries=['y_min']", "friction.mu", "missing"),
        ("friction.boundaries={ bed = 0.1 }", "friction.boundaries", "no boundary 'bed'"),
    ],
)
def test_mu_per_boundary_errors_name_the_key(override, key, text):
    from geofrac.model.errors import SceneError

    with pytest.raises(SceneError) as info:
        load_scene(JOBS / "mpm_incline_block.toml", [override])
    assert info.value.key == key
    assert text in info.value.message


def test_mu_per_boundary_and_the_common_mu_reach_the_rows():
    from geofrac.mpm.driver import prepare

    scene = load_scene(
        JOBS / "mpm_incline_block.toml",
        ["friction.mu=0.2", "friction.boundaries={ y_min = 0.3, x_max = 0.5 }"],
    )
    fr = prepare(scene, MPI.COMM_SELF).settings.friction
    X = prepare(scene, MPI.COMM_SELF).grid.nodes()[fr.nodes]
    floor = fr.normals[:, 1] < 0
    assert np.all(fr.mu[floor] == 0.3) and np.all(fr.mu[~floor] == 0.5)
    assert np.all(X[~floor, 0] >= 4.0)
    scene = load_scene(
        JOBS / "mpm_incline_block.toml", ["friction.mu=0.2", "friction.boundaries=['y_min']"]
    )
    assert np.all(prepare(scene, MPI.COMM_SELF).settings.friction.mu == 0.2)


# --- a real inclined bed: gravity vertical, the slope a polyline of the grid's nodes ---

BED_LO, BED_UP = (0.0, 0.0), (4.0, 3.0)
BED_TOP = 2.5  # the bed's height at x = 0; it falls at 30° towards +x


def _bed_block(mu: float, theta_deg: float = 30.0):
    """The 1 m × 0.5 m block of :func:`_block` turned onto a bed inclined at θ.

    Gravity is vertical (0, −g); the bed is the polyline y = 2.5 − x tan θ, its nodes on or
    below it frictional with the slope's normal (a staircase of grid nodes). The block
    (20 × 10 particles, their GIMP boxes axis-aligned) lies on it from x = 1, with the
    stress of its own weight turned with it. Returns (particles, settings, grid,
    downhill unit vector).
    """
    th = np.radians(theta_deg)
    down = np.array([np.cos(th), -np.sin(th)])  # along the slope, downhill
    up = np.array([np.sin(th), np.cos(th)])  # the bed's normal out of it
    p, _ = _block(theta_deg, prestress=True)  # slope frame: x along, y normal
    s_, h_ = p.x[:, 0] - 1.0, p.x[:, 1]
    origin = np.array([1.0, BED_TOP - np.tan(th)])
    p.x[:] = origin + s_[:, None] * down + h_[:, None] * up
    R = np.column_stack([down, up])  # slope frame -> global
    p.stress[:] = R @ p.stress @ R.T
    g = scene_grid(BED_LO, BED_UP, CELL, padding=2)
    bed = ((0.0, BED_TOP), (4.0, BED_TOP - 4.0 * np.tan(th)))
    fixed, ids, nrm, planes, _ = boundary_rows(
        g, BED_LO, BED_UP, walls={}, bed=bed, frictional=("bed",)
    )
    fr = friction(ids, nrm, mu, offsets=planes)
    dt = time_step(0.2, CELL, MAT, density=RHO, dim=2)
    return p, g, fixed, fr, dt, down, up


def _run_bed(mu, scheme, shape, t_end, dom=None):
    p, g, fixed, fr, dt, down, up = _bed_block(mu)
    if dom is not None:  # the rows on this rank's sub-grid
        p = dom.distribute(p)
        g = dom.local
        bed = ((0.0, BED_TOP), (4.0, BED_TOP - 4.0 * np.tan(np.radians(30.0))))
        fixed, ids, nrm, planes, _ = boundary_rows(
            g, BED_LO, BED_UP, walls={}, bed=bed, frictional=("bed",)
        )
        fr = friction(ids, nrm, mu, offsets=planes)
    s = StepSettings(scheme, shape, dt, np.array([0.0, -G0]), fixed, friction=fr, domain=dom)
    total = dom.allsum if dom is not None else float
    m = total(float(p.mass.sum()))
    x0 = np.array([total(float(p.mass @ p.x[:, a])) for a in range(2)]) / m
    for _ in range(round(t_end / dt)):
        step(g, p, MAT, settings=s)
    x1 = np.array([total(float(p.mass @ p.x[:, a])) for a in range(2)]) / m
    v1 = np.array([total(float(p.mass @ p.v[:, a])) for a in range(2)]) / m
    return (x1 - x0) @ down, v1 @ down, (x1 - x0) @ up


@pytest.mark.xfail(
    strict=True,
    reason="the free nodes just above the bed's staircase let the base slip (0.014-0.022 m "
    "in 0.3 s); rows for them hold it but thicken a landslide's sliding layer "
    "(docs/mpm_friction.md)",
)
@pytest.mark.parametrize(("shape", "scheme"), [("cpgimp", "musl")])
def test_a_block_on_a_30_degree_bed_with_mu_07_sticks(shape, scheme):
    """μ = 0.7 > tan 30° on a bed polyline (gravity vertical): the block stays."""
    moved, v, lift = _run_bed(0.7, scheme, shape, 0.3)
    assert abs(moved) < 0.005  # sliding at the μ = 0.3 rate would be 0.11 in 0.3 s
    assert abs(v) < 0.01
    assert abs(lift) < 0.005


@pytest.mark.parametrize(
    ("shape", "scheme"), [("mpm", "musl"), ("ugimp", "usf"), ("cpgimp", "usavg")]
)
def test_a_block_on_a_30_degree_bed_with_mu_03_slides_at_coulombs_rate(shape, scheme):
    """μ = 0.3 on the bed polyline: v(t) = g (sin θ − μ cos θ) t = 2.40 t along the slope."""
    t = 0.3
    moved, v, lift = _run_bed(0.3, scheme, shape, t)
    a = G0 * (np.sin(np.radians(30.0)) - 0.3 * np.cos(np.radians(30.0)))
    assert v == pytest.approx(a * t, rel=0.02)
    assert moved == pytest.approx(a * t**2 / 2, rel=0.03)
    assert abs(lift) < 0.005  # on the bed, neither sunk into it nor lifted off


@pytest.mark.mpi(min_size=2)
def test_a_block_on_a_30_degree_bed_slides_at_coulombs_rate_on_two_ranks():
    """The bed block (μ = 0.3) decomposed over the ranks, its base on both."""
    dom = decompose(scene_grid(BED_LO, BED_UP, CELL, padding=2), MPI.COMM_WORLD)
    t = 0.3
    moved, v, lift = _run_bed(0.3, "usf", "cpgimp", t, dom)
    assert moved == pytest.approx(
        0.5 * G0 * (0.5 - 0.3 * np.cos(np.radians(30.0))) * t**2, rel=0.03
    )
    a = G0 * (np.sin(np.radians(30.0)) - 0.3 * np.cos(np.radians(30.0)))
    assert v == pytest.approx(a * t, rel=0.02)
    assert abs(lift) < 0.005


# --- walls: a closed box, and a roller wall meeting a frictional floor ---


def _run_walled(p, walls, frictional, gravity, scheme, shape, t_end, up, dom=None, mu=0.5):
    """Step a block in the box [0, up] with ``walls``; returns (particles, energies).

    Energies per step (kinetic + gravity potential + strain), summed over the ranks;
    ``mu`` on every frictional wall.
    """
    lo = (0.0, 0.0)
    g = scene_grid(lo, up, CELL, padding=2)
    if dom is not None:
        p, g = dom.distribute(p), dom.local
    fixed, ids, nrm, planes, _ = boundary_rows(
        g, lo, up, walls=walls, bed=(), frictional=frictional
    )
    fr = friction(ids, nrm, mu, offsets=planes)
    dt = time_step(0.2, CELL, MAT, density=RHO, dim=2)
    s = StepSettings(scheme, shape, dt, gravity, fixed, friction=fr, domain=dom)
    total = dom.allsum if dom is not None else float

    def energy():
        kinetic = 0.5 * float(p.mass @ np.sum(p.v**2, axis=1))
        return total(kinetic - float(p.mass @ (p.x @ gravity)) + strain_energy(p, MAT))

    energies = [energy()]
    for _ in range(round(t_end / dt)):
        step(g, p, MAT, settings=s)
        energies.append(energy())
    return p, np.array(energies)


def _gathered(p, dom):
    """All particles' positions and half-widths, on every rank: shape=(n, 2) twice."""
    if dom is None:
        return p.x, p.lp
    x, lp = dom.allgather_rows(p.x, p.lp)
    return x, lp


BOX = (1.5, 1.5)
ALL_SIDES = {"x_min": "fixed", "x_max": "fixed", "y_min": "fixed", "y_max": "fixed"}


def _thrown(shape, scheme, dom=None):
    """A 0.5 m block thrown at (3, 2) m/s inside a 1.5 m box, μ = 0.5 on every wall."""
    p = lattice([0.5, 0.2], [10, 10], CELL / 2, density=RHO)
    p.v[:] = [3.0, 2.0]
    return _run_walled(
        p, ALL_SIDES, tuple(ALL_SIDES), np.array([0.0, -G0]), scheme, shape, 0.8, BOX, dom
    )


@pytest.mark.parametrize(("shape", "scheme"), COVER)
def test_nothing_leaves_a_closed_frictional_box(shape, scheme):
    """Thrown around a box with friction on all four walls (several impacts in 0.8 s).

    Nothing leaves the grid (no ParticlesLeftGrid), every particle stays inside the box,
    and the walls never add energy: they only stop approaches and slow sliding, so
    kinetic + potential + strain energy never rises above its start (cell-crossing
    noise allowed 1 %). Before the contact knew where the material was, the walls
    stopped every approach of material within 0.1 cell, so particles hung off the
    ceiling and walls.
    """
    p, energies = _thrown(shape, scheme)
    x, _ = _gathered(p, None)
    assert np.all((x > 0) & (x < BOX))
    assert energies.max() <= energies[0] * 1.01


@pytest.mark.mpi(min_size=2)
def test_nothing_leaves_a_closed_frictional_box_on_two_ranks():
    dom = decompose(scene_grid((0.0, 0.0), BOX, CELL, padding=2), MPI.COMM_WORLD)
    p, energies = _thrown("ugimp", "usf", dom)
    x, _ = _gathered(p, dom)
    assert len(x) == 100 and np.all((x > 0) & (x < BOX))
    assert energies.max() <= energies[0] * 1.01


def _cornered(shape, scheme, dom=None):
    """A block in the corner of a roller wall (x = 0) and a frictional floor (μ = 0.5).

    Gravity pushes it into both (g = 10 at 30° from the vertical, towards the wall).
    """
    p, _ = _block(0.0, prestress=False)
    p.x[:, 0] -= 1.0  # against the wall: x in [0, 1]
    th = np.radians(30.0)
    gravity = np.array([-G0 * np.sin(th), -G0 * np.cos(th)])
    walls = {"x_min": "roller", "y_min": "fixed"}
    return _run_walled(p, walls, ("y_min",), gravity, scheme, shape, 0.3, (2.0, 1.5), dom)


@pytest.mark.parametrize(("shape", "scheme"), COVER)
def test_a_block_pressed_into_a_roller_wall_and_frictional_floor_corner_stays_in(shape, scheme):
    """No particle passes the corner; the block comes to rest in it.

    Every particle stays at x > 0 with its box on the floor, and the energy only falls
    as the block settles.

    Before, the corner node (held in x by the roller wall) dropped its floor row, and
    the block's corner fell through it.
    """
    p, energies = _cornered(shape, scheme)
    x, lp = _gathered(p, None)
    assert np.all(x > 0)
    assert np.all(x[:, 1] - lp[:, 1] > -0.02 * CELL)  # its boxes on the floor, not in it
    assert np.all(np.abs(p.v) < 0.05)
    assert energies.max() <= energies[0] * 1.001


@pytest.mark.mpi(min_size=2)
def test_a_block_pressed_into_the_corner_stays_in_on_two_ranks():
    dom = decompose(scene_grid((0.0, 0.0), (2.0, 1.5), CELL, padding=2), MPI.COMM_WORLD)
    p, _ = _cornered("cpgimp", "musl", dom)
    x, lp = _gathered(p, dom)
    assert len(x) == 200 and np.all(x > 0)
    assert np.all(x[:, 1] - lp[:, 1] > -0.02 * CELL)
