"""Velocity expressions (geofrac.model.expr): arithmetic only, never executed, finite."""

import numpy as np
import pytest

from geofrac.model.expr import MAX_LENGTH, ExpressionError, evaluate, parse

XY = ("x", "y")
POINTS = np.array([[0.0, 0.0], [1.0, 2.0], [-3.0, 0.5]])


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("2", lambda x, y: 2.0 + 0 * x),
        ("-0.5*y", lambda x, y: -0.5 * y),
        ("+x - (y - 1)**2 / 4", lambda x, y: x - (y - 1) ** 2 / 4),
        (
            "sin(pi*x) + cos(y) * exp(-x**2)",
            lambda x, y: np.sin(np.pi * x) + np.cos(y) * np.exp(-(x**2)),
        ),
        (
            "sqrt(abs(x)) + max(x, y) - min(x, 1)",
            lambda x, y: np.sqrt(np.abs(x)) + np.maximum(x, y) - np.minimum(x, 1),
        ),
        ("log(2 + x*x) * tan(0.1*y)", lambda x, y: np.log(2 + x * x) * np.tan(0.1 * y)),
        ("2**-1 * x", lambda x, y: 0.5 * x),
    ],
)
def test_arithmetic_matches_numpy(text, expected):
    got = evaluate(parse(text, XY), POINTS)
    np.testing.assert_allclose(got, expected(POINTS[:, 0], POINTS[:, 1]), rtol=1e-15)
    assert got.dtype == np.float64 and got.shape == (3,)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("__import__('os')", "only sin, cos"),
        ("__import__('os').system('true')", "calls Attribute"),
        ("x.real", "contains Attribute, which is not arithmetic"),
        ("().__class__", "Attribute"),
        ("lambda: 1", "Lambda"),
        ("[x for x in (1,)]", "ListComp"),
        ("y[0]", "Subscript"),
        ("'a' * 9", "only numbers"),
        ("True + x", "only numbers"),
        ("1j * x", "only numbers"),
        ("x < y", "Compare"),
        ("x if y else 1", "IfExp"),
        ("x // 2", "FloorDiv"),
        ("x % 2", "Mod"),
        ("~1", "Invert"),
        ("z", "unknown name 'z'"),
        ("open", "unknown name"),
        ("eval('1')", "only sin"),
        ("sin(x, y)", "takes 1 argument"),
        ("max(x)", "takes 2 argument"),
        ("sin(*x)", "takes 1 argument"),
        ("sin(x=1)", "keyword"),
        ("x = 1", "not an arithmetic expression"),
        ("", "empty"),
        ("x" * (MAX_LENGTH + 1), "characters long"),
        ("x" + "+x" * 60, "syntax nodes"),
        ("(" * 99 + "x" + ")" * 99, ""),  # within the limits: accepted or a clean refusal
    ],
)
def test_anything_but_arithmetic_is_refused(text, message):
    try:
        expr = parse(text, XY)
    except ExpressionError as exc:
        assert message in str(exc)
        return
    assert message == "", f"{text!r} was accepted"
    assert np.all(evaluate(expr, POINTS) == POINTS[:, 0])


def test_a_huge_string_is_refused_before_parsing():
    with pytest.raises(ExpressionError, match="10000000 characters long"):
        parse("1+" * 5_000_000, XY)


@pytest.mark.parametrize(
    "text",
    [
        "9**9**9",
        "1/x",
        "1" * 190 + "/x",
        "x/x",
        "log(x)",
        "sqrt(-1 - x*x)",
        "exp(exp(exp(y + 10)))",
        "1" * 190 + "**2",
    ],
)
def test_values_that_are_not_finite_are_refused_with_the_point(text):
    expr = parse(text, XY)  # syntactically fine
    with pytest.raises(ExpressionError, match=r"at x = .*, y = .* \(must be finite\)"):
        evaluate(expr, POINTS)


def test_a_huge_power_is_inf_not_a_hang():
    """float64 power: 9**9**9 is inf at once (a Python int would take hours)."""
    assert parse("9**9**9", XY)({"x": np.zeros(1), "y": np.zeros(1)})[0] == np.inf
