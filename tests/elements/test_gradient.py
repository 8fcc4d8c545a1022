"""RGNT, GNT and RGNQ on DOLFINx: the vertex-to-P2 map and the zero-energy modes."""

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest

from geofrac.elements import available, get
from geofrac.elements.kinematics import dofs_from_gradient
from tests.elements import helpers


def free_stiffness(name, dim, alpha=None):
    """Dense stiffness of element ``name`` on the distorted free mesh of dimension ``dim``."""
    return helpers.free_stiffness(name, helpers.distorted_mesh(dim), alpha)


@pytest.mark.parametrize(
    ("name", "dim"),
    [(n, d) for n in available() for d in get(n).dims if get(n).kinematics is not None],
)
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
