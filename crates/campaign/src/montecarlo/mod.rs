//! Monte Carlo tolerance analysis (`gearpump montecarlo`, and the Python
//! package's `gearpump.montecarlo`): what manufacturing tolerances of the
//! clearances do to a production population.
//!
//! # What a study is
//! `pumps` pumps are drawn from the clearance [`population`] (the paper's
//! statistics by default, a population fitted to a measured campaign, or
//! the user's distributions), each by its own counter-based random stream,
//! and every pump is simulated at every condition (the paper's 14 by
//! default) with the design given (its extension keys, e.g. a diagnosed
//! `extended_design.toml`, act as in `simulate`), no measured torque,
//! suction at 1 atm. Per condition the study reports the distribution of
//! `eta_v`, flow and shaft torque ([`estimators::distribution`]: mean,
//! standard deviation, 1/5/50/95/99th percentiles), the yield against the
//! user's [`spec`], and the first-order and total Sobol index of each
//! clearance on each quantity ([`estimators::sobol_indices`]).
//!
//! # The runs: items and rows
//! The study's *items* are the pumps to simulate: items `0..pumps` are the
//! drawn pumps; with sensitivity on, pumps `2j` and `2j + 1`
//! (`j < pumps / 2`) are the pick-freeze pair `A_j`, `B_j`, and items
//! `pumps + 4j + i` are the hybrids `A_B^i`: pump `2j` with clearance `i`
//! from pump `2j + 1`. So the distributions and yields use all `pumps`
//! pumps, and the indices cost `2 pumps` runs more per condition (3x the
//! runs in all). Row `r` is item `r / C` at condition `r % C` (`C`
//! conditions). Every item's clearances follow from the seed and its index
//! alone ([`Study::clearances`]), so any range of items (a *chunk*) runs
//! anywhere and gives the same numbers: the Python package sends chunks to
//! Dask workers.
//!
//! # Resumable
//! As `campaign`'s journal (`crate::io`), per chunk: each finished chunk
//! of items is appended to `montecarlo-journal.jsonl` in the output folder, one JSON
//! line with its rows' results (floats as text, exact) and a 64-bit FNV-1a
//! fingerprint of everything that determines them (code version, design
//! text, `--set` list, micromotion, the population, conditions, pumps,
//! seed, sensitivity switch, chunk size and the chunk's index). A rerun
//! with the same arguments reuses the chunks whose fingerprint matches;
//! entries that no longer match or do not parse (a torn last line) are
//! dropped. The specification is not part of the fingerprint: a new spec
//! reuses every simulation. The outputs are staged and moved in together
//! (`crate::io`, "Output folders"), then the journal is removed; a resumed
//! study writes the same bytes as an uninterrupted one.
//!
//! # Outputs (in `--out`)
//! `montecarlo.json` (everything below, and the study), `percentiles.csv`
//! (per condition and quantity: n, mean, std, min, max, percentiles),
//! `sensitivity.csv` (per condition, quantity and clearance: first-order
//! and total index), `pumps.csv` (every drawn pump at every condition:
//! clearances and results), `cdf.svg` (the CDF of eta_v, flow and torque,
//! one line per condition) and `tornado.svg` (the indices of each
//! clearance on eta_v and torque at the focus condition: the first spec's,
//! else the one where eta_v varies most).

pub mod estimators;
pub mod figures;
pub mod population;
pub mod spec;

use std::fs;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::json;
use thiserror::Error;

pub use estimators::{Distribution, SobolIndex, Yield};
pub use population::{Dist, Population, CLEARANCES};
pub use spec::{Op, Spec};

use crate::data::Condition;
use crate::effects::EffectModel;
use crate::io::{atomic_write_text, float_cell, push_csv_row, Fnv1a, Staging};
use crate::run::{code_version, with_pool, DesignSource, Observer, RunError};
use gearpump_core::design::Design;
use gearpump_core::limits;
use gearpump_core::model::{Inputs, Options, SampleClearances};
use gearpump_core::units::{
    bar_to_pa, celsius_to_kelvin, kelvin_to_celsius, m3_s_to_lpm, rpm_to_rad_s, um_to_m,
    ATMOSPHERE_PA,
};

/// The journal's file name (its own: a `campaign` journal in the same folder
/// is left alone).
pub const JOURNAL_FILE: &str = "montecarlo-journal.jsonl";
/// The result's files.
pub const OUTPUT_FILES: [&str; 6] = [
    "montecarlo.json",
    "percentiles.csv",
    "sensitivity.csv",
    "pumps.csv",
    "cdf.svg",
    "tornado.svg",
];
/// The largest study accepted (pumps).
pub const MAX_PUMPS: usize = 10_000_000;

/// A quantity of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Quantity {
    #[serde(rename = "eta_v")]
    EtaV,
    #[serde(rename = "flow_lpm")]
    FlowLpm,
    #[serde(rename = "torque_nm")]
    TorqueNm,
}

