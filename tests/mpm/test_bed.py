"""The bed polyline's nodes: ``plane`` and ``staircase`` representations (Edo (2016), 4.3.3).

The node sets are counted by hand on a 6 × 4 grid of unit cells under the bed
y = 2.5 − x/3 (x in [0, 6]); the run checks a block on a real inclined bed (a polyline,
gravity vertical) against the rigid-block closed form g (sin θ − μ cos θ).
"""

import numpy as np
import pytest

from geofrac.mpm.boundaries import bed_nodes, boundary_rows, scene_grid
from geofrac.mpm.elastic import Elastic
from geofrac.mpm.friction import friction
from geofrac.mpm.grid import grid
from geofrac.mpm.particles import lattice
from geofrac.mpm.schemes import StepSettings, step, time_step
from geofrac.scene import SceneError, load_scene

BED = np.array([[0.0, 2.5], [6.0, 0.5]])  # y = 2.5 - x/3


def _xy(g, ids):
    return sorted(map(tuple, g.nodes()[ids].tolist()))


def test_plane_and_staircase_nodes_under_a_sloping_bed_counted_by_hand():
    """Bed heights at x = 0..6: 2.5, 2.17, 1.83, 1.5, 1.17, 0.83, 0.5.

    On or below: 3 + 3 + 2 + 2 + 2 + 1 + 1 = 14 nodes. Staircase: a node is deep when
    the 8 nodes around it (a node beyond the grid counts by its coordinates, one beyond
    the polyline's x-range as above the bed) are below too: (1, 0), (2, 0) and (3, 0);
    (4, 0) sees (5, 1) above the bed, (1, 1) sees (2, 2), the column x = 0 sees x = −1.
    """
    g = grid([0.0, 0.0], 1.0, (6, 4))
    ids, n, d, deep = bed_nodes(g.nodes(), BED, 1.0, representation="plane")
    below = [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 0), (2, 1)]
    below += [(3, 0), (3, 1), (4, 0), (4, 1), (5, 0), (6, 0)]
    assert _xy(g, ids) == sorted(below) and len(deep) == 0
    ids_s, n_s, d_s, deep_s = bed_nodes(g.nodes(), BED, 1.0, representation="staircase")
    assert _xy(g, deep_s) == [(1, 0), (2, 0), (3, 0)]
    assert _xy(g, ids_s) == sorted(set(below) - {(1, 0), (2, 0), (3, 0)})
    # every row: the bed's normal (f', -1)/|.| into the bed, the plane through the bed
    normal = np.array([-1.0 / 3.0, -1.0]) / np.hypot(1.0 / 3.0, 1.0)
    for i, nn, dd in ((ids, n, d), (ids_s, n_s, d_s)):
        np.testing.assert_allclose(nn, np.tile(normal, (len(i), 1)))
        np.testing.assert_allclose(dd, normal @ [0.0, 2.5])  # (0, 2.5) is on the bed
    with pytest.raises(ValueError, match="representation"):
        bed_nodes(g.nodes(), BED, 1.0, representation="stairs")


def test_staircase_holds_the_deep_nodes_and_a_held_bed_is_the_same_either_way():
    g = scene_grid((0.0, 0.0), (6.0, 4.0), 1.0, padding=0)
    bed = tuple(map(tuple, BED))
    X = g.nodes()
    deep = [np.flatnonzero((X[:, 0] == x) & (X[:, 1] == 0)) for x in (1.0, 2.0, 3.0)]
    fixed, ids, *_ = boundary_rows(
        g, (0, 0), (6, 4), walls={}, bed=bed, frictional=("bed",), bed_representation="staircase"
    )
    assert np.all(fixed[np.concatenate(deep)]) and fixed.sum() == 2 * 3
    assert len(ids) == 11 and not np.isin(np.concatenate(deep), ids).any()
    fixed_p, ids_p, *_ = boundary_rows(
        g, (0, 0), (6, 4), walls={}, bed=bed, frictional=("bed",), bed_representation="plane"
    )
    assert not fixed_p.any() and len(ids_p) == 14
    held = [
        boundary_rows(g, (0, 0), (6, 4), walls={}, bed=bed, frictional=(), bed_representation=r)[0]
        for r in ("plane", "staircase")
    ]
    np.testing.assert_array_equal(held[0], held[1])
    assert held[0].sum() == 2 * 14


