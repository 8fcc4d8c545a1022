"""The validation cases: what each capability is checked against, and how well.

Pure Python and numpy: a case names a scene under ``jobs/validation/`` (or a bench), the
quantity geofrac's run gives, the reference value and its source, and the tolerance within which
the case counts as reproduced. Reference values are closed forms written out here (not
taken from geofrac's own exact-solution code), numbers from the literature, or numbers of
Edo (2016). A case known to differ says why (``known``); a case that differs without a
reason is a regression.

Measures read the run's summary (``summary.json`` as a dict) and its output directory;
bench cases read the bench's JSON report.
"""

from __future__ import annotations

import csv
import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from geofrac.analytic_sliding import incline_acceleration, ramped_motion

__all__ = [
    "CASES",
    "CHAPTERS",
    "CONSISTENCY",
    "REPRODUCTION",
    "SECTIONS",
    "VALIDATION",
    "Case",
    "Reference",
    "declared_units",
    "select",
]

#: Chapters in page order.
CHAPTERS = (
    "Elements",
    "EFMM",
    "Fracture networks",
    "Cracking",
    "In-situ stress and stages",
    "Plasticity and factor of safety",
    "MPM dynamics",
    "MPM under gravity and friction",
    "Blocks",
    "3D rock masses",
)

#: What a case checks geofrac against: the physics (closed forms, experiments, the
#: literature), the scene's own inputs, or the numbers of Edo (2016).
VALIDATION = "Validation"
CONSISTENCY = "Consistency"
REPRODUCTION = "Reproduction of Edo (2016)"
#: The page's sections, in page order.
SECTIONS = (VALIDATION, CONSISTENCY, REPRODUCTION)


@dataclass(frozen=True)
class Reference:
    """What geofrac's value is compared with.

    Args:
        value: the reference value, or the bound (``kind = "at_most"``).
        source: where it comes from: a closed form with its citation, the literature, or
            Edo (2016) with the equation, figure or table.
        kind: ``"value"`` (|relative difference| <= ``rtol``), ``"range"`` (``value`` is
            the low end, ``high`` the high end), ``"at_most"`` (geofrac's value <=
            ``value``) or ``"pending"`` (the source is named but its number is not yet
            transcribed: geofrac's value is shown, nothing is compared).
        rtol: relative tolerance of a ``"value"`` reference.
        high: high end of a ``"range"``.
        independent: the source is not Edo (2016) (a closed form or the literature).
    """

    value: float
    source: str
    kind: str = "value"
    rtol: float = 0.01
    high: float = math.nan
    independent: bool = True

    def text(self) -> str:
        """The reference as the page shows it."""
        if self.kind == "pending":
            return "not yet transcribed"
        if self.kind == "range":
            return f"{self.value:.4g} to {self.high:.4g}"
        if self.kind == "at_most":
            return f"≤ {self.value:.2g}"
        return f"{self.value:.6g}"

    def difference(self, measured: float) -> float:
        """Relative difference of ``measured`` (0 inside a range; nan for a bound)."""
        if self.kind in ("at_most", "pending"):
            return math.nan
        if self.kind == "range":
            if self.value <= measured <= self.high:
                return 0.0
            edge = self.value if measured < self.value else self.high
            return (measured - edge) / abs(edge)
        return (measured - self.value) / abs(self.value)

    def holds(self, measured: float) -> bool:
        """Whether ``measured`` reproduces the reference."""
        if not math.isfinite(measured) or self.kind == "pending":
            return False
        if self.kind == "at_most":
            return measured <= self.value
        if self.kind == "range":
            return self.value <= measured <= self.high
        return abs(self.difference(measured)) <= self.rtol


@dataclass(frozen=True)
class Case:
    """One validation case.

    Args:
        name: short identifier (``--cases``).
        chapter: one of :data:`CHAPTERS`.
        title: what is checked, in a few words.
        quantity: the compared quantity, without its unit (``unit``).
        reference: the reference and its source.
        measure: geofrac's value from (summary or bench report, output directory).
        scene: the scene under ``jobs/validation/`` (relative to the repository; there, a
            link to the scene under ``jobs/`` that the docs and tests use), or None for a
            bench.
        bench: ``geofrac bench`` arguments (the first is the bench's name), or None.
        overrides: ``--set`` overrides of the scene.
        quick: part of ``geofrac validate --quick``.
        ci: part of the reduced set the test suite reruns against the page.
        known: why the case differs, when it is known to (None: it should reproduce).
        plot: draws the case's figure from (summary or report, output directory, path).
        estimate_s: rough wall time on 2 cores, seconds: only for the suite's time left.
        section: one of :data:`SECTIONS`: what the reference is (declared, not inferred).
        unit: the quantity's unit in the scene's ``[units]``: a template such as
            ``"1/{length}"`` or ``"{force}"`` (:meth:`quantity_in`), a fixed label, or None
            for a pure number.
    """

    name: str
    chapter: str
    title: str
    quantity: str
    reference: Reference
    measure: Callable[[dict[str, Any], Path], float]
    scene: str | None = None
    bench: tuple[str, ...] | None = None
    overrides: tuple[str, ...] = ()
    quick: bool = True
    ci: bool = False
    known: str | None = None
    plot: Callable[[dict[str, Any], Path, Path], None] | None = field(default=None, repr=False)
    estimate_s: float = 5.0
    section: str = ""
    unit: str | None = None

    def __post_init__(self) -> None:
        """Refuse a case without a section of :data:`SECTIONS`."""
        if self.section not in SECTIONS:
            raise ValueError(
                f"validation case {self.name}: section {self.section!r} is not one of "
                f"{', '.join(SECTIONS)}"
            )

    def quantity_in(self, units: dict[str, str]) -> str:
        """The quantity with its unit in ``units`` (the scene's declared ``[units]``).

        A unit the scene does not declare is not printed (geofrac converts nothing, so
        it would be a guess).
        """
        if self.unit is None:
            return self.quantity
        try:
            label = self.unit.format(**units)
        except KeyError:
            return self.quantity
        return f"{self.quantity} ({label})"

    def command(self) -> str:
        """The command a user runs to reproduce the case."""
        sets = "".join(f" --set {o}" for o in self.overrides)
        if self.bench is not None:
            return "geofrac bench " + " ".join(self.bench) + sets
        return f"geofrac run {self.scene}{sets}"


def declared_units(case: Case, root: Path) -> dict[str, str]:
    """The units the case's scene declares in ``[units]`` (``--set units.*`` applied).

    Only what the file states: a scene that declares no unit of a kind has none on the
    page (nothing is assumed). A bench declares none.

    Args:
        case: the case.
        root: the repository (scene paths are relative to it).
    """
    if case.scene is None:
        return {}
    with open(root / case.scene, "rb") as f:
        units = {k: str(v) for k, v in tomllib.load(f).get("units", {}).items()}
    for override in case.overrides:
        key, _, value = override.partition("=")
        if key.startswith("units."):
            units[key.removeprefix("units.")] = value.strip().strip("\"'")
    return units


#: The experimental peak load of jobs/notched_beam.toml's beam (kN, its 50 mm thickness):
#: Gálvez, Elices, Guinea and Planas (1998) published its load-displacement and load-CMOD
#: curves. The band is not transcribed yet (none of the sources searched for it quoted
#: one), so the row names the source and shows geofrac's value without comparing; once
#: read off the paper's figures it becomes ``Reference(low, source, kind="range",
#: high=high)`` with the loading case (which actuator held) it was read for.
GALVEZ_PEAK = Reference(
    math.nan,
    "experiment: Gálvez, Elices, Guinea and Planas (1998), Int. J. Fract. 94, 267-284, "
    "load-displacement curves; the band is not transcribed yet",
    kind="pending",
)

#: depth (mm) and element size h in the band around the axis (mm) of
#: meshes/sym_notched_beam.geo (its defaults).
SYM_BEAM_DEPTH, SYM_BEAM_H = 100.0, 1.45


def _sym_beam(algorithm: str, short: str) -> Case:
    """The symmetric notched beam on one gmsh mesher: the crack should stay on the axis."""
    return Case(
        f"sym_beam_{short}",
        "Cracking",
        f"symmetric notched beam, {algorithm} mesh: the crack follows the axis",
        "largest distance of a cracked edge from the axis until the crack reaches the pad",
        Reference(
            SYM_BEAM_H,
            "symmetry: the exact path is the axis x = 0; within one element size h = 1.45 mm",
            kind="at_most",
        ),
        _axis_distance,
        scene="jobs/validation/sym_notched_beam.toml",
        overrides=(f"geometry.algorithm={algorithm}",),
        estimate_s=15.0,
        section=VALIDATION,
        unit="{length}",
    )


