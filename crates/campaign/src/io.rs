//! Campaign outputs: atomic files, `tests.csv`, `conditions.csv`, and the
//! resumable journal of simulated rows.
//!
//! # Atomic writes
//! [`atomic_write`] writes to a temporary file in the destination directory
//! (`.NAME.tmp-PID-N`), fsyncs it, renames it over the destination (atomic
//! on POSIX file systems) and fsyncs the directory. A reader sees the old
//! file or the new one, never a partial one; on error the temporary file is
//! removed.
//!
//! # Output folders: staged, then moved in
//! A command's result is several files (`tests.csv`, `conditions.csv`,
//! `report.md`, figures, `diagnosis.json`, `extended/`), and a reader must
//! never take files of two results for one. So a run writes its whole
//! result into a staging folder inside the output folder
//! ([`Staging`]: `.staging-PID-N/`), and only once everything is written
//! (a full disk or any other error fails here, leaving the output folder as
//! it was) [`Staging::commit`] removes from the output folder every result
//! name ([`RESULT_NAMES`]) the new result does not have (an earlier
//! diagnosis's `diagnosis.json` and `extended/` under a new campaign, a
//! sweep figure the new data have no sweep for) and renames the staged
//! entries over the old ones (a staged folder's into the folder of that
//! name; a file of the user's inside `extended/` stays). Renames within one
//! file system write no data,
//! so a full disk cannot stop them half-way; only a crash within those few
//! renames can leave a mix. Anything else in the output folder (the user's
//! files, the resume journal) is left alone; a staging folder left by a
//! killed run is removed by the next run into that folder.
//!
//! # `tests.csv`
//! Every input column, in input order, with the original cell text
//! unchanged (extra columns included), then `flow_lpm_sim`, `eta_v_meas`,
//! `eta_v_sim`, `d`, `torque_nm_sim` and the simulated loss budget (six
//! `loss_*` columns, shares of `Vm n`: `gearpump_core::losses`). Floats are written with Rust's `{}`
//! (shortest text that reads back to the same `f64`: full precision); a
//! non-finite value (e.g. a failed simulation) is an empty cell. If an input
//! column already carries one of the output names (a `tests.csv` fed
//! back as input), the input header gets the suffix `_input` so the output
//! header stays unambiguous; its cells are unchanged.
//!
//! # `conditions.csv`
//! `pressure_bar, speed_rpm, temp_c, n_samples, d_mean, d_std, t_crit,
//! ci_low, ci_high, delta_nu` (seed Eqs. 17-20), one line per working
//! condition in order of first appearance; undefined values are empty cells.
//!
//! # Journal (`journal.jsonl`)
//! Rows are simulated in parallel and a campaign can take hours, so each
//! finished row is appended to `journal.jsonl` in the output folder as one
//! JSON line `{"row": i, "fp": "<16 hex>", "result": {...}}`, written with a
//! single `write` and `fsync`ed. The fingerprint `fp` is a 64-bit FNV-1a hash
//! of everything that determines the row's result: the code version, the
//! design text, the `--set` list (see [`RunFingerprint`]) and the row's own
//! simulation inputs (four clearances, pressure, speed, temperature). On
//! [`Journal::open`] the file is read back; a torn last line (crash during a
//! write) and lines that do not parse are ignored, entries whose fingerprint
//! differs from the current one (changed design, `--set`, version or row) are
//! dropped, and the file is rewritten (atomically) with the valid entries
//! only, so appending never continues a torn line. [`Journal::finish`]
//! removes the journal once the final outputs are written.
//!
//! Why FNV-1a and not `std::hash::DefaultHasher`: the journal outlives the
//! process, and std documents that `DefaultHasher`'s algorithm may change
//! between Rust releases (and `RandomState` is seeded per process), so a
//! rebuilt binary could silently invalidate or, worse, mis-match entries.
//! FNV-1a is fixed by its specification. It is not collision resistant
//! against an adversary, which is not a concern for a local resume file.
//!
//! Floats are journaled as text (`"13.25"`, `"NaN"`) and read back with
//! Rust's correctly rounded parser, so a resumed run reproduces the outputs
//! of an uninterrupted one bit for bit (serde_json's default float parser
//! may be 1 ulp off); strings and floats inside `extra` are tagged the same
//! way (`"s..."`, `"f..."`).

use std::collections::HashMap;
use std::fmt;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use super::data::{Campaign, CampaignRecord, TestRow, COLUMNS};
use super::stats::ConditionSummary;

/// File name of the per-test output.
pub const TESTS_CSV: &str = "tests.csv";
/// File name of the per-condition output.
pub const CONDITIONS_CSV: &str = "conditions.csv";
/// File name of the resume journal.
pub const JOURNAL_FILE: &str = "journal.jsonl";

/// Columns appended to the input columns in `tests.csv`: the simulated
/// outputs, then the simulated loss budget (`gearpump_core::losses`, shares of
/// `Vm n`, empty where undefined) in the order of [`LOSS_COLUMNS`].
pub const TESTS_SIM_COLUMNS: [&str; 11] = [
    "flow_lpm_sim",
    "eta_v_meas",
    "eta_v_sim",
    "d",
    "torque_nm_sim",
    "loss_tip_poiseuille",
    "loss_tip_couette",
    "loss_lateral",
    "loss_bearings",
    "loss_mesh_zone",
    "loss_compressibility",
];

/// The loss-budget columns of `tests.csv`, as [`gearpump_core::losses::LossBudget::parts`].
pub const LOSS_COLUMNS: usize = 6;

/// Columns of `conditions.csv`.
pub const CONDITIONS_COLUMNS: [&str; 16] = [
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
    "eta_hm_err_std",
];

#[derive(Debug, Error)]
pub enum OutputError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("{}: not a file path", path.display())]
    NotAFile { path: PathBuf },
    #[error("tests.csv: {outcomes} simulated results for {rows} input rows")]
    LengthMismatch { rows: usize, outcomes: usize },
}

fn io_err(path: &Path) -> impl FnOnce(io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

static TMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// Write `bytes` to `path` atomically: temporary file in the same directory,
/// fsync, rename, fsync of the directory (best effort).
pub fn atomic_write(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let name = path
        .file_name()
        .ok_or_else(|| OutputError::NotAFile {
            path: path.to_path_buf(),
        })?
        .to_string_lossy()
        .into_owned();
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let mut f = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(io_err(&tmp))?;
        f.write_all(bytes).map_err(io_err(&tmp))?;
        f.sync_all().map_err(io_err(&tmp))?;
        drop(f);
        fs::rename(&tmp, path).map_err(io_err(path))
    })();
    if result.is_err() {
        // Best effort: the original error is what matters.
        let _ = fs::remove_file(&tmp);
        return result;
    }
    // Make the rename itself durable. Some file systems refuse to fsync a
    // directory; the data is already in place, so this is best effort.
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// [`atomic_write`] for text.
pub fn atomic_write_text(path: &Path, text: &str) -> Result<(), OutputError> {
    atomic_write(path, text.as_bytes())
}

