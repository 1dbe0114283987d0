//! # gearpump-fmu-models
//!
//! The FMI 2.0 models of the gearpump project on the generic glue
//! (`gearpump-fmi2`): the gear pump ([`fmi2::pump`]), the transmission
//! circuit it feeds ([`fmi2::circuit`], its model in [`circuit`]), the FMU
//! state's byte form of the LP model and the packaging of `.fmu` files. The
//! thin cdylib crates under `fmus/` export one model each.
#![forbid(unsafe_code)]

pub mod circuit;
pub mod fmi2;
