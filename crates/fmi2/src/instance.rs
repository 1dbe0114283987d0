//! One FMU instance: the state machine, the logger, the error-to-status
//! mapping and the safe implementation of every fmi2 function. Nothing here
//! touches a raw pointer; [`super::exports`] turns the C arguments into
//! slices and strings first.

use std::ffi::{CStr, CString};
use std::fmt;
use std::path::PathBuf;

use super::model::{BaseType, Causality, CoSimModel, ModelError, Variability, Variable};
use super::types::{fmi2Boolean, fmi2CallbackFunctions};
use super::types::{fmi2CallbackLogger, fmi2ComponentEnvironment, fmi2False, fmi2True, Status};

/// The states of an instance (FMI 2.0 co-simulation state machine, without
/// the asynchronous ones). See [`super`] for the transitions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum InstanceState {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated = 1,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode = 2,
    /// Ready for `fmi2DoStep`.
    StepComplete = 4,
    /// After `fmi2Terminate`.
    Terminated = 8,
    /// After any call that returned `fmi2Error`.
    Error = 16,
}

impl InstanceState {
    fn from_u8(b: u8) -> Option<Self> {
        Some(match b {
            1 => InstanceState::Instantiated,
            2 => InstanceState::InitializationMode,
            4 => InstanceState::StepComplete,
            8 => InstanceState::Terminated,
            16 => InstanceState::Error,
            _ => return None,
        })
    }
}

impl fmt::Display for InstanceState {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            InstanceState::Instantiated => "Instantiated",
            InstanceState::InitializationMode => "InitializationMode",
            InstanceState::StepComplete => "StepComplete",
            InstanceState::Terminated => "Terminated",
            InstanceState::Error => "Error",
        })
    }
}

/// A set of [`InstanceState`]s: where a function may be called.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StateMask(u8);

impl StateMask {
    pub const INSTANTIATED: StateMask = StateMask(InstanceState::Instantiated as u8);
    pub const INIT: StateMask = StateMask(InstanceState::InitializationMode as u8);
    pub const STEP_COMPLETE: StateMask = StateMask(InstanceState::StepComplete as u8);
    pub const TERMINATED: StateMask = StateMask(InstanceState::Terminated as u8);
    pub const ERROR: StateMask = StateMask(InstanceState::Error as u8);
    pub const ANY: StateMask = StateMask(31);

    pub const fn or(self, other: StateMask) -> StateMask {
        StateMask(self.0 | other.0)
    }
    pub fn contains(self, s: InstanceState) -> bool {
        self.0 & (s as u8) != 0
    }
}

/// Every fmi2 function that takes an instance, with the states in which it
/// is allowed (FMI 2.0, section 4.2.4; the asynchronous states do not exist
/// here). Unsupported functions are allowed everywhere and then refuse.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    SetDebugLogging,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetReal,
    GetInteger,
    GetBoolean,
    GetString,
    SetReal,
    SetInteger,
    SetBoolean,
    SetString,
    GetFMUstate,
    SetFMUstate,
    FreeFMUstate,
    SerializedFMUstateSize,
    SerializeFMUstate,
    DeSerializeFMUstate,
    GetDirectionalDerivative,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
    GetRealStatus,
    GetIntegerStatus,
    GetBooleanStatus,
    GetStringStatus,
}

