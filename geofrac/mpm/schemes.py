"""One explicit MPM step: MUSL, USF or USAVG (Edo (2016), App. D), pure numpy.

Transfers (eqs. 4.20-4.25, D.1-D.2): nodal mass m_i = Σ m_p φ_ip, momentum Σ m_p v_p φ_ip,
internal force f_i = −Σ V_p σ_p ∇φ_ip, external force Σ m_p b φ_ip. Nodes whose mass is
below :data:`MASS_FLOOR` times the largest carry no velocity or acceleration (a particle
just touching a node would otherwise divide by almost nothing). Wall conditions are
components of nodal velocity and acceleration held at zero (fixed: all components,
roller: the normal one).

Schemes (``scheme``):

- ``musl`` (D.1-D.9): forces from σ^k, grid update, particles moved, nodal velocity
  rebuilt from the new particle momentum (D.6), stress from it (D.7-D.8);
- ``usf`` (D.10-D.17): stress first, from the nodal velocity of the particle momentum,
  then forces from σ^{k+1} and the motion;
- ``usavg`` (D.18-D.29): USF's stress update, then MUSL's. Edo (2016) writes both with the
  full strain increment, which would count each step's strain twice; we follow Nairn's
  USAVG, which the thesis cites, and apply half of the step to each (Δt/2 in D.19 and
  D.27), so the stress over a step averages the two velocity fields.

The stress update is the material's (:class:`~geofrac.mpm.constitutive.
ConstitutiveModel`, registry :data:`~geofrac.mpm.constitutive.MODELS`): it turns σ by the
Jaumann rate (D.30-D.31; :func:`~geofrac.mpm.rotation.rotate_stress`, in 2D and 3D, so a
spinning body's stress turns with it) and adds its increment (the elastic Δσ = D : Δε, D.8, of
:class:`~geofrac.mpm.elastic.Elastic`, or the Drucker-Prager return); the volume
follows ρ^{k+1} = ρ^k / (1 + tr Δε) (D.9), and the deformation gradient
G^{k+1} = (I + ∇v Δt) G^k (4.70) drives ``cpgimp``'s half-widths (4.69).

Backends (``backend``): ``numba`` (default) runs the transfers as the compiled loops of
:mod:`~geofrac.mpm.kernels` (numba is imported by the first such step, never by
importing this module); ``numpy`` is the reference. They agree to round-off.

With a ``domain`` (:mod:`~geofrac.mpm.parallel`) the step runs on one rank's slab: the
nodal sums (mass, momentum, forces, MUSL's re-mapped momentum) of the nodes shared with
other ranks are completed by a halo exchange, MLS smoothing sees its neighbours on
other ranks as ghost particles, errors are raised on every rank alike, and particles
that left the slab move to their new rank at the end of the step.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from geofrac.errors import RunError
from geofrac.mpm.grid import Grid
from geofrac.mpm.particles import Particles
from geofrac.mpm.shapes import Shape, Weights, compiled_weights, get, weights

if TYPE_CHECKING:  # imported only by a step that uses them
    from geofrac.mpm.constitutive import ConstitutiveModel
    from geofrac.mpm.energy import StepBudget
    from geofrac.mpm.friction import Friction
    from geofrac.mpm.parallel import Domain

__all__ = [
    "BACKENDS",
    "MASS_FLOOR",
    "REST_TOL",
    "SCHEMES",
    "SMOOTHINGS",
    "TOUCH_TOL",
    "ParticlesLeftGrid",
    "StepSettings",
    "local_damping",
    "particle_strain_energy",
    "rest_speed",
    "step",
    "strain_energy",
    "time_step",
]

#: Update schemes.
SCHEMES = ("musl", "usf", "usavg")

#: Step implementations: compiled loops, or the numpy reference.
BACKENDS = ("numba", "numpy")

#: MLS smoothing kinds: ``standard``, as in Edo (2016) (4.66-4.67: the fitted increments
#: change the stress), or ``consistent`` (the same, with the grid forces from the operator's
#: adjoint applied to the stresses, :mod:`~geofrac.mpm.consistent`).
SMOOTHINGS = ("standard", "consistent")

#: Nodes lighter than this fraction of the heaviest node (over all ranks) are inactive:
#: no velocity, no acceleration, no contact. The mass a node takes from a particle
#: grows from 0 with the particle's weight on it, so what the node gives the particles
#: when it turns active is weighted by about this fraction: a knife edge of no
#: consequence, and the same on every rank (the masses are exact sums).
MASS_FLOOR = 1e-12

#: A nodal velocity (component, or difference of two) at most this fraction of L/Δt,
#: the speed of one cell per step, is zero: a billionth of a cell per step. Every
#: velocity a stable step forms is below L/Δt (the Courant condition), so its round-off,
#: and what a 1e-12 relative change of the input makes of a body at rest, lie far
#: below; any motion lies far above. Used where a decision on the sign of a velocity
#: jumps: the local damping's sign(v) and the contact's ties (:func:`rest_speed`).
REST_TOL = 1e-9

#: Material within this fraction of a cell of a frictional boundary touches it for the
#: strain's held velocity (:func:`_touching`): far above the gaps a resting body's
#: vibration opens (micrometres on 0.1 m cells), far below those a landing body closes
#: in a step.
TOUCH_TOL = 1e-2


class ParticlesLeftGrid(RunError):
    """Particles (or their GIMP boxes) reach beyond the background grid.

    Attributes:
        ids: the particles' ids (:attr:`Particles.ids`), shape=(k,).
        positions: their positions, shape=(k, dim).
    """

    def __init__(self, ids: np.ndarray, positions: np.ndarray) -> None:
        first = ", ".join(
            f"{int(i)} at {np.array2string(x, precision=4)}"
            for i, x in zip(ids[:3], positions[:3], strict=True)
        )
        more = f" and {len(ids) - 3} more" if len(ids) > 3 else ""
        super().__init__(
            f"{len(ids)} particle(s) left the background grid: {first}{more}; enlarge the grid "
            "or add walls"
        )
        self.ids, self.positions = ids, positions


def particle_strain_energy(p: Particles, material: ConstitutiveModel) -> np.ndarray:
    """½ V_p σ_p : D⁻¹ : σ_p per particle, shape=(n,) (the material's stored energy).

    In 2D the stored out-of-plane stress of plane strain enters (for an elastic history
    it equals ν tr σ).
    """
    return material.stored_energy(p)


def strain_energy(p: Particles, material: ConstitutiveModel) -> float:
    """Σ ½ V_p σ_p : D⁻¹ : σ_p (the elastic energy stored in the stresses)."""
    return float(np.sum(particle_strain_energy(p, material)))


def time_step(
    courant: float, spacing: float, material: ConstitutiveModel, *, density: float, dim: int
) -> float:
    """Δt = α L / c from the Courant number α < 1 (eq. 4.72), c the material's wave speed."""
    if not 0 < courant < 1:
        raise ValueError(f"the Courant number must lie in (0, 1), got {courant}")
    return courant * spacing / material.wave_speed(density, dim)


@dataclass(frozen=True)
class StepSettings:
    """What one step needs besides the grid, particles and material.

    Attributes:
        scheme: one of :data:`SCHEMES`.
        shape: the shape functions (:class:`~geofrac.mpm.shapes.Shape`); a registry name
            (:data:`~geofrac.mpm.shapes.REGISTRY`) is looked up.
        dt: time step.
        gravity: body force per mass b, shape=(dim,).
        fixed: held velocity components of the nodes, shape=(num_nodes, dim) bool.
        smoothing: MLS influence radius of the strain increments as a multiple of the
            cell size (:mod:`~geofrac.mpm.smoothing`), or None for no smoothing (the
            smoothing code is then not even imported).
        smoothing_kind: one of :data:`SMOOTHINGS` (with ``smoothing``).
        friction: a Coulomb friction boundary (:mod:`~geofrac.mpm.friction`), or None.
        damping: Cundall's local (non-viscous) damping coefficient α in [0, 1): each
            component of the nodal force becomes f − α |f| sign(v), v the nodal velocity
            at the step's start (:func:`local_damping`); 0 (the default): no damping,
            and the step does no extra work. For quasi-static starts (a body settling
            under its own weight); it removes energy from every motion, so it is wrong
            for dynamics (waves, a sliding body).
        backend: one of :data:`BACKENDS`.
        domain: this rank's part of a decomposed grid (:func:`geofrac.mpm.parallel.
            decompose`); the step is then given ``domain.local`` and this rank's
            particles, and ``fixed`` and ``friction`` refer to ``domain.local``'s nodes.
            None: the whole grid on one process.
    """

    scheme: str
    shape: Shape
    dt: float
    gravity: np.ndarray
    fixed: np.ndarray = field(repr=False)
    smoothing: float | None = None
    friction: Friction | None = None
    backend: str = "numba"
    domain: Domain | None = field(default=None, repr=False)
    damping: float = 0.0
    smoothing_kind: str = "standard"

    def __post_init__(self) -> None:
        """Check the names and the step."""
        if self.scheme not in SCHEMES:
            raise ValueError(f"scheme {self.scheme!r} is not one of {', '.join(SCHEMES)}")
        if isinstance(self.shape, str):
            object.__setattr__(self, "shape", get(self.shape))
        if not self.dt > 0:
            raise ValueError(f"dt must be > 0, got {self.dt}")
        if self.smoothing is not None and not self.smoothing > 0:
            raise ValueError(f"smoothing radius factor must be > 0, got {self.smoothing}")
        if not 0 <= self.damping < 1:
            raise ValueError(f"the local damping α must lie in [0, 1), got {self.damping}")
        if self.smoothing_kind not in SMOOTHINGS:
            raise ValueError(
                f"smoothing kind {self.smoothing_kind!r} is not one of {', '.join(SMOOTHINGS)}"
            )
        if self.backend not in BACKENDS:
            raise ValueError(f"backend {self.backend!r} is not one of {', '.join(BACKENDS)}")


def rest_speed(spacing: float, dt: float) -> float:
    """The speed at or below which a nodal velocity is at rest: :data:`REST_TOL` × L/Δt."""
    return REST_TOL * spacing / dt


def local_damping(f: np.ndarray, v: np.ndarray, alpha: float, *, rest: float = 0.0) -> np.ndarray:
    """Cundall's local damping force −α |f| sign(v), per node and component.

    The force of each component opposes the velocity with a fraction α of the
    unbalanced force (Cundall 1987; the "local damping" of geotechnical MPM codes such
    as Anura3D). A node at rest is not damped; a body in equilibrium (f = 0) feels
    none, so the static state is not shifted.

    At rest means |v_a| <= ``rest`` (:func:`rest_speed`). The force jumps by 2α|f| where
    v_a changes sign, so for a body at rest under a load, whose nodal velocities are
    0 ± round-off (a block held by friction on a slope), sign(v) would pick the damping
    force's direction by the round-off; with the friction's Coulomb bound it then
    decided stick or slip, and a relative change of the load of 1e-12 moved the block
    by 0.5-0.9 % of its displacement in 0.3 s.

    Args:
        f: the nodal force (internal + external), shape=(N, dim).
        v: the nodal velocity at the step's start, shape=(N, dim).
        alpha: α in [0, 1).
        rest: the speed at or below which a component is at rest (0: exactly 0).

    Returns:
        The damping force, shape=(N, dim) (add it to f).
    """
    return -alpha * np.abs(f) * np.where(np.abs(v) > rest, np.sign(v), 0.0)


def _scatter(w: Weights, terms: np.ndarray, bound: np.ndarray, num_nodes: int) -> np.ndarray:
    """Exact sums of per (particle, node) terms onto the nodes, as fixed-point pairs.

    Args:
        w: the weights (their node ids).
        terms: shape=(n, k, c).
        bound: every column's largest |term| over all ranks (or more), shape=(c,).
        num_nodes: grid nodes.

    Returns:
        Normalised pairs (:mod:`~geofrac.mpm.fixedpoint`), shape=(num_nodes, c, 2) int64.
    """
    from geofrac.mpm.fixedpoint import accumulate, scales

    with np.errstate(invalid="ignore"):  # a non-finite column turns NaN in _complete
        return accumulate(w.nodes, terms, scales(bound), num=num_nodes)


def _to_grid(
    w: Weights, values: np.ndarray, num_nodes: int, bound: np.ndarray | None = None
) -> np.ndarray:
    """Σ_p φ_ip values_p, values shape=(n, c); returns shape=(num_nodes, c).

    ``bound``: the columns' largest |term| over all ranks; None: of these particles.
    """
    terms = w.phi[:, :, None] * values[:, None, :]
    if bound is None:
        bound = np.max(np.abs(terms), axis=(0, 1), initial=0.0)
    return _complete(_scatter(w, terms, bound, num_nodes), bound, None, False)


def _nodal_velocity(
    w: Weights, p: Particles, mass: np.ndarray, active: np.ndarray, fixed: np.ndarray
) -> np.ndarray:
    """v_i = Σ m_p v_p φ_ip / m_i (D.6, D.10), held components zero, shape=(N, dim)."""
    return _velocity(_to_grid(w, p.mass[:, None] * p.v, len(mass)), mass, active, fixed)


def _complete(acc: np.ndarray, bound: np.ndarray, dom: Domain | None, fast: bool) -> np.ndarray:
    """The nodal sums of this rank's pairs, completed over the ranks, as float64.

    Args:
        acc: normalised pairs, shape=(N, c, 2) int64.
        bound: the columns' bounds they were split with, shape=(c,).
        dom: the decomposition, or None.
        fast: convert with the compiled loop (the same bits as the numpy one).

    Returns:
        shape=(N, c): the same values, to the last bit, on every rank holding a node and
        for every decomposition.
    """
    from geofrac.mpm.fixedpoint import exponents, normalise, to_float

    if dom is not None:
        N, c, _ = acc.shape
        acc = normalise(dom.sum_halo(acc.reshape(N, 2 * c)).reshape(N, c, 2))
    if not fast:
        return to_float(acc, bound)
    from geofrac.mpm import kernels

    out = np.empty(acc.shape[:2])
    kernels.pairs_to_float(acc, exponents(bound), out)
    out[:, ~np.isfinite(bound)] = np.nan
    return out


def _mass_momentum_bounds(p: Particles, pmax: float, fast: bool) -> np.ndarray:
    """Bounds of the terms φ m_p and φ m_p v_p, shape=(1 + dim,)."""
    out = np.empty(1 + p.dim)
    if fast:
        from geofrac.mpm import kernels

        kernels.mass_momentum_bounds(p.mass, p.v, pmax, out)
        return out
    out[0] = np.max(p.mass, initial=0.0)
    out[1:] = np.max(p.mass[:, None] * np.abs(p.v), axis=0, initial=0.0)
    return out * pmax


def _forces_bounds(
    p: Particles, stress: np.ndarray, gravity: np.ndarray, pmax: float, gmax: float, fast: bool
) -> np.ndarray:
    """Bounds of the force terms of ``stress`` (shape=(n, dim, dim)), shape=(dim,).

    max V_p Σ_b |σ_ab| gmax + m_p pmax |b_a|.
    """
    out = np.empty(p.dim)
    if fast:
        from geofrac.mpm import kernels

        kernels.forces_bounds(p.volume, stress, p.mass, gravity, pmax, gmax, out)
        return out
    rows = p.volume[:, None] * np.sum(np.abs(stress), axis=2) * gmax
    out[:] = np.max(rows + (p.mass * pmax)[:, None] * np.abs(gravity), axis=0, initial=0.0)
    return out


def _from_grid(w: Weights, values: np.ndarray) -> np.ndarray:
    """Σ_i φ_ip values_i, values shape=(num_nodes, c); returns shape=(n, c)."""
    return np.matmul(w.phi[:, None, :], values[w.nodes])[:, 0, :]


def _forces(w: Weights, p: Particles, stress: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """The terms of f_int + f_ext (eqs. 4.22-4.23, without tractions), shape=(n, k, dim).

    −V_p σ_p ∇φ_ip + m_p b φ_ip per particle and node, σ_p = ``stress`` (shape=(n, dim,
    dim): the particles' own, or the consistent smoothing's adjoint fit).
    """
    f = -p.volume[:, None, None] * np.matmul(w.grad, np.swapaxes(stress, 1, 2))
    f += (p.mass[:, None] * w.phi)[:, :, None] * gravity
    return f


def _velocity(
    mom: np.ndarray, mass: np.ndarray, active: np.ndarray, fixed: np.ndarray
) -> np.ndarray:
    """v_i = (m v)_i / m_i on the active nodes, held components zero, shape=(N, dim)."""
    v = np.zeros_like(mom)
    v[active] = mom[active] / mass[active, None]
    v[fixed] = 0.0
    return v


def _update_stress(
    w: Weights,
    p: Particles,
    material: ConstitutiveModel,
    v: np.ndarray,
    dt: float,
    s: StepSettings,
    smooth_at: tuple | None,
    budget: StepBudget | None = None,
) -> None:
    """Stress, volume and deformation gradient from the nodal velocity v (D.7-D.9, 4.70).

    ``smooth_at`` = (positions at the step's start, ids, radius): the strain increments are
    replaced by their MLS fit there (4.57, 4.66) before they change stress and volume.
    ``budget``: add the stored-energy terms of this update (:mod:`~geofrac.mpm.energy`).
    """
    n, d = p.n, p.dim
    if s.backend == "numba":
        from geofrac.mpm import kernels

        L = kernels.scratch("L", (n, d, d))
        kernels.velocity_gradient(w.nodes, w.grad, v, L)
        deps = kernels.scratch("deps", (n, d, d))
        kernels.strain_increment(L, dt, deps)
    else:
        L = np.matmul(np.swapaxes(v[w.nodes], 1, 2), w.grad)  # ∇v_p, shape=(n, dim, dim)
        deps = 0.5 * dt * (L + np.swapaxes(L, 1, 2))
    raw = deps
    if smooth_at is not None:
        deps = _smoothed(deps, smooth_at, s)
    if budget is not None:
        s0, v0 = p.stress.copy(), p.volume.copy()
        budget.power_raw += float(np.einsum("p,pij,pij->", v0, s0, raw))
        budget.smoothing += float(np.einsum("p,pij,pij->", v0, s0, deps - raw))
    _apply_increment(p, material, deps, L, dt, s, budget)
    if budget is not None:
        budget.quadratic += 0.5 * float(np.einsum("p,pij,pij->", v0, p.stress - s0, deps))


def _apply_increment(
    p: Particles,
    material: ConstitutiveModel,
    deps: np.ndarray,
    L: np.ndarray,
    dt: float,
    s: StepSettings,
    budget: StepBudget | None,
) -> None:
    """The material's stress update, then volume (D.9), G (4.70) and cpGIMP's l_p (4.69).

    The kinematics run compiled when the backend and the material's update are.
    """
    material.stress_update(p, deps, L, dt=dt, backend=s.backend, budget=budget)
    if s.backend == "numba" and material.compiled:
        from geofrac.mpm import kernels

        kernels.kinematics(deps, L, dt, p.volume, p.F, p.lp0, p.lp, s.shape.follows_deformation)
        return
    p.volume *= 1.0 + np.trace(deps, axis1=1, axis2=2)
    p.F = np.matmul(np.eye(p.dim) + dt * L, p.F)
    if s.shape.follows_deformation:
        p.lp = p.lp0 * np.abs(np.diagonal(p.F, axis1=1, axis2=2))


def _smoothed(deps: np.ndarray, smooth_at: tuple, s: StepSettings) -> np.ndarray:
    """The MLS fits of the strain increments (4.57), shape=(n, dim, dim).

    With a domain the neighbours on other ranks take part as ghosts, so every fit is
    the one of the whole set (the same operations in the same order: neighbours are
    summed by global id).
    """
    from geofrac.mpm.smoothing import smooth_strain

    if len(smooth_at) > 3:  # the consistent kind's operator, built at the step's start
        n, d = deps.shape[:2]
        return smooth_at[3].apply(deps.reshape(n, d * d)).reshape(n, d, d)
    x0, ids, h = smooth_at[:3]
    return smooth_strain(deps, x0, ids, h=h, backend=s.backend, domain=s.domain)


@dataclass
class _Nodes:
    """One step's weights and nodal state, filled by the step's parts in turn.

    Attributes:
        w: the particles' weights at the step's start.
        num_nodes: N, the grid's nodes.
        smooth_at: (positions at the step's start, ids, radius(, the consistent kind's
            operator)) for the MLS smoothing, or None.
        fast: the compiled backend.
        pmax: the shape's bound of φ_ip.
        gmax: the shape's bound of |∂φ_ip/∂x_a|.
        rest: the speed at or below which a nodal velocity is at rest (:func:`rest_speed`).
        mass: m_i, shape=(N,).
        mom: (m v)_i of the first transfer, shape=(N, dim).
        f: f_int + f_ext, shape=(N, dim).
        peak: the heaviest node's mass (over all ranks).
        active: the nodes heavier than :data:`MASS_FLOOR` × ``peak``, shape=(N,).
        v: the nodal velocity, shape=(N, dim).
        allow: the contact's allowed approaches (friction), or None.
        v_mapped: the nodal velocity before the contact acted (friction), or None.

    The rows the grid update's contact held, and whether they stuck, are the boundary's
    memory (:attr:`Friction.held_vn`, ``held_stuck``), not kept here twice.
    """

    w: Weights
    num_nodes: int
    smooth_at: tuple | None
    fast: bool
    pmax: float
    gmax: float
    rest: float
    mass: np.ndarray = field(init=False, repr=False)
    mom: np.ndarray = field(init=False, repr=False)
    f: np.ndarray = field(init=False, repr=False)
    peak: float = field(init=False)
    active: np.ndarray = field(init=False, repr=False)
    v: np.ndarray = field(init=False, repr=False)
    allow: np.ndarray | None = field(default=None, init=False, repr=False)
    v_mapped: np.ndarray | None = field(default=None, init=False, repr=False)


def step(
    g: Grid,
    p: Particles,
    material: ConstitutiveModel,
    *,
    settings: StepSettings,
    budget: StepBudget | None = None,
) -> None:
    """Advance the particles by one step of ``settings.scheme`` (in place).

    The parts of the algorithm (App. D): the grid check and the weights
    (:func:`_start`); the transfer of mass and momentum to the grid, with MUSL's forces
    (:func:`_map_mass_momentum`); the nodal velocity and the contact
    (:func:`_velocity_and_contact`); USF's and USAVG's stress update; the forces of the
    updated stress (:func:`_map_forces`, USF, USAVG); the grid update
    (:func:`_grid_update`); the particles' velocity and position from the grid
    (:func:`_grid_to_particles`); MUSL's and USAVG's nodal velocity re-mapped from the
    new particle momentum (:func:`_remap_velocity`) and their stress update from it.

    ``budget``: add this step's energy terms (this rank's part, each node counted on one
    rank: sum over the ranks for the whole) to it (:mod:`~geofrac.mpm.energy`), among
    them ``budget.damping``, the energy the local damping took out (``s.damping`` > 0);
    None (the default) computes none of them.

    With ``settings.domain``, ``g`` is ``settings.domain.local`` and ``p`` this rank's
    particles; every rank calls the step, and at its end ``p``'s arrays hold the particles
    the rank owns then.

    Raises:
        ParticlesLeftGrid: a particle (or its GIMP box) is outside the grid; nothing
            was changed. With a domain: on every rank, naming all such particles.
        geofrac.errors.RunError: after the step a particle's state is non-finite or
            its volume is not positive (an unstable step); with a domain also when a
            particle's support reaches beyond its rank's halo. On every rank alike.
    """
    s = settings
    if p.dim not in material.dims:
        dims = " or ".join(f"{d}D" for d in material.dims)
        raise ValueError(f"the {material.name} material needs {dims} particles, got {p.dim}D")
    nodes = _start(g, p, s)
    _map_mass_momentum(nodes, p, s)
    _velocity_and_contact(nodes, p, s, budget=budget)
    half = 0.5 if s.scheme == "usavg" else 1.0
    if s.scheme in ("usf", "usavg"):  # D.11-D.13, D.19-D.21: stress first
        v_strain = _strain_velocity(nodes, s)
        _update_stress(nodes.w, p, material, v_strain, half * s.dt, s, nodes.smooth_at, budget)
    if s.scheme != "musl":
        nodes.f = _map_forces(nodes, p, s)
    a, v_new, f_damp = _grid_update(nodes, s, budget=budget)
    if budget is not None:
        from geofrac.mpm.energy import owned_nodes

        x_start, v_start = p.x.copy(), p.v.copy()
        budget.grid_terms(
            s.dt,
            mass=nodes.mass,
            mom=nodes.mom,
            f=nodes.f,
            a=a,
            fixed=s.fixed,
            gravity_force=nodes.mass[:, None] * s.gravity,
            floor=MASS_FLOOR * nodes.peak,
            owned=owned_nodes(s.domain, nodes.num_nodes),
            damping=f_damp,
        )
    _grid_to_particles(nodes, p, a, v_new, s.dt)
    if s.scheme in ("musl", "usavg"):  # D.6-D.8, D.26-D.28: stress from the re-mapped v
        _remap_velocity(nodes, p, s, moved=v_new)
        _update_stress(nodes.w, p, material, nodes.v, half * s.dt, s, nodes.smooth_at, budget)
    if budget is not None:
        budget.transfer += 0.5 * float(np.sum(p.mass * np.sum((p.v - v_start) ** 2, axis=1)))
        budget.potential -= float(p.mass @ ((p.x - x_start) @ s.gravity))
    _check(p, s.domain, nodes.fast)
    if s.domain is not None:
        s.domain.migrate(p)


def _start(g: Grid, p: Particles, s: StepSettings) -> _Nodes:
    """The grid check, the weights at the step's start and the smoothing's neighbourhoods.

    Raises:
        ParticlesLeftGrid: (:func:`_check_inside`) before anything changed.
    """
    shape, fast = s.shape, s.backend == "numba"
    _check_inside(g, p, s)
    lp = p.lp if shape.boxes else None
    if fast:
        w = compiled_weights(g, p.x, shape, lp=lp, reuse=True)
    else:
        w = weights(g, p.x, shape, lp=lp)
    smooth_at: tuple | None = None
    if s.smoothing is not None:
        smooth_at = (p.x.copy(), p.ids, s.smoothing * g.spacing)
        if s.smoothing_kind == "consistent":
            from geofrac.mpm.consistent import mls_operator

            smooth_at += (mls_operator(p.x, s.smoothing * g.spacing, p.ids, domain=s.domain),)
    # the terms' bounds need no pass over the weights: every shape has 0 <= φ <=
    # phi_bound and |∂φ/∂x_a| <= grad_bound / L (eqs. 4.29, 4.31; bspline2: N <= 3/4,
    # |N'| <= 1/L; a test pins them)
    pmax, gmax = shape.phi_bound, shape.grad_bound / g.spacing
    return _Nodes(w, g.num_nodes, smooth_at, fast, pmax, gmax, rest_speed(g.spacing, s.dt))


def _force_stress(p: Particles, smooth_at: tuple | None) -> np.ndarray:
    """The stresses the grid forces are made of (the adjoint fit: consistent kind)."""
    if smooth_at is None or len(smooth_at) < 4:
        return p.stress
    dim = p.dim
    flat = p.stress.reshape(p.n, dim * dim)
    return np.ascontiguousarray(smooth_at[3].adjoint(flat, p.volume).reshape(p.n, dim, dim))


def _map_mass_momentum(nodes: _Nodes, p: Particles, s: StepSettings) -> None:
    """Particles to grid: m_i, (m v)_i and, for MUSL, f_i of σ^k (D.1-D.3, D.10, D.18).

    MUSL's forces use σ^k: they join this transfer (one pass, one exchange). The nodal
    sums are exact (fixed-point pairs, geofrac.mpm.fixedpoint), hence the same for any
    particle order and any decomposition; their scales come from bounds of the terms,
    the same on every rank.
    """
    w, fast, dom, dim = nodes.w, nodes.fast, s.domain, p.dim
    N = nodes.num_nodes
    early = s.scheme == "musl"
    ncol = 1 + dim + dim * early  # mass, momentum (, force)
    bound = _mass_momentum_bounds(p, nodes.pmax, fast)
    if early:
        fs = _force_stress(p, nodes.smooth_at)
        forces_bound = _forces_bounds(p, fs, s.gravity, nodes.pmax, nodes.gmax, fast)
        bound = np.concatenate([bound, forces_bound])
    if dom is not None:
        bound = dom.allmax(bound)
    if fast:
        from geofrac.mpm import kernels
        from geofrac.mpm.fixedpoint import scales

        acc = kernels.scratch("acc", (N, ncol, 2), np.int64)
        acc.fill(0)
        scale = scales(bound)
        kernels.mass_momentum(w.nodes, w.phi, p.mass, p.v, scale, acc)
        if early:
            kernels.forces(
                w.nodes, w.phi, w.grad, p.volume, fs, p.mass, s.gravity, scale, acc, 1 + dim
            )
    else:
        terms = np.empty((p.n, w.phi.shape[1], ncol))
        terms[:, :, 0] = w.phi * p.mass[:, None]
        terms[:, :, 1 : 1 + dim] = w.phi[:, :, None] * (p.mass[:, None] * p.v)[:, None, :]
        if early:
            terms[:, :, 1 + dim :] = _forces(w, p, fs, s.gravity)
        acc = _scatter(w, terms, bound, N)
    nodal = _complete(acc, bound, dom, fast)
    nodes.mass, nodes.mom, nodes.f = nodal[:, 0], nodal[:, 1 : 1 + dim], nodal[:, 1 + dim :]


def _velocity_and_contact(
    nodes: _Nodes, p: Particles, s: StepSettings, *, budget: StepBudget | None = None
) -> None:
    """The active nodes and v_i = (m v)_i / m_i (D.6, D.10), then the contact on it.

    The contact (friction.py) holds every nodal velocity: the approaches it allows are
    decided here, from the material's deformed half-widths (cpGIMP's p.lp; also for the
    shapes that do not use them, or the compression of the bottom layer would read as a
    gap). ``budget``: add the contact's work on the mapped velocity (:func:`_contact_work`).
    """
    mass, N, dim = nodes.mass, nodes.num_nodes, p.dim
    peak = mass.max(initial=0.0)
    if s.domain is not None:
        peak = s.domain.allmax(peak)
    nodes.peak = peak
    nodes.active = mass > MASS_FLOOR * peak  # relative to the heaviest node (MASS_FLOOR)
    if nodes.fast:
        from geofrac.mpm import kernels

        nodes.v = kernels.scratch("v", (N, dim))
        kernels.nodal_velocity(nodes.mom, mass, MASS_FLOOR * peak, s.fixed, nodes.v)
    else:
        nodes.v = _velocity(nodes.mom, mass, nodes.active, s.fixed)
    if s.friction is not None:
        from geofrac.mpm.friction import apply_friction, approach_allowed

        lp = p.lp0 * np.abs(np.diagonal(p.F, axis1=1, axis2=2))
        nodes.allow = approach_allowed(
            s.friction,
            p.x,
            lp,
            nodes=nodes.w.nodes,
            phi=nodes.w.phi,
            num_nodes=N,
            dt=s.dt,
            dom=s.domain,
        )
        nodes.v_mapped = nodes.v.copy()
        apply_friction(nodes.v, s.friction, nodes.allow, tol=nodes.rest)
        if budget is not None:
            _contact_work(budget, nodes, s, before=nodes.v_mapped, after=nodes.v)


def _contact_work(
    budget: StepBudget, nodes: _Nodes, s: StepSettings, *, before: np.ndarray, after: np.ndarray
) -> None:
    """Add the contact's work on one nodal velocity (before → after) to ``budget``.

    The kinetic energy change on the owned contact nodes (:meth:`~geofrac.mpm.energy.
    StepBudget.contact_terms`); only for the velocities that move the particles (the
    mapped and the updated one), not MUSL's re-mapped strain velocity.
    """
    from geofrac.mpm.energy import owned_nodes

    assert s.friction is not None
    budget.contact_terms(
        before=before,
        after=after,
        mass=nodes.mass,
        nodes=s.friction.nodes,
        owned=owned_nodes(s.domain, nodes.num_nodes),
    )


def _strain_velocity(nodes: _Nodes, s: StepSettings) -> np.ndarray:
    """The nodal velocity USF's (and USAVG's first) strain takes, shape=(N, dim).

    The mapped velocity, contact held; with friction, on the rows the contact held in
    the previous step's grid update (:attr:`Friction.held_vn`) whose material touches
    the boundary (:func:`_touching`), the velocity that contact left there (the node's
    own velocity at the step's start): its normal component, no more than the approach
    its gap now allows, in both directions, and where the row stuck no tangential one.
    The mapped velocity of such a node mixes in the material above it, and the contact
    clips it only one way (an approach removed, a separation kept), so the strain saw
    the node rise with the layer above while it stood on the boundary: the stored
    compression this added lifted a stress-free block dropped on a floor (0.085 mm in
    0.5 s; docs/mpm_friction.md, "Energy"). The motion keeps the mapped velocity: the
    boundary never pulls.
    """
    fr = s.friction
    if fr is None:
        return nodes.v
    rows = np.flatnonzero(np.isfinite(fr.held_vn) & _touching(nodes, fr))
    if len(rows) == 0:
        return nodes.v
    from geofrac.mpm.friction import hold

    target = fr.held_vn[rows]
    if nodes.allow is not None:  # no more than the approach its gap still allows
        target = np.minimum(target, nodes.allow[rows])
    return hold(nodes.v.copy(), fr, rows, target=target, stuck=fr.held_stuck[rows])


def _touching(nodes: _Nodes, fr: Friction) -> np.ndarray:
    """Rows whose material touches the boundary at the step's start, shape=(k,) bool.

    Its gap g within :data:`TOUCH_TOL` of a cell. There the contact pins the node to
    the boundary, and the strain takes its held normal velocity (at most the gap's
    approach g/Δt: a hundredth of a cell per step). Elsewhere the material lands from
    a gap: the node moves with its allowed approach, which on a light node (a particle
    at the edge of its support) is the noise of f/m clipped to the gap (up to 435 m/s
    for a 0.075 m gap): in a strain it crushed a point-MPM particle thrown at a wall.
    """
    if nodes.allow is None:
        return np.ones(len(fr.nodes), dtype=bool)
    return nodes.allow <= TOUCH_TOL * nodes.rest / REST_TOL  # g <= TOUCH_TOL L


def _map_forces(nodes: _Nodes, p: Particles, s: StepSettings) -> np.ndarray:
    """Particles to grid: f_i = f_int + f_ext of the updated stresses (D.14, D.22).

    Returns:
        shape=(N, dim).
    """
    w, fast, dom, N = nodes.w, nodes.fast, s.domain, nodes.num_nodes
    fs = _force_stress(p, nodes.smooth_at)
    bound = _forces_bounds(p, fs, s.gravity, nodes.pmax, nodes.gmax, fast)
    if dom is not None:
        bound = dom.allmax(bound)
    if fast:
        from geofrac.mpm import kernels
        from geofrac.mpm.fixedpoint import scales

        acc = kernels.scratch("acc", (N, p.dim, 2), np.int64)
        acc.fill(0)
        kernels.forces(
            w.nodes, w.phi, w.grad, p.volume, fs, p.mass, s.gravity, scales(bound), acc, 0
        )
    else:
        acc = _scatter(w, _forces(w, p, fs, s.gravity), bound, N)
    return _complete(acc, bound, dom, fast)


def _grid_update(
    nodes: _Nodes, s: StepSettings, *, budget: StepBudget | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """The nodal acceleration and new velocity (D.4, D.15, D.23), damped, with contact.

    ``budget``: add the contact's work on the updated velocity (:func:`_contact_work`).

    Returns:
        (a, v_new, the damping force or None), shape=(N, dim) each.
    """
    mass, v, N, dt = nodes.mass, nodes.v, nodes.num_nodes, s.dt
    f_damp, f_total = None, nodes.f
    if s.damping > 0:  # a branch: no extra work without damping
        f_damp = local_damping(nodes.f, v, s.damping, rest=nodes.rest)
        f_total = nodes.f + f_damp
    if nodes.fast:
        from geofrac.mpm import kernels

        dim = v.shape[1]
        a, v_new = kernels.scratch("a", (N, dim)), kernels.scratch("v_new", (N, dim))
        kernels.nodal_acceleration(f_total, mass, MASS_FLOOR * nodes.peak, s.fixed, dt, v, a, v_new)
    else:
        a = np.zeros((N, v.shape[1]))
        a[nodes.active] = f_total[nodes.active] / mass[nodes.active, None]
        a[s.fixed] = 0.0
        v_new = v + dt * a
    if s.friction is not None:
        from geofrac.mpm.friction import FREE, STICK, apply_friction

        fr = s.friction
        trial = None if budget is None else v_new.copy()
        states = np.empty(len(fr.nodes), dtype=np.int8)
        apply_friction(v_new, fr, nodes.allow, tol=nodes.rest, states=states)
        if budget is not None and trial is not None:
            _contact_work(budget, nodes, s, before=trial, after=v_new)
        # the memory: the rows the contact held where the material touches the boundary
        held = np.flatnonzero((states != FREE) & _touching(nodes, fr))
        fr.held_vn[:] = np.nan
        fr.held_vn[held] = np.einsum("ka,ka->k", v_new[fr.nodes[held]], fr.normals[held])
        fr.held_stuck[:] = False
        fr.held_stuck[held] = states[held] == STICK
        # the particles take every change the contact made, the mapped velocity's too
        # (else the approach it removed stays in their velocity, step after step, and
        # its friction is lost: a launched block slid 8 % too far)
        a = (v_new - nodes.v_mapped) / dt
    return a, v_new, f_damp


def _grid_to_particles(
    nodes: _Nodes, p: Particles, a: np.ndarray, v_new: np.ndarray, dt: float
) -> None:
    """The particles' velocity and position from the grid (D.4-D.5, D.16-D.17, D.24-D.25)."""
    w = nodes.w
    if nodes.fast:
        from geofrac.mpm import kernels

        kernels.from_grid2(w.nodes, w.phi, a, v_new, dt, p.v, p.x)  # D.4-D.5
    else:
        p.v += dt * _from_grid(w, a)  # D.4, D.16, D.24
        p.x += dt * _from_grid(w, v_new)  # D.5, D.17, D.25


def _remap_velocity(nodes: _Nodes, p: Particles, s: StepSettings, *, moved: np.ndarray) -> None:
    """MUSL's nodal velocity from the new particle momentum (D.6, D.26), contact held.

    ``moved``: the updated nodal velocity the particles moved with, shape=(N, dim).

    With friction, the re-mapped velocity of a node on the boundary mixes in the
    material above it; the node itself moved as the grid update's contact left it. On
    the rows that contact held where the material touches the boundary (the memory it
    has just written, :attr:`Friction.held_vn`), the strain therefore takes the node's
    held velocity: its normal
    component in both directions, and where the row stuck no tangential one. Elsewhere
    only an approach is removed (no friction: the particles took the update's).

    Before, the contact clipped the re-mapped velocity one way (an approach removed, a
    separation kept) and slowed it by μ times the mix's approach, which no particle
    felt: the strain saw a floor node rise with the layer above while it stood on the
    floor, and a stress-free block dropped on it rose 0.088 mm in 0.5 s (energy
    created; docs/mpm_friction.md, "Energy").
    """
    w, fast, dom, N, dim = nodes.w, nodes.fast, s.domain, nodes.num_nodes, p.dim
    bound = _mass_momentum_bounds(p, nodes.pmax, fast)[1:]
    if dom is not None:
        bound = dom.allmax(bound)
    if fast:
        from geofrac.mpm import kernels
        from geofrac.mpm.fixedpoint import scales

        acc = kernels.scratch("acc", (N, dim, 2), np.int64)
        acc.fill(0)
        kernels.momentum(w.nodes, w.phi, p.mass, p.v, scales(bound), acc, 0)
    else:
        terms = w.phi[:, :, None] * (p.mass[:, None] * p.v)[:, None, :]
        acc = _scatter(w, terms, bound, N)
    mom = _complete(acc, bound, dom, fast)
    if fast:  # D.6, D.26
        kernels.nodal_velocity(mom, nodes.mass, MASS_FLOOR * nodes.peak, s.fixed, nodes.v)
    else:
        nodes.v = _velocity(mom, nodes.mass, nodes.active, s.fixed)
    if s.friction is not None:
        from geofrac.mpm.friction import apply_friction, hold

        fr = s.friction
        rows = np.flatnonzero(np.isfinite(fr.held_vn))  # this step's grid update held them
        apply_friction(nodes.v, fr, nodes.allow, sliding_only=True, tol=nodes.rest)
        target = np.einsum("ka,ka->k", moved[fr.nodes[rows]], fr.normals[rows])
        hold(nodes.v, fr, rows, target=target, stuck=fr.held_stuck[rows])


def _outside(g: Grid, p: Particles, s: StepSettings) -> np.ndarray:
    """Which particles' supports (:meth:`Shape.margin`) reach beyond the grid, shape=(n,)."""
    shape = s.shape
    if s.backend != "numba":
        return g.outside(p.x, shape.margin(g.spacing, p.lp))
    from geofrac.mpm import kernels

    out = np.empty(p.n, dtype=bool)
    kernels.outside(p.x, p.lp, shape.boxes, shape.reach(g.spacing), g.origin, g.upper, out)
    return out


def _check_inside(g: Grid, p: Particles, s: StepSettings) -> None:
    """Raise ParticlesLeftGrid when a particle (or its GIMP box) is outside the grid.

    With a domain: against the whole grid, on every rank alike; then a RunError when a
    particle's support reaches beyond its rank's sub-grid (the halo is too narrow).

    The comparison is exact, without a tolerance: a support reaching exactly to the
    grid's last node has the weight 0 beyond it (the shapes' supports are open), so the
    weights need no node outside; one reaching past it by round-off would need one.
    Material only gets there through the padding beyond a wall, or, with no padding,
    pressed onto a boundary at the grid's edge by its elastic compression (a fraction of
    a millimetre, not round-off): an error on any machine.
    """
    dom = s.domain
    if dom is None:
        out = _outside(g, p, s)
        if np.any(out):
            raise ParticlesLeftGrid(p.ids[out], p.x[out])
        return
    out = _outside(dom.grid, p, s)
    ids, positions = dom.allgather_rows(p.ids[out], p.x[out])
    if len(ids):
        order = np.argsort(ids)
        raise ParticlesLeftGrid(ids[order], positions[order])
    if dom.any(local=bool(np.any(_outside(g, p, s)))):
        raise RunError(
            f"a particle's support reaches beyond its rank's halo of {dom.halo} cells; "
            "decompose with a wider halo"
        )


def _check(p: Particles, dom: Domain | None = None, fast: bool = False) -> None:
    """Raise RunError when a particle's state turned non-finite or its volume non-positive.

    A NaN is never carried into the next step: the error names the first particles.
    With a domain every rank raises it, naming the particles of all ranks. ``volume > 0``
    is exact: a volume that a step shrinks to 0 or less by (1 + tr Δε) <= 0 has been
    crushed by a strain of −100 % in one step, an unstable step on any machine.
    """
    if fast:
        from geofrac.mpm import kernels

        bad = np.empty(p.n, dtype=bool)
        kernels.bad_particles(p.x, p.stress, p.volume, bad)
    else:
        bad = ~(
            np.all(np.isfinite(p.x), axis=1)
            & np.all(np.isfinite(p.stress), axis=(1, 2))
            & (p.volume > 0)
        )
    ids = p.ids[bad]
    if dom is not None:
        ids = np.sort(dom.allgather_rows(ids, p.x[bad])[0])
    if len(ids):
        raise RunError(
            f"{len(ids)} particle(s) reached a non-finite state or a non-positive volume "
            f"(first: {ids[:5].tolist()}); reduce the Courant number or check the material"
        )
