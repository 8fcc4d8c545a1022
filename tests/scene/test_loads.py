"""Validation of [[load]] entries: types, groups, pressure and expression values."""

import pytest

from geofrac.scene import SceneError, load_scene
from tests.conftest import JOBS, REPO

CYLINDER = JOBS / "thick_cylinder.toml"  # load.0: pressure 10 on the curve "inner"
BEAM = REPO / "tests" / "fem" / "point_beam.toml"  # load.0: point force on the point "tip"


def _error(*overrides: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        load_scene(CYLINDER, overrides)
    assert "\n" not in str(info.value)
    assert str(info.value).startswith(f"{CYLINDER}: {info.value.key}: ")
    return info.value


def test_pressure_accepts_a_number_an_expression_or_a_list_of_one():
    assert load_scene(CYLINDER).loads[0].value == (10.0,)
    hydro = load_scene(CYLINDER, ['load.0.value="1000*(10 - y)"']).loads[0]
    assert (hydro.type, hydro.value, hydro.group) == ("pressure", ("1000*(10 - y)",), "inner")
    assert load_scene(CYLINDER, ["load.0.value=[2.5]"]).loads[0].value == (2.5,)


def test_traction_components_may_mix_numbers_and_expressions():
    load = load_scene(CYLINDER, ["load.0.type=traction", 'load.0.value=[1, "-2*x + y"]']).loads[0]
    assert load.value == (1.0, "-2*x + y")


def test_pressure_on_the_domain_is_refused():
    err = _error("load.0.group=domain")
    assert err.key == "load[0].group"
    assert "has dimension 2, expected one of (1,)" in err.message


def test_point_load_on_a_curve_is_refused():
    err = _error("load.0.type=point", "load.0.value=[1, 0]")
    assert err.key == "load[0].group"
    assert "'inner' has dimension 1, expected one of (0,)" in err.message


@pytest.mark.parametrize(
    ("value", "text"),
    [
        ('"1000*(10 - q)"', "unknown name 'q' (valid: x, y, pi)"),
        ('"1000*(10 - z)"', "unknown name 'z'"),  # a 2D scene has no z
        ('"1000*(10 - y"', "is not an arithmetic expression"),
        ('"__import__(1)"', "calls '__import__'"),
        ("[1, 2]", "must be one number or one expression of x, y"),
        ("true", "must be one number or one expression"),
        ('"exact"', "unknown name 'exact'"),
    ],
)
def test_bad_pressure_value_names_the_key(value, text):
    err = _error(f"load.0.value={value}")
    assert err.key == "load[0].value"
    assert text in err.message


def test_bad_traction_expression_names_the_entry():
    err = _error("load.0.type=traction", 'load.0.value=[0, "sin(x"]')
    assert err.key == "load[0].value"
    assert "entry 1" in err.message and "not an arithmetic expression" in err.message


@pytest.mark.parametrize(
    ("value", "text"),
    [
        ('["x", 0]', "must be a list of 2 numbers"),
        ("[1, 2, 3]", "must be a list of 2 numbers"),
        ('"exact"', "'exact' applies to traction and body_force loads"),
    ],
)
def test_point_value_is_gdim_numbers(value, text):
    with pytest.raises(SceneError) as info:
        load_scene(BEAM, [f"load.0.value={value}"])
    assert info.value.key == "load[0].value"
    assert text in info.value.message


def test_unknown_load_type_is_refused():
    err = _error("load.0.type=pressur")
    assert err.key == "load[0].type"
    assert "pressure" in err.message


def test_lame_cylinder_needs_a_below_b():
    err = _error("exact.a=3.0")
    assert err.key == "exact.name"
    assert "needs 0 < a < b, got a = 3.0, b = 2.0" in err.message