impl Func {
    /// The C function name.
    pub fn name(self) -> &'static str {
        use Func::*;
        match self {
            SetDebugLogging => "fmi2SetDebugLogging",
            SetupExperiment => "fmi2SetupExperiment",
            EnterInitializationMode => "fmi2EnterInitializationMode",
            ExitInitializationMode => "fmi2ExitInitializationMode",
            Terminate => "fmi2Terminate",
            Reset => "fmi2Reset",
            GetReal => "fmi2GetReal",
            GetInteger => "fmi2GetInteger",
            GetBoolean => "fmi2GetBoolean",
            GetString => "fmi2GetString",
            SetReal => "fmi2SetReal",
            SetInteger => "fmi2SetInteger",
            SetBoolean => "fmi2SetBoolean",
            SetString => "fmi2SetString",
            GetFMUstate => "fmi2GetFMUstate",
            SetFMUstate => "fmi2SetFMUstate",
            FreeFMUstate => "fmi2FreeFMUstate",
            SerializedFMUstateSize => "fmi2SerializedFMUstateSize",
            SerializeFMUstate => "fmi2SerializeFMUstate",
            DeSerializeFMUstate => "fmi2DeSerializeFMUstate",
            GetDirectionalDerivative => "fmi2GetDirectionalDerivative",
            SetRealInputDerivatives => "fmi2SetRealInputDerivatives",
            GetRealOutputDerivatives => "fmi2GetRealOutputDerivatives",
            DoStep => "fmi2DoStep",
            CancelStep => "fmi2CancelStep",
            GetStatus => "fmi2GetStatus",
            GetRealStatus => "fmi2GetRealStatus",
            GetIntegerStatus => "fmi2GetIntegerStatus",
            GetBooleanStatus => "fmi2GetBooleanStatus",
            GetStringStatus => "fmi2GetStringStatus",
        }
    }

    /// The states in which the function may be called.
    pub fn allowed(self) -> StateMask {
        use Func::*;
        const I: StateMask = StateMask::INSTANTIATED;
        const N: StateMask = StateMask::INIT;
        const S: StateMask = StateMask::STEP_COMPLETE;
        const T: StateMask = StateMask::TERMINATED;
        const E: StateMask = StateMask::ERROR;
        match self {
            SetupExperiment | EnterInitializationMode => I,
            ExitInitializationMode => N,
            Terminate | DoStep => S,
            GetReal | GetInteger | GetBoolean | GetString => N.or(S).or(T).or(E),
            SetReal | SetInteger | SetBoolean | SetString => I.or(N).or(S),
            SetDebugLogging | Reset => StateMask::ANY,
            GetFMUstate
            | SetFMUstate
            | FreeFMUstate
            | SerializedFMUstateSize
            | SerializeFMUstate
            | DeSerializeFMUstate => StateMask::ANY,
            // FMI 2.0 section 4.2.4: not in Instantiated (nothing has been
            // computed yet)
            GetDirectionalDerivative => N.or(S).or(T).or(E),
            SetRealInputDerivatives
            | GetRealOutputDerivatives
            | CancelStep
            | GetStatus
            | GetRealStatus
            | GetIntegerStatus
            | GetBooleanStatus
            | GetStringStatus => StateMask::ANY,
        }
    }
}

/// Everything that can go wrong in a call, and the one place where each is
/// mapped to an `fmi2Status` ([`FmiError::status`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FmiError {
    #[error("{function} is not allowed in state {state}")]
    NotAllowed {
        function: &'static str,
        state: InstanceState,
    },
    #[error("argument {0} is NULL")]
    NullArgument(&'static str),
    #[error("{0}")]
    InvalidArgument(String),
    #[error("unknown {} value reference {vr}", base.as_str())]
    UnknownValueReference { base: BaseType, vr: u32 },
    #[error("variable {name} (vr {vr}) cannot be set: {reason}")]
    NotSettable {
        name: &'static str,
        vr: u32,
        reason: &'static str,
    },
    #[error("variable {name} (vr {vr}): {value} is not a valid value")]
    InvalidValue {
        name: &'static str,
        vr: u32,
        value: String,
    },
    #[error("{function} is not supported: {reason}")]
    Unsupported {
        function: &'static str,
        reason: &'static str,
    },
    /// A status the slave cannot give: `fmi2Discard`, the instance state
    /// unchanged (FMI 2.0.2 sections 2.1.3 and 4.2.3: a slave asked for
    /// status information it cannot retrieve returns fmi2Discard).
    #[error("{function}: status not available: {reason}")]
    StatusUnavailable {
        function: &'static str,
        reason: &'static str,
    },
    #[error("unknown log category {0:?} (ignored)")]
    UnknownCategory(String),
    #[error(transparent)]
    Model(#[from] ModelError),
    /// The model could not compute its outputs in Initialization mode
    /// ([`CoSimModel::initial_outputs`]).
    #[error(
        "the outputs in Initialization mode (the state fmi2ExitInitializationMode \
         starts from, computed for the parameters and inputs set so far): {0}"
    )]
    InitialOutputs(ModelError),
    #[error("internal error (panic): {0}")]
    Panic(String),
}

