//! Diagnosis: from measured data to what the simulation gets wrong, its
//! physical cause, the extended model and its gain (issue "Diagnosis").
//!
//! * [`stats`]: the statistics, all at the level of pumps (the independent
//!   units of the seed's argument): association of the residual with each
//!   feature, Holm's multiplicity adjustment, paired one-sided comparisons of
//!   held-out errors and cross-validation folds by pump.
//! * [`findings`]: what is wrong: the residual's association with each
//!   feature a physicist would suspect, Holm-adjusted.

pub mod findings;
pub mod stats;
