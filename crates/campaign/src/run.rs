//! Trace-driven campaign runs: every test simulated with its own sample's
//! measured clearances, in parallel, journaled row by row so an interrupted
//! run resumes where it stopped.
//!
//! # One test
//! [`simulate_test`]: the model at the row's working condition (speed, delivery
//! pressure above a suction of 1 atm absolute, oil temperature), with the
//! row's measured tip and bearing clearances and the design's nominal lateral
//! clearance (the seed's assumption), the row's measured shaft torque (for the
//! mesh force, seed Eq. 8; `None` when the cell is empty) and gear
//! micromotion on, run to the periodic steady state. `eta_v` of the
//! measurement and of the simulation both use the nominal displacement of the
//! design (seed Eqs. 15/16); `d = eta_v,meas - eta_v,sim` (Eq. 17).
//!
//! # Parallel, resumable, deterministic
//! The design's look-up tables are built once and shared by reference; rows
//! run on a rayon pool of `jobs` threads. Each finished row is appended to the
//! journal (`journal.jsonl`, flushed and fsynced per row, see
//! [`super::io::Journal`]), so a run killed at any moment (Ctrl-C, SIGKILL,
//! power loss) loses at most the rows in flight. Rerun with the same
//! arguments, it reuses the journaled rows whose fingerprint (code version,
//! design text, `--set` list, micromotion switch, the row's inputs) still
//! matches and simulates the rest. Each row's result depends on that row
//! only and the journal stores floats exactly, so the final outputs are
//! byte-identical to an uninterrupted run, whatever the number of threads.
//! The outputs are written into a staging folder and moved into the output
//! folder together (`super::io`, "Output folders"), then the journal is
//! removed.
//!
//! A row whose simulation fails (solver failure) is recorded with empty
//! simulated cells, left out of the statistics, listed in `report.md` and in
//! the result; the outputs are still written (the `gearpump` command then
//! exits 1, saying how many rows failed).

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;
use serde::Serialize;
use serde_json::json;
use thiserror::Error;

use super::data::{group_by_condition, read_campaign, Campaign, DataError, TestRow};
use super::effects::{EffectError, EffectModel};
use super::io::{
    atomic_write_text, write_conditions_csv, write_tests_csv, Journal, JournalError, OutputError,
    RowResult, RunFingerprint, Staging, TestOutcome, LOSS_COLUMNS,
};
use super::stats::{add_torque_stats, eta_v, summarize, ConditionSummary, StatsError, ALPHA};
use super::{plots, report};
use gearpump_core::design::{self, Design, DesignError};
use gearpump_core::model::{Inputs, ModelError, Options, Pump, SampleClearances, Summary};
use gearpump_core::units::{kelvin_to_celsius, lpm_to_m3_s, m3_s_to_lpm, ATMOSPHERE_PA};

/// Output file names written by `campaign` besides `tests.csv` and
/// `conditions.csv`.
pub const REPORT_MD: &str = "report.md";

/// Errors of `campaign` and `synth`. [`RunError::is_bad_input`] tells the
/// CLI which exit code to use.
#[derive(Debug, Error)]
pub enum RunError {
    #[error(transparent)]
    Data(#[from] DataError),
    #[error("{0}")]
    Design(#[from] DesignError),
    #[error(transparent)]
    Effect(#[from] EffectError),
    #[error(transparent)]
    Conditions(#[from] super::conditions::ConditionsError),
    #[error("{file}: row {row}, column {column}: {message}")]
    Range {
        file: String,
        row: usize,
        column: &'static str,
        message: String,
    },
    /// A setting of the run out of its range, in the library's terms (the
    /// command line names its flag, [`Setting`]).
    #[error("{}: {message}", setting.name())]
    Setting { setting: Setting, message: String },
    #[error(transparent)]
    Journal(#[from] JournalError),
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("statistics: {0}")]
    Stats(#[from] StatsError),
    #[error("row {row}: simulation failed: {source}")]
    Model {
        row: usize,
        #[source]
        source: ModelError,
    },
    #[error("plot {file}: {message}")]
    Plot { file: String, message: String },
    #[error("thread pool: {0}")]
    Pool(String),
}

impl RunError {
    /// True for errors in what the user gave (exit code 2).
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            RunError::Data(_)
                | RunError::Design(_)
                | RunError::Effect(_)
                | RunError::Conditions(_)
                | RunError::Range { .. }
                | RunError::Setting { .. }
        )
    }
}

/// The settings of a run that a caller chooses (each front end names them
/// its own way: the command line by its flags).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Setting {
    /// Worker threads.
    Jobs,
    /// Pump samples of a synthetic campaign.
    Samples,
    /// Rig noise of a synthetic campaign.
    Noise,
    /// The measured campaign.
    Data,
    /// The output folder.
    Output,
    /// The effects drawn by an evaluation.
    Effects,
    /// Trials of an evaluation.
    Trials,
    /// The trials of an evaluation's plan to run.
    Only,
    /// The effect families an evaluation plants.
    Families,
}

impl Setting {
    /// The setting's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Setting::Jobs => "jobs",
            Setting::Samples => "samples",
            Setting::Noise => "noise",
            Setting::Data => "data",
            Setting::Output => "output folder",
            Setting::Effects => "effects",
            Setting::Trials => "trials",
            Setting::Only => "only",
            Setting::Families => "families",
        }
    }
}

