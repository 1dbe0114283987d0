#!/usr/bin/env bash
# The whole test suite: every Rust test (unit, integration, CLI) in release,
# then the FMU importer tests (fmpy, fmutool) in a Python virtual
# environment that scripts/python-env.sh creates with pinned versions.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
cargo="${CARGO:-cargo}"
# system and Python dependencies: libclang for the `fmi` crate (Rust FMU
# importer, built by the tests) and the pinned virtual environment
"$root/scripts/test-fmu.sh" --deps
"$cargo" test --workspace --release --features gearpump-cli/full-tests
"$root/scripts/test-fmu.sh"
