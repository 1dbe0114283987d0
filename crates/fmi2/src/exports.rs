//! The FMI 2.0 common and co-simulation functions, generic over the model
//! type, as `extern "C"` functions; [`crate::export_fmi2!`] gives them their
//! C names for one model type.
//!
//! Every function has the same shape (after rustls-ffi and the
//! Reference-FMUs): panic boundary -> instance pointer check -> allowed-state
//! check -> pointer arguments turned into slices/strings by null-checking
//! helpers -> a safe call on [`Instance`] -> [`Instance::finish`], the one
//! mapping from `Result` to `fmi2Status`, which logs the message and moves
//! the instance to the Error state on `fmi2Error`.
//!
//! # Safety contract (common to every function taking `c`)
//! * `c` is NULL or a pointer returned by `fmi2Instantiate` of this library
//!   and not yet passed to `fmi2FreeInstance`. A NULL `c` gives `fmi2Error`
//!   (nothing can be logged without an instance); a pointer that is not an
//!   instance is detected by a tag in most cases, but not always.
//! * Calls on one instance are not concurrent (FMI 2.0 does not require an
//!   instance to be thread-safe). Different instances may be used from
//!   different threads at the same time: they share nothing.
//! * Array arguments point to at least the stated number of elements
//!   (NULL is accepted when that number is 0) and do not overlap.
//! * The logger callback must not call back into the same instance.
//!
//! The per-function notes below add what is specific.

use std::ffi::{c_char, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::instance::{instance_magic, FmiError, Func, Instance, Logger};
use super::model::{BaseType, CoSimModel};
use super::types::*;

// ---------------------------------------------------------------------------
// Null-checking helpers: after these, each function body is safe Rust.

/// `n` elements at `p` (`p` may be NULL if `n` is 0).
///
/// # Safety
/// If non-NULL, `p` points to `n` initialised elements valid for `'a`.
unsafe fn in_slice<'a, T>(p: *const T, n: usize, what: &'static str) -> Result<&'a [T], FmiError> {
    if n == 0 {
        return Ok(&[]);
    }
    check_array(p, n, what)?;
    // SAFETY: non-NULL, aligned, size checked; validity is the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts(p, n) })
}

/// `n` writable elements at `p` (`p` may be NULL if `n` is 0).
///
/// # Safety
/// If non-NULL, `p` points to `n` elements writable for `'a`, aliased by
/// nothing else.
unsafe fn out_slice<'a, T>(
    p: *mut T,
    n: usize,
    what: &'static str,
) -> Result<&'a mut [T], FmiError> {
    if n == 0 {
        return Ok(&mut []);
    }
    check_array(p, n, what)?;
    // SAFETY: as for in_slice, plus exclusivity from the caller's contract.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
}

fn check_array<T>(p: *const T, n: usize, what: &'static str) -> Result<(), FmiError> {
    if p.is_null() {
        return Err(FmiError::NullArgument(what));
    }
    if !p.is_aligned() {
        return Err(FmiError::InvalidArgument(format!("{what} is misaligned")));
    }
    if n > isize::MAX as usize / std::mem::size_of::<T>().max(1) {
        return Err(FmiError::InvalidArgument(format!(
            "{what}: {n} elements is too many"
        )));
    }
    Ok(())
}

/// The one output value at `p`.
///
/// # Safety
/// If non-NULL, `p` is valid for writes for `'a`.
unsafe fn out_ref<'a, T>(p: *mut T, what: &'static str) -> Result<&'a mut T, FmiError> {
    check_array(p, 1, what)?;
    // SAFETY: non-NULL and aligned; validity is the caller's contract.
    Ok(unsafe { &mut *p })
}

/// The UTF-8 string at `p`.
///
/// # Safety
/// If non-NULL, `p` is a NUL-terminated string valid for `'a`.
unsafe fn in_str<'a>(p: *const c_char, what: &'static str) -> Result<&'a str, FmiError> {
    if p.is_null() {
        return Err(FmiError::NullArgument(what));
    }
    // SAFETY: non-NULL, NUL-terminated by the caller's contract.
    unsafe { CStr::from_ptr(p) }
        .to_str()
        .map_err(|_| FmiError::InvalidArgument(format!("{what} is not UTF-8")))
}