/// The design a run uses, with the text that identifies it.
#[derive(Debug, Clone)]
pub struct DesignSource {
    /// The validated design (overrides applied).
    pub design: Design,
    /// The design file's text (the bundled text when no file was given).
    pub text: String,
    /// `bundled seed pump` or the file path, for reports.
    pub label: String,
    /// The `--set` overrides, in order.
    pub sets: Vec<String>,
}

impl DesignSource {
    /// The bundled design when `path` is None; `sets` are `--set` overrides.
    pub fn load(path: Option<&Path>, sets: &[String]) -> Result<DesignSource, RunError> {
        let (text, label) = match path {
            None => (
                design::SEED_PUMP_TOML.to_string(),
                "bundled seed pump".to_string(),
            ),
            Some(p) => (
                fs::read_to_string(p).map_err(|e| DesignError::Io {
                    path: p.display().to_string(),
                    message: e.to_string(),
                })?,
                p.display().to_string(),
            ),
        };
        let design = match path {
            Some(p) => design::from_toml_file_text(&text, sets, &p.display().to_string())?,
            None => design::from_toml_str(&text, sets)?,
        };
        Ok(DesignSource {
            design,
            text,
            label,
            sets: sets.to_vec(),
        })
    }
}

/// Receives progress of a run (the library never prints).
pub trait Observer: Sync {
    /// `total` rows, of which `reused` come from the journal.
    fn begin(&self, _total: usize, _reused: usize) {}
    /// One more row simulated.
    fn advance(&self) {}
    /// The run's rows are done.
    fn end(&self) {}
    /// A line of narration (a stage begun, a model run), for a verbose
    /// front end.
    fn message(&self, _text: &str) {}
    /// A new stage of `total` steps begins (e.g. one per candidate); its
    /// progress comes through [`Observer::advance`] and ends with
    /// [`Observer::end`].
    fn stage(&self, _label: &str, total: usize) {
        self.begin(total, 0);
    }
    /// A one-line summary of a finished stage, for every front end (a
    /// terminal or a log).
    fn summary(&self, _line: &str) {}
}

/// An observer that ignores everything.
#[derive(Debug, Default, Clone, Copy)]
pub struct Silent;
impl Observer for Silent {}

/// A version string that changes whenever the binary changes: the crate
/// version plus the running executable's size and modification time. Part of
/// the journal fingerprint, so rows simulated by an older build are not
/// reused.
pub fn code_version() -> String {
    let mut s = format!("gearpump {}", env!("CARGO_PKG_VERSION"));
    if let Some(meta) = std::env::current_exe()
        .ok()
        .and_then(|p| fs::metadata(p).ok())
    {
        s.push_str(&format!(" exe {}", meta.len()));
        if let Some(t) = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        {
            s.push_str(&format!(" {}", t.as_nanos()));
        }
    }
    s
}

