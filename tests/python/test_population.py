"""`gearpump fmu --population CAMPAIGN.csv`: an SSP file with GearPump.fmu
and one SSV parameter set per pump sample, read back with fmpy's SSP support
(fmpy.ssp, which checks the SystemStructure.ssd and each .ssv against the
SSP 1.0 schemas): every sample of the campaign is a component whose
parameter set holds its clearances as the FMU's parameters (read from the
CSV here, not from the code that wrote them); one pump simulated through
the SSP (fmpy.ssp.simulation.simulate_ssp with the SSP's own parameter
sets) gives the mean Q_out of `gearpump simulate` with that pump's
clearances within 0.1 %; bad input exits 2 naming what is wrong.
"""

import csv
import json
import os
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import ParameterSet, find_components, read_ssd

ROOT = Path(__file__).resolve().parents[2]
CAMPAIGN = ROOT / "examples" / "demo_campaign" / "campaign.csv"
PARAMS = {
    "tip_clearance_drive": "tip_clearance_drive_um",
    "tip_clearance_driven": "tip_clearance_driven_um",
    "bearing_clearance_drive": "bearing_clearance_drive_um",
    "bearing_clearance_driven": "bearing_clearance_driven_um",
}


def campaign_pumps(path):
    """sample -> {FMU parameter: clearance in m}, from the CSV."""
    pumps = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            pumps.setdefault(row["sample"], {k: float(row[c]) * 1e-6 for k, c in PARAMS.items()})
    return pumps


@pytest.fixture(scope="module")
def population(gearpump_cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("population") / "demo.ssp"
    r = subprocess.run([gearpump_cli, "fmu", "--population", str(CAMPAIGN), "--out", str(out), "--json"],
                       check=True, stdout=subprocess.PIPE, text=True)
    assert json.loads(r.stdout)["pumps"] == 20
    return str(out)


def bound_parameters(component):
    """The component's parameters from its bindings, prefix removed."""
    values = {}
    for b in component.parameterBindings:
        prefix = b.prefix or ""
        for ps in b.parameterValues:
            for p in ps.parameters:
                assert p.name.startswith(prefix), (p.name, prefix)
                values[p.name[len(prefix):]] = (p.type, float(p.value), p.unit)
    return values


def test_every_pump_is_a_component_with_its_clearances_as_fmu_parameters(population, tmp_path):
    ssd = read_ssd(population)  # validated against the SSP schemas
    components = find_components(ssd.system)
    pumps = campaign_pumps(CAMPAIGN)
    assert sorted(c.name for c in components) == sorted(pumps)
    # the FMU inside the SSP, and its parameters with units
    with zipfile.ZipFile(population) as z:
        sources = {c.source for c in components}
        assert len(sources) == 1
        fmu = tmp_path / "GearPump.fmu"
        fmu.write_bytes(z.read(sources.pop()))
    md = read_model_description(str(fmu))
    variables = {v.name: v for v in md.modelVariables}
    for c in components:
        bound = bound_parameters(c)
        assert set(bound) == set(PARAMS), (c.name, bound)
        for name, (kind, value, unit) in bound.items():
            v = variables[name]
            assert v.causality == "parameter" and kind == "Real"
            assert unit == v.unit == "m"
            assert value == pytest.approx(pumps[c.name][name], rel=1e-12), (c.name, name)
            assert float(v.min) <= value <= float(v.max)
    # the pumps differ: the sets are the samples' own
    assert len({tuple(sorted(bound_parameters(c).items())) for c in components}) == len(pumps)


def test_one_pump_through_the_ssp_gives_simulates_mean_flow(population, gearpump_cli):
    ssd = read_ssd(population)
    components = find_components(ssd.system)
    pumps = campaign_pumps(CAMPAIGN)
    sample = "N07"
    # the SSP's own parameter sets, as the SSP's bindings give them (fmpy's
    # simulate_ssp applies one set whose names carry the component path)
    merged = ParameterSet(name="population")
    for c in components:
        for b in c.parameterBindings:
            for ps in b.parameterValues:
                merged.parameters.extend(ps.parameters)
    rpm, bar, degc = 1000.0, 30.0, 60.0  # the FMU's start values (no input is connected)
    period = 60.0 / (14 * rpm)
    h = period / 4
    res = simulate_ssp(population, stop_time=4 * period - h / 2, step_size=h, parameter_set=merged)
    q = {c.name: float(np.mean(res[f"{c.name}.Q_out"][:16])) * 60000.0 for c in components}
    c = pumps[sample]
    clearances = ",".join(f"{c[k] * 1e6:g}" for k in PARAMS)
    sim = subprocess.run(
        [gearpump_cli, "simulate", "--speed", str(rpm), "--pressure", str(bar), "--temp", str(degc),
         "--sample-clearances", clearances, "--json"],
        check=True, stdout=subprocess.PIPE, text=True,
        env=dict(os.environ, GEARPUMP_TABLE_CACHE="off"),
    )
    q_sim = json.loads(sim.stdout)["flow_lpm"]
    print(f"{sample}: SSP {q[sample]:.5f} l/min, simulate {q_sim:.5f} l/min; "
          f"population {min(q.values()):.3f}-{max(q.values()):.3f} l/min")
    assert abs(q[sample] / q_sim - 1) < 1e-3, (q[sample], q_sim)
    # the clearances took effect: the pumps' flows spread
    assert max(q.values()) - min(q.values()) > 1e-3 * q_sim


@pytest.mark.parametrize("case", ["missing", "no_pumps", "out_of_range", "inconsistent"])
def test_bad_population_input_exits_2_naming_it(gearpump_cli, tmp_path, case):
    lines = CAMPAIGN.read_text().splitlines()
    src = tmp_path / f"{case}.csv"
    if case == "no_pumps":
        src.write_text(lines[0] + "\n")
        want = "no data rows"
    elif case == "out_of_range":
        src.write_text("\n".join([lines[0], lines[1].replace("N01,28,", "N01,900,", 1), *lines[2:]]) + "\n")
        want = "tip_clearance_drive_um"
    elif case == "inconsistent":
        src.write_text("\n".join([lines[0], lines[1], lines[2].replace("N01,28,", "N01,29,", 1), *lines[3:]]) + "\n")
        want = "sample N01 has other clearances"
    else:
        want = "missing.csv"
    out = tmp_path / "x.ssp"
    r = subprocess.run([gearpump_cli, "fmu", "--population", str(src), "--out", str(out)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert r.returncode == 2, r.stderr
    assert want in r.stderr, r.stderr
    assert not out.exists()
