//! Inputs far outside any pump's range are refused before the solver sees
//! them (exit 2, the flag, key or cell named), and operating points where the
//! pump delivers nothing or backwards are said plainly (`warnings`). The
//! battery of issue 18: a table of bad argument vectors and bad CSV and TOML
//! contents, each refused with exit 2 and a message naming what is wrong;
//! rows that cannot be simulated make the command fail; `--jobs` is bounded.

mod campaign_common;
use campaign_common::{gearpump, tree, with_args, Scratch, POINT_1000_30_60};

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

/// Found by an independent bad-input check (session 19): each refused
/// with exit 2, naming the flag, before any work, and nothing written.
#[test]
fn impossible_outputs_caps_and_misnamed_flags_are_refused_before_any_work() {
    let dir = Scratch::new("bad-outputs");
    let file = dir.path("afile");
    std::fs::write(&file, "x").unwrap();
    let folder = dir.path("adir");
    std::fs::create_dir(&folder).unwrap();
    let (file_s, folder_s) = (file.to_str().unwrap(), folder.to_str().unwrap());
    let under_file = format!("{file_s}/sub");
    let csv_under_file = format!("{file_s}/x.csv");
    let slash = format!("{}/", dir.path("sy").to_str().unwrap());
    let data = "examples/demo_campaign/campaign.csv";
    let x_csv = dir.path("x.csv");
    let x_csv = x_csv.to_str().unwrap();
    let ev = dir.path("ev");
    let ev = ev.to_str().unwrap();
    let mc = dir.path("mc");
    let mc = mc.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            with_args(&["simulate"], &POINT_1000_30_60)
                .into_iter()
                .chain(["--trace", file_s])
                .collect(),
            "--trace",
        ),
        (
            vec!["campaign", "--data", data, "--out", &under_file],
            "--out",
        ),
        (vec!["diagnose", "--data", data, "--out", file_s], "--out"),
        (vec!["synth", "--out", folder_s], "--out"),
        (vec!["synth", "--out", &csv_under_file], "--out"),
        (vec!["synth", "--out", &slash], "--out"),
        (vec!["montecarlo", "--out", &under_file], "--out"),
        (vec!["eval-diagnosis", "--out", file_s], "--out"),
        // absurd counts: refused, not drawn up front
        (
            vec!["synth", "--samples", "100000000", "--out", x_csv],
            "--samples",
        ),
        (
            vec!["eval-diagnosis", "--trials", "1000000000", "--out", ev],
            "--trials",
        ),
        (
            vec![
                "eval-diagnosis",
                "--trials",
                "18446744073709551615",
                "--out",
                ev,
            ],
            "--trials",
        ),
        (
            vec![
                "eval-diagnosis",
                "--trials",
                "1",
                "--samples",
                "100000000",
                "--out",
                ev,
            ],
            "--samples",
        ),
        // the flag the user typed, not another
        (
            vec![
                "eval-diagnosis",
                "--trials",
                "1",
                "--families",
                "bogus",
                "--out",
                ev,
            ],
            "--families",
        ),
        (
            vec![
                "montecarlo",
                "--spec",
                "eta_v>=0.85@1e9rpm,30bar,60degC",
                "--out",
                mc,
            ],
            "--spec",
        ),
    ];
    for (args, name) in &cases {
        let (code, err) = run(args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(err.contains(name), "{args:?} should name {name}: {err}");
    }
    // nothing was made: only the two entries put there
    let mut left: Vec<String> = std::fs::read_dir(&dir.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["adir", "afile"]);
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
}

