"""Draw the Kita-Uebaru sweep's runout against time beside Edo (2016), Fig. 4.6.

Run from the repository root after the sweep (``jobs/landslide_sweep.sh``, which calls
this script for its ``--table``)::

    python docs/landslide_runout.py OUT [ANGLE ...] [--png PATH]

OUT holds one run per friction angle, ``OUT/landslide_phi<ANGLE>/summary.json``
(ANGLEs default to the thesis's 8 10 12 14 16 25). It prints the table of runouts at
t_end beside the thesis's and draws ``OUT/landslide_runout.png`` (or PATH): the front's
runout against time per angle, the thesis's final runout of each angle as a marker at
t_end in the same colour, and in the title how far the smallest angle's runout is from
the thesis's. Axes carry the units of the scene's ``[units]`` (none if undeclared).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

#: Runout (m) at each friction angle (deg), Edo (2016), Fig. 4.6/4.9 (25°: it does not move).
THESIS = {8: 205.9, 10: 176.7, 12: 110.7, 14: 63.0, 16: 32.5, 25: 0.0}


def _label(text: str, unit: str) -> str:
    return f"{text} ({unit})" if unit else text


def main() -> None:
    """Print the table and draw the picture (see the module text)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("out", type=Path, help="the sweep's results directory")
    p.add_argument("angles", nargs="*", default=["8", "10", "12", "14", "16", "25"])
    p.add_argument("--png", type=Path, help="the picture (default OUT/landslide_runout.png)")
    args = p.parse_args()
    png = args.png or args.out / "landslide_runout.png"
    print(f"{'phi':>5} {'runout_m':>10} {'Edo2016_m':>9}")
    fig, ax = plt.subplots(figsize=(7.5, 4.6), layout="constrained")
    units: dict[str, str] = {}
    gaps = []
    for k, a in enumerate(args.angles):
        ref = THESIS.get(round(float(a)))
        reference = "" if ref is None else f"{ref:g}"
        path = args.out / f"landslide_phi{a}" / "summary.json"
        if not path.exists():  # killed before it finished: nothing to report
            print(f"{a:>5} {'no run':>10} {reference:>9}  no {path}")
            continue
        summary = json.loads(path.read_text())
        if summary["status"] != "ok":
            print(f"{a:>5} {'failed':>10} {reference:>9}  {summary['status']}")
            continue
        units = summary["scene"]["input"].get("units", {})
        r = summary["results"]
        print(f"{a:>5} {r['runout_m']:10.1f} {reference:>9}")
        h = r["history"]
        colour = f"C{k % 10}"
        ax.plot(h["t"], [f - h["front_x"][0] for f in h["front_x"]], color=colour,
                label=f"φ = {a}°")  # fmt: skip
        if ref is not None:
            ax.plot([h["t"][-1]], [ref], "D", color=colour, mec="k", mew=0.5, ms=6)
            if ref > 0:
                gaps.append((float(a), r["runout_m"], ref))
    ax.plot([], [], "D", color="0.7", mec="k", mew=0.5, label="Edo (2016), Fig. 4.6")
    length, time = units.get("length", ""), units.get("time", "")
    ax.set_xlabel(_label("time", time))
    ax.set_ylabel(_label("runout of the front", length))
    title = "Kita-Uebaru landslide: runout against time, geofrac (lines) and Edo (2016)"
    if gaps:
        a, ours, ref = min(gaps)
        unit = f" {length}" if length else ""
        title += (
            f"\nφ = {a:g}°: {ours:.1f}{unit} against the thesis's {ref:g}{unit}, "
            f"{100 * (ours / ref - 1):+.0f} %"
        )
    ax.set_title(title, fontsize=10)
    ax.legend(title="friction angle", loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.grid(alpha=0.3)
    fig.savefig(png, dpi=110)
    print(f"plot: {png}")


if __name__ == "__main__":
    main()