/// The instance behind `c`, if `c` is non-NULL and carries the tag.
///
/// # Safety
/// `c` is NULL or a live instance of this model type (module contract).
unsafe fn instance_mut<'a, M: CoSimModel>(c: fmi2Component) -> Option<&'a mut Instance<M>> {
    let p = c.cast::<Instance<M>>();
    if p.is_null() || !p.is_aligned() {
        return None;
    }
    // SAFETY: a live instance by the module contract; calls are not concurrent.
    let inst = unsafe { &mut *p };
    inst.magic_ok().then_some(inst)
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic payload".to_string()
    }
}

/// The common frame of every function taking an instance: panic boundary,
/// instance check, allowed-state check, `body`, status mapping.
///
/// # Safety
/// `c` as in the module contract; `body` may dereference only pointers that
/// the calling function's contract covers.
unsafe fn guarded<M: CoSimModel>(
    c: fmi2Component,
    func: Func,
    body: impl FnOnce(&mut Instance<M>) -> Result<(), FmiError>,
) -> fmi2Status {
    catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: forwarded module contract.
        let Some(inst) = (unsafe { instance_mut::<M>(c) }) else {
            return Status::Error;
        };
        let result = inst.check_state(func).and_then(|()| {
            catch_unwind(AssertUnwindSafe(|| body(&mut *inst)))
                .unwrap_or_else(|p| Err(FmiError::Panic(panic_message(&*p))))
        });
        inst.finish(func, result)
    }))
    .unwrap_or(Status::Error)
    .raw()
}

/// A status query the slave cannot answer: it has no asynchronous step, so
/// there is no pending status, last successful time or termination request
/// to report. FMI 2.0.2 sections 2.1.3 and 4.2.3 have such a query return fmi2Discard
/// (the importer decides what follows) rather than fmi2Error, and the
/// instance stays usable.
fn status_unavailable(function: Func) -> Result<(), FmiError> {
    Err(FmiError::StatusUnavailable {
        function: function.name(),
        reason: NOT_ASYNC,
    })
}

/// Refusal of an unsupported function.
fn unsupported(function: Func, reason: &'static str) -> Result<(), FmiError> {
    Err(FmiError::Unsupported {
        function: function.name(),
        reason,
    })
}

// ---------------------------------------------------------------------------
// FMU state objects.

/// What an `fmi2FMUstate` points to: the serialized state (so get, set and
/// serialize share one self-contained representation).
struct StateBox {
    magic: u64,
    bytes: Vec<u8>,
}

fn state_magic<M: CoSimModel>() -> u64 {
    instance_magic::<M>() ^ 0x5354_4154_4542_4f58
}

/// The state object at `s`.
///
/// # Safety
/// `s` is NULL or an `fmi2FMUstate` made by this library for model `M` and
/// not yet freed.
unsafe fn state_mut<'a, M: CoSimModel>(
    s: fmi2FMUstate,
    what: &'static str,
) -> Result<&'a mut StateBox, FmiError> {
    let p = s.cast::<StateBox>();
    if p.is_null() {
        return Err(FmiError::NullArgument(what));
    }
    if !p.is_aligned() {
        return Err(FmiError::InvalidArgument(format!("{what} is misaligned")));
    }
    // SAFETY: by the contract above.
    let b = unsafe { &mut *p };
    if b.magic != state_magic::<M>() {
        return Err(FmiError::InvalidArgument(format!(
            "{what} is not an FMU state of this model"
        )));
    }
    Ok(b)
}

// ---------------------------------------------------------------------------
// Inquire version numbers.

/// `fmi2GetTypesPlatform`: `"default"`. Safe: no arguments; the string is static.
pub extern "C" fn get_types_platform() -> *const c_char {
    TYPES_PLATFORM.as_ptr()
}

