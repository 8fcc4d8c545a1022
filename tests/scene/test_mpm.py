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


TWO_BLOCKS = """
name = "two"
description = "two blocks"
method = "mpm"
effects = {effects}

[material]
E = 1.0e5
nu = 0.25
density = 1000.0

[mpm]
t_end = 1.0
grid = {{ lower = [0.0, 0.0], upper = [4.0, 2.0], spacing = 0.1 }}
{mpm}

[[mpm.bodies]]
name = "a"
lower = [0.5, 0.5]
counts = [8, 8]
spacing = 0.05
velocity = [1.0, "0.5*x"]

[[mpm.bodies]]
name = "b"
lower = [1.0, 0.5]
upper = [1.5, 1.0]
spacing = 0.05
density = 2000.0
{extra}
"""


def _two(tmp_path, extra="", effects="[]", mpm=""):
    path = tmp_path / "two.toml"
    path.write_text(TWO_BLOCKS.format(extra=extra, effects=effects, mpm=mpm))
    return path


def test_bodies_load_in_order_with_their_own_density_and_velocity(tmp_path):
    scene = load_scene(_two(tmp_path))
    a, b = scene.mpm.bodies
    assert scene.mpm.particles.kind == "bodies"
    assert (a.name, a.kind, a.counts, a.density, a.velocity) == (
        "a",
        "lattice",
        (8, 8),
        None,
        (1.0, "0.5*x"),
    )
    assert (b.name, b.counts, b.density, b.velocity) == ("b", (10, 10), 2000.0, None)
    assert scene.size.quantities["particles"] == 64 + 100  # the caps count every body


@pytest.mark.parametrize(
    ("override", "key", "text"),
    [
        ("mpm.bodies.1.lower=[0.8, 0.8]", "mpm.bodies[1].lower", "overlaps body 'a'"),
        ("mpm.bodies.1.name=a", "mpm.bodies[1].name", "names an earlier body"),
        ("mpm.bodies.1.counts=[2, 2]", "mpm.bodies[1].counts", "either 'counts' or 'upper'"),
        ("mpm.bodies.1.upper=[1.52, 1.0]", "mpm.bodies[1].upper", "whole number"),
        ("mpm.bodies.1.group=slope", "mpm.bodies[1].lower", "'group' or a lattice box"),
        ("mpm.bodies.1.density=-1", "mpm.bodies[1].density", "> 0"),
        ("mpm.bodies.1.colour=red", "mpm.bodies[1].colour", "unknown key"),
        ("mpm.bodies.0.velocity=[1.0]", "mpm.bodies[0].velocity", "list of 2 numbers"),
        ("mpm.bodies.0.velocity=[1.0, 'x.real']", "mpm.bodies[0].velocity", "entry 1: expression"),
        ("mpm.bodies.0.velocity=['1/(x - 0.5)', 0]", "mpm.bodies[0].velocity", "x = 0.5, y = 0.5"),
        ("mpm.bodies.0.velocity=['z', 0]", "mpm.bodies[0].velocity", "unknown name 'z'"),
        ("mpm.velocity=['__import__(\"os\")', 0]", "mpm.velocity", "only sin, cos"),
        ("mpm.velocity=['(lambda: 1)()', 0]", "mpm.velocity", "only sin, cos"),
        ("mpm.velocity=['9**9**9', 0]", "mpm.velocity", "is inf at x = 0, y = 0"),
        ("mpm.velocity=['1/0', 0]", "mpm.velocity", "is inf at"),
        ("mpm.velocity=['log(x)', 0]", "mpm.velocity", "at x = 0, y = 0"),
        ("mpm.velocity=[true, 0]", "mpm.velocity", "list of 2 numbers or expressions"),
        ("mpm.particles.lower=[0.0, 0.0]", "mpm.particles", "not both"),
        ("gravity.ramp=1.0", "gravity", "which 'effects' does not declare"),
        ("output.fields=['mass', 'weight']", "output.fields", "unknown particle field 'weight'"),
    ],
)
def test_bad_bodies_and_velocities_name_the_key(tmp_path, override, key, text):
    with pytest.raises(SceneError) as info:
        load_scene(_two(tmp_path), [override])
    assert (info.value.key, text in info.value.message) == (key, True), info.value.message


def test_a_huge_velocity_expression_is_refused_quickly(tmp_path):
    huge = "x+" * 500_000 + "x"
    with pytest.raises(SceneError, match="1000001 characters long") as info:
        load_scene(_two(tmp_path, mpm=f'velocity = ["{huge}", 0.0]'))
    assert info.value.key == "mpm.velocity"
    assert len(str(info.value)) < 300  # the error line quotes the text cut short


