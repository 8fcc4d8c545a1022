"""Grain interfaces, their crack state and the event loop on EFMM grains (Edo (2016), §3.3)."""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.elements.efmm_numpy import integration_domains
from geofrac.errors import RunError
from geofrac.fracture.driver import CrackDriver
from geofrac.fracture.grains import GrainState, connected_cracks, interfaces, side_sites
from geofrac.fracture.loop import END_REASONS
from geofrac.fracture.state import MlsSettings
from geofrac.fracture.topology import edge_mesh, random_sites
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS
from tests.fracture.helpers import grid_mesh

#: The grain beam on a coarse uniform mesh (about 330 nodes).
SMALL = ("geometry.parameters.h=16", "geometry.parameters.h_fine=16")


def grid(n: int = 8, q_rand: float = 0.0) -> tuple:
    """A structured n x n triangle mesh of the unit square, its edges and grains."""
    pts, cells = grid_mesh(n)
    pts = pts / n
    mesh = edge_mesh(pts, cells)
    domains = integration_domains(pts, cells, q_rand, seed=3)
    return mesh, domains, interfaces(mesh, domains)


def state_of(mesh, faces, **kw) -> GrainState:
    n = len(mesh.coords)
    return GrainState(mesh, faces, np.zeros(n, bool), np.zeros(n, bool), MlsSettings(), **kw)


@pytest.mark.parametrize("q_rand", [0.0, 0.6])
def test_interfaces_cross_their_edge_and_join_the_inner_points(q_rand):
    mesh, domains, faces = grid(6, q_rand)
    a, b = mesh.coords[mesh.edges[:, 0]], mesh.coords[mesh.edges[:, 1]]
    d = b - a
    rel = faces.centre - a
    cross = d[:, 0] * rel[:, 1] - d[:, 1] * rel[:, 0]
    t = np.sum(rel * d, axis=1) / np.sum(d * d, axis=1)
    assert np.abs(cross).max() < 1e-12 and t.min() > 0 and t.max() < 1
    inner = domains.inner
    assert np.allclose(faces.segments[:, 0, 0], inner[mesh.edge_cells[:, 0]])
    both = mesh.edge_cells[:, 1] >= 0
    assert np.allclose(faces.segments[both, 1, 1], inner[mesh.edge_cells[both, 1]])
    assert np.allclose(faces.segments[:, 0, 1], faces.centre)
    # σ1 is read at the interface's middle: X inside, halfway along p_T–X on the boundary
    assert np.array_equal(faces.point[both], faces.centre[both])
    half = 0.5 * (inner[mesh.edge_cells[~both, 0]] + faces.centre[~both])
    assert (~both).sum() == 4 * 6 and np.allclose(faces.point[~both], half)
    # the grains tile the square
    from geofrac.elements.efmm_numpy import triangle_areas

    assert abs(triangle_areas(faces.grain_subs).sum() - 1.0) < 1e-12


def test_crack_hides_the_node_across_it_and_the_fit_excludes_it():
    mesh, _, faces = grid(8)
    st = state_of(mesh, faces)
    i = 4 * 9 + 4  # the centre node (0.5, 0.5)
    j = i + 1  # its right neighbour
    e = int(np.flatnonzero((mesh.edges == [i, j]).all(axis=1))[0])
    changed = st.crack_many([e])
    assert {i, j} <= set(changed.tolist())
    assert j not in st.fits[i].nodes and i not in st.fits[j].nodes
    assert st.fits[i].order == 2  # plenty of other satellites
    # the third vertex of a triangle of the edge (switched too) sees both
    k = int(np.setdiff1d(mesh.cells[mesh.edge_cells[e, 0]], [i, j])[0])
    assert {i, j} <= set(st.fits[k].nodes.tolist())