/// The number of threads a run uses for the jobs asked: `jobs`, or all
/// cores when None; more than the available parallelism is clamped to it
/// (the simulations are CPU-bound: more threads than cores only cost
/// memory, and 100000 jobs started thousands of threads), and the number
/// asked for is returned beside it so the caller can say so. 0 is refused.
pub fn pool_size(jobs: Option<usize>) -> Result<(usize, Option<usize>), RunError> {
    let cores = std::thread::available_parallelism()
        .map(usize::from)
        .unwrap_or(1);
    match jobs {
        Some(0) => Err(RunError::Setting {
            setting: Setting::Jobs,
            message: "must be >= 1".into(),
        }),
        None => Ok((cores, None)),
        Some(n) if n > cores => Ok((cores, Some(n))),
        Some(n) => Ok((n, None)),
    }
}

/// Runs `f` on a rayon pool of [`pool_size`] threads.
pub fn with_pool<T: Send>(
    jobs: Option<usize>,
    f: impl FnOnce() -> T + Send,
) -> Result<T, RunError> {
    let (n, _) = pool_size(jobs)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map_err(|e| RunError::Pool(e.to_string()))?;
    Ok(pool.install(f))
}

/// The operating inputs of a test row: suction at 1 atm absolute, delivery
/// the row's gauge pressure above it.
pub fn test_inputs(row: &TestRow, measured_torque: Option<f64>) -> Inputs {
    Inputs {
        omega: row.speed,
        p_suction: ATMOSPHERE_PA,
        p_delivery: ATMOSPHERE_PA + row.pressure,
        temp_k: row.temp,
        measured_torque,
    }
}

/// A row's measured clearances, with the design's nominal lateral clearance.
pub fn measured_clearances(design: &Design, row: &TestRow) -> SampleClearances {
    SampleClearances {
        tip: row.tip_clearance,
        bearing: row.bearing_clearance,
        lateral: design.clearance.lateral,
    }
}

/// Simulates one test row with `model` to the periodic steady state.
pub fn simulate_test(
    model: &EffectModel,
    row: &TestRow,
    measured_torque: Option<f64>,
    micromotion: bool,
) -> Result<Summary, ModelError> {
    let inputs = test_inputs(row, measured_torque);
    let measured = measured_clearances(&model.pump().design, row);
    let options = Options { micromotion };
    let mut sim = model.simulation(inputs, measured, options)?;
    sim.run_periodic()
}

/// Refuses rows the model cannot run (temperature outside the oil model's
/// range) before anything is simulated, naming file, row and column.
pub fn check_rows_in_range(campaign: &Campaign, design: &Design) -> Result<(), RunError> {
    let oil = &design.oil;
    for r in &campaign.rows {
        if !oil.in_range(r.temp) {
            return Err(RunError::Range {
                file: campaign.file.clone(),
                row: r.row,
                column: "temp_c",
                message: format!(
                    "{} degC is outside the oil model's range [{}, {}] degC",
                    r.condition.temp_c,
                    kelvin_to_celsius(oil.t_min_k),
                    kelvin_to_celsius(oil.t_max_k)
                ),
            });
        }
    }
    Ok(())
}

/// Options of a campaign run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CampaignOptions {
    /// Threads; None = all cores.
    pub jobs: Option<usize>,
    /// Gear micromotion coupling (on for campaigns).
    pub micromotion: bool,
}

impl Default for CampaignOptions {
    fn default() -> Self {
        CampaignOptions {
            jobs: None,
            micromotion: true,
        }
    }
}

/// A failed row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FailedRow {
    /// 1-based data row (header not counted).
    pub row: usize,
    pub sample: String,
    pub message: String,
}

/// What a campaign run produced.
#[derive(Debug, Clone)]
pub struct CampaignResult {
    /// The campaign as read.
    pub campaign: Campaign,
    /// One outcome per row, in input order.
    pub outcomes: Vec<TestOutcome>,
    /// Per working condition, in order of first appearance.
    pub summaries: Vec<ConditionSummary>,
    /// Rows simulated by this invocation.
    pub simulated: usize,
    /// Rows reused from the journal.
    pub reused: usize,
    pub failed: Vec<FailedRow>,
    /// Rows whose simulated pump delivers nothing or backwards
    /// (`Summary::warnings`), one line each.
    pub warnings: Vec<String>,
    /// Nominal displacement used for eta_v, m^3/rev.
    pub displacement: f64,
    /// Files written, in the output folder.
    pub files: Vec<PathBuf>,
}