/// Every file or folder name a `campaign` or `diagnose` result may hold in
/// its output folder: on [`Staging::commit`] those the new result does not
/// have are removed, so nothing of an earlier result looks current.
pub const RESULT_NAMES: &[&str] = &[
    TESTS_CSV,
    CONDITIONS_CSV,
    "report.md",
    "curves_pressure.svg",
    "curves_speed.svg",
    "residuals.svg",
    "losses.svg",
    "diagnosis.json",
    "diagnosis.svg",
    "diagnosis_features.svg",
    "extended",
    "extended_design.toml",
];

/// Fails when a folder is where one of the result files
/// ([`RESULT_NAMES`] with an extension) goes in `out`: checked before a
/// run, so it stops before the work (the commit checks again).
pub fn result_places_free(out: &Path) -> Result<(), OutputError> {
    for name in RESULT_NAMES.iter().filter(|n| n.contains('.')) {
        let at = out.join(name);
        if at.is_dir() {
            return Err(OutputError::Io {
                source: io::Error::other(
                    "a folder is where this result file goes; move or rename it",
                ),
                path: at,
            });
        }
    }
    Ok(())
}

/// Checks an output path before any work: a folder (`file` false) must not
/// be a file, a file must not be a folder nor name one (a trailing `/`),
/// and the nearest part of the path that exists must be a folder this
/// process can write in (probed with a file created and removed at once).
/// The error is the reason, as `PATH: why` (or `empty path`); the caller
/// puts the flag or argument before it (the CLI's `--out: ...`, the Python
/// package's `out: ...`).
pub fn check_out(path: &Path, file: bool) -> Result<(), String> {
    let refuse = |why: String| format!("{}: {why}", path.display());
    let text = path.as_os_str().as_encoded_bytes();
    if text.is_empty() {
        return Err("empty path".into());
    }
    if file && path.is_dir() {
        return Err(refuse("is a folder; give the file to write in it".into()));
    }
    if file
        && (path.file_name().is_none()
            || text.ends_with(b"/.")
            || text.ends_with(std::path::MAIN_SEPARATOR_STR.as_bytes()))
    {
        return Err(refuse("names a folder; give the file to write".into()));
    }
    if !file && path.exists() && !path.is_dir() {
        return Err(refuse("exists and is not a directory".into()));
    }
    // the nearest part of the path that exists
    let mut at = if file || !path.exists() {
        path.parent().unwrap_or(Path::new(""))
    } else {
        path
    };
    while !at.as_os_str().is_empty() && !at.exists() {
        at = at.parent().unwrap_or(Path::new(""));
    }
    let at = if at.as_os_str().is_empty() {
        Path::new(".")
    } else {
        at
    };
    if !at.is_dir() {
        return Err(refuse(format!("{} is a file, not a folder", at.display())));
    }
    let probe = at.join(format!(".gearpump-probe-{}", std::process::id()));
    match fs::File::create(&probe) {
        Ok(_) => {
            let _ = fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(refuse(format!("cannot write in {} ({e})", at.display()))),
    }
}

const STAGING_PREFIX: &str = ".staging-";

/// A staging folder inside an output folder: a result is written into
/// [`Staging::path`] and moved into the output folder by
/// [`Staging::commit`]; dropped without a commit, the staging folder is
/// removed and the output folder is as it was (see the module docs).
#[derive(Debug)]
pub struct Staging {
    out: PathBuf,
    dir: PathBuf,
    committed: bool,
    /// The names of this kind of result: the ones the commit may remove
    /// when the new result lacks them ([`RESULT_NAMES`] unless
    /// [`Staging::for_results`] says otherwise).
    results: &'static [&'static str],
}

impl Staging {
    /// A new, empty staging folder in `out` (created if needed); staging
    /// folders of processes that no longer run are removed first.
    pub fn new(out: &Path) -> Result<Staging, OutputError> {
        Self::for_results(out, RESULT_NAMES)
    }

    /// [`Staging::new`] for a result of another kind, whose names are
    /// `results`: the commit removes only those of them the new result
    /// lacks, so that a Monte Carlo study written into a campaign's folder
    /// leaves the campaign's and the diagnosis's files (an edited
    /// `extended_design.toml` among them) where they are.
    pub fn for_results(
        out: &Path,
        results: &'static [&'static str],
    ) -> Result<Staging, OutputError> {
        fs::create_dir_all(out).map_err(io_err(out))?;
        remove_abandoned_staging(out);
        let dir = out.join(format!(
            "{STAGING_PREFIX}{}-{}",
            std::process::id(),
            TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        fs::create_dir(&dir).map_err(io_err(&dir))?;
        Ok(Staging {
            out: out.to_path_buf(),
            dir,
            committed: false,
            results,
        })
    }

    /// The folder to write the result into.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Where `staged` (a path under [`Staging::path`]) will be after the
    /// commit; other paths unchanged.
    pub fn final_path(&self, staged: &Path) -> PathBuf {
        match staged.strip_prefix(&self.dir) {
            Ok(rel) => self.out.join(rel),
            Err(_) => staged.to_path_buf(),
        }
    }

    /// Removes the result names the staged result lacks from the output
    /// folder, renames the staged entries into it (a staged folder's entries
    /// into the folder of that name) and removes the staging folder.
    pub fn commit(mut self) -> Result<(), OutputError> {
        // a staged file whose place in the output folder is taken by a
        // folder would stop the renames half-way: refused before any
        check_places(&self.dir, &self.out)?;
        commit_dir(&self.dir, &self.out, self.results)?;
        fs::remove_dir_all(&self.dir).map_err(io_err(&self.dir))?;
        self.committed = true;
        if let Ok(d) = File::open(&self.out) {
            let _ = d.sync_all();
        }
        Ok(())
    }
}

/// Fails when a staged file's place in `out` (or in its folders there) is
/// a folder: the commit would stop at it with part of the result moved in.
fn check_places(staged: &Path, out: &Path) -> Result<(), OutputError> {
    for entry in fs::read_dir(staged).map_err(io_err(staged))? {
        let entry = entry.map_err(io_err(staged))?;
        let (from, to) = (entry.path(), out.join(entry.file_name()));
        if from.is_dir() {
            if to.is_dir() {
                check_places(&from, &to)?;
            }
        } else if to.is_dir() {
            return Err(OutputError::Io {
                source: io::Error::other("a folder is where this result file goes; move or rename it (nothing of the new result was moved in)",
                ),
                path: to,
            });
        }
    }
    Ok(())
}

/// Moves the staged folder `staged` into `out` (see [`Staging::commit`]).
fn commit_dir(staged: &Path, out: &Path, results: &[&str]) -> Result<(), OutputError> {
    for name in results {
        if !staged.join(name).exists() {
            remove_result(&out.join(name), results)?;
        }
    }
    for entry in fs::read_dir(staged).map_err(io_err(staged))? {
        let entry = entry.map_err(io_err(staged))?;
        let (from, to) = (entry.path(), out.join(entry.file_name()));
        if from.is_dir() {
            if !to.is_dir() {
                remove_result(&to, results)?;
                fs::create_dir(&to).map_err(io_err(&to))?;
            }
            commit_dir(&from, &to, results)?;
        } else {
            fs::rename(&from, &to).map_err(io_err(&to))?;
        }
    }
    Ok(())
}

/// Removes a result file, or the result files of a result folder and the
/// folder if that leaves it empty (a file of the user's in it stays);
/// nothing if it is absent.
fn remove_result(path: &Path, results: &[&str]) -> Result<(), OutputError> {
    match fs::symlink_metadata(path) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(io_err(path)(e)),
        Ok(m) if m.is_dir() => {
            for name in results {
                remove_result(&path.join(name), results)?;
            }
            let _ = fs::remove_dir(path);
            Ok(())
        }
        Ok(_) => fs::remove_file(path).map_err(io_err(path)),
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.dir);
        }
    }
}

