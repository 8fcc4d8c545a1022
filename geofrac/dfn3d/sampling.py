"""Random 3D disc networks: fracture sets, samplers, clipped areas and P32.

A fracture set (:class:`DiscSet`) has a Fisher (1953) distributed pole about a mean pole
(trend, plunge, concentration κ), radii from the truncated power law with
P(R > r) = (r^−α − rmax^−α)/(rmin^−α − rmax^−α) (the convention of dfnWorks), centres
uniform in a region box, and either a fracture count or a target P32 (fracture area per
unit volume inside the domain box). :func:`sample_network` draws the sets, each from its
own random stream, into a :class:`~geofrac.dfn3d.network.DiscNetwork`.

Areas inside a box (:func:`clipped_area`) are those of the inscribed regular polygon of
``sides`` vertices clipped against the box's six half-spaces (Sutherland–Hodgman in the
disc plane); the polygon's relative area error 1 − sin(2π/N)·N/(2π) is 1.27e-5 for the
default N = 720 and the clipped area is never larger than the disc's.

Coordinates: x east, y north, z up; a pole's trend is clockwise from north (+y) and its
plunge positive downwards (:func:`~geofrac.dfn3d.network.pole_to_normal`). A box is
``(xmin, ymin, zmin, xmax, ymax, zmax)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np
from numpy.typing import ArrayLike

from geofrac.dfn.errors import DfnError
from geofrac.dfn.sampling import check_set_name, power_law_cdf, power_law_lengths
from geofrac.dfn3d.network import DiscNetwork, canonical_normals, pole_to_normal

__all__ = [
    "BATCH",
    "CLIP_CHUNK",
    "DEFAULT_SIDES",
    "MAX_P32_FRACTURES",
    "DiscSet",
    "as_box",
    "box_volume",
    "check_radius_law",
    "clipped_area",
    "fisher_poles",
    "network_p32",
    "polygon_area_error",
    "power_law_radii",
    "power_law_radius_cdf",
    "sample_network",
    "set_p32",
]

#: Fractures drawn per batch in :func:`sample_network`; part of the reproducibility
#: contract (changing it changes every network drawn from a seed).
BATCH = 1024

#: A P32 target needing more fractures than this in one set is refused.
MAX_P32_FRACTURES = 1_000_000

#: Vertices of the regular polygon standing for a disc in :func:`clipped_area`.
DEFAULT_SIDES = 720

#: Discs clipped at a time in :func:`clipped_area` (bounds the work arrays' memory).
CLIP_CHUNK = 256


# --------------------------------------------------------------------------- checks


def _real(value: object, field: str, where: str, *, allow_inf: bool = False) -> float:
    """``value`` as a float; DfnError naming ``field`` if not a (finite) real number."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise DfnError(f"{where}: {field} must be a number, got {value!r}")
    x = float(value)
    if math.isnan(x) or (math.isinf(x) and not (allow_inf and x > 0)):
        raise DfnError(f"{where}: {field} must be finite, got {value!r}")
    return x


def check_radius_law(rmin: object, rmax: object, alpha: object, *, where: str) -> None:
    """Check a truncated power law: 0 < rmin <= rmax and α > 0, all finite.

    Raises:
        DfnError: naming ``where`` and the field (radius_min, radius_max or alpha).
    """
    lo = _real(rmin, "radius_min", where)
    hi = _real(rmax, "radius_max", where)
    a = _real(alpha, "alpha", where)
    if lo <= 0.0:
        raise DfnError(f"{where}: radius_min must be > 0, got {lo}")
    if lo > hi:
        raise DfnError(f"{where}: radius_min > radius_max ({lo} > {hi})")
    if a <= 0.0:
        raise DfnError(f"{where}: alpha must be > 0, got {a}")


def _check_kappa(kappa: object, where: str) -> float:
    k = _real(kappa, "kappa", where, allow_inf=True)
    if k <= 0.0:
        raise DfnError(f"{where}: kappa must be > 0 (math.inf: no spread), got {k}")
    return k


