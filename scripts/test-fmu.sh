#!/usr/bin/env bash
# Builds GearPump.fmu and TransmissionCircuit.fmu with fmu-build and runs
# the importer tests on them (tests/python: fmpy validate/simulate/master
# loop and fmutool -check on both, bad input, the pump coupled to the
# circuit with its convergence table, the examples), then the Rust importer
# tests (tests/fmi_import.rs, tests/transmission_cosim.rs, the `fmi` crate)
# on the same .fmu files. Before pytest, the gearpump Python package
# (python/) is built and installed into the venv (pip install ./python).
#
#   scripts/test-fmu.sh [pytest args...]
#   scripts/test-fmu.sh --deps      only install what the FMU tests need
#
# Needs: cargo, python3, and libclang (the `fmi` crate's build generates its
# FMI bindings with bindgen). libclang is installed with apt-get when it is
# missing (CI runs as root with Debian's registry reachable); the Python
# tools come from scripts/python-env.sh (.venv, pinned, created on first
# use). Uses $CARGO (default cargo) and honours CARGO_TARGET_DIR.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cargo="${CARGO:-cargo}"

have_libclang() {
    local f
    for f in /usr/lib/llvm-*/lib/libclang.so* /usr/lib/llvm-*/lib/libclang-[0-9]*.so* \
        /usr/lib/*/libclang.so* /usr/lib/*/libclang-[0-9]*.so* /usr/lib64/libclang.so*; do
        [ -e "$f" ] || continue
        # bindgen also needs clang's own headers (stddef.h, ...)
        compgen -G "/usr/lib/llvm-*/lib/clang/*/include/stddef.h" >/dev/null && return 0
        compgen -G "/usr/lib/clang/*/include/stddef.h" >/dev/null && return 0
    done
    [ -n "${LIBCLANG_PATH:-}" ] && return 0
    return 1
}

ensure_libclang() {
    have_libclang && return 0
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
        echo "test-fmu: installing libclang-dev (needed to build the fmi crate)" >&2
        export DEBIAN_FRONTEND=noninteractive
        apt-get update -qq >&2
        apt-get install -y -qq --no-install-recommends libclang-dev >&2
        have_libclang && return 0
    fi
    echo "test-fmu: libclang not found: install libclang-dev (or set LIBCLANG_PATH)" >&2
    exit 1
}

ensure_libclang
venv="$("$root/scripts/python-env.sh")"
if [ "${1:-}" = "--deps" ]; then
    exit 0
fi

# --release: fmu-build then shares the release build of the gearpump library
# with the cdylibs it packages. It prints GEARPUMP_FMU=... and
# TRANSMISSION_FMU=... (the variables the tests read).
fmus="$(cd "$root" && "$cargo" run --quiet --release -p fmu-build -- --env)"
GEARPUMP_FMU="$(sed -n 's/^GEARPUMP_FMU=//p' <<<"$fmus")"
TRANSMISSION_FMU="$(sed -n 's/^TRANSMISSION_FMU=//p' <<<"$fmus")"
[ -f "$GEARPUMP_FMU" ] && [ -f "$TRANSMISSION_FMU" ] || {
    echo "test-fmu: fmu-build did not report both FMUs:" >&2
    echo "$fmus" >&2
    exit 1
}
export GEARPUMP_FMU TRANSMISSION_FMU
echo "FMUs: $GEARPUMP_FMU $TRANSMISSION_FMU" >&2

# The gearpump Python package (python/: maturin + PyO3) into the venv: built
# by the pinned maturin of the venv (no build isolation, so nothing is
# fetched from PyPI here) with cargo, into $CARGO_TARGET_DIR (default
# <repo>/target), then tests/python/test_python_package.py imports it.
echo "test-fmu: pip install ./python (the gearpump Python package)" >&2
PATH="$venv/bin:$PATH" CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}" \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    "$venv/bin/python" -m pip install --quiet --no-build-isolation --no-deps \
    --force-reinstall "$root/python" >&2

cd "$root"
"$venv/bin/python" -m pytest -q -p no:cacheprovider tests/python "$@"
"$cargo" test --quiet --release --features full-tests --test fmi_import --test transmission_cosim
