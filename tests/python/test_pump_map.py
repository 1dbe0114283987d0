"""GearPump.fmu's `map` fidelity (issue 16 point 3) through fmpy: the FMU
with its shipped map validates; `fidelity` is an Integer parameter (1 = lp,
2 = map) that fmpy sets like any other; the map's mean Q_out and torque
over whole mesh periods equal the LP fidelity's within 0.3 % at a point off
the map's nodes; a fidelity outside 1..2 is refused with a logged reason
naming it; the FMU state of the map fidelity serializes and restores.
"""

import math
import shutil
import tempfile

import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

import fmu_driver as d

ERROR = 3
P_ATM = 101325.0


@pytest.fixture(scope="module")
def pump_dir(pump_fmu):
    path = extract(pump_fmu, unzipdir=tempfile.mkdtemp(prefix="gearpump-map-"))
    yield path
    shutil.rmtree(path, ignore_errors=True)


def test_the_fmu_with_its_map_validates_and_declares_fidelity(pump_fmu):
    assert validate_fmu(pump_fmu) == []
    md = read_model_description(pump_fmu)
    v = {x.name: x for x in md.modelVariables}
    f = v["fidelity"]
    assert (f.type, f.causality, f.variability) == ("Integer", "parameter", "fixed")
    assert (int(f.min), int(f.max), int(f.start)) == (1, 2, 1)
    assert v["map_ripple"].type == "Boolean"


def test_map_matches_the_lp_fidelity_within_0_3_percent(pump_fmu):
    # a point off the map's nodes (1000-4000 rpm in 6 log-spaced nodes, 2-200
    # bar in 9, 20-80 degC in 7)
    rpm, bar, degc = 1700.0, 57.0, 47.0
    period = 60.0 / (14 * rpm)
    h = period / 4
    start = {"speed": rpm * math.pi / 30, "p_out": P_ATM + bar * 1e5, "T_oil": degc + 273.15}
    means = {}
    for fidelity in (1, 2):
        res = simulate_fmu(pump_fmu, stop_time=12 * period, step_size=h, output_interval=h,
                           start_values=dict(start, fidelity=fidelity),
                           output=["V_delivered", "torque"])
        t = res["time"]
        torque = sum(res["torque"][1:] * (t[1:] - t[:-1])) / t[-1]
        means[fidelity] = (res["V_delivered"][-1] / t[-1], torque)
    (q_lp, t_lp), (q_map, t_map) = means[1], means[2]
    assert abs(q_map / q_lp - 1) < 3e-3, means
    assert abs(t_map / t_lp - 1) < 3e-3, means


def test_a_fidelity_outside_its_range_is_refused_naming_it(pump_dir):
    md, fmu = d.slave(pump_dir)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    rec = d.Recorder()
    fmu.instantiate(callbacks=rec.callbacks)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    for bad in (0, 3):
        with pytest.raises(FMICallException):
            fmu.setInteger([vr["fidelity"]], [bad])
        assert rec.has(ERROR, "fidelity", "[1, 2]"), rec.messages
    fmu.freeInstance()


def test_the_map_fidelity_state_serializes_and_restores(pump_dir):
    md, fmu = d.slave(pump_dir)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["fidelity"]], [2])
    fmu.setBoolean([vr["map_ripple"]], [True])
    fmu.setReal([vr["speed"], vr["p_out"]], [2200 * math.pi / 30, P_ATM + 80e5])
    fmu.exitInitializationMode()
    h = 1e-3
    t = d.steps(fmu, 0.0, h, 20)
    data = fmu.serializeFMUstate(fmu.getFMUstate())

    def run(f, t):
        out = []
        for k in range(10):
            f.setReal([vr["p_out"]], [P_ATM + (80 + k) * 1e5])
            f.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            t += h
            out.append(f.getReal([vr["Q_out"], vr["torque"], vr["V_delivered"]]))
        return out

    reference = run(fmu, t)
    assert fmu.getInteger([vr["fidelity"]]) == [2]
    fmu.terminate()
    fmu.freeInstance()

    _, other = d.slave(pump_dir, "other")
    other.instantiate()
    other.setupExperiment(startTime=0.0)
    other.enterInitializationMode()
    other.exitInitializationMode()
    other.setFMUstate(other.deSerializeFMUstate(data))
    assert other.getInteger([vr["fidelity"]]) == [2]
    assert run(other, t) == reference
    other.terminate()
    other.freeInstance()


def test_the_map_fidelity_refuses_a_huge_step_as_the_lp_fidelity_does(pump_dir):
    """doStep(0, 1e15) with fidelity = 2 gave V_delivered 2.3e11 m3 at fmi2OK:
    now refused like the LP fidelity's (more than 1e6 angular steps)."""
    md, _ = d.slave(pump_dir)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    for fidelity in (2, 1):
        _, fmu = d.slave(pump_dir, f"huge-{fidelity}")
        rec = d.Recorder()
        fmu.instantiate(callbacks=rec.callbacks)
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setInteger([vr["fidelity"]], [fidelity])
        fmu.exitInitializationMode()
        with pytest.raises(FMICallException):
            fmu.doStep(0.0, 1e15)
        assert rec.has(ERROR, "fmi2DoStep", "angular steps", "limit 1e6"), rec.messages
        fmu.reset()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setInteger([vr["fidelity"]], [fidelity])
        fmu.exitInitializationMode()
        fmu.doStep(0.0, 1e-3)
        assert fmu.getReal([vr["V_delivered"]])[0] > 0.0
        fmu.freeInstance()


def test_the_map_fidelitys_outputs_in_initialization_mode_are_the_values_after_exit(pump_dir):
    """fidelity = 2: fmi2GetReal of the outputs in Initialization mode (0
    there before) gives the map at the inputs set so far, exactly the values
    read after fmi2ExitInitializationMode; a higher delivery pressure set
    after a read gives less flow and more torque at the next read."""
    md, fmu = d.slave(pump_dir, "init-map")
    vr = {v.name: v.valueReference for v in md.modelVariables}
    names = ("Q_out", "torque", "Q_in", "eta_v", "eta_hm", "P_shaft", "P_hyd", "p_pocket_min")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["fidelity"]], [2])
    fmu.setReal([vr["speed"], vr["p_out"]], [2200 * math.pi / 30, P_ATM + 80e5])
    at_init = fmu.getReal([vr[n] for n in names])
    q, torque = at_init[:2]
    assert q > 0.0 and torque > 0.0, at_init
    fmu.setReal([vr["p_out"]], [P_ATM + 120e5])
    q_hi, torque_hi = fmu.getReal([vr["Q_out"], vr["torque"]])
    assert q_hi < q and torque_hi > torque, (q_hi, q, torque_hi, torque)
    fmu.setReal([vr["p_out"]], [P_ATM + 80e5])
    fmu.exitInitializationMode()
    assert fmu.getReal([vr[n] for n in names]) == at_init
    fmu.terminate()
    fmu.freeInstance()
