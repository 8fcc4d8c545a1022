"""Joint slip around an opening: staged excavation with joints in contact from σ0.

A circular opening (a = 1) in a hydrostatic in-situ stress p = 10 (plane strain), one set
of straight joints dipping δ = 30° with spacing 0.3 (none through the centre), clipped to
a 4 × 4 square around the opening (jobs/joint_slip_opening.toml and its network file),
cohesion c = 1 and friction φ = 30°; the joints are
cracked edges from the start whose faces are in contact and carry σ0; one stage removes
the opening and its release drives the events. Closed form (Kirsch with Coulomb on the
plane of weakness: Brady and Brown (2004); Jaeger, Cook and Zimmerman (2007);
:mod:`geofrac.analytic_joints`): at release share α the stress is σ0 + α (σ_K − σ0); a
point of a joint slips at the least α with |τ| = c + μ σn. On the wall it is
α* = c cos φ / p + sin φ = 0.587 where the joint meets the wall at 30° to its tangent;
the discrete joints meet the wall elsewhere, and their least α is 0.637 (θ = −101°, −19°,
79° and 161°: two joints, each at both ends of its chord of the wall).

- The first event is a slip, on the joint and at the wall point of the closed form's
  least α over the discrete joints (within 3°), and its release share is the closed
  form's at the slipping pair's midpoint within 3 % (0.6552 against 0.6552 measured, mesh
  size 0.025 on the wall and the joints). With 0.05 on the joints the first slip is a
  pair in the thin wedge between a joint and the wall (θ = −82°, r = 1.13), 15 % before
  the closed form at its midpoint: the MLS cells of a wedge bounded by the joint and the
  wall have few satellites, and their stress is poor (docs/insitu.md). The default mesher
  (frontal-delaunay) only: with `delaunay` the first slip is such a wedge pair, 11 % early.
- 1 and 2 ranks slip the same pairs at the same shares (MPI test).
"""

import csv
import math

import numpy as np
import pytest
from mpi4py import MPI

from geofrac.analytic_joints import JointedOpening
from tests.conftest import REPO
from tests.fracture.test_constant_loads import run

SCENE = REPO / "jobs" / "joint_slip_opening.toml"
JOINTS = REPO / "jobs" / "joint_slip_opening_joints.csv"
#: in-situ pressure, radius, joint dip (degrees), spacing, half-width of the jointed box.
P, A, DIP, SPACING, BOX = 10.0, 1.0, 30.0, 0.3, 2.0
COHESION, PHI = 1.0, 30.0
OPENING = JointedOpening(
    sigma_v=P, k=1.0, radius=A, dip=DIP, cohesion=COHESION, friction=math.tan(math.radians(PHI))
)


def joints() -> list[tuple[float, float, float, float]]:
    """The joint traces (x0, y0, x1, y1): lines at DIP, SPACING apart, clipped to the box."""
    d = math.radians(DIP)
    t, n = (math.cos(d), math.sin(d)), (-math.sin(d), math.cos(d))
    out = []
    for k in range(-12, 12):
        px, py = (k + 0.5) * SPACING * n[0], (k + 0.5) * SPACING * n[1]
        lo, hi = -1e9, 1e9
        for p, tt in ((px, t[0]), (py, t[1])):
            a, b = (-BOX - p) / tt, (BOX - p) / tt
            lo, hi = max(lo, min(a, b)), min(hi, max(a, b))
        if hi - lo > 0.5:
            out.append((px + lo * t[0], py + lo * t[1], px + hi * t[0], py + hi * t[1]))
    return out


