//! # gearpump
//!
//! Lumped-parameter model of external gear pumps after Battarra & Mucchi
//! (2020): helical gears with unequal tooth numbers, pocket-by-pocket pressure
//! build-up, leakages, gear micromotions, journal bearings, mesh force; with
//! population validation, diagnosis and an FMI 2.0 co-simulation unit.
//!
//! This crate holds no code: it gathers the layers of the workspace under one
//! name (the paths its users write, `gearpump::model::Simulation`,
//! `gearpump::campaign::run::run_campaign`, ...). Each layer is its own crate
//! and names only the ones below it, so Cargo refuses a wrong-way import:
//!
//! * `gearpump-core` (`crates/core`): units, oil, flow laws, geometry, the
//!   design, hydraulics, mechanics, solvers, the model ([`model`], [`design`],
//!   ...); no `unsafe`.
//! * `gearpump-fmi2` (`crates/fmi2`): the generic FMI 2.0 glue, the only
//!   crate with `unsafe`.
//! * `gearpump-campaign` (`crates/campaign`): campaigns ([`campaign`]) and
//!   figures ([`plots`]); on the core.
//! * `gearpump-diagnosis` (`crates/diagnosis`): [`diagnosis`]; on the
//!   campaign and the core.
//! * `gearpump-fmu-models` (`crates/fmu-models`): the FMU models
//!   ([`fmi2`], [`circuit`]); on the glue and the core.
//! * the command line (`gearpump-cli`, the workspace root: clap, indicatif),
//!   on this crate.
//!
//! SI units everywhere inside; conversions at the edges live in [`units`].
#![forbid(unsafe_code)]

pub use gearpump_core::{
    design, flow, geometry, hash, hydraulics, limits, losses, mechanics, model, oil, operating,
    predictor, solver, units, vec2,
};
pub use gearpump_fmi2::export_fmi2;

pub use gearpump_campaign as campaign;
pub use gearpump_campaign::figures as plots;
pub use gearpump_diagnosis as diagnosis;
pub use gearpump_fmu_models::{circuit, fmi2};