impl CampaignResult {
    /// The `--json` object of `gearpump campaign`.
    pub fn to_json(&self, out: &Path, wall_ms: f64) -> serde_json::Value {
        let d: Vec<f64> = self.outcomes.iter().map(|o| o.d).collect();
        let rmse = rms(&d);
        let dnu_max = self
            .summaries
            .iter()
            .filter_map(|s| s.stats.delta_nu)
            .fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))));
        json!({
            "data": self.campaign.file,
            "out": out.display().to_string(),
            "tests": self.campaign.rows.len(),
            "samples": sample_ids(&self.campaign.rows).len(),
            "conditions": self.summaries,
            "alpha": ALPHA,
            "rmse": rmse,
            "delta_nu_max": dnu_max,
            "displacement_cm3": self.displacement * 1e6,
            "simulated": self.simulated,
            "reused": self.reused,
            "failed": self.failed,
            "files": self.files.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
            "wall_ms": wall_ms,
        })
    }
}

impl CampaignResult {
    /// A few lines for a terminal: size, the worst condition, where the
    /// outputs are.
    pub fn summary_text(&self, out: &Path) -> String {
        let d: Vec<f64> = self.outcomes.iter().map(|o| o.d).collect();
        let mut s = format!(
            "{} tests ({} samples, {} conditions): {} simulated, {} resumed from the journal, {} failed\n",
            self.campaign.rows.len(),
            sample_ids(&self.campaign.rows).len(),
            self.summaries.len(),
            self.simulated,
            self.reused,
            self.failed.len()
        );
        s.push_str("p_bar  n_rpm  T_degC  n_s    d_mean      S_d   delta_nu\n");
        let f = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
        for c in &self.summaries {
            s.push_str(&format!(
                "{:>5} {:>6} {:>7} {:>4} {:>9} {:>8} {:>10}\n",
                c.condition.pressure_bar,
                c.condition.speed_rpm,
                c.condition.temp_c,
                c.stats.n_samples,
                f(c.stats.d_mean),
                f(c.stats.d_std),
                f(c.stats.delta_nu)
            ));
        }
        s.push_str(&format!(
            "RMS of d {}; outputs in {}",
            f(rms(&d)),
            out.display()
        ));
        s
    }
}

/// Root mean square of the finite values (None when there are none).
pub fn rms(v: &[f64]) -> Option<f64> {
    let f: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if f.is_empty() {
        None
    } else {
        Some((f.iter().map(|x| x * x).sum::<f64>() / f.len() as f64).sqrt())
    }
}

/// Sample ids in order of first appearance.
pub fn sample_ids(rows: &[TestRow]) -> Vec<String> {
    let mut seen = BTreeSet::new();
    let mut ids = Vec::new();
    for r in rows {
        if seen.insert(r.sample.as_str()) {
            ids.push(r.sample.clone());
        }
    }
    ids
}

/// The loss budget a row's result carries (NaN where it has none).
fn row_losses(r: &RowResult) -> [f64; LOSS_COLUMNS] {
    let mut out = [f64::NAN; LOSS_COLUMNS];
    if let Some(v) = r.extra.as_ref().and_then(|x| x.get("losses")) {
        if let Some(a) = v.as_array().filter(|a| a.len() == LOSS_COLUMNS) {
            for (o, x) in out.iter_mut().zip(a) {
                *o = x.as_f64().unwrap_or(f64::NAN);
            }
        }
    }
    out
}

fn row_result(summary: Result<Summary, ModelError>) -> RowResult {
    match summary {
        Ok(s) => RowResult {
            flow_lpm_sim: m3_s_to_lpm(s.flow),
            torque_nm_sim: s.torque,
            eta_v_sim: s.eta_v,
            extra: Some(json!({
                "converged": s.converged,
                "revolutions": s.revolutions,
                "losses": s.losses.map(|b| b.parts().map(|(_, v)| v)),
            })),
        },
        Err(e) => RowResult {
            flow_lpm_sim: f64::NAN,
            torque_nm_sim: f64::NAN,
            eta_v_sim: f64::NAN,
            extra: Some(json!({ "error": e.to_string() })),
        },
    }
}

