//! The FMI 2.0 models of the project on the generic glue (the crate
//! `gearpump-fmi2`, re-exported here): the gear pump ([`pump`]), the
//! transmission circuit it feeds ([`circuit`]), the FMU state's byte form of
//! the LP model ([`sim_state`]) and the packaging of `.fmu` files
//! ([`package`]).
//!
//! * the gear pump, [`pump::GearPumpFmu`] (`fmus/gear-pump`, `GearPump.fmu`;
//!   its co-simulation semantics are documented there);
//! * the automatic-transmission circuit it feeds,
//!   [`circuit::TransmissionCircuitFmu`] (`fmus/transmission-circuit`,
//!   `TransmissionCircuit.fmu`).

pub use gearpump_fmi2::*;

pub mod circuit;
pub mod package;
pub mod pump;
pub mod sim_state;
pub mod ssp;

pub use package::{
    build_exported_fmu, build_fmu, build_model_fmu, FmuModel, PackageError, Packaged, PumpDesign,
};

/// The gear pump model, packaged as `GearPump.fmu` (its cdylib is
/// `fmus/gear-pump`). Kept under this name for the CLI and the tests that
/// predate the second FMU; [`FmuModel`] lists every packaged model.
pub type ExportedModel = pump::GearPumpFmu;

/// The transmission circuit model, packaged as `TransmissionCircuit.fmu`
/// (its cdylib is `fmus/transmission-circuit`).
pub type CircuitModel = circuit::TransmissionCircuitFmu;