impl Quantity {
    pub const ALL: [Quantity; 3] = [Quantity::EtaV, Quantity::FlowLpm, Quantity::TorqueNm];
    pub fn name(self) -> &'static str {
        match self {
            Quantity::EtaV => "eta_v",
            Quantity::FlowLpm => "flow_lpm",
            Quantity::TorqueNm => "torque_nm",
        }
    }
    pub fn from_name(s: &str) -> Option<Quantity> {
        match s {
            "eta_v" => Some(Quantity::EtaV),
            "flow_lpm" | "flow" => Some(Quantity::FlowLpm),
            "torque_nm" | "torque" => Some(Quantity::TorqueNm),
            _ => None,
        }
    }
}

/// Errors of a study. [`MonteCarloError::is_bad_input`] picks the exit code.
#[derive(Debug, Error)]
pub enum MonteCarloError {
    #[error("{file}: {message}")]
    Population { file: String, message: String },
    #[error("spec {0}")]
    Spec(String),
    /// A study setting out of its range (`pumps`, `chunk`, `conditions`).
    #[error("{setting}: {message}")]
    Setting {
        setting: &'static str,
        message: String,
    },
    #[error(transparent)]
    Run(#[from] RunError),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("plot {file}: {message}")]
    Plot { file: String, message: String },
}

impl MonteCarloError {
    pub fn is_bad_input(&self) -> bool {
        match self {
            MonteCarloError::Population { .. }
            | MonteCarloError::Spec(_)
            | MonteCarloError::Setting { .. } => true,
            MonteCarloError::Run(e) => e.is_bad_input(),
            _ => false,
        }
    }
}

fn setting(setting: &'static str, message: String) -> MonteCarloError {
    MonteCarloError::Setting { setting, message }
}

/// What a study simulates (see the module doc).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Study {
    pub population: Population,
    /// The study's conditions (the specs' added at the end when missing).
    pub conditions: Vec<Condition>,
    pub pumps: usize,
    pub seed: u64,
    /// Pick-freeze runs for the Sobol indices.
    pub sensitivity: bool,
    pub specs: Vec<Spec>,
    pub micromotion: bool,
}

fn same_condition(a: &Condition, b: &Condition) -> bool {
    let k = |x: f64| (x / 1e-6).round() as i64;
    k(a.pressure_bar) == k(b.pressure_bar)
        && k(a.speed_rpm) == k(b.speed_rpm)
        && k(a.temp_c) == k(b.temp_c)
}

impl Study {
    /// A checked study: at least one pump (four with sensitivity), every
    /// condition (the specs' included) inside the model's ranges.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        design: &Design,
        population: Population,
        conditions: Vec<Condition>,
        pumps: usize,
        seed: u64,
        sensitivity: bool,
        specs: Vec<Spec>,
        micromotion: bool,
    ) -> Result<Study, MonteCarloError> {
        let least = if sensitivity { 4 } else { 1 };
        if pumps < least || pumps > MAX_PUMPS {
            return Err(setting(
                "pumps",
                format!(
                    "must be in [{least}, {MAX_PUMPS}]{}, got {pumps}",
                    if sensitivity {
                        " (the sensitivity indices need two pairs)"
                    } else {
                        ""
                    }
                ),
            ));
        }
        // each condition checked against the model's ranges, a spec's under
        // its own flag (the user typed it there)
        let check = |c: &Condition, flag: &'static str| -> Result<(), MonteCarloError> {
            let label = condition_label(c);
            limits::SPEED_RPM
                .check(c.speed_rpm)
                .map_err(|e| setting(flag, format!("{label}: {e}")))?;
            limits::PRESSURE_BAR
                .check(c.pressure_bar)
                .map_err(|e| setting(flag, format!("{label}: {e}")))?;
            limits::delivery_bar_abs(limits::ATMOSPHERE_BAR, c.pressure_bar)
                .map_err(|e| setting(flag, format!("{label}: {e}")))?;
            let t = celsius_to_kelvin(c.temp_c);
            if !(c.temp_c.is_finite() && design.oil.in_range(t)) {
                return Err(setting(
                    flag,
                    format!(
                        "{label}: {} degC is outside the oil model's range [{}, {}] degC",
                        c.temp_c,
                        kelvin_to_celsius(design.oil.t_min_k),
                        kelvin_to_celsius(design.oil.t_max_k)
                    ),
                ));
            }
            Ok(())
        };
        for c in &conditions {
            check(c, "conditions")?;
        }
        for s in &specs {
            check(&s.condition, "spec")?;
        }
        let mut conditions = conditions;
        for s in &specs {
            if !conditions.iter().any(|c| same_condition(c, &s.condition)) {
                conditions.push(s.condition);
            }
        }
        if conditions.is_empty() {
            return Err(setting("conditions", "no condition to simulate".into()));
        }
        Ok(Study {
            population,
            conditions,
            pumps,
            seed,
            sensitivity,
            specs,
            micromotion,
        })
    }

    /// Pick-freeze pairs.
    pub fn pairs(&self) -> usize {
        if self.sensitivity {
            self.pumps / 2
        } else {
            0
        }
    }
    /// Items (pumps and hybrids) to simulate.
    pub fn items(&self) -> usize {
        self.pumps + 4 * self.pairs()
    }
    /// Rows (items x conditions).
    pub fn rows(&self) -> usize {
        self.items() * self.conditions.len()
    }

    /// Item `item`'s clearances, um (module doc).
    pub fn clearances(&self, item: usize) -> [f64; 4] {
        if item < self.pumps {
            return self.population.draw(self.seed, item as u64);
        }
        let h = item - self.pumps;
        let (j, i) = (h / 4, h % 4);
        let mut a = self.population.draw(self.seed, 2 * j as u64);
        let b = self.population.draw(self.seed, 2 * j as u64 + 1);
        a[i] = b[i];
        a
    }

    /// The items of chunk `c` of `chunk` items each.
    pub fn chunk_items(&self, chunk: usize, c: usize) -> std::ops::Range<usize> {
        let start = (c * chunk).min(self.items());
        start..((c + 1) * chunk).min(self.items())
    }
    /// Chunks of `chunk` items.
    pub fn chunks(&self, chunk: usize) -> usize {
        self.items().div_ceil(chunk)
    }
}

