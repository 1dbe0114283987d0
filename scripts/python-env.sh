#!/usr/bin/env bash
# Creates (or refreshes) the Python virtual environment used by the FMU tests
# and prints its path on stdout.
#
#   scripts/python-env.sh            -> <repo>/.venv
#   GEARPUMP_VENV=/some/dir scripts/python-env.sh
#
# The environment is (re)created with `python3 -m venv --clear` when it is
# missing, when its interpreter no longer runs, or when the pinned requirements
# (tests/python/requirements.txt) or the python3 version changed since the last
# successful install; otherwise nothing is done. Packages come from PyPI with
# the ordinary pip client. Quiet on success; pip's errors go to stderr.
# Concurrent runs are serialised with flock.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
req="$root/tests/python/requirements.txt"
venv="${GEARPUMP_VENV:-$root/.venv}"
python="${PYTHON:-python3}"
stamp="$venv/.gearpump-requirements.sha256"

command -v "$python" >/dev/null 2>&1 || { echo "python-env: $python not found" >&2; exit 1; }
[ -f "$req" ] || { echo "python-env: missing $req" >&2; exit 1; }

# The wanted stamp: the requirements' hash plus the interpreter's version.
want="$( { sha256sum "$req" | cut -d' ' -f1; "$python" -c 'import sys; print(sys.version)'; } | sha256sum | cut -d' ' -f1)"

up_to_date() {
    [ -x "$venv/bin/python" ] && "$venv/bin/python" -c 'import sys' >/dev/null 2>&1 &&
        [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]
}

if ! up_to_date; then
    mkdir -p "$(dirname "$venv")"
    lock="$root/target/.python-env.lock"
    mkdir -p "$(dirname "$lock")"
    exec 9>"$lock"
    flock 9
    # Another run may have finished the job while we waited.
    if ! up_to_date; then
        rm -f "$stamp"
        "$python" -m venv --clear "$venv"
        export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
        "$venv/bin/python" -m pip install --quiet -r "$req" >&2
        # Check that the tools import before declaring success.
        "$venv/bin/python" -c 'import fmpy, fmpy.validation, fmu_manipulation_toolbox, pytest, matplotlib, numpy, pandas, maturin, dask, distributed, pyarrow' >&2
        echo "$want" >"$stamp"
    fi
    exec 9>&-
fi

echo "$venv"
