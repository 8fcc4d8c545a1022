"""A granular deposit read from its particles: surface profile, run-out and failure line.

Pure numpy, 2D (x along the floor, y up). What an experiment of a collapsing column
measures, taken from the particles in a form that does not depend on how many particles
there are:

- the *thickness* t(x) of the deposit: the particles' area in each x-bin divided by the
  bin's width (the height of a dense layer of the same area; scattered single particles
  give a thin t, not a full particle's height). The caller chooses the area: the current
  one, or the mass over a reference density (a deposit whose particles stretched
  without stress, as at a cohesionless material's apex);
- the *run-out*: where t first falls below a stated thickness, going out from the
  deposit's start (an experiment sees the deposit end where it is about one grain thick;
  particles scattered ahead of it, beyond a gap, are not the deposit);
- the *failure line*: the boundary of the undeformed zone, the particles that moved less
  than a stated distance (an experiment's grain size), in the initial configuration, as
  each initial row's farthest undisturbed particle and the least-squares line through
  them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["FailureLine", "failure_line", "runout", "thickness"]


def thickness(
    x: np.ndarray, area: np.ndarray, *, bin_width: float, x_min: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """The deposit's thickness in bins along x.

    Args:
        x: particle positions, shape=(num_particles, 2).
        area: each particle's area (volume per unit width): current, or its mass over a
            reference density; shape=(num_particles,).
        bin_width: the bins' width (> 0).
        x_min: left edge of the first bin; particles left of it are ignored.

    Returns:
        (centres, t): the bins' centres and the thickness in each, shape=(num_bins,) each,
        up to the last bin holding a particle.
    """
    if bin_width <= 0:
        raise ValueError("bin_width must be > 0")
    i = np.floor((x[:, 0] - x_min) / bin_width).astype(np.int64)
    keep = i >= 0
    n = int(i[keep].max()) + 1 if np.any(keep) else 0
    t = np.bincount(i[keep], weights=area[keep], minlength=n) / bin_width
    return x_min + (np.arange(n) + 0.5) * bin_width, t


def runout(centres: np.ndarray, t: np.ndarray, *, at: float) -> float:
    """Where the deposit ends: the thickness first falls below ``at`` going out along x.

    Linear between the centres of the last bin of the contiguous deposit (t ≥ ``at`` from
    the first bin on) and the next one (the deposit thins continuously). Bins beyond the
    first thin one (scattered particles ahead of the deposit) are not counted.

    Raises:
        ValueError: the first bin is not ``at`` thick (no deposit starts there).
    """
    thin = np.nonzero(t < at)[0]
    if len(t) == 0 or (len(thin) and thin[0] == 0):
        raise ValueError(f"the deposit's first bin is not {at:g} thick")
    if len(thin) == 0:
        return float(centres[-1])
    k = int(thin[0]) - 1
    s = (t[k] - at) / (t[k] - t[k + 1])
    return float(centres[k] + s * (centres[k + 1] - centres[k]))


@dataclass(frozen=True)
class FailureLine:
    """The boundary of the undeformed zone in the initial configuration.

    Attributes:
        y: the initial rows' heights, shape=(num_rows,).
        x: each row's farthest undisturbed particle (nan: none), shape=(num_rows,).
        angle_deg: the least-squares line's inclination from the horizontal, degrees.
        x_base: where that line meets y = 0.
    """

    y: np.ndarray
    x: np.ndarray
    angle_deg: float
    x_base: float

    def x_at(self, y: float) -> float:
        """The least-squares line's x at height ``y``."""
        return self.x_base - y / math.tan(math.radians(self.angle_deg))


def failure_line(x0: np.ndarray, u: np.ndarray, *, moved: float, row_tol: float) -> FailureLine:
    """The undeformed zone's boundary: particles that moved less than ``moved``.

    Args:
        x0: initial positions, shape=(num_particles, 2).
        u: displacements, shape=(num_particles, 2).
        moved: a particle is undisturbed when |u| < ``moved``.
        row_tol: initial heights closer than this are one row.

    Raises:
        ValueError: fewer than 3 rows have an undisturbed particle (no line).
    """
    und = np.linalg.norm(u, axis=1) < moved
    keys = np.round(x0[:, 1] / row_tol).astype(np.int64)
    rows = np.unique(keys)
    ys = np.array([x0[keys == k, 1].mean() for k in rows])
    xs = np.array(
        [x0[(keys == k) & und, 0].max() if np.any((keys == k) & und) else np.nan for k in rows]
    )
    good = np.isfinite(xs)
    if good.sum() < 3:
        raise ValueError("fewer than 3 rows keep an undisturbed particle: no failure line")
    slope, x_base = np.polyfit(ys[good], xs[good], 1)  # x = x_base + slope y
    angle = math.degrees(math.atan2(1.0, -slope))
    return FailureLine(ys, xs, angle, float(x_base))
