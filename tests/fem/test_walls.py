"""The facets of an opening's wall integrated on their live side (geofrac/fem/walls.py).

A rectangle [0, 2] × [0, 1] of triangles whose left half is the cell group "hole" and
right half "rock"; the line x = 1 between them is the facet group "wall", inside the
mesh. A stage removes the hole. References are exact: the wall has length 1 and the
rock's outward normal on it is (−1, 0), so ∫ ds = 1, ∫ n ds = (−1, 0) and ∫ y n_x ds =
−1/2 over the wall, once each on any number of ranks. On 2 ranks the cells are
distributed by hand so that the hole is on rank 0 and the rock on rank 1: every wall
facet lies between two ranks (the facet's owner may not hold its live cell), with no
ghost cells (DOLFINx's default) or with the cells beside the wall ghosted on the other
rank; each facet must still be integrated exactly once.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import basix.ufl
import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.walls import facet_measure, live_cells, wall_entities
from geofrac.meshing.distribute import TaggedMesh
from geofrac.model.scene import Load, Material, Stage

HOLE, ROCK, WALL, RIGHT = 1, 2, 3, 4
NX, NY = 4, 2  # squares of the 2 × 1 rectangle, each two triangles


def _grid() -> tuple[np.ndarray, np.ndarray]:
    """The nodes, shape=(m, 2), and triangles, shape=(2 NX NY, 3), of the rectangle."""
    xs, ys = np.linspace(0.0, 2.0, NX + 1), np.linspace(0.0, 1.0, NY + 1)
    x = np.array([(a, b) for b in ys for a in xs])
    cells = []
    for j in range(NY):
        for i in range(NX):
            v = j * (NX + 1) + i
            cells += [[v, v + 1, v + NX + 2], [v, v + NX + 2, v + NX + 1]]
    return x, np.array(cells, dtype=np.int64)


def _mesh(comm: MPI.Comm, *, ghosts: bool) -> TaggedMesh:
    """The rectangle, hole cells on rank 0 and rock cells on the last rank."""
    x, cells = _grid()
    centroid = x[cells].mean(axis=1)[:, 0]

    def partition(comm: Any, n: int, types: Any, local: Any) -> Any:
        mine = np.asarray(local[0]).reshape(-1, 3)
        mid = x[mine].mean(axis=1)[:, 0]
        owner = np.where(mid < 1.0, 0, n - 1)
        near = np.abs(mid - 1.0) < 1.0 / NX  # the cells beside the wall
        dest, offsets = [], [0]
        for k, rank in enumerate(owner):
            dest += [rank] + ([n - 1 - rank] if ghosts and near[k] and n > 1 else [])
            offsets.append(len(dest))
        return dolfinx.graph.adjacencylist(
            np.array(dest, dtype=np.int32), np.array(offsets, dtype=np.int32)
        )._cpp_object

    domain = ufl.Mesh(basix.ufl.element("Lagrange", "triangle", 1, shape=(2,)))
    root = comm.rank == 0
    mesh = dolfinx.mesh.create_mesh(
        comm,
        cells if root else np.empty((0, 3), dtype=np.int64),
        domain,
        x if root else np.empty((0, 2)),
        partition if comm.size > 1 else None,
    )
    assert len(centroid) == comm.allreduce(mesh.topology.index_map(2).size_local)
    tdim = 2
    mesh.topology.create_entities(1)
    n_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    mid = dolfinx.mesh.compute_midpoints(mesh, tdim, np.arange(n_cells, dtype=np.int32))
    cell_tags = dolfinx.mesh.meshtags(
        mesh, tdim, np.arange(n_cells, dtype=np.int32), np.where(mid[:, 0] < 1.0, HOLE, ROCK)
    )
    wall = dolfinx.mesh.locate_entities(mesh, 1, lambda p: np.isclose(p[0], 1.0))
    right = dolfinx.mesh.locate_entities(mesh, 1, lambda p: np.isclose(p[0], 2.0))
    facets = np.concatenate([wall, right])
    order = np.argsort(facets)
    values = np.concatenate([np.full(len(wall), WALL), np.full(len(right), RIGHT)])
    facet_tags = dolfinx.mesh.meshtags(mesh, 1, facets[order], values[order].astype(np.int32))
    groups = {"hole": (2, HOLE), "rock": (2, ROCK), "wall": (1, WALL), "right": (1, RIGHT)}
    data = SimpleNamespace(
        mesh=mesh,
        physical_groups={k: SimpleNamespace(dim=d, tag=t) for k, (d, t) in groups.items()},
        cell_tags=cell_tags,
        facet_tags=facet_tags,
        ridge_tags=None,
        peak_tags=None,
    )
    return TaggedMesh(data)  # type: ignore[arg-type]


def _scene(*stages: Stage, load: Load | None = None) -> Any:
    """What :func:`wall_entities` reads of a scene: its loads and stages."""
    load = load or Load("pressure", (1.0,), "wall", switch_on=stages[-1].name)
    return SimpleNamespace(loads=(load,), stages=stages)


DIG = Stage("dig", remove=("hole",))


def _integrals(tagged: TaggedMesh, ds: ufl.Measure, subdomain: int) -> np.ndarray:
    """∫ 1, ∫ n_x, ∫ n_y, ∫ y n_x over ``ds(subdomain)``, summed over the ranks."""
    n, x = ufl.FacetNormal(tagged.mesh), ufl.SpatialCoordinate(tagged.mesh)
    one = dolfinx.fem.Constant(tagged.mesh, 1.0)
    terms = [one, n[0], n[1], x[1] * n[0]]
    local = [dolfinx.fem.assemble_scalar(dolfinx.fem.form(t * ds(subdomain))) for t in terms]
    return np.array([tagged.mesh.comm.allreduce(v, op=MPI.SUM) for v in local])


def _check(comm: MPI.Comm, *, ghosts: bool) -> None:
    tagged = _mesh(comm, ghosts=ghosts)
    ds, ids = facet_measure(tagged, _scene(DIG))  # type: ignore[arg-type]
    np.testing.assert_allclose(_integrals(tagged, ds, ids[0]), [1, -1, 0, -0.5], atol=1e-14)
    np.testing.assert_allclose(_integrals(tagged, ds, RIGHT), [1, 1, 0, 0.5], atol=1e-14)
    pairs = comm.allreduce(len(wall_entities(tagged, _scene(DIG), 0)) // 2)  # type: ignore[arg-type]
    assert pairs == NY  # one per wall facet


def test_the_wall_is_integrated_once_on_the_rock_side():
    _check(MPI.COMM_SELF, ghosts=False)


@pytest.mark.mpi(min_size=2)
@pytest.mark.parametrize("ghosts", [False, True], ids=["no_ghosts", "ghost_cells"])
def test_the_wall_between_two_ranks_is_integrated_once(ghosts):
    comm = MPI.COMM_WORLD
    tagged = _mesh(comm, ghosts=ghosts)
    top = tagged.mesh.topology
    assert (top.index_map(2).num_ghosts > 0) == (ghosts and comm.rank in (0, comm.size - 1))
    _check(comm, ghosts=ghosts)


def test_live_cells_follow_the_stages():
    tagged = _mesh(MPI.COMM_SELF, ghosts=False)
    hole = tagged.entities("hole")[1]
    back = Stage("back", add=("hole",), material=Material(E=1.0, nu=0.2))
    stages = (DIG, back)
    assert live_cells(tagged, stages, 0).all()
    assert not live_cells(tagged, stages, 1)[hole].any() and live_cells(tagged, stages, 1).sum()
    assert live_cells(tagged, stages, 2).all()
    # a group added before any removal is absent until then
    assert not live_cells(tagged, (back,), 0)[hole].any()


SWAP = Stage("swap", remove=("rock",), add=("hole",), material=Material(E=1.0, nu=0.2))
BAD = [
    ((DIG,), None, "has no 'from'"),
    ((Stage("before"), DIG), "before", "live cells on both sides"),
    ((DIG, Stage("all", remove=("rock",))), "dig", "no live cell"),
    ((DIG, SWAP), "dig", "the live side of group 'wall' changes"),
]


@pytest.mark.parametrize(
    ("stages", "start", "message"), BAD, ids=["no_from", "both", "none", "swapped"]
)
def test_a_wall_without_one_live_side_is_refused_naming_the_key(stages, start, message):
    tagged = _mesh(MPI.COMM_SELF, ghosts=False)
    scene = _scene(*stages, load=Load("pressure", (1.0,), "wall", switch_on=start))
    with pytest.raises(RunError, match=r"^load\[0\]\.group: ") as info:
        facet_measure(tagged, scene)
    assert message in str(info.value)