/// `fmi2GetVersion`: `"2.0"`. Safe: no arguments; the string is static.
pub extern "C" fn get_version() -> *const c_char {
    VERSION.as_ptr()
}

/// `fmi2SetDebugLogging`: `nCategories = 0` switches every category;
/// otherwise only the named ones (an unknown name gives `fmi2Warning`).
/// Errors and warnings are always logged.
///
/// # Safety
/// Module contract; `categories` holds `n` NUL-terminated strings.
pub unsafe extern "C" fn set_debug_logging<M: CoSimModel>(
    c: fmi2Component,
    logging_on: fmi2Boolean,
    n: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetDebugLogging, |inst| {
            let ptrs = in_slice(categories, n, "categories")?;
            let names = ptrs
                .iter()
                .map(|&p| in_str(p, "categories[i]"))
                .collect::<Result<Vec<_>, _>>()?;
            inst.set_debug_logging(logging_on != fmi2False, &names)
        })
    }
}

// ---------------------------------------------------------------------------
// Creation and destruction.

/// `fmi2Instantiate`: a new instance, or NULL with the reason logged through
/// `functions->logger` (NULL `functions`, empty name, model exchange asked,
/// GUID mismatch, bad `fmuResourceLocation`, missing resources folder, a
/// model error).
///
/// # Safety
/// Strings are NULL or NUL-terminated; `functions` is NULL or points to a
/// valid `fmi2CallbackFunctions` whose logger (if not NULL) stays callable
/// and whose `componentEnvironment` stays valid until `fmi2FreeInstance`.
pub unsafe extern "C" fn instantiate<M: CoSimModel>(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    catch_unwind(AssertUnwindSafe(|| {
        if functions.is_null() || !functions.is_aligned() {
            return std::ptr::null_mut();
        }
        // SAFETY: non-NULL, aligned, valid by the contract; copied.
        let logger = Logger::new(unsafe { &*functions });
        // SAFETY: the string arguments are NULL or NUL-terminated.
        let args = unsafe {
            (
                in_str(instance_name, "instanceName"),
                in_str(guid, "fmuGUID"),
                in_str(resource_location, "fmuResourceLocation"),
            )
        };
        let name_for_log = args.0.as_ref().map(|s| *s).unwrap_or("?");
        let result = match args {
            (Ok(name), Ok(guid), Ok(loc)) => catch_unwind(AssertUnwindSafe(|| {
                Instance::<M>::new(name, fmu_type, guid, loc, logger, logging_on != fmi2False)
            }))
            .unwrap_or_else(|p| Err(format!("internal error (panic): {}", panic_message(&*p)))),
            (Err(e), _, _) | (_, Err(e), _) | (_, _, Err(e)) => Err(e.to_string()),
        };
        match result {
            Ok(inst) => Box::into_raw(Box::new(inst)).cast(),
            Err(reason) => {
                logger.log(
                    &super::instance::to_cstring(name_for_log),
                    Status::Error,
                    "logStatusError",
                    &format!("fmi2Instantiate: {reason}"),
                );
                std::ptr::null_mut()
            }
        }
    }))
    .unwrap_or(std::ptr::null_mut())
}

/// `fmi2FreeInstance`: frees the instance (NULL is ignored). Allowed in
/// every state.
///
/// # Safety
/// Module contract; `c` is not used again.
pub unsafe extern "C" fn free_instance<M: CoSimModel>(c: fmi2Component) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: module contract.
        if let Some(inst) = unsafe { instance_mut::<M>(c) } {
            inst.log_event("freeing instance");
            inst.invalidate();
            // SAFETY: made by Box::into_raw in `instantiate`, freed once.
            drop(unsafe { Box::from_raw(c.cast::<Instance<M>>()) });
        }
    }));
}

// ---------------------------------------------------------------------------
// Initialisation, termination, reset.

/// `fmi2SetupExperiment` (state Instantiated). `stopTime` is recorded and
/// passed to the model; steps past it are not refused.
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn setup_experiment<M: CoSimModel>(
    c: fmi2Component,
    tolerance_defined: fmi2Boolean,
    tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetupExperiment, |inst| {
            inst.setup_experiment(
                (tolerance_defined != fmi2False).then_some(tolerance),
                start_time,
                (stop_time_defined != fmi2False).then_some(stop_time),
            )
        })
    }
}