/// Removes the staging folders in `out` whose process no longer runs (a
/// killed run's); best effort.
fn remove_abandoned_staging(out: &Path) {
    let Ok(entries) = fs::read_dir(out) else {
        return;
    };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = name.strip_prefix(STAGING_PREFIX) else {
            continue;
        };
        let pid = rest.split('-').next().and_then(|p| p.parse::<u32>().ok());
        if pid.is_some_and(|p| p != std::process::id() && !process_runs(p)) {
            let _ = fs::remove_dir_all(entry.path());
        }
    }
}

/// Whether process `pid` may still run: its `/proc` entry exists, or there
/// is no `/proc` to tell (then nothing is removed).
fn process_runs(pid: u32) -> bool {
    !Path::new("/proc/self").exists() || Path::new(&format!("/proc/{pid}")).exists()
}

/// A float at full precision (`{}` of `f64`), or an empty cell when not
/// finite.
pub(crate) fn float_cell(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

fn opt_cell(x: Option<f64>) -> String {
    x.map(float_cell).unwrap_or_default()
}

/// Append one CSV record (RFC 4180 quoting where needed) and `\n`.
pub(crate) fn push_csv_row<'a>(out: &mut String, cells: impl IntoIterator<Item = &'a str>) {
    for (i, c) in cells.into_iter().enumerate() {
        if i > 0 {
            out.push(',');
        }
        if c.contains([',', '"', '\n', '\r']) {
            out.push('"');
            out.push_str(&c.replace('"', "\"\""));
            out.push('"');
        } else {
            out.push_str(c);
        }
    }
    out.push('\n');
}

/// The simulated outputs of one test, as written to `tests.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TestOutcome {
    /// Simulated mean delivered flow, l/min.
    pub flow_lpm_sim: f64,
    /// Measured volumetric efficiency (Eq. 15).
    pub eta_v_meas: f64,
    /// Simulated volumetric efficiency (Eq. 16).
    pub eta_v_sim: f64,
    /// `eta_v_meas - eta_v_sim` (Eq. 17).
    pub d: f64,
    /// Simulated mean shaft torque, N.m.
    pub torque_nm_sim: f64,
    /// Simulated loss budget, shares of `Vm n` (`LossBudget::parts` order;
    /// NaN where undefined).
    pub losses: [f64; LOSS_COLUMNS],
}

/// The text of `tests.csv`; `outcomes[i]` belongs to `campaign.rows[i]`.
pub fn tests_csv_string(
    campaign: &Campaign,
    outcomes: &[TestOutcome],
) -> Result<String, OutputError> {
    if outcomes.len() != campaign.rows.len() {
        return Err(OutputError::LengthMismatch {
            rows: campaign.rows.len(),
            outcomes: outcomes.len(),
        });
    }
    let mut header: Vec<String> =
        Vec::with_capacity(campaign.headers.len() + TESTS_SIM_COLUMNS.len());
    for h in &campaign.headers {
        let mut name = h.clone();
        if TESTS_SIM_COLUMNS.contains(&h.trim()) {
            name.push_str("_input");
            while campaign.headers.contains(&name) || header.contains(&name) {
                name.push_str("_input");
            }
        }
        header.push(name);
    }
    header.extend(TESTS_SIM_COLUMNS.iter().map(|s| s.to_string()));
    let mut out = String::new();
    push_csv_row(&mut out, header.iter().map(String::as_str));
    for (row, o) in campaign.rows.iter().zip(outcomes) {
        let sim: Vec<String> = [
            o.flow_lpm_sim,
            o.eta_v_meas,
            o.eta_v_sim,
            o.d,
            o.torque_nm_sim,
        ]
        .iter()
        .chain(o.losses.iter())
        .map(|&v| float_cell(v))
        .collect();
        push_csv_row(
            &mut out,
            row.cells
                .iter()
                .map(String::as_str)
                .chain(sim.iter().map(String::as_str)),
        );
    }
    Ok(out)
}

/// The text of `conditions.csv`.
pub fn conditions_csv_string(summaries: &[ConditionSummary]) -> String {
    let mut out = String::new();
    push_csv_row(&mut out, CONDITIONS_COLUMNS);
    for s in summaries {
        let c = &s.condition;
        let t = &s.stats;
        let cells = [
            float_cell(c.pressure_bar),
            float_cell(c.speed_rpm),
            float_cell(c.temp_c),
            t.n_samples.to_string(),
            opt_cell(t.d_mean),
            opt_cell(t.d_std),
            opt_cell(t.t_crit),
            opt_cell(t.ci_low),
            opt_cell(t.ci_high),
            opt_cell(t.delta_nu),
            s.torque.n_torque.to_string(),
            opt_cell(s.torque.torque_err_mean_nm),
            opt_cell(s.torque.torque_err_std_nm),
            opt_cell(s.torque.torque_err_rel_mean),
            opt_cell(s.torque.eta_hm_err_mean),
            opt_cell(s.torque.eta_hm_err_std),
        ];
        push_csv_row(&mut out, cells.iter().map(String::as_str));
    }
    out
}

