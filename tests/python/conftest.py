"""Fixtures for the FMU tests run through real importers (fmpy, fmutool).

Two FMUs are under test: GearPump.fmu ($GEARPUMP_FMU) and
TransmissionCircuit.fmu ($TRANSMISSION_FMU). When a variable is not set,
both are built once per session with `cargo run --release -p fmu-build --
--env` (honouring CARGO and CARGO_TARGET_DIR).

`fmu_path` is parametrized over both FMUs, so the model-agnostic checks
(test_fmu.py: fmpy validate, fmutool -check, simulate, state serialization
across processes, threads, bad input) run for each; tests of one model skip
the other. `pump_fmu` and `circuit_fmu` are the two paths for the coupling
tests.
"""

import os
import subprocess
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

ROOT = Path(__file__).resolve().parents[2]
ENV_VARS = ("GEARPUMP_FMU", "TRANSMISSION_FMU")


@pytest.fixture(scope="session")
def fmu_paths() -> dict:
    paths = {k: os.environ.get(k) for k in ENV_VARS}
    if not all(paths.values()):
        cargo = os.environ.get("CARGO", "cargo")
        out = subprocess.run(
            [cargo, "run", "--quiet", "--release", "-p", "fmu-build", "--", "--env"],
            cwd=ROOT,
            check=True,
            stdout=subprocess.PIPE,
            text=True,
        )
        built = dict(line.split("=", 1) for line in out.stdout.strip().splitlines() if "=" in line)
        paths = {k: paths[k] or built[k] for k in ENV_VARS}
    for k, p in paths.items():
        assert Path(p).is_file(), f"{k}: FMU not found: {p}"
    return {k: str(Path(p).resolve()) for k, p in paths.items()}


@pytest.fixture(scope="session", params=ENV_VARS, ids=["GearPump", "TransmissionCircuit"])
def fmu_path(request, fmu_paths) -> str:
    return fmu_paths[request.param]


@pytest.fixture(scope="session")
def pump_fmu(fmu_paths) -> str:
    return fmu_paths["GEARPUMP_FMU"]


@pytest.fixture(scope="session")
def circuit_fmu(fmu_paths) -> str:
    return fmu_paths["TRANSMISSION_FMU"]


def _newest_source(root: Path) -> float:
    """The latest modification time of what the gearpump binary is built
    from: the Rust sources, the manifests and the bundled designs (the
    binary embeds the seed design's text, from which the FMU's GUID is
    derived)."""
    newest = 0.0
    for top in ("src", "crates", "designs"):
        for f in (root / top).rglob("*"):
            if f.is_file() and f.suffix in (".rs", ".toml", ".xml"):
                newest = max(newest, f.stat().st_mtime)
    for f in ("Cargo.toml", "Cargo.lock"):
        if (root / f).is_file():
            newest = max(newest, (root / f).stat().st_mtime)
    return newest


@pytest.fixture(scope="session")
def gearpump_cli(pump_fmu) -> str:
    """The gearpump binary of the build that made the FMU (target/release),
    built when missing or older than its sources. A stale binary would
    package a design text other than the FMU library's, whose GUID the FMU
    then refuses ("Failed to instantiate model")."""
    target = Path(pump_fmu).resolve().parent.parent
    exe = target / "release" / "gearpump"
    if not exe.is_file() or exe.stat().st_mtime < _newest_source(ROOT):
        cargo = os.environ.get("CARGO", "cargo")
        env = dict(os.environ, CARGO_TARGET_DIR=str(target))
        subprocess.run([cargo, "build", "--quiet", "--release", "--bin", "gearpump"],
                       cwd=ROOT, env=env, check=True)
        # cargo leaves the binary's time alone when nothing needed building
        # (a source touched but unchanged): mark it as checked
        exe.touch()
    return str(exe)


@pytest.fixture(scope="session")
def model_description(fmu_path):
    return read_model_description(fmu_path)


@pytest.fixture(scope="session")
def unzipdir(fmu_path, tmp_path_factory) -> str:
    return extract(fmu_path, unzipdir=str(tmp_path_factory.mktemp("fmu")))
