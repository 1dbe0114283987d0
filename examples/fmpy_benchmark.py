"""Real-time factor of GearPump.fmu stepped from fmpy (FMU2Slave) at 1 ms
communication steps, 30 bar (gauge), 60 degC, micromotion on, at 1000 and
4000 rpm. The factor is simulated time over the wall time of the doStep /
getReal loop (instantiation and the periodic start are timed separately):
> 1 means faster than real time. `real_time_factor_cpu` uses the process's
CPU time instead (less sensitive to other load on the machine).

    python examples/fmpy_benchmark.py [--fmu target/fmu/GearPump.fmu]
                                      [--duration 1.0] [--step 0.001] [--speeds 1000 4000]
                                      [--no-micromotion] [--fidelity lp|map] [--ripple]
                                      [--ramp]

`--fidelity map` steps the mean-value map (parameter fidelity = 2; issue 16
point 3), `--ripple` with its mesh ripple (map_ripple). `--ramp` sets the
inputs before every step as a drive cycle does (speed from each of
`--speeds` to twice it, delivery pressure 30 -> 40 bar over the span).

Prints one JSON object on stdout. Benchmarks measure; tests only check that
this script runs.
"""

import argparse
import json
import math
import os
import shutil
import tempfile
import time
from pathlib import Path

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parents[1]
P_ATM = 101325.0


def run(md, unzipdir, rpm, duration, h, micromotion=True, fidelity="lp", ripple=False,
        ramp=False):
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
    t0 = time.perf_counter()
    fmu.instantiate()
    t_inst = time.perf_counter() - t0
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setBoolean([vr["micromotion"]], [micromotion])
    if fidelity == "map":
        fmu.setInteger([vr["fidelity"]], [2])
        fmu.setBoolean([vr["map_ripple"]], [ripple])
    fmu.setReal([vr["speed"], vr["p_in"], vr["p_out"], vr["T_oil"]],
                [rpm * math.pi / 30.0, P_ATM, P_ATM + 30e5, 333.15])
    t0 = time.perf_counter()
    fmu.exitInitializationMode()
    t_init = time.perf_counter() - t0
    outs = [vr["Q_out"], vr["torque"]]
    n = int(round(duration / h))
    t = 0.0
    t0, c0 = time.perf_counter(), time.process_time()
    for k in range(n):
        if ramp:
            # a drive cycle's inputs: speed to twice its start and the
            # delivery pressure from 30 to 40 bar over the span, set anew
            # before every step
            s = k / n
            fmu.setReal([vr["speed"], vr["p_out"]],
                        [rpm * (1.0 + s) * math.pi / 30.0, P_ATM + (30.0 + 10.0 * s) * 1e5])
        fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        t += h
        fmu.getReal(outs)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    v = fmu.getReal([vr["V_delivered"]])[0]
    fmu.terminate()
    fmu.freeInstance()
    return {
        "speed_rpm": rpm,
        "simulated_s": t,
        "wall_s": wall,
        "real_time_factor": t / wall,
        "cpu_s": cpu,
        "real_time_factor_cpu": t / cpu,
        "instantiate_s": t_inst,
        "initialize_s": t_init,
        "mean_flow_lpm": v / t * 6e4,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fmu", default=os.environ.get("GEARPUMP_FMU", str(ROOT / "target/fmu/GearPump.fmu")))
    ap.add_argument("--duration", type=float, default=1.0, help="simulated time per speed, s")
    ap.add_argument("--step", type=float, default=1e-3, help="communication step, s")
    ap.add_argument("--speeds", type=float, nargs="+", default=[1000.0, 4000.0], help="rpm")
    ap.add_argument("--no-micromotion", action="store_true", help="gear centres fixed")
    ap.add_argument("--fidelity", choices=["lp", "map"], default="lp", help="model fidelity")
    ap.add_argument("--ripple", action="store_true", help="map fidelity: with the mesh ripple")
    ap.add_argument("--ramp", action="store_true",
                    help="inputs set before every step: speed from each of --speeds to twice "
                         "it, delivery 30 -> 40 bar over --duration")
    ap.add_argument("--out-dir", default=None,
                    help="also write the result as fmpy_benchmark.json into this folder")
    args = ap.parse_args()
    md = read_model_description(args.fmu)
    unzipdir = extract(args.fmu, unzipdir=tempfile.mkdtemp(prefix="gearpump-bench-"))
    try:
        results = [run(md, unzipdir, rpm, args.duration, args.step, not args.no_micromotion,
                       args.fidelity, args.ripple, args.ramp)
                   for rpm in args.speeds]
    finally:
        shutil.rmtree(unzipdir, ignore_errors=True)
    text = json.dumps({"step_s": args.step, "pressure_bar": 30.0, "temp_c": 60.0,
                       "micromotion": not args.no_micromotion, "fidelity": args.fidelity,
                       "ripple": args.ripple, "ramp": args.ramp, "runs": results})
    if args.out_dir is not None:
        out_dir = Path(args.out_dir)
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "fmpy_benchmark.json").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
