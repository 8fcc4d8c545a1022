"""The Brazilian disc in closed form: the elastic field under two strip pressures.

A disc of radius R centred at the origin carries a uniform radial pressure p (positive
pushes into the disc) on two arcs of angular width 2α centred on the top (0, R) and the
bottom (0, -R): the loaded diameter is the y axis. Hondros (1959) gave the stresses
along the two diameters (Hondros, G., "The evaluation of Poisson's ratio and the modulus
of materials of a low tensile resistance by the Brazilian (indirect tensile) test with
particular reference to concrete", Australian Journal of Applied Science 10 (1959)
243-268); :func:`brazilian_disc_stress` is the whole field, written here as the closed
sums of Michell's series solution of the disc with a prescribed normal traction
(Timoshenko and Goodier, Theory of Elasticity, 3rd ed. (1970), §43), which reduces to
Hondros' formulas on the diameters and to the point-load solution (ibid. §41) as α → 0
with the resultant fixed (tests/validation/test_brazilian.py checks both).

Derivation (θ from +x, ρ = r/R): the Airy function Φ = A₀ r² + Σₙ (Aₙ rⁿ + Bₙ rⁿ⁺²) cos nθ
with traction-free shear on ρ = 1 and σ_rr(R, θ) = c₀ + Σ cₙ cos nθ gives

    σ_rr = c₀ + Σ cₙ [ (n/2) ρⁿ⁻² − ((n − 2)/2) ρⁿ ] cos nθ
    σ_θθ = c₀ + Σ cₙ [ −(n/2) ρⁿ⁻² + ((n + 2)/2) ρⁿ ] cos nθ
    σ_rθ = Σ cₙ (n/2) (ρⁿ − ρⁿ⁻²) sin nθ

and the two strips give c₀ = −2pα/π and, for n = 2m, cₙ = −(2p/π) (−1)ᵐ sin(2mα) / m (odd
n vanish). With z = −ρ² e^{2iβ}, β = α ± θ, the sums are geometric and logarithmic:
Σ zᵐ = z/(1 − z), Σ zᵐ/m = −log(1 − z). At the centre σ_xx = (2p/π)(sin 2α − α) and
σ_yy = −(2p/π)(sin 2α + α); on the free rim σ_rr = σ_θθ = 0 (the hoop stress vanishes on
an unloaded stretch of the boundary), on a strip σ_rr = σ_θθ = −p; the field is bounded
but discontinuous at the strips' ends.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "brazilian_centre_stress",
    "brazilian_disc_stress",
    "splitting_tensile_strength",
    "strip_resultant",
]


def _sums(rho: np.ndarray, theta: np.ndarray, alpha: float) -> tuple[np.ndarray, ...]:
    """Im/Re parts of the closed sums over β = α + θ and α − θ (see the module docstring).

    Returns:
        (C0, C1, C1', S1, S1') per point without the factor −2p/π, each of the shape of
        ``rho``: C0 = ½ Im(L₊ + L₋), C1 = ½ Im(G₊ + G₋), C1' = ½ Im(G̃₊ + G̃₋),
        S1 = ½ Re(G₋ − G₊), S1' = ½ Re(G̃₋ − G̃₊), with L = −log(1 − z), G = z/(1 − z),
        G̃ = G/ρ² = −e^{2iβ}/(1 − z).
    """
    out = []
    for beta in (alpha + theta, alpha - theta):
        e = np.exp(2j * beta)
        z = -(rho**2) * e
        one = 1.0 - z
        out.append((-np.log(one), z / one, -e / one))
    (Lp, Gp, Hp), (Lm, Gm, Hm) = out
    return (
        0.5 * (Lp + Lm).imag,
        0.5 * (Gp + Gm).imag,
        0.5 * (Hp + Hm).imag,
        0.5 * (Gm - Gp).real,
        0.5 * (Hm - Hp).real,
    )


def brazilian_disc_stress(
    x: np.ndarray, y: np.ndarray, *, p: float, radius: float, alpha: float
) -> np.ndarray:
    """Stress of the disc under two strip pressures at points (x, y) inside it.

    Args:
        x: abscissae, any shape, |(x, y)| <= ``radius``; the centre is the origin.
        y: ordinates, the shape of ``x``; the strips are centred on (0, ±radius).
        p: the strips' radial pressure (> 0 compresses).
        radius: R.
        alpha: half the strips' angular width, radians (0 < α < π/2).

    Returns:
        (σ_xx, σ_yy, σ_xy), shape=(*x.shape, 3). Tension positive. At a strip's end on
        the rim the field is discontinuous: the value there is one of its limits.
    """
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    rho = np.hypot(x, y) / radius
    theta = np.arctan2(y, x)
    k = -2.0 * p / math.pi  # cₙ (n/2) = k (−1)ᵐ sin 2mα, cₙ = k (−1)ᵐ sin(2mα) / m
    C0, C1, C1p, S1, S1p = (k * s for s in _sums(rho, theta, alpha))
    c0 = -2.0 * p * alpha / math.pi
    srr = c0 + C1p - C1 + C0
    stt = c0 - C1p + C1 + C0
    srt = S1 - S1p
    c, s = np.cos(theta), np.sin(theta)
    sxx = srr * c * c + stt * s * s - 2.0 * srt * s * c
    syy = srr * s * s + stt * c * c + 2.0 * srt * s * c
    sxy = (srr - stt) * s * c + srt * (c * c - s * s)
    return np.stack([sxx, syy, sxy], axis=-1)


def brazilian_centre_stress(p: float, alpha: float) -> tuple[float, float]:
    """(σ_xx, σ_yy) at the disc's centre: (2p/π)(sin 2α − α) and −(2p/π)(sin 2α + α).

    Hondros (1959); σ_xy = 0 there. For 2α = 10°: σ_xx = 0.05499 p = 0.6310 P / (D t).
    """
    k = 2.0 * p / math.pi
    return k * (math.sin(2 * alpha) - alpha), -k * (math.sin(2 * alpha) + alpha)


def strip_resultant(p: float, *, radius: float, alpha: float, thickness: float) -> float:
    """Resultant force P = 2 p R t sin α of one strip's radial pressure (the load on the disc).

    Hondros (1959) writes P = 2 p α R t (the pressure times the arc's length), which
    differs by sin α / α (0.9987 for 2α = 10°); this is the exact resultant, which is
    also what a pressure on the meshed polygonal arc gives (the chord times p t).
    """
    return 2.0 * p * radius * thickness * math.sin(alpha)


def splitting_tensile_strength(
    load: float, *, diameter: float, thickness: float, alpha: float = 0.0
) -> float:
    """Tensile strength from the splitting load ``load`` (the resultant P of one strip).

    ``alpha`` 0: the ISRM formula σ_t = 2P / (π D t) (ISRM Suggested Methods, 1978; the
    point-load centre stress). ``alpha`` > 0: the centre's σ_xx of the strip loading
    with P = 2 p R t sin α (:func:`strip_resultant`), σ_t = 2P/(π D t) (sin 2α − α)/sin α
    (Hondros (1959)'s correction for the strip's width; 0.9911 for 2α = 10°).
    """
    isrm = 2.0 * load / (math.pi * diameter * thickness)
    if alpha == 0.0:
        return isrm
    return isrm * (math.sin(2 * alpha) - alpha) / math.sin(alpha)