def least_on_joints(samples: int = 8001) -> tuple[float, list[float]]:
    """The closed form's least slip share over the joints' points in the rock, and where.

    Returns the least share and the polar angles (degrees) of the points that reach it
    (to 2e-3 relative, the sampling's resolution), one per local minimum.
    """
    points, shares = [], []
    for x0, y0, x1, y1 in joints():
        s = np.linspace(0.0, 1.0, samples)[:, None]
        p = np.array([x0, y0]) + s * np.array([x1 - x0, y1 - y0])
        r = np.hypot(p[:, 0], p[:, 1])
        keep = r >= A
        points.append(p[keep])
        shares.append(
            OPENING.slip_fraction(r[keep], np.degrees(np.arctan2(p[keep, 1], p[keep, 0])))
        )
    alpha = np.concatenate(shares)
    where = np.concatenate(points)[alpha <= alpha.min() * (1.0 + 2e-3)]
    angles: list[float] = []
    for t in np.degrees(np.arctan2(where[:, 1], where[:, 0])).tolist():
        if all(abs((t - u + 180.0) % 360.0 - 180.0) > 1.0 for u in angles):
            angles.append(t)
    return float(alpha.min()), angles


def test_the_job_has_these_joints():
    """The job's network file holds the joints the references are computed for."""
    with open(JOINTS, newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["set"] for r in rows] == ["J"] * len(joints())
    got = np.array([[float(r[k]) for k in ("x0", "y0", "x1", "y1")] for r in rows])
    assert np.array_equal(got, np.array(joints()))


def test_the_closed_form_of_the_discrete_joints():
    """The hand-derived wall value and the discrete joints' least share (the references)."""
    phi = math.radians(PHI)
    assert OPENING.first_slip().alpha == pytest.approx(COHESION * math.cos(phi) / P + math.sin(phi))
    best, where = least_on_joints()
    assert best == pytest.approx(0.6367, abs=2e-4)
    # four wall points: two joints, each met at the two ends of its chord of the wall
    assert sorted(round(t) for t in where) == [-101, -19, 79, 161]


#: Known failure, not located: with integration-consistent MLS cells the first slip is at
#: the right wall point but 4.4 % late (0.6848 against 0.6556 at the pair; docs/cracking.md,
#: "Integration-consistent MLS cells").
CONSISTENT_LATE = pytest.mark.xfail(strict=True, reason="consistent cells: slip 4.4 % late")


@pytest.mark.parametrize("gradient", ["fit", pytest.param("consistent", marks=CONSISTENT_LATE)])
def test_joints_first_slip_where_and_when_the_closed_form_says(gradient):
    """The thesis's MLS cells and the integration-consistent ones (docs/cracking.md)."""
    driver, results = run(SCENE, f"cracking.mls_gradient={gradient}")
    assert driver.rows, results["end_reason"]
    first = driver.rows[0]
    assert first["mode"] == "slip"
    # where: at the wall point of the discrete joints' least share (or its mirror image)
    _, where = least_on_joints()
    assert math.hypot(first["x"], first["y"]) < A + 0.05  # next to the wall
    x, y = first["x"], first["y"]
    theta = math.degrees(math.atan2(y, x))
    off = min(abs((theta - t + 180.0) % 360.0 - 180.0) for t in where)
    assert off < 3.0, (theta, where)
    # when: the closed form's share at the slipping pair's midpoint, within 3 %
    alpha = float(OPENING.slip_fraction(math.hypot(x, y), theta))
    assert first["load_factor"] == pytest.approx(alpha, rel=0.03)
    stage = results["stages"][0]
    assert stage["first_event"]["event"] == 1


@pytest.mark.mpi(min_size=2)
def test_two_ranks_slip_the_same_pairs():
    comm = MPI.COMM_WORLD
    path = SCENE
    parallel, _ = run(path, comm=comm)
    serial, _ = run(path)
    assert [r["edge"] for r in parallel.rows] == [r["edge"] for r in serial.rows]
    assert np.allclose(
        [r["load_factor"] for r in parallel.rows],
        [r["load_factor"] for r in serial.rows],
        rtol=1e-9,
    )
    edges = comm.allgather([r["edge"] for r in parallel.rows])
    assert all(e == edges[0] for e in edges)
