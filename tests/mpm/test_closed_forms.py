"""MPM physics against closed forms, through the step (docs/mpm_physics.md).

- A rigidly spinning prestressed body keeps its stress turning with it (Jaumann rate,
  Edo (2016), eqs. D.30-D.31), elastic and Drucker-Prager, every scheme and shape.
- A laterally confined elastic column under gravity settles, with local damping, to
  σ_yy = −ρ g (H − y) and σ_xx = ν/(1 − ν) σ_yy; undamped it rings about that state.
"""

import numpy as np
import pytest

from geofrac.mpm.elastic import Elastic
from geofrac.mpm.energy import StepBudget
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.plasticity import DruckerPrager
from geofrac.mpm.schemes import SCHEMES, StepSettings, step, strain_energy, time_step
from geofrac.mpm.shapes import REGISTRY

# --- a rigidly rotating prestressed body ------------------------------------------------

S0 = np.array([[0.4, 0.6], [0.6, -0.8]])  # the prestress, deviator amplitude τ₀ = √0.72
SZZ = 0.3
THETA = 0.5  # the rotation angle, rad (ω = 1)
CENTRE = np.array([10.0, 10.0])


def _spin(material, scheme: str, shape: str, steps: int, backend: str = "numpy"):
    """A 8 × 8-cell square (2 particles per cell and direction) turned by THETA.

    The particles are given the velocity of the rigid rotation ω × (x − c) before every
    step: a free prestressed body would unload from its free faces and, without a
    centripetal stress, fly apart; prescribing the particle velocity keeps the motion a
    rigid rotation while the step still builds the nodal velocities, their gradient, the
    spin and the stress. E = 0.01 against a unit prestress: the grid's interpolation
    error of the rotation's gradient is a spurious strain of up to 2.5e-3 over the run
    for point MPM (particles crossing cells; 1e-4 for uGIMP, measured with E = 1), which
    then moves the stress by < 3e-5, far below the first-order error in Δt checked here.

    Returns:
        the stresses, shape=(n, 2, 2), σ_zz, shape=(n,), of the particles whose nodes see
        the full rotation: a node's velocity is the rotation's at the centroid of the
        particles within its support, the node itself only where that support is full;
        particles at least two supports inside the body (mpm, GIMP: two cells, radius 2
        about the centre of the half-width-4 body; the quadratic B-spline's 1.5 cells:
        three cells, radius 1).
    """
    p = lattice(CENTRE - 4.0, [16, 16], 0.5, density=1.0e3)
    p.stress[:] = S0
    p.stress_zz[:] = SZZ
    g = grid([0.0, 0.0], 1.0, [20, 20])
    J = np.array([[0.0, -1.0], [1.0, 0.0]])
    s = StepSettings(
        scheme, shape, THETA / steps, np.zeros(2), np.zeros((g.num_nodes, 2), bool), backend=backend
    )
    inner = np.linalg.norm(p.x - CENTRE, axis=1) < (1.0 if shape == "bspline2" else 2.0)
    for _ in range(steps):
        p.v = (p.x - CENTRE) @ J.T
        step(g, p, material, settings=s)
    return p.stress[inner], p.stress_zz[inner]


def _turned() -> np.ndarray:
    """R(θ) σ₀ R(θ)ᵀ."""
    c, s = np.cos(THETA), np.sin(THETA)
    R = np.array([[c, -s], [s, c]])
    return R @ S0 @ R.T


def _first_order_error(steps: int, scheme: str) -> float:
    """|σ − R σ₀ Rᵀ| of the explicit Jaumann update (D.30) after `steps` steps.

    In 2D a spin Δω = δ [[0, 1], [−1, 0]] (δ = ω Δt) maps a + i b, with a = (σ_xx − σ_yy)/2
    and b = σ_xy, to (1 + 2iδ)(a + i b); the exact rotation is e^{2iδ}: after N steps
    the deviator has grown by (1 + 4δ²)^{N/2} − 1 ≈ 2 θ δ, the phase error is O(N δ³).
    USAVG turns by half a step twice per step: δ/2, 2N times.
    """
    n, delta = (2 * steps, THETA / steps / 2) if scheme == "usavg" else (steps, THETA / steps)
    tau0 = np.hypot(0.5 * (S0[0, 0] - S0[1, 1]), S0[0, 1])
    return float(tau0 * abs((1 + 2j * delta) ** n - np.exp(2j * THETA)))


