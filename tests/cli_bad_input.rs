//! Inputs far outside any pump's range are refused before the solver sees
//! them (exit 2, the flag, key or cell named), and operating points where the
//! pump delivers nothing or backwards are said plainly (`warnings`). The
//! battery of issue 18: a table of bad argument vectors and bad CSV and TOML
//! contents, each refused with exit 2 and a message naming what is wrong;
//! rows that cannot be simulated make the command fail; `--jobs` is bounded.

mod campaign_common;
use campaign_common::{gearpump, with_args, Scratch, POINT_1000_30_60};

/// Exit code and stderr of a run.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = gearpump(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn absurd_simulate_inputs_are_refused_naming_the_flag() {
    // each case: the flags that differ from 1000 rpm / 30 bar / 60 degC,
    // and the name the message must carry
    let cases: &[(&str, &str, &str)] = &[
        ("--speed", "1e9", "--speed"),
        ("--speed", "1e300", "--speed"),
        ("--speed", "1e-9", "--speed"),
        ("--speed", "NaN", "--speed"),
        ("--pressure", "1e6", "--pressure"),
        ("--pressure", "-30", "--pressure"),
        ("--inlet-pressure", "1e6", "--inlet-pressure"),
        ("--sample-clearances", "1e6,30,12,12", "--sample-clearances"),
        ("--set", "clearance.tip_um=1e6", "clearance.tip_um"),
        ("--set", "clearance.lateral_um=0", "clearance.lateral_um"),
        // once past the design into the solver (exit 1, "Newton did not
        // converge", "non-finite residual")
        (
            "--set",
            "oil.density_20c_kg_m3=1e300",
            "oil.density_20c_kg_m3",
        ),
        (
            "--set",
            "oil.bulk_modulus_gpa=1e-300",
            "oil.bulk_modulus_gpa",
        ),
        ("--set", "oil.nu_40c_cst=1e-9", "oil.nu_40c_cst"),
        // once accepted and run (exit 0), or named as the tip radius
        ("--set", "gears.face_width_mm=1e9", "gears.face_width_mm"),
        (
            "--set",
            "casing.port_area_mm2=1e-12",
            "casing.port_area_mm2",
        ),
        (
            "--set",
            "gears.backlash_normal_mm=100",
            "gears.backlash_normal_mm",
        ),
    ];
    for &(flag, value, name) in cases {
        let mut args = vec!["simulate", "--json"];
        for (f, v) in [("--speed", "1000"), ("--pressure", "30"), ("--temp", "60")] {
            args.extend([f, if f == flag { value } else { v }]);
        }
        if !["--speed", "--pressure"].contains(&flag) {
            args.extend([flag, value]);
        }
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{flag} {value}: {err}");
        assert!(
            err.contains(name),
            "{flag} {value} should name {name}: {err}"
        );
    }
}

#[test]
fn a_pump_that_delivers_backwards_is_said_so() {
    // 100 rpm, 40 bar, 120 degC: the leakage exceeds the displacement
    let out = gearpump(&[
        "simulate",
        "--json",
        "--speed",
        "100",
        "--pressure",
        "40",
        "--temp",
        "120",
    ]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["eta_v"].as_f64().unwrap() <= 0.0, "{v}");
    let w = v["warnings"].as_array().expect("a warnings list");
    assert!(
        w.iter().any(|s| s
            .as_str()
            .unwrap()
            .contains("delivers nothing or backwards")),
        "{w:?}"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("warning: the pump delivers nothing"), "{err}");
    // a normal point has an empty list
    let out = gearpump(&with_args(&["simulate", "--json"], &POINT_1000_30_60));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["warnings"], serde_json::json!([]));
}

