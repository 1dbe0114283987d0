"""A production-population study on Dask: 10,000 pumps drawn with the
paper's clearance statistics, simulated at the paper's 14 conditions on a
local cluster (or a scheduler's workers), with the yield against a
specification and the Sobol indices of the four clearances; writes the
CDFs and a tornado figure (matplotlib) and prints one JSON object.

    .venv/bin/python examples/montecarlo_dask.py --out-dir out/mc            # 10,000 pumps, local cluster of 2 workers
    .venv/bin/python examples/montecarlo_dask.py --pumps 200 --out-dir out/mc --scheduler tcp://10.0.0.5:8786

The chunk files in OUT_DIR/chunks make the study resumable: run the same
command again after an interruption and only the missing chunks run.
Three runs per pump and condition (the pump and its share of the
pick-freeze runs of the sensitivity indices): 10,000 pumps at 14
conditions are 420,000 simulations, about half an hour on two cores
(29 min on the 2-core machine of docs/benchmarks.md).
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np

import gearpump


def cdf_figure(record, runs, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    conds = record["summary"]["conditions"]
    n, nc = record["pumps"], len(conds)
    fig, axes = plt.subplots(1, 3, figsize=(15, 5))
    for ax in axes:
        ax.set_prop_cycle(color=plt.cm.tab20.colors)  # 14 conditions, 14 colours
    for ax, (key, label) in zip(axes, [("eta_v", "volumetric efficiency"),
                                       ("flow_lpm", "flow from its median at the condition, %"),
                                       ("torque_nm", "torque from its median at the condition, %")]):
        v = np.asarray(runs[key]).reshape(-1, nc)[:n]
        for c, cond in enumerate(conds):
            x = np.sort(v[:, c][np.isfinite(v[:, c])])
            if key != "eta_v" and len(x):
                x = 100.0 * (x / np.median(x) - 1.0)
            cc = cond["condition"]
            ax.step(x, np.arange(1, len(x) + 1) / len(x), where="post",
                    label=f"{cc['pressure_bar']:g} bar, {cc['speed_rpm']:g} rpm, {cc['temp_c']:g} degC")
        ax.set_xlabel(label)
        ax.set_ylabel("share of pumps at or below")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=6)
    fig.suptitle(f"{n} pumps")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def tornado_figure(record, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = record["summary"]
    focus = s["conditions"][s["focus"]]
    sens = focus["sensitivity"]
    if not sens or not sens["eta_v"]:
        return False
    names = record["clearances"]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, key in zip(axes, ["eta_v", "torque_nm"]):
        idx = sens[key] or [{"first": 0.0, "total": 0.0}] * 4
        order = np.argsort([i["first"] for i in sens["eta_v"]])
        y = np.arange(4)
        ax.barh(y, [idx[k]["first"] for k in order], height=0.6, label="first order")
        ax.barh(y, [idx[k]["total"] for k in order], height=0.8, fill=False, label="total")
        ax.set_yticks(y, [names[k] for k in order])
        ax.set_xlim(0, 1)
        cc = focus["condition"]
        ax.set_title(f"{key} at {cc['pressure_bar']:g} bar, {cc['speed_rpm']:g} rpm, {cc['temp_c']:g} degC")
        ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pumps", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--conditions", default="paper", help="paper or a CSV (pressure_bar,speed_rpm,temp_c)")
    ap.add_argument("--spec", action="append", default=None,
                    help='e.g. "eta_v>=0.72@500rpm,30bar,120degC" (repeatable)')
    ap.add_argument("--scheduler", default="local", help="local, or a scheduler address")
    ap.add_argument("--workers", type=int, default=2, help="workers of the local cluster")
    ap.add_argument("--chunk", type=int, default=16, help="pumps per Dask task")
    ap.add_argument("--no-micromotion", action="store_true")
    ap.add_argument("--out-dir", default=".")
    a = ap.parse_args()
    out = Path(a.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    spec = a.spec or ["eta_v>=0.72@500rpm,30bar,120degC"]
    t0 = time.perf_counter()
    r = gearpump.montecarlo(a.pumps, a.seed, conditions=a.conditions, spec=spec,
                            micromotion=not a.no_micromotion, scheduler=a.scheduler,
                            workers=a.workers, chunk=a.chunk, out=out / "chunks")
    wall = time.perf_counter() - t0
    rec = r["record"]
    (out / "montecarlo.json").write_text(json.dumps(rec, indent=1) + "\n")
    cdf_figure(rec, r["runs"], out / "cdf.png")
    figures = ["cdf.png"]
    if tornado_figure(rec, out / "tornado.png"):
        figures.append("tornado.png")
    s = rec["summary"]
    print(json.dumps({
        "pumps": rec["pumps"],
        "runs": s["runs"],
        "failed_runs": s["failed_runs"],
        "chunks_computed": r["chunks_computed"],
        "chunks_reused": r["chunks_reused"],
        "wall_s": round(wall, 2),
        "yields": {x["spec"]["text"]: x["yield"]["share"] for x in s["specs"]},
        "eta_v_p5_p50_p95": {
            f"{c['condition']['pressure_bar']:g}bar,{c['condition']['speed_rpm']:g}rpm,{c['condition']['temp_c']:g}degC":
            [c["eta_v"]["percentiles"][i] for i in (1, 2, 3)] for c in s["conditions"]},
        "files": ["montecarlo.json"] + figures,
    }))


if __name__ == "__main__":
    main()
