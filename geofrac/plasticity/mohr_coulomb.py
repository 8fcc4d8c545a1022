"""Mohr-Coulomb perfect plasticity with a tension cut-off: return mapping and tangent.

Tension positive, principal stresses σ₁ ≥ σ₂ ≥ σ₃. In this sector the surfaces are
planes in principal stress space (de Souza Neto, Perić and Owen (2008), 8.2):

- main plane f = (σ₁ − σ₃) + (σ₁ + σ₃) sin φ − 2c cos φ, and the two planes that meet it
  at the edges: σ₂ = σ₃ (extension meridian, ``(σ₁ − σ₂) + (σ₁ + σ₂) sin φ``) and
  σ₁ = σ₂ (compression meridian, ``(σ₂ − σ₃) + (σ₂ + σ₃) sin φ``);
- the tension cut-off σᵢ − T ≤ 0 (Rankine, associated flow), 0 <= T <= c cot φ, when
  ``tension`` is given.

Flow is non-associated: each shear plane's potential has the dilatancy angle ψ in place
of φ (flow vector (1 + sin ψ, 0, −(1 − sin ψ)) for the main plane), ψ = 0 keeping the
plastic volume on the planes and edges. Because surfaces and flow vectors are constant in
principal space and the elasticity is isotropic (D = λ 1⊗1 + 2G I there), the return to
a set S of active surfaces is linear: with the trial σ* (principal directions kept),

    Δγ_S = M_S⁻¹ f_S(σ*),  M_ij = aᵢ·D nⱼ,  σ = σ* − Σⱼ Δγⱼ D nⱼ,

and the candidate sets are tried in the order main plane, tension plane, the two edges,
the line where the main plane meets σ₁ = T, the tension edge σ₁ = σ₂ = T; the first with
Δγ >= 0, the principal order kept and every surface satisfied is taken (the order of
de Souza Neto et al., Box 8.5, with the tension cut-off added). Otherwise the stress
goes to a fixed point: a corner of the cut-off (σ₁ = T with σ₂ = σ₃ on the main plane,
or σ₁ = σ₂ = T), its vertex σ = T I, or the apex σ = c cot φ I, the first whose normal
cone holds σ* − σ (Δγ >= 0 on three of its flow vectors); if none does (ψ = 0 at the apex,
where the flow vectors span no volume change) the vertex of the surface. At fixed points
the multipliers are not given by the flow rule and are reported as zero; the plastic
strain increment C⁻¹:(σ* − σ) is exact at every return.

Consistent tangent (de Souza Neto et al., A.5, isotropic tensor functions): with the
principal Jacobian J = ∂σᵢ/∂σ*ⱼ (I − D N_Sᵀ M_S⁻¹ A_S for a set S, 0 at fixed points)
and the trial's principal directions vᵢ, Eᵢⱼ = vᵢ⊗vⱼ,

    D_alg = Σᵢⱼ (J D)ᵢⱼ Eᵢᵢ⊗Eⱼⱼ + Σ_{i≠j} G θᵢⱼ Eᵢⱼ⊗(Eᵢⱼ + Eⱼᵢ),
    θᵢⱼ = (σᵢ − σⱼ)/(σ*ᵢ − σ*ⱼ)

(θᵢⱼ = ½(Jᵢᵢ − Jᵢⱼ − Jⱼᵢ + Jⱼⱼ), its limit, where σ*ᵢ = σ*ⱼ).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from geofrac.plasticity.elasticity import ElasticTrial, compliance
from geofrac.plasticity.invariants import principal
from geofrac.plasticity.returns import (
    APEX,
    EDGE_COMPRESSION,
    EDGE_EXTENSION,
    SMOOTH,
    TENSION,
    TENSION_APEX,
    TENSION_CORNER,
    TENSION_EDGE,
    TENSION_SHEAR,
    Return,
)

__all__ = ["MohrCoulomb"]

#: Relative tolerance (of the stress scale) of the checks that accept a return.
ACCEPT = 1e-12
#: The candidate sets of active surfaces (indices into ``MohrCoulomb.SURFACES``).
CANDIDATES = (
    (SMOOTH, (0,)),
    (TENSION, (3,)),
    (EDGE_EXTENSION, (0, 1)),
    (EDGE_COMPRESSION, (0, 2)),
    (TENSION_SHEAR, (0, 3)),
    (TENSION_EDGE, (3, 4)),
)


@dataclass(frozen=True)
class MohrCoulomb(ElasticTrial):
    """Mohr-Coulomb material with a tension cut-off (isotropic elasticity, perfect plasticity).

    Attributes:
        E: Young's modulus.
        nu: Poisson's ratio.
        friction_angle: φ in degrees (0 <= φ < 90; 0 is Tresca).
        cohesion: c (>= 0).
        dilatancy_angle: ψ in degrees (0 <= ψ <= φ).
        tension: the tensile strength T of the cut-off, 0 <= T <= c cot φ, or None (no
            cut-off).
    """

    #: The multiplier columns: the main plane, the planes of the two edges, the cut-offs.
    SURFACES: ClassVar[tuple[str, ...]] = (
        "main",
        "extension",
        "compression",
        "tension_1",
        "tension_2",
        "tension_3",
    )

    E: float
    nu: float
    friction_angle: float
    cohesion: float = 0.0
    dilatancy_angle: float = 0.0
    tension: float | None = None

    def __post_init__(self) -> None:
        """Check the parameters."""
        self.check_common()
        if self.tension is not None and not 0 <= self.tension <= self.apex_stress():
            raise ValueError(
                f"tension must lie in [0, c cot phi = {self.apex_stress()}], got {self.tension}"
            )

    def apex_stress(self) -> float:
        """The apex stress c cot φ, the hydrostatic stress of the apex (inf for φ = 0)."""
        if self.friction_angle == 0:
            return float("inf")
        return float(self.cohesion / np.tan(np.radians(self.friction_angle)))

    def planes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The surfaces in the sorted principal sector.

        Returns:
            normals aᵢ, shape=(6, 3), offsets rᵢ, shape=(6,) (fᵢ = aᵢ·σ − rᵢ), and flow
            vectors nᵢ, shape=(6, 3), in :attr:`SURFACES` order (the cut-offs with
            offset T, or inf without a cut-off).
        """
        sf, cf = np.sin(np.radians(self.friction_angle)), np.cos(np.radians(self.friction_angle))
        sp = np.sin(np.radians(self.dilatancy_angle))

        def shear(s: float) -> np.ndarray:
            return np.array(
                [[1 + s, 0, -(1 - s)], [1 + s, -(1 - s), 0], [0, 1 + s, -(1 - s)]], dtype=float
            )

        eye = np.eye(3)
        t = np.inf if self.tension is None else self.tension
        offsets = np.array([2 * self.cohesion * cf] * 3 + [t] * 3)
        return np.vstack([shear(sf), eye]), offsets, np.vstack([shear(sp), eye])

    def principal_stiffness(self) -> np.ndarray:
        """D = λ 1⊗1 + 2G I in principal space, shape=(3, 3)."""
        K, G = self.moduli()
        return (K - 2 * G / 3) * np.ones((3, 3)) + 2 * G * np.eye(3)

    def yield_function(self, stress: np.ndarray) -> np.ndarray:
        """max(main plane, σ₁ − T) of each stress, shape=(n, 3, 3) → shape=(n,)."""
        return self._sector_yield(np.linalg.eigvalsh(stress)[:, ::-1])

    def _sector_yield(self, p: np.ndarray) -> np.ndarray:
        """The yield function of sorted principal stresses, shape=(n, 3) → shape=(n,)."""
        A, r, _ = self.planes()
        f = p @ A[0] - r[0]
        if self.tension is not None:
            f = np.maximum(f, p[:, 0] - self.tension)
        return f

    def return_map(self, trial: np.ndarray, *, tangent: bool = False) -> Return:
        """Return mapping of elastic trial stresses (the module docstring).

        Args:
            trial: elastic trial stresses, shape=(n, 3, 3).
            tangent: also compute the consistent tangent, shape=(n, 3, 3, 3, 3).

        Returns:
            The :class:`~geofrac.plasticity.returns.Return`; multipliers shape=(n, 6).
        """
        K, G = self.moduli()
        n = len(trial)
        star, V = principal(trial)
        plastic = self._sector_yield(star) > 0
        sigma, gamma = star.copy(), np.zeros((n, 6))
        kind = np.zeros(n, dtype=np.int8)
        jac = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
        if np.any(plastic):
            s, g, k, j = self._return_principal(star[plastic])
            sigma[plastic], gamma[plastic], kind[plastic], jac[plastic] = s, g, k, j
        new = trial.copy()  # elastic points keep the trial exactly
        new[plastic] = np.einsum("nik,nk,njk->nij", V[plastic], sigma[plastic], V[plastic])
        return Return(
            stress=new,
            multipliers=gamma,
            plastic_strain=compliance(trial - new, K, G),
            kind=kind,
            tangent=self._tangent(star, sigma, V, jac) if tangent else None,
        )

    def _accept(self, star: np.ndarray, s: np.ndarray, g: np.ndarray) -> np.ndarray:
        """Which returns are admissible: Δγ >= 0, order kept, every surface met, shape=(m,)."""
        _, G = self.moduli()
        tol = ACCEPT * np.maximum(np.abs(star).max(axis=1), self.cohesion + 1e-300)
        ok = np.all(G * g >= -tol[:, None], axis=1)
        ok &= (s[:, 0] - s[:, 1] >= -tol) & (s[:, 1] - s[:, 2] >= -tol)
        return ok & (self._sector_yield(s) <= tol)

    def _fixed_points(self) -> list[tuple[int, np.ndarray, tuple[tuple[int, ...], ...]]]:
        """(kind, principal stress, flow subsets) of the corners, vertex and apex."""
        sf, cf = np.sin(np.radians(self.friction_angle)), np.cos(np.radians(self.friction_angle))
        out: list[tuple[int, np.ndarray, tuple[tuple[int, ...], ...]]] = []
        if self.tension is not None:
            T = self.tension
            low = (T * (1 + sf) - 2 * self.cohesion * cf) / (1 - sf)
            out.append((TENSION_CORNER, np.array([T, low, low]), ((0, 1, 3),)))
            subsets = ((0, 3, 4), (2, 3, 4), (0, 2, 3), (0, 2, 4))
            out.append((TENSION_CORNER, np.array([T, T, low]), subsets))
            out.append((TENSION_APEX, np.full(3, T), ((3, 4, 5),)))
        elif self.friction_angle > 0:
            out.append((APEX, np.full(3, self.apex_stress()), ((0, 1, 2),)))
        return out

    def _return_principal(
        self, star: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Returns of plastic trials in principal space.

        Args:
            star: sorted principal trial stresses, shape=(m, 3).

        Returns:
            principal stresses, shape=(m, 3); multipliers, shape=(m, 6); kinds, shape=(m,);
            the principal Jacobians ∂σ/∂σ*, shape=(m, 3, 3).
        """
        A, r, N = self.planes()
        D = self.principal_stiffness()
        m = len(star)
        sigma, gamma = np.zeros((m, 3)), np.zeros((m, 6))
        kind, jac = np.zeros(m, dtype=np.int8), np.zeros((m, 3, 3))
        todo = np.ones(m, dtype=bool)
        for code, active in CANDIDATES:
            if not np.any(todo) or (self.tension is None and 3 in active):
                continue
            S = list(active)
            DN = N[S] @ D  # rows D nⱼ
            Minv = np.linalg.inv(A[S] @ DN.T)
            g = (star[todo] @ A[S].T - r[S]) @ Minv.T
            s = star[todo] - g @ DN
            full = np.zeros((len(g), 6))
            full[:, S] = g
            ok = self._accept(star[todo], s, full)
            idx = np.flatnonzero(todo)[ok]
            sigma[idx], gamma[idx], kind[idx] = s[ok], full[ok], code
            jac[idx] = np.eye(3) - DN.T @ Minv @ A[S]
            todo[idx] = False
        tol = ACCEPT * np.maximum(np.abs(star).max(axis=1), self.cohesion + 1e-300)
        _, G = self.moduli()
        for code, point, subsets in self._fixed_points():
            for flows in subsets:
                B = (N[list(flows)] @ D).T  # columns D nⱼ
                if not np.any(todo) or abs(np.linalg.det(B)) < 1e-12 * np.abs(D).max() ** 3:
                    continue
                g = (star[todo] - point) @ np.linalg.inv(B).T
                ok = np.all(G * g >= -tol[todo, None], axis=1)
                idx = np.flatnonzero(todo)[ok]
                sigma[idx], kind[idx] = point, code
                todo[idx] = False
        if np.any(todo):  # the vertex: ψ = 0 at the apex
            fixed = self._fixed_points()
            if not fixed:
                raise RuntimeError("Mohr-Coulomb return found no admissible return")
            code, point, _ = fixed[-1]
            sigma[todo], kind[todo] = point, code
        return sigma, gamma, kind, jac

    def _tangent(
        self, star: np.ndarray, sigma: np.ndarray, V: np.ndarray, jac: np.ndarray
    ) -> np.ndarray:
        """The consistent tangent (module docstring), shape=(n, 3, 3, 3, 3).

        Args:
            star: principal trial stresses, shape=(n, 3).
            sigma: principal returned stresses, shape=(n, 3).
            V: principal directions as columns, shape=(n, 3, 3).
            jac: ∂σᵢ/∂σ*ⱼ, shape=(n, 3, 3).
        """
        _, G = self.moduli()
        Q = jac @ self.principal_stiffness()
        theta = np.zeros((len(star), 3, 3))
        scale = np.maximum(np.abs(star).max(axis=1), self.cohesion + 1e-300)
        for i in range(3):
            for j in range(3):
                if i == j:
                    continue
                gap = star[:, i] - star[:, j]
                limit = 0.5 * (jac[:, i, i] - jac[:, i, j] - jac[:, j, i] + jac[:, j, j])
                close = np.abs(gap) <= 1e-10 * scale
                theta[:, i, j] = np.where(
                    close, limit, (sigma[:, i] - sigma[:, j]) / np.where(close, 1.0, gap)
                )
        W = G * theta
        out = np.einsum("nij,nai,nbi,ncj,ndj->nabcd", Q, V, V, V, V, optimize=True)
        out += np.einsum("nij,nai,nbj,nci,ndj->nabcd", W, V, V, V, V, optimize=True)
        out += np.einsum("nij,nai,nbj,ncj,ndi->nabcd", W, V, V, V, V, optimize=True)
        return out
