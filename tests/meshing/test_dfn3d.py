"""Conforming tetrahedral mesh of a box cut by disc fractures: the tracker's pains mesh.

One network holds, in separate corners of a 2 × 2 × 2 box, an X intersection, an exact
T, a near-T (1e-4 short), two near-parallel discs 1e-4 apart, a disc touching the top
face, one 1e-4 short of it, one across a box corner and one across a box edge. It is
cleaned and meshed once; the tests check the groups, the conformity (every fracture
triangle is a face of exactly two tetrahedra), the planes, the areas against the
clipped discs, the intersection chain and the quality.

Areas: a fracture's edge is meshed as chords of its circle, each no longer than the
longest fracture triangle edge h, so the mesh area falls short of the clipped disc's by
at most (arc length) × h² / (12 r) (a chord of length h cuts a segment of area ≈
h³ / (12 r) off the disc), and never exceeds it; straight edges (chords on box faces,
intersection lines) are exact.
"""

import numpy as np
import pytest

from geofrac.dfn3d.network import DiscNetwork, canonical_normals
from geofrac.meshing.dfn3d import ALGORITHMS_3D, FACE_GROUPS, FRACTURE_GROUP, mesh_discs
from geofrac.meshing.geo import gmsh_session
from geofrac.meshing.quality import (
    tetrahedron_aspect_ratio,
    tetrahedron_dihedral_angles,
    tetrahedron_quality,
    triangle_angles,
)

BOX = np.array([[0.0, 0.0, 0.0], [2.0, 2.0, 2.0]])
H, HF = 0.5, 0.1  # element sizes: away from and on the fractures
TOL = HF / 4  # mesh_discs' default tolerance
SETS = ("joints", "faults")

# (centre, normal, radius, set, role)
DISCS = [
    ([0.5, 0.5, 0.5], [0, 0, 1], 0.35, 0, "x-a"),
    ([0.5, 0.5, 0.5], [1, 0, 0], 0.25, 1, "x-b"),
    ([1.5, 0.5, 0.5], [0, 0, 1], 0.35, 0, "t-top"),
    ([1.5, 0.5, 0.75], [1, 0, 0], 0.25, 1, "t-stem"),  # its lowest point on t-top
    ([0.5, 1.5, 0.5], [0, 0, 1], 0.35, 0, "near-t-top"),
    ([0.5, 1.5, 0.75 + 1e-4], [1, 0, 0], 0.25, 1, "near-t-stem"),
    ([1.5, 1.5, 0.5], [0, 0, 1], 0.35, 0, "parallel-large"),
    ([1.55, 1.5, 0.5 + 1e-4], [0, 1e-3, 1], 0.25, 1, "parallel-small"),
    ([0.5, 0.5, 1.7], [1, 0, 0], 0.3, 1, "touching-face"),
    ([1.5, 0.5, 1.7 - 1e-4], [1, 0, 0], 0.3, 1, "short-of-face"),
    ([1.9, 1.9, 1.9], [1, 1, 1], 0.3, 0, "corner"),
    ([0.5, 1.9, 1.9], [1, 0, 0], 0.25, 0, "edge"),
]
ROLE = {role: k for k, (*_, role) in enumerate(DISCS)}


def _network(rows=DISCS):
    return DiscNetwork(
        np.array([r[0] for r in rows], dtype=float),
        canonical_normals(np.array([r[1] for r in rows], dtype=float)),
        np.array([r[2] for r in rows], dtype=float),
        np.array([r[3] for r in rows], dtype=np.int64),
        SETS,
    )


def _mesh(network, **kw):
    """Mesh in a fresh session; return the report and what the tests read from gmsh."""
    with gmsh_session(None, {}) as gmsh:
        report = mesh_discs(gmsh, network, box=BOX, mesh_size=H, fracture_mesh_size=HF, **kw)
        model = gmsh.model
        tags, coords, _ = model.mesh.getNodes()
        x = np.zeros((int(tags.max()) + 1, 3))
        x[tags.astype(np.int64)] = coords.reshape(-1, 3)
        _, tet = model.mesh.getElementsByType(4)
        groups = {}
        for dim, tag in model.getPhysicalGroups():
            groups[model.getPhysicalName(dim, tag)] = (
                dim,
                sorted(int(e) for e in model.getEntitiesForPhysicalGroup(dim, tag)),
            )
        triangles = {
            int(s): model.mesh.getElementsByType(2, s)[1].astype(np.int64).reshape(-1, 3)
            for _, s in model.getEntities(2)
        }
    return {
        "report": report,
        "x": x,
        "tets": tet.astype(np.int64).reshape(-1, 4),
        "groups": groups,
        "triangles": triangles,
        "fracture_of": dict(report["surface_fracture"]),
    }


