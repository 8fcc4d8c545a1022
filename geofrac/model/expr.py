"""Safe arithmetic expressions of position in scene files, e.g. ``"-0.5*y"``.

Scenes are untrusted data, so an expression is never given to ``eval``: it is parsed
with ``ast.parse(mode="eval")`` and only a whitelist of nodes is accepted — number
literals, the coordinate names (``x``, ``y``, ``z`` up to the scene's dimension), the
constant ``pi``, ``+ - * / **``, unary ``+``/``-``, parentheses and calls of the
functions in :data:`FUNCTIONS` by their bare name. No attribute, subscript, lambda,
comparison, string or keyword argument passes. The text is at most
:data:`MAX_LENGTH` characters and :data:`MAX_NODES` syntax nodes, so parsing and
evaluation take microseconds per point.

Evaluation is in float64 numpy with floating-point errors ignored (``9**9**9`` is
``inf``, ``1/0`` is ``inf``); :func:`evaluate` refuses a result that is not finite at
every point. Pure Python + numpy.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "FUNCTIONS",
    "MAX_LENGTH",
    "MAX_NODES",
    "Expression",
    "ExpressionError",
    "evaluate",
    "fold",
    "parse",
]

#: Longest expression text.
MAX_LENGTH = 200
#: Most syntax nodes in one expression.
MAX_NODES = 100
#: Functions an expression may call: name -> (numpy function, number of arguments).
FUNCTIONS: dict[str, tuple[Callable[..., np.ndarray], int]] = {
    "sin": (np.sin, 1),
    "cos": (np.cos, 1),
    "tan": (np.tan, 1),
    "exp": (np.exp, 1),
    "log": (np.log, 1),
    "sqrt": (np.sqrt, 1),
    "abs": (np.abs, 1),
    "min": (np.minimum, 2),
    "max": (np.maximum, 2),
}
#: Named constants.
CONSTANTS = {"pi": float(np.pi)}
#: The arithmetic of each operator node; Python's operators, so that the same tree folds
#: over float64 numpy arrays (:meth:`Expression.__call__`) and over other algebras, such as
#: UFL expressions (:func:`fold`).
_BINARY: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}
_UNARY: dict[type, Callable[[Any], Any]] = {
    ast.UAdd: operator.pos,
    ast.USub: operator.neg,
}


class ExpressionError(ValueError):
    """An expression is not one :func:`parse` accepts, or its value is not finite."""


@dataclass(frozen=True)
class Expression:
    """A parsed, checked expression.

    Attributes:
        text: the source text.
        tree: its syntax tree (only whitelisted nodes).
        names: the variable names it may use.
    """

    text: str
    tree: ast.expr
    names: tuple[str, ...]

    def __call__(self, values: Mapping[str, np.ndarray]) -> np.ndarray:
        """The value at the given points (float64; inf/nan are not checked here).

        Args:
            values: name -> coordinates, each shape=(n,).
        """
        n = len(next(iter(values.values()))) if values else 1
        with np.errstate(all="ignore"):
            variables = {k: np.asarray(v, dtype=np.float64) for k, v in values.items()}
            numpy = {name: f for name, (f, _) in FUNCTIONS.items()}
            out = fold(self.tree, variables, numpy, lift=lambda v: np.asarray(v, np.float64))
            return np.broadcast_to(np.asarray(out, dtype=np.float64), (n,)).copy()


def parse(text: str, names: Sequence[str]) -> Expression:
    """Parse and check ``text``; ``names`` are the variables it may use.

    Raises:
        ExpressionError: too long, not an expression, or a construct outside the
            whitelist (the message says which).
    """
    if not isinstance(text, str):
        raise ExpressionError(f"must be a string, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"is {len(text)} characters long; at most {MAX_LENGTH} allowed")
    if not text.strip():
        raise ExpressionError("is empty")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        reason = getattr(exc, "msg", None) or type(exc).__name__
        raise ExpressionError(f"is not an arithmetic expression ({reason})") from None
    nodes = list(ast.walk(tree))
    if len(nodes) > MAX_NODES:
        raise ExpressionError(f"has {len(nodes)} syntax nodes; at most {MAX_NODES} allowed")
    allowed = tuple(names)
    for node in nodes:
        _check(node, allowed)
    return Expression(text, tree.body, allowed)


def _check(node: ast.AST, names: tuple[str, ...]) -> None:
    """Refuse any node outside the whitelist."""
    if isinstance(node, ast.Expression | ast.Load | ast.operator | ast.unaryop):
        if isinstance(node, ast.operator) and type(node) not in _BINARY:
            raise ExpressionError(f"uses the operator {type(node).__name__}; only + - * / **")
        if isinstance(node, ast.unaryop) and type(node) not in _UNARY:
            raise ExpressionError(f"uses the operator {type(node).__name__}; only unary + and -")
        return
    if isinstance(node, ast.BinOp | ast.UnaryOp):
        return
    if isinstance(node, ast.Constant):
        value = node.value
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ExpressionError(f"contains the literal {value!r:.40}; only numbers")
        return
    if isinstance(node, ast.Name):
        if node.id in names or node.id in CONSTANTS:
            return
        if node.id in FUNCTIONS:
            return  # checked as a call's function below
        valid = ", ".join([*names, *CONSTANTS])
        raise ExpressionError(f"uses the unknown name {node.id!r:.40} (valid: {valid})")
    if isinstance(node, ast.Call):
        func = node.func
        if not isinstance(func, ast.Name) or func.id not in FUNCTIONS:
            what = repr(func.id)[:40] if isinstance(func, ast.Name) else type(func).__name__
            raise ExpressionError(f"calls {what}; only {', '.join(FUNCTIONS)} may be called")
        if node.keywords:
            raise ExpressionError(f"passes keyword arguments to {func.id}()")
        arity = FUNCTIONS[func.id][1]
        if len(node.args) != arity or any(isinstance(a, ast.Starred) for a in node.args):
            raise ExpressionError(f"{func.id}() takes {arity} argument(s)")
        return
    raise ExpressionError(f"contains {type(node).__name__}, which is not arithmetic")


def fold(
    tree: ast.expr,
    variables: Mapping[str, Any],
    functions: Mapping[str, Callable[..., Any]],
    *,
    lift: Callable[[Any], Any],
) -> Any:
    """Evaluate a checked tree in an algebra: numpy arrays, UFL expressions, ...

    Args:
        tree: :attr:`Expression.tree` (its depth is bounded by :data:`MAX_NODES`).
        variables: name -> value of each name the expression may use.
        functions: name -> the algebra's function, for each of :data:`FUNCTIONS`.
        lift: turns a number or a value into the algebra's operand type before every
            operation (float64 arrays for numpy, so that ``**`` follows numpy's rules).
    """

    def walk(node: ast.expr) -> Any:
        if isinstance(node, ast.Constant):
            try:
                return float(node.value)
            except OverflowError:  # an integer literal beyond float64
                return math.inf
        if isinstance(node, ast.Name):
            return CONSTANTS[node.id] if node.id in CONSTANTS else variables[node.id]
        if isinstance(node, ast.UnaryOp):
            return _UNARY[type(node.op)](lift(walk(node.operand)))
        if isinstance(node, ast.BinOp):
            return _BINARY[type(node.op)](lift(walk(node.left)), lift(walk(node.right)))
        if isinstance(node, ast.Call):
            call = functions[node.func.id]  # type: ignore[attr-defined]
            return call(*(lift(walk(a)) for a in node.args))
        raise ExpressionError(f"contains {type(node).__name__}")  # unreachable after _check

    return walk(tree)


def evaluate(expression: Expression, points: np.ndarray) -> np.ndarray:
    """The expression at ``points``, refusing non-finite values.

    Args:
        expression: a parsed expression whose names are coordinate names ``x, y, z``.
        points: shape=(n, dim), dim >= the number of names.

    Returns:
        shape=(n,) float64.

    Raises:
        ExpressionError: the value is inf or NaN at some point (the message gives the
            first such point).
    """
    pts = np.asarray(points, dtype=np.float64)
    values = {name: pts[:, i] for i, name in enumerate(expression.names)}
    out = expression(values) if len(pts) else np.zeros(0)
    bad = ~np.isfinite(out)
    if np.any(bad):
        i = int(np.argmax(bad))
        where = ", ".join(f"{n} = {pts[i, a]:g}" for a, n in enumerate(expression.names))
        raise ExpressionError(f"is {out[i]} at {where} (must be finite)")
    return out