/// `30 bar, 1000 rpm, 60 degC`.
pub fn condition_label(c: &Condition) -> String {
    format!(
        "{} bar, {} rpm, {} degC",
        c.pressure_bar, c.speed_rpm, c.temp_c
    )
}

/// The results of a range of rows, in row order (NaN where a simulation
/// failed; its message in `errors` by row).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Outputs {
    pub eta_v: Vec<f64>,
    pub flow_lpm: Vec<f64>,
    pub torque_nm: Vec<f64>,
    pub errors: Vec<(usize, String)>,
}

impl Outputs {
    pub fn get(&self, q: Quantity) -> &[f64] {
        match q {
            Quantity::EtaV => &self.eta_v,
            Quantity::FlowLpm => &self.flow_lpm,
            Quantity::TorqueNm => &self.torque_nm,
        }
    }
    /// Appends `other` (the next rows).
    pub fn extend(&mut self, other: Outputs) {
        self.eta_v.extend(other.eta_v);
        self.flow_lpm.extend(other.flow_lpm);
        self.torque_nm.extend(other.torque_nm);
        self.errors.extend(other.errors);
    }
    pub fn len(&self) -> usize {
        self.eta_v.len()
    }
    pub fn is_empty(&self) -> bool {
        self.eta_v.is_empty()
    }
}

/// One run's (eta_v, flow l/min, torque N m), or the error's text.
type RowOutcome = Result<(f64, f64, f64), String>;

/// Simulates one row.
fn run_row(model: &EffectModel, study: &Study, row: usize) -> RowOutcome {
    let nc = study.conditions.len();
    let c = &study.conditions[row % nc];
    let h = study.clearances(row / nc);
    let inputs = Inputs {
        omega: rpm_to_rad_s(c.speed_rpm),
        p_suction: ATMOSPHERE_PA,
        p_delivery: ATMOSPHERE_PA + bar_to_pa(c.pressure_bar),
        temp_k: celsius_to_kelvin(c.temp_c),
        measured_torque: None,
    };
    let sample = SampleClearances {
        tip: [um_to_m(h[0]), um_to_m(h[1])],
        bearing: [um_to_m(h[2]), um_to_m(h[3])],
        lateral: model.pump().design.clearance.lateral,
    };
    let options = Options {
        micromotion: study.micromotion,
    };
    let run = || -> RowOutcome {
        let mut sim = model
            .simulation(inputs, sample, options)
            .map_err(|e| e.to_string())?;
        let s = sim.run_periodic().map_err(|e| e.to_string())?;
        Ok((s.eta_v, m3_s_to_lpm(s.flow), s.torque))
    };
    catch_unwind(AssertUnwindSafe(run)).unwrap_or_else(|p| {
        let what = p
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| p.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        Err(format!("internal error (panic): {what}"))
    })
}

/// Simulates the rows of `items` (in parallel on the current rayon pool),
/// calling `advance` once per row.
pub fn run_items(
    model: &EffectModel,
    study: &Study,
    items: std::ops::Range<usize>,
    advance: &(dyn Fn() + Sync),
) -> Outputs {
    let nc = study.conditions.len();
    let rows = items.start * nc..items.end * nc;
    let results: Vec<(usize, RowOutcome)> = rows
        .into_par_iter()
        .map(|r| {
            let x = run_row(model, study, r);
            advance();
            (r, x)
        })
        .collect();
    let mut out = Outputs::default();
    for (r, x) in results {
        match x {
            Ok((e, q, t)) => {
                out.eta_v.push(e);
                out.flow_lpm.push(q);
                out.torque_nm.push(t);
            }
            Err(m) => {
                out.eta_v.push(f64::NAN);
                out.flow_lpm.push(f64::NAN);
                out.torque_nm.push(f64::NAN);
                out.errors.push((r, m));
            }
        }
    }
    out
}

// ------------------------------------------------------------- the summary

/// The sensitivity indices at one condition.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sensitivity {
    /// Pairs with every run finite.
    pub pairs_used: usize,
    /// Per quantity (eta_v, flow_lpm, torque_nm): the index of each
    /// clearance in [`CLEARANCES`] order, None when undefined.
    pub eta_v: Option<Vec<SobolIndex>>,
    pub flow_lpm: Option<Vec<SobolIndex>>,
    pub torque_nm: Option<Vec<SobolIndex>>,
}

