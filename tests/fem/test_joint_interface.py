"""Joints in the elasto-plastic solve and the strength reduction (geofrac/fem/joints.py).

Reference: planar sliding of a block on one daylighting joint (Hoek and Bray, Rock Slope
Engineering; Wyllie and Mah (2004)), per unit thickness:

    FoS = (c A + W cos ψ tan φ) / (W sin ψ),   FoS = tan φ / tan ψ when c = 0,

with A the joint length and W the block's weight, written here from the geometry of
meshes/slope_planar_joint.geo (H = 10, face 60°, joint 30° from 2 m above the toe to the
crest: a triangle of height b = 8, A = b / sin ψ = 16, W = γ b² (cot ψ − cot α) / 2 =
960.71 kN with γ = 26), never from the code. Strong rock (c = 1e5 kPa: it never yields),
joint φ = 35°: FoS = 1.2128 (c = 0) and 1.5459 (c = 10 kPa). Measured (docs/plasticity.md,
"Joints in the strength reduction"): the bisection to 1 % lands within 0.4 % of both.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import dolfinx_solver  # noqa: F401

import dolfinx
import numpy as np
import pytest
import ufl
from mpi4py import MPI

from geofrac.effects.plasticity import JointConfig, PlasticityConfig
from geofrac.errors import RunError
from geofrac.fem.joints import JointGeometry, joint_springs
from geofrac.fem.plastic import Law, PlasticProblem
from geofrac.fem.strength_reduction import factor_of_safety, point_monitor
from geofrac.meshing.distribute import TaggedMesh, build_mesh
from geofrac.meshing.geo import inspect_geometry
from geofrac.model.errors import SceneError
from geofrac.model.scene import Geometry
from geofrac.plasticity import MohrCoulomb
from geofrac.plasticity.interface import JointStrength
from geofrac.plasticity.strength_reduction import reduce_strength, trial_factor
from geofrac.scene.load import load_scene
from tests.fem.helpers import JOBS

GEO = Path(__file__).resolve().parents[2] / "meshes" / "slope_planar_joint.geo"
JOB = JOBS / "slope_planar_joint.toml"
#: slope height, face and joint dips (degrees), daylight height, unit weight, joint φ.
H, ALPHA, PSI, YD, GAMMA, PHI_J = 10.0, 60.0, 30.0, 2.0, 26.0, 35.0
ROCK = MohrCoulomb(E=1e6, nu=0.25, cohesion=1e5, friction_angle=45.0, dilatancy_angle=0.0)
#: the issue's tolerance
REL = 0.03


def _rad(deg: float) -> float:
    return math.radians(deg)


def block() -> tuple[float, float]:
    """(W, A): the block's weight per metre and the joint's length, from the geometry."""
    b = H - YD
    W = GAMMA * 0.5 * b * b * (1 / math.tan(_rad(PSI)) - 1 / math.tan(_rad(ALPHA)))
    return W, b / math.sin(_rad(PSI))


def hoek_bray(cohesion: float) -> float:
    """FoS = (c A + W cos ψ tan φ) / (W sin ψ)."""
    W, A = block()
    s, c = math.sin(_rad(PSI)), math.cos(_rad(PSI))
    return (cohesion * A + W * c * math.tan(_rad(PHI_J))) / (W * s)


def joint_mesh(comm: MPI.Comm, *, h: float, algorithm: int = 6) -> TaggedMesh:
    """The meshed slope (size h, gmsh 2D algorithm)."""
    params = {"H": H, "alpha": ALPHA, "psi": PSI, "yd": YD, "h": h, "algorithm": algorithm}
    info = inspect_geometry(GEO, params)
    return build_mesh(Geometry(GEO, params, None, 2, info.groups, order=info.order), comm)


def _space_and_bcs(
    tagged: TaggedMesh, *, base_group: str = "base", back_group: str = "back"
) -> tuple[Any, list[Any]]:
    """The P2 space of a slope, its base fixed and its back on rollers (u_x = 0)."""
    V = dolfinx.fem.functionspace(tagged.mesh, ("Lagrange", 2, (2,)))
    dim, ents = tagged.entities(base_group)
    base = dolfinx.fem.locate_dofs_topological(V, dim, ents)
    dim, ents = tagged.entities(back_group)
    back = dolfinx.fem.locate_dofs_topological(V.sub(0), dim, ents)
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(2), base, V),
        dolfinx.fem.dirichletbc(0.0, back, V.sub(0)),
    ]
    return V, bcs


def factory(tagged: TaggedMesh, cohesion: float) -> Any:
    """Law ↦ the slope under gravity λ γ with the joint (c, tan φ_j) reduced like the law."""
    V, bcs = _space_and_bcs(tagged)
    mesh = tagged.mesh
    strength = JointStrength(cohesion, math.tan(_rad(PHI_J)))
    springs = joint_springs(V, tagged, [("joint", strength)], bcs=bcs, rock=ROCK, penalty=100.0)

    def external(f: Any, v: Any) -> Any:
        return ufl.inner(f * ufl.as_vector([0.0, -GAMMA]), v) * ufl.dx(domain=mesh)

    def make(law: Law) -> PlasticProblem:
        return PlasticProblem(
            V,
            law,
            external,
            bcs=bcs,
            joints=springs(law),
            max_it=25,
            options={"snes_linesearch_type": "bt"},
        )

    return make


#: u at the block's crest edge.
monitor = point_monitor((H / math.tan(_rad(ALPHA)), H))


def test_pairs_cover_the_joint() -> None:
    """H = 2: 2 n + 1 node pairs (n = ceil(A/h) P2 edges), Σ w = A, n ⟂ the joint, upwards."""
    tagged = joint_mesh(MPI.COMM_WORLD, h=2.0)
    V, bcs = _space_and_bcs(tagged)
    g = JointGeometry.build(V, tagged, ["joint"], bcs=bcs)
    _, A = block()
    edges = math.ceil(A / 2.0 - 1e-6)  # the .geo's nj: 8
    assert g.size == 2 * edges + 1
    assert g.weight.sum() == pytest.approx(A, rel=1e-12)
    assert np.allclose(g.normal, [-math.sin(_rad(PSI)), math.cos(_rad(PSI))], atol=1e-12)
    x0 = np.array([YD / math.tan(_rad(ALPHA)), YD])
    along = (g.x - x0) @ np.array([math.cos(_rad(PSI)), math.sin(_rad(PSI))])
    across = (g.x - x0) @ g.normal[0]
    assert np.allclose(across, 0.0, atol=1e-9) and along.min() > -1e-9 and along.max() < A + 1e-9
    assert not g.fixed.any()  # the joint touches no Dirichlet side
    nodes = V.dofmap.index_map.size_global
    assert g.plus.max() < nodes and g.minus.max() < nodes
    assert len(np.intersect1d(g.plus, g.minus)) == 0


def test_unsplit_group_refused() -> None:
    """A curve drawn once (the face, shared by no second curve) is not a joint: named error."""
    tagged = joint_mesh(MPI.COMM_WORLD, h=2.0)
    V, bcs = _space_and_bcs(tagged)
    with pytest.raises(RunError, match=r"plasticity\.joints\.face: .* faces have"):
        JointGeometry.build(V, tagged, ["face"], bcs=bcs)
    with pytest.raises(RunError, match=r"plasticity\.joints\.nope: no group"):
        JointGeometry.build(V, tagged, ["nope"], bcs=bcs)


def test_block_in_equilibrium_on_the_joint() -> None:
    """Full gravity at F = 1: the joint carries N = W cos ψ and T = W sin ψ (relative 1e-9)."""
    tagged = joint_mesh(MPI.COMM_WORLD, h=2.0)
    problem = factory(tagged, 10.0)(ROCK)
    try:
        result = problem.solve_steps(2, max_cuts=1)
        assert result.converged
        joints = problem.joints
        assert joints is not None and joints.ret is not None
        w = joints.geometry.weight
        W, _ = block()
        N = float(np.sum(w * joints.ret.normal))
        T = float(np.sum(w * joints.ret.shear))
        assert pytest.approx(-W * math.cos(_rad(PSI)), rel=1e-9) == N
        assert abs(T) == pytest.approx(W * math.sin(_rad(PSI)), rel=1e-9)
        assert problem.plastic_points() == 0  # the rock stays elastic
    finally:
        problem.destroy()


def bracket_trials(tagged: TaggedMesh, cohesion: float, fos: float) -> dict[float, Any]:
    """The trials F = 0.97, 1.03 and 1.0 × ``fos`` on ``tagged``, keyed by F / fos.

    Asserts 0.97 FoS holds (to λ = 1), 1.03 FoS fails and the bisection's factor of
    safety lies within 3 % of ``fos``.
    """
    result = factor_of_safety(
        factory(tagged, cohesion),
        ROCK,
        steps=5,
        low=fos * (1 - REL),
        high=fos * (1 + REL),
        tolerance=0.04 * fos,  # stops after the middle, 1.0 FoS
        max_cuts=2,
        monitor=monitor,
    )
    trials = {round(t.factor / fos, 6): t for t in result.trials}
    assert trials[1 - REL].stable and trials[1 - REL].load_factor == 1.0
    assert not trials[1 + REL].stable
    assert result.factor_of_safety == pytest.approx(fos, rel=REL)
    return trials


@pytest.mark.parametrize("cohesion", [10.0, 0.0])
def test_planar_sliding_factor_of_safety(cohesion: float) -> None:
    """F = 0.97 FoS holds and F = 1.03 FoS fails (h = 2): the FoS within 3 % of Hoek-Bray."""
    fos = hoek_bray(cohesion)
    trials = bracket_trials(joint_mesh(MPI.COMM_WORLD, h=2.0), cohesion, fos)
    assert trials[1 + REL].end_reason == "step_too_small"


def test_trial_factor_recovers_the_reduction() -> None:
    """trial_factor(law, reduce_strength(law, F)) = F; c alone when φ = 0."""
    for F in (0.5, 1.0, 1.5459, 3.0):
        assert trial_factor(ROCK, reduce_strength(ROCK, F)) == pytest.approx(F, rel=1e-13)
    tresca = MohrCoulomb(E=1e6, nu=0.3, cohesion=5.0, friction_angle=0.0, dilatancy_angle=0.0)
    assert trial_factor(tresca, reduce_strength(tresca, 1.7)) == pytest.approx(1.7, rel=1e-14)


def test_scene_loads_the_joints() -> None:
    """The job's joint table as validated."""
    config = load_scene(JOB).effect_config("plasticity", PlasticityConfig)
    assert config is not None
    assert config.joints == (JointConfig("joint", 0.7002075382097097, 10.0),)
    assert config.contact_penalty == 100.0