#: diameter, thickness (mm), half the strips' angle (rad), f_t (N/mm²) and element size h
#: (mm) of jobs/brazilian_disc.toml and meshes/brazilian_disc.geo (their defaults).
DISC_D, DISC_T, DISC_ALPHA, DISC_FT, DISC_H = 50.0, 25.0, math.radians(5.0), 3.0, 1.0

#: the splitting load of the ISRM formula f_t = 2P / (π D t): P = π D t f_t / 2 (N).
DISC_LOAD = math.pi * DISC_D * DISC_T * DISC_FT / 2.0


def _disc_split(algorithm: str, short: str) -> Case:
    """The Brazilian disc on one gmsh mesher: the split should follow the loaded diameter."""
    return Case(
        f"disc_split_{short}",
        "Cracking",
        f"Brazilian disc, {algorithm} mesh: the split follows the loaded diameter",
        "largest distance of the split from the diameter",
        Reference(
            1.5 * DISC_H,
            "symmetry: the exact split is the loaded diameter x = 0; within 1.5 element "
            "sizes, h = 1 mm",
            kind="at_most",
        ),
        _disc_split_distance,
        scene="jobs/validation/brazilian_disc.toml",
        overrides=(f"geometry.algorithm={algorithm}",),
        quick=False,
        estimate_s=30.0,
        section=VALIDATION,
        unit="{length}",
    )


def _disc_load(algorithm: str, short: str) -> Case:
    """The Brazilian disc on one gmsh mesher: the splitting load against ISRM's formula."""
    return Case(
        f"disc_load_{short}",
        "Cracking",
        f"Brazilian disc, {algorithm} mesh: the splitting load",
        "splitting load P",
        Reference(
            DISC_LOAD,
            "closed form: ISRM (1978) σ_t = 2P/(πDt) with σ_t = f_t; Hondros' (1959) strip "
            "correction for 2α = 10° would put P 0.9 % higher",
            rtol=0.05,
        ),
        _disc_splitting_load,
        scene="jobs/validation/brazilian_disc.toml",
        overrides=(f"geometry.algorithm={algorithm}",),
        quick=False,
        estimate_s=30.0,
        section=VALIDATION,
        unit="{force}",
    )


# -- reading results ---------------------------------------------------------------------


def _results(summary: dict[str, Any]) -> dict[str, Any]:
    return summary["results"]


def _last_frame(out: Path) -> dict[str, np.ndarray]:
    """Datasets of the last frame of ``particles.h5``."""
    from geofrac.io.points import last_frame

    return last_frame(out / "particles.h5")


def _events(out: Path) -> list[dict[str, str]]:
    with open(out / "events.csv", newline="") as f:
        return list(csv.DictReader(f))


# -- closed forms ------------------------------------------------------------------------


def timoshenko_tip(P: float, L: float, D: float, *, E: float, nu: float) -> float:
    """Tip deflection of a cantilever under a parabolic end shear, plane stress.

    Timoshenko and Goodier, Theory of Elasticity (1970), §21; Edo (2016), eq. 2.24-2.25:
    v = P L³ / (3 E I) + (4 + 5ν) P D² L / (24 E I), I = D³ / 12 (unit thickness).
    """
    inertia = D**3 / 12.0
    return P * L**3 / (3 * E * inertia) + (4 + 5 * nu) * P * D**2 * L / (24 * E * inertia)


def lame_inner_displacement(p: float, a: float, b: float, *, E: float, nu: float) -> float:
    """Radial displacement at the bore of a thick cylinder under internal pressure p.

    Plane strain (Timoshenko and Goodier 1970, §28):
    u(a) = (1 + ν) p a² / (E (b² − a²)) ((1 − 2ν) a + b² / a).
    """
    return (1 + nu) * p * a**2 / (E * (b**2 - a**2)) * ((1 - 2 * nu) * a + b**2 / a)


def jaeger_slip_stress(beta_deg: float, c: float, mu: float) -> float:
    """Axial stress at which a joint of cohesion c and friction μ slips (inf: never).

    Jaeger, Cook and Zimmerman, Fundamentals of Rock Mechanics, 4th ed. (2007), §4.7:
    σ1 = 2c / ((1 − μ cot β) sin 2β), β the angle between the joint's normal and the load.
    """
    b = math.radians(beta_deg)
    if math.tan(b) <= mu:
        return math.inf
    return 2.0 * c / ((1.0 - mu / math.tan(b)) * math.sin(2.0 * b))


def _top_stress(step: int) -> Callable[[dict[str, Any], Path], float]:
    """The axial stress on the 1 x 1 top of a 3D prism (compression positive) at a step."""

    def measure(summary: dict[str, Any], out: Path) -> float:
        steps = summary["results"]["plasticity"]["steps"]
        return -float(steps[step]["reactions"]["top"][2])

    return measure


def _joints_top_stress(summary: dict[str, Any], out: Path) -> float:
    """The top's axial stress at the last step of a ``joints`` effect run (1 x 1 top)."""
    steps = summary["results"]["joints"]["steps"]
    return -float(steps[-1]["reactions"]["top"][2])


def _joint_set_modulus(summary: dict[str, Any], out: Path) -> float:
    """E_eff of jobs/joint_set_3d.toml: the top's stress over the strain 0.001 / 1."""
    return _top_stress(-1)(summary, out) / 0.001


#: Sneddon's penny crack of jobs/penny_crack.toml: σ = 1, E = 1000, ν = 0.25, a = 1.
PENNY_W0 = 8.0 * (1.0 - 0.25**2) * 1.0 * 1.0 / (math.pi * 1000.0)


def _penny_opening(out: Path) -> tuple[np.ndarray, np.ndarray]:
    """(r, opening) of the crack's node pairs (``joints.csv``), shape=(m,) each."""
    table = np.loadtxt(out / "joints.csv", delimiter=",", skiprows=1, ndmin=2)
    return np.hypot(table[:, 0], table[:, 1]), table[:, 6]


def _penny_centre(summary: dict[str, Any], out: Path) -> float:
    """The opening at the centre: w² is linear in r² (Sneddon), fitted over r <= 0.5a."""
    r, w = _penny_opening(out)
    inner = r <= 0.5
    slope, w0_squared = np.polyfit(r[inner] ** 2, w[inner] ** 2, 1)
    del slope
    return float(np.sqrt(w0_squared))


def _penny_profile(summary: dict[str, Any], out: Path) -> float:
    """The largest |w − w_exact| / w(0) over the node pairs with r <= 0.95a."""
    r, w = _penny_opening(out)
    inner = r <= 0.95
    exact = PENNY_W0 * np.sqrt(np.clip(1.0 - r[inner] ** 2, 0.0, None))
    return float(np.max(np.abs(w[inner] - exact)) / PENNY_W0)


#: The coarse jointed cube: jobs/dfn3d_triaxial.toml's network (seed 3) on a mesh of
#: sizes 5 and 2 with two load steps (the statistics are the drawn network's).
DFN3D_COARSE = (
    "dfn3d.mesh_size=5.0",
    "dfn3d.fracture_mesh_size=2.0",
    "dfn3d.transition=2.0",
    "plasticity.load_steps=2",
)
#: jobs/dfn3d_triaxial.toml's sets: (name, target P32, κ, rmax); the box is 10 m.
DFN3D_SETS = (("J1", 0.15, 40.0, 5.0), ("J2", 0.15, 25.0, 5.0), ("J3", 0.15, 25.0, 5.0))


def _dfn3d_set(name: str, key: str) -> Callable[[dict[str, Any], Path], float]:
    """A set's statistic from the geometry report's ``sets`` (network_summary)."""

    def measure(summary: dict[str, Any], out: Path) -> float:
        return float(summary["results"]["geometry"]["sets"][name][key])

    return measure


def _dfn3d_kappa_quantile(name: str, kappa: float) -> Callable[[dict[str, Any], Path], float]:
    """F(2κ(N − R)) of the χ²(2(N − 1)) law (Fisher 1953): uniform on [0, 1] for a set of κ.

    N − R = (N − 1)/κ̂ from Fisher's estimator κ̂ = (N − 1)/(N − R).
    """
    from geofrac.dfn.stats import chi2_cdf

    def measure(summary: dict[str, Any], out: Path) -> float:
        got = summary["results"]["geometry"]["sets"][name]
        n = int(got["count"])
        return chi2_cdf(2.0 * kappa * (n - 1) / float(got["kappa_hat"]), 2.0 * (n - 1))

    return measure


