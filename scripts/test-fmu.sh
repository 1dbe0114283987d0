#!/usr/bin/env bash
# Builds the FMU with fmu-build and runs the importer tests on it
# (tests/python: fmpy validate/simulate/master loop, fmutool -check).
#
#   scripts/test-fmu.sh [pytest args...]
#
# Uses $CARGO (default cargo) and honours CARGO_TARGET_DIR; the Python tools
# come from scripts/python-env.sh (.venv, created on first use).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
venv="$("$root/scripts/python-env.sh")"
cargo="${CARGO:-cargo}"

# --release: fmu-build then shares the release build of the gearpump library
# with the cdylib it packages.
fmu="$(cd "$root" && "$cargo" run --quiet --release -p fmu-build)"
echo "FMU: $fmu" >&2

cd "$root"
GEARPUMP_FMU="$fmu" "$venv/bin/python" -m pytest -q -p no:cacheprovider tests/python "$@"
