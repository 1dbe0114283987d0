"""Fixtures for the FMU tests run through real importers (fmpy, fmutool).

The FMU under test is $GEARPUMP_FMU if set; otherwise it is built once per
session with `cargo run --release -p fmu-build` (honouring CARGO and
CARGO_TARGET_DIR).
"""

import os
import subprocess
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def fmu_path() -> str:
    path = os.environ.get("GEARPUMP_FMU")
    if not path:
        cargo = os.environ.get("CARGO", "cargo")
        out = subprocess.run(
            [cargo, "run", "--quiet", "--release", "-p", "fmu-build"],
            cwd=ROOT,
            check=True,
            stdout=subprocess.PIPE,
            text=True,
        )
        path = out.stdout.strip().splitlines()[-1]
    assert Path(path).is_file(), f"FMU not found: {path}"
    return str(Path(path).resolve())


@pytest.fixture(scope="session")
def model_description(fmu_path):
    return read_model_description(fmu_path)


@pytest.fixture(scope="session")
def unzipdir(fmu_path, tmp_path_factory) -> str:
    return extract(fmu_path, unzipdir=str(tmp_path_factory.mktemp("fmu")))
