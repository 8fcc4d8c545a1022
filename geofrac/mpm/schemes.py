"""One explicit MPM step: MUSL, USF or USAVG (seed App. D), pure numpy.

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
- ``usavg`` (D.18-D.29): USF's stress update, then MUSL's. The seed writes both with the
  full strain increment, which would count each step's strain twice; we follow Nairn's
  USAVG, which the seed cites, and apply half of the step to each (Δt/2 in D.19 and
  D.27), so the stress over a step averages the two velocity fields.

The stress update is the elastic increment Δσ = D : Δε (D.8; ``Elastic``), the volume
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
from geofrac.mpm.shapes import SHAPES, Weights, support_margin, weights

if TYPE_CHECKING:  # imported only by a step that uses them
    from geofrac.mpm.energy import StepBudget
    from geofrac.mpm.friction import Friction
    from geofrac.mpm.parallel import Domain
    from geofrac.mpm.plasticity import DruckerPrager

__all__ = [
    "BACKENDS",
    "MASS_FLOOR",
    "SCHEMES",
    "SMOOTHINGS",
    "Elastic",
    "ParticlesLeftGrid",
    "StepSettings",
    "step",
    "strain_energy",
    "time_step",
]

#: Update schemes.
SCHEMES = ("musl", "usf", "usavg")

#: Step implementations: compiled loops, or the numpy reference.
BACKENDS = ("numba", "numpy")

#: MLS smoothing kinds: the seed's (4.66-4.67: the fitted increments change the stress),
#: or ``consistent`` (the same, with the grid forces from the operator's adjoint applied
#: to the stresses, :mod:`~geofrac.mpm.consistent`).
SMOOTHINGS = ("seed", "consistent")

#: Nodes lighter than this fraction of the heaviest node are inactive.
MASS_FLOOR = 1e-12


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


@dataclass(frozen=True)
class Elastic:
    """Linear elastic increments Δσ = D : Δε (eqs. 4.34, D.8).

    In 1D the bar law Δσ = E Δε; in 2D plane strain; in 3D isotropic.

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio (unused in 1D).
    """

    E: float
    nu: float = 0.0

    def lame(self) -> tuple[float, float]:
        """(λ, μ)."""
        lam = self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))
        return lam, self.E / (2 * (1 + self.nu))

    def increment(self, deps: np.ndarray) -> np.ndarray:
        """Δσ of strain increments, both shape=(n, dim, dim)."""
        if deps.shape[1] == 1:
            return self.E * deps
        lam, mu = self.lame()
        tr = np.trace(deps, axis1=1, axis2=2)
        return lam * tr[:, None, None] * np.eye(deps.shape[1]) + 2 * mu * deps

    def wave_speed(self, density: float, dim: int) -> float:
        """The elastic wave speed c of eq. 4.72 (the P wave in 2D and 3D)."""
        if dim == 1:
            return float(np.sqrt(self.E / density))
        lam, mu = self.lame()
        return float(np.sqrt((lam + 2 * mu) / density))


def strain_energy(p: Particles, material: Elastic | DruckerPrager) -> float:
    """Σ ½ V_p σ_p : D⁻¹ : σ_p (the elastic energy stored in the stresses).

    In 2D the stored out-of-plane stress of plane strain enters (for an elastic history
    it equals ν tr σ).
    """
    s = p.stress
    if p.dim == 1:
        return 0.5 * float(np.sum(p.volume * s[:, 0, 0] ** 2) / material.E)
    E, nu = material.E, material.nu
    tr = np.trace(s, axis1=1, axis2=2)
    ss = np.sum(s * s, axis=(1, 2))
    if p.dim == 2:
        tr, ss = tr + p.stress_zz, ss + p.stress_zz**2
    return 0.5 * float(np.sum(p.volume * ((1 + nu) * ss - nu * tr**2) / E))


def time_step(
    courant: float, spacing: float, material: Elastic | DruckerPrager, density: float, dim: int
) -> float:
    """Δt = α L / c from the Courant number α < 1 (eq. 4.72), c the elastic wave speed."""
    if not 0 < courant < 1:
        raise ValueError(f"the Courant number must lie in (0, 1), got {courant}")
    return courant * spacing / Elastic(material.E, material.nu).wave_speed(density, dim)


@dataclass(frozen=True)
class StepSettings:
    """What one step needs besides the grid, particles and material.

    Attributes:
        scheme: one of :data:`SCHEMES`.
        shape: one of :data:`~geofrac.mpm.shapes.SHAPES`.
        dt: time step.
        gravity: body force per mass b, shape=(dim,).
        fixed: held velocity components of the nodes, shape=(num_nodes, dim) bool.
        smoothing: MLS influence radius of the strain increments as a multiple of the
            cell size (:mod:`~geofrac.mpm.smoothing`), or None for no smoothing (the
            smoothing code is then not even imported).
        smoothing_kind: one of :data:`SMOOTHINGS` (with ``smoothing``).
        friction: a Coulomb friction boundary (:mod:`~geofrac.mpm.friction`), or None.
        backend: one of :data:`BACKENDS`.
        domain: this rank's part of a decomposed grid (:func:`geofrac.mpm.parallel.
            decompose`); the step is then given ``domain.local`` and this rank's
            particles, and ``fixed`` and ``friction`` refer to ``domain.local``'s nodes.
            None: the whole grid on one process.
    """

    scheme: str
    shape: str
    dt: float
    gravity: np.ndarray
    fixed: np.ndarray = field(repr=False)
    smoothing: float | None = None
    friction: Friction | None = None
    backend: str = "numba"
    domain: Domain | None = field(default=None, repr=False)
    smoothing_kind: str = "seed"

    def __post_init__(self) -> None:
        """Check the names and the step."""
        if self.scheme not in SCHEMES:
            raise ValueError(f"scheme {self.scheme!r} is not one of {', '.join(SCHEMES)}")
        if self.shape not in SHAPES:
            raise ValueError(f"shape {self.shape!r} is not one of {', '.join(SHAPES)}")
        if not self.dt > 0:
            raise ValueError(f"dt must be > 0, got {self.dt}")
        if self.smoothing is not None and not self.smoothing > 0:
            raise ValueError(f"smoothing radius factor must be > 0, got {self.smoothing}")
        if self.smoothing_kind not in SMOOTHINGS:
            raise ValueError(
                f"smoothing kind {self.smoothing_kind!r} is not one of {', '.join(SMOOTHINGS)}"
            )
        if self.smoothing_kind == "consistent" and self.domain is not None:
            raise ValueError("consistent smoothing runs on one process only")
        if self.backend not in BACKENDS:
            raise ValueError(f"backend {self.backend!r} is not one of {', '.join(BACKENDS)}")


def _scatter(w: Weights, contrib: np.ndarray, num_nodes: int) -> np.ndarray:
    """Sum per (particle, node) contributions onto the nodes.

    Args:
        w: the weights (their node ids).
        contrib: shape=(n, k, c).
        num_nodes: grid nodes.

    Returns:
        shape=(num_nodes, c).
    """
    flat = w.nodes.ravel()
    return np.stack(
        [
            np.bincount(flat, weights=contrib[:, :, c].ravel(), minlength=num_nodes)
            for c in range(contrib.shape[2])
        ],
        axis=1,
    )


def _to_grid(w: Weights, values: np.ndarray, num_nodes: int) -> np.ndarray:
    """Σ_p φ_ip values_p, values shape=(n, c); returns shape=(num_nodes, c)."""
    return _scatter(w, w.phi[:, :, None] * values[:, None, :], num_nodes)


def _from_grid(w: Weights, values: np.ndarray) -> np.ndarray:
    """Σ_i φ_ip values_i, values shape=(num_nodes, c); returns shape=(n, c)."""
    return np.matmul(w.phi[:, None, :], values[w.nodes])[:, 0, :]


def _forces(
    w: Weights, p: Particles, gravity: np.ndarray, num_nodes: int, stress: np.ndarray
) -> np.ndarray:
    """f_int + f_ext (eqs. 4.22-4.23, without tractions) of ``stress``, shape=(num_nodes, dim)."""
    # −Σ V_p σ_p ∇φ_ip + m_p b φ_ip, per particle and node: shape=(n, k, dim)
    f = -p.volume[:, None, None] * np.matmul(w.grad, np.swapaxes(stress, 1, 2))
    f += (p.mass[:, None] * w.phi)[:, :, None] * gravity
    return _scatter(w, f, num_nodes)


def _nodal_velocity(
    w: Weights, p: Particles, mass: np.ndarray, active: np.ndarray, fixed: np.ndarray
) -> np.ndarray:
    """v_i = Σ m_p v_p φ_ip / m_i (D.6, D.10), held components zero, shape=(N, dim)."""
    return _velocity(_to_grid(w, p.mass[:, None] * p.v, len(mass)), mass, active, fixed)


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
    material: Elastic | DruckerPrager,
    v: np.ndarray,
    dt: float,
    s: StepSettings,
    smooth_at: tuple | None,
    budget: StepBudget | None = None,
) -> None:
    """Stress, volume and deformation gradient from the nodal velocity v (D.7-D.9, 4.70).

    ``smooth_at`` = (positions at the step's start, radius): the strain increments are
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
        deps = _smoothed(deps, smooth_at, s).reshape(n, d, d)
    if budget is not None:
        from geofrac.mpm.energy import stored

        nu = material.nu if d > 1 else 0.0
        s0, v0 = p.stress.copy(), p.volume.copy()
        budget.power_raw += float(np.einsum("p,pij,pij->", v0, s0, raw))
        budget.smoothing += float(np.einsum("p,pij,pij->", v0, s0, deps - raw))
        trial = float(np.sum(_trial(p, material, deps)))
    _apply_increment(w, p, material, deps, L, dt, s, budget)
    if budget is not None:
        budget.quadratic += 0.5 * float(np.einsum("p,pij,pij->", v0, p.stress - s0, deps))
        budget.plastic += trial - float(
            np.sum(stored(p.stress, p.stress_zz, p.volume, material.E, nu))
        )


def _trial(p: Particles, material: Elastic | DruckerPrager, deps: np.ndarray) -> np.ndarray:
    """Stored energy of the elastic trial σ + D:Δε at volume V(1 + tr Δε), shape=(n,)."""
    from geofrac.mpm.energy import stored

    el = Elastic(material.E, material.nu)
    tr = np.trace(deps, axis1=1, axis2=2)
    zz = p.stress_zz + (el.lame()[0] * tr if p.dim == 2 else 0.0)
    nu = material.nu if p.dim > 1 else 0.0
    return stored(p.stress + el.increment(deps), zz, p.volume * (1.0 + tr), material.E, nu)


def _apply_increment(
    w: Weights,
    p: Particles,
    material: Elastic | DruckerPrager,
    deps: np.ndarray,
    L: np.ndarray,
    dt: float,
    s: StepSettings,
    budget: StepBudget | None,
) -> None:
    """Stress (D.8 or the plastic return), volume (D.9) and G (4.70) from Δε and ∇v."""
    d = p.dim
    if isinstance(material, Elastic) and s.backend == "numba":
        from geofrac.mpm import kernels

        lam, mu = material.lame() if d > 1 else (0.0, 0.0)
        kernels.elastic_update(
            deps, L, dt, material.E, lam, mu, p.stress, p.stress_zz, p.volume, p.F,
            p.lp0, p.lp, s.shape == "cpgimp",
        )  # fmt: skip
        return
    if isinstance(material, Elastic):
        p.stress += material.increment(deps)
        if p.dim == 2:
            p.stress_zz += material.lame()[0] * np.trace(deps, axis1=1, axis2=2)
    else:
        _plastic_update(p, material, deps, L, dt, budget)
    p.volume *= 1.0 + np.trace(deps, axis1=1, axis2=2)
    p.F = np.matmul(np.eye(p.dim) + dt * L, p.F)
    if s.shape == "cpgimp":
        p.lp = p.lp0 * np.abs(np.diagonal(p.F, axis1=1, axis2=2))


def _smoothed(deps: np.ndarray, smooth_at: tuple, s: StepSettings) -> np.ndarray:
    """The MLS fits of the strain increments (4.57), shape=(n, dim·dim).

    With a domain the neighbours on other ranks take part as ghosts, so every fit is
    the one of the whole set.
    """
    from geofrac.mpm.smoothing import smooth

    x0, h = smooth_at[:2]
    n = len(deps)
    values = deps.reshape(n, deps.shape[1] * deps.shape[2])
    if len(smooth_at) > 2:  # the consistent kind's operator, built at the step's start
        return smooth_at[2].apply(values)
    if s.domain is not None:
        gx, gv = s.domain.ghosts(x0, values, h)  # collective: every rank takes part
        x0, values = np.concatenate([x0, gx]), np.concatenate([values, gv])
    if n == 0:  # a rank whose slab holds no particle (yet) has nothing to smooth
        return values[:0]
    return smooth(x0, values, h, s.backend)[0][:n]


def _plastic_update(
    p: Particles,
    material: DruckerPrager,
    deps: np.ndarray,
    L: np.ndarray,
    dt: float,
    budget: StepBudget | None = None,
) -> None:
    """Jaumann rotation (D.30-D.31) and Drucker-Prager return (4.39-4.43) on 3×3 stresses.

    Plane strain in 2D: the strain increment has no zz part, σ_zz is the stored one.
    """
    from geofrac.mpm.plasticity import jaumann

    n, d = p.n, p.dim
    full = np.zeros((n, 3, 3))
    full[:, :d, :d] = p.stress
    if d == 2:
        full[:, 2, 2] = p.stress_zz
    spin = np.zeros((n, 3, 3))
    spin[:, :d, :d] = -0.5 * dt * (L - np.swapaxes(L, 1, 2))  # the seed's Δω (D.31)
    deps3 = np.zeros((n, 3, 3))
    deps3[:, :d, :d] = deps
    rotated = jaumann(full, spin)
    if budget is not None:  # the rotation's change of the trial's stored energy
        from geofrac.mpm.energy import stored

        tr = np.trace(deps, axis1=1, axis2=2)
        el = Elastic(material.E, material.nu)
        volume, zero = p.volume * (1.0 + tr), np.zeros(n)
        rot = float(
            np.sum(
                stored(rotated + el.increment(deps3), zero, volume, material.E, material.nu)
                - stored(full + el.increment(deps3), zero, volume, material.E, material.nu)
            )
        )
        budget.plastic += rot  # the return starts from the rotated trial
    new, dlam = material.update(rotated, deps3)
    p.stress = new[:, :d, :d].copy()
    if d == 2:
        p.stress_zz = new[:, 2, 2].copy()
    p.plastic += dlam


def step(
    g: Grid,
    p: Particles,
    material: Elastic | DruckerPrager,
    s: StepSettings,
    budget: StepBudget | None = None,
) -> None:
    """Advance the particles by one step of ``s.scheme`` (in place).

    ``budget``: add this step's energy terms (this rank's part) to it
    (:mod:`~geofrac.mpm.energy`); None (the default) computes none of them.

    With ``s.domain``, ``g`` is ``s.domain.local`` and ``p`` this rank's particles; every
    rank calls the step, and at its end ``p``'s arrays hold the particles the rank owns
    then.

    Raises:
        ParticlesLeftGrid: a particle (or its GIMP box) is outside the grid; nothing
            was changed. With a domain: on every rank, naming all such particles.
        geofrac.errors.RunError: after the step a particle's state is non-finite or
            its volume is not positive (an unstable step); with a domain also when a
            particle's support reaches beyond its rank's halo. On every rank alike.
    """
    if not isinstance(material, Elastic) and p.dim == 1:
        raise ValueError("plasticity needs 2D or 3D particles (the 1D bar is elastic)")
    dom = s.domain
    gimp = s.shape in ("ugimp", "cpgimp")
    spline = s.shape == "bspline2"
    fast = s.backend == "numba"
    if fast:
        from geofrac.mpm import kernels
    _check_inside(g, p, s)
    if fast:
        w = kernels.grid_weights(g, p.x, p.lp if gimp else None, reuse=True, bspline=spline)
    else:
        w = weights(g, p.x, p.lp if gimp else None, bspline=spline)
    N, dt, dim = g.num_nodes, s.dt, p.dim
    smooth_at: tuple | None = None
    if s.smoothing is not None:
        smooth_at = (p.x.copy(), s.smoothing * g.spacing)
        if s.smoothing_kind == "consistent":
            from geofrac.mpm.consistent import mls_operator

            smooth_at += (mls_operator(p.x, s.smoothing * g.spacing),)

    def force_stress() -> np.ndarray:
        """The stresses the grid forces are made of (the adjoint fit: consistent kind)."""
        if smooth_at is None or len(smooth_at) < 3:
            return p.stress
        flat = p.stress.reshape(p.n, dim * dim)
        return np.ascontiguousarray(smooth_at[2].adjoint(flat, p.volume).reshape(p.n, dim, dim))

    # MUSL's forces use σ^k: they join the first transfer (one pass, one exchange)
    early = s.scheme == "musl"
    if fast:
        nodal = kernels.scratch("nodal", (N, 1 + dim + dim * early))
        nodal.fill(0.0)
    else:
        nodal = np.zeros((N, 1 + dim + dim * early))  # mass, momentum (, force)
    mass, mom, f = nodal[:, 0], nodal[:, 1 : 1 + dim], nodal[:, 1 + dim :]
    if fast:
        kernels.mass_momentum(w.nodes, w.phi, p.mass, p.v, mass, mom)
        if early:
            kernels.forces(w.nodes, w.phi, w.grad, p.volume, force_stress(), p.mass, s.gravity, f)
    else:
        mass[:] = _to_grid(w, p.mass[:, None], N)[:, 0]
        mom[:] = _to_grid(w, p.mass[:, None] * p.v, N)
        if early:
            f[:] = _forces(w, p, s.gravity, N, force_stress())
    if dom is not None:
        nodal = dom.sum_halo(nodal)
        mass, mom, f = nodal[:, 0], nodal[:, 1 : 1 + dim], nodal[:, 1 + dim :]
    peak = mass.max(initial=0.0)
    if dom is not None:
        peak = dom.allmax(peak)
    active = mass > MASS_FLOOR * peak
    if fast:
        v = kernels.scratch("v", (N, dim))
        kernels.nodal_velocity(mom, mass, MASS_FLOOR * peak, s.fixed, v)
    else:
        v = _velocity(mom, mass, active, s.fixed)
    half = 0.5 if s.scheme == "usavg" else 1.0
    if s.scheme in ("usf", "usavg"):
        _update_stress(w, p, material, v, half * dt, s, smooth_at, budget)
    if not early:
        f = np.zeros((N, dim))
        if fast:
            kernels.forces(w.nodes, w.phi, w.grad, p.volume, force_stress(), p.mass, s.gravity, f)
        else:
            f = _forces(w, p, s.gravity, N, force_stress())
        if dom is not None:
            f = dom.sum_halo(f)
    if fast:
        a, v_new = kernels.scratch("a", (N, dim)), kernels.scratch("v_new", (N, dim))
        kernels.nodal_acceleration(f, mass, MASS_FLOOR * peak, s.fixed, dt, v, a, v_new)
    else:
        a = np.zeros((N, dim))
        a[active] = f[active] / mass[active, None]
        a[s.fixed] = 0.0
        v_new = v + dt * a
    if s.friction is not None:
        from geofrac.mpm.friction import apply_friction

        apply_friction(v_new, s.friction)
        a = (v_new - v) / dt  # the particles take the same, frictional, change
    if budget is not None:
        from geofrac.mpm.energy import owned_nodes

        x_start, v_start = p.x.copy(), p.v.copy()
        budget.grid_terms(
            dt, mass, mom, f, a, s.fixed, mass[:, None] * s.gravity, MASS_FLOOR * peak,
            owned_nodes(dom, N),
        )  # fmt: skip
    if fast:
        kernels.from_grid2(w.nodes, w.phi, a, v_new, dt, p.v, p.x)  # D.4-D.5
    else:
        p.v += dt * _from_grid(w, a)  # D.4, D.16, D.24
        p.x += dt * _from_grid(w, v_new)  # D.5, D.17, D.25
    if s.scheme in ("musl", "usavg"):
        if fast:
            mom = kernels.scratch("mom", (N, dim))
            mom.fill(0.0)
            kernels.momentum(w.nodes, w.phi, p.mass, p.v, mom)
        else:
            mom = _to_grid(w, p.mass[:, None] * p.v, N)
        if dom is not None:
            mom = dom.sum_halo(mom)
        if fast:  # D.6, D.26
            kernels.nodal_velocity(mom, mass, MASS_FLOOR * peak, s.fixed, v)
        else:
            v = _velocity(mom, mass, active, s.fixed)
        if s.friction is not None:
            from geofrac.mpm.friction import apply_friction

            apply_friction(v, s.friction, sliding_only=True)
        _update_stress(w, p, material, v, half * dt, s, smooth_at, budget)
    if budget is not None:
        budget.transfer += 0.5 * float(np.sum(p.mass * np.sum((p.v - v_start) ** 2, axis=1)))
        budget.potential -= float(p.mass @ ((p.x - x_start) @ s.gravity))
    _check(p, dom, fast)
    if dom is not None:
        dom.migrate(p)


def _outside(g: Grid, p: Particles, gimp: bool, fast: bool, margin: float | None) -> np.ndarray:
    """Which particles (or their GIMP boxes) reach beyond the grid, shape=(n,).

    ``margin``: a fixed support half-width instead (``bspline2``), or None.
    """
    if margin is not None:
        return g.outside(p.x, margin)
    if not fast:
        return g.outside(p.x, p.lp if gimp else 0.0)
    from geofrac.mpm import kernels

    out = np.empty(p.n, dtype=bool)
    kernels.outside(p.x, p.lp, gimp, g.origin, g.upper, out)
    return out


def _check_inside(g: Grid, p: Particles, s: StepSettings) -> None:
    """Raise ParticlesLeftGrid when a particle (or its GIMP box) is outside the grid.

    With a domain: against the whole grid, on every rank alike; then a RunError when a
    particle's support reaches beyond its rank's sub-grid (the halo is too narrow).
    """
    gimp, fast = s.shape in ("ugimp", "cpgimp"), s.backend == "numba"
    margin = support_margin(s.shape, g.spacing)
    dom = s.domain
    if dom is None:
        out = _outside(g, p, gimp, fast, margin)
        if np.any(out):
            raise ParticlesLeftGrid(p.ids[out], p.x[out])
        return
    out = _outside(dom.grid, p, gimp, fast, margin)
    ids, positions = dom.allgather_rows(p.ids[out], p.x[out])
    if len(ids):
        order = np.argsort(ids)
        raise ParticlesLeftGrid(ids[order], positions[order])
    if dom.any(bool(np.any(_outside(g, p, gimp, fast, margin)))):
        raise RunError(
            f"a particle's support reaches beyond its rank's halo of {dom.halo} cells; "
            "decompose with a wider halo"
        )


def _check(p: Particles, dom: Domain | None = None, fast: bool = False) -> None:
    """Raise RunError when a particle's state turned non-finite or its volume non-positive.

    A NaN is never carried into the next step: the error names the first particles.
    With a domain every rank raises it, naming the particles of all ranks.
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