MATERIALS = {
    "elastic": Elastic(0.01, 0.25),
    "drucker-prager": DruckerPrager(0.01, 0.25, friction_angle=30.0, cohesion=1e6),
}


@pytest.mark.parametrize("material", list(MATERIALS))
@pytest.mark.parametrize("shape", REGISTRY)
@pytest.mark.parametrize("scheme", SCHEMES)
def test_spinning_prestressed_body_keeps_its_stress_turning_with_it(scheme, shape, material):
    """σ = R(θ) σ₀ R(θ)ᵀ after θ = 0.5 rad, to the explicit update's first-order error.

    The error is the closed form of the explicit rate (≈ 2 θ ω Δt τ₀, 0.0085 at 50
    steps) within 5 %, and halves when Δt halves. With the spin's sign flipped the
    largest component is off by 1.02, with no rotation (the elastic path before the
    Jaumann rate was added to it) by 0.78. The mean stress and σ_zz do not change.
    """
    mat = MATERIALS[material]
    errors = []
    for steps in (50, 100):
        stress, szz = _spin(mat, scheme, shape, steps)
        err = np.abs(stress - _turned()).max()
        assert err <= 1.05 * _first_order_error(steps, scheme)
        errors.append(err)
        np.testing.assert_allclose(np.trace(stress, axis1=1, axis2=2), np.trace(S0), atol=1e-4)
        np.testing.assert_allclose(szz, SZZ, atol=1e-4)
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.05)


@pytest.mark.parametrize("material", list(MATERIALS))
def test_spinning_body_compiled_step_equals_the_reference(material):
    """The compiled elastic update (kernels.elastic_update) turns the stress alike."""
    mat = MATERIALS[material]
    ref, _ = _spin(mat, "musl", "cpgimp", 50)
    fast, _ = _spin(mat, "musl", "cpgimp", 50, backend="numba")
    np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-12)


# --- a confined column settling under gravity -------------------------------------------

RHO, G_ACC, CELL = 1000.0, 10.0, 0.1
NU = 0.3
COLUMN = Elastic(1e7, NU)  # ρ g H / E = 1e-3: small strain


def _column(
    scheme: str,
    shape: str,
    damping: float,
    periods: float,
    backend: str = "numba",
    height: int = 10,
    domain=None,
    comm=None,
):
    """A column 2 cells wide, `height` cells high, stress-free at rest, then gravity.

    2 × 2 particles per cell; gravity is switched on at t = 0; roller walls at x = 0 and
    x = 0.2 and a roller floor at y = 0 (laterally confined: ε_xx = 0, plane strain
    ε_zz = 0).

    Returns:
        (particles, initial heights y₀ shape=(n,), H, the fundamental period T = 4H/c,
        Δt, base stress history shape=(steps,), damping work of every rank summed).
    """
    H = height * CELL
    p = lattice([0.0, 0.0], [4, 2 * height], CELL / 2, density=RHO)
    g = grid([-2 * CELL, -2 * CELL], CELL, [6, height + 4])
    if domain is not None:
        p, g = domain.distribute(p), domain.local
    X = g.nodes()
    fixed = np.zeros((g.num_nodes, 2), dtype=bool)
    fixed[X[:, 1] <= 1e-9, 1] = True
    fixed[(X[:, 0] <= 1e-9) | (X[:, 0] >= 2 * CELL - 1e-9), 0] = True
    dt = time_step(0.2, CELL, COLUMN, density=RHO, dim=2)
    lam, mu = COLUMN.lame()
    T = 4 * H / np.sqrt((lam + 2 * mu) / RHO)
    s = StepSettings(
        scheme, shape, dt, np.array([0.0, -G_ACC]), fixed, backend=backend,
        domain=domain, damping=damping,
    )  # fmt: skip
    y0 = p.x[:, 1].copy()
    budget = StepBudget()
    base = []
    for _ in range(round(periods * T / dt)):
        step(g, p, COLUMN, settings=s, budget=budget)
        bottom = p.stress[y0 < CELL / 2, 1, 1]
        base.append(bottom.mean() if len(bottom) else np.nan)
    total = budget.damping
    if comm is not None:
        total = comm.allreduce(total)
    return p, y0, H, T, dt, np.array(base), total


