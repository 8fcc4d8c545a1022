"""The scene reference documents every key the loader accepts."""

import re

from geofrac import analytic, effects, elements
from geofrac.scene.load import OUTPUT_FIELDS, SECTION_KEYS, TOP_LEVEL_KEYS
from tests.conftest import REPO

TEXT = (REPO / "docs" / "scenes.md").read_text()


def _section(title: str) -> str:
    for heading in (f"## `[{title}]`", f"## `[[{title}]]`"):
        if heading in TEXT:
            start = TEXT.index(heading)
            end = TEXT.find("\n## ", start + 1)
            return TEXT[start : end if end > 0 else None]
    raise AssertionError(f"docs/scenes.md has no section for [{title}]")


def test_every_top_level_key_is_documented():
    for key in TOP_LEVEL_KEYS:
        assert f"`{key}`" in TEXT or f"[{key}]" in TEXT, key


def test_every_table_key_has_a_row_in_its_section():
    for section, keys in SECTION_KEYS.items():
        body = _section(section)
        for key in keys:
            assert re.search(rf"^\| `{key}` \|", body, re.MULTILINE), f"{section}.{key}"


def test_every_registered_name_is_documented():
    names = [*elements.available(), *effects.available(), *analytic.EXACT_SOLUTIONS, *OUTPUT_FIELDS]
    for name in names:
        assert f"`{name}`" in TEXT or f'"{name}"' in TEXT, name


def test_every_dfn_key_has_a_row():
    from geofrac.effects.dfn import CIRCLE_KEYS, HORSESHOE_KEYS, REGION_KEYS, SET_KEYS, TABLE_KEYS

    start = TEXT.index("### `[dfn]`")
    body = TEXT[start:]
    rows = re.findall(r"^\| (`[^|]*`) \|", body, re.MULTILINE)  # first cells, e.g. `a`, `b`
    documented = {name for row in rows for name in re.findall(r"`(\w+)`", row)}
    for key in (*TABLE_KEYS, *SET_KEYS, *REGION_KEYS):
        assert key in documented, key
    for key in (*CIRCLE_KEYS, *HORSESHOE_KEYS):  # the shapes' keys, in their rows' text
        assert f"`{key}`" in body[: body.index("## MPM scenes")], key


def test_every_cracking_key_has_a_row():
    from geofrac.effects.cracking import KEYS

    start = TEXT.index("### `[cracking]`")
    body = TEXT[start : TEXT.index("### `[dfn]`")]
    for key in KEYS:
        assert re.search(rf"^\| `{key}` \|", body, re.MULTILINE), key


def test_every_mpm_key_has_a_row():
    from geofrac.effects import friction, mls_smoothing, plasticity
    from geofrac.scene.mpm import MPM_KEYS, MPM_OUTPUT_FIELDS

    start = TEXT.index("## MPM scenes")
    body = TEXT[start:]
    for key in (*MPM_KEYS["mpm"], *MPM_KEYS["mpm.particles"], *MPM_KEYS["mpm.bodies"]):
        assert re.search(rf"^\| `{key}` \|", body, re.MULTILINE), key
    for key in MPM_KEYS["mpm.grid"]:
        assert f"`{key}`" in body, key
    for module in (friction, mls_smoothing, plasticity):
        for key in module.KEYS:
            assert re.search(rf"^\| `{key}` \|", body, re.MULTILINE), key
    for name in MPM_OUTPUT_FIELDS:
        assert f"`{name}`" in body, name


def test_every_gravity_key_is_documented():
    from geofrac.effects.gravity import KEYS

    row = next(line for line in TEXT.splitlines() if line.startswith("| `gravity` |"))
    for key in KEYS:
        assert f"`{key}`" in row, key


def test_every_blocks_key_has_a_row():
    import dataclasses

    from geofrac.meshing.terrain import TerrainSpec
    from geofrac.scene.blocks import BLOCKS_KEYS, BLOCKS_OUTPUT_KEYS

    start = TEXT.index("## Block scenes")
    body = TEXT[start:]
    terrain = [f.name for f in dataclasses.fields(TerrainSpec)]
    for key in (*BLOCKS_KEYS, *BLOCKS_OUTPUT_KEYS, *terrain):
        assert re.search(rf"^\| `{key}` \|", body, re.MULTILINE), key


