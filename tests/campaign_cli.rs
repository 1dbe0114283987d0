//! `gearpump synth` and `gearpump campaign` through the real binary: the
//! acceptance path (synth 20 samples, campaign, statistics, plots), the
//! output files' columns, a hand check of the statistics against `tests.csv`
//! and a Student t table, reproducibility, and bad input (exit 2 naming
//! file, row and column).

mod campaign_common;

use campaign_common::*;
use serde_json::Value;
use std::fs;

/// The CSV contract of docs/interfaces.md section 4, written out here on purpose rather than
/// taken from the library, so that a wrong constant there fails this test.
const CAMPAIGN_COLUMNS: [&str; 10] = [
    "sample",
    "tip_clearance_drive_um",
    "tip_clearance_driven_um",
    "bearing_clearance_drive_um",
    "bearing_clearance_driven_um",
    "pressure_bar",
    "speed_rpm",
    "temp_c",
    "flow_lpm",
    "torque_nm",
];

/// Student t quantiles t_{0.975, dof} from a printed table.
fn t_table(dof: usize) -> f64 {
    match dof {
        1 => 12.706,
        2 => 4.303,
        3 => 3.182,
        4 => 2.776,
        9 => 2.262,
        19 => 2.093,
        _ => panic!("no table value for {dof}"),
    }
}

fn svg_is_well_formed(path: &std::path::Path) {
    let text = fs::read_to_string(path).unwrap();
    assert!(text.contains("<svg"), "{}", path.display());
    let mut reader = quick_xml::Reader::from_str(&text);
    let mut depth = 0i64;
    let mut elements = 0;
    loop {
        match reader.read_event() {
            Ok(quick_xml::events::Event::Start(_)) => {
                depth += 1;
                elements += 1
            }
            Ok(quick_xml::events::Event::Empty(_)) => elements += 1,
            Ok(quick_xml::events::Event::End(_)) => depth -= 1,
            Ok(quick_xml::events::Event::Eof) => break,
            Ok(_) => {}
            Err(e) => panic!("{}: {e}", path.display()),
        }
    }
    assert_eq!(depth, 0, "{}", path.display());
    assert!(elements > 50, "{}: {elements} elements", path.display());
}

