import shutil
from pathlib import Path

import pytest

from geofrac.model.errors import did_you_mean
from geofrac.model.scene import Units
from geofrac.scene import SceneError, load_scene
from geofrac.scene.load import apply_overrides
from tests.conftest import BROKEN, JOBS

BROKEN_SCENES = sorted(BROKEN.glob("*.toml"))


def _expectation(path: Path) -> tuple[str, str]:
    lines = path.read_text().splitlines()
    key = lines[0].removeprefix("# expect-key:").strip()
    text = lines[1].removeprefix("# expect-text:").strip()
    return key, text


def test_there_are_enough_broken_scenes():
    assert len(BROKEN_SCENES) >= 6


@pytest.mark.parametrize("path", BROKEN_SCENES, ids=lambda p: p.stem)
def test_broken_scene_names_file_and_key(path):
    key, text = _expectation(path)
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == key
    assert text in info.value.message
    prefix = f"{path}: {key}: " if key else f"{path}: "
    assert str(info.value).startswith(prefix)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("path", BROKEN_SCENES, ids=lambda p: p.stem)
def test_check_prints_one_error_line_and_fails(cli, path):
    code, out, err = cli("check", path)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1
    key, text = _expectation(path)
    assert lines[0].startswith(f"error: {path}: {key}")
    assert text in lines[0]


def test_run_of_broken_scene_writes_nothing(cli, tmp_path):
    out = tmp_path / "out"
    code, _, err = cli("run", BROKEN / "nu_half.toml", "--out", out)
    assert code == 2
    assert "material.nu" in err
    assert not out.exists()


def test_quickstart_loads_with_every_section():
    scene = load_scene(JOBS / "quickstart.toml")
    assert scene.gdim == 2
    assert scene.discretization.element == "p2"
    assert scene.effect_names == ()
    assert scene.geometry.groups == {"domain": 2, "fixed": 1, "tip": 1, "top": 1, "bottom": 1}
    # L and D of the exact solution come from the geometry parameters
    assert scene.exact is not None
    assert scene.exact.parameters == {"P": 1.0, "L": 10.0, "D": 1.0}
    assert scene.bcs[0].components == (0, 1)
    assert scene.output.probes["tip"] == (10.0, 0.0)


def test_overrides_are_validated_like_the_file():
    scene = load_scene(
        JOBS / "quickstart.toml", ["discretization.element=cst", "geometry.parameters.nx=20"]
    )
    assert scene.discretization.element == "cst"
    assert scene.geometry.parameters["nx"] == 20.0
    with pytest.raises(SceneError) as info:
        load_scene(JOBS / "quickstart.toml", ["material.nu=0.7"])
    assert info.value.key == "material.nu"


def test_override_syntax_errors():
    data = {"bc": [{"group": "a"}]}
    apply_overrides(data, ["bc.0.group=b", "solver.options.ksp_rtol=1e-8"], Path("x.toml"))
    assert data["bc"][0]["group"] == "b"
    assert data["solver"]["options"]["ksp_rtol"] == 1e-8
    for bad in ("nokey", "bc.3.group=x", "bc.0=x"):
        with pytest.raises(SceneError):
            apply_overrides(data, [bad], Path("x.toml"))


def test_scene_hash_depends_on_content_and_overrides(tmp_path):
    copy = tmp_path / "q.toml"
    shutil.copy(JOBS / "quickstart.toml", copy)
    text = copy.read_text().replace("../meshes", str(JOBS.parent / "meshes"))
    copy.write_text(text)
    a = load_scene(copy).sha256
    assert load_scene(copy).sha256 == a
    assert load_scene(copy, ["material.E=200"]).sha256 != a
    copy.write_text(text + "\n# comment\n")
    assert load_scene(copy).sha256 != a


def test_unreadable_scene_file(tmp_path):
    with pytest.raises(SceneError, match="cannot read scene file"):
        load_scene(tmp_path / "missing.toml")


def test_did_you_mean():
    assert did_you_mean("elemnt", ["element", "quadrature_degree"]) == " (did you mean 'element'?)"
    assert "valid: a, b" in did_you_mean("zzz", ["b", "a"])


@pytest.mark.parametrize("path", sorted(JOBS.glob("*.toml")), ids=lambda p: p.stem)
def test_every_job_scene_is_valid(path):
    load_scene(path)


def test_two_driver_owning_effects_are_refused_naming_both(monkeypatch):
    """Two effects that each bring their own run loop: a SceneError, not a silent choice."""
    import sys
    import types

    from geofrac import effects

    twin = types.ModuleType("geofrac_test_twin_driver")
    twin.configure = lambda table, ctx: None
    twin.driver = lambda config, solution, say, write: {}
    monkeypatch.setitem(sys.modules, twin.__name__, twin)
    monkeypatch.setitem(effects.REGISTRY, "twin", twin.__name__)
    with pytest.raises(SceneError) as info:
        load_scene(JOBS / "crack_patch_test.toml", ['effects=["cracking", "twin"]'])
    assert info.value.key == "effects"
    assert "'cracking' and 'twin'" in info.value.message
    scene = load_scene(JOBS / "crack_patch_test.toml")  # one driver: accepted
    assert effects.driven(scene.effects).name == "cracking"


def test_units_label_the_pictures_and_refuse_markup():
    bare = load_scene(JOBS / "quickstart.toml").units  # no [units]: nothing is assumed
    assert bare == Units() and bare.label("x", "length") == "x"
    units = load_scene(JOBS / "notched_beam.toml").units
    assert (units.length, units.force, units.stress) == ("mm", "N", "MPa")
    assert units.label("x", "length") == "x (mm)" and units.of("volume") == "mm³"
    partial = load_scene(JOBS / "quickstart.toml", ['units.stress="kN/m²"']).units
    assert partial.stress == "kN/m²" and partial.length == partial.force == ""  # only as given
    assert partial.label("σ", "stress") == "σ (kN/m²)" and partial.label("u", "length") == "u"
    # matplotlib reads $...$ and backslashes as mathematics: not a unit label
    for bad in ['units.length="$\\\\alpha$"', 'units.length="a_very_long_unit"', "units.force=3"]:
        with pytest.raises(SceneError, match="units"):
            load_scene(JOBS / "quickstart.toml", [bad])
    with pytest.raises(SceneError, match="unknown key"):
        load_scene(JOBS / "quickstart.toml", ['units.angle="deg"'])


def test_a_linked_scene_reads_its_files_beside_the_link_target(tmp_path):
    # jobs/validation/ links the suite's scenes; their "../meshes/..." is the target's
    link = tmp_path / "elsewhere" / "quickstart.toml"
    link.parent.mkdir()
    link.symlink_to(JOBS / "quickstart.toml")
    scene = load_scene(link)
    assert scene.geometry.file == (JOBS.parent / "meshes" / "cantilever.geo").resolve()
    copy = tmp_path / "elsewhere" / "copy.toml"
    copy.write_text((JOBS / "quickstart.toml").read_text())
    with pytest.raises(SceneError, match="cannot read mesh file"):
        load_scene(copy)  # a copy is not a link: its ../meshes is not there
