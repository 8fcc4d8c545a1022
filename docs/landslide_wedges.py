"""Why the Kita-Uebaru layer moves at every friction angle of the sweep (docs/mpm_landslide.md).

Run from the repository root: ``PYTHONPATH=$PWD .venv/bin/python docs/landslide_wedges.py``
(a second; no simulation). It builds the layer of ``meshes/kita_uebaru.geo`` from the same
parameters (8° ground slope, 237 m long, 15.8 m deep at the kink, lower plane rising at
20°, the lower 20 % of the depth a band of density 1500 under 1900 kg/m³), cuts it into
two wedges by an interface through the kink leaning ω from the vertical, and asks the
method of wedges (:mod:`geofrac.analytic_wedges`; bed μ = 0.1, soil c = 0) at which soil
friction angle the layer would stand. That is the friction the interface mobilises; the
scene's soil has no dilatancy (ψ = 0), and a non-associated soil's shear band carries
Davis's (1968) tan φ* = cos φ cos ψ / (1 − sin φ sin ψ) tan φ (= sin φ for ψ = 0), so the
scene's φ must reach asin(tan φ*) for the layer to stand. It prints the threshold for ω
from −60° to 60° and the soft layer's elastic shortening, and draws
``docs/img/landslide_wedges.png``: the profile with the wedges, the interface force the
upper wedge needs against the one the lower wedge can supply as functions of φ*, and
the MPM runouts, given with ``--runouts`` (``phi:metres`` pairs; the defaults are the
coarse runs of docs/mpm_landslide.md, 8-50°).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from geofrac.analytic_wedges import threshold_angle, wedge_forces
from geofrac.dfn.polygon import polygon_area
from geofrac.plasticity.davis import davis_factor

ROOT = Path(__file__).resolve().parent.parent
__all__ = ["layer", "main", "scene_angle", "shortening", "weights"]

SLOPE, LENGTH, DEPTH, BASE, WEAK = 8.0, 237.0, 15.8, 20.0, 0.2
RHO, RHO_WEAK, G, MU = 1900.0, 1500.0, 9.81, 0.1
E_LAYER, NU_LAYER = 1.34e6, 0.45  # jobs/landslide_kita_uebaru.toml


def layer() -> dict[str, np.ndarray]:
    """The points of the layer as meshes/kita_uebaru.geo builds them, each shape=(2,)."""
    lx = LENGTH * math.cos(math.radians(SLOPE))
    h = lx * math.tan(math.radians(SLOPE))
    tb = -math.tan(math.radians(BASE))
    lower = DEPTH / (h / lx - tb)
    xk = lx - lower
    yk = tb * lower
    yg = h * (1 - xk / lx)
    return {
        "crown": np.array([0.0, h]),
        "toe": np.array([lx, 0.0]),
        "kink": np.array([xk, yk]),
        "band": np.array([xk, yk + WEAK * (yg - yk)]),
        "ground_at_kink": np.array([xk, yg]),
    }


def _clip(poly: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The part of a polygon (shape=(n, 2)) where (x − point)·normal ≤ 0 (Sutherland-Hodgman)."""
    out = []
    d = (poly - point) @ normal
    for i in range(len(poly)):
        j = (i + 1) % len(poly)
        if d[i] <= 0:
            out.append(poly[i])
        if (d[i] < 0 < d[j]) or (d[j] < 0 < d[i]):
            s = d[i] / (d[i] - d[j])
            out.append(poly[i] + s * (poly[j] - poly[i]))
    return np.array(out) if out else np.zeros((0, 2))


def weights(omega: float) -> tuple[float, float]:
    """Weights (N per metre) of the upper and lower wedge for an interface leaning ω (deg)."""
    p = layer()
    whole = np.array([p["crown"], p["kink"], p["toe"]])
    weak = np.array([p["crown"], p["kink"], p["toe"], p["band"]])
    t = np.array([math.sin(math.radians(omega)), math.cos(math.radians(omega))])
    n = np.array([t[1], -t[0]])  # points toward the toe
    out = []
    for side in (1.0, -1.0):
        a = polygon_area(_clip(whole, p["kink"], side * n))
        aw = polygon_area(_clip(weak, p["kink"], side * n))
        out.append(G * (RHO * (a - aw) + RHO_WEAK * aw))
    return out[0], out[1]


def scene_angle(phi_star: float, psi: float = 0.0) -> float:
    """The scene's φ (degrees) whose Davis equivalent is ``phi_star``, for dilatancy ψ.

    The root of atan(β(φ, ψ) tan φ) = φ* on φ in [0, 90) (β of
    :func:`geofrac.plasticity.davis.davis_factor`); inf when no φ < 90° reaches it.
    """
    from scipy.optimize import brentq

    def gap(phi: float) -> float:
        beta = davis_factor(phi, min(psi, phi))
        return math.degrees(math.atan(beta * math.tan(math.radians(phi)))) - phi_star

    if gap(89.999) < 0:
        return math.inf
    return float(brentq(gap, 0.0, 89.999, xtol=1e-9))