/// `gearpump campaign`: reads `data`, simulates every row (reusing the
/// journal in `out`), writes `tests.csv`, `conditions.csv`, `report.md` and
/// the plots into `out`: staged, then moved in, so `out` holds either the
/// whole new result or the one it held before (`super::io`, "Output
/// folders").
pub fn run_campaign(
    source: &DesignSource,
    data: &Path,
    out: &Path,
    options: CampaignOptions,
    observer: &dyn Observer,
) -> Result<CampaignResult, RunError> {
    let (mut result, journal, stage) = run_campaign_staged(source, data, out, options, observer)?;
    result.files = result.files.iter().map(|f| stage.final_path(f)).collect();
    stage.commit()?;
    journal.finish()?;
    Ok(result)
}

/// Each row's outcome from its simulated result (`done`, by row index; a
/// row without one is a failure) at `displacement`, and the rows that
/// failed.
fn outcomes_of(
    campaign: &Campaign,
    done: &std::collections::HashMap<usize, RowResult>,
    displacement: f64,
) -> (Vec<TestOutcome>, Vec<FailedRow>) {
    let mut outcomes = Vec::with_capacity(campaign.rows.len());
    let mut failed = Vec::new();
    for (i, row) in campaign.rows.iter().enumerate() {
        let r = done.get(&i).cloned().unwrap_or(RowResult {
            flow_lpm_sim: f64::NAN,
            torque_nm_sim: f64::NAN,
            eta_v_sim: f64::NAN,
            extra: None,
        });
        if !r.flow_lpm_sim.is_finite() {
            let message = r
                .extra
                .as_ref()
                .and_then(|x| x.get("error"))
                .and_then(|x| x.as_str())
                .unwrap_or("no result")
                .to_string();
            failed.push(FailedRow {
                row: row.row,
                sample: row.sample.clone(),
                message,
            });
        }
        let eta_v_meas = eta_v(row.flow, displacement, row.speed);
        let eta_v_sim = eta_v(lpm_to_m3_s(r.flow_lpm_sim), displacement, row.speed);
        outcomes.push(TestOutcome {
            flow_lpm_sim: r.flow_lpm_sim,
            eta_v_meas,
            eta_v_sim,
            d: eta_v_meas - eta_v_sim,
            torque_nm_sim: r.torque_nm_sim,
            losses: row_losses(&r),
        });
    }
    (outcomes, failed)
}

/// One warning per row whose simulated pump delivers nothing or backwards.
fn delivery_warnings(campaign: &Campaign, outcomes: &[TestOutcome]) -> Vec<String> {
    campaign
    .rows
    .iter()
    .zip(outcomes)
    .filter(|(_, o)| o.eta_v_sim <= 0.0)
    .map(|(r, o)| {
        format!(
            "row {} (sample {}, {} bar, {} rpm, {} degC): the simulated pump delivers nothing or backwards (eta_v {:.3}): outside its operating range",
            r.row,
            r.sample,
            r.condition.pressure_bar,
            r.condition.speed_rpm,
            r.condition.temp_c,
            o.eta_v_sim
        )
    })
    .collect()
}