@pytest.mark.parametrize(
    ("override", "key"),
    [
        ("plasticity.joints.nope={friction = 0.5}", "plasticity.joints.nope"),
        ("plasticity.joints.joint={cohesion = 1.0}", "plasticity.joints.joint.friction"),
        ("plasticity.joints.joint={friction = -0.5}", "plasticity.joints.joint.friction"),
        ("plasticity.joints.joint={friction = 0.5, mu = 1}", "plasticity.joints.joint.mu"),
        ("plasticity.joints.rock={friction = 0.5}", "plasticity.joints.rock"),
        ("plasticity.joints=3", "plasticity.joints"),
        ("plasticity.contact_penalty=0", "plasticity.contact_penalty"),
    ],
)
def test_scene_bad_joint_keys_named(override: str, key: str) -> None:
    """Each bad entry is refused by the loader (no mesh, no solve), naming its key."""
    with pytest.raises(SceneError) as info:
        load_scene(JOB, [override])
    assert info.value.key.startswith(key), info.value


def test_scene_runs_the_planar_slide(tmp_path: Path) -> None:
    """The job on the coarse mesh, bisection to 0.05 from [1.4, 1.7]: within 3 % of 1.5459.

    With output on, ``joints.csv`` has one row per pair (17), every pair in compression
    or open (σₙ <= 0), the shear holding the block: the joint's force on the block,
    −w τ t, points up the dip (t = (n_y, −n_x) runs up the dip), so Σ τ < 0.
    """
    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene_collective

    overrides = [
        "geometry.parameters.h=2.0",
        "plasticity.reduction_tolerance=0.05",
        f"output.dir='{tmp_path}'",
    ]
    scene = load_scene_collective(MPI.COMM_WORLD, JOB, overrides)
    solution = solve_scene(scene, MPI.COMM_WORLD, verbose=False, write=True)
    try:
        out = solution.results["plasticity"]
    finally:
        solution.problem.destroy()
    assert out["factor_of_safety"] == pytest.approx(hoek_bray(10.0), rel=REL)
    assert out["failed"] - out["stable"] <= 0.05
    joints = out["last_stable"]["joints"]
    assert joints["groups"] == ["joint"] and joints["pairs"] == 2 * 8 + 1
    table = np.loadtxt(tmp_path / "joints.csv", delimiter=",", skiprows=1)
    assert table.shape == (17, 7)
    assert np.all(table[:, 2] <= 0.0) and np.sum(table[:, 3]) < 0


