//! Population validation campaign: measured data, trace-driven runs, statistics.
//!
//! After Battarra & Mucchi (2020), Sec. 4. A campaign is a set of tests on
//! nominally identical pump samples, each characterised by its measured
//! radial clearances, each tested at several working conditions (delivery
//! pressure, speed, oil temperature). Every test is simulated with that
//! sample's own clearances (*trace-driven* simulation), and the model accuracy
//! is quantified per working condition from the population of samples.
//!
//! # Equations (seed paper, re-derived)
//! * Eqs. 15/16, volumetric efficiency, measured and simulated:
//!   `eta_v = Q / (V_m n)`, with `Q` the mean delivered flow (m^3/s), `V_m` the
//!   theoretical displacement per driving-gear revolution (m^3/rev) and
//!   `n = omega / (2 pi)` the shaft speed in rev/s ([`stats::eta_v`]).
//! * Eq. 17, per test: `d = eta_v,meas - eta_v,sim`.
//! * Eq. 18, t statistic of `H0: E(d) = mu_0 = 0`:
//!   `t_0 = (d_mean - mu_0) / (S_d / sqrt(n_s))`, `S_d` the sample standard
//!   deviation (divisor `n_s - 1`), `n_s` the number of samples tested at
//!   that condition.
//! * Eq. 19, two-sided confidence interval at significance `alpha` (0.05):
//!   `[d_min, d_max] = d_mean -+ t_{1 - alpha/2, n_s - 1} S_d / sqrt(n_s)`.
//!   The PDF text writes the quantile as `t_{alpha, n_s - 1}` with the
//!   two-sided meaning; we use the `1 - alpha/2` quantile explicitly.
//! * Eq. 20, closeness to reality: `Delta_nu = max(|mu_0 - d_min|, |mu_0 - d_max|)`
//!   with `mu_0 = 0`.
//!
//! # Modules
//! * [`data`]: the measured campaign CSV (reading with strict validation,
//!   writing for `synth`) and grouping by working condition.
//! * [`stats`]: Eqs. 15-20.
//! * [`io`]: atomic output files, `tests.csv`, `conditions.csv`, and the
//!   resumable journal of simulated rows.
//! * [`run`]: `gearpump campaign`: trace-driven simulation of every row in
//!   parallel, journaled and resumable.
//! * [`effects`]: the switchable physical extensions of docs/model.md section 8.
//! * [`synth`]: `gearpump synth`: synthetic campaigns with known hidden effects.
//! * [`report`], [`plots`]: `report.md` and the SVG figures.
//! * [`montecarlo`]: `gearpump montecarlo`: tolerance analysis of a
//!   production population (distributions, yields, Sobol indices).
#![forbid(unsafe_code)]

pub mod conditions;
pub mod data;
pub mod effects;
pub mod extend;
pub mod figures;
pub mod io;
pub mod montecarlo;
pub mod plots;
pub mod point;
pub mod report;
pub mod run;
pub mod stats;
pub mod synth;

pub use data::{
    group_by_condition, parse_campaign_str, read_campaign, Campaign, CampaignRecord, CellProblem,
    Condition, ConditionGroup, DataError, TestRow, COLUMNS,
};
pub use io::{
    atomic_write, atomic_write_text, campaign_csv_string, conditions_csv_string, tests_csv_string,
    write_campaign_csv, write_conditions_csv, write_tests_csv, Fingerprint, Fnv1a, Journal,
    JournalError, JournalLoad, OutputError, RowResult, RunFingerprint, TestOutcome, CONDITIONS_CSV,
    JOURNAL_FILE, TESTS_CSV,
};
pub use stats::{
    condition_stats, eta_v, summarize, t_quantile, ConditionStats, ConditionSummary, StatsError,
    ALPHA,
};