impl Sensitivity {
    pub fn get(&self, q: Quantity) -> Option<&Vec<SobolIndex>> {
        match q {
            Quantity::EtaV => self.eta_v.as_ref(),
            Quantity::FlowLpm => self.flow_lpm.as_ref(),
            Quantity::TorqueNm => self.torque_nm.as_ref(),
        }
    }
}

/// One condition's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConditionResult {
    pub condition: Condition,
    pub eta_v: Distribution,
    pub flow_lpm: Distribution,
    pub torque_nm: Distribution,
    /// Drawn pumps whose simulation failed here.
    pub failed: usize,
    pub sensitivity: Option<Sensitivity>,
}

impl ConditionResult {
    pub fn get(&self, q: Quantity) -> &Distribution {
        match q {
            Quantity::EtaV => &self.eta_v,
            Quantity::FlowLpm => &self.flow_lpm,
            Quantity::TorqueNm => &self.torque_nm,
        }
    }
}

/// One spec's yield.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpecResult {
    pub spec: Spec,
    #[serde(rename = "yield")]
    pub yield_: Yield,
}

/// What a study found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    pub pumps: usize,
    pub pairs: usize,
    pub runs: usize,
    pub failed_runs: usize,
    pub conditions: Vec<ConditionResult>,
    pub specs: Vec<SpecResult>,
    /// The share meeting every spec (None without specs).
    #[serde(rename = "yield")]
    pub yield_all: Option<Yield>,
    /// The condition of the tornado figure (index into `conditions`).
    pub focus: usize,
}

/// The per-condition statistics, yields and indices of all the rows'
/// results `out` (see the module doc and [`estimators`]).
pub fn summarize(study: &Study, out: &Outputs) -> Summary {
    let nc = study.conditions.len();
    let n = study.pumps;
    let pairs = study.pairs();
    let col = |q: Quantity, item: usize, c: usize| out.get(q)[item * nc + c];
    let mut conditions = Vec::with_capacity(nc);
    for (c, cond) in study.conditions.iter().enumerate() {
        let values = |q: Quantity| -> Vec<f64> { (0..n).map(|i| col(q, i, c)).collect() };
        let failed = (0..n)
            .filter(|&i| !col(Quantity::EtaV, i, c).is_finite())
            .count();
        let sensitivity = (pairs > 0).then(|| {
            let mut used = 0;
            let mut per = |q: Quantity| {
                let ya: Vec<f64> = (0..pairs).map(|j| col(q, 2 * j, c)).collect();
                let yb: Vec<f64> = (0..pairs).map(|j| col(q, 2 * j + 1, c)).collect();
                let ab: Vec<Vec<f64>> = (0..4)
                    .map(|i| (0..pairs).map(|j| col(q, n + 4 * j + i, c)).collect())
                    .collect();
                let (idx, u) = estimators::sobol_indices(&ya, &yb, &ab);
                used = u;
                idx
            };
            let eta_v = per(Quantity::EtaV);
            let flow_lpm = per(Quantity::FlowLpm);
            let torque_nm = per(Quantity::TorqueNm);
            Sensitivity {
                pairs_used: used,
                eta_v,
                flow_lpm,
                torque_nm,
            }
        });
        conditions.push(ConditionResult {
            condition: *cond,
            eta_v: estimators::distribution(&values(Quantity::EtaV)),
            flow_lpm: estimators::distribution(&values(Quantity::FlowLpm)),
            torque_nm: estimators::distribution(&values(Quantity::TorqueNm)),
            failed,
            sensitivity,
        });
    }
    let cond_of = |s: &Spec| {
        study
            .conditions
            .iter()
            .position(|c| same_condition(c, &s.condition))
            .unwrap_or(0)
    };
    let meets = |s: &Spec, i: usize| {
        let x = col(s.quantity, i, cond_of(s));
        x.is_finite() && s.op.holds(x, s.limit)
    };
    let specs = study
        .specs
        .iter()
        .map(|s| SpecResult {
            spec: s.clone(),
            yield_: estimators::yield_of((0..n).filter(|&i| meets(s, i)).count(), n),
        })
        .collect();
    let yield_all = (!study.specs.is_empty()).then(|| {
        estimators::yield_of(
            (0..n)
                .filter(|&i| study.specs.iter().all(|s| meets(s, i)))
                .count(),
            n,
        )
    });
    let focus = match study.specs.first() {
        Some(s) => cond_of(s),
        None => (0..nc)
            .max_by(|&a, &b| {
                let v = |c: usize| conditions[c].eta_v.std.unwrap_or(0.0);
                v(a).total_cmp(&v(b)).then(b.cmp(&a))
            })
            .unwrap_or(0),
    };
    Summary {
        pumps: n,
        pairs,
        runs: out.len(),
        failed_runs: out.eta_v.iter().filter(|x| !x.is_finite()).count(),
        conditions,
        specs,
        yield_all,
        focus,
    }
}

// --------------------------------------------------------------- journal

