"""The import graph of geofrac goes one way: a module imports only its own layer or lower.

Every module under ``geofrac/`` and ``forms/`` (the UFL forms, imported as
``geofrac_forms``) is parsed with :mod:`ast`; every ``import`` counts, at module level and
inside functions (a function-level import is still a dependency, only a later one). An
import of ``geofrac.x.y`` also runs ``geofrac/x/__init__.py``, so a package's ``__init__``
is checked like any module. See docs/architecture.md.

PETSc is reached through :mod:`geofrac.solvers` only: no other module imports
``petsc4py`` or ``dolfinx.fem.petsc``.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "geofrac"

#: Source folders and the package each holds.
PACKAGES = {"geofrac": ROOT, "geofrac_forms": ROOT.parent / "forms"}

#: The layers, lowest first: (layer name, module prefixes). A module belongs to the entry
#: with its longest matching prefix; it may import modules of its own layer and lower.
LAYERS: tuple[tuple[str, tuple[str, ...]], ...] = (
    # pure leaves: no geofrac imports but each other ("geofrac" is the package's
    # __init__, which holds only __version__)
    (
        "leaves",
        (
            "geofrac",
            "geofrac.errors",
            "geofrac.log",
            "geofrac.timing",
            "geofrac.interrupt",
            "geofrac.materials",
            "geofrac.analytic",
            "geofrac.analytic_joints",
            "geofrac.kernels",
            # the plasticity laws MPM and the finite-element solver share (pure numpy)
            "geofrac.plasticity",
        ),
    ),
    # the UFL forms (geofrac_forms, folder forms/): pure symbolic definitions that
    # DOLFINx compiles; they import ufl and numpy, no geofrac module above the leaves
    ("forms", ("geofrac_forms",)),
    # the validated scene as data (dataclasses, table checks, expressions): what every
    # layer above reads; importing it imports no loader, no effect, no mesher
    ("scene model", ("geofrac.model",)),
    # file formats: writers and readers of arrays and meshes (XDMF, VTU, CSV series,
    # checkpoints); they know no engine's data types, so the engines may stream into them
    (
        "file formats",
        (
            "geofrac.io",
            "geofrac.io.checkpoint",
            "geofrac.io.grains",
            "geofrac.io.points",
            "geofrac.io.series",
            "geofrac.io.xdmf",
        ),
    ),
    # meshes and the geometry they are made of (DFN networks, gmsh, distribution)
    ("mesh", ("geofrac.meshing", "geofrac.dfn", "geofrac.dfn3d", "geofrac.geometry")),
    # linear algebra: the one adapter to PETSc (matrices, vectors, KSP, MUMPS, assembly of
    # compiled forms); it imports the leaves only (test_linear_algebra_imports_only_leaves)
    ("linear algebra", ("geofrac.solvers",)),
    # discretisation: elements, elastic problems, MLS shape functions
    ("discretisation", ("geofrac.elements", "geofrac.fem", "geofrac.mls")),
    # drivers: the engines that run a discretised problem (crack event loop, MPM time
    # loop, block building and checks)
    ("driver", ("geofrac.fracture", "geofrac.mpm", "geofrac.blocks")),
    # effects: plug-ins binding a scene table to the layers below (configure, forms,
    # a driver); chosen by name at run time through geofrac.effects.load
    ("effects", ("geofrac.effects",)),
    # output of a run: the summary and the owned, published output directory (written
    # once, by the pipeline)
    ("output", ("geofrac.io.summary", "geofrac.io.outdir")),
    # orchestration: loading a scene file (geofrac.scene: it calls effects, elements and
    # meshers to validate),
    # the run pipeline and its methods, the command line, the benchmarks, the validation
    (
        "orchestration",
        (
            "geofrac.scene",
            "geofrac.pipeline",
            "geofrac.runner",
            "geofrac.cli",
            "geofrac.__main__",
            "geofrac.bench",
            # the validation suite runs scenes and benches
            "geofrac.validation",
            # the mesh-dependence bench measures its paths with the validation's
            # measures (geofrac.validation.paths): it sits above the validation, which
            # uses the other benches' reporting
            "geofrac.bench.mesh_dependence",
        ),
    ),
)


def _modules() -> dict[str, Path]:
    out = {}
    for package, folder in PACKAGES.items():
        for path in folder.rglob("*.py"):
            parts = [package, *path.relative_to(folder).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts.pop()
            out[".".join(parts)] = path
    return out


def _ours(module: str) -> bool:
    """Whether ``module`` is one of geofrac's packages or inside one."""
    return any(module == p or module.startswith(p + ".") for p in PACKAGES)


