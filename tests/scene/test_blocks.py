"""Validation of method = "blocks" scenes: every error names the file and the key."""

import pytest

from geofrac.model.errors import SceneError
from geofrac.scene import load_scene
from tests.conftest import JOBS


def _write(tmp_path, text):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


def test_the_block_jobs_validate():
    for job in ("blocks_square", "blocks_cylinder", "terrain_100k", "terrain_100k_hetero"):
        scene = load_scene(JOBS / f"{job}.toml")
        assert scene.method == "blocks" and scene.blocks is not None
        assert scene.material is None and scene.effects == ()
    hetero = load_scene(JOBS / "terrain_100k_hetero.toml").blocks
    assert len(hetero.terrain["zones"]) == 4 and hetero.immobile and hetero.dim == 3


@pytest.mark.parametrize(
    ("text", "key", "message"),
    [
        ('method = "blocks"\n', "blocks", "missing"),
        ('method = "blocks"\n[blocks]\nsource = "geometry"\n', "geometry", "missing"),
        ('method = "blocks"\n[blocks]\nsource = "lidar"\n', "blocks.source", "unknown value"),
        (
            'method = "blocks"\neffects = ["gravity"]\n[blocks]\nsource = "terrain"\n',
            "effects",
            "runs no effects",
        ),
        ('method = "blocks"\n[blocks]\nsource = "terrain"\n[material]\nE = 1\n', "material", ""),
        (
            'method = "blocks"\n[blocks]\nsource = "terrain"\ninner_point = "random"\n',
            "blocks.inner_point",
            "2D blocks only",
        ),
        (
            'method = "blocks"\n[blocks]\nsource = "terrain"\n[blocks.terrain]\nh = 0\n',
            "blocks.terrain",
            "must be > 0",
        ),
        (
            'method = "blocks"\n[blocks]\nsource = "terrain"\n[blocks.terrain]\nheight = 3\n',
            "blocks.terrain.height",
            "unknown key",
        ),
        (
            'method = "blocks"\n[blocks]\nsource = "terrain"\n[blocks.terrain]\n'
            "zones = [{centre = [0, 0], radius = 1, h = 1}]\n",
            "blocks.terrain.zones[0].centre",
            "3 numbers",
        ),
        (
            'method = "blocks"\n[blocks]\nsource = "terrain"\nvalidate = "some"\n',
            "blocks.validate",
            "'all', 'none'",
        ),
        ('[blocks]\nsource = "terrain"\n', "blocks", "applies to method 'blocks'"),
    ],
)
def test_bad_block_scenes_name_the_key(tmp_path, text, key, message):
    with pytest.raises(SceneError) as info:
        load_scene(_write(tmp_path, text))
    assert info.value.key == key
    assert message in str(info.value)


def test_random_2d_options_apply_to_random_points(tmp_path):
    square = (JOBS.parent / "meshes" / "square.geo").as_posix()
    text = (
        f'method = "blocks"\n[geometry]\nfile = "{square}"\n'
        '[blocks]\ninner_point = "incentre"\nradius = 0.5\n'
    )
    warnings = load_scene(_write(tmp_path, text)).warnings
    assert len(warnings) == 1 and "blocks.radius: ignored" in warnings[0]
    text = text.replace('"incentre"', '"random"').replace("0.5", "1.5")
    with pytest.raises(SceneError, match=r"\[0, 1\]"):
        load_scene(_write(tmp_path, text))
