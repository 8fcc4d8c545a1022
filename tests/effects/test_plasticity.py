"""Effect ``plasticity``'s result block (geofrac/effects/plasticity.py ``result``).

jobs/opening_mohr_coulomb.toml: a circular opening a = 1 in a ring to b = 10 m, p0 = 10
MPa held outside, the support pressure lowered to p_i = 1 MPa; E = 1e4, ν = 0.3, c = 1,
φ = 30°: the wall's displacement against Salençon's closed form, in m and MPa.
"""

import dataclasses
import re

from mpi4py import MPI

from geofrac.analytic_plastic import MohrCoulombOpening
from geofrac.effects.plasticity import END_SENTENCES, result
from geofrac.model.scene import Units
from geofrac.pipeline import run_scene
from geofrac.scene import load_scene
from tests.conftest import JOBS


def test_the_wall_moves_as_the_closed_form_says_in_the_scenes_units(tmp_path):
    scene = load_scene(JOBS / "opening_mohr_coulomb.toml", ["output.xdmf=false"], out=tmp_path)
    summary = run_scene(scene, MPI.COMM_SELF, verbose=False)
    plastic = summary["results"]["plasticity"]
    exact = MohrCoulombOpening(
        a=1.0, b=10.0, p0=10.0, pi=1.0, E=1e4, nu=0.3, cohesion=1.0, friction_angle=30.0
    ).wall_displacement
    config = next(e.config for e in scene.effects if e.name == "plasticity")
    lines = result(config, scene, summary["results"])
    assert lines[0].startswith("plasticity (MohrCoulomb): converged to load factor 1; ")
    assert f"{plastic['plastic_points']} plastic points, yielded area " in lines[0]
    assert lines[0].endswith(" m²")
    u = plastic["ground_reaction"]["final"]["u_r"]
    assert lines[1] == (
        f"ground reaction at 'wall': u_r {u:.4g} m at p_i 1 MPa (closed form {exact:.4g} m, "
        f"difference {u - exact:+.3g} m, {100 * (u - exact) / abs(exact):+.3g} %)"
    )
    bare = result(config, dataclasses.replace(scene, units=Units()), summary["results"])
    assert not any(re.search(r"\d (m|MPa|m²)\b", line) for line in bare)


def test_every_end_of_the_plastic_analysis_reads_as_a_sentence():
    for reason in ("converged", "step_too_small", "gravity_step_too_small", "stage_step_too_small"):
        assert reason in END_SENTENCES
        assert END_SENTENCES[reason].format(f=0.5)  # the factor is the only field
