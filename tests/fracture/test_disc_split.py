"""The Brazilian disc's first crack: on the loaded diameter, at the closed-form load.

jobs/brazilian_disc.toml (D = 50 mm, t = 25 mm, strips of 2α = 10° under a unit
pressure, RGNT, force control on the top strip) on a coarse mesh (h = 1.5 mm, about
1,200-1,350 nodes) and the three gmsh meshers, first event only. The exact field
(:func:`geofrac.validation.brazilian.brazilian_disc_stress`, Hondros (1959)) has its
largest σ1 at the centre, σ1 = σ_xx = (2p/π)(sin 2α − α) = 0.05499 p, and σ_xx on the
loaded diameter stays within 1 % of it for |y| < 10 mm, so the first crack should cross
the loaded diameter x = 0 (within one element, |x| ≤ h) at r = f_t / σ_xx(centre), and
the control reaction is r times one strip's resultant 2 p R t sin α (the splitting load
P of the ISRM formula).

Tolerance on r: the criterion takes the largest edge value of the recovered stress, not
the centre's. The recovered centre σ_xx is within 0.1-0.4 % of the closed form
(tests/fracture/test_disc_stress_recovery.py), but the largest edge σ1 at h = 1.5 mm is
1.002 σ_c (frontal-Delaunay), 1.028 σ_c (Delaunay) and 1.025 σ_c (MeshAdapt) (per-edge
recovery error of the stress, which is nearly flat there), so r falls up to 2.8 % below
f_t / σ_c: 4 % allows that and nothing like a lost load (a pressure of the wrong sign
puts the centre in compression and the first crack elsewhere).

The default criterion (``"direction"``) starts a crack where σ1 of an edge reaches f_t,
along the edge there most nearly across σ1; on the coarse MeshAdapt mesh the largest
edge σ1 lies 8.6 mm up the diameter and the edge chosen there is 1.95 mm (1.3 h) off it
(marked below; at h = 1 mm it is 0.55 mm off).
"""

import math

import pytest
from mpi4py import MPI

from geofrac.effects.cracking import scene_driver
from geofrac.scene import load_scene_collective
from geofrac.validation.brazilian import brazilian_centre_stress, strip_resultant
from tests.conftest import JOBS

SCENE = JOBS / "brazilian_disc.toml"
#: the scene's radius, thickness, half strip (rad), pressure and f_t; the coarse h (mm).
R, T, ALPHA, P, FT = 25.0, 25.0, math.radians(5.0), 1.0, 3.0
H = 1.5
SIGMA_C = brazilian_centre_stress(P, ALPHA)[0]
R_RTOL = 0.04

_DIRECTION_MISSES = {
    "meshadapt": "the edge most nearly across σ1 at the largest edge σ1 (8.6 mm up the "
    "diameter) is at x = -1.95 mm, more than h = 1.5 mm from the diameter",
}

CASES = [
    pytest.param(
        alg,
        crit,
        id=f"{alg}-{crit}",
        marks=[pytest.mark.xfail(strict=True, reason=_DIRECTION_MISSES[alg])]
        if crit == "direction" and alg in _DIRECTION_MISSES
        else [],
    )
    for crit in ("principal", "direction")
    for alg in ("frontal-delaunay", "delaunay", "meshadapt")
]


def first_event(algorithm: str, criterion: str) -> tuple[dict, dict]:
    """(the first event's row, the run's results) on the coarse disc."""
    overrides = [
        f"geometry.algorithm={algorithm}",
        f"geometry.parameters.h={H}",
        f"cracking.criterion={criterion}",
        "cracking.max_events=1",
    ]
    driver = scene_driver(load_scene_collective(MPI.COMM_SELF, SCENE, overrides), MPI.COMM_SELF)
    try:
        res = driver.run()
        return driver.rows[0], res
    finally:
        driver.problem.destroy()


@pytest.mark.parametrize(("algorithm", "criterion"), CASES)
def test_first_crack_on_the_diameter_at_the_centre_stress(algorithm, criterion):
    row, res = first_event(algorithm, criterion)
    force = strip_resultant(P, radius=R, alpha=ALPHA, thickness=T)
    assert res["control"]["kind"] == "force"
    assert res["control"]["unit_force"] == pytest.approx(force, rel=1e-6)
    assert row["reaction"] == pytest.approx(row["load_factor"] * force, rel=1e-9)
    assert abs(row["x"]) <= H, (row["x"], row["y"])
    assert row["load_factor"] == pytest.approx(FT / SIGMA_C, rel=R_RTOL)
