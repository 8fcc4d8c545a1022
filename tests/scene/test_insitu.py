"""``[initial_stress]`` and ``[[stages]]``: every bad key is an error naming it, before meshing."""

import pytest

from geofrac.scene import SceneError, load_scene
from tests.conftest import REPO

MESH = REPO / "meshes" / "kirsch.geo"

BASE = f"""
effects = []
[geometry]
file = "{MESH}"
[material]
E = 1000.0
nu = 0.25
plane = "strain"
density = 2500.0
[discretization]
element = "p2"
[[bc]]
group = "left"
value = [0.0]
components = ["x"]
[[bc]]
group = "bottom"
value = [0.0]
components = ["y"]
"""

CONSTANT = """
[initial_stress]
kind = "constant"
stress = [-1.0, -2.0, 0.0]
loaded = ["right", "top"]
"""

STAGES = """
[[stages]]
name = "excavate"
remove = ["hole"]
relaxation = 0.4
[[stages]]
name = "rest"
"""


def _load(tmp_path, text, *, base=BASE):
    path = tmp_path / "scene.toml"
    path.write_text(base + text)
    return load_scene(path)


def test_a_valid_constant_stress_with_stages_loads():
    scene = _load_ok(CONSTANT + STAGES)
    assert scene.initial_stress.kind == "constant"
    assert scene.initial_stress.stress == (-1.0, -2.0, 0.0)
    assert scene.initial_stress.loaded == ("right", "top")
    assert [s.name for s in scene.stages] == ["excavate", "rest"]
    assert scene.stages[0].remove == ("hole",) and scene.stages[1].relaxation is None


def _load_ok(text):
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        return _load(Path(d), text)


def test_a_valid_geostatic_stress_takes_g_from_the_gravity_effect():
    base = BASE.replace("effects = []", 'effects = ["gravity"]')
    text = """
[initial_stress]
kind = "geostatic"
surface = [[0.0, 40.0], [40.0, 45.0]]
density = { rock = 2700.0 }
K0 = { rock = 0.8 }
tectonic = [-1e6, 0.0, 0.0]
"""
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        scene = _load(Path(d), text, base=base)
    spec = scene.initial_stress
    assert spec.gravity == pytest.approx(9.81)
    assert spec.surface == ((0.0, 40.0), (40.0, 45.0))
    assert spec.densities == {"rock": 2700.0} and spec.density == 2500.0
    assert spec.k0 == pytest.approx(0.25 / 0.75) and spec.k0s == {"rock": 0.8}


def test_one_K0_number_holds_for_every_cell_group():
    base = BASE.replace("effects = []", 'effects = ["gravity"]')
    text = '\n[initial_stress]\nkind = "geostatic"\nsurface = 40.0\nK0 = 1.5\n'
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        scene = _load(Path(d), text, base=base)
    spec = scene.initial_stress
    assert spec.k0 == 1.5 and spec.k0s == {}
    with tempfile.TemporaryDirectory() as d, pytest.raises(SceneError, match=r"initial_stress\.K0"):
        _load(Path(d), text.replace("1.5", "11.0"), base=base)


BAD = [
    (
        "[initial_stress]\nkind = 'constant'\nstress = [1.0, 2.0, 0.0]\nsurfce = 1.0\n",
        "initial_stress.surfce",
        "unknown key",
    ),
    ("[initial_stress]\nkind = 'lithostatic'\n", "initial_stress.kind", "unknown value"),
    (
        "[initial_stress]\nkind = 'constant'\nstress = [1.0, 2.0]\n",
        "initial_stress.stress",
        "list of 3 numbers",
    ),
    ("[initial_stress]\nkind = 'constant'\n", "initial_stress.stress", "missing"),
    (
        "[initial_stress]\nkind = 'constant'\nstress = [1.0, 2.0, 0.0]\nsurface = 3.0\n",
        "initial_stress.surface",
        "geostatic' only",
    ),
    (
        "[initial_stress]\nkind = 'geostatic'\nsurface = 3.0\n",
        "initial_stress.kind",
        "needs the gravity effect",
    ),
    (
        "[initial_stress]\nkind = 'constant'\nstress = [1.0, 2.0, 0.0]\nloaded = ['rock']\n",
        "initial_stress.loaded",
        "side group",
    ),
    (
        "[initial_stress]\nkind = 'constant'\nstress = [1.0, 2.0, 0.0]\nloaded = ['rigth']\n",
        "initial_stress.loaded",
        "unknown physical group 'rigth'",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\nrelaxation = 0.7\n"
        "[[stages]]\nname = 'b'\nrelaxation = 0.4\n",
        "stages[1].relaxation",
        "add up to 1.1",
    ),
    (
        "[[stages]]\nname = 'a'\nrelaxation = 0.5\n",
        "stages[0].relaxation",
        "no cells have been removed",
    ),
    ("[[stages]]\nname = 'a'\nremove = ['wall']\n", "stages[0].remove", "cell group"),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole', 'rock']\n",
        "stages[0].remove",
        "no body would be left",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\n[[stages]]\nname = 'a'\n",
        "stages[1].name",
        "named twice",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\n[[stages]]\nname = 'b'\n",
        "stages[1].relaxation",
        "already fully applied",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\nrelaxation = 0.0\n",
        "stages[0].relaxation",
        "must be > 0",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\nexcavate = true\n",
        "stages[0].excavate",
        "unknown key",
    ),
]


