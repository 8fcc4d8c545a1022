"""The deposit's measures (geofrac/mpm/deposit.py) on deposits whose answers are known by hand."""

import math

import numpy as np
import pytest

from geofrac.mpm.deposit import failure_line, runout, thickness


def _lattice(surface, spacing, x_end):
    """Particles of a lattice under y = surface(x), each of area spacing²."""
    xs = np.arange(spacing / 2, x_end, spacing)
    pts = [(x, y) for x in xs for y in np.arange(spacing / 2, surface(x), spacing)]
    return np.array(pts), np.full(len(pts), spacing**2)


@pytest.mark.parametrize("spacing", [0.01, 0.0025])
def test_the_thickness_of_a_wedge_is_its_height_whatever_the_particles(spacing):
    """A wedge y = 0.1 (1 − x / 0.4): the thickness is its height, whatever the particles.

    In 2 cm bins, the wedge's mean height over the bin, to a particle's height, for coarse
    and fine particles alike.
    """
    pts, area = _lattice(lambda x: 0.1 * (1 - x / 0.4), spacing, 0.4)
    centres, t = thickness(pts, area, bin_width=0.02)
    exact = 0.1 * (1 - centres / 0.4)
    assert np.max(np.abs(t - exact)) <= spacing
    assert np.sum(t) * 0.02 == pytest.approx(np.sum(area))


def test_scattered_particles_are_thin_not_a_particle_high():
    """One particle of 5 mm in a 10 cm bin is 0.25 mm thick: below a 2 mm run-out."""
    pts = np.array([[0.05, 0.01], [0.55, 0.0025]])
    centres, t = thickness(pts, np.array([0.01 * 0.1, 0.005**2]), bin_width=0.1)
    assert t[-1] == pytest.approx(0.005**2 / 0.1)
    # the deposit ends between the first bin (10 mm thick) and the empty second one, not at
    # the scattered particle: 0.05 + (0.010 - 0.002) / 0.010 * 0.1
    assert runout(centres, t, at=0.002) == pytest.approx(0.13)


def test_runout_interpolates_between_bins():
    centres = np.array([0.05, 0.15, 0.25, 0.35])
    t = np.array([0.010, 0.006, 0.002, 0.000])
    assert runout(centres, t, at=0.004) == pytest.approx(0.2)
    assert runout(centres, t, at=0.002) == pytest.approx(0.25)
    with pytest.raises(ValueError, match="thick"):
        runout(centres, t, at=0.02)


def test_particles_scattered_beyond_a_gap_are_not_the_deposit():
    centres = np.array([0.05, 0.15, 0.25, 0.35, 0.45])
    t = np.array([0.010, 0.006, 0.000, 0.003, 0.000])
    assert runout(centres, t, at=0.002) == pytest.approx(0.15 + 0.04 / 0.06 * 0.1)


@pytest.mark.parametrize("angle", [33.0, 55.0])
def test_the_failure_line_of_a_sliding_wedge(angle):
    """A column 0.2 x 0.1 that slid beyond a line: the line's angle and foot.

    The particles beyond the line from (0.18, 0) at ``angle`` moved 1 cm, the rest 0.1 mm;
    the line is found to a particle spacing.
    """
    spacing = 0.0025
    pts, _ = _lattice(lambda x: 0.1, spacing, 0.2)
    foot = 0.18
    beyond = pts[:, 0] > foot - pts[:, 1] / math.tan(math.radians(angle))
    u = np.where(beyond[:, None], [0.01, -0.002], [1e-4, 0.0])
    line = failure_line(pts, u, moved=0.0015, row_tol=spacing / 4)
    assert line.angle_deg == pytest.approx(angle, abs=1.0)
    assert line.x_base == pytest.approx(foot, abs=spacing)
    assert line.x_at(0.05) == pytest.approx(
        foot - 0.05 / math.tan(math.radians(angle)), abs=spacing
    )


def test_no_undisturbed_zone_is_refused():
    pts, _ = _lattice(lambda x: 0.1, 0.01, 0.2)
    with pytest.raises(ValueError, match="failure line"):
        failure_line(pts, np.full_like(pts, 0.01), moved=0.0015, row_tol=0.0025)