#[test]
fn absurd_campaign_rows_are_refused_naming_row_and_column() {
    let dir = Scratch::new("bad-input");
    let header = "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm";
    let good = "N01,30,32,10,12,30,1000,60,13.5,";
    for (bad, column) in [
        (
            "N02,1e6,32,10,12,30,1000,60,13.5,",
            "tip_clearance_drive_um",
        ),
        (
            "N02,30,32,0,12,30,1000,60,13.5,",
            "bearing_clearance_drive_um",
        ),
        ("N02,30,32,10,12,1e6,1000,60,13.5,", "pressure_bar"),
        ("N02,30,32,10,12,30,1e-9,60,13.5,", "speed_rpm"),
        ("N02,30,32,10,12,30,1e9,60,13.5,", "speed_rpm"),
    ] {
        let csv = dir.path("c.csv");
        std::fs::write(&csv, format!("{header}\n{good}\n{bad}\n")).unwrap();
        let out = dir.path("out");
        let (code, err) = run(&[
            "campaign",
            "--data",
            csv.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(code, Some(2), "{bad}: {err}");
        assert!(
            err.contains("row 2") && err.contains(column),
            "{bad}: {err}"
        );
        // refused before anything was written
        assert!(!out.join("tests.csv").exists(), "{bad}");
    }
}

const HEADER: &str = "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm";
const GOOD_ROW: &str = "N01,30,32,10,12,30,1000,60,13.5,";

/// One bad input: the files it needs (name, content; `{dir}` in an argument
/// is the scratch folder), the arguments, and what the message must name.
struct Case {
    files: &'static [(&'static str, &'static str)],
    args: &'static [&'static str],
    names: &'static [&'static str],
}

/// A campaign CSV whose second data row is `row`.
fn csv_with(row: &str) -> String {
    format!("{HEADER}\n{GOOD_ROW}\n{row}\n")
}

