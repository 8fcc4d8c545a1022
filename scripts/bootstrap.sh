#!/usr/bin/env bash
# Create the virtual environment VENV (default .venv) with a Python >= 3.12 and install
# geofrac with its test extras into it. Called by the Makefile on first use; safe to rerun.
#
# The versions are the lock's, scripts/constraints.txt: what `make test` passed with in CI
# (pip itself and the build backend included). GEOFRAC_LATEST=1 installs the newest
# releases instead (`make test-latest`), so that an upgrade is tried on purpose; the
# stamp file $VENV/.geofrac-installed says which ("locked" or "latest").
#
# The interpreter is searched for in this order:
#   $GEOFRAC_PYTHON, python3.12, python3.13, python3.14, pyenv-installed 3.12+ versions,
#   `uv python find`, python3, python.
# A candidate counts only if it runs, is >= 3.12 and has the venv and ensurepip modules;
# pyenv shims that answer "command not found" are skipped.
set -euo pipefail

venv=${1:-.venv}
root=$(cd "$(dirname "$0")/.." && pwd)

usable() {
    "$1" -c 'import sys, venv, ensurepip; sys.exit(0 if sys.version_info >= (3, 12) else 1)' \
        >/dev/null 2>&1
}

candidates=()
if [ -n "${GEOFRAC_PYTHON:-}" ]; then
    if ! usable "$GEOFRAC_PYTHON"; then
        echo "error: GEOFRAC_PYTHON=$GEOFRAC_PYTHON is not a Python >= 3.12 with venv/ensurepip" >&2
        exit 1
    fi
    candidates+=("$GEOFRAC_PYTHON")
fi
candidates+=(python3.12 python3.13 python3.14)
pyenv_root=""
if command -v pyenv >/dev/null 2>&1; then
    pyenv_root=$(pyenv root 2>/dev/null || true)
fi
pyenv_root=${pyenv_root:-${PYENV_ROOT:-$HOME/.pyenv}}
if [ -d "$pyenv_root/versions" ]; then
    while IFS= read -r v; do
        candidates+=("$pyenv_root/versions/$v/bin/python")
    done < <(ls "$pyenv_root/versions" | grep -E '^3\.(1[2-9]|[2-9][0-9])(\.[0-9]+)?$' | sort -V)
fi
if command -v uv >/dev/null 2>&1; then
    found=$(uv python find '>=3.12' 2>/dev/null || true)
    [ -n "$found" ] && candidates+=("$found")
fi
candidates+=(python3 python)

python=""
for c in "${candidates[@]}"; do
    if usable "$c"; then
        python=$c
        break
    fi
done

if [ -z "$python" ]; then
    cat >&2 <<'MSG'
error: geofrac needs Python >= 3.12 (the DOLFINx wheel is cp312 abi3), and none was found.
Install one of these, then rerun the same command:
  - Debian/Ubuntu:  apt-get install python3.12 python3.12-venv
  - pyenv:          pyenv install 3.12   (a .python-version file is not needed)
  - uv:             uv python install 3.12
or point GEOFRAC_PYTHON at an existing interpreter: GEOFRAC_PYTHON=/path/to/python3.12
MSG
    exit 1
fi

lock="$root/scripts/constraints.txt"
echo "geofrac: creating $venv with $python ($("$python" -c 'import sys; print(sys.version.split()[0])'))"
"$python" -m venv "$venv"
pip=("$venv/bin/python" -m pip install --quiet --disable-pip-version-check)
if [ -n "${GEOFRAC_LATEST:-}" ]; then
    echo "geofrac: GEOFRAC_LATEST is set: installing the newest releases, not the lock"
    "${pip[@]}" --upgrade pip setuptools
    "${pip[@]}" --upgrade --upgrade-strategy eager -e "$root[test]"
    kind=latest
else
    echo "geofrac: installing the versions of scripts/constraints.txt"
    # pip and the build backend from the lock first; the editable build then uses them
    "${pip[@]}" -c "$lock" pip setuptools
    "${pip[@]}" -c "$lock" --no-build-isolation -e "$root[test]"
    kind=locked
fi
"$venv/bin/python" -c 'import dolfinx_solver, dolfinx, gmsh; print("geofrac: DOLFINx", dolfinx.__version__, "gmsh", gmsh.__version__)'
echo "$kind" > "$venv/.geofrac-installed"
