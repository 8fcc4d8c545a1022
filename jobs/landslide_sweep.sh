#!/usr/bin/env bash
# Friction-angle sweep of the Kita-Uebaru landslide (seed Fig. 4.6): one run per angle, each
# in results/landslide_phi<angle>/, then a table of runout at t_end beside the seed's.
#
#   jobs/landslide_sweep.sh [-n RANKS] [ANGLE ...] [-- extra geofrac run options]
#
# ANGLEs default to the seed's 8 10 12 14 16 25. RANKS defaults to $GEOFRAC_NP or 2.
# Example (a quick coarse sweep): jobs/landslide_sweep.sh 8 25 -- --set mpm.t_end=10
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
np=${GEOFRAC_NP:-2}
if [ "${1:-}" = "-n" ]; then np=$2; shift 2; fi
angles=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do angles+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
[ ${#angles[@]} -eq 0 ] && angles=(8 10 12 14 16 25)
if [ ! -x "$venv/bin/geofrac" ]; then
    echo "error: $venv/bin/geofrac not found; run 'make quickstart' first or set VENV" >&2
    exit 2
fi
scene=$root/jobs/landslide_kita_uebaru.toml
checks=()  # validate the overrides once, before any run (check takes --set only)
for arg in "$@"; do [ "$arg" = "-q" ] || [ "$arg" = "--quiet" ] || checks+=("$arg"); done
"$venv/bin/geofrac" check "$scene" "${checks[@]}" > /dev/null
for a in "${angles[@]}"; do
    echo "== friction angle $a deg ($np ranks)"
    "$venv/bin/mpiexec" -n "$np" "$venv/bin/geofrac" run "$scene" \
        --set plasticity.friction_angle="$a" --out "results/landslide_phi$a" "$@"
done
"$venv/bin/python" - "${angles[@]}" <<'PY'
import json, sys
seed = {8: 205.9, 10: 176.7, 12: 110.7, 14: 63.0, 16: 32.5, 25: 0.0}
print(f"{'phi':>5} {'runout_m':>10} {'seed_m':>8}")
for a in sys.argv[1:]:
    r = json.load(open(f"results/landslide_phi{a}/summary.json"))["results"]
    ref = seed.get(round(float(a)))
    print(f"{a:>5} {r['runout_m']:10.1f} {'' if ref is None else ref:>8}")
PY
