//! End-to-end campaign benchmark: the bundled demo campaign (20 samples x the
//! 14 conditions of seed Table 2 = 280 tests) through `run_campaign` on 2
//! threads with gear micromotion on: reading and validating the CSV,
//! building the design's tables, simulating every test, the statistics and
//! writing tests.csv, conditions.csv, report.md and the plots. Each repetition
//! starts from an empty output folder (no journal reuse).
//!
//! Run: `cargo bench --bench campaign` (optionally `-- JOBS REPS`).
//! Plain timing (no criterion): one end-to-end run takes seconds.

use std::time::Instant;

use gearpump::campaign::run::{run_campaign, CampaignOptions, Silent};

mod common;

fn main() {
    let (data, source, jobs, reps) = common::setup(3);
    let mut times = Vec::new();
    for rep in 0..reps {
        let out = std::env::temp_dir().join(format!(
            "gearpump-bench-campaign-{}-{rep}",
            std::process::id()
        ));
        let _ = std::fs::remove_dir_all(&out);
        let t0 = Instant::now();
        let result = run_campaign(
            &source,
            &data,
            &out,
            CampaignOptions {
                jobs: Some(jobs),
                micromotion: true,
            },
            &Silent,
        );
        let wall = t0.elapsed().as_secs_f64();
        let _ = std::fs::remove_dir_all(&out);
        match result {
            Ok(r) => {
                println!(
                    "campaign_280_tests_{jobs}_threads_micromotion: run {}: {:.2} s wall ({} tests, {} failed)",
                    rep + 1,
                    wall,
                    r.campaign.rows.len(),
                    r.failed.len()
                );
                times.push(wall);
            }
            Err(e) => {
                eprintln!("campaign failed: {e}");
                std::process::exit(1);
            }
        }
    }
    times.sort_by(f64::total_cmp);
    println!(
        "campaign_280_tests_{jobs}_threads_micromotion: median {:.2} s wall over {} runs",
        times[times.len() / 2],
        times.len()
    );
}