def _dfn3d_cases() -> tuple[Case, ...]:
    """Per set of the jointed cube: P32, Fisher κ and the radius law against their bands."""
    out = []
    for name, p32, kappa, rmax in DFN3D_SETS:
        common = {
            "scene": "jobs/validation/dfn3d_triaxial.toml",
            "overrides": DFN3D_COARSE,
            "section": CONSISTENCY,
            "estimate_s": 8.0,
        }
        out += [
            Case(
                f"dfn3d_p32_{name}",
                "3D rock masses",
                f"jointed cube (seed 3), set {name}: P32 drawn until the target is reached",
                "P32",
                Reference(
                    p32,
                    "the set's target; it stops at the first disc that reaches it, so it "
                    "exceeds it by less than one disc's area π rmax² / V",
                    kind="range",
                    high=p32 + math.pi * rmax**2 / 1000.0,
                ),
                _dfn3d_set(name, "p32"),
                unit="1/{length}",
                **common,  # type: ignore[arg-type]
            ),
            Case(
                f"dfn3d_kappa_{name}",
                "3D rock masses",
                f"jointed cube (seed 3), set {name} (κ = {kappa:g}): Fisher's κ̂ as the "
                "quantile of 2κ(N − R) in χ²(2(N − 1))",
                "quantile",
                Reference(
                    0.005,
                    "the 99 % sampling band of Fisher's (1953) estimator: 2κ(N − R) ~ χ²(2(N − 1))",
                    kind="range",
                    high=0.995,
                ),
                _dfn3d_kappa_quantile(name, kappa),
                **common,  # type: ignore[arg-type]
            ),
            Case(
                f"dfn3d_radius_{name}",
                "3D rock masses",
                f"jointed cube (seed 3), set {name}: radii against the truncated power law "
                "(Kolmogorov-Smirnov)",
                "KS p-value",
                Reference(0.01, "the 1 % level of the KS test", kind="range", high=1.0),
                _dfn3d_set(name, "radius_ks_p"),
                **common,  # type: ignore[arg-type]
            ),
        ]
    return tuple(out)


#: Jaeger's slip stress of the validation joint (β = 60°, c = 1, μ = 0.5).
_JAEGER_60 = Reference(
    jaeger_slip_stress(60.0, 1.0, 0.5),
    "closed form: Jaeger, Cook and Zimmerman (2007), §4.7",
    rtol=0.03,
)


#: The Kirsch scene refined as in tests/fem/test_insitu.py: a block of 40 radii (the
#: finite block's error goes as (a/L)², 0.45 % at most here), h = 0.04a on the wall.
KIRSCH_FINE = (
    "geometry.parameters.L=40.0",
    "geometry.parameters.h_wall=0.04",
    "geometry.parameters.h_far=2.0",
    "output.lines={}",
)


def planar_sliding_fos(
    c: float, phi_deg: float, *, psi_deg: float, alpha_deg: float, height: float, gamma: float
) -> float:
    """Hoek and Bray's factor of safety of a block on one daylighting joint, per unit thickness.

    (c A + W cos ψ tan φ)/(W sin ψ) with the joint (dip ψ) from the face (dip α) at
    ``height`` below the crest up to the crest: A = height/sin ψ, W = γ height² (cot ψ −
    cot α)/2 (Hoek and Bray, Rock Slope Engineering; Wyllie and Mah (2004), §6.3).
    """
    psi, alpha = math.radians(psi_deg), math.radians(alpha_deg)
    area = height / math.sin(psi)
    weight = 0.5 * gamma * height**2 * (1 / math.tan(psi) - 1 / math.tan(alpha))
    resisting = c * area + weight * math.cos(psi) * math.tan(math.radians(phi_deg))
    return resisting / (weight * math.sin(psi))


def kirsch_wall_hoop(p: float, k: float, theta_deg: float) -> float:
    """σθθ on the wall of a circular opening under σyy = −p, σxx = −K p (tension positive).

    Kirsch (1898): σθθ(a, θ) = −p (1 + K) − 2 p (1 − K) cos 2θ, θ from the x axis.
    """
    return -p * (1 + k) - 2 * p * (1 - k) * math.cos(2 * math.radians(theta_deg))


def kirsch_wall_displacement(p: float, k: float, theta_deg: float, *, E: float, nu: float) -> float:
    """Radial displacement of the wall that the excavation causes, plane strain.

    u_r(a, θ) = a/(4G) [(S_x + S_y) + (S_x − S_y)(3 − 4ν) cos 2θ] with a = 1, S_x = −K p,
    S_y = −p (Brady and Brown (2004), §7.1); negative: towards the opening.
    """
    g = E / (2 * (1 + nu))
    sx, sy = -k * p, -p
    c2 = math.cos(2 * math.radians(theta_deg))
    return ((sx + sy) + (sx - sy) * (3 - 4 * nu) * c2) / (4 * g)


#: jobs/opening_mohr_coulomb.toml: the quarter ring a <= r <= b with the outer pressure p0
#: held, the internal pressure lowered from p0 to pi; E, nu, c, phi, psi of its rock.
OPENING = {
    "a": 1.0,
    "b": 10.0,
    "p0": 10.0,
    "pi": 1.0,
    "E": 1.0e4,
    "nu": 0.3,
    "c": 1.0,
    "phi": 30.0,
    "psi": 0.0,
}


def salencon_ring(
    a: float,
    b: float,
    *,
    p0: float,
    pi: float,
    E: float,
    nu: float,
    c: float,
    phi: float,
    psi: float,
) -> tuple[float, float]:
    """(plastic radius ρ, wall displacement u_r(a)) of a circular opening in Mohr-Coulomb rock.

    Salençon (1969); Carranza-Torres and Fairhurst (1999): plane strain, elastic-perfectly
    plastic, hydrostatic p0, internal pressure pi (compression positive), here for the
    ring a <= r <= b with p0 held at b (b = inf: the opening in an infinite medium).
    K_p = (1 + sin φ)/(1 − sin φ), σ_c = 2c cos φ/(1 − sin φ), A = c cot φ.

    - plastic zone (σ_θ = K_p σ_r + σ_c with equilibrium): σ_r(r) = (pi + A)(r/a)^(K_p − 1) − A;
    - elastic zone (Lamé's ring, Timoshenko and Goodier (1970), §28), at yield at ρ:
      σ_θ(ρ) = (2 p0 b² − p_ρ (b² + ρ²))/(b² − ρ²) = K_p p_ρ + σ_c gives the radial
      stress p_ρ = (2 p0 b² − σ_c (b² − ρ²))/((b² + ρ²) + K_p (b² − ρ²)) (b → ∞:
      (2 p0 − σ_c)/(1 + K_p)); ρ is where the two σ_r meet (bisection);
    - u(ρ) = ρ ε_θ(ρ) from Hooke's law of the stress change from p0 (plane strain,
      tension positive): ε_θ = (1 + ν)/E ((1 − ν) Δσ_θ − ν Δσ_r);
    - plastic zone: the flow rule εᵖ_r + K_ψ εᵖ_θ = 0 (K_ψ = (1 + sin ψ)/(1 − sin ψ))
      makes d(u r^K_ψ)/dr = r^K_ψ (εᵉ_r + K_ψ εᵉ_θ), integrated from ρ to a by
      64-point Gauss-Legendre quadrature (the integrand is smooth).

    No plastic zone (ρ = a) when the elastic wall is below yield.
    """
    sin_phi, sin_psi = math.sin(math.radians(phi)), math.sin(math.radians(psi))
    kp, kpsi = (1 + sin_phi) / (1 - sin_phi), (1 + sin_psi) / (1 - sin_psi)
    sc = 2 * c * math.cos(math.radians(phi)) / (1 - sin_phi)
    att = c / math.tan(math.radians(phi))

    def p_elastic(rho: float) -> float:
        if math.isinf(b):
            return (2 * p0 - sc) / (1 + kp)
        return (2 * p0 * b * b - sc * (b * b - rho * rho)) / (
            (b * b + rho * rho) + kp * (b * b - rho * rho)
        )

    def p_plastic(rho: float) -> float:
        return (pi + att) * (rho / a) ** (kp - 1) - att

    def strains(sr: Any, st: Any) -> tuple[Any, Any]:
        """(ε_r, ε_θ) of the stress change from p0 (compression-positive σ_r, σ_θ)."""
        dr, dt = p0 - sr, p0 - st  # tension-positive changes
        g = (1 + nu) / E
        return g * ((1 - nu) * dr - nu * dt), g * ((1 - nu) * dt - nu * dr)

    if p_plastic(a) >= p_elastic(a):  # pi above the critical pressure: elastic
        if math.isinf(b):
            st = 2 * p0 - pi
        else:
            st = (2 * p0 * b * b - pi * (b * b + a * a)) / (b * b - a * a)
        return a, a * strains(pi, st)[1]
    lo, hi = a, (b if math.isfinite(b) else 1e3 * a)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if p_plastic(mid) < p_elastic(mid) else (lo, mid)
    rho = 0.5 * (lo + hi)
    p_rho = p_plastic(rho)
    u_rho = rho * strains(p_rho, kp * p_rho + sc)[1]
    x, w = np.polynomial.legendre.leggauss(64)
    r = a + (rho - a) * (x + 1) / 2
    sr = (pi + att) * (r / a) ** (kp - 1) - att
    er, et = strains(sr, kp * sr + sc)
    integral = float(np.sum(w * r**kpsi * (er + kpsi * et))) * (rho - a) / 2
    return rho, (rho**kpsi * u_rho - integral) / a**kpsi