/// `fmi2EnterInitializationMode` (Instantiated -> InitializationMode).
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn enter_initialization_mode<M: CoSimModel>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::EnterInitializationMode, |i| {
            i.enter_initialization_mode()
        })
    }
}

/// `fmi2ExitInitializationMode` (InitializationMode -> StepComplete).
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn exit_initialization_mode<M: CoSimModel>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::ExitInitializationMode, |i| {
            i.exit_initialization_mode()
        })
    }
}

/// `fmi2Terminate` (StepComplete -> Terminated).
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn terminate<M: CoSimModel>(c: fmi2Component) -> fmi2Status {
    unsafe { guarded::<M>(c, Func::Terminate, |i| i.terminate()) }
}

/// `fmi2Reset` (any state -> Instantiated, start values).
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn reset<M: CoSimModel>(c: fmi2Component) -> fmi2Status {
    unsafe { guarded::<M>(c, Func::Reset, |i| i.reset()) }
}

// ---------------------------------------------------------------------------
// Getting and setting variable values.

/// `fmi2GetReal` (InitializationMode, StepComplete, Terminated, Error).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn get_real<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetReal, |inst| {
            inst.get_real(in_slice(vr, nvr, "vr")?, out_slice(value, nvr, "value")?)
        })
    }
}

/// `fmi2GetInteger` (as `fmi2GetReal`).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn get_integer<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetInteger, |inst| {
            inst.get_integer(in_slice(vr, nvr, "vr")?, out_slice(value, nvr, "value")?)
        })
    }
}

/// `fmi2GetBoolean` (InitializationMode, StepComplete, Terminated, Error).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn get_boolean<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetBoolean, |inst| {
            inst.get_boolean(in_slice(vr, nvr, "vr")?, out_slice(value, nvr, "value")?)
        })
    }
}

/// `fmi2GetString`: the models have no String variables (`nvr = 0` is OK).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn get_string<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetString, |inst| {
            out_slice(value, nvr, "value")?;
            inst.no_variables_of(BaseType::String, in_slice(vr, nvr, "vr")?)
        })
    }
}

/// `fmi2SetReal` (Instantiated, InitializationMode, StepComplete): inputs;
/// parameters before the end of initialisation; tunable parameters also
/// later. NaN and values the model refuses give `fmi2Error` naming the
/// variable. Values before the refused one stay set.
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn set_real<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetReal, |inst| {
            inst.set_real(in_slice(vr, nvr, "vr")?, in_slice(value, nvr, "value")?)
        })
    }
}

/// `fmi2SetInteger` (as `fmi2SetReal`; values outside the variable's
/// min/max are refused by the model, naming it).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn set_integer<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetInteger, |inst| {
            inst.set_integer(in_slice(vr, nvr, "vr")?, in_slice(value, nvr, "value")?)
        })
    }
}

/// `fmi2SetBoolean` (as `fmi2SetReal`; any non-zero value is true).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn set_boolean<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetBoolean, |inst| {
            inst.set_boolean(in_slice(vr, nvr, "vr")?, in_slice(value, nvr, "value")?)
        })
    }
}

/// `fmi2SetString`: the models have no String variables (`nvr = 0` is OK).
///
/// # Safety
/// Module contract; `vr` and `value` hold `nvr` elements.
pub unsafe extern "C" fn set_string<M: CoSimModel>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetString, |inst| {
            in_slice(value, nvr, "value")?;
            inst.no_variables_of(BaseType::String, in_slice(vr, nvr, "vr")?)
        })
    }
}

// ---------------------------------------------------------------------------
// FMU state.