/// Write `DIR/tests.csv` atomically; returns its path.
pub fn write_tests_csv(
    dir: &Path,
    campaign: &Campaign,
    outcomes: &[TestOutcome],
) -> Result<PathBuf, OutputError> {
    let path = dir.join(TESTS_CSV);
    atomic_write_text(&path, &tests_csv_string(campaign, outcomes)?)?;
    Ok(path)
}

/// Write `DIR/conditions.csv` atomically; returns its path.
pub fn write_conditions_csv(
    dir: &Path,
    summaries: &[ConditionSummary],
) -> Result<PathBuf, OutputError> {
    let path = dir.join(CONDITIONS_CSV);
    atomic_write_text(&path, &conditions_csv_string(summaries))?;
    Ok(path)
}

// ---------------------------------------------------------------------------
// Fingerprints

pub use gearpump_core::hash::{Fingerprint, Fnv1a};

/// Fingerprints of a campaign run: one for what every row shares (code
/// version, design text, `--set` list) and one per row combining it with the
/// row's simulation inputs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RunFingerprint {
    run: Fingerprint,
    rows: Vec<Fingerprint>,
}

impl RunFingerprint {
    /// `code_version` should change whenever the model code changes (e.g.
    /// the crate version plus a git revision); `sets` are the `--set`
    /// arguments in order (later ones override earlier ones, so order
    /// matters); put any other run-wide option that changes results (e.g. an
    /// inlet pressure) into `sets` too. Each row contributes its sample
    /// clearances, pressure, speed and temperature (the measured flow and
    /// torque do not affect the simulation).
    pub fn new(design_text: &str, sets: &[String], code_version: &str, rows: &[TestRow]) -> Self {
        let mut h = Fnv1a::new();
        h.write_str("gearpump-campaign-journal/1");
        h.write_str(code_version);
        h.write_str(design_text);
        h.write_u64(sets.len() as u64);
        for s in sets {
            h.write_str(s);
        }
        let run = h.finish();
        let rows = rows
            .iter()
            .map(|r| {
                let mut h = Fnv1a::new();
                h.write_u64(run.0);
                for x in r.tip_clearance.iter().chain(&r.bearing_clearance) {
                    h.write_f64(*x);
                }
                h.write_f64(r.pressure);
                h.write_f64(r.speed);
                h.write_f64(r.temp);
                h.finish()
            })
            .collect();
        RunFingerprint { run, rows }
    }

    /// The run-wide part.
    pub fn run(&self) -> Fingerprint {
        self.run
    }
    /// The fingerprint of row `idx`.
    pub fn row(&self, idx: usize) -> Option<Fingerprint> {
        self.rows.get(idx).copied()
    }
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }
}

// ---------------------------------------------------------------------------
// Journal

/// The simulated result of one row, as journaled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RowResult {
    /// Simulated mean delivered flow, l/min.
    pub flow_lpm_sim: f64,
    /// Simulated mean shaft torque, N.m.
    pub torque_nm_sim: f64,
    /// Simulated volumetric efficiency.
    pub eta_v_sim: f64,
    /// Any further outputs the caller wants back on resume.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extra: Option<serde_json::Value>,
}

#[derive(Debug, Error)]
pub enum JournalError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("journal: row {row} out of range ({rows} rows)")]
    RowOutOfRange { row: usize, rows: usize },
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error("journal: cannot encode row {row}: {source}")]
    Encode {
        row: usize,
        #[source]
        source: serde_json::Error,
    },
}

/// What [`Journal::open`] found in an existing journal.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct JournalLoad {
    /// Rows whose result is reused.
    pub reused: usize,
    /// Well-formed entries dropped: fingerprint or row index no longer matches.
    pub stale: usize,
    /// Lines that did not parse (a torn last line after a crash).
    pub unreadable: usize,
}

/// One journal line. Floats are stored as Rust `{}` text and read back with
/// `str::parse` (exact round trip, NaN included): serde_json, built without
/// its `float_roundtrip` feature, may read a float back 1 ulp off, and a
/// resumed run must give bit-identical outputs.
#[derive(Serialize, Deserialize)]
struct Entry {
    row: usize,
    fp: String,
    result: EncodedResult,
}

#[derive(Serialize, Deserialize)]
struct EncodedResult {
    flow_lpm_sim: String,
    torque_nm_sim: String,
    eta_v_sim: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    extra: Option<serde_json::Value>,
}

impl EncodedResult {
    fn encode(r: &RowResult) -> Self {
        EncodedResult {
            flow_lpm_sim: r.flow_lpm_sim.to_string(),
            torque_nm_sim: r.torque_nm_sim.to_string(),
            eta_v_sim: r.eta_v_sim.to_string(),
            extra: r.extra.as_ref().map(encode_value),
        }
    }
    fn decode(self) -> Option<RowResult> {
        Some(RowResult {
            flow_lpm_sim: self.flow_lpm_sim.parse().ok()?,
            torque_nm_sim: self.torque_nm_sim.parse().ok()?,
            eta_v_sim: self.eta_v_sim.parse().ok()?,
            extra: match self.extra {
                None => None,
                Some(v) => Some(decode_value(v)?),
            },
        })
    }
}

/// Exact encoding of extra outputs: every string gets the prefix `s`, every
/// non-integer number becomes the string `f` + its `{}` text; integers,
/// booleans, null, arrays and object keys are unchanged.
fn encode_value(v: &serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::String(s) => Value::String(format!("s{s}")),
        Value::Number(n) if !(n.is_i64() || n.is_u64()) => match n.as_f64() {
            Some(x) => Value::String(format!("f{x}")),
            None => v.clone(),
        },
        Value::Array(a) => Value::Array(a.iter().map(encode_value).collect()),
        Value::Object(o) => Value::Object(
            o.iter()
                .map(|(k, x)| (k.clone(), encode_value(x)))
                .collect(),
        ),
        _ => v.clone(),
    }
}

fn decode_value(v: serde_json::Value) -> Option<serde_json::Value> {
    use serde_json::Value;
    Some(match v {
        Value::String(s) => match s.split_at_checked(1) {
            Some(("s", rest)) => Value::String(rest.to_string()),
            Some(("f", rest)) => Value::Number(serde_json::Number::from_f64(rest.parse().ok()?)?),
            _ => return None,
        },
        Value::Array(a) => Value::Array(a.into_iter().map(decode_value).collect::<Option<_>>()?),
        Value::Object(o) => Value::Object(
            o.into_iter()
                .map(|(k, x)| decode_value(x).map(|x| (k, x)))
                .collect::<Option<_>>()?,
        ),
        other => other,
    })
}