MODULES = _modules()


def _imports(name: str, path: Path) -> list[tuple[str, int]]:
    """(imported geofrac module, line) of every import in the module, at any depth."""
    is_package = path.name == "__init__.py"
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                package = name.split(".") if is_package else name.split(".")[:-1]
                base = package[: len(package) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            if not _ours(module):
                continue
            for alias in node.names:  # `from geofrac.x import y` may import module x.y
                sub = f"{module}.{alias.name}"
                found.append((sub if sub in MODULES else module, node.lineno))
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if _ours(alias.name):
                    found.append((alias.name, node.lineno))
    return found


def layer(module: str) -> int:
    """Index in :data:`LAYERS` of the entry with the longest prefix of ``module``."""
    best, index = -1, -1
    for i, (_, prefixes) in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, index = len(prefix), i
    assert index >= 0, f"{module} is in no layer: add it to LAYERS"
    return index


def edges() -> list[tuple[str, str, int]]:
    """(importer, imported, line) over all geofrac modules.

    An import of a submodule also counts as one of each parent package's ``__init__``.
    """
    out = []
    for name, path in sorted(MODULES.items()):
        for target, line in _imports(name, path):
            out.append((name, target, line))
            parts = target.split(".")
            for k in range(1, len(parts)):  # the parents' __init__ run first
                parent = ".".join(parts[:k])
                if parent in MODULES and not name.startswith(parent):
                    out.append((name, parent, line))
    return out


def unit(module: str) -> str:
    """What a module belongs to for the cycle check.

    Its own entry of :data:`LAYERS` when it has one below its package
    (``geofrac.io.outdir``), else its package (``geofrac.x``).
    """
    named = [p for _, prefixes in LAYERS for p in prefixes if p.count(".") > 1]
    own = [p for p in named if module == p or module.startswith(p + ".")]
    if own:
        return max(own, key=len)
    top = module.partition(".")[0]
    if top != "geofrac":  # geofrac_forms: one unit
        return top
    return ".".join(module.split(".")[:2])


def test_every_module_has_a_layer():
    for name in MODULES:
        layer(name)


def test_no_upward_import():
    upward = [
        f"{a}:{line} ({LAYERS[layer(a)][0]}) imports {b} ({LAYERS[layer(b)][0]})"
        for a, b, line in edges()
        if layer(b) > layer(a)
    ]
    assert not upward, "upward imports:\n" + "\n".join(upward)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found = []
    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10 * len(graph) + 100))

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_no_cycle_between_packages():
    graph: dict[str, set[str]] = {}
    witness: dict[tuple[str, str], str] = {}
    for a, b, line in edges():
        ua, ub = unit(a), unit(b)
        if ub not in (ua, "geofrac"):  # the package __init__ holds only __version__
            graph.setdefault(ua, set()).add(ub)
            witness.setdefault((ua, ub), f"{a}:{line} -> {b}")
    cycles = _cycles(graph)
    lines = []
    for component in cycles:
        lines += [w for (ua, ub), w in witness.items() if ua in component and ub in component]
    assert not cycles, f"package cycles {cycles}:\n" + "\n".join(sorted(lines))


#: Module cycles inside one package not yet broken (function-level imports both ways).
KNOWN_MODULE_CYCLES: list[list[str]] = []


def test_no_cycle_between_modules():
    graph: dict[str, set[str]] = {}
    for a, b, _ in edges():
        if b in MODULES and b != a and not a.startswith(b + "."):
            graph.setdefault(a, set()).add(b)
    new = [c for c in _cycles(graph) if c not in KNOWN_MODULE_CYCLES]
    assert not new, f"module import cycles: {new}"


