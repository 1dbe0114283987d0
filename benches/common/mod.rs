//! What the plain-timing benchmarks (campaign, diagnose) share: their
//! command line `-- JOBS REPS`, the bundled design and the demo campaign.

use std::path::PathBuf;

use gearpump::campaign::run::DesignSource;

/// The demo campaign, the bundled design, and `JOBS REPS` from the command
/// line (cargo's own `--bench` flag is skipped) with these defaults.
pub fn setup(default_reps: usize) -> (PathBuf, DesignSource, usize, usize) {
    let mut args = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .filter_map(|a| a.parse::<usize>().ok());
    let jobs = args.next().unwrap_or(2);
    let reps = args.next().unwrap_or(default_reps).max(1);
    let data =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/demo_campaign/campaign.csv");
    let source = match DesignSource::load(None, &[]) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("design: {e}");
            std::process::exit(1);
        }
    };
    (data, source, jobs, reps)
}
