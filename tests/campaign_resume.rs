//! No lost work: a campaign killed part-way (SIGKILL, no chance to clean
//! up) and restarted with the same arguments resumes from the journaled rows,
//! and its final outputs are byte-identical to an uninterrupted run's.

mod campaign_common;

use campaign_common::*;
use serde_json::Value;
use std::fs;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn journal_lines(dir: &std::path::Path) -> usize {
    fs::read_to_string(dir.join("journal.jsonl"))
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

#[test]
fn campaign_resume_after_kill_gives_identical_outputs() {
    let s = Scratch::new("resume");
    let data = s.path("c.csv");
    // 10 samples x the 12 conditions of Table 2 below 4000 rpm = 120 tests
    // (the 4000 rpm points take many more revolutions to settle). The data's
    // origin does not matter here (no micromotion in the truth, for speed);
    // the campaigns run with their defaults.
    let cond = s.path("cond.csv");
    let mut conditions = Vec::new();
    for t in [60.0, 120.0] {
        for (p, n) in [
            (10.0, 1000.0),
            (20.0, 1000.0),
            (30.0, 1000.0),
            (40.0, 1000.0),
            (30.0, 500.0),
            (30.0, 2000.0),
        ] {
            conditions.push((p, n, t));
        }
    }
    write_conditions(&cond, &conditions);
    gearpump_ok(&[
        "synth",
        "--samples",
        "10",
        "--seed",
        "5",
        "--no-micromotion",
        "--conditions",
        cond.to_str().unwrap(),
        "--jobs",
        "2",
        "--out",
        data.to_str().unwrap(),
    ]);
    let total = 10 * 12;

    // Uninterrupted reference run.
    let reference = s.path("reference");
    let v: Value = serde_json::from_str(&gearpump_ok(&[
        "campaign",
        "--data",
        data.to_str().unwrap(),
        "--out",
        reference.to_str().unwrap(),
        "--jobs",
        "2",
        "--json",
    ]))
    .unwrap();
    assert_eq!(
        (v["simulated"].as_u64(), v["reused"].as_u64()),
        (Some(total), Some(0))
    );

    // Interrupted run: one thread, killed once a quarter of the rows are in
    // the journal.
    let resumed = s.path("resumed");
    let mut child = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args([
            "campaign",
            "--data",
            data.to_str().unwrap(),
            "--out",
            resumed.to_str().unwrap(),
            "--jobs",
            "1",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn gearpump");
    let start = Instant::now();
    let target = total as usize / 4;
    loop {
        if journal_lines(&resumed) >= target {
            break;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the campaign finished ({status}) before it could be killed");
        }
        assert!(start.elapsed() < Duration::from_secs(300), "no progress");
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("SIGKILL");
    child.wait().unwrap();
    let journaled = journal_lines(&resumed);
    assert!(
        journaled >= target && journaled < total as usize,
        "{journaled}"
    );
    assert!(
        !resumed.join("tests.csv").exists(),
        "killed before the outputs"
    );

    // Restart with the same arguments (another thread count is allowed).
    let v: Value = serde_json::from_str(&gearpump_ok(&[
        "campaign",
        "--data",
        data.to_str().unwrap(),
        "--out",
        resumed.to_str().unwrap(),
        "--jobs",
        "2",
        "--json",
    ]))
    .unwrap();
    let reused = v["reused"].as_u64().unwrap();
    assert!(reused as usize >= target, "reused {reused}");
    assert_eq!(v["simulated"].as_u64().unwrap() + reused, total);

    let a = files(&reference);
    let b = files(&resumed);
    assert_eq!(
        a.iter().map(|x| &x.0).collect::<Vec<_>>(),
        b.iter().map(|x| &x.0).collect::<Vec<_>>(),
        "same files, no journal or temporary file left"
    );
    for ((name, x), (_, y)) in a.iter().zip(&b) {
        assert!(
            x == y,
            "{name} differs between the resumed and the uninterrupted run"
        );
    }
    assert!(a.iter().any(|(n, _)| n == "tests.csv"));
}
