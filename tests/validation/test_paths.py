"""Path measures on hand-made event logs whose answers are read off the construction."""

import csv
import math

import numpy as np
import pytest

from geofrac.fracture.output import EVENT_COLUMNS
from geofrac.validation.paths import (
    axis_deviation,
    disc_split,
    main_crack,
    read_events,
    split_through,
    spread_until,
)


def write_events(path, edges):
    """``events.csv`` with one row per (node_a, node_b, x, y[, reaction]) of ``edges``."""
    path.mkdir(parents=True, exist_ok=True)
    with open(path / "events.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=EVENT_COLUMNS)
        w.writeheader()
        for i, e in enumerate(edges):
            row = dict.fromkeys(EVENT_COLUMNS, 0)
            row.update(
                event=i + 1, edge=i, node_a=e[0], node_b=e[1], x=e[2], y=e[3], mode="tension"
            )
            row.update(
                r=0.1 * (i + 1), load_factor=0.1 * (i + 1), reaction=e[4] if len(e) > 4 else 1.0
            )
            w.writerow(row)
    return read_events(path)


#: a crack from the notch tip (y = 50) up a zig-zag to the top (y = 100), with two cracks
#: under the load pad (nodes 100-102, not joined) cracking before it arrives, and one more
#: edge after it reached the top.
BEAM = [
    (1, 2, 0.5, 51.0),
    (2, 3, -1.0, 60.0),
    (3, 4, -6.0, 70.0),  # furthest below the pad zone
    (100, 101, 2.0, 98.0),  # pad crack
    (4, 5, -3.0, 85.0),
    (101, 102, 7.5, 98.2),  # pad crack, further out
    (5, 6, -2.0, 96.0),
    (6, 7, -1.5, 99.6),  # reaches the top (y = 100 within 0.75)
    (7, 8, -30.0, 99.0),  # after: not counted
]


def test_main_crack_follows_shared_nodes(tmp_path):
    ev = write_events(tmp_path, BEAM)
    assert main_crack(ev).tolist() == [True, True, True, False, True, False, True, True, True]
    assert main_crack(ev, upto=4).tolist() == [True] * 3 + [False] * 6
    # a gap of 8 joins the pad cracks to the crack at (-2, 96) and (-1.5, 99.6)
    assert main_crack(ev, gap=8.0).all()


def test_axis_deviation_stops_where_the_crack_reaches_the_face(tmp_path):
    ev = write_events(tmp_path, BEAM)
    d = axis_deviation(ev, face_y=100.0, reach=0.75)
    assert (d.distance, d.x, d.y) == (6.0, -6.0, 70.0)
    assert d.reached_event == 8 and d.face_x == -1.5
    assert d.events == 8 and d.main_edges == 6
    below = axis_deviation(ev, face_y=100.0, reach=0.75, below=65.0, axis=-1.0)
    assert below.distance == pytest.approx(1.5) and below.main_edges == 2


def test_axis_deviation_over_the_whole_run_when_the_face_is_never_reached(tmp_path):
    ev = write_events(tmp_path, BEAM[:7])
    d = axis_deviation(ev, face_y=100.0, reach=0.75)
    assert d.reached_event is None and d.face_x is None
    assert d.distance == 6.0 and d.events == 7


def test_disc_split(tmp_path):
    D, t, a = 50.0, 25.0, math.radians(5.0)
    edges = [
        (1, 2, 0.3, 1.2, 800.0),
        (2, 3, -0.4, 3.0, 2000.0),
        (3, 4, 1.7, 8.0, 5000.0),  # the peak
        (50, 51, 3.9, 24.6, 1200.0),  # at a strip's end, not joined
        (4, 5, 0.9, 15.0, 900.0),
    ]
    s = disc_split(write_events(tmp_path, edges), diameter=D, thickness=t, alpha=a)
    assert s.first_from_diameter == pytest.approx(0.3)
    assert s.first_from_centre == pytest.approx(math.hypot(0.3, 1.2))
    assert s.main_from_diameter == pytest.approx(1.7) and s.any_from_diameter == pytest.approx(3.9)
    assert s.peak_load == 5000.0 and s.peak_event == 3
    assert s.strength_isrm == pytest.approx(2 * 5000.0 / (math.pi * D * t), rel=1e-14)
    hondros = (math.sin(2 * a) - a) / math.sin(a)
    assert s.strength_hondros == pytest.approx(s.strength_isrm * hondros, rel=1e-14)
    assert np.isclose(hondros, 0.99112, rtol=1e-4)


def test_split_through_and_disc_split_until_it(tmp_path):
    """The split ends when the main crack nears the rim above and below; later events drop."""
    D, t, a = 50.0, 25.0, math.radians(5.0)
    edges = [
        (1, 2, 0.2, -0.5, 5900.0),  # the peak, at the first event
        (2, 3, -0.6, 12.0, 3000.0),
        (60, 61, 9.0, 5.0, 2500.0),  # elsewhere, not joined: counts for any_from_diameter
        (3, 4, 0.8, 23.8, 900.0),  # within 1.5 of the rim above
        (1, 5, -1.1, -12.0, 800.0),
        (5, 6, 0.4, -23.6, 700.0),  # within 1.5 below: the split (event 6)
        (4, 7, 6.0, 20.0, 9000.0),  # after the split: not measured
    ]
    events = write_events(tmp_path, edges)
    assert split_through(events, radius=D / 2, reach=1.5) == 6
    assert split_through(events, radius=D / 2, reach=1.0) is None  # 23.6 is 1.4 short
    s = disc_split(events, diameter=D, thickness=t, alpha=a, upto=6)
    assert s.main_from_diameter == pytest.approx(1.1) and s.any_from_diameter == pytest.approx(9.0)
    assert s.peak_load == 5900.0 and s.peak_event == 1
    whole = disc_split(events, diameter=D, thickness=t, alpha=a)
    assert whole.main_from_diameter == pytest.approx(6.0) and whole.peak_load == 9000.0


def test_spread_until_counts_every_edge_until_the_main_crack_enters_the_zone(tmp_path):
    """A side crack (not joined to the main one) counts; edges after the stop do not."""
    events = write_events(
        tmp_path,
        [
            (1, 2, 0.2, 50.5),  # main crack from the notch
            (2, 3, -0.3, 52.0),
            (10, 11, 1.1, 53.0),  # a side crack, not joined: counts
            (3, 4, 0.4, 94.0),
            (4, 5, -0.2, 96.0),  # the main crack enters y >= 95: the count stops here
            (5, 6, 6.0, 98.0),  # spreading under the pad: not counted
        ],
    )
    distance, stop = spread_until(events, y_stop=95.0)
    assert (distance, stop) == (1.1, 5)
    distance, stop = spread_until(events, y_stop=99.0)  # never reached: every event
    assert (distance, stop) == (6.0, None)