def as_box(box: ArrayLike, where: str = "box") -> np.ndarray:
    """Check an axis-aligned box ``(xmin, ymin, zmin, xmax, ymax, zmax)``.

    Args:
        box: six finite numbers with min < max on each axis.
        where: what the box belongs to, for the message.

    Returns:
        The box as floats, shape=(6,).

    Raises:
        DfnError: not six finite numbers, or an empty extent.
    """
    try:
        b = np.array(box, dtype=float)
    except (TypeError, ValueError):
        raise DfnError(
            f"{where}: must be six numbers (xmin, ymin, zmin, xmax, ymax, zmax), got {box!r}"
        ) from None
    if b.shape != (6,):
        raise DfnError(
            f"{where}: must be six numbers (xmin, ymin, zmin, xmax, ymax, zmax), "
            f"got shape {b.shape}"
        )
    if not np.all(np.isfinite(b)):
        raise DfnError(f"{where}: coordinates must be finite, got {b.tolist()}")
    if np.any(b[:3] >= b[3:]):
        raise DfnError(f"{where}: needs min < max on every axis, got {b.tolist()}")
    return b


def box_volume(box: ArrayLike) -> float:
    """The volume of a box ``(xmin, ymin, zmin, xmax, ymax, zmax)``, shape=(6,)."""
    b = as_box(box)
    return float(np.prod(b[3:] - b[:3]))


@dataclass(frozen=True)
class DiscSet:
    """One disc fracture set: orientation, radius law, intensity and region.

    Attributes:
        name: set name, unique in a network; non-empty, no commas, quotes or line breaks.
        trend: trend of the mean pole in degrees, clockwise from north (+y).
        plunge: plunge of the mean pole in degrees, positive down, in [−90, 90].
        kappa: Fisher concentration κ > 0; ``math.inf`` gives every pole the mean pole.
        radius_min: smallest radius rmin > 0.
        radius_max: largest radius rmax >= rmin (rmin == rmax: every radius rmin).
        alpha: exponent α > 0 of P(R > r) = (r^−α − rmax^−α)/(rmin^−α − rmax^−α).
        p32: target fracture area inside the domain box per unit box volume, >= 0;
            exactly one of ``p32`` and ``count``.
        count: number of fractures, >= 0.
        region: box of the centres ``(xmin, ymin, zmin, xmax, ymax, zmax)``; None: the
            domain box of :func:`sample_network`.
    """

    name: str
    trend: float
    plunge: float
    kappa: float
    radius_min: float
    radius_max: float
    alpha: float
    p32: float | None = None
    count: int | None = None
    region: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        """Check every field; raise DfnError naming the set and the field."""
        check_set_name(self.name, "disc set")
        where = f"disc set {self.name!r}"
        _real(self.trend, "trend", where)
        plunge = _real(self.plunge, "plunge", where)
        if not -90.0 <= plunge <= 90.0:
            raise DfnError(f"{where}: plunge must be in [-90, 90] degrees, got {plunge}")
        _check_kappa(self.kappa, where)
        check_radius_law(self.radius_min, self.radius_max, self.alpha, where=where)
        if (self.count is None) == (self.p32 is None):
            raise DfnError(f"{where}: give exactly one of p32 and count")
        if self.count is not None:
            if isinstance(self.count, bool) or not isinstance(self.count, Integral):
                raise DfnError(f"{where}: count must be an integer, got {self.count!r}")
            if self.count < 0:
                raise DfnError(f"{where}: count must be >= 0, got {self.count}")
        if self.p32 is not None and _real(self.p32, "p32", where) < 0.0:
            raise DfnError(f"{where}: p32 must be >= 0, got {self.p32}")
        if self.region is not None:
            region = as_box(self.region, f"{where}: region")
            object.__setattr__(self, "region", tuple(float(v) for v in region))

    @property
    def mean_pole(self) -> np.ndarray:
        """The unit mean pole from trend and plunge, shape=(3,)."""
        return pole_to_normal(self.trend, self.plunge)[0]


# ---------------------------------------------------------------------------- samplers


