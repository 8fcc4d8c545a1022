"""UFL forms of the vertex-gradient-DOF elements RGNT, GNT and RGNQ.

The displacement of these elements is a P2 field u = T w fixed by the vertex DOFs w
(see :mod:`geofrac.elements.kinematics`), so their stiffness is the elastic form of
:mod:`geofrac_forms.elasticity` on P2, pulled back by T. What they add is the
Hughes–Brezzi-type penalty that removes their spurious zero-energy modes (a constant
vertex rotation, and for GNT constant vertex strains, move no node):

    Π(w) = α μ t Σ_c |E_c|² ∫ (g_c - d_c(u))² dΩ,    d_c(u) = ½ <E_c, ∇u> / |E_c|²,

with g_c the linear interpolant of the extra vertex DOFs and E_c their basis matrices.
d_c(u) is the DOF value that reproduces a quadratic field (half the rotation or strain),
so Π vanishes on every linear field and on every quadratic field the element reproduces:
the penalty pins the constant modes without polluting the exact solutions. Expanded for
u = T w it is three forms on the P2 space V and the vertex space W:

    a_VV(u, v) = α μ t Σ_c |E_c|² ∫ d_c(u) d_c(v)
    a_WV(u, h) = -α μ t Σ_c |E_c|² ∫ d_c(u) h_c          (trial in V, test in W)
    a_WW(g, h) = α μ t Σ_c |E_c|² ∫ g_c h_c

and K = Tᵀ (K_el + A_VV) T + A_WV T + (A_WV T)ᵀ + A_WW.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import ufl

__all__ = ["dof_of_gradient", "penalty_forms"]


def dof_of_gradient(u: Any, basis_c: np.ndarray) -> Any:
    """d_c(u) = ½ <E_c, ∇u> / |E_c|² for one basis matrix E_c, shape=(gdim, gdim)."""
    E = ufl.as_matrix(basis_c.tolist())
    return 0.5 * ufl.inner(E, ufl.grad(u)) / float(np.sum(basis_c * basis_c))


def penalty_forms(
    u: Any,
    v: Any,
    g: Any,
    h: Any,
    basis: np.ndarray,
    scale: Any,
    dx: Any,
) -> tuple[Any, Any, Any]:
    """The three bilinear forms (a_VV, a_WV, a_WW) of the zero-mode penalty.

    Args:
        u: trial function of the P2 displacement space V.
        v: test function of V.
        g: trial function of the vertex DOF space W (block size gdim + k; components
            gdim, ..., gdim + k - 1 are the extra DOFs).
        h: test function of W.
        basis: the basis matrices E_c, shape=(k, gdim, gdim).
        scale: α μ t (a UFL constant).
        dx: cell measure.
    """
    gdim = basis.shape[1]
    a_vv = a_wv = a_ww = None
    for c, E in enumerate(basis):
        w = scale * float(np.sum(E * E))
        du, dv = dof_of_gradient(u, E), dof_of_gradient(v, E)
        vv = w * du * dv * dx
        wv = -w * du * h[gdim + c] * dx
        ww = w * g[gdim + c] * h[gdim + c] * dx
        a_vv = vv if a_vv is None else a_vv + vv
        a_wv = wv if a_wv is None else a_wv + wv
        a_ww = ww if a_ww is None else a_ww + ww
    return a_vv, a_wv, a_ww
