"""gearpump.campaign and gearpump.diagnose from Python: the command line's
runs, their --json objects as Python objects, bad input as ValueError with
the CLI's message."""

import csv

import pytest

import gearpump

HEADER = ["sample", "tip_clearance_drive_um", "tip_clearance_driven_um",
          "bearing_clearance_drive_um", "bearing_clearance_driven_um",
          "pressure_bar", "speed_rpm", "temp_c", "flow_lpm", "torque_nm"]


def test_campaign_returns_its_json_and_writes_its_files(tmp_path):
    data = tmp_path / "c.csv"
    with open(data, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(HEADER)
        w.writerow(["A", 30, 31, 12, 13, 30, 1000, 60, 13.9, ""])
        w.writerow(["B", 32, 33, 12, 13, 30, 1000, 60, 13.8, ""])
    r = gearpump.campaign(data, tmp_path / "out", jobs=1, micromotion=False)
    assert r["tests"] == 2 and r["samples"] == 2 and r["failed"] == []
    assert r["simulated"] == 2 and r["reused"] == 0
    # each row's simulated eta_v is simulate's for its clearances
    rows = list(csv.DictReader(open(tmp_path / "out" / "tests.csv")))
    one = gearpump.simulate(1000, 30, 60, sample_clearances_um=[32, 33, 12, 13],
                            micromotion=False)
    assert abs(float(rows[1]["flow_lpm_sim"]) - one["flow_lpm"]) < 1e-9 * one["flow_lpm"]
    c = r["conditions"][0]
    assert c["pressure_bar"] == 30.0 and c["n_samples"] == 2
    assert abs(c["d_mean"] - (float(rows[0]["d"]) + float(rows[1]["d"])) / 2) < 1e-12


def test_campaign_and_diagnose_refuse_bad_input(tmp_path):
    with pytest.raises(ValueError, match="nonexistent.csv"):
        gearpump.campaign(tmp_path / "nonexistent.csv", tmp_path / "o")
    with pytest.raises(ValueError, match="nonexistent.csv"):
        gearpump.diagnose(tmp_path / "nonexistent.csv", tmp_path / "o")
    data = tmp_path / "bad.csv"
    data.write_text(",".join(HEADER) + "\nA,30,31,12,13,30,-5,60,13.9,\n")
    with pytest.raises(ValueError, match="row 1, column speed_rpm"):
        gearpump.campaign(data, tmp_path / "o")
    good = tmp_path / "good.csv"
    good.write_text(",".join(HEADER) + "\nA,30,31,12,13,30,1000,60,13.9,\n")
    with pytest.raises(ValueError, match="jobs: must be >= 1"):
        gearpump.campaign(good, tmp_path / "o", jobs=0)


def _good(tmp_path):
    good = tmp_path / "good.csv"
    good.write_text(",".join(HEADER) + "\nA,30,31,12,13,30,1000,60,13.9,\n")
    return good


@pytest.mark.parametrize("jobs", [-1, -(2**70)])
def test_negative_jobs_is_a_value_error_naming_it(tmp_path, jobs):
    # was: OverflowError: can't convert negative int to unsigned
    for f in (gearpump.campaign, gearpump.diagnose):
        with pytest.raises(ValueError, match=rf"^jobs: must be >= 1, got {jobs}$"):
            f(_good(tmp_path), tmp_path / "o", jobs=jobs)


def test_jobs_above_the_cores_is_clamped_with_a_warning(tmp_path):
    with pytest.warns(UserWarning, match=r"^jobs: 100000 is more than the \d+ cores"):
        r = gearpump.campaign(_good(tmp_path), tmp_path / "o", jobs=100000, micromotion=False)
    assert r["failed"] == [] and r["simulated"] == 1


@pytest.mark.parametrize("out", ["/proc/nope/x", "FILE"])
def test_an_output_folder_that_cannot_be_made_names_out(tmp_path, out):
    # was: RuntimeError (the CLI exits 2 naming --out: its check_out)
    if out == "FILE":
        out = tmp_path / "a-file"
        out.write_text("x")
    for f in (gearpump.campaign, gearpump.diagnose):
        with pytest.raises(ValueError, match=r"^out: "):
            f(_good(tmp_path), out)


@pytest.mark.parametrize("kwargs, name", [
    (dict(data=b"/tmp/c.csv"), "data"),
    (dict(out=None), "out"),
    (dict(design=b"/tmp/x"), "design"),
    (dict(set=[1]), "set[0]"),
    (dict(micromotion=0), "micromotion"),
    (dict(jobs="2"), "jobs"),
    (dict(jobs=True), "jobs"),
])
def test_a_wrong_type_is_a_type_error_naming_it(tmp_path, kwargs, name):
    args = dict(data=_good(tmp_path), out=tmp_path / "o", **{})
    args.update(kwargs)
    with pytest.raises(TypeError) as e:
        gearpump.campaign(args.pop("data"), args.pop("out"), **args)
    assert str(e.value).startswith(f"{name}: "), str(e.value)
