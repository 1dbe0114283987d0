//! End-to-end diagnosis benchmark: `gearpump diagnose` on the bundled demo
//! campaign (20 pumps x the 14 conditions of seed Table 2 = 280 tests, hidden
//! thermal_clearance) on 2 threads with gear micromotion: the baseline
//! campaign, the findings, fitting and cross-validating the seven candidate
//! extensions, the extended run, the report and figures. Each repetition
//! starts from an empty output folder (no journal reuse). Prints the wall
//! time, the candidate stage's share and the model runs it took.
//!
//! Run: `cargo bench --bench diagnose` (optionally `-- JOBS REPS`).
//! Plain timing (no criterion): one run takes tens of seconds. Target: at
//! most 60 s on 2 cores.

use std::time::Instant;

use gearpump::campaign::run::Silent;
use gearpump::diagnosis::diagnose::{run_diagnosis, DiagnoseOptions};

mod common;

fn main() {
    let (data, source, jobs, reps) = common::setup(1);
    for rep in 0..reps {
        let out = std::env::temp_dir().join(format!(
            "gearpump-bench-diagnose-{}-{rep}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&out);
        let t0 = Instant::now();
        let cpu0 = cpu_seconds();
        let result = run_diagnosis(
            &source,
            &data,
            &out,
            DiagnoseOptions {
                jobs: Some(jobs),
                ..DiagnoseOptions::default()
            },
            &Silent,
        );
        let wall = t0.elapsed().as_secs_f64();
        let cpu = cpu_seconds() - cpu0;
        let _ = std::fs::remove_dir_all(&out);
        match result {
            Ok(d) => println!(
                "diagnose/demo-280-tests jobs={jobs}: {wall:.1} s wall ({cpu:.1} s CPU), candidate stage {:.1} s, {} model runs, cause {:?}, RMSE ratio {:.3}",
                d.json["candidate_stage_s"].as_f64().unwrap_or(f64::NAN),
                d.runs,
                d.cause,
                d.extended_rmse.unwrap_or(f64::NAN) / d.baseline_rmse
            ),
            Err(e) => {
                eprintln!("diagnose failed: {e}");
                std::process::exit(1);
            }
        }
    }
}

/// CPU time of this process (user + system), from /proc/self/stat; NaN where
/// that file does not exist.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // fields after the command name (which is in parentheses)
    let Some(rest) = stat.rsplit_once(')').map(|(_, r)| r) else {
        return f64::NAN;
    };
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        f.get(i)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    // utime and stime are fields 14 and 15 of the line: 12 and 13 after ')'
    (ticks(11) + ticks(12)) / 100.0
}
