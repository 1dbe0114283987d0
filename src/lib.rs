//! # gearpump
//!
//! Lumped-parameter model of external gear pumps after Battarra & Mucchi
//! (2020): helical gears with unequal tooth numbers, pocket-by-pocket pressure
//! build-up, leakages, gear micromotions, journal bearings, mesh force; with
//! population validation, diagnosis and an FMI 2.0 co-simulation unit.
//!
//! SI units everywhere inside; conversions at the edges live in [`units`].
//!
//! # Layers (crates of the workspace)
//! * `gearpump-core` (`crates/core`): the physics and the model, re-exported
//!   here module by module ([`model`], [`design`], ...); no `unsafe`.
//! * `gearpump-fmi2` (`crates/fmi2`): the generic FMI 2.0 glue, the only
//!   crate with `unsafe` (re-exported in [`fmi2`]).
//! * this crate: the FMU models ([`fmi2::pump`], [`fmi2::circuit`] and the
//!   circuit model [`circuit`]), campaigns ([`campaign`]), diagnosis
//!   ([`diagnosis`]), figures ([`plots`]) and the command line.
//!
//! A lower crate cannot name a higher one: Cargo refuses the import.
#![forbid(unsafe_code)]

pub use gearpump_core::{
    design, flow, geometry, hash, hydraulics, limits, losses, mechanics, model, oil, predictor,
    solver, units, vec2,
};
pub use gearpump_fmi2::export_fmi2;

pub mod campaign;
pub mod circuit;
pub mod diagnosis;
pub mod fmi2;
pub mod plots;
