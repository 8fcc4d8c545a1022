"""Meshes with [dfn.regions]: outlines follow element edges, cells carry their region's tag.

The references are geometric: a region's polygon is its exact outline, so the area of its
cells equals the shoelace area of the polygon to round-off, and a cell's centroid lies
strictly inside exactly the polygon of the region it is tagged with. Checked with gmsh's
Frontal-Delaunay and Delaunay algorithms at two mesh sizes, and through DOLFINx on 1 and
2 ranks.
"""

from pathlib import Path

import dolfinx_solver  # noqa: F401  (orders MPI before the DOLFINx bindings)

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.dfn.check import covered_length
from geofrac.dfn.clean import clean_network
from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import point_segment_distance, polygon_area, rectangle
from geofrac.dfn.regions import (
    Region,
    circle_polygon,
    cut_polygon,
    layout_regions,
    strictly_inside,
)
from geofrac.dfn.sampling import FractureSet, generate_network
from geofrac.meshing.dfn import DOMAIN_GROUP, FRACTURE_GROUP, MeshSpec, mesh_network
from geofrac.meshing.distribute import build_mesh, check_fracture_cover  # collective import
from geofrac.meshing.geo import gmsh_session
from geofrac.scene import SceneError, load_scene_collective

SIDES = ("bottom", "right", "top", "left")
CORNERS = ("lower_left", "lower_right", "upper_right", "upper_left")
DOMAIN = rectangle((-10.0, -10.0), (10.0, 10.0))
SCENE = Path(__file__).resolve().parent / "scenes" / "dfn_tunnel.toml"
PILLAR = np.array([[4, 4], [8, 4], [8, 5], [5, 5], [5, 8], [4, 8]], dtype=float)


def _layout(outline_size):
    full = circle_polygon([0.0, 0.0], 2.5, 40, level=-0.4)
    regions = [
        Region("heading", cut_polygon(full, -0.4, keep="above"), outline_size),
        Region("bench", cut_polygon(full, -0.4, keep="below"), outline_size),
        Region("pillar", PILLAR, None),  # non-convex; the fractures' size on its outline
    ]
    return layout_regions(regions, DOMAIN, tol=0.1, margin=1.0)


def _network():
    sets = [
        FractureSet("J1", 30.0, 5.0, 2.0, 6.0, 2.0, count=40),
        FractureSet("J2", 115.0, 8.0, 2.0, 6.0, 2.0, count=40),
    ]
    return generate_network(sets, rectangle((-13.0, -13.0), (13.0, 13.0)), 3, domain=DOMAIN)


def _mesh(layout, spec):
    """Mesh the tunnel; return (report, clean, nodes xy, {group: triangles or lines})."""
    clean = clean_network(_network(), DOMAIN, 0.1, constraints=layout.segments)
    with gmsh_session(None, {}) as gmsh:
        report = mesh_network(gmsh, clean, SIDES, corners=CORNERS, spec=spec, regions=layout)
        model = gmsh.model
        tags, coords, _ = model.mesh.getNodes()
        index = {int(t): k for k, t in enumerate(tags)}
        groups = {}
        for dim, tag in model.getPhysicalGroups():
            if dim == 0:
                continue
            cells = []
            for entity in model.getEntitiesForPhysicalGroup(dim, tag):
                _, nodes = model.mesh.getElementsByType(dim, entity)  # 1 line, 2 triangle
                cells.append(np.array([index[int(n)] for n in nodes]).reshape(-1, dim + 1))
            groups[model.getPhysicalName(dim, tag)] = np.concatenate(cells)
    return report, clean, coords.reshape(-1, 3)[:, :2], groups


def _areas(xy, triangles):
    a, b, c = (xy[triangles[:, k]] for k in range(3))
    return 0.5 * np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])


def _check_tags(names, polygons, cells_of, centroid_of):
    """Each cell's centroid is strictly inside exactly the polygon of its tag (or none)."""
    for name in [DOMAIN_GROUP, *names]:
        centroids = centroid_of(cells_of[name])
        inside = np.array([strictly_inside(centroids, p) for p in polygons]).reshape(
            len(polygons), -1
        )
        expected = np.zeros_like(inside)
        if name != DOMAIN_GROUP:
            expected[names.index(name)] = True
        assert np.array_equal(inside, expected), name


