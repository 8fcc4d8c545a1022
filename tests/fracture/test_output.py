"""load_displacement.png (geofrac.fracture.output): what its axes say, in the scene's units."""

import pytest

from geofrac.fracture.control import Control, release_control
from geofrac.fracture.output import load_displacement_figure
from geofrac.model.scene import Units

MM = Units(length="mm", force="N", stress="MPa")


def _rows(*modes):
    return [
        {
            "event": k + 1,
            "control_displacement": 0.01 * (k + 1),
            "reaction": 100.0 * (k + 1),
            "load_factor": 0.1 * (k + 1),
            "mode": mode,
        }
        for k, mode in enumerate(modes)
    ]


def _axes(fig):
    ax = fig.axes[0]
    legend = ax.get_legend()
    texts = [t.get_text() for t in legend.get_texts()] if legend is not None else []
    return ax.get_xlabel(), ax.get_ylabel(), ax.get_title(), texts


@pytest.mark.parametrize(
    ("control", "x", "y"),
    [
        (Control("displacement", "top", 0.1, 0.1), "prescribed displacement of 'top'",
         "reaction on 'top'"),
        (Control("force", "load", 1.0, 0.1), "displacement of the load on 'load', work-conjugate",
         "force of the load on 'load'"),
    ],
)  # fmt: skip
def test_the_curve_names_the_control_and_its_units(control, x, y):
    xlabel, ylabel, title, legend = _axes(
        load_displacement_figure(_rows("tension", "tension"), control, name="beam", units=MM)
    )
    assert (xlabel, ylabel) == (f"{x} (mm)", f"{y} (N)")
    assert title == "beam: load against displacement, 2 events" and legend == []
    xlabel, ylabel, _, _ = _axes(
        load_displacement_figure(_rows("tension"), control, name="beam", units=Units())
    )
    assert (xlabel, ylabel) == (x, y)  # no [units]: no unit


def test_slip_events_are_circled_and_a_release_is_drawn_by_event():
    control = Control("displacement", "top", 0.1, 0.1)
    fig = load_displacement_figure(_rows("slip", "tension"), control, name="jaeger", units=MM)
    assert _axes(fig)[3] == ["event", "slip event"]
    xlabel, ylabel, title, _ = _axes(
        load_displacement_figure(_rows("tension"), release_control(1.0), name="t", units=MM)
    )
    assert (xlabel, ylabel) == ("event", "load factor λ of the stage's release")
    assert title == "t: the stages' release by event, 1 event"