@pytest.mark.mpi(min_size=2)
def test_two_ranks_same_joint_solution() -> None:
    """2 ranks equal each rank's serial solve: pairs, the trials' verdicts, joint tractions."""
    world = MPI.COMM_WORLD
    fos = hoek_bray(10.0)
    tables, verdicts = [], []
    for comm in (world, MPI.COMM_SELF):
        tagged = joint_mesh(comm, h=2.0)
        if comm is world:  # the joint crosses the partition (measured 15 and 1 facets)
            dim, facets = tagged.entities("joint")
            assert min(world.allgather(len(tagged.owned(dim, facets)))) > 0
        make = factory(tagged, 10.0)
        problem = make(reduce_strength(ROCK, 0.97 * fos))
        try:
            assert problem.solve_steps(5, max_cuts=2).converged
            assert problem.joints is not None
            table = problem.joints.table()  # pairs in global node order: sort by place
            tables.append(table[np.lexsort((table[:, 1], table[:, 0]))])
        finally:
            problem.destroy()
        result = factor_of_safety(
            make, ROCK, steps=5, low=0.97 * fos, high=1.03 * fos, tolerance=1.0, max_cuts=2
        )
        verdicts.append([(t.factor, t.stable) for t in result.trials])
    two, one = tables
    assert two.shape == one.shape
    assert np.allclose(two[:, :2], one[:, :2], rtol=0, atol=1e-12)
    scale = np.abs(one[:, 2:4]).max()
    gap = float(np.abs(two[:, 2:4] - one[:, 2:4]).max()) / scale
    assert world.allreduce(gap, op=MPI.MAX) <= 1e-8
    assert world.allreduce(int(verdicts[0] != verdicts[1]), op=MPI.SUM) == 0


