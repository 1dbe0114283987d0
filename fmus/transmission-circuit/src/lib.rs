//! `TransmissionCircuit.fmu`'s shared library: the FMI 2.0 common and
//! co-simulation functions for the automatic-transmission circuit model
//! ([`gearpump::fmi2::circuit::TransmissionCircuitFmu`]). Everything else
//! lives in the `gearpump` library; `fmu-build` packages this cdylib as
//! `binaries/<platform>/TransmissionCircuit.so`.
// The crate is named after the modelIdentifier, as the FMU's library must be.
#![allow(non_snake_case)]

gearpump::export_fmi2!(gearpump::fmi2::circuit::TransmissionCircuitFmu);
