"""Blocks of a distributed DOLFINx mesh: the same block set on 1 and N ranks."""

import dolfinx_solver  # noqa: F401

import numpy as np
import pytest
from dolfinx.mesh import CellType, create_unit_cube, create_unit_square
from mpi4py import MPI

from geofrac.blocks.distributed import build_blocks


def _mesh(comm, dim):
    if dim == 2:
        mesh = create_unit_square(comm, 9, 7, CellType.triangle)
    else:
        mesh = create_unit_cube(comm, 5, 4, 4, CellType.tetrahedron)
    x = mesh.geometry.x
    index = np.asarray(mesh.geometry.input_global_indices, dtype=float)
    inside = np.all((x[:, :dim] > 1e-12) & (x[:, :dim] < 1 - 1e-12), axis=1)
    for axis in range(dim):  # a distortion that depends only on the input node
        x[inside, axis] += 0.03 * np.sin(1.7 * index[inside] + axis)
    return mesh


def _measures(blocks):
    """Per block: id, number of faces, volume (area), seed, sorted by id, shape=(n, 3 + dim)."""
    p = blocks.points
    if blocks.dim == 3:
        q = p[blocks.faces]
        face = (
            np.einsum("ij,ij->i", q[:, 0], np.cross(q[:, 1], q[:, 2]))
            + np.einsum("ij,ij->i", q[:, 0], np.cross(q[:, 2], q[:, 3]))
        ) / 6
    else:
        ring = blocks.faces[:, 0]
        nxt = np.arange(len(ring)) + 1
        nxt[blocks.face_offsets[1:] - 1] = blocks.face_offsets[:-1]
        face = 0.5 * (p[ring, 0] * p[ring[nxt], 1] - p[ring[nxt], 0] * p[ring, 1])
    volume = np.add.reduceat(face, blocks.face_offsets[:-1])
    return np.column_stack([blocks.ids, np.diff(blocks.face_offsets), volume, blocks.seeds])


@pytest.mark.parametrize("dim", [2, 3])
def test_blocks_on_one_rank_fill_the_domain(dim):
    blocks = build_blocks(_mesh(MPI.COMM_SELF, dim), inner="random", seed=2)
    m = _measures(blocks)
    assert abs(m[:, 2].sum() - 1.0) < 1e-12
    assert m[:, 2].min() > 0


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("dim", [2, 3])
def test_blocks_are_the_same_on_one_and_n_ranks(dim):
    comm = MPI.COMM_WORLD
    blocks = build_blocks(_mesh(comm, dim), inner="random", seed=2)
    assert comm.allreduce(blocks.num_blocks) == (10 * 8 if dim == 2 else 6 * 5 * 5)
    gathered = comm.allgather(_measures(blocks))
    distributed = np.concatenate(gathered)
    distributed = distributed[np.argsort(distributed[:, 0])]
    serial = _measures(build_blocks(_mesh(MPI.COMM_SELF, dim), inner="random", seed=2))
    np.testing.assert_array_equal(distributed[:, :2], serial[:, :2])  # ids, face counts
    np.testing.assert_allclose(distributed[:, 2:], serial[:, 2:], rtol=1e-13, atol=1e-16)
    assert all(len(g) for g in gathered)  # every rank built some