def _product_texts() -> list:
    """README, docs pages, and the package's Python and C sources."""
    files = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
    files += sorted((REPO / "geofrac").rglob("*.py")) + sorted((REPO / "geofrac").rglob("*.c"))
    return files


def test_the_thesis_is_never_called_the_seed():
    """Seed means a random-number seed (or a seed point); the thesis is Edo (2016)."""
    thesis = re.compile(
        r"\bseed'?s?\s+(eq|fig|table|§|thesis|chapter|model|value|number)"
        r"|\b(the|of the|in the)\s+seed\b(?!\s+(point|of|and|only|must|\d))"
        r"|\bseed\s+§",
        re.IGNORECASE,
    )
    random_words = ("random", "rng", "generator", "seeded", "draw")
    hits = []
    for path in _product_texts():
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if thesis.search(line) and not any(w in line.lower() for w in random_words):
                hits.append(f"{path.relative_to(REPO)}:{n}: {line.strip()}")
    assert not hits, "\n".join(hits)


def test_docs_link_only_inside_the_repository_and_cite_no_issue_numbers():
    link = re.compile(r"\]\(([^)\s]+)\)")
    hits = []
    for path in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        text = path.read_text()
        for target in link.findall(text):
            if re.match(r"[a-z]+:", target):
                hits.append(f"{path.name}: external link {target}")
                continue
            resolved = (path.parent / target.split("#")[0]).resolve()
            if REPO.resolve() not in resolved.parents or not resolved.exists():
                hits.append(f"{path.name}: link {target} leaves the repository or is broken")
        for m in re.finditer(r"\bissues?\s+#?\d+", text, re.IGNORECASE):
            hits.append(f"{path.name}: cites {m.group(0)!r}")
        if "shared/" in text:
            hits.append(f"{path.name}: names a path outside the repository")
    assert not hits, "\n".join(hits)


#: The commands a picture's "made by" may start with (docs/output.md, "Pictures").
ENTRY_POINTS = ("geofrac", "mpiexec", "python", "make")
MADE_BY = re.compile(r"<!-- (\S+\.png) made by: (.+?) -->")
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+\.png)\)")


def _entry_point_problem(command: str) -> str | None:
    """Why ``command`` is not a known entry point of the repository, or None."""
    words = command.split()
    if words[0] == "mpiexec":  # mpiexec -n N geofrac ...
        words = words[3:] if len(words) > 3 and words[1] == "-n" else []
        return None if words[:1] == ["geofrac"] else "mpiexec does not run geofrac"
    if words[0] == "python":
        script = words[1] if len(words) > 1 else ""
        if not script.endswith(".py") or not (REPO / script).is_file():
            return f"no script {script!r} in the repository"
        return None
    if words[0] == "make":
        target = words[1] if len(words) > 1 else ""
        makefile = (REPO / "Makefile").read_text()
        return None if re.search(rf"^{re.escape(target)}:", makefile, re.M) else "no make target"
    return None if words[0] in ENTRY_POINTS else f"{words[0]!r} is no entry point"


def test_every_picture_exists_and_names_the_command_that_made_it():
    """Each image of README.md and docs/*.md exists and names the command that made it.

    The comment ``<!-- PATH made by: CMD -->`` sits next to the image; PATH is the
    image's link as written; CMD starts with an entry point of the repository
    (``geofrac``, ``mpiexec -n N geofrac``, ``python SCRIPT.py`` with the script in the
    repository, ``make TARGET``).
    """
    hits = []
    for path in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        text = path.read_text()
        made = {}
        for name, command in MADE_BY.findall(text):
            made.setdefault(name, command.strip())
        for target in IMAGE.findall(text):
            where = f"{path.relative_to(REPO)}: {target}"
            if not (path.parent / target).is_file():
                hits.append(f"{where}: no such file")
            if target not in made:
                hits.append(f"{where}: no '<!-- {target} made by: COMMAND -->'")
            elif (problem := _entry_point_problem(made[target])) is not None:
                hits.append(f"{where}: made by {made[target]!r}: {problem}")
    assert not hits, "\n".join(hits)
