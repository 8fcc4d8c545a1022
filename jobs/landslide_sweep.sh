#!/usr/bin/env bash
# Friction-angle sweep of the Kita-Uebaru landslide (Edo (2016), Fig. 4.6): one run per angle, each
# in $OUT/landslide_phi<angle>/ (results/ by default), then a table of runout at t_end beside the thesis's.
#
#   jobs/landslide_sweep.sh [-n RANKS] [ANGLE ...] [-- extra geofrac run options]
#   jobs/landslide_sweep.sh --table [ANGLE ...]   (no runs: table and plot of the results there)
#
# ANGLEs default to the thesis's 8 10 12 14 16 25. RANKS defaults to $GEOFRAC_NP or 2. Writes
# $OUT/landslide_runout.png (runout against time beside Edo (2016), Fig. 4.6: docs/landslide_runout.py).
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
"$venv/bin/python" "$root/docs/landslide_runout.py" "$out" "${angles[@]}"