@pytest.mark.parametrize(("text", "key", "message"), BAD, ids=[b[1] + "-" + b[2] for b in BAD])
def test_bad_keys_name_the_key(tmp_path, text, key, message):
    with pytest.raises(SceneError) as info:
        _load(tmp_path, text)
    assert info.value.key == key
    assert message in info.value.message


def test_geostatic_with_sideways_gravity_is_refused(tmp_path):
    base = (
        BASE.replace("effects = []", 'effects = ["gravity"]')
        + "[gravity]\nacceleration = [1.0, -9.81]\n"
    )
    with pytest.raises(SceneError) as info:
        _load(tmp_path, "[initial_stress]\nkind = 'geostatic'\nsurface = 3.0\n", base=base)
    assert info.value.key == "gravity.acceleration"


def test_polyline_x_must_increase(tmp_path):
    base = BASE.replace("effects = []", 'effects = ["gravity"]')
    text = "[initial_stress]\nkind = 'geostatic'\nsurface = [[0.0, 1.0], [0.0, 2.0]]\n"
    with pytest.raises(SceneError) as info:
        _load(tmp_path, text, base=base)
    assert info.value.key == "initial_stress.surface"
    assert "increase strictly" in info.value.message


def test_vertex_dof_elements_and_driving_effects_are_refused(tmp_path):
    with pytest.raises(SceneError) as info:
        straight = BASE.replace("kirsch.geo", "plate_with_hole.geo").replace('"p2"', '"rgnt"')
        _load(tmp_path, CONSTANT, base=straight)
    assert info.value.key == "initial_stress" and "Lagrange element" in info.value.message
    cracking = (
        BASE.replace("effects = []", 'effects = ["cracking"]')
        .replace("density = 2500.0", "density = 2500.0\ntensile_strength = 1.0")
        .replace(f'file = "{MESH}"', f'file = "{MESH}"\nparameters = {{ order = 1 }}')
        .replace('"p2"', '"cst"')
    )
    with pytest.raises(SceneError) as info:
        _load(
            tmp_path,
            STAGES + "[[load]]\ntype='traction'\ngroup='top'\nvalue=[0.0, -1.0]\n",
            base=cracking,
        )
    assert info.value.key == "stages" and "cracking" in info.value.message


def test_an_mpm_scene_refuses_the_fem_tables(tmp_path):
    path = tmp_path / "m.toml"
    path.write_text(
        'method = "mpm"\n[initial_stress]\nkind = "constant"\n'
        "[mpm]\ndim = 2\n[material]\nE = 1.0\nnu = 0.2\ndensity = 1.0\n"
    )
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == "initial_stress"


ADD_BAD = [
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\n[[stages]]\nname = 'b'\nadd = ['hole']\n",
        "stages[1].material",
        "missing",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\n[[stages]]\nname = 'b'\nadd = ['hole']\n"
        "material = { E = 1.0, nu = 0.2 }\n[[stages]]\nname = 'c'\nadd = ['hole']\n"
        "material = { E = 1.0, nu = 0.2 }\n",
        "stages[2].add",
        "in the body already",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\nmaterial = { E = 1.0, nu = 0.2 }\n",
        "stages[0].material",
        "add some",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\n[[stages]]\nname = 'b'\nadd = ['hole']\n"
        "material = { E = 1.0, nu = 0.7 }\n",
        "stages[1].material.nu",
        "(-1, 0.5)",
    ),
    (
        "[[stages]]\nname = 'a'\nremove = ['hole']\n[[stages]]\nname = 'b'\nadd = ['hole']\n"
        "material = { E = 1.0, nu = 0.2, G = 3.0 }\n",
        "stages[1].material.G",
        "unknown key",
    ),
]


@pytest.mark.parametrize(("text", "key", "message"), ADD_BAD, ids=[b[1] for b in ADD_BAD])
def test_bad_add_keys_name_the_key(tmp_path, text, key, message):
    with pytest.raises(SceneError) as info:
        _load(tmp_path, text)
    assert info.value.key == key
    assert message in info.value.message


def test_a_group_added_before_any_removal_is_absent_until_then(tmp_path):
    text = (
        "[[stages]]\nname = 'dig'\nremove = ['rock']\nrelaxation = 0.5\n"
        "[[stages]]\nname = 'fill'\nadd = ['rock']\nmaterial = { E = 5.0, nu = 0.3 }\n"
    )
    scene = _load(tmp_path, text)
    assert scene.stages[1].add == ("rock",) and scene.stages[1].material.E == 5.0
    absent = "[[stages]]\nname = 'place'\nadd = ['hole']\nmaterial = { E = 5.0, nu = 0.3 }\n"
    scene = _load(tmp_path, absent)
    assert scene.stages[0].add == ("hole",) and scene.stages[0].relaxation is None