def test_dirichlet_dofs_found_per_component() -> None:
    """Pairs on the rollers (x fixed) and on the base (both fixed) get no spring rows there."""
    from geofrac.fem.joints import _fixed

    tagged = joint_mesh(MPI.COMM_WORLD, h=2.0)
    V, bcs = _space_and_bcs(tagged)
    imap = V.dofmap.index_map
    x = V.tabulate_dof_coordinates()[: imap.size_local]
    glob = imap.local_to_global(np.arange(imap.size_local, dtype=np.int32))
    back = glob[np.isclose(x[:, 0], x[:, 0].max()) & (x[:, 1] > 1e-9)]
    base = glob[np.isclose(x[:, 1], 0.0)]
    back = np.concatenate(MPI.COMM_WORLD.allgather(back))
    base = np.concatenate(MPI.COMM_WORLD.allgather(base))
    m = min(len(back), len(base))
    assert m > 0
    fixed = _fixed(V, bcs, back[:m], base[:m])  # (u⁺ on the back, u⁻ on the base)
    assert fixed[:, 0].all() and not fixed[:, 1].any() and fixed[:, 2:].all()


def test_scene_single_solve_with_joints(tmp_path: Path) -> None:
    """Without strength reduction: one load-stepped solve at full strength, the joints' summary.

    FoS 1.55 > 1: the block holds, part of the joint sticks (not every pair slips).
    """
    from geofrac.runner import solve_scene
    from geofrac.scene import load_scene_collective

    text = JOB.read_text()
    kept = [
        line
        for line in text.splitlines()
        if not line.startswith(("strength_reduction", "reduction_"))
    ]
    job = tmp_path / "single.toml"
    job.write_text("\n".join(kept).replace("../meshes/", f"{GEO.parent}/"))
    overrides = ["geometry.parameters.h=2.0"]
    scene = load_scene_collective(MPI.COMM_WORLD, job, overrides)
    solution = solve_scene(scene, MPI.COMM_WORLD, verbose=False)
    try:
        out = solution.results["plasticity"]
    finally:
        solution.problem.destroy()
    assert out["converged"] and out["plastic_points"] == 0
    joints = out["joints"]
    assert joints["pairs"] == 17 and 0 <= joints["slipping"] < 17
    assert out["solver"]["linesearch"] == "bt"
