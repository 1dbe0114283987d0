//! The FMI 2.0 C types (`fmi2TypesPlatform.h`, `fmi2FunctionTypes.h`),
//! declared with plain C types, named as in the standard.
//!
//! Enumerations that the importer passes *in* (`fmi2Type`, `fmi2StatusKind`)
//! are plain `c_int`s, not Rust enums: a C caller can pass any integer and a
//! Rust enum with an undeclared discriminant would be undefined behaviour.
#![allow(non_camel_case_types, non_upper_case_globals, non_snake_case)]

use std::ffi::{c_char, c_double, c_int, c_uint, c_void};

/// Opaque pointer to one FMU instance (an `Instance<M>` behind the scenes).
pub type fmi2Component = *mut c_void;
/// Opaque pointer owned by the importer, handed back to its callbacks.
pub type fmi2ComponentEnvironment = *mut c_void;
/// Opaque pointer to a saved FMU state.
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = c_uint;
pub type fmi2Real = c_double;
pub type fmi2Integer = c_int;
/// `fmi2True` = 1, `fmi2False` = 0; any non-zero value is read as true.
pub type fmi2Boolean = c_int;
pub type fmi2Char = c_char;
pub type fmi2String = *const fmi2Char;
pub type fmi2Byte = c_char;

pub const fmi2True: fmi2Boolean = 1;
pub const fmi2False: fmi2Boolean = 0;

/// `fmi2Status` as returned to C.
pub type fmi2Status = c_int;
/// `fmi2Type`: `fmi2ModelExchange` = 0, `fmi2CoSimulation` = 1.
pub type fmi2Type = c_int;
pub const fmi2ModelExchange: fmi2Type = 0;
pub const fmi2CoSimulation: fmi2Type = 1;
/// `fmi2StatusKind`: `fmi2DoStepStatus` = 0, `fmi2PendingStatus`,
/// `fmi2LastSuccessfulTime`, `fmi2Terminated`.
pub type fmi2StatusKind = c_int;

/// The status codes of `fmi2Status`, as a Rust enum for use inside the glue.
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Status {
    /// All well.
    Ok = 0,
    /// Something is not quite right (an unknown log category, ...), but the
    /// computation can go on. The instance state is unchanged.
    Warning = 1,
    /// Not used by this FMU (it would mean "retry the step smaller").
    Discard = 2,
    /// The call failed: the instance is now in the Error state; only
    /// getters, `fmi2SetFMUstate` (to roll back), `fmi2Reset` and
    /// `fmi2FreeInstance` are accepted.
    Error = 3,
    /// Not returned by this FMU: there is no state shared between instances
    /// that an error could corrupt.
    Fatal = 4,
    /// Not used (no asynchronous `fmi2DoStep`).
    Pending = 5,
}

impl Status {
    /// The C value.
    pub fn raw(self) -> fmi2Status {
        self as fmi2Status
    }

    /// The status for a C value, `None` for an undeclared one.
    pub fn from_raw(raw: fmi2Status) -> Option<Status> {
        Some(match raw {
            0 => Status::Ok,
            1 => Status::Warning,
            2 => Status::Discard,
            3 => Status::Error,
            4 => Status::Fatal,
            5 => Status::Pending,
            _ => return None,
        })
    }
}

/// `fmi2CallbackLogger`: a C variadic function
/// `(env, instanceName, status, category, message_format, ...)`.
/// This FMU always calls it with the format `"%s"` and the message as the one
/// variadic argument, so a message containing `%` is printed verbatim.
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
>;
/// `fmi2CallbackAllocateMemory` (never called: `canNotUseMemoryManagementFunctions="true"`).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// `fmi2CallbackFreeMemory` (never called).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// `fmi2StepFinished` (never called: no asynchronous `fmi2DoStep`).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// `fmi2CallbackFunctions`, passed by pointer to `fmi2Instantiate`. The FMU
/// copies the logger and the environment pointer; the struct itself need not
/// outlive the call.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct fmi2CallbackFunctions {
    pub logger: fmi2CallbackLogger,
    pub allocateMemory: fmi2CallbackAllocateMemory,
    pub freeMemory: fmi2CallbackFreeMemory,
    pub stepFinished: fmi2StepFinished,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// `fmi2TypesPlatform` returned by `fmi2GetTypesPlatform`.
pub const TYPES_PLATFORM: &std::ffi::CStr = c"default";
/// `fmi2Version` returned by `fmi2GetVersion`.
pub const VERSION: &std::ffi::CStr = c"2.0";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_round_trip_and_layout() {
        for raw in 0..6 {
            assert_eq!(Status::from_raw(raw).map(Status::raw), Some(raw));
        }
        assert_eq!(Status::from_raw(6), None);
        // Five pointer-sized fields, as in fmi2FunctionTypes.h.
        assert_eq!(
            std::mem::size_of::<fmi2CallbackFunctions>(),
            5 * std::mem::size_of::<*const c_void>()
        );
    }
}