/// A folder where a result file goes stops the campaign before it runs, and
/// the folder's earlier contents stay as they were (it used to run, then
/// move part of the result in and stop at the folder: exit 1, half a
/// result).
#[test]
fn a_folder_in_the_place_of_a_result_file_is_refused_before_the_run() {
    let dir = Scratch::new("bad-place");
    let out = dir.path("out");
    std::fs::create_dir_all(out.join("tests.csv")).unwrap();
    std::fs::write(out.join("tests.csv").join("mine.txt"), "keep").unwrap();
    let (code, err) = run(&[
        "campaign",
        "--data",
        "examples/demo_campaign/campaign.csv",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--out") && err.contains("tests.csv"), "{err}");
    let entries: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(entries, ["tests.csv"]);
    assert_eq!(
        std::fs::read_to_string(out.join("tests.csv").join("mine.txt")).unwrap(),
        "keep"
    );
}

/// Negative values as documented, written with a space: `--pressure -0.5`
/// and `--temp -10` are values, not flags. The delivery's absolute
/// pressure has a floor: -1 bar above an inlet at 0.05 bar absolute would
/// be -0.95 bar absolute (it ran, with eta_v 1.685), and -1 bar above the
/// atmosphere is 0.013 bar absolute, below the inlet range's near-vacuum.
#[test]
fn negative_values_are_values_and_the_delivery_has_an_absolute_floor() {
    let out = gearpump(&[
        "simulate",
        "--json",
        "--speed",
        "1000",
        "--pressure",
        "-0.5",
        "--temp",
        "-10",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (p, inlet, shown) in [("-1", "0.05", "-0.9500"), ("-1", "1.01325", "0.0132")] {
        let (code, err) = run(&[
            "simulate",
            "--speed",
            "1000",
            "--pressure",
            p,
            "--temp",
            "60",
            "--inlet-pressure",
            inlet,
        ]);
        assert_eq!(code, Some(2), "{p} above {inlet}: {err}");
        assert!(
            err.contains("--pressure") && err.contains(shown) && err.contains("bar absolute"),
            "{err}"
        );
    }
}

/// Where a message points: the conditions file by its name, a syntax error
/// of a distributions file by line and column.
#[test]
fn messages_name_the_file_and_the_place() {
    let dir = Scratch::new("bad-names");
    let conds = dir.path("conds.csv");
    std::fs::write(&conds, "pressure_bar,speed_rpm,temp_c\n30,1e9,60\n").unwrap();
    let (code, err) = run(&[
        "synth",
        "--conditions",
        conds.to_str().unwrap(),
        "--out",
        dir.path("x.csv").to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("conds.csv") && err.contains("speed_rpm"),
        "{err}"
    );
    let dists = dir.path("d.toml");
    std::fs::write(&dists, "[tip\nx = 1\n").unwrap();
    let (code, err) = run(&[
        "montecarlo",
        "--distributions",
        dists.to_str().unwrap(),
        "--out",
        dir.path("mc").to_str().unwrap(),
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("line 1, column"), "{err}");
    assert!(!err.trim().contains('\n'), "one line: {err}");
}

/// `gearpump fmu` refuses a bad population and an impossible `--out` with
/// exit 2 and a one-line message naming the row or `--out` and the path,
/// before anything is built and without making a folder or leaving a
/// temporary file: a sample id of 65,600 letters (the zip crate panicked
/// on its entry name, exit 134, leaving `x.fmu.tmp-PID` and
/// `x.ssp.tmp-PID`), ids that cannot name an SSP component (the FMU was
/// built first and `fm/p1/` left behind), an existing folder or a path
/// below a file as `--out` (exit 1, `--out` not named).
#[test]
fn fmu_refuses_bad_populations_and_impossible_out_paths_before_any_work() {
    let dir = Scratch::new("fmu-paths");
    let path = |name: &str| dir.path(name).display().to_string();
    std::fs::create_dir(dir.path("fm")).unwrap();
    std::fs::create_dir(dir.path("DIR")).unwrap();
    std::fs::write(dir.path("afile"), "a file").unwrap();
    std::fs::write(
        dir.path("small.csv"),
        format!("{HEADER}\n{GOOD_ROW}\nN02,28,30,11,12,30,1000,60,13.5,\n"),
    )
    .unwrap();
    let long = "N".repeat(65_600);
    std::fs::write(
        dir.path("long.csv"),
        format!("{HEADER}\n{long},30,32,10,12,30,1000,60,13.5,\n"),
    )
    .unwrap();
    let before = tree(&dir.0);

    // the long id: refused where every command reads sample ids
    for args in [
        vec![
            "fmu".to_string(),
            "--population".into(),
            path("long.csv"),
            "--out".into(),
            path("fm/l/x.ssp"),
        ],
        vec![
            "campaign".to_string(),
            "--data".into(),
            path("long.csv"),
            "--out".into(),
            path("fm/l"),
        ],
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{:?}: {err}", args[0]);
        for name in [
            "long.csv",
            "row 1",
            "column sample",
            "at most 64 characters",
        ] {
            assert!(
                err.contains(name),
                "{:?} should name {name}: {err}",
                args[0]
            );
        }
        assert!(err.len() < 300, "a short message: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert_eq!(tree(&dir.0), before, "{:?}: nothing written", args[0]);
    }

    // ids that cannot name an SSP component, refused before the FMU is built
    for id in ["N/1", "N 1", "\u{c4}01", "N01\0"] {
        std::fs::write(
            dir.path("pop_badid.csv"),
            format!("{HEADER}\n{GOOD_ROW}\n{id},28,30,11,12,30,1000,60,13.5,\n"),
        )
        .unwrap();
        let before = tree(&dir.0);
        let (code, err) = run(&[
            "fmu",
            "--population",
            &path("pop_badid.csv"),
            "--out",
            &path("fm/p1/x.ssp"),
        ]);
        assert_eq!(code, Some(2), "{id:?}: {err}");
        for name in ["--population", "pop_badid.csv", "row 2", "letters, digits"] {
            assert!(err.contains(name), "{id:?} should name {name}: {err}");
        }
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert_eq!(tree(&dir.0), before, "{id:?}: no folder, no file");
    }

    // impossible --out paths: (arguments before --out, --out, also named)
    let before = tree(&dir.0);
    let fmu: &[&str] = &["fmu"];
    let pop = ["fmu", "--population", &path("small.csv")];
    let cases: [(&[&str], String, &str); 6] = [
        (fmu, path("DIR"), "is a folder"),
        (fmu, path("DIR") + "/", "is a folder"),
        (fmu, path("afile/x.fmu"), "afile is a file"),
        (fmu, path("afile/sub/x.fmu"), "afile is a file"),
        (&pop, path("fm"), "is a folder"),
        (&pop, path("afile/q/x.ssp"), "afile is a file"),
    ];
    for (args, out, why) in &cases {
        let args = with_args(args, &["--out", out]);
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{args:?}: {err}");
        assert!(
            err.contains(&format!("--out: {out}: ")) && err.contains(why),
            "{args:?} should name --out, {out} and say {why:?}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert_eq!(tree(&dir.0), before, "{args:?}: nothing written");
    }
}