impl FmiError {
    /// The status returned to the importer.
    pub fn status(&self) -> Status {
        match self {
            FmiError::UnknownCategory(_) => Status::Warning,
            FmiError::StatusUnavailable { .. } => Status::Discard,
            _ => Status::Error,
        }
    }
}

/// Log categories (`LogCategories` in the XML), by index.
pub const LOG_CATEGORIES: &[(&str, &str)] = &[
    (
        "logEvents",
        "Calls and events: instantiation, initialisation, reset, FMU state save/restore",
    ),
    ("logStatusWarning", "Calls that returned fmi2Warning"),
    ("logStatusDiscard", "Calls that returned fmi2Discard"),
    ("logStatusError", "Calls that returned fmi2Error"),
    (
        "logModelWarnings",
        "Warnings of the model on its results (e.g. an operating point outside its range), each sent once",
    ),
    ("logAll", "Everything"),
];
const CAT_EVENTS: usize = 0;
const CAT_MODEL_WARNINGS: usize = 4;
const CAT_ALL: usize = 5;

/// The importer's logger and environment pointer, copied at instantiation.
#[derive(Clone, Copy)]
pub struct Logger {
    func: fmi2CallbackLogger,
    env: fmi2ComponentEnvironment,
}

impl Logger {
    /// The logger of a callback struct.
    pub fn new(functions: &fmi2CallbackFunctions) -> Self {
        Logger {
            func: functions.logger,
            env: functions.componentEnvironment,
        }
    }

    /// Calls `logger(env, instance_name, status, category, "%s", message)`;
    /// NUL bytes in the message are replaced.
    pub fn log(&self, instance_name: &CStr, status: Status, category: &str, message: &str) {
        let Some(func) = self.func else { return };
        let category = to_cstring(category);
        let message = to_cstring(message);
        // SAFETY: the importer promised (fmi2Instantiate's contract) that the
        // logger is a valid function of the fmi2CallbackLogger type; every
        // pointer passed is a valid NUL-terminated string that lives for the
        // call, and the format "%s" matches the one char* argument.
        unsafe {
            func(
                self.env,
                instance_name.as_ptr(),
                status.raw(),
                category.as_ptr(),
                c"%s".as_ptr(),
                message.as_ptr(),
            );
        }
    }
}

/// A C string of `s`, with NUL bytes replaced by spaces.
pub fn to_cstring(s: &str) -> CString {
    CString::new(s.replace('\0', " ")).unwrap_or_default()
}

/// A step may end beyond a defined stopTime by this much relative to
/// max(|stopTime|, h) (the rounding of an importer's `t += h`).
pub const STOP_TIME_REL_TOL: f64 = 1e-12;

/// The layout tag of a serialized FMU state (format version 1).
const STATE_TAG: &[u8; 8] = b"GPFMI2S1";

/// One FMU instance. Created by `fmi2Instantiate`, owned by the importer
/// through the `fmi2Component` pointer until `fmi2FreeInstance`.
pub struct Instance<M: CoSimModel> {
    magic: u64,
    name: CString,
    logger: Logger,
    categories: [bool; LOG_CATEGORIES.len()],
    state: InstanceState,
    /// The expected next communication point, s.
    time: f64,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    resources: PathBuf,
    model: M,
}

/// A per-model-type tag at the start of every instance, checked on every
/// call: it catches a pointer that is not one of this library's instances
/// (a freed one, an FMU state passed as a component, ...) in most cases.
pub fn instance_magic<M: CoSimModel>() -> u64 {
    // FNV-1a of the GUID, mixed with "FMI2INST".
    let mut h = gearpump_core::hash::Fnv1a::new();
    h.write(M::GUID.as_bytes());
    h.finish().0 ^ 0x464d_4932_494e_5354
}

