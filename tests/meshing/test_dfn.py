"""gmsh model of a network: every fracture is a chain of mesh edges; groups; quality."""

import numpy as np
import pytest

from geofrac.dfn.check import covered_length, match_facets
from geofrac.dfn.clean import clean_network
from geofrac.dfn.polygon import rectangle
from geofrac.dfn.sampling import Network
from geofrac.meshing.dfn import FRACTURE_GROUP, MeshSpec, mesh_network
from geofrac.meshing.geo import gmsh_session
from geofrac.meshing.quality import triangle_quality

SIDES = ("bottom", "right", "top", "left")
CORNERS = ("lower_left", "lower_right", "upper_right", "upper_left")


def _clean():
    segs = [
        [[2, 2], [8, 8]],  # an X with the next
        [[2, 8], [8, 2]],
        [[6, 6], [6, 9]],  # an exact T on the first
        [[1, 5], [4.95, 5]],  # ends 0.05 from the X's centre: merged into it
        [[7, 5], [12, 5]],  # leaves through the right side
        [[3, 0], [3, 1.5]],  # starts on the bottom side
    ]
    net = Network(np.array(segs, dtype=float), np.zeros(len(segs), dtype=np.int64), ("s",))
    return clean_network(net, rectangle((0, 0), (10, 10)), 0.1)


def _mesh(clean, spec):
    with gmsh_session(None, {}) as gmsh:
        report = mesh_network(gmsh, clean, SIDES, corners=CORNERS, spec=spec)
        model = gmsh.model
        groups = {model.getPhysicalName(d, t): (d, t) for d, t in model.getPhysicalGroups()}
        tags, coords, _ = model.mesh.getNodes()
        xyz = dict(zip(tags.tolist(), coords.reshape(-1, 3).tolist(), strict=True))
        dim, tag = groups[FRACTURE_GROUP]
        facets = []
        for curve in model.getEntitiesForPhysicalGroup(dim, tag):
            _, nodes = model.mesh.getElementsByType(1, curve)
            facets += [[xyz[a][:2], xyz[b][:2]] for a, b in nodes.reshape(-1, 2).tolist()]
    return report, groups, np.array(facets)


def test_fracture_lines_are_chains_of_mesh_edges():
    clean = _clean()
    report, groups, facets = _mesh(clean, MeshSpec(0.5, 0.5, 5.0))
    assert set(groups) == {"domain", FRACTURE_GROUP, *SIDES, *CORNERS}
    assert len(facets) == report["fracture_edges"]
    assert np.all(match_facets(facets, clean) >= 0)
    np.testing.assert_allclose(covered_length(facets, clean), clean.length, rtol=1e-12)
    assert clean.modified.tolist() == [False, False, False, True, False, False]
    keep = ~clean.modified
    np.testing.assert_allclose(clean.length[keep], clean.clipped_length[keep], rtol=1e-12)
    assert np.bincount(clean.edges.ravel()).max() == 5  # the X's centre and the merged end
    assert report["min_angle_deg"] <= clean.min_junction_angle() + 1e-9
    assert report["shortest_edge"] > 0 and report["cells"] > 2 * report["nodes"] - 100


def test_finer_size_on_fractures_refines_only_near_them():
    clean = _clean()
    coarse, _, _ = _mesh(clean, MeshSpec(0.5, 0.5, 5.0))
    fine, _, facets_fine = _mesh(clean, MeshSpec(0.5, 0.1, 1.0))
    assert fine["fracture_edges"] > 4 * coarse["fracture_edges"]
    assert fine["longest_edge"] > 0.4  # far from fractures the size is still 0.5
    mean = np.mean(np.hypot(*(facets_fine[:, 1] - facets_fine[:, 0]).T))
    assert mean == pytest.approx(0.1, rel=0.3)


def test_triangle_quality_of_a_right_isosceles_triangle():
    q = triangle_quality(np.array([[0, 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]]))
    assert q["min_angle_deg"] == pytest.approx(45.0)
    assert q["max_angle_deg"] == pytest.approx(90.0)
    assert q["shortest_edge"] == pytest.approx(1.0)
    assert q["longest_edge"] == pytest.approx(2**0.5)