def test_patch_switch_changes_the_third_vertices_grain_switch_only_the_two():
    mesh, _, faces = grid(8)
    i, j = 40, 41
    e = int(np.flatnonzero((mesh.edges == [i, j]).all(axis=1))[0])
    third = set(mesh.cells[mesh.edge_cells[e]].ravel().tolist()) - {i, j}
    assert len(third) == 2
    patch = state_of(mesh, faces)
    patch.crack_many([e])
    grain = state_of(mesh, faces, switch="grain")
    grain.crack_many([e])
    assert set(grain.fits) == {i, j}
    assert set(patch.fits) == {i, j} | third


def test_isolated_grain_becomes_a_fragment_then_orders_drop_with_visibility():
    mesh, _, faces = grid(8)
    st = state_of(mesh, faces, switch="grain")
    i = 40
    edges = st.edges_of_node(i)
    st.crack_many([int(e) for e in edges[:-1]])
    assert st.fits[i].order >= 0  # one uncracked interface: it sees through it
    st.crack_many([int(edges[-1])])
    assert st.fits[i].order == -1 and len(st.fits[i].nodes) == 1
    assert i in st.fragments().tolist() and i in st.void_cells().tolist()


def test_corner_node_drops_to_rotation_when_fenced_in():
    """A corner grain fenced by cracks two rings out sees 1-3 nodes: rotation only."""
    mesh, _, faces = grid(8)
    st = state_of(mesh, faces, switch="grain")
    c = mesh.coords
    # crack every interface crossing the square [0, 0.13]^2's border: the corner node
    # (0, 0) then sees only (1/8, 0), (0, 1/8) and (1/8, 1/8)
    inside = (c[:, 0] < 0.13) & (c[:, 1] < 0.13)
    e = mesh.edges
    cut = np.flatnonzero(inside[e[:, 0]] ^ inside[e[:, 1]])
    st.crack_many(cut.tolist())
    st.refit(np.array([0]))
    assert st.fits[0].order == 0
    assert sorted(st.fits[0].nodes[1:].tolist()) == [1, 9, 10]


def test_side_sites_separate_the_two_faces_of_a_notch_line():
    mesh, _, faces = grid(8)
    # a horizontal line of edges at y = 0.5 from x = 0.25 to 0.75
    c = mesh.coords
    on = (np.abs(c[:, 1] - 0.5) < 1e-12) & (c[:, 0] > 0.2) & (c[:, 0] < 0.8)
    e = mesh.edges
    pairs = e[on[e[:, 0]] & on[e[:, 1]]]
    sites = side_sites(mesh, pairs)
    st = state_of(mesh, faces)
    st.start(sites)
    # every node on the line is hidden from every node straight above it
    for n in np.flatnonzero(on):
        above = int(
            np.flatnonzero((np.abs(c[:, 0] - c[n, 0]) < 1e-12) & (np.abs(c[:, 1] - 0.625) < 1e-12))[
                0
            ]
        )
        assert above not in st.fits[n].nodes
        assert n not in st.fits[above].nodes


def test_random_sites_are_seeded_and_a_fraction_of_the_candidates():
    cand = np.zeros(1000, bool)
    cand[::2] = True
    points = np.random.default_rng(0).uniform(size=(1000, 2))
    a = random_sites(cand, 0.04, 7, points=points)
    assert len(a) == 20 and cand[a].all()
    assert np.array_equal(a, random_sites(cand, 0.04, 7, points=points))
    assert not np.array_equal(a, random_sites(cand, 0.04, 8, points=points))
    assert len(random_sites(cand, 0.0, 7, points=points)) == 0
    # the same sites numbered otherwise: the same sites are drawn
    perm = np.random.default_rng(1).permutation(1000)
    b = random_sites(cand[perm], 0.04, 7, points=points[perm])
    assert np.array_equal(np.sort(perm[b]), a)


