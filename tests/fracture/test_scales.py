"""The scales of the event loop's decisions, and the criterion's floor and ties (closed forms)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geofrac.fracture.criterion import TIE_TOLERANCE, least, select_edges, tie_order
from geofrac.fracture.scales import MAX_LOAD_RATIO, SEPARATED, TENSION_FLOOR, Scales
from tests.fracture.helpers import grid_mesh

#: A 40 x 80 specimen, δ = 0.01, E = 1e4, t = 2.
SCALES = Scales(math.hypot(40.0, 80.0), 0.01, 1e4, 2.0 * 40.0 * 80.0)


def test_scales_of_a_mesh_are_its_diagonal_and_volume():
    coords, cells = grid_mesh(6)  # the square [0, 6]² in 6 x 6 x 2 triangles
    x = coords / 6.0 * [40.0, 80.0]
    s = Scales.of_mesh(x, cells, displacement=0.01, modulus=1e4, thickness=2.0)
    assert s.length == pytest.approx(math.hypot(40.0, 80.0), rel=1e-14)
    assert s.volume == pytest.approx(2.0 * 40.0 * 80.0, rel=1e-14)


def test_stress_and_energy_are_those_of_a_uniform_strain():
    strain = 0.01 / math.hypot(40.0, 80.0)
    assert SCALES.stress == pytest.approx(1e4 * strain, rel=1e-14)
    assert SCALES.energy == pytest.approx(0.5 * 1e4 * strain**2 * 6400.0, rel=1e-14)
    # a uniform stress σ stores σ² V / (2E): its rms is σ
    assert SCALES.rms_stress(3.0**2 * 6400.0 / 2e4) == pytest.approx(3.0, rel=1e-14)
    assert SCALES.rms_stress(-1e-30) == 0.0


@pytest.mark.parametrize("energy", [0.0, -7e-16, 8.6e-17, 0.5 * SEPARATED * SCALES.energy])
def test_round_off_energy_at_the_first_event_is_separated(energy):
    """The numbers of a specimen pulled apart (8.6e-17 on one BLAS kernel, -7e-16 on another)."""
    why = SCALES.separated(energy, None)
    assert why is not None and "½ E V (δ/L)²" in why


def test_a_load_path_is_not_separated_and_later_events_use_the_first_energy():
    assert SCALES.separated(1e-6 * SCALES.energy, None) is None
    assert SCALES.separated(2e-9, 1.0) is None
    assert "first event" in SCALES.separated(0.5e-9, 1.0)


def test_events_beyond_the_specimen_or_far_beyond_the_first_load_are_refused():
    r_size = SCALES.length / SCALES.displacement  # r at which r δ = L
    assert SCALES.beyond(0.99 * r_size, None) is None
    assert "specimen's size" in SCALES.beyond(1.01 * r_size, None)
    assert SCALES.beyond(100.0, 1.0) is None
    assert f"{MAX_LOAD_RATIO:g} times" in SCALES.beyond(2.0 * MAX_LOAD_RATIO * 1e-3, 1e-3)
    assert SCALES.beyond(math.inf, None) is not None
    assert SCALES.beyond(math.nan, None) is not None


def test_a_measured_control_displacement_replaces_r_delta():
    """Force control: the bound is on the event's measured |control displacement|."""
    L = SCALES.length
    assert SCALES.beyond(1.0, None, control_displacement=0.99 * L) is None
    assert "specimen's size" in SCALES.beyond(1.0, None, control_displacement=-1.01 * L)
    assert SCALES.beyond(1.0, None, control_displacement=math.nan) is not None


def test_round_off_tension_is_no_tension():
    """σ_xx of uniaxial compression is 0 ± round-off: below the floor no edge cracks."""
    rms = 1.25
    sigma1 = np.array([-1.25, 3e-16, -2e-16, 1e-17])
    edges, r = select_edges(sigma1, np.ones(4, bool), 3.0, floor=TENSION_FLOOR * rms)
    assert len(edges) == 0 and r == math.inf
    sigma1[2] = 1e-3  # a real (small) tension cracks
    edges, r = select_edges(sigma1, np.ones(4, bool), 3.0, floor=TENSION_FLOOR * rms)
    assert edges.tolist() == [2] and r == pytest.approx(3e3)


def test_ties_go_by_position_whatever_the_numbering():
    """Four edges tied within round-off: the one of least x (then y) wins, under any ids."""
    points = np.array([[2.0, 0.0], [1.0, 5.0], [1.0, 3.0], [4.0, 0.0]])
    sigma1 = 2.0 * (1.0 + np.array([0.0, 3e-13, -2e-13, 1e-13]))
    for perm in ([0, 1, 2, 3], [3, 2, 1, 0], [1, 3, 0, 2]):
        p = np.array(perm)
        edges, _ = select_edges(sigma1[p], np.ones(4, bool), 3.0, points=points[p])
        assert points[p][edges[0]].tolist() == [1.0, 3.0]
        e, _ = least(np.arange(4), 3.0 / sigma1[p], points[p])
        assert points[p][e].tolist() == [1.0, 3.0]
    # beyond the tie tolerance the least r wins wherever it lies
    sigma1[3] *= 1.0 + 10 * TIE_TOLERANCE
    edges, _ = select_edges(sigma1, np.ones(4, bool), 3.0, points=points)
    assert edges.tolist() == [3]


def test_tie_order_is_x_then_y_then_id():
    points = np.array([[1.0, 2.0], [0.0, 9.0], [1.0, 1.0], [0.0, 9.0]])
    assert tie_order(np.arange(4), points).tolist() == [1, 3, 2, 0]
    assert tie_order(np.array([3, 0, 2]), None).tolist() == [1, 2, 0]