struct Inner {
    file: File,
    done: HashMap<usize, RowResult>,
}

/// Append-only, crash-tolerant record of simulated rows (see module doc).
/// `record` may be called from many threads.
pub struct Journal {
    path: PathBuf,
    fingerprint: RunFingerprint,
    load: JournalLoad,
    inner: Mutex<Inner>,
}

impl fmt::Debug for Journal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Journal")
            .field("path", &self.path)
            .field("run", &self.fingerprint.run())
            .field("load", &self.load)
            .finish()
    }
}

impl Journal {
    /// Open (or create) `DIR/journal.jsonl` for the run `fingerprint`,
    /// keeping the entries that still match and compacting the file.
    pub fn open(dir: &Path, fingerprint: &RunFingerprint) -> Result<Journal, JournalError> {
        fs::create_dir_all(dir).map_err(|source| JournalError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let path = dir.join(JOURNAL_FILE);
        let jerr = |source| JournalError::Io {
            path: path.clone(),
            source,
        };
        let mut load = JournalLoad::default();
        let mut done: HashMap<usize, RowResult> = HashMap::new();
        match fs::read(&path) {
            Ok(bytes) => {
                for line in bytes.split(|&b| b == b'\n') {
                    if line.iter().all(u8::is_ascii_whitespace) {
                        continue;
                    }
                    let parsed = serde_json::from_slice::<Entry>(line)
                        .ok()
                        .and_then(|e| Some((e.row, e.fp, e.result.decode()?)));
                    let Some((row, fp_text, result)) = parsed else {
                        load.unreadable += 1;
                        continue;
                    };
                    match fingerprint.row(row) {
                        Some(fp) if fp.to_string() == fp_text => {
                            done.insert(row, result);
                        }
                        _ => load.stale += 1,
                    }
                }
            }
            Err(e) if e.kind() == io::ErrorKind::NotFound => {}
            Err(e) => return Err(jerr(e)),
        }
        load.reused = done.len();

        // Rewrite with the valid entries only (sorted, one line each), so a
        // torn tail or stale entries never precede new appends.
        let mut rows: Vec<usize> = done.keys().copied().collect();
        rows.sort_unstable();
        let mut text = String::new();
        for row in rows {
            if let (Some(result), Some(fp)) = (done.get(&row), fingerprint.row(row)) {
                text.push_str(&encode_line(row, fp, result)?);
            }
        }
        atomic_write_text(&path, &text)?;
        let file = OpenOptions::new().append(true).open(&path).map_err(jerr)?;
        Ok(Journal {
            path,
            fingerprint: fingerprint.clone(),
            load,
            inner: Mutex::new(Inner { file, done }),
        })
    }

    /// Path of the journal file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// What was found on open.
    pub fn load_report(&self) -> JournalLoad {
        self.load
    }

    /// Rows already simulated for this run fingerprint (from the journal on
    /// disk and from [`Journal::record`] since), by row index.
    pub fn done(&self) -> HashMap<usize, RowResult> {
        self.lock().done.clone()
    }

    /// Append the result of row `idx` (one line, flushed and fsynced before
    /// returning). Thread-safe.
    pub fn record(&self, idx: usize, result: &RowResult) -> Result<(), JournalError> {
        let fp = self
            .fingerprint
            .row(idx)
            .ok_or(JournalError::RowOutOfRange {
                row: idx,
                rows: self.fingerprint.len(),
            })?;
        let line = encode_line(idx, fp, result)?;
        let mut inner = self.lock();
        let io = |source| JournalError::Io {
            path: self.path.clone(),
            source,
        };
        inner.file.write_all(line.as_bytes()).map_err(io)?;
        inner.file.flush().map_err(io)?;
        inner.file.sync_data().map_err(io)?;
        inner.done.insert(idx, result.clone());
        Ok(())
    }

    /// Close the journal after the final outputs have been written: the
    /// outputs are now the record, so the journal file is removed.
    pub fn finish(self) -> Result<(), JournalError> {
        let path = self.path.clone();
        drop(self);
        match fs::remove_file(&path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(()),
            Err(source) => Err(JournalError::Io { path, source }),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic in another thread while holding the lock cannot leave the
        // map or the file half-updated in a way that matters: each line is
        // one write, and a torn line is ignored on the next open.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }
}

fn encode_line(row: usize, fp: Fingerprint, result: &RowResult) -> Result<String, JournalError> {
    let mut s = serde_json::to_string(&Entry {
        row,
        fp: fp.to_string(),
        result: EncodedResult::encode(result),
    })
    .map_err(|source| JournalError::Encode { row, source })?;
    s.push('\n');
    Ok(s)
}

/// A measured campaign CSV (header + rows, columns in [`COLUMNS`] order,
/// `\n` line ends) with every float at full precision (shortest text that
/// reads back to the same `f64`). Non-finite values are written as empty
/// cells, which the reader refuses except for `torque_nm`.
pub fn campaign_csv_string(records: &[CampaignRecord]) -> String {
    let mut out = String::new();
    push_csv_row(&mut out, COLUMNS.iter().copied());
    for r in records {
        let cells = [
            r.sample.clone(),
            float_cell(r.tip_clearance_drive_um),
            float_cell(r.tip_clearance_driven_um),
            float_cell(r.bearing_clearance_drive_um),
            float_cell(r.bearing_clearance_driven_um),
            float_cell(r.pressure_bar),
            float_cell(r.speed_rpm),
            float_cell(r.temp_c),
            float_cell(r.flow_lpm),
            r.torque_nm.map(float_cell).unwrap_or_default(),
        ];
        push_csv_row(&mut out, cells.iter().map(String::as_str));
    }
    out
}

/// Write a measured campaign CSV atomically (see [`atomic_write`]).
pub fn write_campaign_csv(path: &Path, records: &[CampaignRecord]) -> Result<(), OutputError> {
    atomic_write_text(path, &campaign_csv_string(records))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::parse_campaign_str;
    use crate::stats::{condition_stats, ConditionSummary, ALPHA};
    use crate::Condition;

    /// The output-path check shared by the CLI (`--out: ...`) and the
    /// Python package (`out: ...`): the reason after the path.
    #[test]
    fn check_out_says_why_a_path_cannot_be_written() {
        let dir = std::env::temp_dir().join(format!("gearpump-check-out-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let file = dir.join("a-file");
        fs::write(&file, "x").unwrap();
        assert_eq!(check_out(Path::new(""), false).unwrap_err(), "empty path");
        assert!(check_out(&dir.join("new/deeper"), false).is_ok());
        assert!(check_out(&dir.join("out.csv"), true).is_ok());
        let e = check_out(&file, false).unwrap_err();
        assert!(e.ends_with("a-file: exists and is not a directory"), "{e}");
        let e = check_out(&dir, true).unwrap_err();
        assert!(e.contains("is a folder"), "{e}");
        let e = check_out(&file.join("x"), false).unwrap_err();
        assert!(e.contains("is a file, not a folder"), "{e}");
        if Path::new("/proc/self").is_dir() {
            let e = check_out(Path::new("/proc/nope/x"), false).unwrap_err();
            assert!(e.starts_with("/proc/nope/x: cannot write in /proc"), "{e}");
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    /// A fresh scratch directory, removed on drop.
    struct Scratch(PathBuf);
    impl Scratch {
        fn new(name: &str) -> Self {
            let p = std::env::temp_dir().join(format!(
                "gearpump-campaign-{name}-{}-{}",
                std::process::id(),
                TMP_COUNTER.fetch_add(1, Ordering::Relaxed)
            ));
            let _ = fs::remove_dir_all(&p);
            fs::create_dir_all(&p).unwrap();
            Scratch(p)
        }
    }
    impl Drop for Scratch {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    const CSV: &str = "note,sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,speed_rpm,pressure_bar,temp_c,flow_lpm,torque_nm,operator\n\
        \"a, b\",N01,30,32,10,12,1000,30,60,13.50,7.1,x\n\
        ,N02,31,33,11,13,1000,30,60,13.4,,\"say \"\"hi\"\"\"\n\
        c,N01,30,32,10,12,2000,30,60,27.0,7.3,y\n";

    fn campaign() -> Campaign {
        parse_campaign_str("c.csv", CSV).unwrap()
    }

    fn result(x: f64) -> RowResult {
        RowResult {
            flow_lpm_sim: x,
            torque_nm_sim: 2.0 * x,
            eta_v_sim: 0.9 + x * 1e-3,
            extra: Some(serde_json::json!({"ripple_lpm": x / 3.0, "iters": 4})),
        }
    }

    fn fp(c: &Campaign, design: &str) -> RunFingerprint {
        RunFingerprint::new(design, &["oil.nu_40c_cst=32".into()], "0.1.0", &c.rows)
    }

    #[test]
    fn campaign_io_atomic_write_leaves_no_temp_file() {
        let s = Scratch::new("atomic");
        let p = s.0.join("out.txt");
        atomic_write_text(&p, "first\n").unwrap();
        atomic_write_text(&p, "second, longer\n").unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "second, longer\n");
        assert_eq!(entries(&s.0), vec!["out.txt"]);
    }

    #[test]
    fn campaign_io_atomic_write_failure_keeps_nothing_half_written() {
        let s = Scratch::new("atomic-fail");
        // Destination is a non-empty directory: the rename fails.
        let p = s.0.join("out.txt");
        fs::create_dir(&p).unwrap();
        fs::write(p.join("keep"), "k").unwrap();
        let e = atomic_write_text(&p, "data").unwrap_err();
        assert!(e.to_string().contains("out.txt"), "{e}");
        assert_eq!(entries(&s.0), vec!["out.txt"]);
        assert_eq!(fs::read_to_string(p.join("keep")).unwrap(), "k");
        // Missing directory: error names the path, nothing created.
        let e = atomic_write_text(&s.0.join("nodir/x.csv"), "data").unwrap_err();
        assert!(e.to_string().contains("nodir"), "{e}");
    }

    #[test]
    fn campaign_io_atomic_write_readers_never_see_half_file() {
        let s = Scratch::new("atomic-race");
        let p = s.0.join("big.bin");
        let a = vec![b'a'; 1 << 20];
        let b = vec![b'b'; 1 << 20];
        atomic_write(&p, &a).unwrap();
        let stop = std::sync::atomic::AtomicBool::new(false);
        std::thread::scope(|sc| {
            sc.spawn(|| {
                for i in 0..20 {
                    atomic_write(&p, if i % 2 == 0 { &b } else { &a }).unwrap();
                }
                stop.store(true, Ordering::SeqCst);
            });
            let mut reads = 0;
            while !stop.load(Ordering::SeqCst) || reads == 0 {
                let got = fs::read(&p).unwrap();
                assert_eq!(got.len(), 1 << 20);
                assert!(got.iter().all(|&c| c == got[0]));
                reads += 1;
            }
        });
        assert_eq!(entries(&s.0), vec!["big.bin"]);
    }

    #[test]
    fn campaign_io_tests_csv_keeps_every_input_column_in_order() {
        let c = campaign();
        let outcomes = vec![
            TestOutcome {
                flow_lpm_sim: 13.0,
                eta_v_meas: 0.1 + 0.2,
                eta_v_sim: 0.9,
                d: 1.0 / 3.0,
                torque_nm_sim: 7.0,
                losses: [0.02, -0.005, 0.01, 0.0, 0.005, 0.003],
            },
            TestOutcome {
                flow_lpm_sim: f64::NAN,
                eta_v_meas: 0.91,
                eta_v_sim: f64::NAN,
                d: f64::NAN,
                torque_nm_sim: f64::INFINITY,
                losses: [f64::NAN; LOSS_COLUMNS],
            },
            TestOutcome {
                flow_lpm_sim: 26.5,
                eta_v_meas: 0.92,
                eta_v_sim: 0.93,
                d: -0.01,
                torque_nm_sim: 7.2,
                losses: [f64::NAN; LOSS_COLUMNS],
            },
        ];
        let text = tests_csv_string(&c, &outcomes).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "note,sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,speed_rpm,pressure_bar,temp_c,flow_lpm,torque_nm,operator,flow_lpm_sim,eta_v_meas,eta_v_sim,d,torque_nm_sim,loss_tip_poiseuille,loss_tip_couette,loss_lateral,loss_bearings,loss_mesh_zone,loss_compressibility"
        );
        // Original text unchanged ("13.50" stays "13.50"), quoting preserved.
        assert_eq!(
            lines[1],
            "\"a, b\",N01,30,32,10,12,1000,30,60,13.50,7.1,x,13,0.30000000000000004,0.9,0.3333333333333333,7,0.02,-0.005,0.01,0,0.005,0.003"
        );
        assert_eq!(
            lines[2],
            ",N02,31,33,11,13,1000,30,60,13.4,,\"say \"\"hi\"\"\",,0.91,,,,,,,,,"
        );
        // The output reads back as a valid campaign with the same input cells.
        let back = parse_campaign_str("tests.csv", &text).unwrap();
        assert_eq!(back.rows.len(), 3);
        for (r0, r1) in c.rows.iter().zip(&back.rows) {
            assert_eq!(r0.cells[..], r1.cells[..12]);
        }
        assert!(matches!(
            tests_csv_string(&c, &outcomes[..2]),
            Err(OutputError::LengthMismatch {
                rows: 3,
                outcomes: 2
            })
        ));
    }

    #[test]
    fn campaign_io_tests_csv_renames_colliding_input_columns() {
        let text = "sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm,d,eta_v_sim\n\
                    N01,1,1,1,1,30,1000,60,1,,0.5,0.7\n";
        let c = parse_campaign_str("c.csv", text).unwrap();
        let o = TestOutcome {
            flow_lpm_sim: 1.0,
            eta_v_meas: 1.0,
            eta_v_sim: 1.0,
            d: 0.0,
            torque_nm_sim: 1.0,
            losses: [f64::NAN; LOSS_COLUMNS],
        };
        let out = tests_csv_string(&c, &[o]).unwrap();
        let header = out.lines().next().unwrap();
        assert!(header.ends_with(",torque_nm,d_input,eta_v_sim_input,flow_lpm_sim,eta_v_meas,eta_v_sim,d,torque_nm_sim,loss_tip_poiseuille,loss_tip_couette,loss_lateral,loss_bearings,loss_mesh_zone,loss_compressibility"), "{header}");
        assert!(out.lines().nth(1).unwrap().contains(",0.5,0.7,1,1,1,0,1"));
    }

    #[test]
    fn campaign_io_conditions_csv_full_precision_and_empty_undefined() {
        let cond = Condition {
            pressure_bar: 30.0,
            speed_rpm: 1000.0,
            temp_c: 60.0,
        };
        let s2 = condition_stats(&[0.1, 0.2, 0.3 + 1e-12], ALPHA).unwrap();
        let s1 = condition_stats(&[0.1], ALPHA).unwrap();
        let text = conditions_csv_string(&[
            ConditionSummary {
                condition: cond,
                stats: s2.clone(),
                torque: Default::default(),
            },
            ConditionSummary {
                condition: Condition {
                    temp_c: 120.0,
                    ..cond
                },
                stats: s1,
                torque: Default::default(),
            },
        ]);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "pressure_bar,speed_rpm,temp_c,n_samples,d_mean,d_std,t_crit,ci_low,ci_high,delta_nu,n_torque,torque_err_mean_nm,torque_err_std_nm,torque_err_rel_mean,eta_hm_err_mean,eta_hm_err_std"
        );
        let cells: Vec<&str> = lines[1].split(',').collect();
        assert_eq!(cells[3], "3");
        assert_eq!(cells[4].parse::<f64>().unwrap(), s2.d_mean.unwrap());
        assert_eq!(cells[9].parse::<f64>().unwrap(), s2.delta_nu.unwrap());
        // undefined statistics and conditions without a measured torque:
        // empty cells, not zeros
        assert_eq!(lines[2], "30,1000,120,1,0.1,,,,,,0,,,,,");
        let s = Scratch::new("cond");
        let p = write_conditions_csv(&s.0, &[]).unwrap();
        assert_eq!(fs::read_to_string(p).unwrap(), format!("{}\n", lines[0]));
    }

    #[test]
    fn campaign_io_fnv1a_reference_vectors() {
        let h = |s: &str| {
            let mut f = Fnv1a::new();
            f.write(s.as_bytes());
            f.finish().0
        };
        assert_eq!(h(""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(h("a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(h("foobar"), 0x8594_4171_f739_67e8);
        assert_eq!(Fingerprint(0xab).to_string(), "00000000000000ab");
    }

    #[test]
    fn campaign_io_journal_resumes_recorded_rows() {
        let s = Scratch::new("journal");
        let c = campaign();
        let f = fp(&c, "design");
        let j = Journal::open(&s.0, &f).unwrap();
        assert!(j.done().is_empty());
        j.record(0, &result(1.0)).unwrap();
        j.record(2, &result(3.0)).unwrap();
        assert_eq!(j.done().len(), 2);
        drop(j);
        let j = Journal::open(&s.0, &f).unwrap();
        let done = j.done();
        assert_eq!(done.len(), 2);
        assert_eq!(done[&0], result(1.0));
        assert_eq!(done[&2], result(3.0));
        assert_eq!(j.load_report().reused, 2);
        assert!(matches!(
            j.record(3, &result(0.0)),
            Err(JournalError::RowOutOfRange { row: 3, rows: 3 })
        ));
    }

    #[test]
    fn campaign_io_journal_round_trips_bits_exactly() {
        let s = Scratch::new("journal-exact");
        let c = campaign();
        let f = fp(&c, "design");
        let tricky = RowResult {
            flow_lpm_sim: 0.1 + 0.2,
            torque_nm_sim: f64::NAN,
            eta_v_sim: 1.0 / 3.0,
            extra: Some(serde_json::json!({
                "fname": "f1.5", "s": "s", "empty": "", "n": -3, "big": u64::MAX,
                "list": [1.0e-300, 5e-324, 2.0f64.sqrt(), null, true, {"x": 0.7}],
            })),
        };
        let j = Journal::open(&s.0, &f).unwrap();
        j.record(1, &tricky).unwrap();
        for i in 0..50 {
            j.record(0, &result(i as f64 / 7.0)).unwrap();
        }
        drop(j);
        let done = Journal::open(&s.0, &f).unwrap().done();
        let got = &done[&1];
        assert_eq!(got.flow_lpm_sim.to_bits(), tricky.flow_lpm_sim.to_bits());
        assert!(got.torque_nm_sim.is_nan());
        assert_eq!(got.eta_v_sim.to_bits(), tricky.eta_v_sim.to_bits());
        assert_eq!(got.extra, tricky.extra);
        // Last entry for a row wins.
        assert_eq!(done[&0], result(49.0 / 7.0));
    }

    #[test]
    fn campaign_io_journal_ignores_torn_last_line() {
        let s = Scratch::new("journal-torn");
        let c = campaign();
        let f = fp(&c, "design");
        let j = Journal::open(&s.0, &f).unwrap();
        for i in 0..3 {
            j.record(i, &result(i as f64 + 0.5)).unwrap();
        }
        drop(j);
        // Crash in the middle of writing row 2's line.
        let p = s.0.join(JOURNAL_FILE);
        let bytes = fs::read(&p).unwrap();
        let last_start = bytes[..bytes.len() - 1]
            .iter()
            .rposition(|&b| b == b'\n')
            .unwrap()
            + 1;
        let cut = last_start + (bytes.len() - last_start) / 2;
        fs::write(&p, &bytes[..cut]).unwrap();

        let j = Journal::open(&s.0, &f).unwrap();
        let done = j.done();
        assert_eq!(done.len(), 2);
        assert!(done.contains_key(&0) && done.contains_key(&1) && !done.contains_key(&2));
        assert_eq!(j.load_report().unreadable, 1);
        // Appending after the torn line must not corrupt the new entry.
        j.record(2, &result(9.0)).unwrap();
        drop(j);
        let j = Journal::open(&s.0, &f).unwrap();
        assert_eq!(j.done().len(), 3);
        assert_eq!(j.done()[&2], result(9.0));
        assert_eq!(j.load_report().unreadable, 0);
        assert_eq!(entries(&s.0), vec![JOURNAL_FILE]);
    }

    #[test]
    fn campaign_io_journal_fingerprint_change_invalidates() {
        let s = Scratch::new("journal-fp");
        let c = campaign();
        let f = fp(&c, "design");
        let j = Journal::open(&s.0, &f).unwrap();
        for i in 0..3 {
            j.record(i, &result(i as f64)).unwrap();
        }
        drop(j);
        // A different design text invalidates every row.
        let j = Journal::open(&s.0, &fp(&c, "design, edited")).unwrap();
        assert!(j.done().is_empty());
        assert_eq!(j.load_report().stale, 3);
        drop(j);

        // Rebuild with the original run, then change one row's clearance.
        let j = Journal::open(&s.0, &f).unwrap();
        for i in 0..3 {
            j.record(i, &result(i as f64)).unwrap();
        }
        drop(j);
        let edited = CSV.replace("N02,31,33", "N02,31,34");
        let c2 = parse_campaign_str("c.csv", &edited).unwrap();
        let j = Journal::open(&s.0, &fp(&c2, "design")).unwrap();
        let done = j.done();
        assert_eq!(done.len(), 2);
        assert!(!done.contains_key(&1));
        // The --set list and the code version are part of the fingerprint.
        let other_set = RunFingerprint::new("design", &[], "0.1.0", &c.rows);
        let other_version =
            RunFingerprint::new("design", &["oil.nu_40c_cst=32".into()], "0.2.0", &c.rows);
        assert_ne!(other_set.run(), f.run());
        assert_ne!(other_version.run(), f.run());
        assert_ne!(f.row(0), f.row(1));
        // Measured flow does not affect the simulation: same fingerprint.
        let c3 = parse_campaign_str("c.csv", &CSV.replace("13.50", "13.6")).unwrap();
        assert_eq!(fp(&c3, "design"), f);
    }

    #[test]
    fn campaign_io_journal_parallel_records_and_finish() {
        use rayon::prelude::*;
        let s = Scratch::new("journal-par");
        let mut text = String::from("sample,tip_clearance_drive_um,tip_clearance_driven_um,bearing_clearance_drive_um,bearing_clearance_driven_um,pressure_bar,speed_rpm,temp_c,flow_lpm,torque_nm\n");
        for i in 0..200 {
            text.push_str(&format!("N{i},30,30,10,10,30,1000,60,13,\n"));
        }
        let c = parse_campaign_str("c.csv", &text).unwrap();
        let f = fp(&c, "design");
        let j = Journal::open(&s.0, &f).unwrap();
        (0..200usize)
            .into_par_iter()
            .try_for_each(|i| j.record(i, &result(i as f64)))
            .unwrap();
        drop(j);
        let j = Journal::open(&s.0, &f).unwrap();
        let done = j.done();
        assert_eq!(done.len(), 200);
        assert!((0..200).all(|i| done[&i] == result(i as f64)));
        j.finish().unwrap();
        assert!(entries(&s.0).is_empty());
    }

    /// An output folder holds the whole new result or the one it held: a
    /// staged result dropped before its commit leaves the folder as it was;
    /// a commit moves the new files in and removes the result names the new
    /// result lacks (an earlier diagnosis under a new campaign), keeping the
    /// user's files and the journal (issue 18 point 9).
    #[test]
    fn staged_results_replace_the_old_one_whole_or_not_at_all() {
        let s = Scratch::new("staging");
        let out = s.0.join("out");
        fs::create_dir_all(out.join("extended")).unwrap();
        for (name, text) in [
            ("tests.csv", "old"),
            ("report.md", "old"),
            ("curves_speed.svg", "old"),
            ("diagnosis.json", "old"),
            ("extended/tests.csv", "old"),
            ("notes.txt", "the user's"),
            (JOURNAL_FILE, "{}"),
        ] {
            fs::write(out.join(name), text).unwrap();
        }
        let before = entries(&out);
        // a run that fails while writing: nothing changes
        {
            let stage = Staging::new(&out).unwrap();
            fs::write(stage.path().join("tests.csv"), "new").unwrap();
        }
        assert_eq!(entries(&out), before);
        assert_eq!(fs::read_to_string(out.join("tests.csv")).unwrap(), "old");
        // a staging folder of a process that no longer runs is removed
        let dead = out.join(".staging-4000000000-0");
        fs::create_dir(&dead).unwrap();
        // a committed campaign result
        let stage = Staging::new(&out).unwrap();
        assert!(!dead.exists());
        for name in ["tests.csv", "report.md", "residuals.svg"] {
            fs::write(stage.path().join(name), "new").unwrap();
        }
        let staged = stage.path().join("tests.csv");
        assert_eq!(stage.final_path(&staged), out.join("tests.csv"));
        stage.commit().unwrap();
        assert_eq!(
            entries(&out),
            [
                JOURNAL_FILE,
                "notes.txt",
                "report.md",
                "residuals.svg",
                "tests.csv"
            ]
        );
        for name in ["tests.csv", "report.md", "residuals.svg"] {
            assert_eq!(fs::read_to_string(out.join(name)).unwrap(), "new");
        }
        // a staged folder's result files replace the old ones; a file of the
        // user's in it stays, and the folder too while it holds one
        fs::create_dir_all(out.join("extended")).unwrap();
        fs::write(out.join("extended/notes.txt"), "the user's").unwrap();
        fs::write(out.join("extended/conditions.csv"), "old").unwrap();
        let stage = Staging::new(&out).unwrap();
        fs::create_dir(stage.path().join("extended")).unwrap();
        fs::write(stage.path().join("extended/tests.csv"), "new").unwrap();
        stage.commit().unwrap();
        assert_eq!(entries(&out.join("extended")), ["notes.txt", "tests.csv"]);
        assert_eq!(entries(&out), ["extended", JOURNAL_FILE, "notes.txt"]);
        assert_eq!(
            fs::read_to_string(out.join("extended/tests.csv")).unwrap(),
            "new"
        );
        Staging::new(&out).unwrap().commit().unwrap();
        assert_eq!(entries(&out.join("extended")), ["notes.txt"]);
    }
}
