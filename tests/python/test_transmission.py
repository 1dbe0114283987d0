"""GearPump.fmu coupled to TransmissionCircuit.fmu through fmpy, with the
master of examples/transmission_cosim.py (engagement at idle, run-up from
800 to 2500 rpm): the line pressure settles where the regulator's equations
put it, the clutch fills in the time its feed orifice allows, the volume the
pump delivers is the volume the circuit receives (to round-off), and the
coupled result converges as the communication step shrinks. The expected
values are computed from the circuit's parameters (its start values in the
model description) and the oil density it reports, not typed in.

Both FMUs also go through test_fmu.py (fmpy validate, fmutool -check, ...),
which is parametrized over them.
"""

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "examples"))
import transmission_cosim as tc  # noqa: E402

STOP = 0.5  # s: idle, engagement, run-up (0.2-0.3 s), 0.2 s at 2500 rpm
SETTLED = 0.4  # s: the window [SETTLED, STOP] is at constant speed with the clutch full


@pytest.fixture(scope="module")
def run(pump_fmu, circuit_fmu):
    """The scenario with micromotion on, 1 ms steps (the plot in docs/fmu.md)."""
    return tc.cosimulate(pump_fmu, circuit_fmu, h=1e-3, stop=STOP, micromotion=True)


@pytest.fixture(scope="module")
def rho(circuit_fmu):
    from fmpy import simulate_fmu
    r = simulate_fmu(circuit_fmu, stop_time=1e-3, output_interval=1e-3, output=["rho_oil"])
    return float(r["rho_oil"][0])


def test_line_pressure_settles_at_the_regulator_set_point(run, rho):
    p = run["params"]
    late = run["t"] >= SETTLED
    assert run["x_clutch"][late].min() >= p["clutch_stroke"], "clutch full in the window"
    q = float(np.mean(run["Q_pump"][late]))
    dp = float(np.mean(run["p_line"][late])) - p["p_sump"]
    # the regulator's band: cracking pressure .. fully open
    a_s = math.pi * p["reg_diameter"] ** 2 / 4
    full_open = p["reg_dp_set"] + p["reg_spring_rate"] * (p["reg_stroke"] - p["reg_overlap"]) / a_s
    assert p["reg_dp_set"] < dp < full_open
    # the steady balance of spool and orifices for the mean pump flow; the
    # tolerance is 1 % of the droop there (the pump's flow ripple, +-5 %,
    # moves the mean pressure by its second order only)
    expect = tc.steady_dp(p, rho, q)
    tol = 0.01 * (expect - p["reg_dp_set"])
    print(f"line {dp / 1e5:.4f} bar vs {expect / 1e5:.4f} bar (set point "
          f"{p['reg_dp_set'] / 1e5:g} bar, tolerance {tol:.0f} Pa) at {q * 6e4:.2f} l/min")
    assert abs(dp - expect) < tol
    # and settled: the last 50 ms hold the same mean as the 50 ms before
    a = run["t"] >= STOP - 0.05
    b = (run["t"] >= STOP - 0.1) & ~a
    assert abs(np.mean(run["p_line"][a]) - np.mean(run["p_line"][b])) < tol


def test_clutch_fills_in_the_time_its_feed_orifice_allows(run, rho):
    p = run["params"]
    fill = tc.fill_time(run)
    assert fill is not None, "the clutch never reached the pack"
    during = (run["t"] > tc.CLUTCH_ON + 0.01) & (run["t"] < tc.CLUTCH_ON + 0.8 * fill)
    dp_line = float(np.mean(run["p_line"][during])) - p["p_sump"]
    # fill volume over the feed orifice's flow at the drop from the line to
    # the return spring's mean pressure
    p_spring = (p["clutch_spring_preload"] + p["clutch_spring_rate"] * p["clutch_stroke"] / 2) / p["clutch_area"]
    q_feed = p["cd"] * math.pi * p["feed_diameter"] ** 2 / 4 * math.sqrt(2 * (dp_line - p_spring) / rho)
    estimate = p["clutch_area"] * p["clutch_stroke"] / q_feed
    print(f"fill {fill * 1e3:.1f} ms, orifice estimate {estimate * 1e3:.1f} ms")
    assert abs(fill / estimate - 1) < 0.1
    assert 0.1 < fill < 0.5, "outside the range of automatic-transmission clutch fills"
    # while filling, the chamber sits near the return-spring pressure
    assert np.mean(run["p_clutch"][during]) - p["p_sump"] < 1.5 * p_spring
    # once full, the clutch pressure follows the line
    late = run["t"] >= SETTLED
    assert np.max(np.abs(run["p_clutch"][late] - run["p_line"][late])) < 0.05 * p["reg_dp_set"]


