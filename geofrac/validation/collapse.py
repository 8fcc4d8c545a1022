"""The aluminium-rod column collapse of Bui et al. (2008): the experiment and its measures.

Bui, H. H., Fukagawa, R., Sako, K. and Ohno, S., "Lagrangian meshfree particles method
(SPH) for large deformation and failure flows of geomaterial using elastic-plastic soil
constitutive model", Int. J. Numer. Anal. Meth. Geomech. 32 (2008) 1537-1570: a column of
aluminium rods (1 and 1.5 mm diameter, 50 mm long), 0.2 m long and 0.1 m high against a
wall, released by removing the gate on its other side (plane strain). The final surface
and the failure line (the boundary of the zone that did not deform) below are the
experiment's, as digitised from Bui et al.'s figure by Huo et al. (2025, Computers and
Geotechnics 107189); x from the wall, metres.

The measures (:mod:`geofrac.mpm.deposit`) read the deposit the way the experiment does:

- run-out: where the deposit first thins to :data:`RUNOUT_THICKNESS` = 2 mm going out
  from the wall (about one rod's diameter; the digitised surface ends at 1.5 mm), from
  the thickness in bins of :data:`BIN` = 10 mm, particles scattered ahead of the deposit
  not counted; the experiment's by linear interpolation of its surface;
- failure line: particles that moved less than :data:`MOVED` = 1.5 mm (the coarser rods'
  diameter; Ghaïtanellis et al. (2018, Adv. Water Resour. 111) use the same threshold)
  are undeformed; the angle of the least-squares line through each initial row's
  farthest undeformed particle, against the same fit of the digitised line;
- surface: RMS of (thickness − experiment's height) at the digitised points.

The thickness counts each particle's area at the rods' density (its mass over
:data:`DENSITY`), not its current area: the flow has no dilatancy (ψ = 0), but a particle
at the Drucker-Prager apex (zero stress, c = 0) stretches without resistance, and the
thin flowing layer's particles end up to 3 times their area at 10 mm cells (docs/mpm.md,
"Column collapse"); the rods of a deposit do not stand apart like that.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from geofrac.mpm.deposit import failure_line, runout, thickness

__all__ = [
    "BIN",
    "DENSITY",
    "FAILURE",
    "MOVED",
    "RUNOUT_THICKNESS",
    "SURFACE",
    "experiment_failure_angle",
    "experiment_runout",
    "measure_failure_angle",
    "measure_runout",
    "measure_surface_rms",
    "plot",
]

#: The experiment's final surface (x, y), metres, x from the wall, shape=(23, 2).
SURFACE = np.array(
    [
        (0.00012288, 0.099231753), (0.019603788, 0.099281704), (0.03983696, 0.095872045),
        (0.060043158, 0.089000779), (0.080267338, 0.084437251), (0.100083918, 0.077564986),
        (0.120302104, 0.072232212), (0.140127675, 0.066513816), (0.160348858, 0.061565666),
        (0.180159444, 0.053924154), (0.199979021, 0.047436512), (0.220200204, 0.042488361),
        (0.240790026, 0.034848848), (0.262186058, 0.030672941), (0.282023617, 0.026493037),
        (0.3022448, 0.021544886), (0.322094348, 0.018903475), (0.342312534, 0.013570701),
        (0.362162081, 0.010929289), (0.38239825, 0.007904254), (0.402235809, 0.00372435),
        (0.422094348, 0.002236808), (0.442348498, 0.001519511),
    ]
)  # fmt: skip

#: The experiment's failure line (x, y), metres, shape=(9, 2).
FAILURE = np.array(
    [
        (0.021159264, 0.098901077), (0.039792004, 0.090102699), (0.059974225, 0.080154449),
        (0.079727867, 0.065205099), (0.099904094, 0.054487602), (0.119636756, 0.036845891),
        (0.139420368, 0.025742772), (0.159560631, 0.010409798), (0.179353234, 0.000460549),
    ]
)  # fmt: skip

#: Thickness at which the deposit ends (m): about one rod diameter.
RUNOUT_THICKNESS = 0.002
#: Width of the thickness bins (m): half the spacing of the digitised surface.
BIN = 0.01
#: A particle that moved less than this (m) is in the undeformed zone.
MOVED = 0.0015
#: The rods' bulk density (kg/m³), Bui et al. (2008); the job's material.density.
DENSITY = 2650.0


def experiment_runout() -> float:
    """Where the digitised surface falls to :data:`RUNOUT_THICKNESS` (linear), metres."""
    x, y = SURFACE[:, 0], SURFACE[:, 1]
    k = int(np.nonzero(y >= RUNOUT_THICKNESS)[0][-1])
    s = (y[k] - RUNOUT_THICKNESS) / (y[k] - y[k + 1])
    return float(x[k] + s * (x[k + 1] - x[k]))


def experiment_failure_angle() -> float:
    """The digitised failure line's inclination from the horizontal (degrees).

    The least-squares line x(y) through its points, the fit of :func:`measure_failure_angle`.
    """
    slope, _ = np.polyfit(FAILURE[:, 1], FAILURE[:, 0], 1)
    return math.degrees(math.atan2(1.0, -slope))


def _last(out: Path) -> dict[str, np.ndarray]:
    """The last frame, with ``x0`` (initial positions) and ``x``, shape=(num_particles, 2)."""
    from geofrac.io.points import last_frame

    last = last_frame(out / "particles.h5")
    missing = {"mass", "displacement"} - set(last)
    if missing:
        raise ValueError(f"the collapse's measures need output.fields to hold {sorted(missing)}")
    last["x"] = last["geometry"][:, :2]
    last["x0"] = last["x"] - last["displacement"][:, :2]
    return last


def _thickness(out: Path) -> tuple[np.ndarray, np.ndarray]:
    last = _last(out)
    return thickness(last["x"], last["mass"] / DENSITY, bin_width=BIN)


def measure_runout(summary: dict[str, Any], out: Path) -> float:
    """The deposit's run-out from the wall (m) where it thins to 2 mm."""
    centres, t = _thickness(out)
    return runout(centres, t, at=RUNOUT_THICKNESS)