/// [`run_campaign`] up to its result written into a staging folder of
/// `out`, not yet committed (its `files` are in the staging folder), and
/// the journal, not yet finished: `diagnose` adds its own files to the same
/// result before the commit.
pub fn run_campaign_staged(
    source: &DesignSource,
    data: &Path,
    out: &Path,
    options: CampaignOptions,
    observer: &dyn Observer,
) -> Result<(CampaignResult, Journal, Staging), RunError> {
    let campaign = read_campaign(data)?;
    check_rows_in_range(&campaign, &source.design)?;
    if out.exists() && !out.is_dir() {
        return Err(RunError::Setting {
            setting: Setting::Output,
            message: format!("{} exists and is not a directory", out.display()),
        });
    }
    fs::create_dir_all(out).map_err(|e| RunError::Io {
        path: out.to_path_buf(),
        source: e,
    })?;
    let mut run_args = source.sets.clone();
    run_args.push(format!("#micromotion={}", options.micromotion));
    run_args.push(format!("#p_suction_pa={ATMOSPHERE_PA}"));
    let fingerprint = RunFingerprint::new(&source.text, &run_args, &code_version(), &campaign.rows);
    let journal = Journal::open(out, &fingerprint)?;
    let mut done = journal.done();
    let reused = done.len();
    let mut todo: Vec<usize> = (0..campaign.rows.len())
        .filter(|i| !done.contains_key(i))
        .collect();
    // Longest first (the periodic state takes more revolutions at high
    // speed), one row per task: the last rows to finish are short ones.
    // Results do not depend on the order.
    todo.sort_by(|&a, &b| campaign.rows[b].speed.total_cmp(&campaign.rows[a].speed));
    observer.begin(campaign.rows.len(), reused);

    let displacement = if todo.is_empty() {
        source.design.pair().displacement_closed_form()
    } else {
        let pump = Arc::new(Pump::new(source.design.clone()));
        let model = EffectModel::on(&pump, &[])?;
        let rows = &campaign.rows;
        let journal_ref = &journal;
        let fresh: Vec<(usize, RowResult)> = with_pool(options.jobs, || {
            todo.par_iter()
                .with_max_len(1)
                .map(|&i| {
                    let row = &rows[i];
                    let r = row_result(simulate_test(&model, row, row.torque, options.micromotion));
                    journal_ref.record(i, &r)?;
                    observer.advance();
                    Ok((i, r))
                })
                .collect::<Result<Vec<_>, JournalError>>()
        })??;
        done.extend(fresh);
        pump.displacement
    };
    observer.end();

    let (outcomes, failed) = outcomes_of(&campaign, &done, displacement);
    let d: Vec<f64> = outcomes.iter().map(|o| o.d).collect();
    let groups = group_by_condition(&campaign.rows);
    let mut summaries = summarize(&groups, &d, ALPHA)?;
    let torque_sim: Vec<f64> = outcomes.iter().map(|o| o.torque_nm_sim).collect();
    add_torque_stats(
        &mut summaries,
        &groups,
        &campaign.rows,
        &torque_sim,
        displacement,
    );

    let stage = Staging::new(out)?;
    let dir = stage.path();
    let mut files = vec![
        write_tests_csv(dir, &campaign, &outcomes)?,
        write_conditions_csv(dir, &summaries)?,
    ];
    let figures = plots::write_plots(dir, &campaign.rows, &outcomes)?;
    let report = report::campaign_report(&report::ReportInput {
        campaign: &campaign,
        outcomes: &outcomes,
        summaries: &summaries,
        failed: &failed,
        design_label: &source.label,
        sets: &source.sets,
        micromotion: options.micromotion,
        displacement,
        figures: &figures,
    });
    let report_path = dir.join(REPORT_MD);
    atomic_write_text(&report_path, &report)?;
    files.push(report_path);
    files.extend(figures.iter().map(|f| dir.join(&f.file)));
    let warnings = delivery_warnings(&campaign, &outcomes);
    let result = CampaignResult {
        campaign,
        outcomes,
        summaries,
        simulated: todo.len(),
        reused,
        failed,
        warnings,
        displacement,
        files,
    };
    Ok((result, journal, stage))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--jobs` above the available parallelism is clamped to it, with a
    /// note (issue 18 point 7: `--jobs 100000` started thousands of
    /// threads); 0 is refused.
    #[test]
    fn jobs_are_bounded_by_the_cores() {
        let cores = std::thread::available_parallelism()
            .map(usize::from)
            .unwrap_or(1);
        let threads = with_pool(Some(cores + 1), rayon::current_num_threads).unwrap();
        assert_eq!(threads, cores);
        let (n, note) = pool_size(Some(100_000)).unwrap();
        assert_eq!(n, cores);
        assert_eq!(note, Some(100_000));
        assert_eq!(pool_size(Some(1)).unwrap(), (1, None));
        assert_eq!(pool_size(None).unwrap(), (cores, None));
        let e = pool_size(Some(0)).unwrap_err();
        assert!(
            matches!(
                e,
                RunError::Setting {
                    setting: Setting::Jobs,
                    ..
                }
            ) && e.to_string().starts_with("jobs: "),
            "{e}"
        );
    }
}