def test_volume_is_conserved_across_the_coupling(run):
    v_del, v_in, v_lin = run["V_delivered"], run["V_in"], run["V_lin"]
    n = len(v_del) - 1
    # the circuit integrates exactly the Q_out it received times the step
    # (the flow's slope adds nothing over a step) plus what the pump's
    # linearisation added (V_lin): the pump's delivered volume to round-off
    # at every step
    bound = n * np.finfo(float).eps * v_del[-1]
    assert np.max(np.abs(v_in - v_lin - v_del)) <= bound, np.max(np.abs(v_in - v_lin - v_del))
    # the linearisation's volume is small: the pump's sensitivity times the
    # pressure's excursion within a step
    assert np.max(np.abs(v_lin)) < 1e-3 * v_in[-1]
    assert np.all(run["G_pump"][1:] < 0)
    # inside the circuit: received = returned to the sump + stored (Newton tolerance)
    imbalance = v_in - run["V_sump"] - run["V_stored"]
    assert np.max(np.abs(imbalance)) < 1e-9 * v_in[-1]
    # the volume reached the sump mostly through the regulator and the lube orifice
    assert run["V_sump"][-1] > 0.8 * v_in[-1]


def test_coupled_result_converges_as_the_step_shrinks(pump_fmu, circuit_fmu):
    conv = tc.convergence(pump_fmu, circuit_fmu, stop=0.4)
    print("\n" + tc.format_table(conv))
    rows = {c: [r for r in conv["rows"] if r["coupling"] == c] for c in tc.COUPLINGS}
    held, shaped = rows["held"], rows["shaped"]
    err = [r["err_p_line_bar"] for r in held]
    err_c = [r["err_p_clutch_bar"] for r in held]
    assert all(b < a for a, b in zip(err, err[1:])), err
    assert all(b < a for a, b in zip(err_c, err_c[1:])), err_c
    # first order (zero-order hold of speed, flow and line pressure): 10x
    # smaller step, at least 5x smaller error
    assert err[-1] < err[0] / 5, err
    fill = [r["err_fill_ms"] for r in held]
    assert fill[-1] < fill[0], fill
    # the shaped coupling (mean speed over the step, the pump's flow slope
    # and pressure sensitivity): the target, 0.1 bar at 1 ms, and
    # better than the held coupling at every step
    assert shaped[0]["h_ms"] == 1.0 and shaped[0]["err_p_line_bar"] < 0.1, shaped[0]
    for a, b in zip(held, shaped):
        assert b["err_p_line_bar"] < a["err_p_line_bar"], (a, b)
        assert b["err_p_clutch_bar"] < a["err_p_clutch_bar"], (a, b)
    # the reference itself hardly depends on the coupling at 0.02 ms
    assert conv["reference_coupling_spread_bar"] < 0.05


def test_example_runs_and_writes_the_plots(pump_fmu, circuit_fmu, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    r = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "transmission_cosim.py"), "--pump", pump_fmu,
         "--circuit", circuit_fmu, "--stop", "0.1", "--no-micromotion", "--out-dir", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert out["steps"] == 100
    assert out["V_in_l"] - out["V_lin_l"] == pytest.approx(out["V_delivered_l"], rel=1e-12)
    for p in out["plots"]:
        assert Path(p).stat().st_size > 10_000, p
    assert {Path(p).suffix for p in out["plots"]} == {".png", ".svg"}