@pytest.fixture(scope="module")
def meshed():
    return _mesh(_network())


def _face_counts(tets):
    faces = np.sort(tets[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3), axis=1)
    unique, counts = np.unique(faces, axis=0, return_counts=True)
    return {tuple(f): c for f, c in zip(unique.tolist(), counts.tolist(), strict=True)}


def _area(x, tri):
    p = x[tri]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()


def _clipped(centre, normal, radius, *, samples=20000):
    """Area and arc length of a disc inside BOX, by clipping a fine polygon (independent)."""
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    e1 = np.cross(normal, [1.0, 0, 0] if abs(normal[0]) < 0.9 else [0, 1.0, 0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    t = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    poly = centre + radius * (np.cos(t)[:, None] * e1 + np.sin(t)[:, None] * e2)
    inside = np.all((poly >= BOX[0] - 1e-12) & (poly <= BOX[1] + 1e-12), axis=1)
    arc = 2 * np.pi * radius * inside.mean()
    for axis in range(3):
        for side, bound in ((1.0, BOX[1, axis]), (-1.0, BOX[0, axis])):
            d = side * (poly[:, axis] - bound)  # > 0 outside
            q, dq = np.roll(poly, -1, axis=0), np.roll(d, -1)
            with np.errstate(divide="ignore", invalid="ignore"):
                cut = poly + (d / (d - dq))[:, None] * (q - poly)
            both = np.stack([poly, cut], axis=1)  # per edge: its start, then the crossing
            keep = np.stack([d <= 0, d * dq < 0], axis=1)
            poly = both[keep]
    rel = poly - centre
    u, v = rel @ e1, rel @ e2
    area = 0.5 * abs(np.sum(u * np.roll(v, -1) - np.roll(u, -1) * v))
    return area, arc


def test_groups_exist_with_their_dimensions_and_sets_partition_fractures(meshed):
    groups, report = meshed["groups"], meshed["report"]
    assert set(groups) == {"rock", *FACE_GROUPS, FRACTURE_GROUP, *SETS}
    assert groups["rock"][0] == 3
    assert all(groups[name][0] == 2 for name in (*FACE_GROUPS, FRACTURE_GROUP, *SETS))
    joints, faults = set(groups["joints"][1]), set(groups["faults"][1])
    assert joints.isdisjoint(faults) and joints | faults == set(groups[FRACTURE_GROUP][1])
    net = _network()
    for s in joints | faults:
        expected = "joints" if net.set_index[meshed["fracture_of"][s]] == 0 else "faults"
        assert s in groups[expected][1]
    faces = [s for name in FACE_GROUPS for s in groups[name][1]]
    assert len(faces) == len(set(faces))  # each box surface on one face
    # the corner disc cuts the box's corner off: two volumes, both rock
    assert report["volumes"] == 2 and report["groups"]["rock"] == [3, 2]
    assert report["max_node_tag"] == report["nodes"]  # node tags 1..nodes


def test_cleaning_report_names_the_pains(meshed):
    cleaning = meshed["report"]["cleaning"]
    assert cleaning["fractures"]["tee"] == [ROLE["t-stem"], ROLE["near-t-stem"]]
    assert cleaning["fractures"]["parallel"] == [ROLE["parallel-small"]]
    assert cleaning["fractures"]["boundary_tip"] == [ROLE["touching-face"], ROLE["short-of-face"]]
    assert cleaning["dropped"] == [ROLE["parallel-small"]]
    report = meshed["report"]
    assert report["fractures"] == len(DISCS) and report["fractures_inside"] == len(DISCS) - 1
    for role in ("x-a", "x-b", "corner", "edge", "t-top"):
        assert ROLE[role] not in cleaning["shrunk"]


def test_mesh_is_conforming_on_every_fracture(meshed):
    counts = _face_counts(meshed["tets"])
    fractures = meshed["groups"][FRACTURE_GROUP][1]
    for s in fractures:
        tri = np.sort(meshed["triangles"][s], axis=1)
        assert len(tri) > 0
        assert all(counts.get(tuple(t), 0) == 2 for t in tri.tolist()), f"surface {s}"
    boundary = [s for name in FACE_GROUPS for s in meshed["groups"][name][1]]
    for s in boundary:
        tri = np.sort(meshed["triangles"][s], axis=1)
        assert all(counts.get(tuple(t), 0) == 1 for t in tri.tolist()), f"face {s}"
    on_faces = {tuple(t) for s in boundary for t in np.sort(meshed["triangles"][s], 1).tolist()}
    on_fractures = {
        tuple(t) for s in fractures for t in np.sort(meshed["triangles"][s], 1).tolist()
    }
    assert on_faces.isdisjoint(on_fractures)


def test_fracture_triangles_lie_on_their_planes(meshed):
    net = _network()
    x = meshed["x"]
    for s, f in meshed["fracture_of"].items():
        nodes = np.unique(meshed["triangles"][s])
        distance = np.abs((x[nodes] - net.centre[f]) @ net.normal[f])
        assert distance.max() < 1e-9 * 2.0, (s, f)
        assert np.all((x[nodes] >= BOX[0] - 1e-12) & (x[nodes] <= BOX[1] + 1e-12))


def test_fracture_areas_match_the_clipped_discs(meshed):
    report, x = meshed["report"], meshed["x"]
    cleaning = report["cleaning"]
    assert cleaning["kept"] == len(DISCS) - 1
    radius = dict(_cleaned_radii(cleaning["tolerance"]))
    area = {}
    longest = 0.0
    for s, f in meshed["fracture_of"].items():
        tri = meshed["triangles"][s]
        area[f] = area.get(f, 0.0) + _area(x, tri)
        p = x[tri]
        longest = max(longest, np.linalg.norm(p - np.roll(p, 1, axis=1), axis=2).max())
    assert longest < 2 * HF
    total = 0.0
    for f, (centre, normal, r0, *_) in enumerate(DISCS):
        if f == ROLE["parallel-small"]:
            assert f not in area
            continue
        r = radius.get(f, r0)
        exact, arc = _clipped(np.array(centre, float), normal, r)
        deficit = arc * longest**2 / (12 * r)
        assert exact * (1 - 1e-12) - deficit <= area[f] <= exact * (1 + 1e-6), (
            DISCS[f][-1],
            area[f],
            exact,
        )
        total += area[f]
    np.testing.assert_allclose(report["fracture_area"], total, rtol=1e-12)
    # a disc wholly inside: π r² to within the circle's discretisation
    r = DISCS[ROLE["x-a"]][2]
    assert np.pi * r**2 * (1 - longest**2 / (6 * r**2)) <= area[ROLE["x-a"]] <= np.pi * r**2


def _cleaned_radii(tolerance):
    """(fracture, radius) of each kept fracture after the cleaning (recomputed)."""
    from geofrac.dfn3d.clean import clean_discs

    out, rep = clean_discs(_network(), box=BOX, tolerance=tolerance)
    return [(int(f), float(r)) for f, r in zip(rep.kept, out.radius, strict=True)]


def test_x_intersection_is_a_chain_of_shared_mesh_edges(meshed):
    x = meshed["x"]
    a, b = ROLE["x-a"], ROLE["x-b"]

    def edges(f):
        out = set()
        for s, g in meshed["fracture_of"].items():
            if g == f:
                for t in meshed["triangles"][s].tolist():
                    out |= {tuple(sorted((t[i], t[(i + 1) % 3]))) for i in range(3)}
        return out

    shared = np.array(sorted(edges(a) & edges(b)))
    assert len(shared) >= 5
    p = x[shared]
    # on the line x = 0.5, z = 0.5, covering y in [0.25, 0.75] (the smaller disc's chord)
    np.testing.assert_allclose(p[..., 0], 0.5, atol=1e-12)
    np.testing.assert_allclose(p[..., 2], 0.5, atol=1e-12)
    length = np.linalg.norm(p[:, 1] - p[:, 0], axis=1).sum()
    np.testing.assert_allclose(length, 0.5, rtol=1e-12)
    ends = np.unique(shared.ravel(), return_counts=True)
    assert sorted(x[ends[0][ends[1] == 1], 1].tolist()) == pytest.approx([0.25, 0.75])
    # the T pair no longer meets: no shared edge between the stem and the top
    assert not edges(ROLE["t-top"]) & edges(ROLE["t-stem"])


def test_quality_is_finite_and_positive(meshed):
    report = meshed["report"]
    keys = (
        "min_dihedral_deg",
        "max_dihedral_deg",
        "max_aspect_ratio",
        "mean_aspect_ratio",
        "fracture_min_angle_deg",
    )
    assert all(np.isfinite(report[k]) for k in keys)
    assert report["min_dihedral_deg"] > 0 and report["max_aspect_ratio"] >= 1
    assert report["tetrahedra"] == len(meshed["tets"])
    for k in ("clean", "build", "fragment", "mesh_surface", "mesh_volume", "mesh", "quality"):
        assert report[f"time_{k}_s"] >= 0


def test_tetrahedron_quality_measures():
    regular = np.array([[[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]], dtype=float)
    corner = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]], dtype=float)
    flat = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]], dtype=float)
    np.testing.assert_allclose(tetrahedron_dihedral_angles(regular), np.degrees(np.arccos(1 / 3)))
    np.testing.assert_allclose(tetrahedron_aspect_ratio(regular), 1.0)
    angles = np.sort(tetrahedron_dihedral_angles(corner)[0])
    np.testing.assert_allclose(angles, [*[np.degrees(np.arccos(1 / np.sqrt(3)))] * 3, 90, 90, 90])
    np.testing.assert_allclose(tetrahedron_aspect_ratio(corner), (np.sqrt(3) + 1) / 2)
    assert tetrahedron_aspect_ratio(flat)[0] == np.inf
    summary = tetrahedron_quality(np.concatenate([regular, corner]))
    assert summary["max_aspect_ratio"] == pytest.approx((np.sqrt(3) + 1) / 2)
    assert summary["min_dihedral_deg"] == pytest.approx(54.7356103172)
    tri = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=float)
    np.testing.assert_allclose(triangle_angles(tri), [[90, 45, 45]])