def _check_settled(p, y0, H):
    """σ_yy = −ρ g (H − y₀) within ρ g L/4 + 1 % of ρ g H; σ_xx = K₀ σ_yy; σ_zz = ν tr."""
    rho_g_H = RHO * G_ACC * H
    exact = -RHO * G_ACC * (H - y0)
    err = np.abs(p.stress[:, 1, 1] - exact)
    assert err.max() <= RHO * G_ACC * CELL / 4 + 0.01 * rho_g_H
    k0 = NU / (1 - NU)
    np.testing.assert_allclose(p.stress[:, 0, 0], k0 * p.stress[:, 1, 1], rtol=1e-9)
    tr = p.stress[:, 0, 0] + p.stress[:, 1, 1]
    np.testing.assert_allclose(p.stress_zz, NU * tr, rtol=1e-9)
    np.testing.assert_allclose(p.stress[:, 0, 1], 0.0, atol=1e-9 * rho_g_H)


@pytest.mark.parametrize(
    ("scheme", "shape"), [("musl", "ugimp"), ("usf", "mpm"), ("usavg", "cpgimp")]
)
def test_damped_column_settles_to_its_weight(scheme, shape):
    """With local damping α = 0.2 the column settles in 12 periods T = 4H/c.

    Tolerance: two particles of a cell share its stress (linear shape functions give one
    strain per cell along y), so the particles at ±L/4 of the cell centre are off by
    ρ g L/4 (2.5 % of ρ g H here); the residual vibration after 12 periods is below
    e^{−2 α · 12} ≈ 1 % of ρ g H (per cycle of a harmonic vibration the local damping
    takes 4α of its energy, the amplitude falls by e^{−2α}: a damping ratio ξ = α/π,
    docs/mpm_physics.md). The damping work closes the energy balance:
    gravity's work = strain energy + kinetic energy + damping work, to 0.1 %.
    """
    p, y0, H, _, _, _, dissipated = _column(scheme, shape, 0.2, 12)
    _check_settled(p, y0, H)
    assert p.kinetic_energy() < 1e-6 * strain_energy(p, COLUMN)
    gravity_work = G_ACC * float(np.sum(p.mass * (y0 - p.x[:, 1])))
    balance = strain_energy(p, COLUMN) + p.kinetic_energy() + dissipated
    assert balance == pytest.approx(gravity_work, rel=1e-3)
    # statically: gravity's work is twice the strain energy, the damping took the other half
    assert dissipated == pytest.approx(strain_energy(p, COLUMN), rel=1e-2)


def test_undamped_column_rings_about_its_weight():
    """Without damping the base stress swings between 0 and ≈ 2 ρ g H for ever.

    A suddenly applied uniform body force excites the odd modes of the fixed-free column,
    periods T/(2n − 1) with T = 4H/c: over one period T the mean of the base stress is the
    static one (here that of the base cell's centre, ρ g (H − L/2), the discrete static
    state) up to the grid's dispersion (3 %); the swing in the last of 10 periods is
    still above 85 % of 2 ρ g H.
    """
    _, _, H, T, dt, base, dissipated = _column("musl", "ugimp", 0.0, 10)
    rho_g_H = RHO * G_ACC * H
    last = base[-round(T / dt) :]
    assert -last.mean() == pytest.approx(RHO * G_ACC * (H - CELL / 2), rel=0.03)
    assert -last.min() > 0.85 * 2 * rho_g_H
    assert -last.max() < 0.15 * rho_g_H
    assert dissipated == 0.0


