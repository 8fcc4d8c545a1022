"""The source thesis is cited as Edo (2016) in every tracked text file, never as "the seed".

"Seed" means a random-number seed (``seed = 7``, ``precrack_seed``, "DFN set 1, seed 1",
"seeded"), a Voronoi or grain seed point, or a crack nucleus ("seeds at the notch
tips"); the thesis is "Edo (2016), eq. 2.24", "Edo (2016), §2.4.3", "Edo (2016),
Fig. 5.10", "Edo (2016), Table 2.1". tests/test_docs.py checks the product texts
(README, docs, geofrac) with its own pattern; this test covers every tracked text file,
the meshes' comments, the tests' and scripts' docstrings and the job files included.
"""

import re
import subprocess

from tests.conftest import REPO

#: Suffixes of the text files checked.
SUFFIXES = (".py", ".md", ".toml", ".geo", ".txt", ".json", ".csv", ".c", ".h", ".sh")

#: Forms that cite the thesis as "seed" whatever the line says (section numbers, the
#: thesis' figures, equations and tables, its meshes and model sizes, its counts).
THESIS = re.compile(
    r"\bseed(?:'s|s)?\s+(?:eqs?\b|fig|table|§|thesis|chapter|ch\.|section|app\.|appendix"
    r"|models?\b|meshe?s?\b|size\b|scale\b|shape\b|patch\b)"
    r"|\bseed[-‐](?:size|scale)\b"
    r"|\bseed(?:'s)?\s+\d+\.\d"
    r"|\bseed:\s+(?:\d{1,3}(?:,\d{3})+|\d+\s+(?:nodes|elements|faces|triangles|blocks)\b)"
    r"|\bthe\s+seed's\b",
    re.IGNORECASE,
)

#: "The seed" as a subject ("the seed gives", "(the seed: uniform"), unless a random
#: seed is meant (the line speaks of randomness, or "the seed and the key", "the seed of").
THE_SEED = re.compile(
    r"\b(?:the|of the|in the)\s+seed\b(?!\s+(?:point|of|and the|only|must|\d))", re.IGNORECASE
)
RANDOM_WORDS = ("random", "rng", "generator", "seeded", "draw")


def _tracked_texts() -> list:
    """Tracked text files (git ls-files; every file under the repository without git)."""
    try:
        out = subprocess.run(
            ["git", "ls-files"], cwd=REPO, capture_output=True, text=True, check=True
        ).stdout.split()
        files = [REPO / name for name in out]
    except (OSError, subprocess.CalledProcessError):
        files = [p for p in REPO.rglob("*") if ".venv" not in p.parts and ".git" not in p.parts]
    return sorted(p for p in files if p.suffix in SUFFIXES and p.is_file())


def thesis_called_seed(line: str) -> bool:
    """Whether ``line`` cites the thesis as "seed"."""
    if THESIS.search(line):
        return True
    return bool(THE_SEED.search(line)) and not any(w in line.lower() for w in RANDOM_WORDS)


def test_the_patterns_tell_the_thesis_from_random_seeds():
    thesis = [
        "// Notched beam after Galvez et al. (seed thesis, section 2.4.3): a beam",
        "// 7,800 nodes (seed: 7,863).",
        "(seed: 12,933 nodes, 25,448 elements)",
        "# seed Table 2.1: (name, mean angle in degrees, variance in deg²)",
        '"""Seed 4.5.1 (Fig. 4.13): RMS stress error below 2%."""',
        "the lengths pass a KS test against the power law of seed eq. (2.28)",
        "the seed's Table 2.1 (3000 fractures each)",
        "# the seed-scale terrain at h = 25 m",
        "#: A coarse mesh of the seed models for tests (the seed size is geofrac bench dfn)",
        "// The seed gives the slope length (237 m along the ground surface)",
        '"""C-MultiMLSM node field (seed App. C, eqs. 3.12-3.28)."""',
        "// Seed patch test (section 2.4.2, Fig. 2.9): a = 5 mm",
        "assert np.all(faces == 6)  # seed: 6 faces each",
    ]
    random = [
        "seed = 7",
        "precrack_seed: int = 0",
        "fractures (DFN set 1, seed 1) and run parallel to the compression.",
        "P21 0.5 and 0.4 /m, seed 7), with the heading and the bench as mesh regions",
        "The random point of a triangle depends only on the seed and the key of the triangle",
        "positions (x, then y), so the choice depends on the mesh's geometry and the seed only:",
        "whether each interface belongs to a seed's crack, shape=(num_edges,).",
        "Edo (2016) 2.4.5, Zhu and Tang: seeds at the notch tips, then the crack of one",
        "under any numbering of the mesh); before, this seed met the top 25-40 mm right",
        "`geofrac bench stability` (the defaults: ny = 8, seed 0). 52 cases in 6.4 s;",
        "rng = np.random.default_rng(seed)",
        "Repeated over seeds 0-299 (900 set samples), the KS test at p <= 0.01",
    ]
    assert [line for line in thesis if not thesis_called_seed(line)] == []
    assert [line for line in random if thesis_called_seed(line)] == []


def test_no_tracked_text_calls_the_thesis_the_seed():
    this = REPO / "tests" / "test_citations.py"
    hits = []
    for path in _tracked_texts():
        if path == this:
            continue
        for n, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if thesis_called_seed(line):
                hits.append(f"{path.relative_to(REPO)}:{n}: {line.strip()}")
    assert not hits, "\n".join(hits)
