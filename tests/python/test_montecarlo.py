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
    (dict(jobs=0), "jobs: must be >= 1, got 0"),
    # negative or huge counts: the value is wrong, not the type (were
    # OverflowError, or "study: pumps: wrong type (<class 'int'>)")
    (dict(jobs=-1), "jobs: must be >= 1, got -1"),
    (dict(pumps=-1), "pumps: must be in [4, 10000000] (the sensitivity indices need two "
                     "pairs), got -1"),
    (dict(pumps=2**70, sensitivity=False), "pumps: must be in [1, 10000000], got "),
    (dict(seed=-1), "seed: must be in [0, 18446744073709551615], got -1"),
    (dict(seed=2**70), "seed: must be in [0, 18446744073709551615], got 1180591620717411303424"),
])
def test_bad_input_raises_value_error_naming_it(kwargs, says):
    with pytest.raises(ValueError) as e:
        gearpump.montecarlo(**dict(dict(pumps=4, conditions=[(30.0, 1000.0, 60.0)]), **kwargs))
    assert says in str(e.value)


SMALL = dict(pumps=1, sensitivity=False, conditions=[(30.0, 1000.0, 60.0)], micromotion=False)


@pytest.mark.parametrize("kwargs, name", [
    (dict(pumps="4"), "pumps"),
    (dict(pumps=4.0), "pumps"),
    (dict(seed=True), "seed"),
    (dict(conditions=None), "conditions"),
    (dict(conditions=(30.0, 1000.0, 60.0)), "conditions[0]"),
    (dict(conditions=[(30.0, "1000", 60.0)]), "conditions[0][1]"),
    (dict(conditions=b"paper"), "conditions"),
    (dict(set=[1]), "set[0]"),
    (dict(spec=[b"x"]), "spec[0]"),
    (dict(design=b"/tmp/x"), "design"),
    (dict(fit=1), "fit"),
    (dict(sensitivity=1), "sensitivity"),
    (dict(micromotion=0), "micromotion"),
    (dict(jobs="2"), "jobs"),
    (dict(out=b"/tmp/x"), "out"),
])
def test_a_wrong_type_is_a_type_error_naming_it(kwargs, name):
    with pytest.raises(TypeError) as e:
        gearpump.montecarlo(**dict(SMALL, **kwargs))
    assert str(e.value).startswith(f"{name}: "), str(e.value)


def test_negative_chunk_is_a_value_error_naming_it(tmp_path):
    # was: OverflowError: can't convert negative int to unsigned
    with pytest.raises(ValueError, match=r"^chunk: must be >= 1, got -1$"):
        gearpump.montecarlo(**SMALL, out=tmp_path / "o", chunk=-1)
    with pytest.raises(ValueError, match=r"^chunk: must be >= 1, got 0$"):
        gearpump.montecarlo(**SMALL, out=tmp_path / "o", chunk=0)
    with pytest.raises(ValueError, match=r"^chunk: must be >= 1, got -1$"):
        gearpump.montecarlo(**SMALL, out=tmp_path / "d", chunk=-1, scheduler="local")
    with pytest.raises(ValueError, match=r"^jobs: must be >= 1, got -1$"):
        gearpump.montecarlo(**SMALL, out=tmp_path / "o", jobs=-1)


def test_jobs_above_the_cores_is_clamped_with_a_warning(tmp_path):
    with pytest.warns(UserWarning, match=r"^jobs: 100000 is more than the \d+ cores"):
        a = gearpump.montecarlo(**SMALL, jobs=100000)
    with pytest.warns(UserWarning, match=r"^jobs: 100000 is more than the \d+ cores"):
        b = gearpump.montecarlo(**SMALL, out=tmp_path / "o", jobs=100000)
    same_runs(a["runs"], b["runs"])


def test_a_single_spec_string_is_one_spec():
    # was split into characters: "spec: `e`: no `@`"
    one = gearpump.montecarlo(**SMALL, spec="eta_v>=0.8@1000rpm,30bar,60degC")
    ref = gearpump.montecarlo(**SMALL, spec=["eta_v>=0.8@1000rpm,30bar,60degC"])
    assert len(one["record"]["summary"]["specs"]) == 1
    assert one["record"] == ref["record"]
    two = gearpump.montecarlo(**SMALL, set="clearance.lateral_um=14")
    assert two["record"]["set"] == ["clearance.lateral_um=14"]


def test_an_output_folder_that_cannot_be_made_names_out(tmp_path):
    with pytest.raises(ValueError, match=r"^out: /proc/nope/x: "):
        gearpump.montecarlo(**SMALL, out="/proc/nope/x")
    with pytest.raises(ValueError, match=r"^out: /proc/nope/x: "):
        gearpump.montecarlo(**SMALL, out="/proc/nope/x", scheduler="local")


def test_summarize_takes_integer_columns_and_names_a_wrong_one():
    from gearpump import _gearpump

    study = dict(design=None, set=None, pumps=1, seed=1, fit=None, distributions=None,
                 conditions=[(30.0, 1000.0, 60.0), (30.0, 500.0, 60.0)], spec=None,
                 sensitivity=False, micromotion=False)
    z = np.zeros(2)
    ref = _gearpump.montecarlo_summarize(study, z, z, z)
    # was: "type mismatch: from=int64, to=float64"
    assert _gearpump.montecarlo_summarize(study, np.zeros(2, dtype=int), z, z) == ref
    for bad, name in ((np.zeros(2, dtype=bool), "eta_v"), (np.zeros(2, dtype=complex),
                                                            "eta_v"), ([0.0, 0.0], "eta_v")):
        with pytest.raises(TypeError, match=f"^{name}: expected a 1-D numpy array of floats"):
            _gearpump.montecarlo_summarize(study, bad, z, z)
    with pytest.raises(TypeError, match="^torque_nm: "):
        _gearpump.montecarlo_summarize(study, z, z, np.zeros((2, 1)))


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
