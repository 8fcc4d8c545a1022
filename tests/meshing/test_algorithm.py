"""``geometry.algorithm``: the gmsh 2D algorithm chosen per scene, overriding the file's."""

import numpy as np
import pytest

from geofrac.meshing.geo import ALGORITHMS, meshed_model
from geofrac.scene import SceneError, load_scene
from tests.conftest import JOBS, REPO

BEAM = REPO / "meshes" / "notched_beam.geo"
COARSE = {"h": 40.0, "h_fine": 12.0}  # a few hundred nodes


def _nodes(parameters: dict[str, float], algorithm: str | None) -> np.ndarray:
    with meshed_model(BEAM, parameters, None, dim=2, algorithm=algorithm) as gmsh:
        xyz = gmsh.model.mesh.getNodes()[1].reshape(-1, 3)[:, :2]
    return xyz[np.lexsort(xyz.T[::-1])]


def test_the_three_algorithms_mesh_one_file_differently():
    meshes = {name: _nodes(COARSE, name) for name in ALGORITHMS}
    names = list(meshes)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            same = meshes[a].shape == meshes[b].shape and np.allclose(meshes[a], meshes[b])
            assert not same, f"{a} and {b} gave the same mesh"


@pytest.mark.parametrize("name", sorted(ALGORITHMS))
def test_the_key_overrides_the_files_own_setting(name):
    """The key overrides the ``Mesh.Algorithm`` a file sets.

    notched_beam.geo sets it from its parameter ``algorithm``: the file told to use an
    algorithm and the key overriding the file's 6 (frontal-Delaunay) mesh alike.
    """
    by_file = _nodes({**COARSE, "algorithm": ALGORITHMS[name]}, None)
    by_key = _nodes({**COARSE, "algorithm": 6}, name)
    assert by_file.shape == by_key.shape
    np.testing.assert_array_equal(by_file, by_key)


def test_the_scene_key_and_its_override():
    assert load_scene(JOBS / "notched_beam.toml").geometry.algorithm is None  # the file's
    scene = load_scene(JOBS / "notched_beam.toml", ["geometry.algorithm=delaunay"])
    assert scene.geometry.algorithm == "delaunay"


def test_a_bad_name_is_a_scene_error_naming_the_key():
    with pytest.raises(SceneError, match=r"geometry\.algorithm.*unknown value 'delaunay6'"):
        load_scene(JOBS / "notched_beam.toml", ["geometry.algorithm=delaunay6"])