def _tee():
    return _network([DISCS[ROLE["t-top"]], DISCS[ROLE["t-stem"]]])


@pytest.mark.parametrize("algorithm", ["delaunay", "hxt"])
def test_both_3d_algorithms_mesh_the_tee(algorithm):
    meshed = _mesh(_tee(), algorithm3d=algorithm)
    report = meshed["report"]
    assert report["algorithm3d"] == algorithm and ALGORITHMS_3D[algorithm] in (1, 10)
    assert report["cleaning"]["fractures"]["tee"] == [1]
    counts = _face_counts(meshed["tets"])
    for s in meshed["groups"][FRACTURE_GROUP][1]:
        tri = np.sort(meshed["triangles"][s], axis=1)
        assert all(counts.get(tuple(t), 0) == 2 for t in tri.tolist())
    assert report["min_dihedral_deg"] > 5.0


def test_cleaning_is_what_keeps_the_near_tee_from_flat_tetrahedra():
    """Meshed as given, the near-T's 1e-4 gap makes slivers; cleaned, it does not."""
    near = _network([DISCS[ROLE["near-t-top"]], DISCS[ROLE["near-t-stem"]]])
    raw = _mesh(near, clean=False)["report"]
    clean = _mesh(near)["report"]
    assert raw["cleaning"] is None and raw["min_dihedral_deg"] < 1.0
    assert clean["min_dihedral_deg"] > 5.0


def test_a_mesh_ignoring_the_fractures_is_refused(monkeypatch):
    """The Frontal 3D algorithm (4) ignores embedded surfaces: the check catches it."""
    monkeypatch.setitem(ALGORITHMS_3D, "frontal", 4)
    with pytest.raises(ValueError, match=r"not a face of exactly two tetrahedra") as info:
        _mesh(_tee(), algorithm3d="frontal")
    assert "fractures 0, 1" in str(info.value)


def test_bad_input_raises_value_error():
    net = _tee()
    with gmsh_session(None, {}) as gmsh:
        with pytest.raises(ValueError, match="fracture_mesh_size"):
            mesh_discs(gmsh, net, box=BOX, mesh_size=0.1, fracture_mesh_size=0.2)
        with pytest.raises(ValueError, match="3D algorithm"):
            mesh_discs(gmsh, net, box=BOX, mesh_size=H, fracture_mesh_size=HF, algorithm3d="x")
        clash = DiscNetwork(net.centre, net.normal, net.radius, net.set_index, ("rock", "xmin"))
        with pytest.raises(ValueError, match="clash"):
            mesh_discs(gmsh, clash, box=BOX, mesh_size=H, fracture_mesh_size=HF)