def fisher_poles(rng: np.random.Generator, n: int, *, mean: ArrayLike, kappa: float) -> np.ndarray:
    """Poles from the Fisher (1953) distribution about ``mean`` with concentration κ.

    Draws ``u = rng.random(n)`` then ``v = rng.random(n)`` (also for κ = inf, so the
    stream advances the same). The angle θ to the mean follows the inverse CDF
    cos θ = 1 + ln(u' + (1 − u')e^−2κ)/κ with u' = 1 − u, evaluated as
    1 − cos θ = −log1p(u·expm1(−2κ))/κ, which neither overflows for large κ (1e6 and
    beyond: expm1 → −1) nor cancels for small θ, and sin θ = √((1 − cos θ)(1 + cos θ)).
    The azimuth about the mean is 2πv, measured from the first of the in-plane axes
    (e1 ∝ a × mean with a the coordinate axis least aligned with the mean, e2 = mean × e1).

    Args:
        rng: random generator.
        n: number of poles, >= 0.
        mean: the mean pole, a nonzero vector, shape=(3,).
        kappa: concentration κ > 0; ``math.inf`` returns the mean pole n times.

    Returns:
        Unit poles (not sign-normalised: they scatter about ``mean``), shape=(n, 3).
    """
    k = _check_kappa(kappa, "fisher_poles")
    m = _unit_vector(mean, "fisher_poles: mean")
    u = rng.random(n)
    v = rng.random(n)
    if math.isinf(k):
        one_minus_cos = np.zeros(n)
    else:
        one_minus_cos = np.clip(-np.log1p(u * math.expm1(-2.0 * k)) / k, 0.0, 2.0)
    cos_t = 1.0 - one_minus_cos
    sin_t = np.sqrt(one_minus_cos * (2.0 - one_minus_cos))
    phi = 2.0 * np.pi * v
    e1, e2 = _plane_basis(m[None, :])
    return (
        (sin_t * np.cos(phi))[:, None] * e1
        + (sin_t * np.sin(phi))[:, None] * e2
        + cos_t[:, None] * m[None, :]
    )


def power_law_radius_cdf(r: ArrayLike, *, rmin: float, rmax: float, alpha: float) -> np.ndarray:
    """P(R <= r) of the truncated power law.

    1 − (r^−α − rmax^−α)/(rmin^−α − rmax^−α) on [rmin, rmax], 0 below and 1 above; a
    step at rmin when rmin == rmax. The law of :mod:`geofrac.dfn.sampling` (same formula).

    Args:
        r: radii, any shape.
        rmin: smallest radius, > 0.
        rmax: largest radius, >= rmin.
        alpha: α > 0.

    Returns:
        Probabilities, same shape as ``r``.
    """
    check_radius_law(rmin, rmax, alpha, where="power law")
    return power_law_cdf(r, rmin, rmax, exponent=alpha)


def power_law_radii(
    rng: np.random.Generator, n: int, *, rmin: float, rmax: float, alpha: float
) -> np.ndarray:
    """Radii from the truncated power law by inverse transform.

    Draws ``u = rng.random(n)`` (also when rmin == rmax) and returns
    ``r = rmin·(q + u(1 − q))^(−1/α)`` with ``q = (rmax/rmin)^−α``, the solution of
    P(R > r) = u (:func:`geofrac.dfn.sampling.power_law_lengths`).

    Args:
        rng: random generator.
        n: number of radii, >= 0.
        rmin: smallest radius, > 0.
        rmax: largest radius, >= rmin.
        alpha: α > 0.

    Returns:
        Radii in [rmin, rmax], shape=(n,).
    """
    check_radius_law(rmin, rmax, alpha, where="power law")
    return power_law_lengths(rng, n, rmin, lmax=rmax, exponent=alpha)


# ----------------------------------------------------------------------- clipped area


def _unit_vector(v: ArrayLike, where: str) -> np.ndarray:
    x = np.asarray(v, dtype=float)
    if x.shape != (3,) or not np.all(np.isfinite(x)) or not np.any(x != 0.0):
        raise DfnError(f"{where}: must be a finite nonzero 3-vector, got {x.tolist()}")
    return x / float(np.linalg.norm(x))


