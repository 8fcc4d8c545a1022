"""Random fracture networks: fracture sets, samplers and the :class:`Network` they make.

A fracture set (Edo (2016), §2.4, Table 2.1) has a mean orientation with a normal or von Mises
spread, lengths from the power law F_N = 1/L^n (eq. 2.28) truncated to
[lmin, lmax], and centres uniform in a region. :func:`generate_network` draws the sets,
each from its own random stream, either a fixed number of fractures or until a target
density P21 (trace length per unit area) is reached in a domain.

Angles are trace directions counter-clockwise from +x in degrees; fractures are axial
(θ and θ + 180° are the same fracture), so angles are returned folded to [0, 180).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Integral, Real
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from geofrac.dfn.errors import DfnError
from geofrac.dfn.polygon import as_polygon, clip_segments, points_in_polygon, polygon_area
from geofrac.dfn.stats import fold_axial_deg

__all__ = [
    "BATCH",
    "MAX_P21_FRACTURES",
    "FractureSet",
    "Network",
    "check_set_name",
    "generate_network",
    "network_p21",
    "power_law_ccdf",
    "power_law_cdf",
    "power_law_lengths",
    "sample_angles",
    "uniform_points",
]

#: Fractures drawn per batch in :func:`generate_network`; part of the reproducibility
#: contract (changing it changes every network drawn from a seed).
BATCH = 1024

#: A P21 target needing more fractures than this in one set is refused.
MAX_P21_FRACTURES = 2_000_000

_DISTRIBUTIONS = ("normal", "von_mises")


def check_set_name(name: object, where: str) -> str:
    """Check a fracture set name: a non-empty string without commas, quotes or line breaks.

    The name is written as it is in the CSV file format of :mod:`geofrac.dfn.io`.

    Args:
        name: the candidate name.
        where: what the name belongs to, for the message.

    Returns:
        The name.
    """
    if not isinstance(name, str) or not name:
        raise DfnError(f"{where}: set name must be a non-empty string, got {name!r}")
    bad = [c for c in ',"\n\r' if c in name]
    if bad or name != name.strip():
        raise DfnError(
            f"{where}: set name {name!r} must not contain commas, quotes or line breaks, "
            "nor start or end with white space"
        )
    return name


def _finite_real(value: object, field: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, Real):
        raise DfnError(f"{where}: {field} must be a number, got {value!r}")
    if not math.isfinite(float(value)):
        raise DfnError(f"{where}: {field} must be finite, got {value!r}")
    return float(value)


def _check_power_law(lmin: float, lmax: float, exponent: float, where: str) -> None:
    for field, v in (("lmin", lmin), ("lmax", lmax), ("exponent", exponent)):
        _finite_real(v, field, where)
    if lmin <= 0.0:
        raise DfnError(f"{where}: lmin must be > 0, got {lmin}")
    if lmin > lmax:
        raise DfnError(f"{where}: lmin > lmax (lmin = {lmin}, lmax = {lmax})")
    if exponent <= 0.0:
        raise DfnError(f"{where}: exponent must be > 0, got {exponent}")


@dataclass(frozen=True)
class FractureSet:
    """One fracture set: orientation, length law and how many fractures.

    Attributes:
        name: set name, unique in a network; non-empty, no commas, quotes or line breaks.
        mean_deg: mean trace direction in degrees counter-clockwise from +x (axial).
        spread: for ``"normal"``, the standard deviation of the angle in degrees (0 gives
            every fracture the mean angle); for ``"von_mises"``, the concentration κ > 0
            of the axial von Mises law: the doubled angle 2θ follows VM(2·mean, κ) and is
            halved, the correct way to put a von Mises law on axial data.
        lmin: shortest length, > 0.
        lmax: longest length, >= lmin (lmin == lmax: all fractures that long).
        exponent: power-law exponent n of F_N = 1/L^n (Edo (2016), eq. 2.28), > 0.
        distribution: ``"normal"`` or ``"von_mises"``.
        count: number of fractures to draw; exactly one of ``count`` and ``p21``.
        p21: target density: trace length clipped to the domain per unit domain area.
    """

    name: str
    mean_deg: float
    spread: float
    lmin: float
    lmax: float
    exponent: float
    distribution: Literal["normal", "von_mises"] = "normal"
    count: int | None = None
    p21: float | None = None

    def __post_init__(self) -> None:
        """Check every field; raise DfnError naming the set and the field."""
        where = f"fracture set {self.name!r}"
        check_set_name(self.name, "fracture set")
        _finite_real(self.mean_deg, "mean_deg", where)
        _finite_real(self.spread, "spread", where)
        _check_power_law(self.lmin, self.lmax, self.exponent, where)
        if self.distribution not in _DISTRIBUTIONS:
            raise DfnError(
                f"{where}: unknown distribution {self.distribution!r}, "
                f"expected one of {', '.join(_DISTRIBUTIONS)}"
            )
        if self.spread < 0.0:
            raise DfnError(f"{where}: spread must be >= 0, got {self.spread}")
        if self.distribution == "von_mises" and self.spread <= 0.0:
            raise DfnError(f"{where}: von Mises concentration (spread) must be > 0, got 0")
        if (self.count is None) == (self.p21 is None):
            raise DfnError(f"{where}: give exactly one of count and p21")
        if self.count is not None and (
            isinstance(self.count, bool) or not isinstance(self.count, Integral)
        ):
            raise DfnError(f"{where}: count must be an integer, got {self.count!r}")
        if self.count is not None and self.count < 0:
            raise DfnError(f"{where}: count must be >= 0, got {self.count}")
        if self.p21 is not None:
            _finite_real(self.p21, "p21", where)
            if self.p21 < 0.0:
                raise DfnError(f"{where}: negative density p21 = {self.p21}")


# ---------------------------------------------------------------------------- samplers


def power_law_ccdf(l: ArrayLike, lmin: float, lmax: float, *, exponent: float) -> np.ndarray:  # noqa: E741
    """P(L > l) of the power law F_N = 1/L^n (Edo (2016), eq. (2.28)) truncated to [lmin, lmax].

    ``(l^-n − lmax^-n) / (lmin^-n − lmax^-n)`` on [lmin, lmax], 1 below and 0 above; for
    ``lmin == lmax`` a step from 1 to 0 at lmin.

    Args:
        l: lengths, any shape.
        lmin: shortest length, > 0.
        lmax: longest length, >= lmin.
        exponent: n > 0.

    Returns:
        Probabilities, same shape as ``l``.
    """
    _check_power_law(lmin, lmax, exponent, "power law")
    x = np.asarray(l, dtype=float)
    if lmin == lmax:
        return np.where(x < lmin, 1.0, 0.0)
    rmax = (lmax / lmin) ** -exponent
    xr = np.clip(x, lmin, lmax) / lmin
    return np.clip((xr**-exponent - rmax) / (1.0 - rmax), 0.0, 1.0)


def power_law_cdf(l: ArrayLike, lmin: float, lmax: float, *, exponent: float) -> np.ndarray:  # noqa: E741
    """P(L <= l) of the truncated power law: 1 − :func:`power_law_ccdf`.

    Args:
        l: lengths, any shape.
        lmin: shortest length, > 0.
        lmax: longest length, >= lmin.
        exponent: n > 0.

    Returns:
        Probabilities, same shape as ``l``.
    """
    return 1.0 - power_law_ccdf(l, lmin, lmax, exponent=exponent)


def power_law_lengths(
    rng: np.random.Generator, n: int, lmin: float, *, lmax: float, exponent: float
) -> np.ndarray:
    """Lengths from the truncated power law by inverse transform.

    Draws ``u = rng.random(n)`` (also when lmin == lmax, so the stream advances the same)
    and solves ``P(L > l) = u``: ``l = lmin·(r + u(1 − r))^(−1/n)`` with
    ``r = (lmax/lmin)^−n``.

    Args:
        rng: random generator.
        n: number of lengths, >= 0.
        lmin: shortest length, > 0.
        lmax: longest length, >= lmin.
        exponent: n > 0.

    Returns:
        Lengths in [lmin, lmax], shape=(n,).
    """
    _check_power_law(lmin, lmax, exponent, "power law")
    u = rng.random(n)
    if lmin == lmax:
        return np.full(n, float(lmin))
    r = (lmax / lmin) ** -exponent
    return np.clip(lmin * (r + u * (1.0 - r)) ** (-1.0 / exponent), lmin, lmax)


def sample_angles(rng: np.random.Generator, n: int, fset: FractureSet) -> np.ndarray:
    """Fracture angles of a set.

    ``"normal"``: ``mean + spread · rng.standard_normal(n)``; ``"von_mises"``:
    ``rng.vonmises(2·mean, κ, n) / 2`` (in radians), a von Mises law on the doubled
    angle as befits axial data.

    Args:
        rng: random generator.
        n: number of angles, >= 0.
        fset: the set giving the distribution, mean and spread.

    Returns:
        Angles in degrees folded to [0, 180), shape=(n,).
    """
    if fset.distribution == "von_mises":
        doubled = rng.vonmises(math.radians(2.0 * fset.mean_deg), fset.spread, n)
        return fold_axial_deg(np.degrees(doubled) / 2.0)
    return fold_axial_deg(fset.mean_deg + fset.spread * rng.standard_normal(n))


def uniform_points(rng: np.random.Generator, n: int, poly: ArrayLike) -> np.ndarray:
    """Points uniform in a polygon, by rejection from its bounding box.

    Draws batches of ``rng.random((k, 2))`` scaled to the bounding box, with ``k`` sized
    from the area ratio, and keeps the accepted points in drawing order until ``n`` are
    found; the result depends only on the generator's state, ``n`` and the polygon.

    Args:
        rng: random generator.
        n: number of points, >= 0.
        poly: polygon vertices, shape=(m, 2).

    Returns:
        Points, shape=(n, 2).
    """
    poly = as_polygon(poly)
    if n < 0:
        raise DfnError(f"uniform_points: n must be >= 0, got {n}")
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    ratio = polygon_area(poly) / float(np.prod(hi - lo))
    found: list[np.ndarray] = []
    missing = n
    while missing > 0:
        k = int(1.1 * missing / ratio) + 16
        pts = lo + rng.random((k, 2)) * (hi - lo)
        pts = pts[points_in_polygon(pts, poly)][:missing]
        found.append(pts)
        missing -= len(pts)
    return np.concatenate(found) if found else np.zeros((0, 2))


# ----------------------------------------------------------------------------- network


@dataclass(frozen=True, eq=False)
class Network:
    """Fracture traces: straight segments, each in one set.

    The arrays are stored as read-only copies. Segments are not clipped: a fracture
    centred near the edge of the region extends beyond it.

    Attributes:
        segments: endpoints, shape=(n, 2, 2) (fracture, endpoint, xy), finite.
        set_index: set of each fracture, shape=(n,) int in [0, len(set_names)).
        set_names: distinct set names, see :func:`check_set_name`.
    """

    segments: np.ndarray
    set_index: np.ndarray
    set_names: tuple[str, ...]

    def __post_init__(self) -> None:
        """Check and freeze the arrays; raise DfnError on a wrong shape or value."""
        try:
            seg = np.array(self.segments, dtype=float)
        except (TypeError, ValueError) as exc:
            raise DfnError(f"network: segments are not numbers ({exc})") from None
        if seg.size == 0:
            seg = seg.reshape(0, 2, 2)
        if seg.ndim != 3 or seg.shape[1:] != (2, 2):
            raise DfnError(f"network: segments must have shape (n, 2, 2), got {seg.shape}")
        if not np.all(np.isfinite(seg)):
            bad = int(np.nonzero(~np.all(np.isfinite(seg), axis=(1, 2)))[0][0])
            raise DfnError(f"network: fracture {bad} has a non-finite coordinate")
        idx = np.array(self.set_index)
        if idx.size == 0:
            idx = idx.astype(np.intp).reshape(0)
        if not np.issubdtype(idx.dtype, np.integer):
            raise DfnError(f"network: set_index must be integers, got dtype {idx.dtype}")
        if idx.shape != (len(seg),):
            raise DfnError(f"network: set_index must have shape ({len(seg)},), got {idx.shape}")
        names = tuple(self.set_names)
        for name in names:
            check_set_name(name, "network")
        if len(set(names)) != len(names):
            raise DfnError(f"network: set names must be distinct, got {list(names)}")
        if len(idx) and (idx.min() < 0 or idx.max() >= len(names)):
            bad = int(np.nonzero((idx < 0) | (idx >= len(names)))[0][0])
            raise DfnError(
                f"network: fracture {bad} has set index {int(idx[bad])}, outside [0, {len(names)})"
            )
        idx = idx.astype(np.intp)
        seg.flags.writeable = False
        idx.flags.writeable = False
        object.__setattr__(self, "segments", seg)
        object.__setattr__(self, "set_index", idx)
        object.__setattr__(self, "set_names", names)

    def __len__(self) -> int:
        """Number of fractures."""
        return len(self.segments)

    @property
    def lengths(self) -> np.ndarray:
        """Fracture lengths, shape=(n,)."""
        d = self.segments[:, 1] - self.segments[:, 0]
        return np.hypot(d[:, 0], d[:, 1])

    @property
    def angles_deg(self) -> np.ndarray:
        """Trace directions in degrees folded to [0, 180), shape=(n,)."""
        d = self.segments[:, 1] - self.segments[:, 0]
        return fold_axial_deg(np.degrees(np.arctan2(d[:, 1], d[:, 0])))

    @property
    def centres(self) -> np.ndarray:
        """Fracture midpoints, shape=(n, 2)."""
        return 0.5 * (self.segments[:, 0] + self.segments[:, 1])


def network_p21(network: Network, domain: ArrayLike) -> float:
    """P21 density: trace length inside the domain per unit domain area.

    Args:
        network: the fractures.
        domain: polygon vertices, shape=(m, 2).
    """
    poly = as_polygon(domain)
    pieces, _ = clip_segments(network.segments, poly)
    d = pieces[:, 1] - pieces[:, 0]
    return float(np.sum(np.hypot(d[:, 0], d[:, 1]))) / polygon_area(poly)


def _draw_batch(rng: np.random.Generator, fset: FractureSet, region: np.ndarray) -> np.ndarray:
    """BATCH fractures of a set: centres, then angles, then lengths; shape=(BATCH, 2, 2)."""
    centres = uniform_points(rng, BATCH, region)
    theta = np.radians(sample_angles(rng, BATCH, fset))
    lengths = power_law_lengths(rng, BATCH, fset.lmin, lmax=fset.lmax, exponent=fset.exponent)
    half = 0.5 * lengths[:, None] * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    return np.stack([centres - half, centres + half], axis=1)


def _draw_set(
    rng: np.random.Generator, fset: FractureSet, region: np.ndarray, domain: np.ndarray
) -> np.ndarray:
    """The fractures of one set, shape=(k, 2, 2)."""
    if fset.count is not None:
        n_batches = -(-fset.count // BATCH)
        if n_batches == 0:
            return np.zeros((0, 2, 2))
        return np.concatenate([_draw_batch(rng, fset, region) for _ in range(n_batches)])[
            : fset.count
        ]
    assert fset.p21 is not None
    target = fset.p21 * polygon_area(domain)
    batches: list[np.ndarray] = []
    total = 0.0
    while target > 0.0:
        if len(batches) * BATCH >= MAX_P21_FRACTURES:
            raise DfnError(
                f"fracture set {fset.name!r}: p21 = {fset.p21} not reached with "
                f"{MAX_P21_FRACTURES} fractures (P21 so far {total / polygon_area(domain):.6g}); "
                "does the region overlap the domain?"
            )
        batch = _draw_batch(rng, fset, region)
        pieces, parent = clip_segments(batch, domain)
        d = pieces[:, 1] - pieces[:, 0]
        clipped = np.bincount(parent, weights=np.hypot(d[:, 0], d[:, 1]), minlength=BATCH)
        running = total + np.cumsum(clipped)
        reached = np.nonzero(running >= target)[0]
        if len(reached):
            batches.append(batch[: reached[0] + 1])
            break
        batches.append(batch)
        total = float(running[-1])
    return np.concatenate(batches) if batches else np.zeros((0, 2, 2))


def generate_network(
    sets: Sequence[FractureSet],
    region: ArrayLike,
    seed: int,
    *,
    domain: ArrayLike | None = None,
) -> Network:
    """Draw a fracture network, set after set.

    Set ``i`` draws from its own stream ``np.random.default_rng([seed, i])``, so adding a
    set after the others leaves their fractures unchanged. A set draws fractures in
    batches of :data:`BATCH`; in each batch, the centres of all its fractures (uniform in
    ``region``, :func:`uniform_points`), then their angles (:func:`sample_angles`), then
    their lengths (:func:`power_law_lengths`). Each fracture is the segment of that
    length and angle centred at its centre (not clipped). Fracture ``k`` of a set is the
    same whatever the set's ``count``, so a smaller count gives a prefix.

    - ``count``: exactly ``count`` fractures.
    - ``p21``: the shortest prefix of the drawn sequence whose length clipped to
      ``domain`` reaches ``p21 × area(domain)``: the target is met, and without the last
      fracture it would not be. ``p21 = 0`` gives no fractures.

    Args:
        sets: the fracture sets, distinct names; their order fixes the streams.
        region: polygon of the fracture centres, shape=(m, 2).
        seed: non-negative integer seed.
        domain: polygon of the P21 density, shape=(k, 2); defaults to ``region``.

    Returns:
        The network, fractures ordered by set, ``set_names`` in the order of ``sets``.

    Raises:
        DfnError: a bad seed, set list or polygon, or a P21 target not reached with
            :data:`MAX_P21_FRACTURES` fractures (e.g. region and domain apart).
    """
    if isinstance(seed, bool) or not isinstance(seed, Integral) or seed < 0:
        raise DfnError(f"generate_network: seed must be a non-negative integer, got {seed!r}")
    for i, fset in enumerate(sets):
        if not isinstance(fset, FractureSet):
            raise DfnError(f"generate_network: sets[{i}] is not a FractureSet: {fset!r}")
    names = [fset.name for fset in sets]
    dupes = sorted({name for name in names if names.count(name) > 1})
    if dupes:
        raise DfnError(f"generate_network: set names must be distinct, repeated: {dupes}")
    region_poly = as_polygon(region)
    domain_poly = region_poly if domain is None else as_polygon(domain)
    segments: list[np.ndarray] = []
    index: list[np.ndarray] = []
    for i, fset in enumerate(sets):
        rng = np.random.default_rng([int(seed), i])
        seg = _draw_set(rng, fset, region_poly, domain_poly)
        segments.append(seg)
        index.append(np.full(len(seg), i, dtype=np.intp))
    return Network(
        segments=np.concatenate(segments) if segments else np.zeros((0, 2, 2)),
        set_index=np.concatenate(index) if index else np.zeros(0, dtype=np.intp),
        set_names=tuple(names),
    )