@pytest.mark.parametrize("algorithm", ["frontal-delaunay", "delaunay"])
@pytest.mark.parametrize("size, outline", [(2.0, 0.4), (1.0, 0.2)])
def test_region_outlines_tags_and_areas(algorithm, size, outline):
    layout = _layout(outline)
    spec = MeshSpec(size, 0.5 * size, 3.0, algorithm)
    report, clean, xy, groups = _mesh(layout, spec)
    names = list(layout.names)
    polygons = [r.polygon for r in layout.regions]
    # every cell in exactly one group, the centroid test agrees with the tags
    total = sum(len(groups[n]) for n in [DOMAIN_GROUP, *names])
    assert total == report["cells"]
    assert report["region_cells"] == {n: len(groups[n]) for n in names}
    _check_tags(names, polygons, groups, lambda t: xy[t].mean(axis=1))
    # tagged areas are the polygons' areas (the outline is polygonal, so exactly)
    for name, poly in zip(names, polygons, strict=True):
        assert _areas(xy, groups[name]).sum() == pytest.approx(polygon_area(poly), rel=1e-12)
    rock = polygon_area(DOMAIN) - sum(polygon_area(p) for p in polygons)
    assert _areas(xy, groups[DOMAIN_GROUP]).sum() == pytest.approx(rock, rel=1e-12)
    # every outline side is a chain of element edges, and those edges are triangle edges
    edges_of = {
        name: {
            tuple(sorted(e))
            for t in groups[name]
            for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))
        }
        for name in names
    }
    for k, (name, (loop, _)) in enumerate(zip(names, layout.loops, strict=True)):
        lines = groups[f"{name}_outline"]
        assert {tuple(sorted(e)) for e in lines} <= edges_of[name]
        sides = layout.segments[loop]
        a, b = xy[lines[:, 0]], xy[lines[:, 1]]
        d0, _ = point_segment_distance(a[:, None], sides[None, :, 0], sides[None, :, 1])
        d1, _ = point_segment_distance(b[:, None], sides[None, :, 0], sides[None, :, 1])
        on = (d0 <= 1e-12 * 20) & (d1 <= 1e-12 * 20)
        assert np.all(on.sum(axis=1) == 1), f"{name}: an element edge off its outline"
        length = np.hypot(*(b - a).T)
        per_side = np.bincount(np.argmax(on, axis=1), weights=length, minlength=len(sides))
        np.testing.assert_allclose(per_side, np.hypot(*(sides[:, 1] - sides[:, 0]).T), 1e-12)
        if layout.regions[k].mesh_size is not None:  # the outline's size is honoured
            assert np.mean(length) == pytest.approx(outline, rel=0.25)
    # the fractures, inside and outside the regions, are chains of element edges
    lines = groups[FRACTURE_GROUP]
    facets = np.stack([xy[lines[:, 0]], xy[lines[:, 1]]], axis=1)
    np.testing.assert_allclose(covered_length(facets, clean), clean.length, rtol=1e-12)
    inside = strictly_inside(clean.segments.mean(axis=1), polygons[0])
    assert inside.sum() >= 2  # some fracture edges lie in the heading and stay fractures
    assert report["min_angle_deg"] <= clean.min_junction_angle() + 1e-9


def test_without_regions_the_mesh_is_unchanged():
    """No [dfn.regions] and an empty constraint set give the same model as before."""
    clean = clean_network(_network(), DOMAIN, 0.1)
    same = clean_network(_network(), DOMAIN, 0.1, constraints=np.zeros((0, 2, 2)))
    assert np.array_equal(clean.vertices, same.vertices)
    assert np.array_equal(clean.edges, same.edges)
    spec = MeshSpec(1.0, 0.5, 3.0)
    with gmsh_session(None, {}) as gmsh:
        report = mesh_network(gmsh, clean, SIDES, corners=CORNERS, spec=spec)
        names = {gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups()}
    assert "region_cells" not in report
    assert names == {DOMAIN_GROUP, FRACTURE_GROUP, *SIDES, *CORNERS}


# ------------------------------------------------------------------- scene and DOLFINx


def _scene_error(tmp_path, text, match):
    base = SCENE.read_text()
    start = base.index("[dfn.regions.heading]")
    end = base.index("[material]")
    path = tmp_path / "s.toml"
    path.write_text(base[:start] + text + "\n" + base[end:])
    with pytest.raises(SceneError, match=match):
        load_scene_collective(MPI.COMM_SELF, path)


@pytest.mark.parametrize(
    "text, match",
    [
        ("[dfn.regions.a]\ncircle = { centre = [0, 0] }", r"dfn\.regions\.a\.circle\.radius"),
        ("[dfn.regions.a]\ncircle = { centre = [0, 0], radius = 2, radius2 = 1 }", "radius2"),
        ("[dfn.regions.a]\ncircle = { centre = [0, 0], radius = 2, above = 3 }", "misses"),
        ("[dfn.regions.a]\ncircle = { centre = [0, 0], radius = 2 }\npolygon = [[0, 0]]", "one of"),
        ("[dfn.regions.a]\nhorseshoe = { centre = [0, 0], width = 4 }", "wall_height"),
        (
            "[dfn.regions.fractures]\ncircle = { centre = [0, 0], radius = 2 }",
            "must be an identifier",
        ),
        ("[dfn.regions.J1]\ncircle = { centre = [0, 0], radius = 2 }", "fracture sets"),
        ("[dfn.regions.a]\ncircle = { centre = [9, 0], radius = 2 }", r"dfn\.regions: region 'a'"),
        ("[dfn.regions.a]\ncircle = { centre = [0, 0], radius = 2 }\nmesh_size = 9.0", "mesh_size"),
        (
            "[dfn.regions.a]\ncircle = { centre = [0, 0], radius = 2 }\n"
            "[dfn.regions.b]\ncircle = { centre = [1, 0], radius = 2 }",
            "overlap",
        ),
    ],
)
def test_bad_regions_are_scene_errors_naming_the_key(tmp_path, text, match):
    _scene_error(tmp_path, text, match)