/// Every bad input is refused with exit 2 and a one-line message naming
/// the flag, key, file, row or column, before anything is simulated or
/// written (issue 18 points 6, 7 and 8; docs/interfaces.md section 2).
#[test]
fn every_bad_input_is_refused_with_exit_2_naming_what_is_wrong() {
    let dir = Scratch::new("bad-table");
    // campaign CSV rows: (second data row, column named)
    let rows: &[(&str, &str)] = &[
        ("N02,0,32,10,12,30,1000,60,13.5,", "tip_clearance_drive_um"),
        (
            "N02,1e6,32,10,12,30,1000,60,13.5,",
            "tip_clearance_drive_um",
        ),
        (
            "N02,30,1e6,10,12,30,1000,60,13.5,",
            "tip_clearance_driven_um",
        ),
        (
            "N02,30,32,10,1e6,30,1000,60,13.5,",
            "bearing_clearance_driven_um",
        ),
        ("N02,30,32,10,12,1e6,1000,60,13.5,", "pressure_bar"),
        ("N02,30,32,10,12,-3,1000,60,13.5,", "pressure_bar"),
        ("N02,30,32,10,12,30,1e-9,60,13.5,", "speed_rpm"),
        ("N02,30,32,10,12,30,0,60,13.5,", "speed_rpm"),
        ("N02,30,32,10,12,30,1e5,60,13.5,", "speed_rpm"),
        ("N02,30,32,10,12,30,1000,500,13.5,", "temp_c"),
        ("N02,30,32,10,12,30,1000,-300,13.5,", "temp_c"),
        ("N02,30,32,10,12,30,1000,60,1e9,", "flow_lpm"),
        ("N02,30,32,10,12,30,1000,60,-1,", "flow_lpm"),
        ("N02,30,32,10,12,30,1000,60,13.5,1e9", "torque_nm"),
        ("N02,30,32,10,12,30,1000,60,13.5,-5", "torque_nm"),
        ("N02,30,32,10,12,30,1000,60,13.5,abc", "torque_nm"),
        ("N02,30,32,10,12,30,NaN,60,13.5,", "speed_rpm"),
        ("N02,30,32,10,12,30,1000,60,,", "flow_lpm"),
        ("N02,30,32,10,12,30,1000,60", "row 2"),
        ("N01,30,32,10,12,30,1000,60,13.5,", "row 2"),
    ];
    for &(row, column) in rows {
        for command in ["campaign", "diagnose"] {
            let csv = dir.path("c.csv");
            std::fs::write(&csv, csv_with(row)).unwrap();
            let out = dir.path("out");
            let (code, err) = run(&[
                command,
                "--data",
                csv.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ]);
            assert_eq!(code, Some(2), "{command} {row}: {err}");
            assert!(
                err.contains("c.csv") && err.contains("row 2") && err.contains(column),
                "{command} {row} should name c.csv, row 2 and {column}: {err}"
            );
            assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
            assert!(!out.exists(), "{command} {row}: nothing written");
        }
    }
    let missing_column = HEADER.replace(",speed_rpm", "");
    let cases = [
        // a CSV missing a column
        Case {
            files: &[("c.csv", "")],
            args: &["campaign", "--data", "{dir}/c.csv", "--out", "{dir}/out"],
            names: &["c.csv", "speed_rpm"],
        },
        // TOML syntax errors: the file, line and column
        Case {
            files: &[("d.toml", "[gears\nz_drive = 12\n")],
            args: &[
                "simulate",
                "--design",
                "{dir}/d.toml",
                "--speed",
                "1000",
                "--pressure",
                "30",
                "--temp",
                "60",
            ],
            names: &["d.toml: line 1, column 7", "TOML syntax"],
        },
        Case {
            files: &[("d.toml", "[gears]\nz_drive = 12\nname = \"open\n")],
            args: &[
                "campaign",
                "--design",
                "{dir}/d.toml",
                "--data",
                "{dir}/c.csv",
                "--out",
                "{dir}/out",
            ],
            names: &["d.toml: line 3, column", "TOML syntax"],
        },
        Case {
            files: &[("d.toml", "[gears]\n\nz_drive = = 12\n")],
            args: &["synth", "--design", "{dir}/d.toml", "--out", "{dir}/s.csv"],
            names: &["d.toml: line 3, column 11", "TOML syntax"],
        },
        // a design file with a key that does not exist
        Case {
            files: &[("d.toml", "[gears]\nzz = 1\n")],
            args: &[
                "simulate",
                "--design",
                "{dir}/d.toml",
                "--speed",
                "1000",
                "--pressure",
                "30",
                "--temp",
                "60",
            ],
            names: &["d.toml", "gears.zz"],
        },
        // flags
        Case {
            files: &[],
            args: &[
                "simulate",
                "--speed",
                "1000",
                "--pressure",
                "30",
                "--temp",
                "500",
            ],
            names: &["--temp"],
        },
        Case {
            files: &[],
            args: &[
                "simulate",
                "--set",
                "nope.x=1",
                "--speed",
                "1000",
                "--pressure",
                "30",
                "--temp",
                "60",
            ],
            names: &["nope.x"],
        },
        Case {
            files: &[],
            args: &[
                "simulate",
                "--set",
                "clearance.tip_um=1e6",
                "--speed",
                "1000",
                "--pressure",
                "30",
                "--temp",
                "60",
            ],
            names: &["clearance.tip_um"],
        },
        Case {
            files: &[],
            args: &[
                "campaign",
                "--data",
                "{dir}/c.csv",
                "--out",
                "{dir}/out",
                "--jobs",
                "0",
            ],
            names: &["--jobs"],
        },
        Case {
            files: &[],
            args: &["synth", "--out", "{dir}/s.csv", "--jobs", "0"],
            names: &["--jobs"],
        },
        Case {
            files: &[],
            args: &["synth", "--out", "{dir}/s.csv", "--noise", "abc"],
            names: &["--noise"],
        },
        Case {
            files: &[],
            args: &["synth", "--out", "{dir}/s.csv", "--samples", "0"],
            names: &["--samples"],
        },
        Case {
            files: &[],
            args: &["synth", "--out", "{dir}/s.csv", "--effect", "bogus=1"],
            names: &["--effect", "bogus"],
        },
        Case {
            files: &[],
            args: &[
                "synth",
                "--out",
                "{dir}/s.csv",
                "--conditions",
                "{dir}/none.csv",
            ],
            names: &["none.csv"],
        },
        Case {
            files: &[],
            args: &["eval-diagnosis", "--out", "{dir}/e", "--effects", "bogus"],
            names: &["--effects", "bogus"],
        },
        Case {
            files: &[],
            args: &[
                "eval-diagnosis",
                "--out",
                "{dir}/e",
                "--trials",
                "2",
                "--families",
                "two_effects",
                "--only",
                "two_effects-5",
            ],
            names: &["--only", "two_effects-5"],
        },
        Case {
            files: &[],
            args: &["campaign", "--data", "{dir}/none.csv", "--out", "{dir}/out"],
            names: &["none.csv"],
        },
        Case {
            files: &[],
            args: &["fmu", "--model", "bogus"],
            names: &["--model"],
        },
    ];
    for case in &cases {
        let _ = std::fs::remove_dir_all(dir.path("out"));
        std::fs::write(
            dir.path("c.csv"),
            csv_with("N02,28,30,11,12,30,1000,60,13.5,"),
        )
        .unwrap();
        for (name, text) in case.files {
            let text = if *name == "c.csv" {
                format!("{missing_column}\n")
            } else {
                text.to_string()
            };
            std::fs::write(dir.path(name), text).unwrap();
        }
        let root = dir.0.display().to_string();
        let args: Vec<String> = case
            .args
            .iter()
            .map(|a| a.replace("{dir}", &root))
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        for name in case.names {
            assert!(err.contains(name), "{args:?} should name {name}: {err}");
        }
        assert_eq!(
            err.trim_end().lines().count(),
            1,
            "{args:?}, one line: {err}"
        );
        assert!(!dir.path("out").exists(), "{args:?}: nothing written");
    }
}