/// The run-wide fingerprint of a study (module doc, "Resumable").
pub fn study_fingerprint(source: &DesignSource, study: &Study, chunk: usize) -> u64 {
    let mut h = Fnv1a::new();
    h.write_str("gearpump-montecarlo-journal/1");
    h.write_str(&code_version());
    h.write_str(&source.text);
    h.write_u64(source.sets.len() as u64);
    for s in &source.sets {
        h.write_str(s);
    }
    let what = json!({
        "population": study.population,
        "conditions": study.conditions,
        "pumps": study.pumps,
        "seed": study.seed,
        "sensitivity": study.sensitivity,
        "micromotion": study.micromotion,
        "chunk": chunk,
    });
    h.write_str(&what.to_string());
    h.finish().0
}

fn chunk_fingerprint(run: u64, c: usize) -> String {
    let mut h = Fnv1a::new();
    h.write_u64(run);
    h.write_u64(c as u64);
    format!("{:016x}", h.finish().0)
}

#[derive(Serialize, Deserialize)]
struct Entry {
    chunk: usize,
    fp: String,
    eta_v: Vec<String>,
    flow_lpm: Vec<String>,
    torque_nm: Vec<String>,
    errors: Vec<(usize, String)>,
}

fn text(v: &[f64]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}
fn floats(v: &[String]) -> Option<Vec<f64>> {
    v.iter().map(|s| s.parse().ok()).collect()
}

/// The chunk journal of a study's output folder.
struct ChunkJournal {
    path: PathBuf,
    file: Mutex<fs::File>,
}

impl ChunkJournal {
    /// Opens `dir/montecarlo-journal.jsonl`, keeps the chunks of this run (with the
    /// right number of rows), rewrites it with them only.
    fn open(
        dir: &Path,
        run: u64,
        rows_of: impl Fn(usize) -> Option<usize>,
    ) -> Result<(ChunkJournal, std::collections::BTreeMap<usize, Outputs>), MonteCarloError> {
        let path = dir.join(JOURNAL_FILE);
        let io = |source| MonteCarloError::Io {
            path: path.clone(),
            source,
        };
        let mut done = std::collections::BTreeMap::new();
        match fs::read(&path) {
            Ok(bytes) => {
                for line in bytes.split(|&b| b == b'\n') {
                    let Ok(e) = serde_json::from_slice::<Entry>(line) else {
                        continue;
                    };
                    if e.fp != chunk_fingerprint(run, e.chunk) {
                        continue;
                    }
                    let (Some(a), Some(b), Some(t)) =
                        (floats(&e.eta_v), floats(&e.flow_lpm), floats(&e.torque_nm))
                    else {
                        continue;
                    };
                    let rows = rows_of(e.chunk);
                    if rows != Some(a.len()) || b.len() != a.len() || t.len() != a.len() {
                        continue;
                    }
                    done.insert(
                        e.chunk,
                        Outputs {
                            eta_v: a,
                            flow_lpm: b,
                            torque_nm: t,
                            errors: e.errors,
                        },
                    );
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(e)),
        }
        let mut text_all = String::new();
        for (c, o) in &done {
            text_all.push_str(&entry_line(run, *c, o));
        }
        atomic_write_text(&path, &text_all).map_err(|e| MonteCarloError::Run(e.into()))?;
        let file = fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .map_err(io)?;
        Ok((
            ChunkJournal {
                path,
                file: Mutex::new(file),
            },
            done,
        ))
    }

    fn record(&self, run: u64, c: usize, o: &Outputs) -> Result<(), MonteCarloError> {
        use std::io::Write;
        let line = entry_line(run, c, o);
        let mut f = self.file.lock().unwrap_or_else(|e| e.into_inner());
        let io = |source| MonteCarloError::Io {
            path: self.path.clone(),
            source,
        };
        f.write_all(line.as_bytes()).map_err(io)?;
        f.flush().map_err(io)?;
        f.sync_data().map_err(io)
    }

    fn finish(self) -> Result<(), MonteCarloError> {
        let path = self.path.clone();
        drop(self);
        match fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                Err(MonteCarloError::Io { path, source: e })
            }
            _ => Ok(()),
        }
    }
}

fn entry_line(run: u64, c: usize, o: &Outputs) -> String {
    let e = Entry {
        chunk: c,
        fp: chunk_fingerprint(run, c),
        eta_v: text(&o.eta_v),
        flow_lpm: text(&o.flow_lpm),
        torque_nm: text(&o.torque_nm),
        errors: o.errors.clone(),
    };
    let mut s = serde_json::to_string(&e).unwrap_or_default();
    s.push('\n');
    s
}

// ------------------------------------------------------------ the command

/// How a study runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOptions {
    /// Threads; None = all cores.
    pub jobs: Option<usize>,
    /// Items per chunk (journal entry, Dask task).
    pub chunk: usize,
}

/// A finished study.
#[derive(Debug, Clone)]
pub struct StudyResult {
    pub summary: Summary,
    pub outputs: Outputs,
    /// Rows simulated by this invocation and resumed from the journal.
    pub simulated: usize,
    pub reused: usize,
    pub files: Vec<PathBuf>,
}