def crossed(mesh, x0: float, y_min: float) -> np.ndarray:
    """Interfaces of the edges a vertical line x = x0 crosses above y_min, bottom up.

    Each triangle the line crosses has two crossed edges, whose interfaces meet at its
    inner point: the interfaces form one connected chain along the line.
    """
    a, b = mesh.coords[mesh.edges[:, 0]], mesh.coords[mesh.edges[:, 1]]
    hit = (a[:, 0] - x0) * (b[:, 0] - x0) < 0
    ids = np.flatnonzero(hit & (np.minimum(a[:, 1], b[:, 1]) > y_min))
    t = (x0 - a[ids, 0]) / (b[ids, 0] - a[ids, 0])
    return ids[np.argsort(a[ids, 1] + t * (b[ids, 1] - a[ids, 1]))]  # by the crossing's y


def test_connected_cracks_follow_shared_triangles_only():
    mesh, _, _ = grid(8)
    chain = crossed(mesh, 0.437, 0.3)
    cracked = np.zeros(len(mesh.edges), bool)
    cracked[chain] = True
    far = crossed(mesh, 0.061, 0.7)[0]  # a lone crack, not next to the chain
    cracked[far] = True
    main = connected_cracks(mesh, cracked, chain[:1])
    assert main[chain].all() and not main[far]
    assert main.sum() == len(chain)
    cracked[chain[len(chain) // 2]] = False  # a gap splits the chain
    main = connected_cracks(mesh, cracked, chain[:1])
    assert main[chain[: len(chain) // 2]].all() and not main[chain[len(chain) // 2 + 1 :]].any()
    with pytest.raises(ValueError, match="cracked"):
        connected_cracks(mesh, cracked, [chain[len(chain) // 2]])


def make_driver(
    *overrides: str, comm: MPI.Comm = MPI.COMM_WORLD, job: str = "grain_notched_beam"
) -> CrackDriver:
    """The grain driver of ``jobs/<job>.toml`` (the beam on the SMALL mesh), no output."""
    small = SMALL if job == "grain_notched_beam" else ()
    return scene_driver(load_scene_collective(comm, JOBS / f"{job}.toml", small + overrides), comm)


def test_nodes_across_the_notch_slot_do_not_see_each_other():
    d = make_driver("cracking.max_events=0")
    st, c = d.state, d.gm.coords
    left = np.flatnonzero((np.abs(c[:, 0] + 1) < 1e-9) & (c[:, 1] > 10) & (c[:, 1] < 70))
    right = np.flatnonzero((np.abs(c[:, 0] - 1) < 1e-9) & (c[:, 1] > 10) & (c[:, 1] < 70))
    assert len(left) and len(right)
    for i in left:
        assert not st.through_body(int(i), right).any()
    up = np.flatnonzero(np.abs(c[:, 0] + 1) < 1e-9)  # along the same face: visible
    assert st.through_body(int(left[0]), up[up != left[0]]).all()
    d.destroy()


def test_grain_events_are_finite_and_frozen_interfaces_never_crack():
    d = make_driver("cracking.max_events=20")
    res = d.run()
    # the crack may reach the top and separate the coarse beam before event 20
    assert res["end_reason"] in END_REASONS
    assert res["events"] == 20 or res["end_reason"] == "separated", res["end_reason"]
    assert res["events"] >= 10
    rows = d.rows
    assert all(np.isfinite(r["r"]) and r["r"] > 0 for r in rows)
    assert not (d.state.cracked & ~d.state.crackable).any()
    assert np.hypot(rows[0]["x"], rows[0]["y"] - 75.0) < 3.0  # at the notch tip
    assert res["cracked_interfaces"] == res["events"]  # one interface per event


def test_fully_isolated_grain_is_a_fragment_and_the_run_goes_on():
    """Pre-crack every interface of an interior node: its grain is a fragment, held."""
    d = make_driver("cracking.max_events=3", "cracking.switch=grain")
    c = d.gm.coords
    i = int(np.argmin(np.hypot(c[:, 0] + 150, c[:, 1] - 75)))  # far from the notch
    d.sites.add(d.state.edges_of_node(i))
    res = d.run()
    assert d.state.fits[i].order == -1
    assert res["grains_by_field"]["fragment"] >= 1
    assert res["events"] == 3 and res["end_reason"] == "max_events"
    assert all(np.isfinite(r["reaction"]) for r in d.rows)


#: Centres of 27 interfaces of the five-hole plate cracked by event 258 of
#: jobs/grain_holes5.toml (2026-11-26, with the grains drawn from each triangle's corner
#: coordinates), within 8 mm of (27.9, 66.4), at the top of the lower small hole. They fence
#: in the grains of the nodes at (27.59, 65.49) (on the hole's edge) and (28.18, 67.38),
#: which drop to rotation-only fields; the one linear fit that still sees both (the node at
#: (29.04, 69.26)) leaves one joint motion of theirs without strain energy, so the system of
#: event 259 is singular until the driver pins their 4 DOFs (that run then goes on to its
#: 300 events). The first such mechanism, at event 327 of jobs/grain_dcn_4pct_seed2.toml
#: with the earlier grains (2026-11-24), ended that run ``singular``; with today's grains no
#: DCN scene has one.
MECHANISM = [
    (30.49, 65.9), (28.55, 65.74), (28.89, 66.63), (26.76, 64.95), (27.04, 66.04),
    (27.24, 67.03), (29.33, 67.54), (27.57, 68.06), (31.79, 67.41), (28.29, 73.99),
    (30.14, 73.29), (32.02, 72.6), (30.36, 72.17), (32.25, 71.6), (30.75, 71.13),
    (32.51, 70.71), (25.58, 69.48), (27.07, 70.86), (31.53, 68.41), (27.93, 69.13),
    (29.3, 70.21), (28.35, 70.04), (29.99, 69.43), (31.32, 69.33), (28.53, 71.93),
    (28.57, 70.92), (30.29, 70.27),
]  # fmt: skip
#: The nodes of the two rotation-only grains.
MECHANISM_NODES = [(27.59, 65.49), (28.18, 67.38)]


def check_mechanism_is_pinned(comm: MPI.Comm) -> None:
    """Two rotation-only grains seen by one fit: singular until their free DOFs are pinned."""
    d = make_driver("cracking.max_events=0", comm=comm, job="grain_holes5")
    centre = d.units.faces.centre
    pts = np.array(MECHANISM)
    ids = np.array([np.argmin(np.hypot(*(centre - p).T)) for p in pts])
    assert np.hypot(*(centre[ids] - pts).T).max() < 0.01
    d.state.start(np.sort(ids))
    coords = d.gm.coords[:, :2]
    pair = [int(np.argmin(np.hypot(*(coords - p).T))) for p in MECHANISM_NODES]
    assert [d.state.fits[i].order for i in pair] == [0, 0]
    assert set(pair) <= set(d.units.stiffless_nodes().tolist())

    def solve() -> float:
        A, b, _ = d.assemble(np.zeros(d.n_global))
        x = b.duplicate()
        try:
            d.solve(A, b, x)
            return x.norm()
        finally:
            for obj in (A, b, x):
                obj.destroy()

    with pytest.raises(RunError, match="singular"):
        solve()
    assert d.assembler.find_fragments()  # no piece is cut free: only the new check acts
    assert not len(d.assembler.fragment_nodes)
    assert set(d.assembler.pinned_nodes.tolist()) == set(pair) and len(d.assembler.pinned_dofs) == 4
    pinned = sorted(d.assembler.pinned_dofs.tolist())
    assert comm.allgather(pinned) == [pinned] * comm.size
    norm = solve()
    assert np.isfinite(norm) and norm > 0
    d.destroy()


def test_grains_that_move_without_strain_energy_are_pinned():
    check_mechanism_is_pinned(MPI.COMM_SELF)


@pytest.mark.mpi(min_size=2)
def test_grains_that_move_without_strain_energy_are_pinned_on_every_rank():
    check_mechanism_is_pinned(MPI.COMM_WORLD)


def test_random_precracks_follow_the_seed():
    a = make_driver("cracking.max_events=0", "cracking.precracked_fraction=0.04")
    b = make_driver("cracking.max_events=0", "cracking.precracked_fraction=0.04",
                    "cracking.precrack_seed=1")  # fmt: skip
    assert len(a.sites.random) == len(b.sites.random) > 0
    assert not np.array_equal(a.sites.random, b.sites.random)
    interior = a.state.crackable & ~a.state.mesh.boundary_edges
    assert len(a.sites.random) == round(0.04 * interior.sum())
    a.destroy()
    b.destroy()


@pytest.mark.mpi(min_size=2)
def test_same_grain_events_on_1_and_2_ranks():
    comm = MPI.COMM_WORLD
    d2 = make_driver("cracking.max_events=20", "cracking.precracked_fraction=0.04", comm=comm)
    d2.run()
    rows2 = d2.rows
    if comm.rank == 0:
        d1 = make_driver(
            "cracking.max_events=20", "cracking.precracked_fraction=0.04", comm=MPI.COMM_SELF
        )
        d1.run()
        rows1 = d1.rows
        same = [a["edge"] for a in rows1] == [b["edge"] for b in rows2]
        close = np.allclose([a["r"] for a in rows1], [b["r"] for b in rows2], rtol=1e-9)
    else:
        same = close = True
    assert comm.allreduce(same and close, op=MPI.LAND)


def test_crack_reaches_the_face_only_through_the_crack_from_its_origin():
    """A lone crack on the top face does not count; the chain from the origin does."""
    d = make_driver("cracking.max_events=0")
    m = d.state.mesh
    chain = crossed(m, 30.37, 80.0)
    top = d.units.faces.centre[chain[-1]]
    assert abs(top[1] - 150.0) < 1e-9  # the chain ends on the top face
    lone = crossed(m, -150.37, 130.0)[-1]  # a top-face interface far from the chain
    d.state.cracked[lone] = True
    d.state.cracked[chain[:-1]] = True
    assert d.units.face_x(chain[:1]) is None  # stops one interface short; the lone one is apart
    d.state.cracked[chain[-1]] = True
    assert d.units.face_x(chain[-1:]) == pytest.approx(top[0])
    assert abs(top[0] - 30.37) < 16.0  # within one element of the line
    main = d.units.main.describe()
    assert main["interfaces"] == len(chain) and main["nearest_to_face"]["distance"] < 1e-9
    d.destroy()


def test_zero_width_notch_is_one_chain_of_precracked_interfaces():
    """meshes/notched_beam.geo with w = 0: an embedded notch line, cracked on one side."""
    d = make_driver("cracking.max_events=0", "geometry.parameters.w=0",
                    'cracking.precracked=["notch"]')  # fmt: skip
    m, sites = d.state.mesh, d.sites.group
    assert len(sites) >= 75 / 16 and not m.boundary_edges[sites].all()
    mask = np.zeros(len(m.edges), bool)
    mask[sites] = True
    assert connected_cracks(m, mask, sites[:1]).sum() == len(sites)  # one polyline
    y = d.units.faces.centre[sites, 1]
    assert y.min() < 16 and abs(y.max() - 75) < 16  # from the bottom face to the tip
    d.destroy()


def test_thickness_scales_efmm_and_cmultimlsm_grains_alike():
    """Thickness t multiplies every grain's stiffness: same events, energy x t."""
    thick = make_driver("cracking.max_events=6")  # the beam: t = 50
    thick.run()
    thin = make_driver("cracking.max_events=6", "material.thickness=1.0")
    thin.run()
    assert [r["edge"] for r in thick.rows] == [r["edge"] for r in thin.rows]
    assert len(thick.state.fits) > 0  # C-MultiMLSM grains take part after event 1
    e50 = np.array([r["strain_energy"] for r in thick.rows])
    e1 = np.array([r["strain_energy"] for r in thin.rows])
    assert np.allclose(e50, 50.0 * e1, rtol=1e-8)
    assert np.allclose([r["r"] for r in thick.rows], [r["r"] for r in thin.rows], rtol=1e-8)
