"""gearpump.montecarlo: the same study in this process, through the command
line's journaled path and on a Dask LocalCluster of two workers gives the
same numbers to the bit; the Dask study resumes from its Parquet chunks;
bad input raises ValueError naming what is wrong.

Small on purpose (a few pumps at one or two conditions, micromotion off
where the test is about plumbing, not physics): the whole Python suite runs
inside CI's budget.
"""

import numpy as np
import pytest

import gearpump

pytest.importorskip("distributed")
pytest.importorskip("pyarrow")

STUDY = dict(
    pumps=6,
    seed=7,
    conditions=[(30.0, 1000.0, 60.0), (30.0, 500.0, 120.0)],
    spec=["eta_v>=0.72@500rpm,30bar,120degC"],
    micromotion=False,
)


def same_runs(a, b):
    for k in ("eta_v", "flow_lpm", "torque_nm"):
        x, y = np.asarray(a[k]), np.asarray(b[k])
        assert x.dtype == y.dtype == np.float64
        # bit for bit (NaN included)
        assert x.tobytes() == y.tobytes(), k
    assert [tuple(e) for e in a["errors"]] == [tuple(e) for e in b["errors"]]


@pytest.fixture(scope="module")
def single():
    return gearpump.montecarlo(**STUDY, jobs=2)


def test_single_process_study_is_summarised(single):
    rec = single["record"]
    s = rec["summary"]
    # 6 pumps + 4 hybrids per pair (3 pairs), at 2 conditions
    assert s["runs"] == (6 + 12) * 2 == len(single["runs"]["eta_v"])
    assert s["pumps"] == 6 and s["pairs"] == 3
    eta = np.asarray(single["runs"]["eta_v"]).reshape(-1, 2)[:6, 1]
    # the yield counted here from the runs
    y = s["specs"][0]["yield"]
    assert y["pass"] == int(np.sum(eta >= 0.72)) and y["n"] == 6
    # numpy's default percentile is the same definition (linear, type 7)
    p = s["conditions"][1]["eta_v"]["percentiles"]
    assert np.allclose(p, np.percentile(eta, rec["percentiles"]), rtol=1e-14, atol=0)
    assert len(s["conditions"][0]["sensitivity"]["eta_v"]) == 4


def test_dask_local_cluster_of_two_workers_equals_single_process(single, tmp_path):
    done = []
    d = gearpump.montecarlo(**STUDY, scheduler="local", workers=2, out=tmp_path / "dask",
                            chunk=4, progress=lambda i, n: done.append((i, n)))
    assert d["chunks_computed"] == 5 and d["chunks_reused"] == 0
    assert done[-1] == (5, 5)
    same_runs(single["runs"], d["runs"])
    assert d["record"] == single["record"]
    files = sorted(p.name for p in (tmp_path / "dask").iterdir())
    assert files == ["chunk-%06d.parquet" % c for c in range(5)] + ["study.json"]

    # interrupted: two chunks lost; the rerun computes those only
    (tmp_path / "dask" / "chunk-000001.parquet").unlink()
    (tmp_path / "dask" / "chunk-000003.parquet").unlink()
    r = gearpump.montecarlo(**STUDY, scheduler="local", workers=2, out=tmp_path / "dask",
                            chunk=4)
    assert (r["chunks_computed"], r["chunks_reused"]) == (2, 3)
    same_runs(single["runs"], r["runs"])
    assert r["record"] == single["record"]

    # another study in the same folder starts afresh
    other = dict(STUDY, seed=8)
    o = gearpump.montecarlo(**other, scheduler="local", workers=1, out=tmp_path / "dask",
                            chunk=4)
    assert o["chunks_reused"] == 0
    assert o["record"] != single["record"]


def test_journaled_path_equals_single_process(single, tmp_path):
    r = gearpump.montecarlo(**STUDY, out=tmp_path / "cli", jobs=2)
    assert r["simulated"] == 36 and r["reused"] == 0
    same_runs(single["runs"], r["runs"])
    assert r["record"] == single["record"]
    names = {p.name for p in (tmp_path / "cli").iterdir()}
    assert {"montecarlo.json", "cdf.svg", "tornado.svg", "pumps.csv"} <= names
    assert "montecarlo-journal.jsonl" not in names


@pytest.mark.parametrize("kwargs, says", [
    (dict(pumps=3), "pumps: must be in [4,"),
    (dict(spec=["eta_v>0.8"]), "spec: `eta_v>0.8`: no `@`"),
    (dict(conditions=[(30.0, 1000.0, 900.0)]), "900 degC is outside"),
    (dict(set=["clearance.nonsense=1"]), "clearance.nonsense"),
    (dict(distributions="/nonexistent/d.toml"), "distributions: /nonexistent/d.toml"),
    (dict(conditions=[(30.0, 1000.0)]), "conditions: expected"),
    (dict(jobs=0), "jobs: must be at least 1"),
])
def test_bad_input_raises_value_error_naming_it(kwargs, says):
    with pytest.raises(ValueError) as e:
        gearpump.montecarlo(**dict(dict(pumps=4, conditions=[(30.0, 1000.0, 60.0)]), **kwargs))
    assert says in str(e.value)


def test_dask_needs_a_folder():
    with pytest.raises(ValueError, match="out: "):
        gearpump.montecarlo(pumps=4, scheduler="local")


def test_example_script_runs_a_small_study_and_resumes(tmp_path):
    import json
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    cond = tmp_path / "c.csv"
    cond.write_text("pressure_bar,speed_rpm,temp_c\n30,1000,60\n30,500,120\n")
    args = [sys.executable, str(root / "examples" / "montecarlo_dask.py"), "--pumps", "4",
            "--conditions", str(cond), "--no-micromotion", "--chunk", "4",
            "--out-dir", str(tmp_path / "o")]
    first = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    assert first["runs"] == (4 + 8) * 2 and first["chunks_computed"] == 3
    for f in first["files"]:
        assert (tmp_path / "o" / f).stat().st_size > 0, f
    again = json.loads(subprocess.run(args, check=True, capture_output=True, text=True).stdout)
    assert (again["chunks_computed"], again["chunks_reused"]) == (0, 3)
    assert again["yields"] == first["yields"]