#[test]
fn campaign_cli_synth_then_campaign_twenty_samples() {
    let s = Scratch::new("cli-20");
    // Both sweeps of Table 2 (pressure at 1000 rpm, speed at 30 bar) at both
    // temperatures, without the slow 4000 rpm points: 20 x 6 = 120 tests.
    let cond = s.path("cond.csv");
    write_conditions(
        &cond,
        &[
            (10.0, 1000.0, 60.0),
            (30.0, 1000.0, 60.0),
            (30.0, 500.0, 60.0),
            (10.0, 1000.0, 120.0),
            (30.0, 1000.0, 120.0),
            (30.0, 500.0, 120.0),
        ],
    );
    let data = s.path("c.csv");
    let out = s.path("out");
    let v: Value = serde_json::from_str(&gearpump_ok(&[
        "synth",
        "--samples",
        "20",
        "--seed",
        "1",
        "--conditions",
        cond.to_str().unwrap(),
        "--out",
        data.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["tests"], 120);
    assert_eq!(v["samples"], 20);

    let text = gearpump_ok(&[
        "campaign",
        "--data",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
        "--json",
    ]);
    assert_eq!(text.trim().lines().count(), 1, "one JSON object");
    let v: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["tests"], 120);
    assert_eq!(v["samples"], 20);
    assert_eq!(v["failed"].as_array().map(Vec::len), Some(0));
    assert_eq!(v["conditions"].as_array().map(Vec::len), Some(6));

    // conditions.csv: columns, 6 rows, t_crit 2.093, delta_nu = max(|lo|, |hi|).
    let conds = read_csv(&out.join("conditions.csv"));
    assert_eq!(
        conds.0,
        [
            "pressure_bar",
            "speed_rpm",
            "temp_c",
            "n_samples",
            "d_mean",
            "d_std",
            "t_crit",
            "ci_low",
            "ci_high",
            "delta_nu",
            "n_torque",
            "torque_err_mean_nm",
            "torque_err_std_nm",
            "torque_err_rel_mean",
            "eta_hm_err_mean",
            "eta_hm_err_std"
        ]
    );
    assert_eq!(conds.1.len(), 6);
    for ((t, lo), (hi, dnu)) in column(&conds, "t_crit")
        .iter()
        .zip(column(&conds, "ci_low"))
        .zip(
            column(&conds, "ci_high")
                .iter()
                .zip(column(&conds, "delta_nu")),
        )
    {
        assert_eq!((t * 1000.0).round() / 1000.0, 2.093);
        assert_eq!(dnu, lo.abs().max(hi.abs()));
    }
    assert!(column(&conds, "n_samples").iter().all(|&n| n == 20.0));

    // tests.csv: the input columns in order, then the five simulated ones
    // and the seven parts of the loss budget.
    let tests = read_csv(&out.join("tests.csv"));
    let mut want: Vec<&str> = CAMPAIGN_COLUMNS.to_vec();
    let losses = [
        "loss_tip_poiseuille",
        "loss_tip_couette",
        "loss_lateral",
        "loss_bearings",
        "loss_mesh_zone",
        "loss_compressibility",
    ];
    want.extend([
        "flow_lpm_sim",
        "eta_v_meas",
        "eta_v_sim",
        "d",
        "torque_nm_sim",
    ]);
    want.extend(losses);
    assert_eq!(tests.0, want);
    // the budget's parts add up to 1 - eta_v,sim on every row
    let sim = column(&tests, "eta_v_sim");
    let parts: Vec<Vec<f64>> = losses.iter().map(|c| column(&tests, c)).collect();
    for (i, eta) in sim.iter().enumerate() {
        let sum: f64 = parts.iter().map(|p| p[i]).sum();
        assert!(
            (sum - (1.0 - eta)).abs() < 1e-3,
            "row {i}: {sum} vs {}",
            1.0 - eta
        );
    }
    assert_eq!(tests.1.len(), 120);
    let input = read_csv(&data);
    for (a, b) in input.1.iter().zip(&tests.1) {
        assert_eq!(a[..], b[..10], "input cells kept verbatim");
    }
    let d = column(&tests, "d");
    let em = column(&tests, "eta_v_meas");
    let es = column(&tests, "eta_v_sim");
    for i in 0..d.len() {
        assert!(d[i].is_finite());
        assert!((d[i] - (em[i] - es[i])).abs() < 1e-15);
        assert!(es[i] > 0.5 && es[i] < 1.0, "eta_v_sim {}", es[i]);
    }
    assert!(column(&tests, "torque_nm_sim").iter().all(|t| *t > 0.0));

    // The statistics by hand from tests.csv and a printed t table.
    let p = column(&tests, "pressure_bar");
    let n = column(&tests, "speed_rpm");
    let t = column(&tests, "temp_c");
    for (k, row) in conds.1.iter().enumerate() {
        let key: Vec<f64> = row[..3].iter().map(|x| x.parse().unwrap()).collect();
        let ds: Vec<f64> = (0..d.len())
            .filter(|&i| p[i] == key[0] && n[i] == key[1] && t[i] == key[2])
            .map(|i| d[i])
            .collect();
        assert_eq!(ds.len(), 20);
        let mean = ds.iter().sum::<f64>() / 20.0;
        let sd = (ds.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 19.0).sqrt();
        let half = t_table(19) * sd / 20f64.sqrt();
        let c = |name: &str| column(&conds, name)[k];
        assert!((c("d_mean") - mean).abs() < 1e-12);
        assert!((c("d_std") - sd).abs() < 1e-12);
        // the table's 4 digits: |t - 2.093| < 5e-4
        assert!((c("ci_low") - (mean - half)).abs() < 5e-4 * sd);
        assert!((c("ci_high") - (mean + half)).abs() < 5e-4 * sd);
    }

    // report and plots
    let report = fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| 30 | 500 | 120 | 20 |"), "{report}");
    for f in [
        "curves_pressure.svg",
        "curves_speed.svg",
        "residuals.svg",
        "losses.svg",
    ] {
        assert!(report.contains(&format!("]({f})")), "{f} in report");
        svg_is_well_formed(&out.join(f));
    }
    // no journal or temporary file left behind
    let mut names: Vec<String> = fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "conditions.csv",
            "curves_pressure.svg",
            "curves_speed.svg",
            "losses.svg",
            "report.md",
            "residuals.svg",
            "tests.csv"
        ]
    );
}

#[test]
fn campaign_cli_synth_is_reproducible_and_writes_only_rig_columns() {
    let s = Scratch::new("cli-synth");
    let cond = s.path("cond.csv");
    write_conditions(&cond, &[(30.0, 1000.0, 60.0), (20.0, 1000.0, 120.0)]);
    let run = |name: &str, seed: &str, jobs: &str| {
        let path = s.path(name);
        gearpump_ok(&[
            "synth",
            "--samples",
            "3",
            "--seed",
            seed,
            "--conditions",
            cond.to_str().unwrap(),
            "--effect",
            "thermal_clearance=0.03",
            "--effect",
            "entrained_air=0.01",
            "--no-micromotion",
            "--jobs",
            jobs,
            "--out",
            path.to_str().unwrap(),
        ]);
        fs::read_to_string(path).unwrap()
    };
    let a = run("a.csv", "7", "1");
    let b = run("b.csv", "7", "2");
    let c = run("c.csv", "8", "2");
    assert_eq!(a, b, "same seed: byte-identical, whatever the thread count");
    assert_ne!(a, c, "another seed: another population");
    let lines: Vec<&str> = a.lines().collect();
    assert_eq!(lines[0], CAMPAIGN_COLUMNS.join(","));
    assert_eq!(lines.len(), 1 + 3 * 2);
    assert!(lines[1].starts_with("N01,"));
    for word in ["thermal", "air", "effect", "0.03"] {
        assert!(
            !a.contains(word),
            "the hidden effect leaks into the file: {word}"
        );
    }
    // It reads back as a valid measured campaign.
    let campaign = gearpump::campaign::parse_campaign_str("a.csv", &a).unwrap();
    assert_eq!(campaign.rows.len(), 6);
    assert!(campaign.rows.iter().all(|r| r.torque.is_some()));
}

