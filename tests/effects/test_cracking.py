"""Effect ``cracking``'s result block (geofrac/effects/cracking.py ``result``, ``end_sentence``).

A coarse jobs/notched_beam.toml (about 1,200 nodes): the peak load of its event log in N,
where the crack reached the top in mm, against the experiment's band of 30-40 mm
(Gálvez et al. 1998) that the scene names; every end reason the event loops can give in
words.
"""

import csv
import dataclasses
import re

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import END_SENTENCES, end_sentence, result
from geofrac.fracture.config import CrackingConfig
from geofrac.fracture.loop import END_REASONS, _Run
from geofrac.model.errors import SceneError
from geofrac.model.scene import Units
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene
from tests.conftest import JOBS, REPO

COARSE = ["geometry.parameters.h=25", "geometry.parameters.h_fine=6", "output.xdmf=false"]


def test_every_end_reason_of_the_loop_reads_as_a_sentence():
    assert set(END_SENTENCES) == set(END_REASONS)
    for reason in END_REASONS:
        text = end_sentence(reason, 48)
        assert text.startswith(reason) and len(text) > len(reason) + 20  # named, explained
        assert re.search(r"\b4[89]\b", text), text  # the event it ended at
    assert (
        end_sentence("separated", 48) == "separated: the specimen broke into two pieces at event 48"
    )
    assert end_sentence("max_events", 600) == "max_events reached: 600 events (cracking.max_events)"


def test_every_end_the_loops_set_is_one_of_the_reasons():
    """Each ``run.end = "..."`` of the event loops (edges, constant loads, stages) is known."""
    found = set()
    for path in (REPO / "geofrac" / "fracture").glob("*.py"):
        found |= set(re.findall(r'\.end = "(\w+)"', path.read_text()))
    assert found and found <= set(END_REASONS)
    assert _Run(u_unit=np.zeros(1)).end in END_REASONS  # the end when nothing else ends it


def test_an_unknown_reason_prints_as_is_and_a_lost_load_path_gives_its_detail():
    assert end_sentence("the_solver_ran_away", 3) == "the_solver_ran_away"
    detail = "the next event would need a load factor of 9, more than 5 times the first's 1"
    text = end_sentence("separated", 7, detail)
    assert text.startswith("separated: after event 7 the specimen no longer carries the load")
    assert detail in text
    energy = "the unit-load strain energy 4.48e-09 is below 1e-09 of the first event's (926)"
    assert end_sentence("separated", 7, energy).endswith("broke into two pieces at event 7")
    assert end_sentence("separated", 0, energy).startswith(
        "separated: the specimen carries no load before the first event ("
    )


@pytest.fixture(scope="module")
def beam(tmp_path_factory):
    out = tmp_path_factory.mktemp("beam")
    scene = load_scene(JOBS / "notched_beam.toml", COARSE, out=out)
    return scene, run_scene(scene, MPI.COMM_SELF, verbose=False), out


def test_the_block_gives_the_peak_load_and_the_crack_at_the_top_against_the_band(beam):
    scene, summary, out = beam
    config = scene.effect_config("cracking", CrackingConfig)
    crack = summary["results"]["cracking"]
    with open(out / "events.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    peak = max(rows, key=lambda r: float(r["reaction"]))
    lines = result(config, scene, summary["results"])
    assert lines[0] == f"cracking: {len(rows)} events (tension {len(rows)})"
    assert lines[1] == "end: " + end_sentence(
        crack["end_reason"], len(rows), crack.get("end_detail")
    )
    assert lines[2] == (
        f"peak load: {float(peak['reaction']):.4g} N at event {peak['event']} "
        f"(load factor {float(peak['load_factor']):.4g})"
    )
    x = crack["crack_face"]["x_from_origin"]
    assert (
        lines[3] == f"crack reached 'top' at x = {x:.4g} mm (event {crack['crack_face']['event']})"
    )
    low, high = 30.0, 40.0  # Gálvez et al. (1998)
    if low <= x <= high:
        where = "inside"
    else:
        edge = low if x < low else high
        where = f"difference {x - edge:+.3g} mm, {100 * (x - edge) / edge:+.3g} %"
    assert lines[4].startswith("  against the band 30 to 40 mm: ") and where in lines[4]


def test_without_units_the_block_names_none(beam):
    scene, summary, _ = beam
    bare = dataclasses.replace(scene, units=Units())
    lines = result(scene.effect_config("cracking", CrackingConfig), bare, summary["results"])
    assert lines and not any(" N" in s or " mm" in s for s in lines)


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ("cracking.face_band=[40, 30]", "low <= high"),
        ("cracking.face_band=[30]", r"\[low, high\]"),
        ("cracking.face_band=['a', 1]", r"\[low, high\]"),
    ],
)
def test_a_band_must_be_low_to_high(override, message):
    with pytest.raises(SceneError, match=message) as info:
        load_scene(JOBS / "notched_beam.toml", [override])
    assert info.value.key == "cracking.face_band"


def test_a_band_needs_a_face():
    with pytest.raises(SceneError, match=r"needs cracking\.face"):
        load_scene(JOBS / "crack_patch_test.toml", ["cracking.face_band=[30, 40]"])


def test_with_contact_the_block_gives_the_faces_states_at_the_end(tmp_path):
    """The Jaeger joint (3 slip events): the face pairs' states, as the contact recorded."""
    scene = load_scene(JOBS / "jaeger_joint.toml", ["output.xdmf=false"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_WORLD, verbose=False)
    contact = summary["results"]["cracking"]["contact"]
    assert contact["slip"] > 0  # the joint slipped: the line has something to say
    assert contact["stick"] + contact["slip"] + contact["open"] == contact["pairs"]
    lines = result(scene.effect_config("cracking", CrackingConfig), scene, summary["results"])
    expected = (
        f"contact: {contact['pairs']} face pairs at the end: {contact['stick']} stick, "
        f"{contact['slip']} slip, {contact['open']} open"
    )
    assert expected in lines