def test_damping_is_the_same_on_both_backends():
    """The damped step of the numpy reference and the compiled step agree (300 steps)."""
    ref = _column("musl", "cpgimp", 0.3, 1.5, backend="numpy", height=6)
    fast = _column("musl", "cpgimp", 0.3, 1.5, backend="numba", height=6)
    np.testing.assert_allclose(fast[0].stress, ref[0].stress, rtol=1e-10, atol=1e-6)
    assert fast[-1] == pytest.approx(ref[-1], rel=1e-10)
    assert fast[-1] > 0


def test_damping_coefficient_is_checked():
    with pytest.raises(ValueError, match="local damping"):
        StepSettings("musl", "mpm", 1.0, np.zeros(2), np.zeros((4, 2), bool), damping=1.0)
    with pytest.raises(ValueError, match="local damping"):
        StepSettings("musl", "mpm", 1.0, np.zeros(2), np.zeros((4, 2), bool), damping=-0.1)


@pytest.mark.mpi(min_size=2)
def test_damped_column_on_two_ranks():
    """The column split between two ranks settles alike.

    Each rank owns one of the column's two cells across; the damping work summed over
    the ranks equals the one-rank value (each node counted on one rank).
    """
    from mpi4py import MPI

    from geofrac.mpm.parallel import decompose

    comm = MPI.COMM_WORLD
    whole = grid([-2 * CELL, -2 * CELL], CELL, [6, 14])
    dom = decompose(whole, comm)
    p, _, H, _, _, _, dissipated = _column("musl", "ugimp", 0.2, 12, domain=dom, comm=comm)
    assert comm.allreduce(p.n) == 80
    assert comm.allgather(p.n)[comm.rank] < 80  # really split
    gathered = dom.gather(p)
    serial = _column("musl", "ugimp", 0.2, 12)
    failure = None
    if comm.rank == 0:  # compare on rank 0, then every rank raises alike (no deadlock)
        try:
            _check_settled(gathered, serial[1], H)
            np.testing.assert_allclose(gathered.stress, serial[0].stress, rtol=1e-8, atol=1e-6)
            assert dissipated == pytest.approx(serial[-1], rel=1e-8)
        except AssertionError as e:
            failure = str(e)
    failure = comm.bcast(failure, root=0)
    assert failure is None, failure


def test_the_settling_column_scene_reaches_its_weight(tmp_path):
    """jobs/mpm_settling_column.toml: `mpm.damping` reaches the step.

    The last frame is the settled column, within the tolerance argued in
    test_damped_column_settles_to_its_weight.
    """
    from mpi4py import MPI

    from geofrac.io.points import last_frame
    from geofrac.pipeline import run_scene
    from geofrac.scene import load_scene
    from tests.conftest import JOBS

    scene = load_scene(JOBS / "mpm_settling_column.toml", out=tmp_path)
    assert scene.mpm.damping == 0.2
    assert run_scene(scene, MPI.COMM_SELF, verbose=False)["status"] == "ok"
    last = last_frame(tmp_path / "particles.h5")
    x, u, stress = last["geometry"], last["displacement"], last["stress"]
    y0, H = x[:, 1] - u[:, 1], 1.0
    sxx, syy = stress[:, 0], stress[:, 4]
    err = np.abs(syy + RHO * G_ACC * (H - y0))
    assert err.max() <= RHO * G_ACC * CELL / 4 + 0.01 * RHO * G_ACC * H
    np.testing.assert_allclose(sxx, NU / (1 - NU) * syy, rtol=1e-9)