/// `fmi2GetFMUstate`: saves the whole instance (model, time, state). If
/// `*state` is NULL a new object is made, otherwise the given one (from this
/// library, not freed) is overwritten.
///
/// # Safety
/// Module contract; `state` is a valid `fmi2FMUstate*`.
pub unsafe extern "C" fn get_fmu_state<M: CoSimModel>(
    c: fmi2Component,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetFMUstate, |inst| {
            let slot = out_ref(state, "FMUstate")?;
            let bytes = inst.save();
            if slot.is_null() {
                let b = Box::new(StateBox {
                    magic: state_magic::<M>(),
                    bytes,
                });
                *slot = Box::into_raw(b).cast();
            } else {
                state_mut::<M>(*slot, "*FMUstate")?.bytes = bytes;
            }
            inst.log_event("FMU state saved");
            Ok(())
        })
    }
}

/// `fmi2SetFMUstate`: restores a state saved by `fmi2GetFMUstate` or
/// deserialized (also into an instance in the Error state: that is how an
/// importer rolls back after an error).
///
/// # Safety
/// Module contract; `state` is an `fmi2FMUstate` of this library not yet freed.
pub unsafe extern "C" fn set_fmu_state<M: CoSimModel>(
    c: fmi2Component,
    state: fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetFMUstate, |inst| {
            let b = state_mut::<M>(state, "FMUstate")?;
            inst.restore(&b.bytes)
        })
    }
}

/// `fmi2FreeFMUstate`: frees `*state` and sets it to NULL (NULL is ignored).
///
/// # Safety
/// Module contract; `state` is a valid `fmi2FMUstate*` whose target is NULL
/// or an `fmi2FMUstate` of this library not yet freed.
pub unsafe extern "C" fn free_fmu_state<M: CoSimModel>(
    c: fmi2Component,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::FreeFMUstate, |_| {
            let slot = out_ref(state, "FMUstate")?;
            if !slot.is_null() {
                let b = state_mut::<M>(*slot, "*FMUstate")?;
                b.magic = 0;
                // SAFETY: made by Box::into_raw in this module, freed once.
                drop(Box::from_raw((*slot).cast::<StateBox>()));
                *slot = std::ptr::null_mut();
            }
            Ok(())
        })
    }
}

/// `fmi2SerializedFMUstateSize`: the size of the serialized `state`.
///
/// # Safety
/// Module contract; `state` as in `fmi2SetFMUstate`; `size` is writable.
pub unsafe extern "C" fn serialized_fmu_state_size<M: CoSimModel>(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SerializedFMUstateSize, |_| {
            let b = state_mut::<M>(state, "FMUstate")?;
            *out_ref(size, "size")? = b.bytes.len();
            Ok(())
        })
    }
}

/// `fmi2SerializeFMUstate`: copies the serialized `state` into `bytes`
/// (`size` must be at least `fmi2SerializedFMUstateSize`). The bytes are
/// self-contained: they restore in another process.
///
/// # Safety
/// Module contract; `state` as in `fmi2SetFMUstate`; `bytes` holds `size`
/// writable bytes.
pub unsafe extern "C" fn serialize_fmu_state<M: CoSimModel>(
    c: fmi2Component,
    state: fmi2FMUstate,
    bytes: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SerializeFMUstate, |_| {
            let b = state_mut::<M>(state, "FMUstate")?;
            if size < b.bytes.len() {
                return Err(FmiError::InvalidArgument(format!(
                    "size = {size} is smaller than the serialized state ({} bytes)",
                    b.bytes.len()
                )));
            }
            let out = out_slice(bytes.cast::<u8>(), b.bytes.len(), "serializedState")?;
            out.copy_from_slice(&b.bytes);
            Ok(())
        })
    }
}

/// `fmi2DeSerializeFMUstate`: a new `fmi2FMUstate` from serialized bytes
/// (checked to be a state of this model); `*state` is overwritten, not freed.
///
/// # Safety
/// Module contract; `bytes` holds `size` bytes; `state` is a valid
/// `fmi2FMUstate*`.
pub unsafe extern "C" fn de_serialize_fmu_state<M: CoSimModel>(
    c: fmi2Component,
    bytes: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::DeSerializeFMUstate, |_| {
            let data = in_slice(bytes.cast::<u8>(), size, "serializedState")?;
            let slot = out_ref(state, "FMUstate")?;
            Instance::<M>::check_saved(data)?;
            let b = Box::new(StateBox {
                magic: state_magic::<M>(),
                bytes: data.to_vec(),
            });
            *slot = Box::into_raw(b).cast();
            Ok(())
        })
    }
}