def _plane_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unit in-plane axes e1, e2 with (e1, e2, n) right-handed, each shape=(n, 3).

    e1 ∝ a × n with a the coordinate axis of the smallest |n_k| (first on ties).
    """
    a = np.zeros_like(normal)
    a[np.arange(len(normal)), np.argmin(np.abs(normal), axis=1)] = 1.0
    e1 = np.cross(a, normal)
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    return e1, np.cross(normal, e1)


def polygon_area_error(sides: int = DEFAULT_SIDES) -> float:
    """Relative area deficit 1 − sin(2π/N)·N/(2π) of the inscribed regular N-gon of a disc."""
    return 1.0 - math.sin(2.0 * math.pi / sides) * sides / (2.0 * math.pi)


def _clip_half_plane(poly: np.ndarray, off: np.ndarray, grad: np.ndarray) -> np.ndarray:
    """Clip rings of 2D points to {p: off + grad·p >= 0} (Sutherland–Hodgman).

    Args:
        poly: convex rings, repeated points allowed, shape=(m, k, 2).
        off: offsets, shape=(m,).
        grad: gradients, shape=(m, 2).

    Returns:
        The clipped rings padded by repeating their last point (all zeros when
        nothing is left), shape=(m, k + 1, 2).
    """
    m, k, _ = poly.shape
    d = off[:, None] + poly[..., 0] * grad[:, 0, None] + poly[..., 1] * grad[:, 1, None]
    d_next = np.roll(d, -1, axis=1)
    inside = d >= 0.0
    crosses = inside != (d_next >= 0.0)
    t = np.where(crosses, d / np.where(crosses, d - d_next, 1.0), 0.0)
    hit = poly + t[..., None] * (np.roll(poly, -1, axis=1) - poly)
    candidates = np.stack([poly, hit], axis=2).reshape(m, 2 * k, 2)
    keep = np.stack([inside, crosses], axis=2).reshape(m, 2 * k)
    count = keep.sum(axis=1)
    width = k + 1  # the most a convex ring can have; fixed, so rows do not depend on others
    order = np.argsort(~keep, axis=1, kind="stable")[:, :width]
    out = np.take_along_axis(candidates, order[..., None], axis=1)
    last = np.take_along_axis(out, np.maximum(count - 1, 0)[:, None, None], axis=1)
    valid = np.arange(width)[None, :] < count[:, None]
    out = np.where(valid[..., None], out, last)
    out[count == 0] = 0.0
    return out


def _clipped_polygon_area(
    centre: np.ndarray, normal: np.ndarray, radius: np.ndarray, *, box: np.ndarray, sides: int
) -> np.ndarray:
    """Areas of the inscribed polygons clipped to the box, shape=(m,), by chunks."""
    angle = 2.0 * np.pi * np.arange(sides) / sides
    unit = np.stack([np.cos(angle), np.sin(angle)], axis=1)
    out = np.empty(len(radius))
    for start in range(0, len(radius), CLIP_CHUNK):
        sl = slice(start, start + CLIP_CHUNK)
        c, r = centre[sl], radius[sl]
        e1, e2 = _plane_basis(normal[sl])
        poly = r[:, None, None] * unit[None, :, :]
        for axis in range(3):
            g = np.stack([e1[:, axis], e2[:, axis]], axis=1)
            poly = _clip_half_plane(poly, c[:, axis] - box[axis], g)
            poly = _clip_half_plane(poly, box[3 + axis] - c[:, axis], -g)
        x, y = poly[..., 0], poly[..., 1]
        xn, yn = np.roll(x, -1, axis=1), np.roll(y, -1, axis=1)
        out[sl] = 0.5 * np.sum(x * yn - xn * y, axis=1)
    return np.maximum(out, 0.0)


def clipped_area(
    discs: DiscNetwork | tuple[ArrayLike, ArrayLike, ArrayLike],
    box: ArrayLike,
    *,
    sides: int = DEFAULT_SIDES,
) -> np.ndarray:
    """The area of each disc inside an axis-aligned box.

    Each disc is replaced by its inscribed regular polygon of ``sides`` vertices (in the
    disc plane, starting on the axis e1 of :func:`fisher_poles`), which is clipped
    against the six half-spaces of the box (Sutherland–Hodgman in the disc plane,
    vectorised over discs); the clipped area is the shoelace area of what is left. The
    polygon's relative area error is 1 − sin(2π/N)·N/(2π) (1.27e-5 for N = 720,
    5.1e-5 for N = 360): a disc wholly inside gets (N/2)·r²·sin(2π/N) and any clipped
    area A satisfies A_disc − (1 − sin(2π/N)N/(2π))·πr² <= A <= A_disc, since the
    polygon lies inside the disc. Discs whose extent c_k ± r√(1 − n_k²) along each axis
    is inside the box are not clipped, nor are discs with an extent outside it (area 0).
    For N divisible by 4 a cut through the centre along any line (two perpendicular
    lines) leaves exactly 1/2 (1/4) of the polygon's area.

    Args:
        discs: a network, or its ``(centre, normal, radius)``: centres shape=(n, 3),
            nonzero normals shape=(n, 3), radii > 0 shape=(n,).
        box: ``(xmin, ymin, zmin, xmax, ymax, zmax)``, shape=(6,).
        sides: polygon vertices, >= 3.

    Returns:
        Areas inside the box, shape=(n,).
    """
    b = as_box(box, "clipped_area: box")
    if isinstance(sides, bool) or not isinstance(sides, Integral) or sides < 3:
        raise DfnError(f"clipped_area: sides must be an integer >= 3, got {sides!r}")
    if isinstance(discs, DiscNetwork):
        centre, raw, radius = discs.centre, discs.normal, discs.radius
    else:
        centre = np.asarray(discs[0], dtype=float).reshape(-1, 3)
        raw = np.asarray(discs[1], dtype=float)
        radius = np.asarray(discs[2], dtype=float).reshape(-1)
    try:  # unit normals, whatever was given (the same rounding for either input)
        normal = canonical_normals(raw)
    except ValueError as exc:
        raise DfnError(f"clipped_area: {exc}") from None
    if not isinstance(discs, DiscNetwork):
        if len(centre) != len(radius) or len(normal) != len(radius):
            raise DfnError(
                f"clipped_area: {len(centre)} centres, {len(normal)} normals and "
                f"{len(radius)} radii"
            )
        if not (np.all(np.isfinite(centre)) and np.all(np.isfinite(radius))):
            raise DfnError("clipped_area: centres and radii must be finite")
        if np.any(radius <= 0.0):
            raise DfnError("clipped_area: radii must be > 0")
    extent = radius[:, None] * np.sqrt(np.clip(1.0 - normal**2, 0.0, 1.0))
    lo, hi = centre - extent, centre + extent
    inside = np.all((lo >= b[:3]) & (hi <= b[3:]), axis=1)
    outside = np.any((hi < b[:3]) | (lo > b[3:]), axis=1)
    area = np.zeros(len(radius))
    area[inside] = 0.5 * sides * math.sin(2.0 * math.pi / sides) * radius[inside] ** 2
    cut = ~inside & ~outside
    if np.any(cut):
        area[cut] = _clipped_polygon_area(
            centre[cut], normal[cut], radius[cut], box=b, sides=int(sides)
        )
    return area


def network_p32(network: DiscNetwork, box: ArrayLike) -> float:
    """P32: the network's fracture area inside the box per unit box volume.

    Args:
        network: the discs.
        box: ``(xmin, ymin, zmin, xmax, ymax, zmax)``, shape=(6,).
    """
    return float(np.sum(clipped_area(network, box))) / box_volume(box)


def set_p32(network: DiscNetwork, box: ArrayLike) -> np.ndarray:
    """P32 of each set: its area inside the box per unit box volume.

    Args:
        network: the discs.
        box: ``(xmin, ymin, zmin, xmax, ymax, zmax)``, shape=(6,).

    Returns:
        P32 by set in the order of ``network.set_names``, shape=(len(set_names),).
    """
    area = clipped_area(network, box)
    per_set = np.bincount(network.set_index, weights=area, minlength=len(network.set_names))
    return per_set / box_volume(box)


# -------------------------------------------------------------------------- networks


def _draw_batch(
    rng: np.random.Generator, dset: DiscSet, region: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """BATCH discs: centres, then canonical poles, then radii.

    Returns:
        centres shape=(BATCH, 3), poles shape=(BATCH, 3), radii shape=(BATCH,).
    """
    centre = region[:3] + rng.random((BATCH, 3)) * (region[3:] - region[:3])
    pole = canonical_normals(fisher_poles(rng, BATCH, mean=dset.mean_pole, kappa=dset.kappa))
    radius = power_law_radii(
        rng, BATCH, rmin=dset.radius_min, rmax=dset.radius_max, alpha=dset.alpha
    )
    return centre, pole, radius


def _draw_set(
    rng: np.random.Generator, dset: DiscSet, box: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The discs of one set: centres shape=(k, 3), poles shape=(k, 3), radii shape=(k,)."""
    region = box if dset.region is None else np.asarray(dset.region)
    batches: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    if dset.count is not None:
        batches = [_draw_batch(rng, dset, region) for _ in range(-(-int(dset.count) // BATCH))]
        keep = int(dset.count)
    else:
        assert dset.p32 is not None
        volume = float(np.prod(box[3:] - box[:3]))
        target = dset.p32 * volume
        reach = dset.radius_max
        if target > 0.0 and (
            np.any(region[:3] - reach > box[3:]) or np.any(region[3:] + reach < box[:3])
        ):
            raise DfnError(
                f"disc set {dset.name!r}: p32 = {dset.p32} cannot be reached: no disc centred "
                f"in the region {region.tolist()} reaches the box {box.tolist()}"
            )
        total = 0.0
        keep = 0
        while target > 0.0:
            if len(batches) * BATCH >= MAX_P32_FRACTURES:
                raise DfnError(
                    f"disc set {dset.name!r}: p32 = {dset.p32} (area {target:.6g} in the box) "
                    f"not reached with {MAX_P32_FRACTURES} fractures (P32 so far "
                    f"{total / volume:.6g}); does the region overlap the box?"
                )
            batch = _draw_batch(rng, dset, region)
            batches.append(batch)
            running = total + np.cumsum(clipped_area(batch, box))
            reached = np.nonzero(running >= target)[0]
            if len(reached):
                keep = (len(batches) - 1) * BATCH + int(reached[0]) + 1
                break
            total = float(running[-1])
    if not batches:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    centre, pole, radius = (np.concatenate(parts)[:keep] for parts in zip(*batches, strict=True))
    return centre, pole, radius


def sample_network(sets: Sequence[DiscSet], *, box: ArrayLike, seed: int) -> DiscNetwork:
    """Draw a disc network, set after set.

    Set ``i`` draws from its own stream ``np.random.default_rng([seed, i])`` (as
    :func:`geofrac.dfn.sampling.generate_network`), so adding a set after the others
    leaves their fractures unchanged. A set draws discs in batches of :data:`BATCH`; in
    each batch the centres of all its discs (uniform in the set's region), then their
    poles (:func:`fisher_poles`), then their radii (:func:`power_law_radii`). Disc ``k``
    of a set is the same whatever its count or P32, so a smaller count (or P32) gives a
    prefix.

    - ``count``: exactly ``count`` discs.
    - ``p32``: the shortest prefix whose area inside ``box`` (:func:`clipped_area`)
      reaches ``p32 × volume(box)``: the target is met, and without the last disc it
      would not be, so the set's achieved P32 lies in [p32, p32 + a_last/V) with a_last
      the last disc's clipped area (< π rmax²). ``p32 = 0`` gives no discs.

    Args:
        sets: the disc sets, distinct names; their order fixes the streams.
        box: the domain ``(xmin, ymin, zmin, xmax, ymax, zmax)``, shape=(6,): the
            default region of the centres and the box of the P32 targets.
        seed: non-negative integer seed; the same seed gives the same network bit for bit.

    Returns:
        The network, discs ordered by set, normals sign-normalised
        (:func:`~geofrac.dfn3d.network.canonical_normals`), ``set_names`` in the order
        of ``sets``.

    Raises:
        DfnError: a bad seed, set list or box; a P32 target that no disc can reach
            (region farther than rmax from the box) or not reached with
            :data:`MAX_P32_FRACTURES` discs.
    """
    if isinstance(seed, bool) or not isinstance(seed, Integral) or seed < 0:
        raise DfnError(f"sample_network: seed must be a non-negative integer, got {seed!r}")
    b = as_box(box, "sample_network: box")
    for i, dset in enumerate(sets):
        if not isinstance(dset, DiscSet):
            raise DfnError(f"sample_network: sets[{i}] is not a DiscSet: {dset!r}")
    names = [dset.name for dset in sets]
    dupes = sorted({name for name in names if names.count(name) > 1})
    if dupes:
        raise DfnError(f"sample_network: set names must be distinct, repeated: {dupes}")
    centres: list[np.ndarray] = [np.zeros((0, 3))]
    poles: list[np.ndarray] = [np.zeros((0, 3))]
    radii: list[np.ndarray] = [np.zeros(0)]
    index: list[np.ndarray] = [np.zeros(0, dtype=np.intp)]
    for i, dset in enumerate(sets):
        rng = np.random.default_rng([int(seed), i])
        c, p, r = _draw_set(rng, dset, b)
        centres.append(c)
        poles.append(p)
        radii.append(r)
        index.append(np.full(len(r), i, dtype=np.intp))
    return DiscNetwork(
        centre=np.concatenate(centres),
        normal=np.concatenate(poles),  # canonical already (_draw_batch)
        radius=np.concatenate(radii),
        set_index=np.concatenate(index),
        set_names=tuple(names),
    )
