"""Joints split automatically before distribution (geofrac.meshing.split.split_model).

The planar-sliding slope of tests/fem/test_joint_interface.py with its joint drawn ONCE
(meshes/slope_planar_joint_single.geo): cut along the joint when meshed, it pairs like
the hand-split one and gives the same factor of safety (Hoek and Bray's closed form,
1.5459 with c = 10 kPa, within 3 %) on two gmsh algorithms.
"""

from __future__ import annotations

import math
from pathlib import Path

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from geofrac.errors import RunError
from geofrac.fem.joints import JointGeometry
from geofrac.meshing.distribute import TaggedMesh, build_mesh
from geofrac.meshing.geo import inspect_geometry
from geofrac.model.scene import Geometry
from geofrac.plasticity.strength_reduction import reduce_strength
from tests.fem.test_joint_interface import (
    ALPHA,
    JOB,
    PSI,
    REL,
    ROCK,
    YD,
    H,
    _space_and_bcs,
    block,
    bracket_trials,
    factory,
    hoek_bray,
    joint_mesh,
)

SINGLE = Path(__file__).resolve().parents[2] / "meshes" / "slope_planar_joint_single.geo"


def single_mesh(
    comm: MPI.Comm, *, h: float, algorithm: int = 6, split: tuple[str, ...] = ("joint",)
) -> TaggedMesh:
    """The slope with the joint drawn once, cut along ``split`` when meshed."""
    params = {"H": H, "alpha": ALPHA, "psi": PSI, "yd": YD, "h": h, "algorithm": algorithm}
    info = inspect_geometry(SINGLE, params)
    geometry = Geometry(SINGLE, params, None, 2, info.groups, order=info.order, split=split)
    return build_mesh(geometry, comm)


def test_split_joint_pairs_like_the_hand_split_one() -> None:
    """At h = 2 the same 17 pairs at the same places as the hand-split joint, Σ w = A, n ⟂ it."""
    comm = MPI.COMM_WORLD
    pairs = []
    for tagged in (single_mesh(comm, h=2.0), joint_mesh(comm, h=2.0)):
        V, bcs = _space_and_bcs(tagged)
        g = JointGeometry.build(V, tagged, ["joint"], bcs=bcs)
        pairs.append(g)
    single, hand = pairs
    _, A = block()
    assert single.size == hand.size == 2 * 8 + 1
    assert single.weight.sum() == pytest.approx(A, rel=1e-12)
    assert np.allclose(single.normal, [-math.sin(math.radians(PSI)), math.cos(math.radians(PSI))])
    a = single.x[np.lexsort(single.x.T)]
    b = hand.x[np.lexsort(hand.x.T)]
    assert np.allclose(a, b, atol=1e-12)
    assert len(np.intersect1d(single.plus, single.minus)) == 0


def test_unsplit_single_joint_refused() -> None:
    """The same mesh not cut: the joint's facets have two cells, refused by name."""
    tagged = single_mesh(MPI.COMM_WORLD, h=2.0, split=())
    V, bcs = _space_and_bcs(tagged)
    with pytest.raises(
        RunError, match=r"plasticity\.joints\.joint: the joint 'joint' is not split"
    ):
        JointGeometry.build(V, tagged, ["joint"], bcs=bcs)


def test_split_keeps_area_and_cell_count() -> None:
    """Cutting adds nodes only: the cell count and the area are those of the uncut mesh."""
    import dolfinx
    import ufl

    comm = MPI.COMM_WORLD
    out = []
    for split in ((), ("joint",)):
        mesh = single_mesh(comm, h=2.0, split=split).mesh
        area = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ufl.dx(domain=mesh)))
        out.append(
            (
                mesh.topology.index_map(2).size_global,
                mesh.geometry.index_map().size_global,
                comm.allreduce(area, op=MPI.SUM),
            )
        )
    (cells0, nodes0, area0), (cells1, nodes1, area1) = out
    assert cells1 == cells0 and area1 == pytest.approx(area0, rel=1e-12)
    b = H - YD
    x2 = H / math.tan(math.radians(ALPHA))
    x3 = YD / math.tan(math.radians(ALPHA)) + b / math.tan(math.radians(PSI))
    exact = (x3 + 10.0) * H - 0.5 * H * x2  # L = 10 beyond the joint's exit
    assert area0 == pytest.approx(exact, rel=1e-12)
    # 9 joint vertices (both ends on the boundary: cut) and 8 midpoints doubled
    assert nodes1 - nodes0 == 9 + 8


@pytest.mark.parametrize("algorithm", [6, 5])
def test_split_planar_sliding_factor_of_safety(algorithm: int) -> None:
    """F = 0.97 FoS holds and F = 1.03 FoS fails (h = 2), as with the hand-split joint."""
    fos = hoek_bray(10.0)
    bracket_trials(single_mesh(MPI.COMM_WORLD, h=2.0, algorithm=algorithm), 10.0, fos)