/// `fmi2GetDirectionalDerivative`: for a model with
/// [`CoSimModel::PROVIDES_DIRECTIONAL_DERIVATIVE`], the derivatives of
/// outputs with respect to inputs ([`Instance::directional_derivative`]);
/// otherwise `fmi2Error` (`providesDirectionalDerivative="false"`).
///
/// # Safety
/// Module contract; `unknown` and `dv_unknown` hold `n_unknown` values,
/// `known` and `dv_known` hold `n_known` (read only when supported).
pub unsafe extern "C" fn get_directional_derivative<M: CoSimModel>(
    c: fmi2Component,
    unknown: *const fmi2ValueReference,
    n_unknown: usize,
    known: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetDirectionalDerivative, |inst| {
            if !M::PROVIDES_DIRECTIONAL_DERIVATIVE {
                return unsupported(
                    Func::GetDirectionalDerivative,
                    "providesDirectionalDerivative=\"false\"",
                );
            }
            let unknown = in_slice(unknown, n_unknown, "vUnknown_ref")?;
            let known = in_slice(known, n_known, "vKnown_ref")?;
            let dv_known = in_slice(dv_known, n_known, "dvKnown")?;
            let dv_unknown = out_slice(dv_unknown, n_unknown, "dvUnknown")?;
            inst.directional_derivative(unknown, known, dv_known, dv_unknown)
        })
    }
}

// ---------------------------------------------------------------------------
// Co-simulation.

/// `fmi2SetRealInputDerivatives`: not supported (`canInterpolateInputs="false"`).
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn set_real_input_derivatives<M: CoSimModel>(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::SetRealInputDerivatives, |_| {
            unsupported(
                Func::SetRealInputDerivatives,
                "canInterpolateInputs=\"false\"",
            )
        })
    }
}

/// `fmi2GetRealOutputDerivatives`: not supported (`maxOutputDerivativeOrder="0"`).
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn get_real_output_derivatives<M: CoSimModel>(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetRealOutputDerivatives, |_| {
            unsupported(
                Func::GetRealOutputDerivatives,
                "maxOutputDerivativeOrder=\"0\"",
            )
        })
    }
}

/// `fmi2DoStep` (StepComplete): advances from `t` (which must be where the
/// previous step ended, relative tolerance 1e-8) by `h > 0`. Synchronous:
/// never returns `fmi2Pending`. A model error gives `fmi2Error` (roll back
/// with `fmi2SetFMUstate` if needed).
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn do_step<M: CoSimModel>(
    c: fmi2Component,
    t: fmi2Real,
    h: fmi2Real,
    _no_set_fmu_state_prior: fmi2Boolean,
) -> fmi2Status {
    unsafe { guarded::<M>(c, Func::DoStep, |i| i.do_step(t, h)) }
}

const NOT_ASYNC: &str = "fmi2DoStep is synchronous (canRunAsynchronuously=\"false\")";

/// `fmi2CancelStep`: not supported (no asynchronous step to cancel).
///
/// # Safety
/// Module contract.
pub unsafe extern "C" fn cancel_step<M: CoSimModel>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::CancelStep, |_| {
            unsupported(Func::CancelStep, NOT_ASYNC)
        })
    }
}

/// `fmi2GetStatus`: not supported (only meaningful for asynchronous steps).
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn get_status<M: CoSimModel>(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2Status,
) -> fmi2Status {
    unsafe { guarded::<M>(c, Func::GetStatus, |_| status_unavailable(Func::GetStatus)) }
}

/// `fmi2GetRealStatus`: not supported.
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn get_real_status<M: CoSimModel>(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetRealStatus, |_| {
            status_unavailable(Func::GetRealStatus)
        })
    }
}

