//! An output folder holds either the whole new result or the one it held
//! before, and nothing of another command's result looks current (issue 18
//! point 9; docs/interfaces.md section 5): a campaign into a folder holding
//! an earlier diagnosis removes the diagnosis's files, and a write that
//! fails half-way (a full disk, here a file size limit) leaves the previous
//! result untouched.

mod campaign_common;
use campaign_common::{gearpump, FileSizeLimit, Scratch};

use std::collections::BTreeMap;
use std::fs;
use std::path::Path;
use std::process::Command;

const HEADER: &str = "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm";

/// Two tests at 1000 rpm / 30 bar / 60 degC with measured flow `flow`.
fn write_data(path: &Path, flow: f64) {
    fs::write(
        path,
        format!(
            "{HEADER}\nN01,30,32,10,12,30,1000,60,{flow},\nN02,28,30,11,12,30,1000,60,{flow},\n"
        ),
    )
    .unwrap();
}

/// Every file under `dir` (relative path -> bytes), the journal left out.
fn result_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let rel = p.strip_prefix(dir).unwrap().display().to_string();
            if rel != "journal.jsonl" {
                out.insert(rel, fs::read(&p).unwrap());
            }
        }
    }
    out
}

fn campaign(data: &Path, out: &Path) -> Vec<String> {
    vec![
        "campaign".into(),
        "--data".into(),
        data.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--no-micromotion".into(),
    ]
}

#[test]
fn a_campaign_into_a_diagnosis_folder_leaves_nothing_of_the_diagnosis() {
    let s = Scratch::new("stale");
    let data = s.path("c.csv");
    write_data(&data, 13.5);
    let out = s.path("out");
    fs::create_dir_all(out.join("extended")).unwrap();
    for name in [
        "diagnosis.json",
        "diagnosis.svg",
        "diagnosis_features.svg",
        "curves_speed.svg",
        "extended/tests.csv",
        "extended/conditions.csv",
        "notes.txt",
    ] {
        fs::write(out.join(name), "an earlier result").unwrap();
    }
    let args = campaign(&data, &out);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let run = gearpump(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let files: Vec<String> = result_files(&out).into_keys().collect();
    assert_eq!(
        files,
        [
            "conditions.csv",
            "losses.svg",
            "notes.txt",
            "report.md",
            "residuals.svg",
            "tests.csv"
        ],
        "the earlier diagnosis's files and the stale sweep figure are gone, the user's file kept"
    );
    assert!(!out.join("extended").exists());
}

#[test]
fn a_write_failing_half_way_leaves_the_previous_result_untouched() {
    let s = Scratch::new("full-disk");
    let (a, b) = (s.path("a.csv"), s.path("b.csv"));
    write_data(&a, 13.5);
    write_data(&b, 12.0);
    let out = s.path("out");
    let args = campaign(&a, &out);
    let run = gearpump(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(run.status.success());
    let before = result_files(&out);
    assert!(before.contains_key("tests.csv") && before.contains_key("residuals.svg"));

    // The same campaign with other measured flows, under a file size limit
    // the small CSV files fit and the figures do not: a disk that fills up
    // while the result is written.
    let limited = Command::new(env!("CARGO_BIN_EXE_gearpump"))
        .args(campaign(&b, &out))
        .pre_exec_file_size_limit(8192)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&limited.stderr);
    assert_eq!(limited.status.code(), Some(1), "{err}");
    assert_eq!(
        result_files(&out),
        before,
        "the previous result is untouched ({err})"
    );
    let staging: Vec<_> = fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| {
            let n = e.unwrap().file_name().to_string_lossy().into_owned();
            n.starts_with('.').then_some(n)
        })
        .collect();
    assert!(staging.is_empty(), "{staging:?}");

    // without the limit the same command completes (from the journal)
    let args = campaign(&b, &out);
    let run = gearpump(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(run.status.success());
    assert_ne!(result_files(&out)["tests.csv"], before["tests.csv"]);
}
