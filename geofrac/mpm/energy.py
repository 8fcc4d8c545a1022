"""The energy budget of an MPM step and run: where the total energy goes (docs/mpm_energy.md).

Pure numpy. A step of :func:`geofrac.mpm.schemes.step` given a :class:`StepBudget`
fills it with the work terms below (a step without one computes nothing extra).

Stored energy. Two measures: U = Σ ½ V_p σ_p : D⁻¹ : σ_p (``strain``; what the stresses
would store in a linear material at small strain) and W, the work the stresses have
done on the particles, accumulated per stress update as Σ ½ V_p (σ_p^k + σ_p^{k+1}) : Δε_p
(trapezoidal) minus the plastic dissipation (``stored_work``). They agree to O(ε) relative:
at the translating bar's impact strain v₀/c = 0.089 U is 3 % below W, the stored energy
of the hypoelastic bar (σ = E ln λ, W = E V₀ (λ ln λ − λ + 1) in 1D). W is the one
whose sum with K and Π an exact time integration would conserve.

The budget. With K = Σ ½ m_p |v_p|² and Π = −Σ m_p b·x_p, every step satisfies, to
round-off,

    ΔK + ΔW + ΔΠ = wall + friction + smoothing − plastic − damping + numerical

with, for the step's nodal mass m_i, momentum p_i (of the particles), total force f_i
(internal + gravity, without the local damping), the acceleration a_i the particles
take (zero on held components, damping and friction applied) and v*_i = p_i / m_i on
the active nodes (not zeroed on held ones):

- ``wall`` = Δt Σ_held R_i·v*_i, R_i = m_i a_i − f_i − d_i (= −f_i on a held component,
  d_i the local damping force): the
  work of the walls' reactions on the grid velocity (a rigid wall does none; this is
  energy the held nodes take out or put in);
- ``friction`` = Δt Σ R_i·v*_i over the other nodes (R_i ≠ 0 only on frictional ones),
  negative when friction dissipates;
- ``smoothing`` = Σ V_p σ_p : (Δε̃_p − Δε_p) over the stress updates: the stress work of
  the MLS fit Δε̃ of the raw increments Δε (Edo (2016), eq. 4.66) beyond theirs;
- ``plastic`` = U(elastic trial) − U(after the return mapping) ≥ 0 (with the Jaumann
  rotation's change of the trial), the dissipation of the Drucker-Prager return (zero
  for an elastic material);
- ``damping`` = −Δt Σ d_i·v*_i ≥ 0, the energy Cundall's local damping
  (:func:`geofrac.mpm.schemes.local_damping`, ``mpm.damping``) takes out, a dissipation
  signed like ``plastic``;
- ``numerical`` = K_tr + (P_raw + Q + W_int) + (W_g + ΔΠ), the time-integration and
  transfer error, from its own parts: K_tr = Σ ½ m_p |δv_p|² (δv_p = Δt Σ φ_ip a_i),
  P_raw = Σ V_p σ_p : Δε_p the stress power of the raw increments, Q = Σ ½ V_p
  (σ_p^{k+1} − σ_p^k) : Δε̃_p the trapezoid's second half, W_int = Δt Σ f_int,i·v*_i
  the internal forces' work on the grid (−P_raw in a scheme whose stress update used
  the force velocities) and W_g = Δt Σ m_i b·v*_i against ΔΠ.

It follows from ΔK = Σ m_p v_p·δv_p + K_tr and Σ_p m_p v_p·δv_p = Δt Σ_i a_i·p_i =
Δt Σ_i (f_i + d_i + R_i)·v*_i (held components have a_i = 0 and d_i = 0, the others
p_i = m_i v*_i).

Gravity may change from step to step (``[gravity] ramp``): ΔΠ is then the work of the
step's own gravity b_k, −Σ m_p b_k·(x_p^{k+1} − x_p^k), and Π the sum of these
(:meth:`EnergyLog.potential`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any

import numpy as np

__all__ = [
    "COLUMNS",
    "CONTACT_FLOOR",
    "CONTACT_ROUNDOFF",
    "CSV_COLUMNS",
    "GRAVITY_JUDGED",
    "NUMERICAL_BOUND",
    "Budget",
    "EnergyLog",
    "StepBudget",
    "owned_nodes",
    "stored",
]

#: Budget columns of ``energies.csv`` (after step, t, kinetic, strain, gravity, total,
#: dissipated); every one but ``stored_work`` cumulative since t = 0.
COLUMNS = (
    "stored_work",
    "wall_work",
    "friction_work",
    "smoothing_work",
    "plastic_dissipation",
    "damping_dissipation",
    "numerical_work",
)


#: A step's contact work is positive (energy created by the contact) only above this
#: fraction of its scale, the kinetic energy on the contact nodes before the contact
#: (:attr:`StepBudget.contact_scale`) plus :data:`CONTACT_FLOOR`: the round-off of the
#: per-node differences ½ m (v_after − v_before)·(v_after + v_before) is ~1e-16 of it.
CONTACT_ROUNDOFF = 1e-12

#: The absolute floor of the contact work's scale, J: the smallest normal double, only so
#: that a step whose contact nodes hold no kinetic energy (nothing to change: its contact
#: work is exactly 0) has a positive scale.
CONTACT_FLOOR = float(np.finfo(float).tiny)

#: The largest ``numerical_work`` allowed in a friction run with gravity, as a fraction of
#: gravity's work W_g = −Π (one-sided: energy created; a loss is not judged).
NUMERICAL_BOUND = 0.01

#: The ratio numerical_work / W_g is judged at the steps where gravity's work W_g exceeds
#: this fraction of the run's energy scale S so far (:class:`EnergyLog`): where gravity is
#: a main source of the run's energy. A body released at rest has W_g ≈ S/2 from its
#: first step; a block launched on a level floor has W_g ≤ 1e-3 S (gravity does no work
#: there, and the ratio swings by ±3 with the numerical work of its elastic ringing).
GRAVITY_JUDGED = 0.1

#: The judged ratios are kept per bin of W_g, bins a factor 1 + GRAVITY_BIN wide: a step
#: counts once W_g is at least :data:`GRAVITY_JUDGED` of its largest over the run (the
#: start of a gravity ramp, where gravity has done a few millijoules and the scheme's
#: start-up a few microjoules, is not judged against the run's gravity), to within this
#: relative width at that threshold; the bins below it are dropped (at most
#: log(1/GRAVITY_JUDGED) / log(1 + GRAVITY_BIN) ≈ 232 kept, for checkpoints).
GRAVITY_BIN = 0.01


def stored(
    stress: np.ndarray, stress_zz: np.ndarray, volume: np.ndarray, *, E: float, nu: float
) -> np.ndarray:
    """½ V σ : D⁻¹ : σ per particle, shape=(n,).

    Args:
        stress: shape=(n, dim, dim).
        stress_zz: the plane-strain σ_zz (2D; ignored otherwise), shape=(n,).
        volume: shape=(n,).
        E: Young's modulus.
        nu: Poisson's ratio (unused in 1D).
    """
    if stress.shape[1] == 1:
        return 0.5 * volume * stress[:, 0, 0] ** 2 / E
    tr = np.trace(stress, axis1=1, axis2=2)
    ss = np.sum(stress * stress, axis=(1, 2))
    if stress.shape[1] == 2:
        tr, ss = tr + stress_zz, ss + stress_zz**2
    return 0.5 * volume * ((1 + nu) * ss - nu * tr**2) / E


def owned_nodes(domain: Any, num_nodes: int) -> np.ndarray | None:
    """Which of a rank's local nodes it owns (each global node once), shape=(N,) bool.

    None without a domain (one process owns every node). A node plane j (along axis 0)
    belongs to the rank whose slab starts at or below it; the last plane to the last rank.
    """
    if domain is None:
        return None
    r = domain.rank
    a = int(domain.planes[r][0])
    per = num_nodes // (int(domain.planes[r][1]) - a + 1)
    j = a + np.arange(num_nodes) // per
    lo, hi = int(domain.cuts[r]), int(domain.cuts[r + 1])
    last = r == len(domain.cuts) - 2
    return (j >= lo) & ((j < hi) | (last & (j == hi)))


@dataclass
class StepBudget:
    """One step's work terms on this rank (see the module docstring); zero at creation.

    Attributes:
        internal: W_int, the internal forces' work on v*.
        gravity_grid: W_g, gravity's work on v*.
        wall: the held components' reactions' work on v*.
        friction: the frictional reactions' work on v*.
        transfer: K_tr, Σ ½ m_p |δv_p|².
        power_raw: P_raw, Σ V σ : Δε of the raw increments.
        smoothing: Σ V σ : (Δε̃ − Δε), the smoothing's stress work.
        quadratic: Q, Σ ½ V (σ^{k+1} − σ^k) : Δε̃.
        plastic: the plastic dissipation (≥ 0).
        potential: ΔΠ of the particles' motion.
        damping: the energy the local damping took out (≥ 0).
        contact: the contact's work at its own velocities (a diagnostic outside the
            budget's identity, ≤ 0 up to round-off): Σ ½ m_i (|v_after|² − |v_before|²)
            over the owned contact nodes, for the contact on the mapped and on the
            updated nodal velocity (:meth:`contact_terms`).
        contact_scale: Σ ½ m_i |v_before|² over the same nodes and applications, the
            scale of the contact work's round-off (:data:`CONTACT_ROUNDOFF`).
    """

    internal: float = 0.0
    gravity_grid: float = 0.0
    wall: float = 0.0
    friction: float = 0.0
    transfer: float = 0.0
    power_raw: float = 0.0
    smoothing: float = 0.0
    quadratic: float = 0.0
    plastic: float = 0.0
    potential: float = 0.0
    damping: float = 0.0
    contact: float = 0.0
    contact_scale: float = 0.0

    def numerical(self) -> float:
        """K_tr + (P_raw + Q + W_int) + (W_g + ΔΠ): the time-integration and transfer error."""
        return (
            self.transfer
            + (self.power_raw + self.quadratic + self.internal)
            + (self.gravity_grid + self.potential)
        )

    def stored(self) -> float:
        """ΔW, the change of the stored energy: P_raw + smoothing + Q − plastic."""
        return self.power_raw + self.smoothing + self.quadratic - self.plastic

    def terms(self) -> np.ndarray:
        """Every field, in declaration order, shape=(13,) (for a sum over the ranks)."""
        return np.array([getattr(self, f.name) for f in fields(self)])

    def grid_terms(
        self,
        dt: float,
        *,
        mass: np.ndarray,
        mom: np.ndarray,
        f: np.ndarray,
        a: np.ndarray,
        fixed: np.ndarray,
        gravity_force: np.ndarray,
        floor: float,
        owned: np.ndarray | None,
        damping: np.ndarray | None = None,
    ) -> None:
        """Add W_int, W_g, wall, friction and damping work of the step's grid update.

        Args:
            dt: time step.
            mass: nodal mass, shape=(N,).
            mom: nodal momentum of the particles, shape=(N, dim).
            f: total nodal force (internal + gravity, no damping), shape=(N, dim).
            a: the nodal acceleration the particles take, shape=(N, dim).
            fixed: held components, shape=(N, dim) bool.
            gravity_force: Σ_p m_p b φ_ip, shape=(N, dim).
            floor: the active-node mass threshold.
            owned: the nodes this rank counts (None: all).
            damping: the local damping force d_i (zero on held components), shape=(N,
                dim); None: no damping.
        """
        active = mass > floor
        if owned is not None:
            active = active & owned
        vs = np.zeros_like(mom)
        vs[active] = mom[active] / mass[active, None]
        reaction = mass[:, None] * a - f
        if damping is not None:
            reaction -= damping
            self.damping -= dt * float(np.sum(damping * vs))
        reaction[~active] = 0.0
        rv = reaction * vs
        self.wall += dt * float(np.sum(rv[fixed]))
        self.friction += dt * float(np.sum(rv[~fixed]))
        self.gravity_grid += dt * float(np.sum(gravity_force * vs))
        self.internal += dt * float(np.sum((f - gravity_force) * vs))

    def contact_terms(
        self,
        *,
        before: np.ndarray,
        after: np.ndarray,
        mass: np.ndarray,
        nodes: np.ndarray,
        owned: np.ndarray | None,
    ) -> None:
        """Add one application of the contact: its work and scale on the owned contact nodes.

        Args:
            before: the nodal velocity before the contact, shape=(N, dim).
            after: after it, shape=(N, dim).
            mass: nodal mass, shape=(N,).
            nodes: the contact's rows' nodes (a corner node repeats), shape=(k,).
            owned: the nodes this rank counts (None: all).
        """
        ids = np.unique(nodes)
        if owned is not None:
            ids = ids[owned[ids]]
        m, v0, v1 = mass[ids], before[ids], after[ids]
        # ½ m (v1 − v0)·(v1 + v0): the difference per node, not of two sums (round-off)
        self.contact += 0.5 * float(m @ np.sum((v1 - v0) * (v1 + v0), axis=1))
        self.contact_scale += 0.5 * float(m @ np.sum(v0 * v0, axis=1))


@dataclass
class Budget:
    """Cumulative budget terms of a run (energy added since t = 0) and the stored energy W.

    Attributes:
        stored_work: W, the initial ½ V σ : D⁻¹ : σ plus Σ ΔW.
        wall_work: Σ wall.
        friction_work: Σ friction.
        smoothing_work: Σ smoothing.
        plastic_dissipation: Σ plastic (energy removed).
        damping_dissipation: Σ damping (energy removed).
        numerical_work: Σ numerical.
    """

    stored_work: float = 0.0
    wall_work: float = 0.0
    friction_work: float = 0.0
    smoothing_work: float = 0.0
    plastic_dissipation: float = 0.0
    damping_dissipation: float = 0.0
    numerical_work: float = 0.0

    def add(self, terms: np.ndarray) -> StepBudget:
        """Add one step's :meth:`StepBudget.terms` (summed over the ranks); returns the step's."""
        s = StepBudget(*(float(t) for t in terms))
        self.stored_work += s.stored()
        self.wall_work += s.wall
        self.friction_work += s.friction
        self.smoothing_work += s.smoothing
        self.plastic_dissipation += s.plastic
        self.damping_dissipation += s.damping
        self.numerical_work += s.numerical()
        return s

    def row(self) -> list[float]:
        """The values of :data:`COLUMNS`."""
        return [getattr(self, c) for c in COLUMNS]

    def explained(self) -> float:
        """E_W(t) − E_W(0) from the terms.

        wall + friction + smoothing − plastic − damping + numerical.
        """
        return (
            self.wall_work
            + self.friction_work
            + self.smoothing_work
            - self.plastic_dissipation
            - self.damping_dissipation
            + self.numerical_work
        )

    def physical(self) -> float:
        """The terms a physical process explains: friction − plastic − damping."""
        return self.friction_work - self.plastic_dissipation - self.damping_dissipation


#: Every column of ``energies.csv`` (docs/output.md).
CSV_COLUMNS = (
    "step",
    "t",
    "kinetic",
    "strain",
    "gravity",
    "total",
    "dissipated",
    *COLUMNS,
    "total_work",
    "closure",
)


class EnergyLog:
    """The energies of a run, step by step, and the summary's measures of their error.

    One instance serves the MPM driver (``energies.csv``, ``summary.json``) and the
    translating-bar bench alike, so both report the same numbers for the same run.

    Measures (E₀ = K + U at t = 0; gravity Π relative to its start, :meth:`potential`):

    - ``drift_max`` = max |K + U + Π − E₀| / E₀ (``energy_drift_max``; None when E₀ = 0);
    - ``drift_work_max`` = max |K + W + Π − E₀| / E₀, the same with the stored energy W;
    - ``balance_error`` = max |K + W + Π − E₀ − friction + plastic + damping| / S with the
      scale S = max over time of K + W + |Π| (t = 0 included): the energy no physical
      term explains (walls, smoothing, time integration), meaningful for a body starting
      at rest (S > 0 once anything moves); None while S = 0;
    - ``closure_max``: the largest |K + W + Π − E₀ − (terms)|, round-off.

    The contact's invariant (docs/mpm_energy.md, "The contact's invariant"), judged by
    :meth:`invariant`:

    - ``contact_max``: the largest per-step contact work (:attr:`StepBudget.contact`, J;
      None before the first step), ``contact_relative_max`` the largest of it over its
      scale (``contact_scale`` + :data:`CONTACT_FLOOR`), ``contact_positive`` the
      number of steps where that exceeds :data:`CONTACT_ROUNDOFF`, ``contact_total`` the
      sum over the steps;
    - ``gravity_ratio``: ``numerical_work`` / W_g at the last step, W_g = −Π the work
      gravity did, and ``gravity_ratio_max`` its largest (signed) value over the steps,
      each taken only where W_g > :data:`GRAVITY_JUDGED` × S (None where not) and, for
      the largest, W_g at least :data:`GRAVITY_JUDGED` of its largest over the run
      (:data:`GRAVITY_BIN`).
    """

    def __init__(self, kinetic: float, strain: float, potential: float = 0.0) -> None:
        """Start at t = 0 with the initial kinetic and stored energies (Π = 0).

        ``potential``: −Σ m b·x at t = 0 with the full gravity b (:meth:`potential`).
        """
        self.e0 = kinetic + strain
        self.u0 = self.last_potential = potential
        self.ramp_offset = 0.0
        self.budget = Budget(stored_work=strain)
        self.drift = 0.0
        self.drift_work = 0.0
        self.unexplained = 0.0
        self.scale = kinetic + strain
        self.closure = 0.0
        self.contact_max: float | None = None
        self.contact_relative_max: float | None = None
        self.contact_positive = 0
        self.contact_total = 0.0
        self.gravity_ratio: float | None = None
        self.gravity_work_max = 0.0
        self.gravity_bins: dict[int, float] = {}  # bin of W_g -> largest judged ratio

    def potential(self, potential: float, factor: float = 1.0) -> float:
        """Π after a step, relative to t = 0: the work gravity did against the motion.

        Args:
            potential: −Σ m b·x after the step, with the full gravity b.
            factor: the step's gravity over the full one (< 1 during ``[gravity] ramp``).

        Returns:
            Σ_k factor_k (P_k − P_{k−1}) (P = ``potential``): the −Σ m b_k·Δx of every
            step with its own gravity b_k, as the budget's ΔΠ; without a ramp exactly
            P_k − P_0.
        """
        if factor != 1.0:
            self.ramp_offset += (factor - 1.0) * (potential - self.last_potential)
        self.last_potential = potential
        return potential - self.u0 + self.ramp_offset

    def record(
        self, kinetic: float, strain: float, gravity: float, *, terms: np.ndarray
    ) -> list[float]:
        """Add a step: its energies (Π relative to t = 0) and its :class:`StepBudget` terms.

        Returns:
            The row of ``energies.csv`` after ``step`` and ``t``.
        """
        b = self.budget
        self._contact(b.add(terms))
        total = kinetic + strain + gravity
        total_work = kinetic + b.stored_work + gravity
        closure = total_work - self.e0 - b.explained()
        self.drift = max(self.drift, abs(total - self.e0))
        self.drift_work = max(self.drift_work, abs(total_work - self.e0))
        self.unexplained = max(
            self.unexplained,
            abs(total_work - self.e0 - b.physical()),
        )
        self.scale = max(self.scale, kinetic + b.stored_work + abs(gravity))
        self.closure = max(self.closure, abs(closure))
        self._gravity(-gravity)
        return [kinetic, strain, gravity, total, self.e0 - total, *b.row(), total_work, closure]

    def _contact(self, s: StepBudget) -> None:
        """Track the step's contact work (:attr:`StepBudget.contact`)."""
        relative = s.contact / (s.contact_scale + CONTACT_FLOOR)
        self.contact_max = (
            s.contact if self.contact_max is None else max(self.contact_max, s.contact)
        )
        self.contact_relative_max = (
            relative
            if self.contact_relative_max is None
            else max(self.contact_relative_max, relative)
        )
        self.contact_positive += int(relative > CONTACT_ROUNDOFF)
        self.contact_total += s.contact

    def _gravity(self, work: float) -> None:
        """Track numerical_work / W_g once gravity's work W_g is judged (GRAVITY_JUDGED)."""
        if not (work > GRAVITY_JUDGED * self.scale and work > 0):
            self.gravity_ratio = None
            return
        self.gravity_ratio = ratio = self.budget.numerical_work / work
        self.gravity_work_max = max(self.gravity_work_max, work)
        b = _gravity_bin(work)
        self.gravity_bins[b] = max(ratio, self.gravity_bins.get(b, ratio))
        low = _gravity_bin(GRAVITY_JUDGED * self.gravity_work_max)
        for old in [k for k in self.gravity_bins if k < low]:  # never judged again
            del self.gravity_bins[old]

    @property
    def gravity_ratio_max(self) -> float | None:
        """The largest judged ratio where W_g >= GRAVITY_JUDGED × its largest; or None."""
        if not self.gravity_bins:
            return None
        low = _gravity_bin(GRAVITY_JUDGED * self.gravity_work_max)
        judged = [r for b, r in self.gravity_bins.items() if b >= low]
        return max(judged) if judged else None

    def invariant(self, *, contact: bool, gravity: bool) -> tuple[str | None, list[str]]:
        """The contact's invariant: its verdict and a warning line per broken bound.

        Args:
            contact: the run has a contact (friction): judge its per-step work.
            gravity: it also has gravity: judge ``numerical_work`` against W_g.

        Returns:
            (None when nothing is judged, "ok", or the broken bounds in short, joined by
            "; "; the warnings, one line each).
        """
        if not contact:
            return None, []
        broken, lines = [], []
        if self.contact_positive:
            broken.append(f"contact work > 0 in {self.contact_positive} step(s)")
            lines.append(
                f"warning: the contact created energy in {self.contact_positive} step(s), up "
                f"to {self.contact_max:.3g} J = {self.contact_relative_max:.3g} of the "
                f"contact nodes' kinetic energy (bound {CONTACT_ROUNDOFF:g}, round-off; "
                "docs/mpm_energy.md)"
            )
        ratio = self.gravity_ratio_max
        if gravity and ratio is not None and ratio > NUMERICAL_BOUND:
            broken.append(f"numerical work {100 * ratio:+.3g} % of gravity work")
            lines.append(
                f"warning: numerical work {100 * ratio:+.3g} % of the gravity work (bound "
                f"{100 * NUMERICAL_BOUND:g} %): the scheme created energy (docs/mpm_energy.md)"
            )
        return ("; ".join(broken) if broken else "ok"), lines

    def first_row(self) -> list[float]:
        """The row of t = 0."""
        e0 = self.e0
        return [e0 - self.budget.stored_work, self.budget.stored_work, 0.0, e0, 0.0,
                *self.budget.row(), e0, 0.0]  # fmt: skip

    @property
    def drift_max(self) -> float | None:
        """Max |K + U + Π − E₀| / E₀, None when E₀ = 0."""
        return self.drift / self.e0 if self.e0 > 0 else None

    @property
    def drift_work_max(self) -> float | None:
        """Max |K + W + Π − E₀| / E₀, None when E₀ = 0."""
        return self.drift_work / self.e0 if self.e0 > 0 else None

    @property
    def balance_error(self) -> float | None:
        """Max |K + W + Π − E₀ − friction + plastic + damping| / S, None while S = 0."""
        return self.unexplained / self.scale if self.scale > 0 else None

    def state(self) -> dict[str, Any]:
        """Everything needed to continue (a checkpoint's part)."""
        return {
            "e0": self.e0,
            "budget": [getattr(self.budget, f.name) for f in fields(Budget)],
            "maxima": [self.drift, self.drift_work, self.unexplained, self.scale, self.closure],
            "gravity": [self.u0, self.last_potential, self.ramp_offset],
            "contact": [
                self.contact_max,
                self.contact_relative_max,
                self.contact_positive,
                self.contact_total,
                self.gravity_ratio,
                self.gravity_work_max,
                sorted(self.gravity_bins.items()),
            ],
        }

    @classmethod
    def from_state(cls, state: dict[str, Any]) -> EnergyLog:
        """The log of :meth:`state`."""
        log = cls(0.0, 0.0)
        log.e0 = float(state["e0"])
        log.budget = Budget(*(float(v) for v in state["budget"]))
        log.drift, log.drift_work, log.unexplained, log.scale, log.closure = (
            float(v) for v in state["maxima"]
        )
        log.u0, log.last_potential, log.ramp_offset = (float(v) for v in state["gravity"])
        # a checkpoint written before the contact's invariant has no "contact": its
        # steps so far are not judged (the measures start at the resume)
        c = state.get("contact", [None, None, 0, 0.0, None, 0.0, []])
        log.contact_max, log.contact_relative_max, log.gravity_ratio = (
            None if v is None else float(v) for v in (c[0], c[1], c[4])
        )
        log.contact_positive, log.contact_total = int(c[2]), float(c[3])
        if len(c) == 7:  # the binned ratios (older checkpoints: judged from the resume on)
            log.gravity_work_max = float(c[5])
            log.gravity_bins = {int(b): float(r) for b, r in c[6]}
        return log


def _gravity_bin(work: float) -> int:
    """The bin of gravity's work W_g > 0 (:data:`GRAVITY_BIN`)."""
    return int(np.floor(np.log(work) / np.log1p(GRAVITY_BIN)))
