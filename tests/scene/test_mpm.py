"""Validation of ``method = "mpm"`` scenes (geofrac.scene.mpm)."""

import pytest

from geofrac.scene import SceneError, load_scene
from tests.conftest import JOBS

BAR = """
method = "mpm"
effects = {effects}

[material]
E = 500.0
density = 1.0

[mpm]
t_end = 1.0
grid = {{ lower = [0.0], upper = [50.0], spacing = 0.5 }}
walls = {{ x_min = "fixed" }}
particles = {{ lower = [22.5], counts = [20], spacing = 0.25 }}
{extra}
"""


def _bar(tmp_path, effects="[]", extra=""):
    path = tmp_path / "bar.toml"
    path.write_text(BAR.format(effects=effects, extra=extra))
    return path


def test_a_valid_bar_loads_with_defaults(tmp_path):
    scene = load_scene(_bar(tmp_path))
    m = scene.mpm
    assert scene.method == "mpm" and scene.discretization is None and scene.gdim == 1
    assert (m.scheme, m.shape, m.courant, m.padding) == ("musl", "mpm", 0.1, 2)
    assert m.walls == {"x_min": "fixed"}
    assert m.particles.kind == "lattice" and m.particles.counts == (20,)
    assert scene.output.fields[0] == "displacement"


@pytest.mark.parametrize(
    ("effects", "extra", "key", "text"),
    [
        ('["cracking"]', "", "effects", "applies to method 'fem'"),
        ('["plasticity"]', "[plasticity]\nfriction_angle = 10", "effects", "2D or 3D"),
        ('["friction"]', "[friction]\nmu = 0.1", "friction.boundaries", "no boundary 'bed'"),
        ('["friction"]', "[friction]\nmu = -1", "friction.mu", ">= 0"),
        ('["mls_smoothing"]', "[mls_smoothing]\nradius = 0", "mls_smoothing.radius", "> 0"),
        ("[]", "[discretization]\nelement = 'p1'", "discretization", "method 'fem' only"),
    ],
)
def test_bad_mpm_scenes_name_the_key(tmp_path, effects, extra, key, text):
    with pytest.raises(SceneError) as info:
        load_scene(_bar(tmp_path, effects, extra))
    assert info.value.key == key
    assert text in info.value.message


@pytest.mark.parametrize(
    ("override", "key", "text"),
    [
        ("mpm.scheme=usl", "mpm.scheme", "did you mean 'musl'"),
        ("mpm.courant=1.5", "mpm.courant", "(0, 1)"),
        ("mpm.grid.upper=[-1.0]", "mpm.grid.upper", "must exceed lower"),
        ("mpm.particles.counts=[0]", "mpm.particles.counts", "positive integers"),
        ("mpm.walls.y_min=fixed", "mpm.walls.y_min", "unknown key"),
        ("mpm.walls.x_max=glued", "mpm.walls.x_max", "unknown value"),
        ("mpm.bed=[[0.0, 1.0], [1.0, 2.0]]", "mpm.bed", "2D scenes only"),
        ("material.nu=0.3", "material.nu", "no Poisson's ratio"),
        ("output.fields=['von_mises']", "output.fields", "unknown particle field"),
    ],
)
def test_bad_mpm_entries_name_the_key(tmp_path, override, key, text):
    with pytest.raises(SceneError) as info:
        load_scene(_bar(tmp_path), [override])
    assert info.value.key == key
    assert text in info.value.message


def test_the_courant_and_dt_conflict_is_reported(tmp_path):
    with pytest.raises(SceneError, match="either 'courant' or 'dt'"):
        load_scene(_bar(tmp_path), ["mpm.courant=0.2", "mpm.dt=0.1"])


def test_an_mpm_table_needs_method_mpm():
    with pytest.raises(SceneError) as info:
        load_scene(JOBS / "quickstart.toml", ["mpm.t_end=1"])
    assert info.value.key == "mpm"


def test_the_landslide_scene_loads_its_groups_and_bed():
    scene = load_scene(JOBS / "landslide_kita_uebaru.toml")
    m = scene.mpm
    assert m.dim == 2 and m.bed_group == "bed" and m.particles.kind == "geometry"
    assert m.particles.densities == {"weak": 1500.0}
    assert scene.effect_names == ("gravity", "plasticity", "friction")


def test_an_unknown_density_group_is_named():
    with pytest.raises(SceneError) as info:
        load_scene(JOBS / "landslide_kita_uebaru.toml", ["mpm.particles.density.wek=1.0"])
    assert info.value.key == "mpm.particles.density.wek"
    assert "did you mean 'weak'" in info.value.message


def test_geostatic_initial_stress_needs_2d_and_vertical_gravity(tmp_path):
    with pytest.raises(SceneError, match="2D and 3D") as info:
        load_scene(_bar(tmp_path), ["mpm.initial_stress=geostatic"])
    assert info.value.key == "mpm.initial_stress"
    slide = JOBS / "landslide_kita_uebaru.toml"
    tilted = ["mpm.initial_stress=geostatic", "gravity.acceleration=[1.0, -9.81]"]
    with pytest.raises(SceneError, match="gravity along -y") as info:
        load_scene(slide, tilted)
    assert info.value.key == "mpm.initial_stress"
    assert load_scene(slide, ["mpm.initial_stress=geostatic"]).mpm.initial_stress == "geostatic"


def test_local_damping_is_read_and_checked(tmp_path):
    """``mpm.damping = { kind = "local", alpha = α }``, α in [0, 1); absent: 0."""
    assert load_scene(_bar(tmp_path)).mpm.damping == 0.0
    damped = _bar(tmp_path, extra='damping = { kind = "local", alpha = 0.2 }')
    assert load_scene(damped).mpm.damping == 0.2
    for extra, key, text in [
        ("damping = { alpha = 1.0 }", "mpm.damping.alpha", "must be < 1"),
        ("damping = { alpha = -0.1 }", "mpm.damping.alpha", ">= 0"),
        ("damping = { kind = 'viscous', alpha = 0.1 }", "mpm.damping.kind", "unknown value"),
        ("damping = { kind = 'local' }", "mpm.damping.alpha", "missing"),
        ("damping = { alpha = 0.1, ratio = 0.1 }", "mpm.damping.ratio", "unknown key"),
    ]:
        with pytest.raises(SceneError) as info:
            load_scene(_bar(tmp_path, extra=extra))
        assert info.value.key == key, extra
        assert text in info.value.message, extra