def test_the_layer_check_sees_an_upward_import():
    """The checks themselves: an import of the loader from the scene model is upward."""
    assert layer("geofrac.scene.load") > layer("geofrac.model.scene")
    assert layer("geofrac.io.outdir") > layer("geofrac.mpm.driver") > layer("geofrac.io.points")
    assert layer("geofrac.fem.elastic") > layer("geofrac.solvers.linear") > layer("geofrac.meshing")
    assert (
        layer("geofrac.model.scene") > layer("geofrac_forms.elasticity") > layer("geofrac.errors")
    )
    assert unit("geofrac_forms.gradient_dofs") == "geofrac_forms"
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(graph) == [["a", "b", "c"]]


def test_linear_algebra_imports_only_leaves():
    """The PETSc adapter sits low so that every engine can use it: leaves only below it."""
    bad = [
        f"{a}:{line} imports {b}"
        for a, b, line in edges()
        if a.startswith("geofrac.solvers") and not b.startswith("geofrac.solvers")
        if layer(b) != 0
    ]
    assert not bad, "geofrac.solvers imports above the leaves:\n" + "\n".join(bad)


#: The modules that bind PETSc: only the solver adapter may import them.
PETSC_MODULES = ("petsc4py", "dolfinx.fem.petsc")


def petsc_imports(source: str, filename: str = "<source>") -> list[tuple[str, int]]:
    """(imported PETSc module, line) of every import of :data:`PETSC_MODULES` in ``source``.

    At any depth: in functions and in ``if TYPE_CHECKING:`` blocks too. ``from dolfinx.fem
    import petsc`` counts as an import of ``dolfinx.fem.petsc``.
    """

    def binds(module: str) -> bool:
        return any(module == m or module.startswith(m + ".") for m in PETSC_MODULES)

    found = []
    for node in ast.walk(ast.parse(source, filename)):
        if isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            found += [(n, node.lineno) for n in names if binds(n)][:1]
        elif isinstance(node, ast.Import):
            found += [(a.name, node.lineno) for a in node.names if binds(a.name)]
    return found


def test_only_the_solvers_import_petsc():
    """PETSc objects are made and configured in geofrac.solvers alone (issue 44)."""
    bad = [
        f"{name}:{line} imports {module}"
        for name, path in sorted(MODULES.items())
        if not (name == "geofrac.solvers" or name.startswith("geofrac.solvers."))
        for module, line in petsc_imports(path.read_text(), str(path))
    ]
    assert not bad, "import PETSc through geofrac.solvers:\n" + "\n".join(bad)


def test_the_petsc_check_sees_every_kind_of_import():
    """The check itself: module level, function level, TYPE_CHECKING, ``from`` forms."""
    source = (
        "from typing import TYPE_CHECKING\n"
        "import dolfinx.fem\n"
        "from dolfinx import fem\n"
        "if TYPE_CHECKING:\n"
        "    from petsc4py import PETSc\n"
        "def f():\n"
        "    import dolfinx.fem.petsc as p\n"
        "    from dolfinx.fem import petsc\n"
        "    from dolfinx.fem.petsc import assemble_matrix\n"
        "    import petsc4py.PETSc\n"
    )
    assert petsc_imports(source) == [
        ("petsc4py", 5),
        ("dolfinx.fem.petsc", 7),
        ("dolfinx.fem.petsc", 8),
        ("dolfinx.fem.petsc", 9),
        ("petsc4py.PETSc", 10),
    ]
    assert petsc_imports("import dolfinx\nfrom dolfinx.fem import Function\n") == []


@pytest.mark.parametrize(
    ("module", "absent"),
    [
        ("geofrac.model.scene", ("geofrac.scene", "geofrac.effects", "geofrac.meshing")),
        ("geofrac.model.table", ("geofrac.scene", "geofrac.effects", "geofrac.mpm")),
        ("geofrac.fem.elastic", ("geofrac.effects", "geofrac.scene", "geofrac.fracture")),
        ("geofrac.elements.efmm_numpy", ("geofrac.blocks",)),
        (
            "geofrac.solvers",
            ("geofrac.elements", "geofrac.fem", "geofrac.meshing", "geofrac.model"),
        ),
        ("geofrac_forms.gradient_dofs", ("geofrac.",)),
    ],
)
def test_a_lower_module_imports_alone(module, absent):
    """Importing ``module`` in a fresh interpreter imports none of the upper packages."""
    code = (
        f"import sys, {module}\nprint(sorted(m for m in sys.modules if m.startswith({absent!r})))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT.parent,
    )
    assert out.stdout.strip() == "[]", out.stdout
