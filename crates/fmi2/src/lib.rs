//! # gearpump-fmi2
//!
//! FMI 2.0 co-simulation export, generic over the model: the only crate of
//! the workspace with `unsafe` code (the C boundary). It knows no pump: the
//! models (`gearpump::fmi2::pump`, `gearpump::fmi2::circuit`) implement its
//! trait.
//!
//! # Layers
//! * [`model`]: the safe trait [`CoSimModel`] a model implements (variable
//!   table, set/get by value reference, initialisation, step, reset, state
//!   save/restore). The model never sees an FMI type or a pointer.
//! * [`instance`]: [`Instance<M>`](instance::Instance), the state machine, the
//!   logger and the one mapping from errors to `fmi2Status`.
//! * [`exports`]: the 34 FMI 2.0 common and co-simulation functions as
//!   generic `extern "C"` functions; [`export_fmi2!`](crate::export_fmi2)
//!   gives them their C names (`fmi2DoStep`, ...) for one model type.
//! * [`xml`]: `modelDescription.xml` and `documentation/index.html` from the
//!   variable table (the zipped `.fmu`: `gearpump::fmi2::package`).
//! * [`types`]: the C types; [`uri`]: `fmuResourceLocation` parsing.
//!
//! # Plugging a model in
//! Implement [`CoSimModel`], add the model to `gearpump::fmi2::package::FmuModel`
//! (the list `fmu-build` and `gearpump fmu` package), and give it a thin
//! cdylib crate under `fmus/` whose whole source is one
//! `gearpump::export_fmi2!(TheModel);` (see [`export_fmi2!`](crate::export_fmi2)).
//! The library itself is an rlib and exports no FMI symbol, so any number of
//! FMUs link it without clashing `fmi2*` names. Two models are packaged:
//! * the gear pump, `gearpump::fmi2::pump::GearPumpFmu` (`fmus/gear-pump`, `GearPump.fmu`;
//!   its co-simulation semantics are documented there);
//! * the automatic-transmission circuit it feeds,
//!   `gearpump::fmi2::circuit::TransmissionCircuitFmu` (`fmus/transmission-circuit`,
//!   `TransmissionCircuit.fmu`).
//!
//! The first-order tank [`example::Tank`] stays as the glue's test model (not
//! packaged).
//!
//! # State machine
//! ```text
//!  fmi2Instantiate ──► Instantiated ──fmi2EnterInitializationMode──► InitializationMode
//!                        ▲   (fmi2SetupExperiment,                     │ (set parameters,
//!                        │    set parameters/inputs)                   │  inputs; get)
//!        fmi2Reset       │                          fmi2ExitInitializationMode
//!      (from any state)  │                                             ▼
//!                        │              ┌──── fmi2DoStep, set inputs / tunable parameters, get
//!                        │              ▼    │
//!                        └───────── StepComplete ──fmi2Terminate──► Terminated (get)
//!
//!  any fmi2Error ──► Error (get, fmi2SetFMUstate to roll back, fmi2Reset, fmi2FreeInstance)
//! ```
//! Every function checks its allowed states first ([`instance::Func::allowed`]);
//! a call in another state returns `fmi2Error` and moves the instance to
//! Error. `fmi2SetFMUstate` restores the state (Instantiated ...
//! StepComplete) in which the FMU state was saved, also from Error.
//! `fmi2SetDebugLogging`, `fmi2Reset`, `fmi2FreeInstance` and the FMU-state
//! functions are allowed in every state; `fmi2GetDirectionalDerivative` from
//! InitializationMode on (not in Instantiated: FMI 2.0 section 4.2.4), the
//! model refusing it while it cannot give the true value. In
//! InitializationMode, reading an output (or a directional derivative) first
//! has the model compute its outputs for the parameters and inputs set so far
//! ([`CoSimModel::initial_outputs`]: GearPump gives the values
//! `fmi2ExitInitializationMode` would, and keeps the work for it). A `fmi2DoStep`
//! that would end beyond a stopTime given to `fmi2SetupExperiment` is
//! `fmi2Error` (relative tolerance [`instance::STOP_TIME_REL_TOL`]).
//! `fmi2SetBoolean` takes only `fmi2True` (1) and `fmi2False` (0).
//!
//! # Status codes returned
//! * `fmi2OK`: done.
//! * `fmi2Warning`: done with a remark in the log (only: an unknown log
//!   category in `fmi2SetDebugLogging`); the instance state is unchanged.
//! * `fmi2Error`: refused or failed, with the reason sent to the logger
//!   (category `logStatusError`): NULL or invalid arguments, a call in the
//!   wrong state, an unknown value reference, setting an output or a fixed
//!   parameter after initialisation, NaN or a value the model refuses, a
//!   non-contiguous `fmi2DoStep` or a step size <= 0, a model error, an
//!   unsupported function, or a panic caught at the boundary. The instance
//!   goes to the Error state. A NULL `fmi2Component` also gives `fmi2Error`
//!   (without a log message: there is no logger to send it to).
//! * `fmi2Discard`: a status query (`fmi2GetStatus`, `fmi2GetRealStatus`,
//!   ...) the slave cannot answer (no asynchronous step), as FMI 2.0.2
//!   sections 2.1.3 and 4.2.3 ask; logged under `logStatusDiscard`, the instance state
//!   unchanged.
//! * `fmi2Fatal`, `fmi2Pending`: never returned (no shared state between
//!   instances, no asynchronous step).
//!
//! `fmi2Instantiate` returns NULL instead of an error, with the reason logged.
//!
//! # Logging
//! The logger is called as `logger(env, instanceName, status, category, "%s",
//! message)`. Errors and warnings are always sent; informational messages
//! (category `logEvents`) only when debug logging is on for that category
//! (`loggingOn` at instantiation, `fmi2SetDebugLogging`).
//!
//! # Safety
//! The safety contract common to all functions, and the one of each
//! function, is documented in [`exports`]. Every function body runs inside
//! `catch_unwind` (a panic becomes `fmi2Error`, or NULL from
//! `fmi2Instantiate`); this relies on `panic = "unwind"` (the default; do not
//! set `panic = "abort"` in a profile used to build the FMU). There is no
//! global or thread-local state and no background thread: instances are
//! independent, may live on different threads, and nothing outlives
//! `fmi2FreeInstance` (importers may unload the library then).

#[doc(hidden)]
pub mod example;
pub mod exports;
pub mod instance;
pub mod model;
pub mod types;
pub mod uri;
pub mod xml;

pub use model::{
    check_model, BaseType, Causality, CoSimModel, DefaultExperiment, Initial, ModelError,
    StateReader, StateWriter, UnitDefinition, Variability, Variable, VariableKind,
};
pub use xml::{documentation_html, model_description_xml};