def shortening(e: float = E_LAYER) -> float:
    """The upper wedge's elastic shortening along its plane (m), a hand estimate.

    The bed carries μ cos α₁ of the weight and the rest, sin α₁ − μ cos α₁, loads the
    layer axially: the wedge is a triangle whose thickness grows linearly from the
    crown, so the axial stress grows linearly, σ = γ (sin α₁ − μ cos α₁) s / 2 at a
    distance s from the crown, and the plane-strain shortening over the plane's length
    L is γ (sin α₁ − μ cos α₁) L² / (4 E / (1 − ν²)) (γ of the layer above the band).
    """
    p = layer()
    a1 = math.radians(_dip())
    length = float(np.linalg.norm(p["kink"] - p["crown"]))
    drive = math.sin(a1) - MU * math.cos(a1)
    return RHO * G * drive * length**2 / (4 * e / (1 - NU_LAYER**2))


def _dip() -> float:
    p = layer()
    d = p["kink"] - p["crown"]
    return math.degrees(math.atan2(-d[1], d[0]))


def main(argv: list[str] | None = None) -> None:
    """Print the thresholds and draw the picture."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--runouts",
        default="8:63.0,10:54.4,12:48.6,14:44.9,16:42.3,25:34.7,30:32.4,35:30.2,40:28.7,45:27.8,50:27.0",
        help="MPM runouts as phi:metres pairs (the scene's phi, psi = 0), comma separated",
    )
    ap.add_argument("--label", default="MPM runout, coarse (h 1.5 m, 2 m cells), ψ = 0")
    ap.add_argument("--out", default=str(ROOT / "docs" / "img" / "landslide_wedges.png"))
    args = ap.parse_args(argv)
    a1 = _dip()
    w1, w2 = weights(0.0)
    print(
        f"upper plane dips {a1:.2f} deg; bed mu = {MU} "
        f"(phi_b = {math.degrees(math.atan(MU)):.2f} deg)"
    )
    print(f"vertical interface: W_upper = {w1 / 1e6:.2f} MN/m, W_lower = {w2 / 1e6:.2f} MN/m")
    print(
        "| interface from vertical (deg) | W_upper (MN/m) | W_lower (MN/m) | threshold phi (deg) |"
    )
    print("|---|---|---|---|")
    worst = (0.0, -1.0)
    for om in range(-60, 61, 5):
        u, lo = weights(float(om))
        th = threshold_angle(u, lo, alpha_upper=a1, alpha_lower=BASE, mu=MU, omega=float(om))
        worst = max(worst, (th, float(om)))
        print(f"| {om} | {u / 1e6:.2f} | {lo / 1e6:.2f} | {th:.1f} |")
    print(f"largest threshold: {worst[0]:.1f} deg (interface {worst[1]:.0f} deg from vertical)")
    print(f"elastic shortening of the upper wedge: {shortening():.1f} m (E = {E_LAYER:g})")
    print(
        f"the scene's phi for that with psi = 0 (Davis: tan phi* = sin phi): "
        f"{scene_angle(worst[0]):.1f} deg; with psi = phi (associated): {worst[0]:.1f} deg"
    )

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = layer()
    om_c = worst[1]
    fig, (ax0, ax1) = plt.subplots(2, 1, figsize=(10, 9), gridspec_kw={"height_ratios": [1, 1.25]})
    exag = 3.0
    up = np.array([p["crown"], p["kink"], p["ground_at_kink"]])
    lo_ = np.array([p["kink"], p["toe"], p["ground_at_kink"]])
    for poly, colour, name, w in ((up, "tab:orange", "upper", w1), (lo_, "tab:blue", "lower", w2)):
        ax0.fill(
            poly[:, 0],
            exag * poly[:, 1],
            color=colour,
            alpha=0.5,
            label=f"{name} wedge, {w / 1e6:.1f} MN/m",
        )
    scarp_y = p["crown"][1] + 30 * (p["crown"][1] - p["kink"][1]) / p["kink"][0]
    bx = [-30, p["crown"][0], p["kink"][0], p["toe"][0], p["toe"][0] + 60]
    by = [scarp_y, p["crown"][1], p["kink"][1], 0, 0]
    ax0.plot(bx, [exag * v for v in by], "k-", lw=2, label=f"bed (Coulomb, μ = {MU})")
    ax0.plot(
        [p["kink"][0]] * 2,
        [exag * p["kink"][1], exag * p["ground_at_kink"][1]],
        "r--",
        lw=1.5,
        label="vertical interface (soil c = 0, φ)",
    )
    # the critical interface: from the kink to the ground surface, leaning om_c from the vertical
    t = np.array([math.sin(math.radians(om_c)), math.cos(math.radians(om_c))])
    gs = (p["toe"][1] - p["crown"][1]) / (p["toe"][0] - p["crown"][0])  # ground slope
    s_ = (p["crown"][1] + gs * (p["kink"][0] - p["crown"][0]) - p["kink"][1]) / (t[1] - gs * t[0])
    e = p["kink"] + s_ * t
    ax0.plot(
        [p["kink"][0], e[0]],
        [exag * p["kink"][1], exag * e[1]],
        "m:",
        lw=2,
        label=f"critical interface, {om_c:.0f}° from vertical",
    )
    a1r, a2r = math.radians(a1), math.radians(BASE)
    ax0.text(
        60,
        exag * 2,
        f"upper plane dips {a1:.1f}°: driving sin α₁ = {math.sin(a1r):.3f} W, "
        f"the bed resists μ cos α₁ = {MU * math.cos(a1r):.3f} W",
        fontsize=9,
        rotation=-8,
    )
    ax0.text(
        150,
        exag * -22,
        f"lower plane rises {BASE:.0f}°: pushed uphill it resists\n"
        f"(sin α₂ + μ cos α₂) W = {math.sin(a2r) + MU * math.cos(a2r):.3f} W at φ = 0",
        fontsize=9,
    )
    ax0.set_xlim(-35, 300)
    ax0.set_ylim(exag * -30, exag * 75)
    ax0.set_yticks([exag * v for v in (-20, 0, 20, 40, 60)], ["−20", "0", "20", "40", "60"])
    ax0.set_xlabel("x (m)")
    ax0.set_ylabel(f"y (m), vertical exaggeration {exag:.0f}×")
    ax0.set_title("The Kita-Uebaru layer (our profile) as two wedges")
    ax0.legend(loc="upper right", fontsize=8)

    phis = np.linspace(0, 50, 201)
    u_c, l_c = weights(om_c)
    for om, (wu, wl), ls in ((om_c, (u_c, l_c), "-"), (0.0, (w1, w2), "--")):
        f = [
            wedge_forces(wu, wl, alpha_upper=a1, alpha_lower=BASE, mu=MU, phi=float(v), omega=om)
            for v in phis
        ]
        ax1.plot(
            phis,
            [v.required / 1e6 for v in f],
            "tab:orange",
            ls=ls,
            label=f"needed by the upper wedge, P_req ({om:.0f}°)",
        )
        ax1.plot(
            phis,
            [min(v.capacity, 1e12) / 1e6 for v in f],
            "tab:blue",
            ls=ls,
            label=f"supplied by the lower wedge, P_cap ({om:.0f}°)",
        )
    ax1.axvline(worst[0], color="m", ls=":", lw=1.5)

    def star(phi: float) -> float:  # the scene's φ (ψ = 0) as the interface's φ*
        return math.degrees(math.atan(math.sin(math.radians(phi))))

    ax1.axvspan(star(8), star(25), color="grey", alpha=0.15, label="the sweep's angles (φ 8-25°)")
    ax1.text(
        worst[0] + 0.5,
        1.0,
        f"the layer stands\nonly above\nφ* = {worst[0]:.1f}°\n"
        f"(ψ = 0: φ = {scene_angle(worst[0]):.0f}°)",
        color="m",
        fontsize=9,
    )
    ax1.set_ylim(0, 6)
    ax1.set_xlabel("friction angle mobilised on the interface, φ* (deg)")
    top = ax1.secondary_xaxis(
        "top",
        functions=(
            lambda v: np.degrees(np.arcsin(np.clip(np.tan(np.radians(v)), 0, 1))),
            lambda v: np.degrees(np.arctan(np.sin(np.radians(v)))),
        ),
    )
    top.set_xlabel("the scene's φ with ψ = 0 (Davis: tan φ* = sin φ)")
    top.set_xticks([10, 20, 30, 40, 50, 60, 70, 90])
    ax1.set_ylabel("interface normal force (MN per m of width)")
    ax1.set_title(
        "Method of wedges (interface through the kink): the layer moves while P_req > P_cap"
    )
    ax2 = ax1.twinx()
    pts = sorted((float(a), float(b)) for a, b in (s.split(":") for s in args.runouts.split(",")))
    ax2.plot([star(a) for a, _ in pts], [b for _, b in pts], "ko-", ms=4, label=args.label)
    ax2.axhline(shortening(), color="k", ls=":", lw=1)
    ax2.text(
        0.5,
        shortening() + 1,
        f"elastic shortening of the upper wedge ≈ {shortening():.0f} m (E = {E_LAYER / 1e6:g} MPa)",
        fontsize=8,
    )
    ax2.set_ylabel("MPM runout at 50 s (m)")
    ax2.set_ylim(0, 1.2 * max(b for _, b in pts))
    h1, l1 = ax1.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax1.legend(h1 + h2, l1 + l2, loc="lower left", fontsize=8)
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"picture: {args.out}")


if __name__ == "__main__":
    main()