/// Simulates every chunk of `study` not yet journaled in `out`, and
/// returns all the rows' results with the counts simulated and reused
/// (the journal left in place; see [`run_study`]).
fn simulate_study(
    source: &DesignSource,
    study: &Study,
    out: &Path,
    options: RunOptions,
    observer: &dyn Observer,
) -> Result<(Outputs, usize, usize, ChunkJournal), MonteCarloError> {
    if options.chunk == 0 {
        return Err(setting("chunk", "must be >= 1".into()));
    }
    if out.exists() && !out.is_dir() {
        return Err(setting(
            "out",
            format!("{} exists and is not a directory", out.display()),
        ));
    }
    fs::create_dir_all(out).map_err(|source| MonteCarloError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    let run = study_fingerprint(source, study, options.chunk);
    let nc = study.conditions.len();
    let nchunks = study.chunks(options.chunk);
    let (journal, mut done) = ChunkJournal::open(out, run, |c| {
        (c < nchunks).then(|| study.chunk_items(options.chunk, c).len() * nc)
    })?;
    let reused: usize = done.values().map(Outputs::len).sum();
    let todo: Vec<usize> = (0..nchunks).filter(|c| !done.contains_key(c)).collect();
    observer.begin(study.rows(), reused);
    if !todo.is_empty() {
        let (pump, _) = gearpump_core::model::Pump::with_env_cache(source.design.clone());
        let pump = std::sync::Arc::new(pump);
        let model = EffectModel::on(&pump, &[]).map_err(RunError::from)?;
        let advance = || observer.advance();
        let fresh = with_pool(options.jobs, || {
            todo.par_iter()
                .with_max_len(1)
                .map(|&c| {
                    let o = run_items(&model, study, study.chunk_items(options.chunk, c), &advance);
                    journal.record(run, c, &o)?;
                    Ok((c, o))
                })
                .collect::<Result<Vec<_>, MonteCarloError>>()
        })??;
        done.extend(fresh);
    }
    observer.end();
    let simulated = study.rows() - reused;
    let mut all = Outputs::default();
    for (_, o) in done {
        all.extend(o);
    }
    Ok((all, simulated, reused, journal))
}

/// `gearpump montecarlo`: simulates (resuming from the journal in `out`),
/// summarises, writes the outputs (module doc) staged into `out`.
pub fn run_study(
    source: &DesignSource,
    study: &Study,
    out: &Path,
    options: RunOptions,
    observer: &dyn Observer,
) -> Result<StudyResult, MonteCarloError> {
    let (outputs, simulated, reused, journal) =
        simulate_study(source, study, out, options, observer)?;
    let summary = summarize(study, &outputs);
    // only a study's own files are replaced: a campaign's or a diagnosis's
    // results in the same folder stay
    let stage = Staging::for_results(out, &OUTPUT_FILES).map_err(RunError::from)?;
    let files = write_outputs(stage.path(), source, study, &summary, &outputs)?;
    let files = files.iter().map(|f| stage.final_path(f)).collect();
    stage.commit().map_err(RunError::from)?;
    journal.finish()?;
    Ok(StudyResult {
        summary,
        outputs,
        simulated,
        reused,
        files,
    })
}

/// The JSON record of a study and its summary (`montecarlo.json`).
pub fn study_json(
    design_label: &str,
    sets: &[String],
    study: &Study,
    summary: &Summary,
) -> serde_json::Value {
    json!({
        "design": design_label,
        "set": sets,
        "population": study.population,
        "clearances": CLEARANCES,
        "pumps": study.pumps,
        "seed": study.seed,
        "sensitivity": study.sensitivity,
        "micromotion": study.micromotion,
        "percentiles": estimators::PERCENTILES,
        "summary": summary,
    })
}

fn write_outputs(
    dir: &Path,
    source: &DesignSource,
    study: &Study,
    summary: &Summary,
    outputs: &Outputs,
) -> Result<Vec<PathBuf>, MonteCarloError> {
    let w = |name: &str, text: &str| -> Result<PathBuf, MonteCarloError> {
        let p = dir.join(name);
        atomic_write_text(&p, text).map_err(|e| MonteCarloError::Run(e.into()))?;
        Ok(p)
    };
    let mut files = Vec::new();
    let v = study_json(&source.label, &source.sets, study, summary);
    let pretty = serde_json::to_string_pretty(&v).unwrap_or_default();
    files.push(w("montecarlo.json", &format!("{pretty}\n"))?);
    files.push(w("percentiles.csv", &percentiles_csv(summary))?);
    files.push(w("sensitivity.csv", &sensitivity_csv(summary))?);
    files.push(w("pumps.csv", &pumps_csv(study, outputs))?);
    files.push(figures::cdf(&dir.join("cdf.svg"), study, outputs)?);
    files.push(figures::tornado(&dir.join("tornado.svg"), summary)?);
    Ok(files)
}

fn opt(x: Option<f64>) -> String {
    x.map(float_cell).unwrap_or_default()
}

/// `percentiles.csv`.
pub fn percentiles_csv(summary: &Summary) -> String {
    let mut s = String::new();
    let mut header: Vec<String> = [
        "pressure_bar",
        "speed_rpm",
        "temp_c",
        "quantity",
        "n",
        "failed",
        "mean",
        "std",
        "min",
        "max",
    ]
    .map(String::from)
    .to_vec();
    header.extend(estimators::PERCENTILES.iter().map(|p| format!("p{p}")));
    push_csv_row(&mut s, header.iter().map(String::as_str));
    for c in &summary.conditions {
        for q in Quantity::ALL {
            let d = c.get(q);
            let mut cells = vec![
                float_cell(c.condition.pressure_bar),
                float_cell(c.condition.speed_rpm),
                float_cell(c.condition.temp_c),
                q.name().to_string(),
                d.n.to_string(),
                c.failed.to_string(),
                opt(d.mean),
                opt(d.std),
                opt(d.min),
                opt(d.max),
            ];
            cells.extend(d.percentiles.iter().map(|x| opt(*x)));
            push_csv_row(&mut s, cells.iter().map(String::as_str));
        }
    }
    s
}

/// `sensitivity.csv` (header only without sensitivity runs).
pub fn sensitivity_csv(summary: &Summary) -> String {
    let mut s = String::new();
    push_csv_row(
        &mut s,
        [
            "pressure_bar",
            "speed_rpm",
            "temp_c",
            "quantity",
            "clearance",
            "first_order",
            "total",
            "pairs_used",
        ],
    );
    for c in &summary.conditions {
        let Some(sens) = &c.sensitivity else { continue };
        for q in Quantity::ALL {
            for (k, name) in CLEARANCES.iter().enumerate() {
                let idx = sens.get(q).map(|v| v[k]);
                let cells = [
                    float_cell(c.condition.pressure_bar),
                    float_cell(c.condition.speed_rpm),
                    float_cell(c.condition.temp_c),
                    q.name().to_string(),
                    name.to_string(),
                    opt(idx.map(|i| i.first)),
                    opt(idx.map(|i| i.total)),
                    sens.pairs_used.to_string(),
                ];
                push_csv_row(&mut s, cells.iter().map(String::as_str));
            }
        }
    }
    s
}

/// `pumps.csv`: every drawn pump at every condition.
pub fn pumps_csv(study: &Study, o: &Outputs) -> String {
    let nc = study.conditions.len();
    let mut s = String::new();
    push_csv_row(
        &mut s,
        [
            "pump",
            "tip1_um",
            "tip2_um",
            "bearing1_um",
            "bearing2_um",
            "pressure_bar",
            "speed_rpm",
            "temp_c",
            "eta_v",
            "flow_lpm",
            "torque_nm",
        ],
    );
    for i in 0..study.pumps {
        let h = study.clearances(i);
        for (c, cond) in study.conditions.iter().enumerate() {
            let r = i * nc + c;
            let cells = [
                i.to_string(),
                float_cell(h[0]),
                float_cell(h[1]),
                float_cell(h[2]),
                float_cell(h[3]),
                float_cell(cond.pressure_bar),
                float_cell(cond.speed_rpm),
                float_cell(cond.temp_c),
                float_cell(o.eta_v[r]),
                float_cell(o.flow_lpm[r]),
                float_cell(o.torque_nm[r]),
            ];
            push_csv_row(&mut s, cells.iter().map(String::as_str));
        }
    }
    s
}

impl StudyResult {
    /// Lines for a terminal: per condition the spread of eta_v and torque
    /// and the clearance that drives eta_v; the yields.
    pub fn summary_text(&self, out: &Path) -> String {
        let s = &self.summary;
        let f = |x: Option<f64>, d: usize| x.map_or("-".to_string(), |v| format!("{v:.d$}"));
        let mut t = format!(
            "{} pumps x {} conditions: {} runs ({} simulated, {} resumed), {} failed\n",
            s.pumps,
            s.conditions.len(),
            s.runs,
            self.simulated,
            self.reused,
            s.failed_runs
        );
        t.push_str("p_bar  n_rpm  T_degC   eta_v p5    p50    p95   torque_nm p50    p95   eta_v driven by (S_i)\n");
        for c in &s.conditions {
            let drive = c
                .sensitivity
                .as_ref()
                .and_then(|x| x.eta_v.as_ref())
                .map(|idx| {
                    let mut k: Vec<usize> = (0..4).collect();
                    k.sort_by(|&a, &b| idx[b].first.total_cmp(&idx[a].first));
                    k.iter()
                        .take(2)
                        .map(|&i| format!("{} {:.2}", CLEARANCES[i], idx[i].first))
                        .collect::<Vec<_>>()
                        .join(", ")
                })
                .unwrap_or_else(|| "-".into());
            t.push_str(&format!(
                "{:>5} {:>6} {:>7} {:>10} {:>6} {:>6} {:>13} {:>6}   {}\n",
                c.condition.pressure_bar,
                c.condition.speed_rpm,
                c.condition.temp_c,
                f(c.eta_v.percentiles[1], 4),
                f(c.eta_v.percentiles[2], 4),
                f(c.eta_v.percentiles[3], 4),
                f(c.torque_nm.percentiles[2], 3),
                f(c.torque_nm.percentiles[3], 3),
                drive
            ));
        }
        for r in &s.specs {
            t.push_str(&format!(
                "yield {}: {} ({} of {}; 95 % {} .. {})\n",
                r.spec.text,
                f(r.yield_.share, 4),
                r.yield_.pass,
                r.yield_.n,
                f(r.yield_.ci95.map(|c| c[0]), 4),
                f(r.yield_.ci95.map(|c| c[1]), 4)
            ));
        }
        if let Some(y) = &s.yield_all {
            if s.specs.len() > 1 {
                t.push_str(&format!(
                    "yield, every spec: {} ({} of {})\n",
                    f(y.share, 4),
                    y.pass,
                    y.n
                ));
            }
        }
        t.push_str(&format!("outputs in {}", out.display()));
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn study(pumps: usize, sensitivity: bool) -> Study {
        let d = Design::seed();
        Study::new(
            &d,
            Population::paper(&d),
            vec![Condition {
                pressure_bar: 30.0,
                speed_rpm: 1000.0,
                temp_c: 60.0,
            }],
            pumps,
            5,
            sensitivity,
            vec![],
            true,
        )
        .unwrap()
    }

    #[test]
    fn items_are_pumps_then_hybrids() {
        let s = study(7, true);
        assert_eq!((s.pairs(), s.items(), s.rows()), (3, 19, 19));
        let a = s.clearances(4);
        let b = s.clearances(5);
        // pair j = 2: hybrids 7 + 8 .. 7 + 11
        for i in 0..4 {
            let h = s.clearances(7 + 4 * 2 + i);
            for k in 0..4 {
                assert_eq!(h[k], if k == i { b[k] } else { a[k] });
            }
        }
        assert_eq!(s.chunks(5), 4);
        assert_eq!(s.chunk_items(5, 3), 15..19);
        assert_eq!(study(7, false).items(), 7);
    }

    /// Yields and percentiles of a study summarised from results given by
    /// hand: 5 pumps at two conditions.
    #[test]
    fn a_summary_counts_by_hand() {
        let d = Design::seed();
        let c1 = Condition {
            pressure_bar: 30.0,
            speed_rpm: 500.0,
            temp_c: 120.0,
        };
        let c2 = Condition {
            pressure_bar: 10.0,
            speed_rpm: 1000.0,
            temp_c: 60.0,
        };
        let specs = vec![
            Spec::parse("eta_v>=0.8@500rpm,30bar,120degC").unwrap(),
            Spec::parse("torque_nm<3@1000rpm,10bar,60degC").unwrap(),
        ];
        let s = Study::new(
            &d,
            Population::paper(&d),
            vec![c1],
            5,
            1,
            false,
            specs,
            true,
        )
        .unwrap();
        assert_eq!(s.conditions, vec![c1, c2], "the spec's condition added");
        // rows item-major: (pump 0, c1), (pump 0, c2), ...
        let eta = [0.9, 0.5, 0.7, 0.6, 0.8, f64::NAN, 0.85, 0.6, 0.81, 0.6];
        let torque = [5.0, 2.0, 5.0, 3.5, 5.0, f64::NAN, 5.0, 1.0, 5.0, 3.0];
        let o = Outputs {
            eta_v: eta.to_vec(),
            flow_lpm: eta.to_vec(),
            torque_nm: torque.to_vec(),
            errors: vec![(5, "x".into())],
        };
        let r = summarize(&s, &o);
        // eta_v at c1: 0.9 0.7 0.8 0.85 0.81 -> >= 0.8: pumps 0, 2, 3, 4
        assert_eq!((r.specs[0].yield_.pass, r.specs[0].yield_.n), (4, 5));
        // torque < 3 at c2: pumps 0 (2.0) and 3 (1.0); pump 2 failed there,
        // pump 4 has exactly 3
        assert_eq!(r.specs[1].yield_.pass, 2);
        // both: pumps 0 and 3
        assert_eq!(r.yield_all.unwrap().pass, 2);
        // c1 sorted 0.7 0.8 0.81 0.85 0.9: median 0.81
        assert_eq!(r.conditions[0].eta_v.percentiles[2], Some(0.81));
        // c2: 0.5 0.6 0.6 0.6 and a failure
        assert_eq!(r.conditions[1].failed, 1);
        assert_eq!(r.conditions[1].eta_v.n, 4);
        assert_eq!(r.conditions[1].eta_v.min, Some(0.5));
        assert_eq!((r.failed_runs, r.focus), (1, 0));
    }

    #[test]
    fn studies_outside_the_model_are_refused() {
        let d = Design::seed();
        let p = Population::paper(&d);
        let c = |t: f64| Condition {
            pressure_bar: 30.0,
            speed_rpm: 1000.0,
            temp_c: t,
        };
        let e = Study::new(&d, p.clone(), vec![c(60.0)], 3, 1, true, vec![], true).unwrap_err();
        assert!(e.to_string().starts_with("pumps: must be in [4,"), "{e}");
        let e = Study::new(&d, p.clone(), vec![c(900.0)], 4, 1, true, vec![], true).unwrap_err();
        assert!(e.to_string().contains("900 degC is outside"), "{e}");
        let spec = Spec::parse("eta_v>=0.8@1e9rpm,30bar,60degC").unwrap();
        let e = Study::new(&d, p, vec![c(60.0)], 4, 1, true, vec![spec], true).unwrap_err();
        assert!(
            e.to_string().starts_with("spec: 30 bar, 1000000000 rpm"),
            "{e}"
        );
        assert!(e.is_bad_input());
    }
}