/// Rows whose simulation fails (here every row: Newton allowed one
/// iteration to a tolerance it cannot reach) are written with empty cells
/// and listed, and the command exits 1 saying how many (issue 18 point 6:
/// it exited 0).
#[test]
fn rows_that_cannot_be_simulated_make_the_campaign_exit_1() {
    let dir = Scratch::new("failed-rows");
    let csv = dir.path("c.csv");
    std::fs::write(&csv, csv_with("N02,28,30,11,12,30,1000,60,13.5,")).unwrap();
    let out = dir.path("out");
    let (code, err) = run(&[
        "campaign",
        "--data",
        csv.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-micromotion",
        "--set",
        "numerics.newton_tolerance=1e-14",
        "--set",
        "numerics.newton_max_iterations=1",
    ]);
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("row 1 (sample N01): no simulated result")
            && err.contains("2 of 2 rows could not be simulated"),
        "{err}"
    );
    // the outputs are written, the failed rows' simulated cells empty
    let tests = std::fs::read_to_string(out.join("tests.csv")).unwrap();
    assert!(tests.lines().nth(1).unwrap().contains("13.5,,"), "{tests}");
}

/// `--jobs` above the available parallelism is clamped to it with a note
/// (issue 18 point 7: `--jobs 100000` started thousands of threads).
#[test]
fn jobs_above_the_cores_are_clamped_with_a_note() {
    let dir = Scratch::new("jobs");
    let csv = dir.path("c.csv");
    std::fs::write(&csv, format!("{HEADER}\n{GOOD_ROW}\n")).unwrap();
    let out = dir.path("out");
    let (code, err) = run(&[
        "campaign",
        "--data",
        csv.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--no-micromotion",
        "--jobs",
        "100000",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    assert!(
        err.contains(&format!(
            "note: --jobs 100000 is more than the {cores} cores available: using {cores}"
        )),
        "{err}"
    );
}
