//! `gearpump montecarlo` end to end: bad input refused with exit 2 naming
//! what is wrong; a drawn pump is `simulate` of its clearances; the yield
//! and percentiles are those counted from `pumps.csv`; a study killed
//! part-way and restarted writes the same bytes as an uninterrupted one.

mod campaign_common;

use campaign_common::*;
use serde_json::Value;
use std::fs;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = gearpump(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn montecarlo_bad_input_exits_2_naming_what_is_wrong() {
    let s = Scratch::new("mc-bad");
    let out = s.path("out");
    let out = out.to_str().unwrap();
    let cond = s.path("c.csv");
    write_conditions(&cond, &[(30.0, 1000.0, 60.0)]);
    let cond = cond.to_str().unwrap();
    let toml = |name: &str, text: &str| {
        let p = s.path(name);
        fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let gamma = toml("gamma.toml", "[tip1_um]\ndist = \"gamma\"\n");
    let huge = toml(
        "huge.toml",
        "[bearing2_um]\ndist = \"normal\"\nmean = 1e5\nstd = 1\n",
    );
    let one_pump = toml(
        "one.csv",
        "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\nA,30,31,12,13,30,1000,60,14,\n",
    );
    let file = toml("file", "x");
    let base = ["montecarlo", "--conditions", cond];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--pumps", "0"], "--pumps: must be in [4,"),
        (vec!["--pumps", "3"], "sensitivity indices need two pairs"),
        (
            vec!["--pumps", "100000000"],
            "--pumps: must be in [4, 10000000]",
        ),
        (vec!["--spec", "eta_v>0.8"], "--spec: `eta_v>0.8`: no `@`"),
        (
            vec!["--spec", "eta>=0.8@1000rpm,30bar,60degC"],
            "unknown quantity `eta`",
        ),
        (
            vec!["--spec", "eta_v>=0.8@1000rpm,30bar"],
            "lacks the temperature",
        ),
        (
            vec!["--spec", "eta_v>=0.8@1e9rpm,30bar,60degC"],
            "--spec: 30 bar, 1000000000 rpm, 60 degC: speed",
        ),
        (
            vec!["--spec", "eta_v>=0.8@1000rpm,30bar,400degC"],
            "400 degC is outside the oil model's range",
        ),
        (vec!["--distributions", &gamma], "--distributions: "),
        (
            vec!["--distributions", &gamma],
            "tip1_um: unknown dist \"gamma\"",
        ),
        (
            vec!["--distributions", &huge],
            "bearing2_um: mean = 100000 um is outside",
        ),
        (
            vec!["--distributions", "/nonexistent/p.toml"],
            "--distributions: /nonexistent/p.toml",
        ),
        (vec!["--fit", &one_pump], "--fit: "),
        (
            vec!["--fit", &one_pump],
            "at least two pumps, the campaign has 1",
        ),
        (vec!["--fit", "/nonexistent/c.csv"], "--fit: "),
        (
            vec!["--fit", &one_pump, "--distributions", &gamma],
            "cannot be used with",
        ),
        (vec!["--chunk", "0"], "--chunk: must be >= 1"),
        (vec!["--jobs", "0"], "--jobs: must be >= 1"),
        (vec!["--set", "clearance.nonsense=1"], "clearance.nonsense"),
        (
            vec!["--design", "/nonexistent/d.toml"],
            "/nonexistent/d.toml",
        ),
        (vec!["--pumps=-1"], "invalid value '-1' for '--pumps <N>'"),
    ];
    for (extra, says) in cases {
        let mut args = base.to_vec();
        if !extra.iter().any(|a| a.starts_with("--pumps")) {
            args.extend(["--pumps", "4"]);
        }
        args.extend(&extra);
        args.extend(["--out", out]);
        let (code, err) = run(&args);
        assert_eq!(code, Some(2), "{extra:?}: {err}");
        assert!(err.contains(says), "{extra:?}: expected `{says}` in: {err}");
    }
    // a conditions file that is not one; an output folder that is a file
    let (code, err) = run(&["montecarlo", "--conditions", &file, "--out", out]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("--conditions: "), "{err}");
    let (code, err) = run(&[
        "montecarlo",
        "--conditions",
        cond,
        "--pumps",
        "4",
        "--out",
        &file,
    ]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("--out: ") && err.contains("not a directory"),
        "{err}"
    );
    assert!(!s.path("out").exists(), "nothing written on bad input");
}

/// One small study checked by other mechanisms: a drawn pump's row is
/// `gearpump simulate` of its clearances, the yield is the share counted
/// from `pumps.csv`, the median the middle value of its column.
#[test]
fn montecarlo_results_are_simulate_runs_counted() {
    let s = Scratch::new("mc-check");
    let cond = s.path("c.csv");
    write_conditions(&cond, &[(30.0, 1000.0, 60.0)]);
    let out = s.path("out");
    let v: Value = serde_json::from_str(&gearpump_ok(&[
        "montecarlo",
        "--conditions",
        cond.to_str().unwrap(),
        "--pumps",
        "5",
        "--no-sensitivity",
        "--seed",
        "3",
        "--spec",
        "eta_v>=0.96@1000rpm,30bar,60degC",
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ]))
    .unwrap();
    let pumps = read_csv(&out.join("pumps.csv"));
    assert_eq!(pumps.1.len(), 5);
    let eta = column(&pumps, "eta_v");
    // pump 2 by the simulate command, its clearances as written
    let row = &pumps.1[2];
    let h = format!("{},{},{},{}", row[1], row[2], row[3], row[4]);
    let one: Value = serde_json::from_str(&gearpump_ok(&[
        "simulate",
        "--speed",
        "1000",
        "--pressure",
        "30",
        "--temp",
        "60",
        "--sample-clearances",
        &h,
        "--json",
    ]))
    .unwrap();
    let e = one["eta_v"].as_f64().unwrap();
    assert!((e - eta[2]).abs() < 1e-9, "{e} vs {}", eta[2]);
    // the yield counted by hand from the file
    let pass = eta.iter().filter(|x| **x >= 0.96).count();
    let y = &v["summary"]["specs"][0]["yield"];
    assert_eq!(y["pass"].as_u64(), Some(pass as u64));
    assert_eq!(y["n"].as_u64(), Some(5));
    // the median of five values is the third smallest
    let mut sorted = eta.clone();
    sorted.sort_by(f64::total_cmp);
    // (from percentiles.csv: written exactly; serde_json's reader may be
    // 1 ulp off)
    let pct = read_csv(&out.join("percentiles.csv"));
    let q = pct.0.iter().position(|h| h == "quantity").unwrap();
    let r = pct.1.iter().position(|r| r[q] == "eta_v").unwrap();
    assert_eq!(column(&pct, "p50")[r], sorted[2]);
    let p50 = v["summary"]["conditions"][0]["eta_v"]["percentiles"][2]
        .as_f64()
        .unwrap();
    assert!((p50 - sorted[2]).abs() <= 1e-15);
    // the five pumps differ (drawn, not copied)
    assert!(sorted[0] < sorted[4]);
    for f in [
        "montecarlo.json",
        "percentiles.csv",
        "sensitivity.csv",
        "cdf.svg",
        "tornado.svg",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
}

fn journal_lines(dir: &std::path::Path) -> usize {
    fs::read_to_string(dir.join("montecarlo-journal.jsonl"))
        .map(|t| t.lines().filter(|l| l.ends_with('}')).count())
        .unwrap_or(0)
}

fn files(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            (
                e.file_name().to_string_lossy().into_owned(),
                fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    v.sort();
    v
}

/// Killed (SIGKILL) once a quarter of the chunks are journaled, restarted
/// with another thread count: the same files, byte for byte.
#[test]
fn montecarlo_resume_after_kill_gives_identical_outputs() {
    let s = Scratch::new("mc-resume");
    let cond = s.path("c.csv");
    write_conditions(&cond, &[(30.0, 1000.0, 60.0), (30.0, 500.0, 120.0)]);
    let cond = cond.to_str().unwrap().to_string();
    let args = |out: &str, jobs: &'static str| {
        vec![
            "montecarlo".to_string(),
            "--conditions".into(),
            cond.clone(),
            "--pumps".into(),
            "16".into(),
            "--chunk".into(),
            "1".into(),
            "--spec".into(),
            "eta_v>=0.72@500rpm,30bar,120degC".into(),
            "--jobs".into(),
            jobs.into(),
            "--out".into(),
            out.to_string(),
        ]
    };
    let chunks = 16 + 4 * 8;
    let reference = s.path("reference");
    let a = args(reference.to_str().unwrap(), "2");
    gearpump_ok(&a.iter().map(String::as_str).collect::<Vec<_>>());

    let resumed = s.path("resumed");
    let mut child = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args(args(resumed.to_str().unwrap(), "1"))
        .env("GEARPUMP_TABLE_CACHE", "off")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn gearpump");
    let start = Instant::now();
    let target = chunks / 4;
    loop {
        if journal_lines(&resumed) >= target {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the study finished ({status}) before it could be killed");
        }
        assert!(start.elapsed() < Duration::from_secs(300), "no progress");
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().expect("SIGKILL");
    child.wait().unwrap();
    let journaled = journal_lines(&resumed);
    assert!(journaled >= target && journaled < chunks, "{journaled}");
    assert!(!resumed.join("montecarlo.json").exists());

    let b = args(resumed.to_str().unwrap(), "2");
    let mut b: Vec<&str> = b.iter().map(String::as_str).collect();
    b.push("--json");
    let v: Value = serde_json::from_str(&gearpump_ok(&b)).unwrap();
    let reused = v["reused"].as_u64().unwrap() as usize;
    assert!(reused >= 2 * target, "reused {reused} runs");
    assert_eq!(
        reused + v["simulated"].as_u64().unwrap() as usize,
        2 * chunks
    );

    let x = files(&reference);
    let y = files(&resumed);
    assert_eq!(
        x.iter().map(|f| &f.0).collect::<Vec<_>>(),
        y.iter().map(|f| &f.0).collect::<Vec<_>>(),
        "same files, no journal left"
    );
    for ((name, p), (_, q)) in x.iter().zip(&y) {
        assert!(
            p == q,
            "{name} differs between the resumed and the uninterrupted study"
        );
    }
}

/// A design's extension keys (what `diagnose` writes into
/// `extended_design.toml`) act in the study: clearances that open with
/// temperature lower every pump's eta_v at 120 degC.
#[test]
fn montecarlo_runs_a_design_with_extension_keys() {
    let s = Scratch::new("mc-ext");
    let cond = s.path("c.csv");
    write_conditions(&cond, &[(30.0, 1000.0, 120.0)]);
    let eta = |extra: &[&str], out: &str| {
        let mut a = vec![
            "montecarlo",
            "--conditions",
            cond.to_str().unwrap(),
            "--pumps",
            "4",
            "--no-sensitivity",
            "--no-micromotion",
            "--out",
            out,
        ];
        a.extend(extra);
        gearpump_ok(&a);
        column(&read_csv(&s.path(out).join("pumps.csv")), "eta_v")
    };
    let base = eta(&[], s.path("a").to_str().unwrap());
    let grown = eta(
        &["--set", "clearance.thermal_growth_um_per_k=0.05"],
        s.path("b").to_str().unwrap(),
    );
    for (b, g) in base.iter().zip(&grown) {
        assert!(g < &(b - 0.005), "{g} vs {b}");
    }
}

/// A study written into a folder that already holds a campaign's and a
/// diagnosis's results (and a file of the user's) replaces only its own
/// files: the others are there afterwards, byte for byte.
#[test]
fn montecarlo_into_a_campaign_folder_keeps_the_campaigns_files() {
    let s = Scratch::new("mc-keep");
    let cond = s.path("c.csv");
    write_conditions(&cond, &[(30.0, 1000.0, 60.0)]);
    let out = s.path("out");
    fs::create_dir_all(out.join("extended")).unwrap();
    let kept = [
        ("tests.csv", "a campaign's tests\n"),
        ("report.md", "a campaign's report\n"),
        ("diagnosis.json", "{}\n"),
        ("extended_design.toml", "# edited by the user\n"),
        ("extended/notes.txt", "the user's notes\n"),
        ("my_data.csv", "x\n1\n"),
    ];
    for (name, text) in kept {
        fs::write(out.join(name), text).unwrap();
    }
    let args = [
        "montecarlo",
        "--conditions",
        cond.to_str().unwrap(),
        "--pumps",
        "2",
        "--no-sensitivity",
        "--no-micromotion",
        "--out",
        out.to_str().unwrap(),
    ];
    // twice: the second run replaces the first one's files
    gearpump_ok(&args);
    gearpump_ok(&args);
    for (name, text) in kept {
        assert_eq!(fs::read_to_string(out.join(name)).unwrap(), text, "{name}");
    }
    for name in ["montecarlo.json", "pumps.csv", "percentiles.csv"] {
        assert!(out.join(name).is_file(), "{name}");
    }
}