/// `fmi2GetIntegerStatus`: not supported.
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn get_integer_status<M: CoSimModel>(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetIntegerStatus, |_| {
            status_unavailable(Func::GetIntegerStatus)
        })
    }
}

/// `fmi2GetBooleanStatus`: not supported (the FMU never asks to terminate).
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn get_boolean_status<M: CoSimModel>(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetBooleanStatus, |_| {
            status_unavailable(Func::GetBooleanStatus)
        })
    }
}

/// `fmi2GetStringStatus`: not supported.
///
/// # Safety
/// Module contract (no other pointer is read).
pub unsafe extern "C" fn get_string_status<M: CoSimModel>(
    c: fmi2Component,
    _kind: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, Func::GetStringStatus, |_| {
            status_unavailable(Func::GetStringStatus)
        })
    }
}

/// The C names of the functions [`crate::export_fmi2!`] exports: every FMI
/// 2.0 common and co-simulation function.
pub const EXPORTED_SYMBOLS: [&str; 34] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

/// Exports the FMI 2.0 common and co-simulation functions under their C
/// names (`fmi2DoStep`, ...) for one model type. Use it once per cdylib, in
/// a crate of its own (`crate-type = ["cdylib"]`, named after the
/// modelIdentifier; the library `gearpump` is an rlib and exports nothing):
///
/// ```ignore
/// // fmus/gear-pump/src/lib.rs
/// gearpump::export_fmi2!(gearpump::fmi2::pump::GearPumpFmu);
/// ```
///
/// It defines, in the calling module, a hidden type alias
/// `Fmi2ExportedModel` and a hidden module `fmi2_symbols` holding the 34
/// `#[unsafe(no_mangle)] extern "C"` functions, each forwarding to the
/// generic function of [`exports`](crate::exports) with the same
/// safety contract.
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => {
        #[doc(hidden)]
        pub type Fmi2ExportedModel = $model;

        #[doc(hidden)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub mod fmi2_symbols {
            use super::Fmi2ExportedModel as M;
            use ::std::ffi::c_char;
            use $crate::exports as x;
            use $crate::types::*;

            #[unsafe(no_mangle)]
            pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
                x::get_types_platform()
            }
            #[unsafe(no_mangle)]
            pub extern "C" fn fmi2GetVersion() -> *const c_char {
                x::get_version()
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetDebugLogging(
                c: fmi2Component,
                on: fmi2Boolean,
                n: usize,
                cats: *const fmi2String,
            ) -> fmi2Status {
                unsafe { x::set_debug_logging::<M>(c, on, n, cats) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2Instantiate(
                name: fmi2String,
                kind: fmi2Type,
                guid: fmi2String,
                resources: fmi2String,
                functions: *const fmi2CallbackFunctions,
                visible: fmi2Boolean,
                logging_on: fmi2Boolean,
            ) -> fmi2Component {
                unsafe {
                    x::instantiate::<M>(name, kind, guid, resources, functions, visible, logging_on)
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2FreeInstance(c: fmi2Component) {
                unsafe { x::free_instance::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetupExperiment(
                c: fmi2Component,
                tol_defined: fmi2Boolean,
                tol: fmi2Real,
                start: fmi2Real,
                stop_defined: fmi2Boolean,
                stop: fmi2Real,
            ) -> fmi2Status {
                unsafe { x::setup_experiment::<M>(c, tol_defined, tol, start, stop_defined, stop) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
                unsafe { x::enter_initialization_mode::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
                unsafe { x::exit_initialization_mode::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
                unsafe { x::terminate::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
                unsafe { x::reset::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetReal(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut fmi2Real,
            ) -> fmi2Status {
                unsafe { x::get_real::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetInteger(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut fmi2Integer,
            ) -> fmi2Status {
                unsafe { x::get_integer::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetBoolean(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut fmi2Boolean,
            ) -> fmi2Status {
                unsafe { x::get_boolean::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetString(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *mut fmi2String,
            ) -> fmi2Status {
                unsafe { x::get_string::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetReal(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const fmi2Real,
            ) -> fmi2Status {
                unsafe { x::set_real::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetInteger(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const fmi2Integer,
            ) -> fmi2Status {
                unsafe { x::set_integer::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetBoolean(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const fmi2Boolean,
            ) -> fmi2Status {
                unsafe { x::set_boolean::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetString(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                v: *const fmi2String,
            ) -> fmi2Status {
                unsafe { x::set_string::<M>(c, vr, n, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetFMUstate(
                c: fmi2Component,
                s: *mut fmi2FMUstate,
            ) -> fmi2Status {
                unsafe { x::get_fmu_state::<M>(c, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetFMUstate(
                c: fmi2Component,
                s: fmi2FMUstate,
            ) -> fmi2Status {
                unsafe { x::set_fmu_state::<M>(c, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2FreeFMUstate(
                c: fmi2Component,
                s: *mut fmi2FMUstate,
            ) -> fmi2Status {
                unsafe { x::free_fmu_state::<M>(c, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
                c: fmi2Component,
                s: fmi2FMUstate,
                size: *mut usize,
            ) -> fmi2Status {
                unsafe { x::serialized_fmu_state_size::<M>(c, s, size) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SerializeFMUstate(
                c: fmi2Component,
                s: fmi2FMUstate,
                bytes: *mut fmi2Byte,
                size: usize,
            ) -> fmi2Status {
                unsafe { x::serialize_fmu_state::<M>(c, s, bytes, size) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
                c: fmi2Component,
                bytes: *const fmi2Byte,
                size: usize,
                s: *mut fmi2FMUstate,
            ) -> fmi2Status {
                unsafe { x::de_serialize_fmu_state::<M>(c, bytes, size, s) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
                c: fmi2Component,
                unknown: *const fmi2ValueReference,
                n_unknown: usize,
                known: *const fmi2ValueReference,
                n_known: usize,
                dv_known: *const fmi2Real,
                dv_unknown: *mut fmi2Real,
            ) -> fmi2Status {
                unsafe {
                    x::get_directional_derivative::<M>(
                        c, unknown, n_unknown, known, n_known, dv_known, dv_unknown,
                    )
                }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                order: *const fmi2Integer,
                v: *const fmi2Real,
            ) -> fmi2Status {
                unsafe { x::set_real_input_derivatives::<M>(c, vr, n, order, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
                c: fmi2Component,
                vr: *const fmi2ValueReference,
                n: usize,
                order: *const fmi2Integer,
                v: *mut fmi2Real,
            ) -> fmi2Status {
                unsafe { x::get_real_output_derivatives::<M>(c, vr, n, order, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2DoStep(
                c: fmi2Component,
                t: fmi2Real,
                h: fmi2Real,
                no_set_prior: fmi2Boolean,
            ) -> fmi2Status {
                unsafe { x::do_step::<M>(c, t, h, no_set_prior) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
                unsafe { x::cancel_step::<M>(c) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetStatus(
                c: fmi2Component,
                k: fmi2StatusKind,
                v: *mut fmi2Status,
            ) -> fmi2Status {
                unsafe { x::get_status::<M>(c, k, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetRealStatus(
                c: fmi2Component,
                k: fmi2StatusKind,
                v: *mut fmi2Real,
            ) -> fmi2Status {
                unsafe { x::get_real_status::<M>(c, k, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetIntegerStatus(
                c: fmi2Component,
                k: fmi2StatusKind,
                v: *mut fmi2Integer,
            ) -> fmi2Status {
                unsafe { x::get_integer_status::<M>(c, k, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetBooleanStatus(
                c: fmi2Component,
                k: fmi2StatusKind,
                v: *mut fmi2Boolean,
            ) -> fmi2Status {
                unsafe { x::get_boolean_status::<M>(c, k, v) }
            }
            #[unsafe(no_mangle)]
            pub unsafe extern "C" fn fmi2GetStringStatus(
                c: fmi2Component,
                k: fmi2StatusKind,
                v: *mut fmi2String,
            ) -> fmi2Status {
                unsafe { x::get_string_status::<M>(c, k, v) }
            }
        }
    };
}
