#!/usr/bin/env bash
# Run one or more scenes with mpiexec, with rank-0 progress across scenes.
#
#   jobs/run.sh [-n RANKS] SCENE.toml [SCENE.toml ...] [-- extra geofrac run options]
#
# RANKS defaults to $GEOFRAC_NP or 2. The venv is .venv at the repository root unless
# $VENV says otherwise (run `make quickstart` once to create it). Each scene writes its
# own output directory (output.dir in the scene); a failing scene stops the batch with
# its exit code, and its summary.json records the error. A scene whose output directory
# holds a completed run is refused (exit 2): pass `-- --overwrite` to replace such
# results (only when the new run succeeds).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
venv=${VENV:-$root/.venv}
np=${GEOFRAC_NP:-2}
if [ "${1:-}" = "-n" ]; then np=$2; shift 2; fi
scenes=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do scenes+=("$1"); shift; done
[ "${1:-}" = "--" ] && shift
if [ ${#scenes[@]} -eq 0 ]; then
    echo "usage: jobs/run.sh [-n RANKS] SCENE.toml [...] [-- geofrac run options]" >&2
    exit 2
fi
if [ ! -x "$venv/bin/geofrac" ]; then
    echo "error: $venv/bin/geofrac not found; run 'make quickstart' first or set VENV" >&2
    exit 2
fi
for scene in "${scenes[@]}"; do  # validate everything before running anything
    "$venv/bin/geofrac" check "$scene" > /dev/null
done
start=$(date +%s)
i=0
for scene in "${scenes[@]}"; do
    i=$((i + 1))
    "$venv/bin/mpiexec" -n "$np" "$venv/bin/geofrac" run "$scene" "$@"
    now=$(date +%s)
    elapsed=$((now - start))
    left=$((elapsed * (${#scenes[@]} - i) / i))
    echo "[$i/${#scenes[@]}] done: $scene (elapsed ${elapsed}s, left ~${left}s)"
done