SCENE = """
method = "mpm"
effects = ["friction"]
[material]
E = 1e6
nu = 0.3
density = 1000.0
[mpm]
t_end = 0.1
grid = {{ lower = [0.0, 0.0], upper = [4.0, 2.0], spacing = 0.25 }}
particles = {{ lower = [1.0, 1.0], counts = [4, 4], spacing = 0.125 }}
{extra}
[friction]
mu = 0.2
{boundaries}
"""


@pytest.mark.parametrize(
    ("extra", "boundaries", "text"),
    [
        ('bed = [[0.0, 0.5], [4.0, 0.0]]\nbed_representation = "stairs"', "", "unknown value"),
        (
            'bed_representation = "staircase"\nwalls = { y_min = "fixed" }',
            'boundaries = ["y_min"]',
            "applies to a scene with an 'mpm.bed'",
        ),
    ],
)
def test_a_bad_bed_representation_names_the_key(tmp_path, extra, boundaries, text):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.format(extra=extra, boundaries=boundaries))
    with pytest.raises(SceneError) as info:
        load_scene(path)
    assert info.value.key == "mpm.bed_representation"
    assert text in info.value.message
    path.write_text(
        SCENE.format(
            extra='bed = [[0.0, 0.5], [4.0, 0.0]]\nbed_representation = "staircase"', boundaries=""
        )
    )
    assert load_scene(path).mpm.bed_representation == "staircase"


G0, RHO, CELL = 10.0, 1000.0, 0.1
MAT = Elastic(1e7, 0.3)


def _block_on_bed(theta_deg: float):
    """A 1 m × 0.5 m block (20 × 10 particles) resting on the bed y = −x tan θ.

    It starts from the stress of its own weight in the slope's frame (t downhill,
    m the bed's outward normal): σ_mm = −ρ g cos θ d, σ_tt = K₀ σ_mm, σ_tm = ρ g sin θ d
    at depth d below the block's top.
    """
    th = np.radians(theta_deg)
    t, m = np.array([np.cos(th), -np.sin(th)]), np.array([np.sin(th), np.cos(th)])
    p = lattice([0.0, 0.0], [20, 10], CELL / 2, density=RHO)
    s, h = p.x[:, 0] + 0.5, p.x[:, 1].copy()
    p.x[:] = s[:, None] * t + h[:, None] * m
    d, k0 = 0.5 - h, MAT.nu / (1 - MAT.nu)
    smm, stm = -RHO * G0 * np.cos(th) * d, RHO * G0 * np.sin(th) * d
    tt, mm, tm = np.outer(t, t), np.outer(m, m), np.outer(t, m) + np.outer(m, t)
    p.stress[:] = (k0 * smm)[:, None, None] * tt + smm[:, None, None] * mm
    p.stress[:] += stm[:, None, None] * tm
    p.stress_zz[:] = k0 * smm
    return p, t


@pytest.mark.parametrize("representation", ["plane", "staircase"])
def test_a_block_slides_down_a_30_degree_bed_at_the_coulomb_rate(representation):
    """μ = 0.3 < tan 30°: v(t) = g (sin θ − μ cos θ) t = 1.441 m/s at 0.6 s (uGIMP, MUSL).

    A bed that grips more than μ (nodes reached by the GIMP supports held in every
    component) stops the block instead.
    """
    theta, mu, t_end = 30.0, 0.3, 0.6
    p, t = _block_on_bed(theta)
    lo, up = (-0.5, -3.0), (4.0, 1.5)
    g = scene_grid(lo, up, CELL, padding=2)
    tan = np.tan(np.radians(theta))
    bed = ((-1.0, tan), (5.0, -5.0 * tan))
    fixed, ids, nrm, planes, _ = boundary_rows(
        g, lo, up, walls={}, bed=bed, frictional=("bed",), bed_representation=representation
    )
    dt = time_step(0.2, CELL, MAT, density=RHO, dim=2)
    fr = friction(ids, nrm, mu, offsets=planes)
    s = StepSettings("musl", "ugimp", dt, np.array([0.0, -G0]), fixed, friction=fr)
    for _ in range(round(t_end / dt)):
        step(g, p, MAT, settings=s)
    v = (p.mass @ p.v / p.mass.sum()) @ t
    exact = G0 * (np.sin(np.radians(theta)) - mu * np.cos(np.radians(theta))) * t_end
    assert abs(v - exact) < 0.01 * exact
    depth = np.max(p.x @ -np.array([np.sin(np.radians(theta)), np.cos(np.radians(theta))]))
    assert depth < 0.0  # no particle centre below the bed