def test_scene_declares_the_region_groups():
    scene = load_scene_collective(MPI.COMM_SELF, SCENE)
    groups = scene.geometry.groups
    for name in ("heading", "bench", "pillar"):
        assert groups[name] == 2 and groups[f"{name}_outline"] == 1
    assert groups[DOMAIN_GROUP] == 2


def test_layout_error_is_a_dfn_error():
    with pytest.raises(DfnError):
        layout_regions([Region("a", PILLAR + 5.0)], DOMAIN, tol=0.1, margin=1.0)


def _distributed_tags(comm):
    """Per cell group: global cell count, area, and cells whose centroid disagrees."""
    scene = load_scene_collective(comm, SCENE)
    tagged = build_mesh(scene.geometry, comm)
    check_fracture_cover(tagged)
    layout = scene.geometry.builder.config.regions
    names = list(layout.names)
    polygons = [r.polygon for r in layout.regions]
    out = {}
    wrong = 0
    for name in [DOMAIN_GROUP, *names]:
        dim, cells = tagged.entities(name)
        cells = tagged.owned(dim, cells)
        xy = tagged.vertex_coordinates(dim, cells)[:, :, :2]
        area = _areas(xy.reshape(-1, 2), np.arange(3 * len(cells)).reshape(-1, 3)).sum()
        inside = np.array([strictly_inside(xy.mean(axis=1), p) for p in polygons])
        expected = np.zeros_like(inside)
        if name != DOMAIN_GROUP:
            expected[names.index(name)] = True
        wrong += int(np.count_nonzero(np.any(inside != expected, axis=0)))
        out[name] = (comm.allreduce(len(cells), op=MPI.SUM), comm.allreduce(area, op=MPI.SUM))
    dim, facets = tagged.entities("heading_outline")
    length = tagged.vertex_coordinates(dim, tagged.owned(dim, facets))[:, :, :2]
    out["heading_outline"] = comm.allreduce(
        float(np.hypot(*(length[:, 1] - length[:, 0]).T).sum()), op=MPI.SUM
    )
    out["wrong"] = comm.allreduce(wrong, op=MPI.SUM)
    owned = tagged.mesh.topology.index_map(2).size_local
    out["split"] = comm.allreduce(int(owned < tagged.num_global(2)), op=MPI.SUM)
    out["areas"] = {r.name: polygon_area(r.polygon) for r in layout.regions}
    out["outline_length"] = float(
        np.hypot(*np.diff(layout.segments[layout.loops[0][0]], axis=1)[:, 0].T).sum()
    )
    return out


def _check_distributed(tags):
    assert tags["wrong"] == 0
    for name, area in tags["areas"].items():
        assert tags[name][1] == pytest.approx(area, rel=1e-12)
        assert tags[name][0] > 10
    assert tags["heading_outline"] == pytest.approx(tags["outline_length"], rel=1e-12)


def test_dolfinx_cell_tags_follow_the_regions():
    _check_distributed(_distributed_tags(MPI.COMM_SELF))


@pytest.mark.mpi(min_size=2)
def test_dolfinx_cell_tags_same_on_one_and_n_ranks():
    world = MPI.COMM_WORLD
    serial = None
    if world.rank == 0:  # a failure here must not leave the other ranks in bcast
        try:
            serial = _distributed_tags(MPI.COMM_SELF)
        except Exception as exc:
            serial = RuntimeError(f"the 1-rank mesh failed: {exc}")
    serial = world.bcast(serial, root=0)
    if isinstance(serial, Exception):
        raise serial
    tags = _distributed_tags(world)
    _check_distributed(tags)
    assert tags["split"] == world.size  # the mesh really is split
    for name in (DOMAIN_GROUP, "heading", "bench", "pillar"):
        assert tags[name][0] == serial[name][0]
        assert tags[name][1] == pytest.approx(serial[name][1], rel=1e-12)


def test_the_tunnel_example_in_the_docs_is_a_valid_scene(tmp_path):
    text = (Path(__file__).resolve().parents[2] / "docs" / "dfn.md").read_text()
    section = text[text.index("## Regions: openings") :]
    example = section[section.index("```toml\n") + 8 : section.index("```\n", 10)]
    path = tmp_path / "tunnel.toml"
    path.write_text(example)  # the example names itself (its picture's title)
    scene = load_scene_collective(MPI.COMM_SELF, path)
    layout = scene.geometry.builder.config.regions
    assert layout.names == ("heading", "bench")
    assert len(layout.vertices) == 40  # sides of 0.47 m: at least 4 x tolerance (0.125)
    assert len(layout.holes) == 1
    area = sum(polygon_area(r.polygon) for r in layout.regions)
    assert area == pytest.approx(np.pi * 9.0, rel=0.005)  # the inscribed 40-gon
