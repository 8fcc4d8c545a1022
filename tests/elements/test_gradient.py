"""RGNT, GNT and RGNQ on DOLFINx: the vertex-to-P2 map and the zero-energy modes."""

import dolfinx_solver  # noqa: F401

import dolfinx
import dolfinx.fem.petsc
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.elements import GRADIENT_DOF_DEFAULTS, make_element
from geofrac.elements.kinematics import dofs_from_gradient
from geofrac.materials import lame
from geofrac_forms.elasticity import stiffness_form
from geofrac_forms.gradient_dofs import penalty_forms

SELF = MPI.COMM_SELF


def _mesh(dim):
    """A small free mesh, distorted so that no symmetry hides a mode."""
    if dim == 2:
        mesh = dolfinx.mesh.create_unit_square(SELF, 3, 2)
    else:
        mesh = dolfinx.mesh.create_unit_cube(SELF, 2, 1, 1)
    x = mesh.geometry.x
    x[:, :dim] += 0.1 * np.sin(5.0 * x[:, :dim] + 3.0 * x[:, ::-1][:, :dim])
    return mesh


def free_stiffness(name, dim, alpha=None):
    """Dense stiffness of element ``name`` on a free mesh, as the elastic problem builds it.

    Returns:
        (K, element), K shape=(num_dofs, num_dofs).
    """
    mesh = _mesh(dim)
    element = make_element(name, mesh)
    lam, mu = lame(1000.0, 0.3, dim)
    u, v = ufl.TrialFunction(element.space), ufl.TestFunction(element.space)
    a = stiffness_form(u, v, lam, mu, 1.0, ufl.dx)
    if name not in GRADIENT_DOF_DEFAULTS:
        A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(a))
        A.assemble()
        K = A.convert("dense").getDenseArray().copy()
        A.destroy()
        return K, element
    alpha = GRADIENT_DOF_DEFAULTS[name] if alpha is None else alpha
    W = element.unknowns
    g, h = ufl.TrialFunction(W), ufl.TestFunction(W)
    pvv, pwv, pww = penalty_forms(u, v, g, h, element.kind.basis, alpha * mu, ufl.dx)
    mats = [dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(f)) for f in (a + pvv, pwv, pww)]
    for M in mats:
        M.assemble()
    Kp = element.reduce(*mats)
    K = Kp.convert("dense").getDenseArray().copy()
    for M in (*mats, Kp):
        M.destroy()
    return K, element


@pytest.mark.parametrize(
    ("name", "dim"), [("cst", 2), ("p2", 2), ("rgnt", 2), ("gnt", 2), ("p1", 3), ("rgnq", 3)]
)
def test_free_mesh_has_exactly_the_rigid_body_zero_modes(name, dim):
    """3 zero eigenvalues in 2D and 6 in 3D, with the default zero-mode penalty."""
    K, element = free_stiffness(name, dim)
    assert np.allclose(K, K.T, atol=1e-12 * np.abs(K).max())
    eig = np.linalg.eigvalsh(K)
    scale = eig[-1]
    n_rigid = 3 if dim == 2 else 6
    # rigid modes sit at round-off (measured <= 2e-16 λmax); the next eigenvalue, for
    # RGNT/RGNQ the penalised constant-rotation mode of order α μ |Ω| (measured >= 4e-9
    # λmax with α = 1e-6), stands clear above the zero threshold
    assert np.abs(eig[:n_rigid]).max() < 1e-12 * scale
    assert eig[n_rigid] > 1e-10 * scale
    element.destroy()


@pytest.mark.parametrize(("name", "dim"), [("rgnt", 2), ("gnt", 2), ("rgnq", 3)])
def test_rigid_body_modes_are_zero_energy_and_other_modes_are_not(name, dim):
    K, element = free_stiffness(name, dim)
    space = element.unknowns
    ns = element.rigid_body_modes()
    modes = np.array([v.getArray(readonly=True).copy() for v in ns.getVecs()])
    scale = np.abs(K).max()
    assert np.abs(modes @ K).max() < 1e-10 * scale
    # without the penalty the constant extra DOFs are zero-energy too: that is what it removes
    K0, el0 = free_stiffness(name, dim, alpha=1e-300)
    eig = np.linalg.eigvalsh(K0)
    n_spurious = int(np.sum(np.abs(eig) < 1e-12 * eig[-1])) - (3 if dim == 2 else 6)
    assert n_spurious >= len(element.kind.names)
    bs = element.kind.block_size
    constant = np.zeros((space.dofmap.index_map.size_local, bs))
    constant[:, dim:] = 1.0
    assert np.abs(K0 @ constant.ravel()).max() < 1e-10 * scale
    assert constant.ravel() @ K @ constant.ravel() > 0.0
    element.destroy()
    el0.destroy()


def test_rotation_dofs_of_a_rigid_rotation():
    """The near-nullspace rotation carries θ = ½ ω (the DOF value of a linear field)."""
    K, element = free_stiffness("rgnt", 2)
    ns = element.rigid_body_modes()
    x = element.unknowns.tabulate_dof_coordinates()[:, :2]
    w = np.zeros((len(x), 3))
    w[:, 0], w[:, 1] = -x[:, 1], x[:, 0]
    w[:, 2] = dofs_from_gradient(element.kind, np.array([[[0.0, -1.0], [1.0, 0.0]]]))[0]
    basis = np.array([v.getArray(readonly=True).copy() for v in ns.getVecs()])
    coeff, *_ = np.linalg.lstsq(basis.T, w.ravel(), rcond=None)
    assert np.abs(basis.T @ coeff - w.ravel()).max() < 1e-12
    assert np.abs(K @ w.ravel()).max() < 1e-10 * np.abs(K).max()
    element.destroy()
