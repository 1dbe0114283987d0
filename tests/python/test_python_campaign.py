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
