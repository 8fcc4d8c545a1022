"""Free-mesh stiffness of any registered element, as its own elastic problem assembles it."""

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import ufl
from mpi4py import MPI

from geofrac import elements
from geofrac.elements.base import Element
from geofrac.materials import d_matrix, lame
from geofrac.solvers import assemble_matrix
from geofrac_forms.elasticity import stiffness_form
from geofrac_forms.gradient_dofs import penalty_forms

E_MOD, NU = 1000.0, 0.3


def distorted_mesh(dim: int, cells: tuple[int, ...] | None = None) -> dolfinx.mesh.Mesh:
    """A small free mesh on one rank, distorted so that no symmetry hides a mode.

    ``cells``: cells per side (default (3, 2) in 2D, (2, 1, 1) in 3D).
    """
    if dim == 2:
        mesh = dolfinx.mesh.create_unit_square(MPI.COMM_SELF, *(cells or (3, 2)))
    else:
        mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, *(cells or (2, 1, 1)))
    x = mesh.geometry.x
    x[:, :dim] += 0.1 * np.sin(5.0 * x[:, :dim] + 3.0 * x[:, ::-1][:, :dim])
    return mesh


def _dense(M) -> np.ndarray:
    D = M.convert("dense")
    out = D.getDenseArray().copy()
    D.destroy()
    return out


def free_stiffness(
    name: str, mesh: dolfinx.mesh.Mesh, alpha: float | None = None
) -> tuple[np.ndarray, Element]:
    """Dense stiffness of element ``name`` on ``mesh``, without Dirichlet rows.

    E = 1000, ν = 0.3, plane stress in 2D; on the element's unknowns. The route follows
    the element's spec: the EFMM patch stiffness (``hold == "nodes"``), the vertex-DOF
    reduction with the zero-mode penalty α (``kinematics``; default α the spec's), or the
    plain UFL stiffness.

    Returns:
        (K shape=(num_dofs, num_dofs), element); the caller destroys the element.
    """
    spec = elements.get(name)
    dim = mesh.geometry.dim
    element = spec.build(mesh)
    if spec.hold == "nodes":
        element.setup(d_matrix(E_MOD, NU, dim), 0.0, seed=0)
        K = element.stiffness()
        out = _dense(K)
        K.destroy()
        return out, element
    lam, mu = lame(E_MOD, NU, dim)
    u, v = ufl.TrialFunction(element.space), ufl.TestFunction(element.space)
    a = stiffness_form(u, v, lam, mu, 1.0, ufl.dx)
    if spec.kinematics is None:
        A = assemble_matrix(dolfinx.fem.form(a))
        out = _dense(A)
        A.destroy()
        return out, element
    alpha = spec.zero_mode_penalty if alpha is None else alpha
    W = element.unknowns
    g, h = ufl.TrialFunction(W), ufl.TestFunction(W)
    pvv, pwv, pww = penalty_forms(u, v, g, h, element.kind.basis, alpha * mu, ufl.dx)
    mats = [assemble_matrix(dolfinx.fem.form(f)) for f in (a + pvv, pwv, pww)]
    Kp = element.reduce(*mats)
    out = _dense(Kp)
    for M in (*mats, Kp):
        M.destroy()
    return out, element
