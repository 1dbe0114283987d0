"""Throughput and scaling of the Python package and Dask (docs/benchmarks.md).

    .venv/bin/python scripts/bench-montecarlo.py [--pumps 20] [--repeat 1] [--skip-dask]

Measures, back to back, on this machine:

1. ``throughput``: simulations per second per core: the same rows (pumps
   drawn with the paper's statistics at the paper's 14 conditions,
   micromotion on, no measured torque) through ``simulate_batch(jobs=1)``
   and through ``gearpump campaign --jobs 1`` (the rows written as a
   campaign CSV with empty torque cells, so both run the same work; the
   pumps drawn with the paper's statistics around the bundled design's
   clearances, rounded to 0.1 um). Both as rows over wall time; the
   campaign's includes starting the process, building the pump (tables
   from the cache) and writing its outputs, the batch's the call alone
   (the pump built once before).
2. ``dask``: the same Monte Carlo study on a LocalCluster of one worker and
   of two workers (one thread each), the speed-up, and the per-chunk
   overhead: a round trip of an empty chunk through the cluster (task
   submission, pickling, the worker's call, the result), median of 20.
   Rates are given per wall second with one thread (per core on a quiet
   machine) and per CPU second (what the process was given: on a shared,
   loaded machine the wall rate measures the share, the CPU rate the work).
3. ``projection``: wall time on W workers of a study of R runs in chunks of
   k runs: ``ceil(R / k / W) (o + k t)``, with ``t`` the measured seconds
   per run on one worker and ``o`` the measured overhead per chunk; the
   speed-up at W = 100 against one worker.

Prints one JSON object.
"""

import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import gearpump

ROOT = Path(__file__).resolve().parents[1]


def paper_conditions():
    return [(p, 1000.0, t) for t in (60.0, 120.0) for p in (10.0, 20.0, 30.0, 40.0)] + \
        [(30.0, n, t) for t in (60.0, 120.0) for n in (500.0, 2000.0, 4000.0)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pumps", type=int, default=20)
    ap.add_argument("--dask-pumps", type=int, default=24)
    ap.add_argument("--chunk", type=int, default=4)
    ap.add_argument("--skip-dask", action="store_true")
    ap.add_argument("--gearpump", default=str(ROOT / "target" / "release" / "gearpump"))
    a = ap.parse_args()
    out = {}
    conds = paper_conditions()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        # --- 1. the same rows both ways
        rng = np.random.default_rng(1)
        import tomllib

        c = tomllib.loads((ROOT / "designs" / "seed_pump.toml").read_text())["clearance"]
        nominal = np.array([c["tip_um"], c["tip_um"], c["bearing_um"], c["bearing_um"]])
        rows = []
        for i in range(a.pumps):
            h = nominal * (1 + np.array([0.025, 0.035, 0.10, 0.17]) + 0.06 * rng.standard_normal(4))
            h = np.round(h, 1)
            for (p, n, t) in conds:
                rows.append((f"P{i:03d}", *h, p, n, t))
        data = tmp / "rows.csv"
        with open(data, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["sample", "tip_clearance_drive_um", "tip_clearance_driven_um",
                        "bearing_clearance_drive_um", "bearing_clearance_driven_um",
                        "pressure_bar", "speed_rpm", "temp_c", "flow_lpm", "torque_nm"])
            for r in rows:
                w.writerow([*r, 10.0, ""])
        cols = {
            "tip1_um": np.array([r[1] for r in rows]),
            "tip2_um": np.array([r[2] for r in rows]),
            "bearing1_um": np.array([r[3] for r in rows]),
            "bearing2_um": np.array([r[4] for r in rows]),
            "pressure_bar": np.array([r[5] for r in rows]),
            "speed_rpm": np.array([r[6] for r in rows]),
            "temp_c": np.array([r[7] for r in rows]),
        }
        gearpump.simulate_batch({k: v[:1] for k, v in cols.items()}, jobs=1)  # tables cached
        import resource

        t0, c0 = time.perf_counter(), time.process_time()
        b = gearpump.simulate_batch(cols, jobs=1)
        t_batch, cpu_batch = time.perf_counter() - t0, time.process_time() - c0
        t0 = time.perf_counter()
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([a.gearpump, "campaign", "--data", str(data), "--out", str(tmp / "c"),
                        "--jobs", "1"], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        t_cli = time.perf_counter() - t0
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu_cli = (ru1.ru_utime + ru1.ru_stime) - (ru0.ru_utime + ru0.ru_stime)
        flow_cli = []
        with open(tmp / "c" / "tests.csv") as f:
            for r in csv.DictReader(f):
                flow_cli.append(float(r["flow_lpm_sim"]))
        out["throughput"] = {
            "rows": len(rows),
            "conditions": "the paper's 14, micromotion on",
            "simulate_batch_jobs1_s": round(t_batch, 3),
            "simulate_batch_points_per_s_per_core": round(len(rows) / t_batch, 1),
            "campaign_jobs1_wall_s": round(t_cli, 3),
            "campaign_points_per_s_per_core": round(len(rows) / t_cli, 1),
            "simulate_batch_points_per_cpu_s": round(len(rows) / cpu_batch, 1),
            "campaign_points_per_cpu_s": round(len(rows) / cpu_cli, 1),
            "same_flows": bool(np.allclose(b["flow_lpm"], flow_cli, rtol=1e-12, atol=0)),
        }
        if a.skip_dask:
            print(json.dumps(out))
            return
        # --- 2. dask 1 vs 2 workers
        from distributed import Client, LocalCluster

        study = dict(pumps=a.dask_pumps, seed=3, conditions=conds[:7], sensitivity=True)
        res = {}
        for workers in (1, 2):
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            client = Client(cluster)
            try:
                # warm: every worker builds its pump once (as in a long study)
                client.run(lambda: gearpump._gearpump.montecarlo_chunk(
                    dict(study), 0, 1, jobs=1))
                t0 = time.perf_counter()
                r = gearpump.montecarlo(**study, scheduler=client, out=tmp / f"d{workers}",
                                        chunk=a.chunk)
                res[workers] = time.perf_counter() - t0
                if workers == 1:
                    from gearpump.distributed import _run_chunk
                    lat = []
                    for _ in range(20):
                        t0 = time.perf_counter()
                        client.submit(_run_chunk, study, 0, 0, 0, 1, pure=False).result()
                        lat.append(time.perf_counter() - t0)
                    overhead = float(np.median(lat))
                    runs = r["record"]["summary"]["runs"]
            finally:
                client.close()
                cluster.close()
        t_run = res[1] / runs
        out["dask"] = {
            "study": {"pumps": a.dask_pumps, "conditions": 7, "runs": runs, "chunk_items": a.chunk,
                      "runs_per_chunk": a.chunk * 7},
            "one_worker_s": round(res[1], 3),
            "two_workers_s": round(res[2], 3),
            "speedup": round(res[1] / res[2], 3),
            "overhead_per_chunk_s": round(overhead, 4),
            "seconds_per_run_one_worker": round(t_run, 5),
        }
        k = 16 * 14  # the example's chunk: 16 items at 14 conditions
        R = 10_000 * 3 * 14
        tw = lambda w: math.ceil(R / k / w) * (overhead + k * t_run)
        out["projection"] = {
            "runs": R, "runs_per_chunk": k,
            "one_worker_h": round(tw(1) / 3600, 2),
            "hundred_workers_min": round(tw(100) / 60, 2),
            "speedup_100": round(tw(1) / tw(100), 1),
        }
    print(json.dumps(out))


if __name__ == "__main__":
    main()
