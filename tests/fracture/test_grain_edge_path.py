"""The notched beam cracked along grain interfaces and along element edges: one crack.

Edo (2016) 2.4.3 and 3.5.1 crack the same beam (Gálvez et al.: the crack meets the top
face 30-40 mm right of the centre) with two discretisations: element edges (chapter 2,
RGNT) and EFMM grain interfaces (chapter 3). On the same coarse uniform mesh
(h = 12 mm, the grain size) the two paths must meet the top within two grain sizes of
each other, and each within one grain size of the experiment's 30-40 mm. Before the
grain criterion read the traction normal to the interface (docs/granular.md), the grain
crack ran under the top face and met it at 273 mm (frontal mesher) or 120 mm (Delaunay).

The grains are random (q_rand = 0.1, Edo (2016)'s value): each ``domain_seed`` is one
realisation, and single realisations scatter by grain sizes. Over seeds 1-8 the grain
crack met the top at 13-49 mm on both meshers, 13 mm once in eight on each (frontal:
13, 25, 49, 49, 37, 37, 49, 37; Delaunay: 37, 37, 49, 37, 25, 13, 37, 37), against 43 and
31 mm for the edge crack. So the grain crack is judged by the median of
:data:`SEEDS` realisations, as a prediction of a random microstructure is.

Both are the thesis's rules (the edge crack by σ1 at the edge's midpoint,
``criterion = "principal"``). The default edge criterion follows the stress averaged
over twice the element size about the tip, a third of this beam's 75 mm ligament at
h = 12 mm: it meets the top at 91 mm (frontal) and 67 mm (Delaunay) here, and at 37 mm
on the 4 mm mesh of the path reference (docs/cracking_paths.md).
"""

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.fracture.criterion import normal_stress
from geofrac.scene import load_scene_collective
from tests.conftest import JOBS

#: mesh size = grain size (mm).
H = 12.0
#: the experiment's window for where the crack meets the top (mm from the centre).
WINDOW = (30.0, 40.0)
#: the grain realisations (``discretization.domain_seed``) whose median is judged.
SEEDS = (1, 2, 3, 4, 5)


def crack_top_x(job: str, algorithm: int, *overrides: str) -> float:
    """Where the crack from the notch meets the top face of ``job`` on the coarse mesh."""
    comm = MPI.COMM_SELF
    overrides = (
        f"geometry.parameters.h={H}",
        f"geometry.parameters.h_fine={H}",
        f"geometry.parameters.algorithm={algorithm}",
        "cracking.max_events=150",
        *overrides,
    )
    d = scene_driver(load_scene_collective(comm, JOBS / f"{job}.toml", overrides), comm)
    res = d.run()
    assert res["end_reason"] == "separated"
    return float(res["crack_top_x_mm"])


@pytest.mark.parametrize("algorithm", [6, 5], ids=["frontal", "delaunay"])
def test_grain_and_edge_cracks_meet_the_top_together(algorithm):
    edge = crack_top_x("notched_beam", algorithm, "cracking.criterion=principal")
    grains = [
        crack_top_x("grain_notched_beam", algorithm, f"discretization.domain_seed={seed}")
        for seed in SEEDS
    ]
    grain = float(np.median(grains))
    assert abs(grain - edge) <= 2.0 * H, grains
    for x in (edge, grain):
        assert WINDOW[0] - H <= x <= WINDOW[1] + H


def test_interface_opens_under_the_traction_normal_to_it():
    """Uniaxial σ_xx loads a plane of normal x fully and one of normal y not at all."""
    s = np.array([[5.0, 0.0, 0.0], [1.0, 3.0, 2.0]])
    n = np.array([[1.0, 0.0], [np.sqrt(0.5), np.sqrt(0.5)]])
    assert normal_stress(s, n) == pytest.approx([5.0, 0.5 * (1.0 + 3.0) + 2.0])
    assert normal_stress(s[:1], n[:1, ::-1]) == pytest.approx([0.0])