def test_pump_pressure_sensitivity_through_the_directional_derivative(pump_fmu):
    """fmi2GetDirectionalDerivative(Q_out, p_out) is the dQ_out_dp_out output,
    negative, and matches the difference of the mean Q_out of the FMU
    stepped at p_out +- 0.5 bar over whole mesh periods (the FMU's own steps,
    not the sensitivity's code); asking for the derivative with respect to an
    output is refused."""
    from fmpy.fmi1 import FMICallException

    rpm, bar = 2500.0, 13.0
    tooth = 60.0 / (14 * rpm)  # mesh period of the 14-tooth driving gear, s
    h = tooth / 4

    def mean_q(p_out, sensitivity=False):
        u = tc.Unit(pump_fmu, "probe")
        try:
            u.fmu.setBoolean([u.vr["micromotion"]], [False])
            u.set(speed=rpm * tc.RPM, p_out=101325.0 + p_out, T_oil=333.15)
            u.fmu.exitInitializationMode()
            t = 0.0
            for _ in range(40):  # settle: 10 mesh periods
                u.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
                t += h
            q = []
            for _ in range(16):  # 4 mesh periods
                u.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
                t += h
                q.append(u.get("Q_out")[0])
            if not sensitivity:
                return float(np.mean(q))
            (g,) = u.fmu.getDirectionalDerivative([u.vr["Q_out"]], [u.vr["p_out"]], [1.0])
            (out,) = u.get("dQ_out_dp_out")
            (g2,) = u.fmu.getDirectionalDerivative([u.vr["Q_out"]], [u.vr["p_out"]], [2.0])
            with pytest.raises(FMICallException):
                u.fmu.getDirectionalDerivative([u.vr["Q_out"]], [u.vr["torque"]], [1.0])
            return g, out, g2
        finally:
            if sensitivity:  # the refused call leaves the instance in its error state
                u.fmu.freeInstance()
                shutil.rmtree(u.dir, ignore_errors=True)
            else:
                u.close()

    g, out, g2 = mean_q(bar * 1e5, sensitivity=True)
    fd = (mean_q((bar + 0.5) * 1e5) - mean_q((bar - 0.5) * 1e5)) / 1e5
    print(f"dQ/dp {g:.4e} m3/s/Pa, output {out:.4e}, FMU runs at +-0.5 bar {fd:.4e}")
    assert g == out and g2 == 2 * g
    assert g < 0 and abs(g / fd - 1) < 0.005, (g, fd)


@pytest.mark.parametrize(
    "name,value",
    [
        ("feed_diameter", 1e30),
        ("exhaust_diameter", 1e30),
        ("reg_diameter", 1e30),
        ("line_volume", 1e30),
        ("bulk_modulus", 1e30),
        ("reg_mass", 1e30),
        ("reg_spring_rate", 1e30),
        ("reg_damping", 1e30),
        ("clutch_area", 1e30),
        ("clutch_pack_stiffness", 1e30),
        ("p_line_start", 1e30),
        ("reg_dp_set", 1e30),
        ("reg_damping", 0.0),
        ("clutch_spring_rate", 0.0),
        ("clutch_spring_preload", 0.0),
        ("Q_pump", 2.0),
    ],
)
def test_circuit_values_outside_their_range_are_refused_naming_them(circuit_fmu, tmp_path, name, value):
    """Every parameter and input has a physical range (the XML's min/max);
    a value outside it is fmi2Error at fmi2SetReal naming the variable."""
    import fmu_driver as d
    from fmpy import extract
    from fmpy.fmi1 import FMICallException

    unzipdir = extract(circuit_fmu, unzipdir=str(tmp_path / "fmu"))
    md, fmu = d.slave(unzipdir, "ranges")
    v = {x.name: x for x in md.modelVariables}
    assert float(v[name].min) <= float(v[name].start) <= float(v[name].max)
    rec = d.Recorder()
    fmu.instantiate(callbacks=rec.callbacks)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    with pytest.raises(FMICallException):
        fmu.setReal([v[name].valueReference], [value])
    assert rec.has(3, "fmi2SetReal", name, "outside its range"), rec.messages
    # a value within the range is taken, and the circuit runs
    fmu.reset()
    fmu.setupExperiment(startTime=0.0, stopTime=2e-3)
    fmu.enterInitializationMode()
    fmu.setReal([v[name].valueReference], [float(v[name].start)])
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)
    fmu.doStep(1e-3, 1e-3)
    with pytest.raises(FMICallException):  # past the stop time
        fmu.doStep(2e-3, 1e-3)
    assert rec.has(3, "fmi2DoStep", "beyond stopTime"), rec.messages
    fmu.freeInstance()
