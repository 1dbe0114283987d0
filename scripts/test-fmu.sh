#!/usr/bin/env bash
# Builds GearPump.fmu with fmu-build and runs the importer tests on it
# (tests/python: fmpy validate/simulate/master loop, fmutool -check, bad
# input, the examples), then the Rust importer test (tests/fmi_import.rs,
# the `fmi` crate) on the same .fmu.
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
# with the cdylib it packages.
fmu="$(cd "$root" && "$cargo" run --quiet --release -p fmu-build)"
echo "FMU: $fmu" >&2

cd "$root"
GEARPUMP_FMU="$fmu" "$venv/bin/python" -m pytest -q -p no:cacheprovider tests/python "$@"
GEARPUMP_FMU="$fmu" "$cargo" test --quiet --release --test fmi_import