# -- measures ----------------------------------------------------------------------------


def _opening_plastic_radius(summary: dict[str, Any], out: Path) -> float:
    """ρ from the yielded area of the quarter ring: π/4 (ρ² − a²) (plastic quadrature points)."""
    area = _results(summary)["plasticity"]["yielded_area"]
    return math.sqrt(OPENING["a"] ** 2 + 4.0 * area / math.pi)


def _opening_wall(summary: dict[str, Any], out: Path) -> float:
    """u_x at the wall probe (a, 0): the radial wall displacement."""
    return float(_results(summary)["probes"]["wall"][0])


def _factor_of_safety(summary: dict[str, Any], out: Path) -> float:
    return float(_results(summary)["plasticity"]["factor_of_safety"])


def _plot_ground_reaction(summary: dict[str, Any], out: Path, path: Path) -> None:
    """The run's ground reaction curve (ground_reaction.csv) beside :func:`salencon_ring`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    with open(out / "ground_reaction.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    o = OPENING
    fine = np.linspace(o["p0"], o["pi"], 91)
    exact = [-salencon_ring(o["a"], o["b"], **{**_ring_data(), "pi": float(p)})[1] for p in fine]
    fig, ax = plt.subplots(figsize=(6.0, 4.0), constrained_layout=True)
    ax.plot(exact, fine, "k-", label="closed form: Salençon (1969), the ring of b = 10a")
    ax.plot(
        [-float(r["u_r"]) for r in rows],
        [float(r["p_i"]) for r in rows],
        "o",
        mfc="none",
        label="geofrac (P2, load steps)",
    )
    ax.set_xlabel("wall convergence −u_r (m)")
    title = "opening_mohr_coulomb: ground reaction curve"
    save_figure(fig, [ax], path, title=title, ylabel="internal pressure p_i (MPa)")


def _ring_data() -> dict[str, float]:
    """:data:`OPENING` as :func:`salencon_ring`'s keyword arguments."""
    return {k: v for k, v in OPENING.items() if k not in ("a", "b")}


def _plot_reduction(summary: dict[str, Any], out: Path, path: Path) -> None:
    """Monitor displacement against the trial factor F, stable and failed trials."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    entry = _results(summary)["plasticity"]
    trials = sorted(entry["trials"], key=lambda t: t["factor"])
    fig, ax = plt.subplots(figsize=(6.0, 4.0), constrained_layout=True)
    for stable, mark, label in (
        (True, "o", "stable"),
        (False, "x", "failed (last converged load)"),
    ):
        pts = [(t["factor"], 1e3 * t["monitor"]) for t in trials if t["stable"] == stable]
        if pts:
            ax.plot(*zip(*pts, strict=True), mark, label=label)
    ax.axvline(1.4, color="k", lw=0.8, ls="--", label="Griffiths and Lane (1999): 1.4")
    ax.axvline(entry["factor_of_safety"], color="C2", lw=0.8, label="geofrac's FoS")
    ax.set_xlabel("trial factor F")
    title = "slope_griffiths_lane: strength reduction, crest displacement"
    save_figure(fig, [ax], path, title=title, ylabel="|u| at the crest's edge (mm)")


def _tip_deflection(summary: dict[str, Any], out: Path) -> float:
    return abs(_results(summary)["probes"]["tip"][1])


def _patch_error(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["errors"]["u_relative"]


def _scf(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["stress_concentration"]["hole_edge"]["principal"]


def _probe_stress(probe: str, component: str) -> Callable[[dict[str, Any], Path], float]:
    """A probe's total stress component (``output.probe_fields`` with ``stress``)."""

    def measure(summary: dict[str, Any], out: Path) -> float:
        return float(_results(summary)["probe_fields"][probe]["stress"][component])

    return measure


def _probe_displacement(probe: str, axis: int) -> Callable[[dict[str, Any], Path], float]:
    """A probe's displacement component (relative to the initial state)."""

    def measure(summary: dict[str, Any], out: Path) -> float:
        return float(_results(summary)["probes"][probe][axis])

    return measure


