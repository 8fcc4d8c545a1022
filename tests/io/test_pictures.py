"""The run pictures (geofrac.io.pictures): labels carry the scene's units, or none."""

import numpy as np
import pytest

from geofrac.io.pictures import (
    network_figure,
    particles_figure,
    save,
    section_figure,
    section_polygons,
    section_segments,
)
from geofrac.model.scene import Units

MM = Units(length="mm", force="N", stress="MPa", time="s")
NONE = Units()


def _labels(fig):
    """(xlabel, ylabel, title, colour bar label or None, legend texts) of the main axes."""
    ax = fig.axes[0]
    bars = [a.get_ylabel() for a in fig.axes[1:]]
    legend = ax.get_legend() or (fig.legends[0] if fig.legends else None)
    texts = [t.get_text() for t in legend.get_texts()] if legend is not None else []
    return ax.get_xlabel(), ax.get_ylabel(), ax.get_title(), (bars or [None])[0], texts


def _network(units):
    domain = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]])
    fractures = np.array([[[0.1, 0.1], [0.9, 0.8]], [[1.2, 0.2], [1.8, 0.3]]])
    mesh = np.array([[[0.0, 0.0], [1.0, 0.5]], [[1.0, 0.5], [2.0, 1.0]]])
    return network_figure(
        domain=domain,
        fractures=fractures,
        sets=np.array([0, 1]),
        set_names=("J1", "J2"),
        mesh_edges=mesh,
        title="dfn_scene: 2 fractures and the mesh",
        units=units,
    )


def test_the_network_names_its_axes_sets_and_scene_in_the_scenes_units():
    x, y, title, _, legend = _labels(_network(MM))
    assert (x, y) == ("x (mm)", "y (mm)") and "dfn_scene" in title
    assert {"set J1", "set J2", "domain"} <= set(legend)
    assert any(t.startswith("mesh (2 edges") for t in legend)


def test_without_units_no_picture_shows_one():
    x, y, _, _, _ = _labels(_network(NONE))
    assert (x, y) == ("x", "y")
    x0 = np.array([[0.0, 0.0], [0.1, 0.0], [0.0, 0.1], [0.1, 0.1]])
    for fig in (
        particles_figure(x0=x0, x=x0 + 0.01, cell=0.1, title="t", units=NONE),
        particles_figure(x0=x0[:, :1], x=x0[:, :1] + 0.01, cell=0.1, title="t", units=NONE),
        section_figure(
            polygons=[x0[[0, 1, 3, 2]]],
            values=np.array([0.01]),
            axes_names=("x", "y"),
            quantity="area",
            title="t",
            units=NONE,
        ),
    ):
        x, y, _, bar, _ = _labels(fig)
        assert "(" not in x + y + bar, (x, y, bar)


def test_the_particles_carry_their_displacement_and_the_initial_outline():
    x0 = np.stack(np.meshgrid(np.arange(5) * 0.1, np.arange(3) * 0.1), -1).reshape(-1, 2)
    x = x0 + np.array([0.3, -0.05])
    x_label, y_label, title, bar, legend = _labels(
        particles_figure(x0=x0, x=x, cell=0.2, title="mpm_scene: 15 particles", units=MM)
    )
    assert (x_label, y_label, bar) == ("x (mm)", "y (mm)", "displacement magnitude |u| (mm)")
    assert "mpm_scene" in title and legend == ["initial outline"]
    fig = particles_figure(x0=x0[:, :1], x=x[:, :1], cell=0.2, title="bar", units=MM)  # 1D
    x_label, _, _, bar, legend = _labels(fig)
    assert x_label == "x (mm)" and bar == "displacement magnitude |u| (mm)"
    assert legend == ["initial outline", "initial positions"]
    up = np.column_stack([x0[:, 0], np.zeros(len(x0)), x0[:, 1]])  # 3D: x right, z up
    assert _labels(particles_figure(x0=up, x=up, cell=0.2, title="t", units=MM))[1] == "z (mm)"


def _cube(origin):
    """A unit cube as one convex hexahedron in VTK order, and its six quadrilateral faces."""
    corners = np.array(
        [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
        dtype=float,
    )
    faces = np.array(
        [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    )
    return corners + origin, np.arange(8)[None, :], faces


def test_a_plane_cuts_a_hexahedron_into_its_section():
    points, pieces, faces = _cube([2.0, -0.5, 1.0])
    polygons, which = section_polygons(points, pieces, axis=1, at=0.25)
    assert list(which) == [0] and polygons[0].shape == (4, 2)
    px, pz = polygons[0].T  # the unit square [2, 3] x [1, 2] in (x, z), in ring order
    area = 0.5 * abs(np.dot(px, np.roll(pz, -1)) - np.dot(pz, np.roll(px, -1)))
    assert area == pytest.approx(1.0)
    segments = section_segments(points, faces, axis=1, at=0.25)
    assert len(segments) == 4  # the four side faces; top and bottom lie parallel
    assert section_polygons(points, pieces, axis=1, at=0.75)[0] == []  # beyond the cube


def test_the_section_colours_blocks_by_volume_in_the_scenes_unit(tmp_path):
    points, pieces, faces = _cube([0.0, -0.5, 0.0])
    polygons, _ = section_polygons(points, pieces, axis=1, at=0.0)
    fig = section_figure(
        polygons=polygons,
        values=np.array([1.0]),
        background_lines=section_segments(points + np.array([1.0, 0, 0]), faces, axis=1, at=0.0),
        outlines=section_segments(points, faces, axis=1, at=0.0),
        axes_names=("x", "z"),
        quantity="volume",
        title="blocks_scene: section y = 0",
        units=Units(length="m"),
    )
    x, y, title, bar, legend = _labels(fig)
    assert (x, y, bar) == ("x (m)", "z (m)", "block volume (m³)")
    assert "blocks_scene" in title and legend == ["immobile block's outline"]
    save(fig, tmp_path / "section.png")
    assert (tmp_path / "section.png").stat().st_size > 0
