"""GearPump.fmu of a design file (issue 16 point 1) through fmpy: `gearpump
fmu --design FILE --set ...` writes an FMU that passes `fmpy validate` and
`fmutool -check`, whose clearance parameters start at the design's, and
whose mean Q_out over whole
mesh periods equals `gearpump simulate` with the same design within 0.1 %.
The design carries extension keys (thermal and pressure clearance growth,
Barus, a viscosity factor). Uses the release `gearpump` binary beside the
FMU fmu-build wrote (target/release), built by cargo when missing.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

ROOT = Path(__file__).resolve().parents[2]

SETS = [
    "clearance.tip_um=33.5",
    "clearance.thermal_growth_um_per_k=0.05",
    "clearance.pressure_growth_um_per_bar=0.1",
    "clearance.pressure_growth_on=tips",
    "oil.pressure_viscosity_per_pa=2e-8",
    "oil.viscosity_factor_60c=0.9",
]


@pytest.fixture(scope="module")
def design_fmu(gearpump_cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("design")
    design = d / "sample.toml"
    text = (ROOT / "designs" / "seed_pump.toml").read_text()
    design.write_text(text.replace("bearing_um = 12.0 ", "bearing_um = 14.0 "))
    out = d / "GearPump.fmu"
    args = ["--design", str(design)] + [a for s in SETS for a in ("--set", s)]
    exe = gearpump_cli
    subprocess.run([exe, "fmu", *args, "--out", str(out)], check=True,
                   stdout=subprocess.PIPE)
    return exe, args, str(out)


def test_fmu_of_a_design_validates_and_starts_at_its_clearances(design_fmu):
    _, _, fmu = design_fmu
    assert validate_fmu(fmu) == []
    md = read_model_description(fmu)
    start = {v.name: v.start for v in md.modelVariables}
    assert float(start["tip_clearance_drive"]) == pytest.approx(33.5e-6, rel=1e-12)
    assert float(start["bearing_clearance_driven"]) == pytest.approx(14.0e-6, rel=1e-12)
    for name in ("Q_in", "P_shaft", "P_hyd", "p_pocket_min", "cavitation_margin", "out_of_range"):
        assert name in start, name


def test_fmu_of_a_design_passes_fmutool_check(design_fmu):
    """fmu-manipulation-toolbox's checker on the FMU of a design (the issue's
    "done when": fmpy validate and fmutool -check)."""
    _, _, fmu = design_fmu
    out = subprocess.run(
        [str(Path(sys.executable).parent / "fmutool"), "-input", fmu, "-check"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    assert out.returncode == 0, out.stdout
    assert "compliant with FMI-2.0" in out.stdout, out.stdout
    assert "No semantic error" in out.stdout, out.stdout


def test_fmu_of_a_design_matches_simulate_within_0_1_percent(design_fmu):
    exe, args, fmu = design_fmu
    rpm, bar, degc = 1000.0, 30.0, 60.0
    sim = subprocess.run(
        [exe, "simulate", *args, "--speed", str(rpm), "--pressure", str(bar),
         "--temp", str(degc), "--json"],
        check=True, stdout=subprocess.PIPE, text=True,
        env=dict(os.environ, GEARPUMP_TABLE_CACHE="off"),
    )
    q_sim = json.loads(sim.stdout)["flow_lpm"]
    # ten mesh periods (14 teeth) in steps of a quarter period
    period = 60.0 / (14 * rpm)
    h = period / 4
    res = simulate_fmu(fmu, stop_time=10 * period, step_size=h, output_interval=h,
                       output=["V_delivered", "Q_out", "Q_in", "P_hyd", "cavitation_margin"])
    q_fmu = res["V_delivered"][-1] / res["time"][-1] * 60000.0
    assert abs(q_fmu / q_sim - 1) < 1e-3, (q_fmu, q_sim)
    assert (res["cavitation_margin"] > 1).all()
