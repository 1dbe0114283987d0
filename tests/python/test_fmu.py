"""Each FMU (GearPump.fmu and TransmissionCircuit.fmu: the fmu_path fixture
is parametrized over both) through real importers: fmpy (validation, simulation, a
hand-written master loop with FMU state serialization across processes) and
fmu-manipulation-toolbox's checker. Model-agnostic except the closed-form
check of the Tank test model, which runs only when that model is packaged.
"""

import json
import math
import os
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import fmu_driver as d

HERE = Path(__file__).resolve().parent
BIN = Path(sys.executable).parent
ERROR = 3


def step_size(md):
    de = md.defaultExperiment
    return float(de.stepSize) if de is not None and de.stepSize else 1e-3


def test_fmpy_validate_finds_no_problem(fmu_path):
    assert validate_fmu(fmu_path) == []


def test_fmutool_check_passes(fmu_path):
    out = subprocess.run(
        [str(BIN / "fmutool"), "-input", fmu_path, "-check"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    assert out.returncode == 0, out.stdout
    assert "compliant with FMI-2.0" in out.stdout, out.stdout
    assert "No semantic error" in out.stdout, out.stdout


def test_model_description_basics(model_description):
    md = model_description
    assert md.fmiVersion == "2.0"
    assert md.coSimulation is not None and md.modelExchange is None
    cs = md.coSimulation
    assert cs.canHandleVariableCommunicationStepSize
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate
    assert cs.canNotUseMemoryManagementFunctions
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    assert [u.variable for u in md.outputs] == outputs


def test_fmpy_cli_simulate_loads_every_symbol(fmu_path, model_description, tmp_path):
    h = step_size(model_description)
    out = tmp_path / "out.csv"
    r = subprocess.run(
        [str(BIN / "fmpy"), "simulate", fmu_path, "--interface-type", "CoSimulation",
         "--stop-time", str(20 * h), "--output-interval", str(h), "--output-file", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    assert r.returncode == 0, r.stdout
    assert len(out.read_text().splitlines()) >= 21


def test_simulate_fmu_gives_finite_outputs(fmu_path, model_description):
    h = step_size(model_description)
    result = simulate_fmu(fmu_path, fmi_type="CoSimulation", stop_time=50 * h, output_interval=h)
    assert len(result) == 51
    for name in result.dtype.names:
        assert np.all(np.isfinite(result[name].astype(float))), name


def test_tank_matches_closed_form(fmu_path, model_description):
    if model_description.coSimulation.modelIdentifier != "Tank":
        pytest.skip("closed form only for the Tank test model")
    q, k, a = 2.0e-3, 0.01, 0.5
    result = simulate_fmu(fmu_path, fmi_type="CoSimulation", stop_time=10.0, output_interval=0.5,
                          start_values={"q_in": q})
    t = result["time"]
    expect = q / k * (1.0 - np.exp(-k * t / a))
    assert np.allclose(result["level"], expect, rtol=1e-12, atol=1e-15)


def test_state_serialized_in_one_process_restores_in_another(unzipdir, model_description, tmp_path):
    md = model_description
    h = step_size(md)
    _, fmu = d.slave(unzipdir)
    rec = d.Recorder()
    fmu.instantiate(callbacks=rec.callbacks)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    t = d.steps(fmu, 0.0, h, 10)
    state = fmu.getFMUstate()
    data = fmu.serializeFMUstate(state)
    fmu.freeFMUstate(state)
    (tmp_path / "state.bin").write_bytes(bytes(data))
    d.steps(fmu, t, h, 10)
    reference = d.outputs(md, fmu)
    fmu.terminate()
    fmu.freeInstance()

    r = subprocess.run(
        [sys.executable, str(HERE / "fmu_driver.py"), unzipdir, str(tmp_path / "state.bin"),
         repr(t), repr(h), "10"],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    assert r.returncode == 0, r.stdout
    assert json.loads(r.stdout.strip().splitlines()[-1]) == reference


def test_instances_on_threads_agree(unzipdir, model_description):
    md = model_description
    h = step_size(md)
    results = [None] * 4
    errors = []

    def run(k):
        try:
            _, fmu = d.slave(unzipdir, f"t{k}")
            fmu.instantiate()
            fmu.setupExperiment(startTime=0.0)
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            d.steps(fmu, 0.0, h, 50)
            results[k] = d.outputs(md, fmu)
            fmu.terminate()
            fmu.freeInstance()
        except Exception as e:  # reported below
            errors.append(e)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(4)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    assert not errors, errors
    assert all(r == results[0] for r in results)


def test_wrong_guid_fails_with_a_logged_reason(unzipdir):
    _, fmu = d.slave(unzipdir, guid="{00000000-0000-0000-0000-000000000000}")
    rec = d.Recorder()
    with pytest.raises(Exception, match="Failed to instantiate"):
        fmu.instantiate(callbacks=rec.callbacks)
    assert rec.has(ERROR, "GUID mismatch"), rec.messages


def test_nan_input_is_an_error_naming_the_variable(unzipdir, model_description):
    md = model_description
    inputs = [v for v in md.modelVariables if v.causality == "input" and v.type == "Real"]
    if not inputs:
        pytest.skip("no Real input")
    v = inputs[0]
    _, fmu = d.slave(unzipdir)
    rec = d.Recorder()
    fmu.instantiate(callbacks=rec.callbacks)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    state = fmu.getFMUstate()
    with pytest.raises(FMICallException):
        fmu.setReal([v.valueReference], [math.nan])
    assert rec.has(ERROR, v.name, "NaN"), rec.messages
    # Roll back from the error and go on.
    fmu.setFMUstate(state)
    fmu.freeFMUstate(state)
    d.steps(fmu, 0.0, step_size(md), 3)
    fmu.terminate()
    fmu.freeInstance()


def test_wrong_communication_point_and_zero_step_are_errors(unzipdir, model_description):
    h = step_size(model_description)
    for t, step, needle in [(5 * h, h, "currentCommunicationPoint"), (0.0, 0.0, "must be > 0")]:
        _, fmu = d.slave(unzipdir)
        rec = d.Recorder()
        fmu.instantiate(callbacks=rec.callbacks)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        with pytest.raises(FMICallException):
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=step)
        assert rec.has(ERROR, "fmi2DoStep", needle), rec.messages
        fmu.reset()
        fmu.freeInstance()