def _bore_displacement(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["probes"]["inner"][0]


def _rate(element: str) -> Callable[[dict[str, Any], Path], float]:
    def measure(report: dict[str, Any], out: Path) -> float:
        return report["rates"][element]["u"]

    return measure


def _qrand_error(report: dict[str, Any], out: Path) -> float:
    """Mean ‖E‖_u over q_rand and seeds on the 8×2 mesh (Table 3.1's first row)."""
    return float(np.mean([r["error_u"] for r in report["records"] if r["ny"] == 2]))


def _qrand_spread(report: dict[str, Any], out: Path) -> float:
    """Population std / mean of ‖E‖_u over q_rand and seeds on the 8×2 mesh."""
    errors = [r["error_u"] for r in report["records"] if r["ny"] == 2]
    return float(np.std(errors) / np.mean(errors))


def _set_orientation(name: str) -> Callable[[dict[str, Any], Path], float]:
    """Mean orientation (degrees) of a fracture set's generated fractures, network.csv."""

    def measure(summary: dict[str, Any], out: Path) -> float:
        from geofrac.dfn.io import load_network

        network = load_network(out / "network.csv")
        mine = network.set_index == network.set_names.index(name)
        # traces are axes, folded to [0, 180); the sets lie well inside it
        return float(np.mean(network.angles_deg[mine]))

    return measure


def _p21(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["geometry"]["p21"]


def _crack_top(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["cracking"]["crack_top_x_mm"]


#: kN per unit of a scene's declared force unit (the experiments' loads are in kN).
_KN = {"N": 1e-3, "kN": 1.0, "MN": 1e3}


def _peak_load_kn(summary: dict[str, Any], out: Path) -> float:
    """The largest reaction of the run's events (the load P for the scene's thickness), kN.

    Converted from the force unit the scene declares (``[units] force``); a scene that
    declares none, or another, gives no value.
    """
    force = summary["scene"]["input"].get("units", {}).get("force")
    if force not in _KN:
        raise ValueError(f"the scene's force unit {force!r} is not one of {', '.join(_KN)}")
    return float(_results(summary)["cracking"]["peak_reaction"]) * _KN[force]


def _axis_distance(summary: dict[str, Any], out: Path) -> float:
    """Largest distance of any cracked edge from the symmetric beam's axis.

    Every edge cracked until the crack enters the load pad's zone
    (:data:`~geofrac.validation.paths.PAD_ZONE` below the top) counts.
    """
    from geofrac.validation.paths import PAD_ZONE, read_events, spread_until

    return spread_until(read_events(out), y_stop=SYM_BEAM_DEPTH - PAD_ZONE)[0]


def _disc(out: Path) -> Any:
    """The disc's split until the main crack nears the rim above and below (or all events)."""
    from geofrac.validation.paths import disc_split, read_events, split_through

    events = read_events(out)
    upto = split_through(events, radius=DISC_D / 2, reach=1.5 * DISC_H)
    return disc_split(events, diameter=DISC_D, thickness=DISC_T, alpha=DISC_ALPHA, upto=upto)


def _disc_split_distance(summary: dict[str, Any], out: Path) -> float:
    """Largest distance of the disc's main crack from the loaded diameter until it splits."""
    return _disc(out).main_from_diameter


def _disc_splitting_load(summary: dict[str, Any], out: Path) -> float:
    """The disc's splitting load: the largest reaction (one strip's force) until it splits."""
    return _disc(out).peak_load


def _first_slip_stress(width: float, thickness: float) -> Callable[[dict[str, Any], Path], float]:
    """σ1 = reaction / (W t) at the first event, which must be the joint's slip."""

    def measure(summary: dict[str, Any], out: Path) -> float:
        rows = _events(out)
        if not rows or rows[0]["mode"] != "slip":
            return math.nan
        return abs(float(rows[0]["reaction"])) / (width * thickness)

    return measure


def _joint_slip_ratio(summary: dict[str, Any], out: Path) -> float:
    """The first slip's release share over the closed form's at its pair's midpoint.

    jobs/joint_slip_opening.toml: p = 10 hydrostatic, a = 1, joints dipping 30°, c = 1,
    φ = 30° (:mod:`geofrac.analytic_joints`); NaN unless the first event is a slip.
    """
    from geofrac.analytic_joints import JointedOpening

    rows = _events(out)
    if not rows or rows[0]["mode"] != "slip":
        return math.nan
    opening = JointedOpening(
        sigma_v=10.0,
        k=1.0,
        radius=1.0,
        dip=30.0,
        cohesion=1.0,
        friction=math.tan(math.radians(30.0)),
    )
    x, y = float(rows[0]["x"]), float(rows[0]["y"])
    alpha = float(opening.slip_fraction(math.hypot(x, y), math.degrees(math.atan2(y, x))))
    return float(rows[0]["load_factor"]) / alpha


def _bar_stress_error(summary: dict[str, Any], out: Path) -> float:
    """RMS stress error over the bar against Edo (2016), eq. 4.73, over ρ₀ |b| L₀."""
    frame = _last_frame(out)
    x, stress = frame["geometry"][:, 0], frame["stress"][:, 0]
    return float(np.sqrt(np.mean((stress - _self_weight(x)) ** 2)) / (1.0 * 20.0 * 50.0))


def _self_weight(x: np.ndarray) -> np.ndarray:
    """σ(x) of the bar of jobs/mpm_bar_w1000.toml at rest, Edo (2016), eq. 4.73-4.74.

    σ(x) = E (sqrt(2 ρ₀ b (Δ − x) / E + 1) − 1), Δ = L₀ + ρ₀ b L₀² / (2E), with the body
    force b = −20 (downwards), ρ₀ = 1, L₀ = 50, E = 1e6 (after Bardenhagen and Kober, 2004).
    """
    rho0, b, length, young = 1.0, -20.0, 50.0, 1e6
    delta = length + rho0 * b * length**2 / (2 * young)
    return young * (np.sqrt(2 * rho0 * b * (delta - x) / young + 1) - 1)


def _plot_bar(summary: dict[str, Any], out: Path, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    frame = _last_frame(out)
    x, stress = frame["geometry"][:, 0], frame["stress"][:, 0]
    order = np.argsort(x)
    fig, ax = plt.subplots(figsize=(6.0, 4.0), constrained_layout=True)
    ax.plot(x[order], _self_weight(x[order]), "k-", label="Edo (2016), eq. 4.73")
    ax.plot(x[order], stress[order], "o", ms=3, mfc="none", label="geofrac (MPM, MUSL)")
    units = summary["scene"]["input"].get("units", {})  # the scene's [units]: none declared
    ax.set_xlabel(f"x ({units['length']})" if units.get("length") else "x")
    save_figure(
        fig,
        [ax],
        path,
        title="mpm_bar_w1000: stress under self-weight at rest",
        ylabel=f"σxx ({units['stress']})" if units.get("stress") else "σxx",
    )


def _plot_rates(report: dict[str, Any], out: Path, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    fig, ax = plt.subplots(figsize=(6.0, 4.2), constrained_layout=True)
    for element in sorted({r["element"] for r in report["records"]}):
        rows = [r for r in report["records"] if r["element"] == element]
        rate = report["rates"][element]["u"]
        ax.loglog(
            [r["nodes"] for r in rows],
            [r["error_u_relative"] for r in rows],
            "o-",
            label=f"{element.upper()}: R = {rate:.2f}",
        )
    ax.set_xlabel("nodes")
    title = "cantilever (Edo (2016), §2.4.1): error against nodes"
    save_figure(fig, [ax], path, title=title, ylabel="relative displacement error (L2)")


def _impact_stress_ratio(summary: dict[str, Any], out: Path) -> float:
    """Mean σ behind the wave over −E v₀ / c (jobs/mpm_impact_bar.toml: −2e4 Pa)."""
    frame = _last_frame(out)
    x0 = frame["geometry"][:, 0] - frame["displacement"][:, 0]
    behind = x0 < 0.7 * 50.0
    return float(np.mean(frame["stress"][behind, 0] / -20000.0))


def _incline_mean_slide(summary: dict[str, Any], out: Path) -> float:
    return float(_last_frame(out)["displacement"].mean(axis=0)[0])


def _column_base_stress(summary: dict[str, Any], out: Path) -> float:
    """σyy at the column's base over ρ g H, extrapolated from the particles' linear fit."""
    frame = _last_frame(out)
    y0 = frame["geometry"][:, 1] - frame["displacement"][:, 1]
    _, intercept = np.polyfit(y0, frame["stress"][:, 4], 1)
    return float(-intercept / (1000.0 * 10.0 * 1.0))


def _column_k0(summary: dict[str, Any], out: Path) -> float:
    frame = _last_frame(out)
    s = frame["stress"]
    return float(np.median(s[:, 0] / s[:, 4]))


#: the half-width B/2 of jobs/footing_prandtl.toml's footing (its reaction acts over it).
FOOTING_HALF_WIDTH = 1.0


def _footing_pressure(summary: dict[str, Any], out: Path) -> float:
    """−R_y / (B/2) of the footing's reaction at the last accepted step (the plateau)."""
    steps = [s for s in _results(summary)["plasticity"]["steps"] if s["accepted"]]
    return -float(steps[-1]["reactions"]["footing"][1]) / FOOTING_HALF_WIDTH


def _plot_footing(summary: dict[str, Any], out: Path, path: Path) -> None:
    """The footing's pressure against its settlement, with (2 + π) c."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from geofrac.bench.report import save_figure

    results = _results(summary)
    steps = [s for s in results["plasticity"]["steps"] if s["accepted"]]
    settlement = -float(results["probes"]["centre"][1])  # the prescribed one, at factor 1
    x = [0.0] + [s["factor"] * settlement for s in steps]
    q = [0.0] + [-s["reactions"]["footing"][1] / FOOTING_HALF_WIDTH for s in steps]
    fig, ax = plt.subplots(figsize=(6.0, 4.0), constrained_layout=True)
    ax.axhline((2.0 + math.pi) * 100.0, color="k", lw=0.8, label="(2 + π) c, Prandtl (1920)")
    ax.plot(x, q, "o-", ms=3, label="geofrac (P2, footing reaction / (B/2))")
    ax.set_xlabel("settlement (m)")
    title = "footing_prandtl: pressure against settlement"
    save_figure(fig, [ax], path, title=title, ylabel="footing pressure (kPa)")


def _front_moved_max(summary: dict[str, Any], out: Path) -> float:
    """The largest displacement of the front over the run (history, m)."""
    front = np.asarray(_results(summary)["history"]["front_x"])
    return float(np.max(np.abs(front - front[0])))


def _numerical_over_gravity(summary: dict[str, Any], out: Path) -> float:
    """The scheme's numerical work over gravity's, at its largest over the run."""
    value = _results(summary)["numerical_over_gravity_work_max"]
    return math.nan if value is None else float(value)


def _ramped_slide(t_end: float) -> Reference:
    """jobs/mpm_incline_block.toml's closed form at ``t_end``: μ 0.3 on 30°, 0.1 s ramp."""
    return Reference(
        ramped_motion(incline_acceleration(30.0, 0.3), t_end, ramp=0.1)[0],
        "closed form: Coulomb friction, a = g (sin θ − μ cos θ), gravity ramped over 0.1 s",
        rtol=0.01,
    )


#: The closed-form friction runs from a natural start: every shape and scheme.
INCLINE_PAIRS = [(sh, sc) for sh in ("mpm", "ugimp", "cpgimp") for sc in ("musl", "usf", "usavg")]


def _incline_cases(shape: str, scheme: str) -> list[Case]:
    """The stress-free block on 30°, gravity ramped over 0.1 s, 3 s: sticks, slides."""
    pair = (f"mpm.shape={shape}", f"mpm.scheme={scheme}", "mpm.t_end=3")
    stick = (*pair, "friction.boundaries.y_min=0.7")
    slip = (*pair, "mpm.grid.upper=[14.0, 1.5]")  # 10.6 m of slide
    tag = f"{shape}/{scheme}"
    energy = Reference(
        0.01,
        "the scheme creates at most 1 % of gravity's work (docs/mpm_energy.md)",
        kind="at_most",
    )
    return [
        Case(
            f"incline_stick_{shape}_{scheme}",
            "MPM under gravity and friction",
            f"block released stress-free on 30°, μ = 0.7, 3 s ({tag}): settles and stays",
            "largest front displacement",
            Reference(
                0.005, "closed form: μ > tan θ, the block sticks (within 5 mm)", kind="at_most"
            ),
            _front_moved_max,
            scene="jobs/validation/mpm_incline_block.toml",
            overrides=stick,
            quick=False,
            estimate_s=30.0,
            section=VALIDATION,
            unit="{length}",
        ),
        Case(
            f"incline_stick_energy_{shape}_{scheme}",
            "MPM under gravity and friction",
            f"the same settling block ({tag}): energy the scheme creates",
            "numerical work / gravity work, largest",
            energy,
            _numerical_over_gravity,
            scene="jobs/validation/mpm_incline_block.toml",
            overrides=stick,
            quick=False,
            section=CONSISTENCY,
        ),
        Case(
            f"incline_slip_{shape}_{scheme}",
            "MPM under gravity and friction",
            f"block released stress-free on 30°, μ = 0.3, 3 s ({tag}): mean slide",
            "mean displacement along the slope",
            _ramped_slide(3.0),
            _incline_mean_slide,
            scene="jobs/validation/mpm_incline_block.toml",
            overrides=slip,
            quick=False,
            estimate_s=40.0,
            section=VALIDATION,
            unit="{length}",
        ),
        Case(
            f"incline_slip_energy_{shape}_{scheme}",
            "MPM under gravity and friction",
            f"the same sliding block ({tag}): energy the scheme creates",
            "numerical work / gravity work, largest",
            energy,
            _numerical_over_gravity,
            scene="jobs/validation/mpm_incline_block.toml",
            overrides=slip,
            quick=False,
            section=CONSISTENCY,
        ),
    ]


def _collapse_cases(cell: str) -> list[Case]:
    """Bui et al. (2008)'s column collapse at a cell of 5 or 2.5 mm (the same run thrice)."""
    from geofrac.validation import collapse

    overrides: tuple[str, ...] = ()
    estimate = 120.0
    if cell == "2_5mm":
        overrides = (
            "mpm.grid.spacing=0.0025",
            "mpm.particles.counts=[160,80]",
            "mpm.particles.spacing=0.00125",
        )
        estimate = 900.0
    source = "Bui et al. (2008), the experiment (digitised by Huo et al. 2025)"
    unconverged = (
        "the run-out grows and the failure line flattens as the cell shrinks (10, 5, 2.5 mm: "
        "0.471, 0.474, 0.515 m; 34.5°, 31.0°, 29.1°): the perfectly plastic material "
        "without dilatancy localises into bands a cell wide and the front is a few mm "
        'thick (docs/mpm.md, "Column collapse")'
    )
    size = cell.replace("_", ".").replace("mm", " mm")
    kw: dict[str, Any] = dict(
        scene="jobs/validation/mpm_column_collapse.toml",
        overrides=overrides,
        quick=False,
        estimate_s=estimate,
    )
    return [
        Case(
            f"collapse_runout_{cell}",
            "MPM under gravity and friction",
            f"aluminium-rod column collapse, cell {size}: run-out (deposit 2 mm thick)",
            "run-out from the wall",
            Reference(collapse.experiment_runout(), source, rtol=0.1),
            collapse.measure_runout,
            known=unconverged,
            plot=collapse.plot,
            **kw,
            section=VALIDATION,
            unit="{length}",
        ),
        Case(
            f"collapse_failure_{cell}",
            "MPM under gravity and friction",
            f"aluminium-rod column collapse, cell {size}: failure line (moved < 1.5 mm)",
            "failure line's angle (deg)",
            Reference(collapse.experiment_failure_angle(), source, rtol=0.1),
            collapse.measure_failure_angle,
            known=unconverged if cell == "2_5mm" else None,
            **kw,
            section=VALIDATION,
        ),
        Case(
            f"collapse_surface_{cell}",
            "MPM under gravity and friction",
            f"aluminium-rod column collapse, cell {size}: final surface against the experiment",
            "RMS height difference",
            Reference(0.005, source + "; bound: 5 % of the column's height", kind="at_most"),
            collapse.measure_surface_rms,
            **kw,
            section=VALIDATION,
            unit="{length}",
        ),
    ]


def _runout(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["runout_m"]


def _block_volume(summary: dict[str, Any], out: Path) -> float:
    return _results(summary)["quality"]["total_volume"]


def _block_count(summary: dict[str, Any], out: Path) -> float:
    return float(_results(summary)["quality"]["count"] - 1)  # the immobile block apart


# -- the cases ---------------------------------------------------------------------------

_P, _L, _D, _E, _NU = 1.0, 10.0, 1.0, 100.0, 0.2  # jobs/quickstart.toml

CASES: tuple[Case, ...] = (
    Case(
        "cantilever_tip",
        "Elements",
        "Timoshenko cantilever, P2, tip deflection",
        "tip deflection",
        Reference(
            timoshenko_tip(_P, _L, _D, E=_E, nu=_NU),
            "closed form: Timoshenko and Goodier (1970), §21; Edo (2016), eq. 2.24-2.25",
            rtol=0.01,
        ),
        _tip_deflection,
        scene="jobs/validation/quickstart.toml",
        ci=True,
        section=VALIDATION,
        unit="{length}",
    ),
    Case(
        "cantilever_rate_rgnt",
        "Elements",
        "Timoshenko cantilever, RGNT: convergence rate of the displacement error",
        "rate R (error ∝ nodes^(−R/2))",
        Reference(2.1, "Edo (2016), Fig. 2.8 (R = 2.1 for RGNT)", rtol=0.05, independent=False),
        _rate("rgnt"),
        bench=("cantilever", "--elements", "cst,rgnt", "--repeat", "1"),
        plot=_plot_rates,
        estimate_s=15.0,
        section=REPRODUCTION,
    ),
    Case(
        "cantilever_rate_cst",
        "Elements",
        "Timoshenko cantilever, CST: convergence rate of the displacement error",
        "rate R",
        Reference(2.0, "Edo (2016), Fig. 2.8; linear elements converge at O(h²)", rtol=0.05),
        _rate("cst"),
        bench=("cantilever", "--elements", "cst,rgnt", "--repeat", "1"),
        section=VALIDATION,
    ),
    Case(
        "patch_test",
        "Elements",
        "patch test: a uniform strain field on an unstructured mesh, CST",
        "relative L2 displacement error",
        Reference(
            1e-10,
            "exact: a linear field is in every element's space (eq. 2.26-2.27)",
            kind="at_most",
        ),
        _patch_error,
        scene="jobs/validation/patch_test.toml",
        ci=True,
        section=VALIDATION,
    ),
    Case(
        "hole_scf",
        "Elements",
        "strip with a hole, d/D = 0.1: stress concentration at the hole's edge, P2",
        "Kt (gross section)",
        Reference(
            3.03, "Howland (1930), Phil. Trans. R. Soc. A 229; Peterson's chart 4.1", rtol=0.01
        ),
        _scf,
        scene="jobs/validation/plate_hole_elastic.toml",
        ci=True,
        section=VALIDATION,
    ),
    Case(
        "kirsch_sidewall",
        "In-situ stress and stages",
        "circular opening under σv = 10, σh = 5 (K = 0.5), excavated in two stages (0.4 + 0.6), "
        "P2: hoop stress on the sidewall",
        "σθθ at (a, 0), compression negative",
        Reference(
            kirsch_wall_hoop(10.0, 0.5, 0.0),
            "closed form: Kirsch (1898); Jaeger, Cook and Zimmerman (2007), §8.4",
            rtol=0.01,
        ),
        _probe_stress("sidewall", "yy"),
        scene="jobs/validation/kirsch_stages.toml",
        overrides=KIRSCH_FINE,
        ci=True,
        section=VALIDATION,
        unit="{stress}",
    ),
    Case(
        "kirsch_crown",
        "In-situ stress and stages",
        "the same opening: radial wall displacement at the crown caused by the excavation",
        "u_y at (0, a)",
        Reference(
            kirsch_wall_displacement(10.0, 0.5, 90.0, E=10000.0, nu=0.25),
            "closed form: Kirsch (1898); Brady and Brown (2004), §7.1",
            rtol=0.01,
        ),
        _probe_displacement("crown", 1),
        scene="jobs/validation/kirsch_stages.toml",
        overrides=KIRSCH_FINE,
        ci=True,
        section=VALIDATION,
        unit="{length}",
    ),
    Case(
        "joint_slip_opening",
        "In-situ stress and stages",
        "joints dipping 30° (c = 1, φ = 30°) around a circular opening in a hydrostatic "
        "in-situ stress, excavated in one stage with the joints in contact: the release "
        "share of the first slip",
        "λ / closed-form α at the slipping pair",
        Reference(
            1.0,
            "closed form: Kirsch's stresses with Coulomb's criterion on the plane of weakness "
            "(Brady and Brown (2004); Jaeger, Cook and Zimmerman (2007), §4.7)",
            rtol=0.03,
        ),
        _joint_slip_ratio,
        scene="jobs/validation/joint_slip_opening.toml",
        overrides=("cracking.max_events=1",),
        estimate_s=20.0,
        section=VALIDATION,
    ),
    Case(
        "footing_prandtl",
        "Plasticity and factor of safety",
        "rigid smooth strip footing on weightless Tresca soil (φ = ψ = 0, c = 100 kPa), "
        "pushed down by a prescribed settlement, P2: the collapse pressure",
        "footing reaction / (B/2) at the plateau",
        Reference(
            (2.0 + math.pi) * 100.0,
            "closed form: (2 + π) c, Prandtl (1920); Hill (1950)",
            rtol=0.03,
        ),
        _footing_pressure,
        scene="jobs/validation/footing_prandtl.toml",
        plot=_plot_footing,
        estimate_s=60.0,
        section=VALIDATION,
        unit="{stress}",
    ),
    Case(
        "lame_cylinder",
        "Elements",
        "thick cylinder under internal pressure, plane strain, P2",
        "radial displacement at the bore",
        Reference(
            lame_inner_displacement(10.0, 1.0, 2.0, E=1000.0, nu=0.3),
            "closed form: Lamé; Timoshenko and Goodier (1970), §28",
            rtol=0.005,
        ),
        _bore_displacement,
        scene="jobs/validation/thick_cylinder.toml",
        ci=True,
        section=VALIDATION,
        unit="{length}",
    ),
    Case(
        "efmm_table31",
        "EFMM",
        "EFMM cantilever on random integration domains (q_rand 0-0.8), 8×2 mesh: mean error",
        "‖E‖_u",
        Reference(5.96e-2, "Edo (2016), Table 3.1", rtol=0.1, independent=False),
        _qrand_error,
        bench=("efmm-qrand", "--meshes", "2"),
        known="EFMM's displacement error is 1.3-2.9 times the thesis's on every mesh, while "
        "CST on the same beam matches the thesis's; the formulation difference is not found "
        "(docs/efmm.md)",
        estimate_s=25.0,
        section=REPRODUCTION,
    ),
    Case(
        "efmm_spread",
        "EFMM",
        "EFMM on random integration domains, 8×2 mesh: spread of the error",
        "std / mean of ‖E‖_u",
        Reference(
            0.1,
            "Edo (2016), §3.4.2: the spread stays an order of magnitude below the mean",
            kind="at_most",
            independent=False,
        ),
        _qrand_spread,
        bench=("efmm-qrand", "--meshes", "2"),
        section=REPRODUCTION,
    ),
    Case(
        "dfn_orientation",
        "Fracture networks",
        "DFN Model 1: mean orientation of fracture set 1",
        "mean orientation (°)",
        # 149 traces of standard deviation 7.8°: the sample mean's 99 % band is ±1.6° (3.5 %)
        Reference(
            47.473,
            "the scene's set 1, whose mean orientation is Edo (2016), Table 2.1's",
            rtol=0.035,
            independent=False,
        ),
        _set_orientation("set1"),
        scene="jobs/validation/dfn_model1.toml",
        estimate_s=10.0,
        section=CONSISTENCY,
    ),
    Case(
        "dfn_p21",
        "Fracture networks",
        "DFN Model 1: fracture intensity P21 after meshing",
        "P21",
        Reference(0.1, "the scene's target P21, Edo (2016), §2.5.1", rtol=0.05, independent=False),
        _p21,
        scene="jobs/validation/dfn_model1.toml",
        section=CONSISTENCY,
        unit="1/{length}",
    ),
    Case(
        "notched_beam",
        "Cracking",
        "notched beam in three-point bending: where the crack reaches the top",
        "crack top x",
        Reference(
            30.0,
            "experiment: Gálvez et al. (1998), Int. J. Fract. 94; Edo (2016), Fig. 2.12",
            kind="range",
            high=40.0,
        ),
        _crack_top,
        scene="jobs/validation/notched_beam.toml",
        estimate_s=12.0,
        known="29.85 mm: 0.15 mm short of the experimental band on the default mesh "
        "(docs/cracking.md)",
        section=VALIDATION,
        unit="{length}",
    ),
    Case(
        "notched_beam_peak",
        "Cracking",
        "notched beam: its peak load against the experiment's",
        "peak load P on the 50 mm thickness",
        GALVEZ_PEAK,
        _peak_load_kn,
        scene="jobs/validation/notched_beam.toml",
        estimate_s=12.0,
        known="the scene has no fracture energy: brittle sequentially linear cracking peaks "
        "at its first event, when the stress at the notch's corner (a stress concentration "
        "that grows as the elements shrink) reaches f_t, so this peak depends on the "
        "element size there and is not the experiment's cohesive peak; docs/cracking.md "
        "reports 2,650 N with material.fracture_energy = 0.069 (Gálvez's 69 N/m)",
        section=VALIDATION,
        unit="kN",
    ),
    _sym_beam("frontal-delaunay", "frontal"),
    _sym_beam("delaunay", "delaunay"),
    _sym_beam("meshadapt", "meshadapt"),
    _disc_split("frontal-delaunay", "frontal"),
    _disc_split("delaunay", "delaunay"),
    _disc_split("meshadapt", "meshadapt"),
    _disc_load("frontal-delaunay", "frontal"),
    _disc_load("delaunay", "delaunay"),
    _disc_load("meshadapt", "meshadapt"),
    Case(
        "jaeger_60",
        "Cracking",
        "joint at β = 60° in uniaxial compression: the stress at which it slips",
        "σ1 at slip",
        _JAEGER_60,
        _first_slip_stress(40.0, 1.0),
        scene="jobs/validation/jaeger_joint.toml",
        overrides=("geometry.parameters.beta=60", "cracking.max_events=1"),
        known="the MLS cells fail the patch test in stress (a band of them in a uniformly "
        "compressed specimen carries 1.08-1.17 times the uniform stress), so the faces' stress, "
        "exact for a field linear on each side of the joint, reads shear tractions up to "
        "10 % high (normal ones up to 26 % at the specimen's sides) and the joint slips "
        "6-17 % early at β = 45° and 60° on every mesh tried (h = 2.5, 1.25; three gmsh "
        "algorithms), whatever the contact penalty; integration-consistent MLS cells "
        "(cracking.mls_gradient = 'consistent', the next row) slip within 1e-11 of the law "
        "for β = 45-60° on those meshes (docs/cracking.md, integration-consistent MLS cells)",
        section=VALIDATION,
        unit="{stress}",
    ),
    Case(
        "jaeger_60_consistent",
        "Cracking",
        "the same joint with integration-consistent MLS cells (cracking.mls_gradient = "
        "'consistent', h = 2.5): the stress at which it slips",
        "σ1 at slip",
        _JAEGER_60,
        _first_slip_stress(40.0, 1.0),
        scene="jobs/validation/jaeger_joint.toml",
        overrides=(
            "geometry.parameters.beta=60",
            "geometry.parameters.h=2.5",
            "cracking.mls_gradient=consistent",
            "cracking.max_events=1",
        ),
        section=VALIDATION,
        unit="{stress}",
    ),
    Case(
        "opening_plastic_radius",
        "Plasticity and factor of safety",
        "circular opening in Mohr-Coulomb rock (c = 1, φ = 30°, ψ = 0), p0 = 10 lowered to "
        "pi = 1 in 5 load steps, P2, h = 0.2a: radius of the plastic zone",
        "ρ/a from the yielded area π/4 (ρ² − a²)",
        Reference(
            salencon_ring(OPENING["a"], OPENING["b"], **_ring_data())[0],
            "closed form: Salençon (1969); Carranza-Torres and Fairhurst (1999), for the "
            "ring a ≤ r ≤ 10a with p0 held outside",
            rtol=0.02,
        ),
        _opening_plastic_radius,
        scene="jobs/validation/opening_mohr_coulomb.toml",
        ci=True,
        plot=_plot_ground_reaction,
        section=VALIDATION,
    ),
    Case(
        "opening_wall_displacement",
        "Plasticity and factor of safety",
        "the same opening: radial wall displacement at pi = 1 (the end of the ground "
        "reaction curve)",
        "u_r(a)",
        Reference(
            salencon_ring(OPENING["a"], OPENING["b"], **_ring_data())[1],
            "closed form: Salençon (1969); Carranza-Torres and Fairhurst (1999), flow "
            "rule εᵖ_r + K_ψ εᵖ_θ = 0",
            rtol=0.02,
        ),
        _opening_wall,
        scene="jobs/validation/opening_mohr_coulomb.toml",
        ci=True,
        section=VALIDATION,
        unit="{length}",
    ),
    Case(
        "slope_fos",
        "Plasticity and factor of safety",
        "2:1 slope, H = 10 m, c/(γH) = 0.05, φ = 20°, ψ = 0 (Griffiths and Lane (1999), "
        "example 1), P2, h = 1 m: factor of safety by strength reduction",
        "factor of safety",
        Reference(
            1.4,
            "literature: Griffiths and Lane (1999), Géotechnique 49(3), example 1 "
            "(Bishop's simplified method: about 1.38)",
            rtol=0.03,
        ),
        _factor_of_safety,
        scene="jobs/validation/slope_griffiths_lane.toml",
        quick=False,
        plot=_plot_reduction,
        estimate_s=200.0,
        section=VALIDATION,
    ),
    Case(
        "planar_sliding_fos",
        "Plasticity and factor of safety",
        "rock slope (60° face, H = 10 m) cut by one joint dipping 30° that daylights 2 m "
        "above the toe, joint c = 10 kPa, φ = 35°, strong rock, P2, h = 1 m: factor of "
        "safety by strength reduction with the joint's c and tan φ reduced",
        "factor of safety",
        Reference(
            planar_sliding_fos(10.0, 35.0, psi_deg=30.0, alpha_deg=60.0, height=8.0, gamma=26.0),
            "closed form: planar sliding, (c A + W cos ψ tan φ)/(W sin ψ), Hoek and Bray, "
            "Rock Slope Engineering; Wyllie and Mah (2004)",
            rtol=0.03,
        ),
        _factor_of_safety,
        scene="jobs/validation/slope_planar_joint.toml",
        quick=False,
        plot=_plot_reduction,
        estimate_s=80.0,
        section=VALIDATION,
    ),
    Case(
        "mpm_bar",
        "MPM dynamics",
        "bar under self-weight, brought to rest (W = 1000): stress along the bar",
        "RMS stress error / (ρ₀ |b| L₀)",
        Reference(
            0.02,
            "closed form: the bar at rest under its weight, Edo (2016), eq. 4.73, after "
            "Bardenhagen and Kober (2004); bound: 2 % of ρ₀ |b| L₀",
            kind="at_most",
        ),
        _bar_stress_error,
        scene="jobs/validation/mpm_bar_w1000.toml",
        ci=True,
        plot=_plot_bar,
        section=VALIDATION,
    ),
    Case(
        "mpm_impact",
        "MPM dynamics",
        "bar striking a fixed base: stress behind the compression wave",
        "σ / (−E v₀ / c)",
        Reference(
            1.0,
            "1D elastic wave theory: σ = −ρ c v₀ (e.g. Graff, Wave Motion in "
            "Elastic Solids, 1975, §2.1); Edo (2016), eq. 4.75",
            rtol=0.03,
        ),
        _impact_stress_ratio,
        scene="jobs/validation/mpm_impact_bar.toml",
        ci=True,
        section=VALIDATION,
    ),
    Case(
        "mpm_incline",
        "MPM under gravity and friction",
        "block sliding down a 30° slope, μ = 0.3: mean slide at t = 0.5 s",
        "mean displacement along the slope",
        _ramped_slide(0.5),
        _incline_mean_slide,
        scene="jobs/validation/mpm_incline_block.toml",
        overrides=("mpm.t_end=0.5",),
        section=VALIDATION,
        unit="{length}",
    ),
    *(case for shape, scheme in INCLINE_PAIRS for case in _incline_cases(shape, scheme)),
    Case(
        "mpm_column_weight",
        "MPM under gravity and friction",
        "elastic column settling under gravity: vertical stress at the base",
        "σyy(base) / (ρ g H)",
        Reference(1.0, "closed form: the column's weight", rtol=0.05),
        _column_base_stress,
        scene="jobs/validation/mpm_settling_column.toml",
        section=VALIDATION,
    ),
    Case(
        "mpm_column_k0",
        "MPM under gravity and friction",
        "elastic column settling under gravity: lateral stress ratio",
        "σxx / σyy",
        Reference(0.3 / 0.7, "closed form: K₀ = ν / (1 − ν) under lateral confinement", rtol=0.01),
        _column_k0,
        scene="jobs/validation/mpm_settling_column.toml",
        section=VALIDATION,
    ),
    Case(
        "landslide_8deg",
        "MPM under gravity and friction",
        "Kita-Uebaru landslide, friction angle 8°: runout",
        "runout",
        Reference(205.9, "Edo (2016), Fig. 4.6", rtol=0.1, independent=False),
        _runout,
        scene="jobs/validation/landslide_kita_uebaru.toml",
        overrides=("plasticity.friction_angle=8",),
        quick=False,
        known="the thesis gives the slope's length and depth, not the shape of the ground "
        "or the slip surface, so the profile is ours; the runout falls smoothly with the "
        "friction angle instead of stopping near 25°: by the method of wedges our layer "
        "slides below φ = 58° (ψ = 0), and its softness shortens it by about 14 m at any φ "
        "(docs/mpm_landslide.md)",
        estimate_s=700.0,
        section=REPRODUCTION,
        unit="{length}",
    ),
    *(case for cell in ("5mm", "2_5mm") for case in _collapse_cases(cell)),
    Case(
        "blocks_cylinder",
        "Blocks",
        "median-dual blocks of a meshed cylinder: total volume",
        "volume",
        Reference(
            math.pi * 0.5**2 * 2.0,
            "closed form: π r² l of the meshed cylinder (polygonal boundary: h²/r sag)",
            rtol=0.02,
        ),
        _block_volume,
        scene="jobs/validation/blocks_cylinder.toml",
        ci=True,
        section=CONSISTENCY,
        unit="{length}³",
    ),
    Case(
        "terrain_blocks",
        "Blocks",
        "the 100k terrain of Edo (2016), §5.4: number of moving blocks",
        "blocks",
        Reference(100_824, "Edo (2016), §5.4", rtol=0.01, independent=False),
        _block_count,
        scene="jobs/validation/terrain_100k.toml",
        estimate_s=25.0,
        section=CONSISTENCY,
    ),
    Case(
        "joint_set_compliance",
        "3D rock masses",
        "a 1 x 1 x 1 prism cut by four horizontal joints 0.25 apart (k_n = 4e4) under a "
        "uniaxial stress normal to them: its modulus",
        "E_eff",
        Reference(
            1.0 / (1.0 / 10000.0 + 1.0 / (40000.0 * 0.25)),
            "closed form: 1/E_eff = 1/E + 1/(k_n s) (Goodman (1976); Priest (1993))",
            rtol=0.01,
        ),
        _joint_set_modulus,
        scene="jobs/validation/joint_set_3d.toml",
        ci=True,
        section=VALIDATION,
        unit="{stress}",
        estimate_s=15.0,
    ),
    Case(
        "jaeger_3d_60",
        "3D rock masses",
        "a prism crossed by one joint at β = 60° (c = 1, μ = 0.5) in uniaxial compression, "
        "P2, h = 0.25: the axial stress while the joint slips",
        "σ1 at slip",
        _JAEGER_60,
        _top_stress(-1),
        scene="jobs/validation/jaeger_joint_3d.toml",
        overrides=("geometry.parameters.beta=60",),
        ci=True,
        section=VALIDATION,
        unit="{stress}",
        estimate_s=15.0,
    ),
    Case(
        "jaeger_3d_60_rgnq",
        "3D rock masses",
        "the same prism and joint with RGNQ (three rotations per vertex) and the joints "
        "effect (elastic rock): the axial stress while the joint slips",
        "σ1 at slip",
        _JAEGER_60,
        _joints_top_stress,
        scene="jobs/validation/jaeger_joint_3d_rgnq.toml",
        overrides=("geometry.parameters.beta=60",),
        ci=True,
        section=VALIDATION,
        unit="{stress}",
        estimate_s=10.0,
    ),
    Case(
        "penny_crack_centre",
        "3D rock masses",
        "Sneddon's penny crack, a quarter with the far boundary at 6a, P2, h = 0.05a on "
        "the crack: its opening at the centre (w² fitted linear in r² over r ≤ 0.5a)",
        "w(0)",
        Reference(
            PENNY_W0,
            "closed form: Sneddon (1946), w(0) = 8 (1 − ν²) σ a / (π E)",
            rtol=0.03,
        ),
        _penny_centre,
        scene="jobs/validation/penny_crack.toml",
        overrides=("geometry.parameters.h=0.05",),
        quick=False,
        section=VALIDATION,
        unit="{length}",
        estimate_s=60.0,
    ),
    Case(
        "penny_crack_profile",
        "3D rock masses",
        "the same crack's opening profile: the largest difference from Sneddon's "
        "w(r) = w(0) sqrt(1 − r²/a²) over r ≤ 0.95a, over w(0)",
        "max |w − w_exact| / w(0)",
        Reference(
            0.03,
            "closed form: Sneddon (1946); 3 % of the largest opening w(0)",
            kind="at_most",
        ),
        _penny_profile,
        scene="jobs/validation/penny_crack.toml",
        overrides=("geometry.parameters.h=0.05",),
        quick=False,
        section=VALIDATION,
        estimate_s=60.0,
    ),
    *_dfn3d_cases(),
)


def select(names: list[str] | None = None, *, quick: bool = False, ci: bool = False) -> list[Case]:
    """The cases to run: by name, or the quick / CI subsets, in chapter order.

    Raises:
        ValueError: an unknown case name.
    """
    if names:
        by_name = {c.name: c for c in CASES}
        unknown = [n for n in names if n not in by_name]
        if unknown:
            raise ValueError(
                f"unknown validation case(s) {', '.join(unknown)}; known: {', '.join(by_name)}"
            )
        chosen = [by_name[n] for n in names]
    else:
        chosen = [c for c in CASES if (c.ci if ci else (c.quick or not quick))]
    return sorted(chosen, key=lambda c: CHAPTERS.index(c.chapter))
