//! Inputs far outside any pump's range are refused before the solver sees
//! them (exit 2, the flag, key or cell named), and operating points where the
//! pump delivers nothing or backwards are said plainly (`warnings`).

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
