"""Geometry files are data: refuse ``.geo`` statements that act outside the geometry.

A gmsh ``.geo`` file is a program. Besides points, curves and physical groups it can run
shell commands (``System``, ``SystemCall``, ``NonBlockingSystemCall``, ``OnelabRun``),
write, create or remove files (``Save``, ``Print``, ``Printf(...) > "f"``, ``CreateDir``,
``Save View``), read arbitrary files into the model (``Merge``, ``ShapeFromFile``), end the
interpreter and with it the program that embeds gmsh (``Exit``, ``Abort``), run plugins,
and set ``General.*`` / ``Solver.*`` options (option and session files, editor, solver
executables). :func:`scan_geo` reads a file and everything it ``Include``s the way gmsh's
lexer does (``Gmsh.l``: ``//`` and ``/* */`` comments, strings between ``"`` or ``'`` with
no escapes) and raises :class:`GeoRefused` on the first such statement, naming file, line
and statement. ``geometry.trusted = true`` in a scene skips the scan.

:func:`parameter_specs` and :func:`check_parameters` refuse ``geometry.parameters`` that
gmsh would silently misread: beyond :data:`PARAMETER_BOUND` (gmsh converts counts to
``int``; ``nx = 1e20`` overflows and the transfinite line quietly falls back to the mesh
size), outside the file's ``DefineConstant`` ``Min``/``Max``/``Range``, and non-integers
where the file marks the parameter as an integer (``Step 1`` with an integer default) or
uses it directly as a number of divisions (``Transfinite Curve{...} = n [+- k]``,
``Layers{n}``).

Pure Python: no gmsh, no MPI.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

__all__ = [
    "MAX_STRING",
    "PARAMETER_BOUND",
    "GeoRefused",
    "ParameterSpec",
    "Token",
    "check_parameters",
    "count_parameters",
    "parameter_specs",
    "scan_geo",
    "tokenize",
]

#: Largest |value| of a ``.geo`` parameter: gmsh turns counts into C ``int`` (2^31 - 1).
PARAMETER_BOUND = 1e9
#: gmsh's lexer stops a string at 1023 characters and reads the rest as code.
MAX_STRING = 1000
#: Most files one geometry may read through ``Include``.
MAX_FILES = 200

_TRUST = "geometry files are data (set geometry.trusted = true to allow it)"

#: name -> why it is refused (a statement or function that acts outside the model).
_REFUSED = {
    "System": "runs a program",
    "SystemCall": "runs a program",
    "NonBlockingSystemCall": "runs a program",
    "OnelabRun": "runs a program",
    "Save": "writes a file",
    "CreateDir": "creates a directory",
    "DeleteFile": "deletes a file",
    "RenameFile": "renames a file",
    "SendToServer": "sends data to a ONELAB server",
    "Merge": "reads another file into gmsh, which cannot be checked",
    "MergeWithBoundingBox": "reads another file into gmsh, which cannot be checked",
    "ShapeFromFile": "reads another file into gmsh, which cannot be checked",
    "Exit": "ends the gmsh interpreter and the program that runs it",
    "Abort": "ends the gmsh interpreter",
    "Sleep": "pauses gmsh",
    "Plugin": "runs a gmsh plugin (plugins can write files)",
    "S2N": "turns a string into a statement or variable name, which cannot be checked",
    "StringToName": "turns a string into a statement or variable name, which cannot be checked",
}
#: Option categories whose assignment is refused (files, commands, executables).
_OPTION_CATEGORIES = ("General", "Solver")
_ASSIGN = {"=", "+=", "-=", "*=", "/=", "++", "--"}
_OPS3 = ("...",)
_OPS2 = (">>", "<<", ">=", "<=", "==", "!=", "&&", "||", "++", "--", "+=", "-=", "*=", "/=", "::")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_NUMBER = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[Ee][-+]?\d+)?")


class GeoRefused(ValueError):
    """A geometry file (or a file it includes) has a statement that acts outside gmsh.

    The message is one line: ``FILE:LINE: 'STATEMENT' WHY; geometry files are data ...``.

    Args:
        file: the file, as it should be shown.
        line: 1-based line number (0 for the file as a whole).
        message: what is refused and why.
    """

    def __init__(self, file: str, line: int, message: str) -> None:
        self.file = file
        self.line = line
        self.message = message
        where = f"{file}:{line}" if line else file
        super().__init__(f"{where}: {message}")

    def __reduce__(self) -> tuple[type, tuple[str, int, str]]:
        """Pickle by constructor arguments (the error may be broadcast over MPI)."""
        return (GeoRefused, (self.file, self.line, self.message))


@dataclass(frozen=True)
class Token:
    """One lexical token of a ``.geo`` file.

    Attributes:
        kind: ``"name"``, ``"number"``, ``"string"`` (text without the quotes) or ``"op"``.
        text: the token's text.
        line: 1-based line where it starts.
    """

    kind: str
    text: str
    line: int


def _shown(path: Path) -> str:
    """``path`` relative to the working directory when it lies below it."""
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def tokenize(text: str, file: str = "<geo>") -> list[Token]:
    """Split ``.geo`` source into tokens as gmsh's lexer does; comments are dropped.

    Raises:
        GeoRefused: a NUL byte (gmsh's lexer ends comments and strings there and reads the
            rest as code), an unterminated comment or string, or a string longer than
            :data:`MAX_STRING` characters (gmsh reads its tail as code).
    """
    if "\0" in text:
        line = text.count("\n", 0, text.index("\0")) + 1
        raise GeoRefused(file, line, "NUL byte in the file; gmsh would read what follows as code")
    tokens: list[Token] = []
    i, line, n = 0, 1, len(text)
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
            i += 1
        elif c in " \t\r\f\v":
            i += 1
        elif text.startswith("//", i):
            end = text.find("\n", i)
            i = n if end < 0 else end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            if end < 0:
                raise GeoRefused(file, line, "unterminated /* comment")
            line += text.count("\n", i, end)
            i = end + 2
        elif c in "\"'":
            end = text.find(c, i + 1)
            if end < 0:
                raise GeoRefused(file, line, "unterminated string")
            body = text[i + 1 : end]
            if len(body) > MAX_STRING:
                raise GeoRefused(
                    file, line, f"string longer than {MAX_STRING} characters (gmsh cuts it)"
                )
            tokens.append(Token("string", body, line))
            line += body.count("\n")
            i = end + 1
        elif c.isdigit() or (c == "." and i + 1 < n and text[i + 1].isdigit()):
            m = _NUMBER.match(text, i)
            assert m is not None
            tokens.append(Token("number", m.group(), line))
            i = m.end()
        elif c.isalpha() or c == "_":
            m = _NAME.match(text, i)
            assert m is not None
            tokens.append(Token("name", m.group(), line))
            i = m.end()
        else:
            op = next((o for o in (*_OPS3, *_OPS2) if text.startswith(o, i)), c)
            tokens.append(Token("op", op, line))
            i += len(op)
    return tokens


def _closing(tokens: list[Token], start: int) -> int:
    """Index of the bracket closing the one at ``start`` (or len(tokens))."""
    pairs = {"(": ")", "[": "]", "{": "}"}
    stack = [pairs[tokens[start].text]]
    i = start + 1
    while i < len(tokens) and stack:
        t = tokens[i]
        if t.kind == "op" and t.text in pairs:
            stack.append(pairs[t.text])
        elif t.kind == "op" and t.text == stack[-1]:
            stack.pop()
        i += 1
    return i - 1


def _text(tokens: list[Token], i: int) -> str:
    return tokens[i].text if i < len(tokens) else ""


def _literal_file(
    tokens: list[Token], i: int, what: str, here: Path, root: Path, shown: str
) -> tuple[Path, int]:
    """The in-tree file named by the string literal at ``tokens[i]``; (path, next index)."""
    t = tokens[i - 1]
    if i >= len(tokens) or tokens[i].kind != "string":
        raise GeoRefused(
            shown, t.line, f"'{what}' of a computed file name cannot be checked; {_TRUST}"
        )
    name = tokens[i].text
    target = (here.parent / name).resolve()
    if not target.is_relative_to(root):
        raise GeoRefused(
            shown,
            t.line,
            f"'{what} \"{name}\"' reads a file outside '{_shown(root)}'; {_TRUST}",
        )
    if not target.is_file():
        raise GeoRefused(shown, t.line, f"'{what} \"{name}\"': no such file (looked for {target})")
    return target, i + 1


def _scan_tokens(tokens: list[Token], here: Path, root: Path, shown: str) -> list[Path]:
    """Refuse what acts outside the model; return the files this one includes."""
    includes: list[Path] = []
    for i, t in enumerate(tokens):
        if t.kind != "name":
            continue
        word, nxt = t.text, _text(tokens, i + 1)
        if word in _REFUSED:
            raise GeoRefused(shown, t.line, f"'{word}' {_REFUSED[word]}; {_TRUST}")
        if word == "Print" and nxt != ".":
            raise GeoRefused(shown, t.line, f"'Print' writes a file; {_TRUST}")
        if word == "Delete" and nxt == "File":
            raise GeoRefused(shown, t.line, f"'Delete File' deletes a file; {_TRUST}")
        if word == "Printf" and nxt == "(":
            after = _closing(tokens, i + 1) + 1
            if _text(tokens, after) in (">", ">>"):
                raise GeoRefused(
                    shown, t.line, f"'Printf(...) {_text(tokens, after)}' writes a file; {_TRUST}"
                )
        if word in _OPTION_CATEGORIES and nxt in (".", "["):
            j = i + 1
            while j < len(tokens) and tokens[j].text in (".", "["):
                j = _closing(tokens, j) + 1 if tokens[j].text == "[" else j + 2
            if _text(tokens, j) in _ASSIGN:
                raise GeoRefused(
                    shown,
                    t.line,
                    f"'{word}.*' options set gmsh's files and commands; {_TRUST}",
                )
        if word == "Include":
            target, _ = _literal_file(tokens, i + 1, "Include", here, root, shown)
            includes.append(target)
        if word == "ListFromFile" and nxt in ("(", "["):
            _literal_file(tokens, i + 2, "ListFromFile", here, root, shown)
    return includes


def scan_geo(path: Path) -> list[Path]:
    """Check a ``.geo`` file and every file it includes; return the files read.

    Includes are resolved relative to the including file, as gmsh does, and must lie in
    the directory tree of ``path`` (symbolic links resolved) and exist.

    Raises:
        GeoRefused: one line naming file, line and the refused statement.
    """
    root = path.resolve().parent
    seen: list[Path] = []

    def visit(current: Path, chain: tuple[Path, ...]) -> None:
        shown = _shown(current)
        if current in chain:
            raise GeoRefused(shown, 0, "includes itself (gmsh would never stop)")
        if current in seen:
            return  # gmsh reads it again; its content is already checked
        if len(seen) >= MAX_FILES:
            raise GeoRefused(_shown(path), 0, f"includes more than {MAX_FILES} files")
        seen.append(current)
        try:
            text = current.read_bytes().decode("latin-1")
        except OSError as exc:
            raise GeoRefused(shown, 0, f"cannot read: {exc.strerror}") from None
        for target in _scan_tokens(tokenize(text, shown), current, root, shown):
            visit(target, (*chain, current))

    visit(path.resolve(), ())
    return seen


@dataclass(frozen=True)
class ParameterSpec:
    """What a ``DefineConstant`` entry says about a parameter (None: not said or unclear).

    Attributes:
        name: the parameter.
        default: its default value when a plain number.
        minimum, maximum: ``Min``/``Max`` (or ``Range {min, max, step}``) when numbers.
        step: ``Step`` (or the third entry of ``Range``) when a number.
    """

    name: str
    default: float | None = None
    minimum: float | None = None
    maximum: float | None = None
    step: float | None = None

    @property
    def integer(self) -> bool:
        """The file marks it an integer: ``Step 1`` and an integer default."""
        return self.step == 1 and self.default is not None and float(self.default).is_integer()


def _number(tokens: list[Token]) -> float | None:
    """The value of ``[-+]? NUMBER`` tokens, else None (an expression is not evaluated)."""
    sign = 1.0
    if len(tokens) == 2 and tokens[0].text in "+-" and tokens[0].kind == "op":
        sign = -1.0 if tokens[0].text == "-" else 1.0
        tokens = tokens[1:]
    if len(tokens) == 1 and tokens[0].kind == "number":
        return sign * float(tokens[0].text)
    return None


def _split(tokens: list[Token]) -> list[list[Token]]:
    """Split at top-level commas."""
    parts: list[list[Token]] = [[]]
    depth = 0
    for t in tokens:
        if t.kind == "op" and t.text in "([{":
            depth += 1
        elif t.kind == "op" and t.text in ")]}":
            depth -= 1
        if depth == 0 and t.kind == "op" and t.text == ",":
            parts.append([])
        else:
            parts[-1].append(t)
    return [p for p in parts if p]


def _spec(entry: list[Token]) -> ParameterSpec | None:
    if not entry or entry[0].kind != "name":
        return None
    name = entry[0].text
    eq = next((k for k, t in enumerate(entry) if t.text == "="), None)
    if eq is None:
        return ParameterSpec(name)
    value = entry[eq + 1 :]
    if not (value and value[0].text == "{" and value[-1].text == "}"):
        return ParameterSpec(name, default=_number(value))
    items = _split(value[1:-1])
    attrs: dict[str, float | None] = {}
    for item in items[1:]:
        key = item[0].text
        if key == "Range" and len(item) > 2 and item[1].text == "{":
            bounds = [_number(p) for p in _split(item[2:-1])]
            for k, v in zip(("Min", "Max", "Step"), bounds, strict=False):
                attrs[k] = v
        elif key in ("Min", "Max", "Step"):
            attrs[key] = _number(item[1:])
    return ParameterSpec(
        name,
        default=_number(items[0]) if items else None,
        minimum=attrs.get("Min"),
        maximum=attrs.get("Max"),
        step=attrs.get("Step"),
    )


def parameter_specs(text: str) -> dict[str, ParameterSpec]:
    """The ``DefineConstant[...]`` entries of ``.geo`` source ``text``, by name."""
    tokens = tokenize(text)
    specs: dict[str, ParameterSpec] = {}
    for i, t in enumerate(tokens):
        if t.text == "DefineConstant" and _text(tokens, i + 1) == "[":
            end = _closing(tokens, i + 1)
            for entry in _split(tokens[i + 2 : end]):
                spec = _spec(entry)
                if spec is not None:
                    specs.setdefault(spec.name, spec)
    return specs


def count_parameters(text: str) -> dict[str, str]:
    """Names used directly as a number of mesh divisions -> the statement that uses them.

    ``Transfinite Curve|Line {...} = n`` or ``= n +- k`` (k an integer), and ``Layers{n}``
    or ``Layers{{n, ...}, {...}}``: gmsh truncates a non-integer ``n``.
    """
    tokens = tokenize(text)
    uses: dict[str, str] = {}
    for i, t in enumerate(tokens):
        if t.text == "Transfinite" and _text(tokens, i + 1) in ("Curve", "Line"):
            if _text(tokens, i + 2) != "{":
                continue
            j = _closing(tokens, i + 2) + 1
            if _text(tokens, j) != "=":
                continue
            end = j + 1
            while end < len(tokens) and tokens[end].text not in (";", "Using"):
                end += 1
            rhs = tokens[j + 1 : end]
            if rhs and rhs[0].kind == "name":
                tail = rhs[1:]
                simple = not tail or (
                    len(tail) == 2
                    and tail[0].text in "+-"
                    and tail[1].kind == "number"
                    and float(tail[1].text).is_integer()
                )
                if simple:
                    shown = f"Transfinite {tokens[i + 1].text}{{...}} = " + " ".join(
                        x.text for x in rhs
                    )
                    uses.setdefault(rhs[0].text, shown)
        elif t.text == "Layers" and _text(tokens, i + 1) == "{":
            end = _closing(tokens, i + 1)
            inner = tokens[i + 2 : end]
            if inner and inner[0].text == "{":
                inner = inner[1 : _closing(inner, 0)]
            for part in _split(inner):
                if len(part) == 1 and part[0].kind == "name":
                    uses.setdefault(part[0].text, f"Layers{{{part[0].text}}}")
    return uses


def check_parameters(
    parameters: dict[str, float], specs: dict[str, ParameterSpec], counts: dict[str, str]
) -> list[tuple[str, str]]:
    """What is wrong with ``parameters``: a list of (parameter name, message).

    Args:
        parameters: name -> value, as the scene gives them.
        specs: the file's ``DefineConstant`` entries (:func:`parameter_specs`).
        counts: parameters used as numbers of divisions (:func:`count_parameters`).
    """
    errors: list[tuple[str, str]] = []
    for name, value in parameters.items():
        v = float(value)
        spec = specs.get(name, ParameterSpec(name))
        if not math.isfinite(v):
            errors.append((name, f"must be finite, got {value!r}"))
        elif abs(v) > PARAMETER_BOUND:
            errors.append(
                (
                    name,
                    f"must lie within +-{PARAMETER_BOUND:g} (gmsh turns larger values into "
                    f"overflowing integers and silently meshes something else), got {value!r}",
                )
            )
        elif spec.minimum is not None and v < spec.minimum:
            errors.append(
                (name, f"must be >= {spec.minimum:g} (the file's DefineConstant), got {value!r}")
            )
        elif spec.maximum is not None and v > spec.maximum:
            errors.append(
                (name, f"must be <= {spec.maximum:g} (the file's DefineConstant), got {value!r}")
            )
        elif not v.is_integer() and (spec.integer or name in counts):
            why = (
                f"the file uses it as a number of divisions: {counts[name]}"
                if name in counts
                else "the file's DefineConstant declares Step 1"
            )
            errors.append((name, f"must be an integer ({why}), got {value!r}"))
    return errors
