#!/usr/bin/env bash
# Friction-angle sweep of the Kita-Uebaru landslide (Edo (2016), Fig. 4.6): one run per angle, each
# in $OUT/landslide_phi<angle>/ (results/ by default), then a table of runout at t_end beside the thesis's.
#
#   jobs/landslide_sweep.sh [-n RANKS] [ANGLE ...] [-- extra geofrac run options]
#   jobs/landslide_sweep.sh --table [ANGLE ...]   (no runs: table and plot of the results there)
#
# ANGLEs default to the thesis's 8 10 12 14 16 25. RANKS defaults to $GEOFRAC_NP or 2. Writes
# $OUT/landslide_runout.png (runout against time, cf. Edo (2016), Fig. 4.6).
# Example (a quick coarse sweep): jobs/landslide_sweep.sh 8 25 -- --set mpm.t_end=10
# GEOFRAC sets the geofrac command (default: $VENV/bin/geofrac), e.g. from a source tree:
#   GEOFRAC="$VENV/bin/python -m geofrac" jobs/landslide_sweep.sh ...
# OUT sets the results directory (default: results).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
np=${GEOFRAC_NP:-2}
read -r -a geofrac <<< "${GEOFRAC:-$venv/bin/geofrac}"
out=${OUT:-results}
table_only=0
if [ "${1:-}" = "--table" ]; then table_only=1; shift; fi
if [ "${1:-}" = "-n" ]; then np=$2; shift 2; fi
angles=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do angles+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
[ ${#angles[@]} -eq 0 ] && angles=(8 10 12 14 16 25)
if [ ! -x "${geofrac[0]}" ]; then
    echo "error: ${geofrac[0]} not found; run 'make quickstart' first or set VENV or GEOFRAC" >&2
    exit 2
fi
scene=$root/jobs/landslide_kita_uebaru.toml
if [ $table_only -eq 0 ]; then
checks=()  # validate the overrides once, before any run (check takes --set only)
for arg in "$@"; do [ "$arg" = "-q" ] || [ "$arg" = "--quiet" ] || checks+=("$arg"); done
"${geofrac[@]}" check "$scene" "${checks[@]}" > /dev/null
for a in "${angles[@]}"; do  # a failed angle is reported in the table, the others still run
    echo "== friction angle $a deg ($np ranks)"
    start=$(date +%s)
    "$venv/bin/mpiexec" -n "$np" "${geofrac[@]}" run "$scene" \
        --set plasticity.friction_angle="$a" --out "$out/landslide_phi$a" "$@" || true
    echo "== friction angle $a deg: $(( $(date +%s) - start )) s wall"
done
fi
"$venv/bin/python" - "$out" "${angles[@]}" <<'PY'
import json, os, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
thesis = {8: 205.9, 10: 176.7, 12: 110.7, 14: 63.0, 16: 32.5, 25: 0.0}
print(f"{'phi':>5} {'runout_m':>10} {'Edo2016_m':>9}")
fig, ax = plt.subplots(figsize=(6, 4))
out = sys.argv[1]
for a in sys.argv[2:]:
    ref = thesis.get(round(float(a)))
    path = f"{out}/landslide_phi{a}/summary.json"
    if not os.path.exists(path):  # killed before it finished: nothing to report
        print(f"{a:>5} {'no run':>10} {'' if ref is None else ref:>8}  no {path}")
        continue
    summary = json.load(open(path))
    if summary["status"] != "ok":
        print(f"{a:>5} {'failed':>10} {'' if ref is None else ref:>8}  {summary['status']}")
        continue
    r = summary["results"]
    print(f"{a:>5} {r['runout_m']:10.1f} {'' if ref is None else ref:>8}")
    h = r["history"]
    ax.plot(h["t"], [f - h["front_x"][0] for f in h["front_x"]], label=f"{a} deg")
ax.set_xlabel("time (s)")
ax.set_ylabel("runout of the front (m)")
ax.set_title("Kita-Uebaru landslide: runout against time (cf. Edo (2016), Fig. 4.6)")
ax.legend(title="friction angle")
ax.grid(alpha=0.3)
fig.tight_layout()
fig.savefig(f"{out}/landslide_runout.png", dpi=120)
print(f"plot: {out}/landslide_runout.png")
PY
