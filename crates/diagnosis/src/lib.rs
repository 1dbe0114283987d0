//! Diagnosis: from measured data to what the simulation gets wrong, its
//! physical cause, the extended model and its gain (issue "Diagnosis").
//!
//! * [`stats`]: the statistics, all at the level of pumps (the independent
//!   units of the seed's argument): association of the residual with each
//!   feature, Holm's multiplicity adjustment, paired one-sided comparisons of
//!   held-out errors and cross-validation folds by pump.
//! * [`findings`]: what is wrong: the residual's association with each
//!   feature a physicist would suspect, Holm-adjusted.
//! * [`pairs`]: every pair of first-step candidates screened on their
//!   linearisations, the best one checked on the model (two effects at once).
//! * [`candidates`]: why: every effect of docs/model.md section 8 fitted with few
//!   model runs (sensitivities, Broyden) and cross-validated over pumps.
//! * [`diagnose`]: `gearpump diagnose`: the decision rule (Holm over
//!   candidates, ambiguity, "not explained"), the extended model and its gain.
//! * [`verdict`]: what a diagnosis found and the names of its files.
//! * [`report`]: `report.md` and `diagnosis.svg`.
//! * [`eval`]: `gearpump eval-diagnosis`: detection and false-alarm rates over
//!   many synthetic campaigns.
#![forbid(unsafe_code)]

pub mod candidates;
pub mod diagnose;
pub mod eval;
pub mod findings;
pub mod pairs;
pub mod plant;
pub mod report;
pub mod stats;
pub mod structure;
pub mod torque;
pub mod verdict;

/// Helpers of the unit tests.
#[cfg(test)]
pub(crate) mod testing {
    /// A standard normal draw (Box-Muller) from a seeded stream.
    pub fn normal(rng: &mut impl rand::Rng) -> f64 {
        let u1: f64 = rng.gen_range(1e-12..1.0);
        let u2: f64 = rng.gen();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
}