fn assert_bad(args: &[&str], fragments: &[&str]) {
    let out = gearpump(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "one-line message: {err}");
    for f in fragments {
        assert!(err.contains(f), "{args:?}: `{f}` not in {err}");
    }
    assert!(out.stdout.is_empty());
}

#[test]
fn campaign_cli_bad_input_exits_2_naming_file_row_and_column() {
    let s = Scratch::new("cli-bad");
    let header = CAMPAIGN_COLUMNS.join(",");
    let good = "N01,30,32,12,13,30,1000,60,13.0,7.5";
    let cases: [(&str, String, &[&str]); 6] = [
        (
            "missing.csv",
            format!("{}\n{good}\n", header.replace(",speed_rpm", "")),
            &["missing.csv", "header", "speed_rpm"],
        ),
        (
            "text.csv",
            format!("{header}\n{good}\nN02,30,32,12,13,30,1000,60,abc,\n"),
            &["text.csv", "row 2", "flow_lpm", "not a number"],
        ),
        (
            "negative.csv",
            format!("{header}\n{good}\nN02,30,-32,12,13,30,1000,60,13,\n"),
            &["negative.csv", "row 2", "tip_clearance_driven_um"],
        ),
        (
            "speed.csv",
            format!("{header}\nN02,30,32,12,13,30,0,60,13,\n"),
            &["speed.csv", "row 1", "speed_rpm", "> 0"],
        ),
        (
            "dup.csv",
            format!("{header}\n{good}\n{good}\n"),
            &["dup.csv", "row 2", "sample", "duplicate"],
        ),
        (
            "hot.csv",
            format!("{header}\n{good}\nN02,30,32,12,13,30,1000,400,13,\n"),
            &["hot.csv", "row 2", "temp_c", "oil model"],
        ),
    ];
    for (name, text, fragments) in &cases {
        let path = s.path(name);
        fs::write(&path, text).unwrap();
        let out = s.path(&format!("{name}.out"));
        assert_bad(
            &[
                "campaign",
                "--data",
                path.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            fragments,
        );
        assert!(!out.exists(), "nothing written for bad input {name}");
    }
    let data = s.path("good.csv");
    fs::write(&data, format!("{header}\n{good}\n")).unwrap();
    let d = data.to_str().unwrap();
    let o = s.path("o");
    let o = o.to_str().unwrap();
    assert_bad(
        &["campaign", "--data", d, "--out", o, "--jobs", "0"],
        &["--jobs"],
    );
    assert_bad(
        &["campaign", "--data", d, "--out", o, "--set", "oil.nope=1"],
        &["oil.nope"],
    );
    assert_bad(
        &["campaign", "--data", "no-such-file.csv", "--out", o],
        &["no-such-file.csv"],
    );
    let csv = s.path("x.csv");
    let x = csv.to_str().unwrap();
    assert_bad(
        &["synth", "--out", x, "--effect", "warp=1"],
        &["effect warp=1", "unknown effect"],
    );
    assert_bad(
        &["synth", "--out", x, "--effect", "lateral_clearance=-3"],
        &["effect lateral_clearance=-3"],
    );
    assert_bad(&["synth", "--out", x, "--noise", "big"], &["--noise"]);
    assert_bad(&["synth", "--out", x, "--samples", "0"], &["--samples"]);
    let cond = s.path("cond.csv");
    fs::write(
        &cond,
        "pressure_bar,speed_rpm,temp_c\n30,1000,60\n30,1000,x\n",
    )
    .unwrap();
    assert_bad(
        &["synth", "--out", x, "--conditions", cond.to_str().unwrap()],
        &["cond.csv", "row 2", "temp_c"],
    );
    assert_bad(
        &["synth", "--out", x, "--conditions", "nowhere.csv"],
        &["nowhere.csv"],
    );
    assert!(!csv.exists());
}

#[test]
fn campaign_cli_bundled_demo_campaign_is_a_valid_population() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/demo_campaign/campaign.csv");
    let c = gearpump::campaign::read_campaign(&path).unwrap();
    assert_eq!(c.rows.len(), 280);
    assert_eq!(gearpump::campaign::group_by_condition(&c.rows).len(), 14);
    let samples: std::collections::BTreeSet<&str> =
        c.rows.iter().map(|r| r.sample.as_str()).collect();
    assert_eq!(samples.len(), 20);
    let readme = fs::read_to_string(path.with_file_name("README.md")).unwrap();
    assert!(readme.contains("SYNTHETIC"));
    assert!(readme.contains("--effect thermal_clearance=0.03"));
}
