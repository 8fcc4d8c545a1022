"""Strain drivers for the plasticity tests: strain paths, a mixed Newton solve, FD tangents.

They call only a law's public ``trial``/``return_map`` and build their own elasticity;
the reference numbers the tests compare with are closed forms written in the tests.
"""

from __future__ import annotations

import numpy as np

from geofrac.plasticity.elasticity import elastic_tangent


def hooke(eps: np.ndarray, E: float, nu: float) -> np.ndarray:
    """σ = λ tr ε I + 2μ ε of strains, shape=(..., 3, 3)."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    tr = np.trace(eps, axis1=-2, axis2=-1)[..., None, None]
    return lam * tr * np.eye(3) + 2 * mu * eps


def symmetric(n: int, scale: float, seed: int) -> np.ndarray:
    """Random symmetric tensors, shape=(n, 3, 3)."""
    a = np.random.default_rng(seed).normal(scale=scale, size=(n, 3, 3))
    return 0.5 * (a + np.swapaxes(a, 1, 2))


def secant(fun, *, scale: float) -> float:
    """Root of an affine function of one variable (the yield function along the flow)."""
    a, b = 0.0, 1e-6 * scale
    fa, fb = fun(a), fun(b)
    for _ in range(5):
        if fb == fa:
            break
        a, fa, b = b, fb, b - fb * (b - a) / (fb - fa)
        fb = fun(b)
    return b


def on_surface(eps: np.ndarray, flow: np.ndarray, f, *, E: float, nu: float) -> np.ndarray:
    """The closed-form plastic point σ = Hooke(ε − γ m) with f(σ) = 0, shape=(3, 3).

    ε the total strain, m the (constant) flow direction, f the test's yield function of
    shape=(n, 3, 3) → (n,). Along these fixed-axis paths f is affine in γ while the
    principal order holds, so the secant from γ = 0 and a small γ finds the root.
    """
    g = secant(lambda gam: f(hooke(eps - gam * flow, E, nu)[None])[0], scale=np.abs(eps).max())
    return hooke(eps - g * flow, E, nu)


def strain_path(law, strains: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drive one point through total strains, shape=(steps, 3, 3), from zero.

    Returns:
        the stresses after each step, shape=(steps, 3, 3), and the return kinds, shape=(steps,).
    """
    stress, eps = np.zeros((1, 3, 3)), np.zeros((1, 3, 3))
    out, kinds = [], []
    for target in strains:
        ret = law.update(stress, target[None] - eps)
        stress, eps = ret.stress, target[None].copy()
        out.append(stress[0])
        kinds.append(ret.kind[0])
    return np.array(out), np.array(kinds)


def fd_tangent(law, trial: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Central differences of the return in the strain, and where the return kind held.

    Args:
        law: a plasticity law.
        trial: elastic trial stresses, shape=(n, 3, 3).
        h: strain step.

    Returns:
        dσ/dε, shape=(n, 3, 3, 3, 3) (symmetric strain perturbations), and a mask,
        shape=(n,), true where both perturbed returns took the same return as the trial.
    """
    kind = law.return_map(trial).kind
    out = np.zeros((len(trial), 3, 3, 3, 3))
    same = np.ones(len(trial), dtype=bool)
    for k in range(3):
        for m in range(3):
            e = np.zeros((3, 3))
            e[k, m] += 0.5 * h
            e[m, k] += 0.5 * h
            dsig = hooke(e, law.E, law.nu)
            plus, minus = law.return_map(trial + dsig), law.return_map(trial - dsig)
            same &= (plus.kind == kind) & (minus.kind == kind)
            out[:, :, :, k, m] = (plus.stress - minus.stress) / (2 * h)
    return out, same


def mixed_newton(
    law,
    eps: np.ndarray,
    *,
    free: list[tuple[int, int]],
    target: np.ndarray,
    stress0: np.ndarray | None = None,
    eps0: np.ndarray | None = None,
    elastic_jacobian: bool = False,
    maxit: int = 30,
    tol: float = 1e-12,
) -> tuple[np.ndarray, np.ndarray, list[float], int]:
    """One strain-driven step with mixed conditions, solved by Newton on the free strains.

    The strain ``eps`` (3×3) is prescribed except the normal components ``free`` (i, i),
    whose stresses must reach ``target`` (shape=(len(free),)). The step starts from
    ``stress0``/``eps0`` (zero by default); the Jacobian is the law's consistent tangent
    (or, with ``elastic_jacobian``, the elastic stiffness: a modified Newton).

    Returns:
        the stress and strain at the end, shapes=(3, 3), the residual norms |σ_free −
        target| of every iteration, and the kinds of the last return.
    """
    stress0 = np.zeros((3, 3)) if stress0 is None else stress0
    eps0 = np.zeros((3, 3)) if eps0 is None else eps0
    eps = eps.copy()
    rows = tuple(np.array(free).T)
    history = []
    for _ in range(maxit):
        ret = law.update(stress0[None], (eps - eps0)[None], tangent=True)
        residual = ret.stress[0][rows] - target
        history.append(float(np.linalg.norm(residual)))
        if history[-1] <= tol:
            break
        D = elastic_tangent(*law.moduli()) if elastic_jacobian else ret.tangent[0]
        J = np.array([[D[a + b] for b in free] for a in free])
        eps[rows] -= np.linalg.solve(J, residual)
    return ret.stress[0], eps, history, int(ret.kind[0])
