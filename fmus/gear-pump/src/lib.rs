//! `GearPump.fmu`'s shared library: the FMI 2.0 common and co-simulation
//! functions for the gear pump model ([`gearpump::fmi2::pump::GearPumpFmu`]).
//! Everything else (the model, the glue, the safety contract of each
//! function) lives in the `gearpump` library; `fmu-build` packages this
//! cdylib as `binaries/<platform>/GearPump.so`.
// The crate is named after the modelIdentifier, as the FMU's library must be.
#![allow(non_snake_case)]

gearpump::export_fmi2!(gearpump::fmi2::pump::GearPumpFmu);