def test_touching_boxes_are_not_an_overlap(tmp_path):
    scene = load_scene(_two(tmp_path), ["mpm.bodies.1.lower=[0.9, 0.5]"])  # a ends at x = 0.9
    assert len(scene.mpm.bodies) == 2
    above = ["mpm.bodies.1.lower=[0.5, 1.0]", "mpm.bodies.1.upper=[1.0, 1.5]"]  # same x, apart in y
    assert len(load_scene(_two(tmp_path), above).mpm.bodies) == 2


def test_gravity_ramp_is_validated(tmp_path):
    scene = load_scene(_two(tmp_path, "[gravity]\nramp = 0.5", '["gravity"]'))
    assert scene.effects[0].config.ramp == 0.5
    for value, text in (("-1", r"in \[0, 1e\+15\]"), ("inf", r"in \[0"), ("'soon'", "number")):
        with pytest.raises(SceneError, match=text) as info:
            load_scene(_two(tmp_path, "[gravity]", '["gravity"]'), [f"gravity.ramp={value}"])
        assert info.value.key == "gravity.ramp"
    with pytest.raises(SceneError, match="MPM scenes only") as info:
        load_scene(
            JOBS / "quickstart.toml",
            ["effects=['gravity']", "material.density=1.0", "gravity.ramp=1.0"],
        )
    assert info.value.key == "gravity.ramp"
    slide = JOBS / "landslide_kita_uebaru.toml"
    with pytest.raises(SceneError, match="full gravity") as info:
        load_scene(slide, ["mpm.initial_stress=geostatic", "gravity.ramp=1.0"])
    assert info.value.key == "gravity.ramp"


def test_group_bodies_name_existing_regions_once(tmp_path):
    geo = (JOBS.parent / "meshes" / "kita_uebaru.geo").resolve()
    head = (
        'method = "mpm"\neffects = []\n[geometry]\nfile = "' + str(geo) + '"\n'
        "[material]\nE = 1.0e6\nnu = 0.3\ndensity = 1900.0\n"
        "[mpm]\nt_end = 1.0\n"
        "grid = { lower = [-30.0, -20.0], upper = [530.0, 100.0], spacing = 2.0 }\n"
    )
    path = tmp_path / "groups.toml"
    bodies = (
        '[[mpm.bodies]]\ngroup = "weak"\ndensity = 1500.0\n'
        '[[mpm.bodies]]\ngroup = "upper"\nvelocity = [1.0, 0.0]\n'
    )
    path.write_text(head + bodies)
    scene = load_scene(path)
    assert [(b.group, b.density, b.velocity) for b in scene.mpm.bodies] == [
        ("weak", 1500.0, None),
        ("upper", None, (1.0, 0.0)),
    ]
    cases = [
        ('group = "wek"', "mpm.bodies[2].group", "did you mean 'weak'"),
        ('group = "bed"', "mpm.bodies[2].group", "not a 2D region"),
        ('group = "weak"', "mpm.bodies[2].group", "is body 'body0' already"),
        ("lower = [0.0, 0.0]\ncounts = [1, 1]\nspacing = 1.0", "mpm.bodies", "mixes lattice boxes"),
    ]
    for entry, key, text in cases:
        path.write_text(head + bodies + "[[mpm.bodies]]\n" + entry + "\n")
        with pytest.raises(SceneError) as info:
            load_scene(path)
        assert (info.value.key, text in info.value.message) == (key, True), info.value.message


def test_a_group_body_needs_a_geometry(tmp_path):
    with pytest.raises(SceneError, match="needs particles from a") as info:
        load_scene(_two(tmp_path, '[[mpm.bodies]]\ngroup = "slope"'))
    assert info.value.key == "mpm.bodies[2].group"


def test_the_description_says_it_was_modified_by_set(tmp_path):
    path = _two(tmp_path)
    assert load_scene(path).description == "two blocks"
    assert load_scene(path, ["output.dir=elsewhere"]).description == "two blocks"
    scene = load_scene(path, ["mpm.t_end=0.5", "mpm.bodies.1.density=10.0"])
    assert scene.description == (
        "two blocks (modified by --set mpm.t_end=0.5, --set mpm.bodies.1.density=10.0)"
    )
    assert scene.overrides == ("mpm.t_end=0.5", "mpm.bodies.1.density=10.0")
    fem = load_scene(JOBS / "quickstart.toml", ["material.E=1.0"])  # every method
    assert fem.description.endswith("(modified by --set material.E=1.0)")
    assert fem.overrides == ("material.E=1.0",)