impl<M: CoSimModel> Instance<M> {
    /// The safe part of `fmi2Instantiate`: everything after the pointers
    /// were read. `Err` carries the reason, already suitable for the log.
    pub fn new(
        name: &str,
        fmu_type: super::types::fmi2Type,
        guid: &str,
        resource_location: &str,
        logger: Logger,
        logging_on: bool,
    ) -> Result<Self, String> {
        if name.trim().is_empty() {
            return Err("instanceName is empty".into());
        }
        if fmu_type != super::types::fmi2CoSimulation {
            return Err(format!(
                "fmuType {fmu_type} requested, but {} supports only co-simulation \
                 (fmi2CoSimulation = 1)",
                M::MODEL_IDENTIFIER
            ));
        }
        let resources = super::uri::file_uri_to_path(resource_location)
            .map_err(|e| format!("fmuResourceLocation: {e}"))?;
        if !resources.is_dir() {
            return Err(format!(
                "fmuResourceLocation: the resources folder {} does not exist",
                resources.display()
            ));
        }
        let expected = M::guid_for_resources(&resources);
        if guid != expected {
            return Err(format!(
                "GUID mismatch: the importer expects {guid:?}, this binary with these \
                 resources is {expected:?} (modelDescription.xml, binary and resources \
                 come from different builds or designs)"
            ));
        }
        let name = to_cstring(name);
        let categories = [logging_on; LOG_CATEGORIES.len()];
        let info = |msg: &str| {
            if logging_on {
                logger.log(&name, Status::Ok, LOG_CATEGORIES[CAT_EVENTS].0, msg);
            }
        };
        let model = M::instantiate(&resources, &info).map_err(|e| e.to_string())?;
        info(&format!(
            "instantiated {} (resources {})",
            M::MODEL_IDENTIFIER,
            resources.display()
        ));
        Ok(Instance {
            magic: instance_magic::<M>(),
            name,
            logger,
            categories,
            state: InstanceState::Instantiated,
            time: 0.0,
            start_time: 0.0,
            stop_time: None,
            tolerance: None,
            resources,
            model,
        })
    }

    /// Whether the tag is intact (see [`instance_magic`]).
    pub fn magic_ok(&self) -> bool {
        self.magic == instance_magic::<M>()
    }

    /// Clears the tag before the instance is dropped.
    pub fn invalidate(&mut self) {
        self.magic = 0;
    }

    pub fn state(&self) -> InstanceState {
        self.state
    }

    /// The next expected communication point, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The model (for tests and diagnostics).
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The resources folder given at instantiation.
    pub fn resources(&self) -> &std::path::Path {
        &self.resources
    }

    fn enabled(&self, category: usize) -> bool {
        self.categories[category] || self.categories[CAT_ALL]
    }

    /// An informational message, sent when its category is enabled.
    pub fn log_event(&self, message: &str) {
        if self.enabled(CAT_EVENTS) {
            self.logger.log(
                &self.name,
                Status::Ok,
                LOG_CATEGORIES[CAT_EVENTS].0,
                message,
            );
        }
    }

    /// The model's warnings ([`CoSimModel::take_warnings`]), sent with status
    /// fmi2Warning whatever the debug-logging settings (as every warning).
    fn send_model_warnings(&mut self) {
        for w in self.model.take_warnings() {
            self.logger.log(
                &self.name,
                Status::Warning,
                LOG_CATEGORIES[CAT_MODEL_WARNINGS].0,
                &w,
            );
        }
    }

    /// Checks that `func` may be called now.
    pub fn check_state(&self, func: Func) -> Result<(), FmiError> {
        if func.allowed().contains(self.state) {
            Ok(())
        } else {
            Err(FmiError::NotAllowed {
                function: func.name(),
                state: self.state,
            })
        }
    }