def test_scene_splits_its_joint_group() -> None:
    """A [plasticity.joints.NAME] table asks for its group to be split when meshed."""
    from geofrac.scene.load import load_scene

    scene = load_scene(JOB, [f"geometry.file='{SINGLE}'"])
    assert scene.geometry is not None and scene.geometry.split == ("joint",)


@pytest.mark.mpi(min_size=2)
def test_two_ranks_same_split_joint() -> None:
    """2 ranks: the split joint's pairs and the trial at 0.97 FoS equal 1 rank's."""
    world = MPI.COMM_WORLD
    fos = hoek_bray(10.0)
    tables = []
    for comm in (world, MPI.COMM_SELF):
        tagged = single_mesh(comm, h=2.0)
        problem = factory(tagged, 10.0)(reduce_strength(ROCK, 0.97 * fos))
        try:
            assert problem.solve_steps(5, max_cuts=2).converged
            assert problem.joints is not None
            table = problem.joints.table()
            tables.append(table[np.lexsort((table[:, 1], table[:, 0]))])
        finally:
            problem.destroy()
    two, one = tables
    assert two.shape == one.shape == (17, 7)
    assert np.allclose(two[:, :2], one[:, :2], rtol=0, atol=1e-12)
    gap = float(np.abs(two[:, 2:4] - one[:, 2:4]).max()) / np.abs(one[:, 2:4]).max()
    assert world.allreduce(gap, op=MPI.MAX) <= 1e-8


#: jobs/slope_joint_set.toml: the free block between the face, J1 and the tension crack
SET_JOB = JOB.parent / "slope_joint_set.toml"


def tension_crack_fos(cohesion: float) -> float:
    """Hoek and Bray's planar sliding with a dry vertical tension crack at x = 10 m."""
    t = math.tan(math.radians(ALPHA))
    x1, x2, xt = YD / t, H / t, 10.0
    psi = math.radians(PSI)
    yt = YD + (xt - x1) * math.tan(psi)
    corners = [(x1, YD), (xt, yt), (xt, H), (x2, H)]
    area = 0.5 * abs(
        sum(
            a[0] * b[1] - b[0] * a[1]
            for a, b in zip(corners, corners[1:] + corners[:1], strict=True)
        )
    )
    W, A = 26.0 * area, (xt - x1) / math.cos(psi)
    return (cohesion * A + W * math.cos(psi) * math.tan(math.radians(35.0))) / (W * math.sin(psi))


def test_joint_set_closed_form() -> None:
    """The job's header numbers: area 29.7014 m², A = 10.2137 m, FoS 1.4773."""
    assert tension_crack_fos(10.0) == pytest.approx(1.4773, abs=5e-5)


def test_joint_set_scene_factor_of_safety() -> None:
    """The DFN joint set (tips, a T junction) on a coarse mesh: 0.97 FoS holds, 1.03 FoS fails."""
    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene_collective

    fos = tension_crack_fos(10.0)
    overrides = [
        "dfn.mesh_size=2.0",
        "dfn.fracture_mesh_size=1.0",
        "plasticity.max_cuts=1",
        f"plasticity.reduction_bracket=[{(1 - REL) * fos}, {(1 + REL) * fos}]",
        "plasticity.reduction_tolerance=0.2",
        "output.xdmf=false",
    ]
    scene = load_scene_collective(MPI.COMM_WORLD, SET_JOB, overrides)
    assert scene.geometry is not None and scene.geometry.split == ("fractures",)
    solution = solve_scene(scene, MPI.COMM_WORLD, verbose=False)
    try:
        out = solution.results["plasticity"]
    finally:
        solution.problem.destroy()
    assert out["stable"] == pytest.approx((1 - REL) * fos, rel=1e-12)
    assert out["failed"] == pytest.approx((1 + REL) * fos, rel=1e-12)
    assert out["factor_of_safety"] == pytest.approx(fos, rel=REL)


@pytest.mark.mpi(min_size=2)
def test_two_ranks_same_joint_set_pairs() -> None:
    """The DFN joint set cut on rank 0: the same pairs (places, weights) on 2 ranks as on 1."""
    from geofrac.scene.load import load_scene

    scene = load_scene(SET_JOB, ["dfn.mesh_size=2.0", "dfn.fracture_mesh_size=1.0"])
    assert scene.geometry is not None
    world = MPI.COMM_WORLD
    out = []
    for comm in (world, MPI.COMM_SELF):
        tagged = build_mesh(scene.geometry, comm)
        V = dolfinx.fem.functionspace(tagged.mesh, ("Lagrange", 2, (2,)))
        g = JointGeometry.build(V, tagged, ["fractures"])
        table = np.column_stack([g.x, g.weight, g.normal])
        # by place, then (several pairs at a junction) by normal
        out.append(table[np.lexsort(np.round(table[:, [4, 3, 2, 1, 0]].T, 9))])
    two, one = out
    assert two.shape == one.shape
    assert world.allreduce(float(np.abs(two - one).max()), op=MPI.MAX) <= 1e-12
    # the T junction where the tension crack meets J1: three pairs at one place
    place = np.round(one[:, :2], 9)
    _, count = np.unique(place, axis=0, return_counts=True)
    assert count.max() == 3
