"""Size estimates: every scene of jobs/ is well below every cap; the formulas' anchors."""

import pytest

from geofrac.scene import load_scene
from geofrac.scene.size import CAPS, format_count
from tests.conftest import JOBS


def test_every_job_is_ten_times_below_every_cap():
    for path in sorted(JOBS.glob("*.toml")):
        scene = load_scene(path)
        assert scene.size is not None and scene.size.summary()
        for name, value in scene.size.quantities.items():
            if name in CAPS:
                assert value * 10 <= CAPS[name][0], (path.name, name, value)


def test_estimates_match_the_structured_meshes_and_the_terrain():
    quick = load_scene(JOBS / "quickstart.toml").size.quantities
    assert quick["cells"] == 320  # 40 x 4 squares, two triangles each
    assert quick["dofs"] == pytest.approx(2 * 4 * 160)  # P2: 2 x 4 nodes per vertex
    for element, per_vertex in (("cst", 2), ("rgnt", 3), ("gnt", 6)):  # (u, v), (u, v, θ), ...
        dofs = load_scene(JOBS / "quickstart.toml", [f"discretization.element={element}"])
        assert dofs.size.quantities["dofs"] == pytest.approx(per_vertex * 160), element
    bar = load_scene(JOBS / "mpm_bar_w1000.toml").size.quantities
    assert bar["particles"] == 100 and bar["grid_nodes"] == 59
    assert bar["steps"] == 500  # t_end 0.05, dt = 0.1 * 1 / sqrt(1e6 / 1)
    terrain = load_scene(JOBS / "terrain_100k.toml").size.quantities
    assert terrain["blocks"] == pytest.approx(100_643, rel=0.05)


def test_format_count():
    assert format_count(80) == "80"
    assert format_count(1.0e9) == "1.0e9"