    /// The one mapping from a call's result to its status: logs the error
    /// (errors and warnings are always sent to the logger, whatever the
    /// debug-logging settings), moves the instance to the Error state on
    /// `fmi2Error`, and returns the status.
    pub fn finish(&mut self, func: Func, result: Result<(), FmiError>) -> Status {
        match result {
            Ok(()) => Status::Ok,
            Err(e) => {
                let status = e.status();
                let category = match status {
                    Status::Warning => "logStatusWarning",
                    Status::Discard => "logStatusDiscard",
                    _ => "logStatusError",
                };
                let message = format!("{}: {e}", func.name());
                self.logger.log(&self.name, status, category, &message);
                if status >= Status::Error {
                    self.state = InstanceState::Error;
                }
                status
            }
        }
    }

    /// `fmi2SetDebugLogging`: `categories` empty = all categories.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Result<(), FmiError> {
        if categories.is_empty() {
            self.categories = [on; LOG_CATEGORIES.len()];
            return Ok(());
        }
        let mut unknown = Vec::new();
        for c in categories {
            match LOG_CATEGORIES.iter().position(|(n, _)| n == c) {
                Some(i) => self.categories[i] = on,
                None => unknown.push(*c),
            }
        }
        if unknown.is_empty() {
            Ok(())
        } else {
            Err(FmiError::UnknownCategory(unknown.join(", ")))
        }
    }

    /// `fmi2SetupExperiment`.
    pub fn setup_experiment(
        &mut self,
        tolerance: Option<f64>,
        start_time: f64,
        stop_time: Option<f64>,
    ) -> Result<(), FmiError> {
        if !start_time.is_finite() {
            return Err(FmiError::InvalidArgument(format!(
                "startTime = {start_time} is not finite"
            )));
        }
        if let Some(stop) = stop_time {
            if !(stop.is_finite() && stop >= start_time) {
                return Err(FmiError::InvalidArgument(format!(
                    "stopTime = {stop} is not a finite time >= startTime = {start_time}"
                )));
            }
        }
        if let Some(tol) = tolerance {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(FmiError::InvalidArgument(format!(
                    "tolerance = {tol} is not > 0"
                )));
            }
        }
        self.model
            .setup_experiment(start_time, stop_time, tolerance)?;
        self.start_time = start_time;
        self.time = start_time;
        self.stop_time = stop_time;
        self.tolerance = tolerance;
        Ok(())
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Result<(), FmiError> {
        self.time = self.start_time;
        self.state = InstanceState::InitializationMode;
        self.log_event("entered initialization mode");
        Ok(())
    }

    /// `fmi2ExitInitializationMode`.
    pub fn exit_initialization_mode(&mut self) -> Result<(), FmiError> {
        self.model.exit_initialization()?;
        self.send_model_warnings();
        self.state = InstanceState::StepComplete;
        self.log_event(&format!("initialized at t = {} s", self.time));
        Ok(())
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Result<(), FmiError> {
        self.state = InstanceState::Terminated;
        self.log_event(&format!("terminated at t = {} s", self.time));
        Ok(())
    }

    /// `fmi2Reset`: back to Instantiated with the start values.
    pub fn reset(&mut self) -> Result<(), FmiError> {
        self.model.reset()?;
        self.state = InstanceState::Instantiated;
        self.time = 0.0;
        self.start_time = 0.0;
        self.stop_time = None;
        self.tolerance = None;
        self.log_event("reset");
        Ok(())
    }

    fn variable(&self, vr: u32, base: BaseType) -> Result<&'static Variable, FmiError> {
        M::variables()
            .iter()
            .find(|v| v.value_reference == vr && v.base_type() == base)
            .ok_or(FmiError::UnknownValueReference { base, vr })
    }

    /// The variable `vr` of type `base` if it may be set now: inputs always
    /// (before termination), parameters until the end of initialisation,
    /// tunable parameters also between steps, outputs and locals never.
    fn settable(&self, vr: u32, base: BaseType) -> Result<&'static Variable, FmiError> {
        let v = self.variable(vr, base)?;
        let refuse = |reason| {
            Err(FmiError::NotSettable {
                name: v.name,
                vr,
                reason,
            })
        };
        match (v.causality, self.state) {
            (Causality::Input, _) => Ok(v),
            (Causality::Parameter, InstanceState::Instantiated)
            | (Causality::Parameter, InstanceState::InitializationMode) => Ok(v),
            (Causality::Parameter, _) if v.variability == Variability::Tunable => Ok(v),
            (Causality::Parameter, _) => {
                refuse("a fixed parameter can only be set before fmi2ExitInitializationMode")
            }
            (Causality::Output, _) => refuse("it is an output"),
            (Causality::Local, _) => refuse("it is a local variable"),
        }
    }

    /// In Initialization mode, when `vr` names an output of type `base`
    /// (or `vr` is `None`: a directional derivative), the model computes
    /// its outputs for the parameters and inputs set so far
    /// ([`CoSimModel::initial_outputs`]) and its warnings are sent; in any
    /// other state, or for parameters and inputs only, nothing is done.
    fn initial_outputs(&mut self, vr: Option<(&[u32], BaseType)>) -> Result<(), FmiError> {
        if self.state != InstanceState::InitializationMode {
            return Ok(());
        }
        if let Some((vr, base)) = vr {
            let output = |r: &u32| {
                M::variables().iter().any(|v| {
                    v.value_reference == *r
                        && v.base_type() == base
                        && v.causality == Causality::Output
                })
            };
            if !vr.iter().any(output) {
                return Ok(());
            }
        }
        let result = self.model.initial_outputs();
        self.send_model_warnings();
        result.map_err(FmiError::InitialOutputs)
    }

    /// `fmi2SetReal` (`vr` and `value` have the same length).
    pub fn set_real(&mut self, vr: &[u32], value: &[f64]) -> Result<(), FmiError> {
        for (&r, &x) in vr.iter().zip(value) {
            let v = self.settable(r, BaseType::Real)?;
            if x.is_nan() {
                return Err(FmiError::InvalidValue {
                    name: v.name,
                    vr: r,
                    value: "NaN".into(),
                });
            }
            self.model.set_real(r, x)?;
        }
        Ok(())
    }

    /// `fmi2GetReal` (in Initialization mode, an output's value is the one
    /// `fmi2ExitInitializationMode` would give: [`CoSimModel::initial_outputs`]).
    pub fn get_real(&mut self, vr: &[u32], value: &mut [f64]) -> Result<(), FmiError> {
        self.initial_outputs(Some((vr, BaseType::Real)))?;
        for (&r, x) in vr.iter().zip(value.iter_mut()) {
            self.variable(r, BaseType::Real)?;
            *x = self.model.get_real(r)?;
        }
        Ok(())
    }

    /// `fmi2GetDirectionalDerivative`: `dv_unknown[i] = Σ_j ∂unknown_i /
    /// ∂known_j dv_known[j]`, each unknown a Real output and each known a
    /// Real input it depends on ([`CoSimModel::output_dependencies`]). In
    /// Initialization mode the model first computes its outputs
    /// ([`CoSimModel::initial_outputs`]), so the derivatives are taken at
    /// the state `fmi2ExitInitializationMode` would start from.
    pub fn directional_derivative(
        &mut self,
        unknown: &[u32],
        known: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), FmiError> {
        for &k in known {
            let v = self.variable(k, BaseType::Real)?;
            if v.causality != Causality::Input {
                return Err(FmiError::InvalidArgument(format!(
                    "known {} (vr {k}) is not an input",
                    v.name
                )));
            }
        }
        if let Some((j, x)) = dv_known.iter().enumerate().find(|(_, x)| !x.is_finite()) {
            return Err(FmiError::InvalidArgument(format!(
                "dvKnown[{j}] = {x} is not finite"
            )));
        }
        let mut result = vec![0.0; unknown.len()];
        let mut prepared = false;
        for (&u, r) in unknown.iter().zip(result.iter_mut()) {
            let v = self.variable(u, BaseType::Real)?;
            let deps = M::output_dependencies(u).filter(|_| v.causality == Causality::Output);
            let Some(deps) = deps else {
                return Err(FmiError::InvalidArgument(format!(
                    "unknown {} (vr {u}): no derivatives (not an output with declared dependencies)",
                    v.name
                )));
            };
            for (&k, &dv) in known.iter().zip(dv_known) {
                if deps.contains(&k) && dv != 0.0 {
                    if !std::mem::replace(&mut prepared, true) {
                        self.initial_outputs(None)?;
                    }
                    *r += self.model.partial_derivative(u, k)? * dv;
                }
            }
        }
        dv_unknown.copy_from_slice(&result);
        Ok(())
    }

    /// `fmi2SetBoolean`: each value must be `fmi2True` (1) or `fmi2False`
    /// (0), the two values FMI 2.0 defines (section 2.1.2); any other int
    /// is refused rather than read as true (an uninitialised or
    /// wrongly typed value more likely than an intended true).
    pub fn set_boolean(&mut self, vr: &[u32], value: &[fmi2Boolean]) -> Result<(), FmiError> {
        for (&r, &x) in vr.iter().zip(value) {
            let v = self.settable(r, BaseType::Boolean)?;
            if x != fmi2True && x != fmi2False {
                return Err(FmiError::InvalidValue {
                    name: v.name,
                    vr: r,
                    value: format!(
                        "{x} (an fmi2Boolean is fmi2True = {fmi2True} or fmi2False = {fmi2False})"
                    ),
                });
            }
            self.model.set_boolean(r, x == fmi2True)?;
        }
        Ok(())
    }

    /// `fmi2GetBoolean` (outputs in Initialization mode as `fmi2GetReal`).
    pub fn get_boolean(&mut self, vr: &[u32], value: &mut [fmi2Boolean]) -> Result<(), FmiError> {
        self.initial_outputs(Some((vr, BaseType::Boolean)))?;
        for (&r, x) in vr.iter().zip(value.iter_mut()) {
            self.variable(r, BaseType::Boolean)?;
            *x = if self.model.get_boolean(r)? {
                fmi2True
            } else {
                fmi2False
            };
        }
        Ok(())
    }

    /// `fmi2SetInteger`.
    pub fn set_integer(&mut self, vr: &[u32], value: &[i32]) -> Result<(), FmiError> {
        for (&r, &x) in vr.iter().zip(value) {
            self.settable(r, BaseType::Integer)?;
            self.model.set_integer(r, x)?;
        }
        Ok(())
    }

    /// `fmi2GetInteger` (outputs in Initialization mode as `fmi2GetReal`).
    pub fn get_integer(&mut self, vr: &[u32], value: &mut [i32]) -> Result<(), FmiError> {
        self.initial_outputs(Some((vr, BaseType::Integer)))?;
        for (&r, x) in vr.iter().zip(value.iter_mut()) {
            self.variable(r, BaseType::Integer)?;
            *x = self.model.get_integer(r)?;
        }
        Ok(())
    }

    /// `fmi2Get/SetString`: the models have no such
    /// variables, so any value reference is unknown (an empty call is fine).
    pub fn no_variables_of(&self, base: BaseType, vr: &[u32]) -> Result<(), FmiError> {
        match vr.first() {
            None => Ok(()),
            Some(&vr) => Err(FmiError::UnknownValueReference { base, vr }),
        }
    }

    /// `fmi2DoStep`: `t` must be the end of the previous step (relative
    /// tolerance 1e-8 of max(|t|, h), at most h/10), `h > 0`, and with a
    /// stopTime defined in `fmi2SetupExperiment` the step must not end
    /// beyond it (FMI 2.0 section 4.2.1: computing past stopTime is
    /// fmi2Error; [`STOP_TIME_REL_TOL`] allows for the importer's rounding).
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<(), FmiError> {
        if !(h.is_finite() && h > 0.0) {
            return Err(FmiError::InvalidArgument(format!(
                "communicationStepSize = {h} must be > 0"
            )));
        }
        let tol = (1e-8 * self.time.abs().max(h)).min(0.1 * h);
        if !t.is_finite() || (t - self.time).abs() > tol {
            return Err(FmiError::InvalidArgument(format!(
                "currentCommunicationPoint = {t} s, but the FMU is at t = {} s \
                 (steps must be contiguous)",
                self.time
            )));
        }
        if let Some(stop) = self.stop_time {
            let end = t + h;
            if end > stop + STOP_TIME_REL_TOL * stop.abs().max(h) {
                return Err(FmiError::InvalidArgument(format!(
                    "currentCommunicationPoint + communicationStepSize = {t} + {h} = {end} s \
                     is beyond stopTime = {stop} s (fmi2SetupExperiment with \
                     stopTimeDefined = fmi2True)"
                )));
            }
        }
        self.model.do_step(t, h)?;
        self.send_model_warnings();
        self.time = t + h;
        Ok(())
    }

    /// `fmi2GetFMUstate`: the complete state as self-contained bytes.
    pub fn save(&self) -> Vec<u8> {
        let mut w = super::model::StateWriter::new(STATE_TAG);
        w.bytes(M::GUID.as_bytes())
            .u64(u64::from(self.state as u8))
            .f64(self.time)
            .f64(self.start_time)
            .bool(self.stop_time.is_some())
            .f64(self.stop_time.unwrap_or(0.0))
            .bool(self.tolerance.is_some())
            .f64(self.tolerance.unwrap_or(0.0))
            .bytes(&self.model.save_state());
        w.finish()
    }

    /// Reads the glue part of a saved state (checks it belongs to this
    /// model); returns the parsed fields and the model bytes.
    fn parse_saved(bytes: &[u8]) -> Result<SavedHeader<'_>, FmiError> {
        let bad = |e: ModelError| {
            FmiError::InvalidArgument(format!("not an FMU state of this model: {e}"))
        };
        let mut r = super::model::StateReader::new(bytes, STATE_TAG).map_err(bad)?;
        let guid = r.bytes().map_err(bad)?;
        if guid != M::GUID.as_bytes() {
            return Err(FmiError::InvalidArgument(format!(
                "the FMU state belongs to GUID {:?}, not {:?}",
                String::from_utf8_lossy(guid),
                M::GUID
            )));
        }
        let state = r.u64().map_err(bad)?;
        let state = u8::try_from(state)
            .ok()
            .and_then(InstanceState::from_u8)
            .ok_or_else(|| FmiError::InvalidArgument(format!("invalid instance state {state}")))?;
        let time = r.f64().map_err(bad)?;
        let start_time = r.f64().map_err(bad)?;
        let has_stop = r.bool().map_err(bad)?;
        let stop = r.f64().map_err(bad)?;
        let has_tol = r.bool().map_err(bad)?;
        let tol = r.f64().map_err(bad)?;
        let model = r.bytes().map_err(bad)?;
        r.finish().map_err(bad)?;
        Ok(SavedHeader {
            state,
            time,
            start_time,
            stop_time: has_stop.then_some(stop),
            tolerance: has_tol.then_some(tol),
            model,
        })
    }

    /// Checks that `bytes` are a state of this model
    /// (`fmi2DeSerializeFMUstate`).
    pub fn check_saved(bytes: &[u8]) -> Result<(), FmiError> {
        Self::parse_saved(bytes).map(|_| ())
    }

    /// `fmi2SetFMUstate`: restores model, time and instance state.
    pub fn restore(&mut self, bytes: &[u8]) -> Result<(), FmiError> {
        let h = Self::parse_saved(bytes)?;
        self.model.restore_state(h.model)?;
        self.state = h.state;
        self.time = h.time;
        self.start_time = h.start_time;
        self.stop_time = h.stop_time;
        self.tolerance = h.tolerance;
        self.log_event(&format!(
            "FMU state restored (t = {} s, state {})",
            self.time, self.state
        ));
        Ok(())
    }
}

struct SavedHeader<'a> {
    state: InstanceState,
    time: f64,
    start_time: f64,
    stop_time: Option<f64>,
    tolerance: Option<f64>,
    model: &'a [u8],
}
