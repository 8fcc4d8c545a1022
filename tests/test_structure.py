"""The shape of the code at its joints (docs/architecture.md, "Rules at the joints").

Every module under ``geofrac/`` is parsed with :mod:`ast`:

- a public function or constructor takes at most :data:`MAX_POSITIONAL` parameters by
  position (besides ``self``/``cls``); the rest are keyword-only, and a ``bool`` flag is
  always keyword-only. Compiled kernels (numba-jitted functions and the generated
  ``mls_kernels``) are exempt: numba cannot call them with keywords.
- in ``fracture/`` and ``mpm/`` no function is longer than :data:`MAX_FUNCTION_LINES`
  lines and no class longer than :data:`MAX_CLASS_LINES` (generated kernels excepted).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "geofrac"

#: Positional parameters a public function may take; the rest are keyword-only.
MAX_POSITIONAL = 3
#: Longest function and class (lines, decorators excluded) in the engines.
MAX_FUNCTION_LINES = 80
MAX_CLASS_LINES = 300
#: The engines whose functions and classes are held to the size limits.
SIZED = ("fracture", "mpm")
#: Generated source (code written by a program, compiled by numba): exempt from both rules.
GENERATED = ("mpm/mls_kernels.py",)


def _files() -> list[Path]:
    return sorted(p for p in ROOT.rglob("*.py") if str(p.relative_to(ROOT)) not in GENERATED)


def _compiled(node: ast.FunctionDef) -> bool:
    """True for a function under a numba decorator (``@njit``, ``@numba.jit(...)``, ``@_jit``)."""
    for deco in node.decorator_list:
        target = deco.func if isinstance(deco, ast.Call) else deco
        if "jit" in ast.unparse(target).lower() or "vectorize" in ast.unparse(target):
            return True
    return False


def _functions(tree: ast.AST):
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            yield node


def positional_violations(source: str, name: str) -> list[str]:
    """``name:line function (n positional)`` for every public function breaking the rule."""
    out = []
    for node in _functions(ast.parse(source)):
        public = not node.name.startswith("_") or node.name in ("__init__", "__call__")
        if not public or _compiled(node):
            continue
        params = node.args.posonlyargs + node.args.args
        if params and params[0].arg in ("self", "cls"):
            params = params[1:]
        flags = [
            p.arg
            for p in params
            if p.annotation is not None and ast.unparse(p.annotation) in ("bool", "bool | None")
        ]
        if len(params) > MAX_POSITIONAL:
            out.append(f"{name}:{node.lineno} {node.name} ({len(params)} positional)")
        elif flags:
            out.append(f"{name}:{node.lineno} {node.name} (positional flag {flags[0]})")
    return out


def size_violations(source: str, name: str) -> list[str]:
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not _compiled(node):
            limit = MAX_FUNCTION_LINES
        elif isinstance(node, ast.ClassDef):
            limit = MAX_CLASS_LINES
        else:
            continue
        lines = node.end_lineno - node.lineno + 1
        if lines > limit:
            out.append(f"{name}:{node.lineno} {node.name} ({lines} lines > {limit})")
    return out


def test_keyword_only_beyond_three():
    bad = []
    for path in _files():
        bad += positional_violations(path.read_text(), str(path.relative_to(ROOT.parent)))
    assert not bad, f"{len(bad)} functions take too much by position:\n" + "\n".join(bad)


@pytest.mark.parametrize("package", SIZED)
def test_engine_functions_and_classes_are_small(package):
    bad = []
    for path in _files():
        if path.relative_to(ROOT).parts[0] == package:
            bad += size_violations(path.read_text(), str(path.relative_to(ROOT.parent)))
    assert not bad, "\n".join(bad)


def test_the_rules_see_a_violation():
    """The checks themselves, on small sources that break and keep each rule."""
    assert positional_violations("def f(a, b, c, d): pass", "m")
    assert positional_violations("def f(a, verbose: bool = False): pass", "m")
    assert positional_violations("class A:\n    def __init__(self, a, b, c, d): pass", "m")
    assert not positional_violations("def f(a, b, c, *, d, verbose: bool = False): pass", "m")
    assert not positional_violations("def _f(a, b, c, d): pass", "m")
    assert not positional_violations("@numba.njit(cache=True)\ndef f(a, b, c, d): pass", "m")
    long = "def f():\n" + "    x = 1\n" * MAX_FUNCTION_LINES
    assert size_violations(long, "m")
    assert not size_violations("def f():\n    return 1\n", "m")