def measure_failure_angle(summary: dict[str, Any], out: Path) -> float:
    """The failure line's inclination from the horizontal (degrees)."""
    last = _last(out)
    spacing = float(np.sqrt(np.median(last["mass"]) / DENSITY))  # the lattice's spacing
    line = failure_line(last["x0"], last["x"] - last["x0"], moved=MOVED, row_tol=0.25 * spacing)
    return line.angle_deg


def measure_surface_rms(summary: dict[str, Any], out: Path) -> float:
    """RMS (m) of the deposit's thickness against the experiment's surface at its points."""
    centres, t = _thickness(out)
    got = np.interp(SURFACE[:, 0], centres, t, right=0.0)
    return float(np.sqrt(np.mean((got - SURFACE[:, 1]) ** 2)))


def plot(summary: dict[str, Any], out: Path, path: Path) -> None:
    """The deposit against the experiment: particles, thickness, failure lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    last = _last(out)
    x = last["x"]
    moved = np.linalg.norm(x - last["x0"], axis=1)
    centres, t = _thickness(out)
    fig, ax = plt.subplots(figsize=(9.0, 4.2), constrained_layout=True)
    und = moved < MOVED
    ax.plot(x[~und, 0], x[~und, 1], ".", ms=1.5, color="0.6", label="particles (moved)")
    ax.plot(
        x[und, 0],
        x[und, 1],
        ".",
        ms=1.5,
        color="tab:green",
        label=f"particles moved < {MOVED * 1e3:g} mm",
    )
    ax.step(
        centres,
        t,
        where="mid",
        color="tab:blue",
        label=f"thickness at the rods' density ({BIN * 1e3:g} mm bins)",
    )
    ax.plot(SURFACE[:, 0], SURFACE[:, 1], "k^", ms=4, label="experiment: surface")
    ax.plot(FAILURE[:, 0], FAILURE[:, 1], "kd", ms=4, mfc="none", label="experiment: failure line")
    ax.plot([0.2, 0.2, 0.0], [0.0, 0.1, 0.1], "k:", lw=1, label="column at t = 0")
    ax.set_xlim(0.0, max(0.6, float(centres[-1]) if len(centres) else 0.6))
    ax.set_ylim(0.0, 0.12)
    ax.set_xlabel("x from the wall (m)")
    ax.legend(fontsize=7, loc="upper right")
    spacing = float(np.sqrt(np.median(last["mass"]) / DENSITY))
    title = (
        "Column collapse (Bui et al. 2008): deposit at t_end against the experiment "
        f"(particles {spacing * 1e3:g} mm apart)"
    )
    save_figure(fig, [ax], path, title=title, ylabel="y (m)")
