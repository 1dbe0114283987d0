//! The FMI 2.0 glue, tested in-process by calling its `extern "C"`
//! functions directly (generic over the model, here the test model
//! `example::Tank` and two small models defined below), with a Rust logger
//! callback.
#![allow(unsafe_code)]

mod fmi_common;

use std::ffi::{c_char, CStr, CString};
use std::path::Path;
use std::ptr::{null, null_mut};

use fmi_common::{callbacks, Log, TempDir};
use gearpump::fmi2::example::{vr, Tank};
use gearpump::fmi2::exports as x;
use gearpump::fmi2::instance::{Instance, InstanceState};
use gearpump::fmi2::types::*;
use gearpump::fmi2::{
    CoSimModel, ModelError, StateReader, StateWriter, Variability, Variable, VariableKind,
};

/// `export_fmi2!` used outside the library, as in `fmus/*/src/lib.rs`.
mod exported {
    gearpump::export_fmi2!(gearpump::fmi2::example::Tank);
}

fn st(raw: fmi2Status) -> Status {
    Status::from_raw(raw).expect("a valid fmi2Status")
}

/// One instance of model `M` with its own log and resources folder.
struct Inst<M: CoSimModel = Tank> {
    c: fmi2Component,
    log: Box<Log>,
    _dir: TempDir,
    _m: std::marker::PhantomData<M>,
}

fn instantiate_raw<M: CoSimModel>(
    name: &str,
    kind: fmi2Type,
    guid: &str,
    uri: &str,
    log: &Log,
    logging_on: bool,
) -> fmi2Component {
    let name = CString::new(name).unwrap();
    let guid = CString::new(guid).unwrap();
    let uri = CString::new(uri).unwrap();
    let cb = callbacks(log);
    // SAFETY: valid strings and callbacks; `log` outlives the instance.
    unsafe {
        x::instantiate::<M>(
            name.as_ptr(),
            kind,
            guid.as_ptr(),
            uri.as_ptr(),
            &cb,
            fmi2False,
            if logging_on { fmi2True } else { fmi2False },
        )
    }
}

impl<M: CoSimModel> Inst<M> {
    fn new(logging_on: bool) -> Self {
        let dir = TempDir::new("glue");
        let res = dir.path().join("resources");
        std::fs::create_dir(&res).unwrap();
        let log = Box::<Log>::default();
        let c = instantiate_raw::<M>(
            "inst",
            fmi2CoSimulation,
            M::GUID,
            &TempDir::uri(&res),
            &log,
            logging_on,
        );
        assert!(!c.is_null(), "instantiate failed: {}", log.dump());
        Inst {
            c,
            log,
            _dir: dir,
            _m: std::marker::PhantomData,
        }
    }

    fn state(&self) -> InstanceState {
        // SAFETY: a live instance of M.
        unsafe { &*(self.c as *const Instance<M>) }.state()
    }

    fn setup(&self, start: f64, stop: Option<f64>) -> Status {
        let (d, s) = match stop {
            Some(s) => (fmi2True, s),
            None => (fmi2False, 0.0),
        };
        st(unsafe { x::setup_experiment::<M>(self.c, fmi2False, 0.0, start, d, s) })
    }
    fn enter(&self) -> Status {
        st(unsafe { x::enter_initialization_mode::<M>(self.c) })
    }
    fn exit(&self) -> Status {
        st(unsafe { x::exit_initialization_mode::<M>(self.c) })
    }
    fn init(&self, start: f64) {
        assert_eq!(self.setup(start, None), Status::Ok, "{}", self.log.dump());
        assert_eq!(self.enter(), Status::Ok, "{}", self.log.dump());
        assert_eq!(self.exit(), Status::Ok, "{}", self.log.dump());
    }
    fn set_real(&self, r: u32, v: f64) -> Status {
        st(unsafe { x::set_real::<M>(self.c, &r, 1, &v) })
    }
    fn set_bool(&self, r: u32, v: bool) -> Status {
        let b = if v { fmi2True } else { fmi2False };
        st(unsafe { x::set_boolean::<M>(self.c, &r, 1, &b) })
    }
    fn get_real(&self, r: u32) -> (Status, f64) {
        let mut v = f64::NAN;
        let s = st(unsafe { x::get_real::<M>(self.c, &r, 1, &mut v) });
        (s, v)
    }
    fn real(&self, r: u32) -> f64 {
        let (s, v) = self.get_real(r);
        assert_eq!(s, Status::Ok, "{}", self.log.dump());
        v
    }
    fn get_bool(&self, r: u32) -> (Status, bool) {
        let mut v = -1;
        let s = st(unsafe { x::get_boolean::<M>(self.c, &r, 1, &mut v) });
        assert!(s != Status::Ok || v == fmi2True || v == fmi2False);
        (s, v == fmi2True)
    }
    fn step(&self, t: f64, h: f64) -> Status {
        st(unsafe { x::do_step::<M>(self.c, t, h, fmi2True) })
    }
    fn get_state(&self, s: &mut fmi2FMUstate) -> Status {
        st(unsafe { x::get_fmu_state::<M>(self.c, s) })
    }
    fn set_state(&self, s: fmi2FMUstate) -> Status {
        st(unsafe { x::set_fmu_state::<M>(self.c, s) })
    }
    fn free_state(&self, s: &mut fmi2FMUstate) -> Status {
        st(unsafe { x::free_fmu_state::<M>(self.c, s) })
    }
    fn serialize(&self, s: fmi2FMUstate) -> Vec<u8> {
        let mut n = 0usize;
        assert_eq!(
            st(unsafe { x::serialized_fmu_state_size::<M>(self.c, s, &mut n) }),
            Status::Ok
        );
        let mut buf = vec![0u8; n];
        assert_eq!(
            st(unsafe { x::serialize_fmu_state::<M>(self.c, s, buf.as_mut_ptr().cast(), n) }),
            Status::Ok
        );
        buf
    }
    fn deserialize(&self, bytes: &[u8], s: &mut fmi2FMUstate) -> Status {
        st(
            unsafe {
                x::de_serialize_fmu_state::<M>(self.c, bytes.as_ptr().cast(), bytes.len(), s)
            },
        )
    }
}

impl<M: CoSimModel> Drop for Inst<M> {
    fn drop(&mut self) {
        unsafe { x::free_instance::<M>(self.c) };
    }
}

const OUTPUTS: [u32; 3] = [vr::LEVEL, vr::Q_OUT, vr::VOLUME];

fn outputs(i: &Inst) -> Vec<f64> {
    OUTPUTS.iter().map(|&r| i.real(r)).collect()
}

fn cstr(p: *const c_char) -> String {
    unsafe { CStr::from_ptr(p) }.to_str().unwrap().to_string()
}

#[test]
fn version_and_types_platform() {
    assert_eq!(cstr(x::get_types_platform()), "default");
    assert_eq!(cstr(x::get_version()), "2.0");
    // The symbols the macro exports from a downstream crate (here this test
    // crate, as the thin cdylib crates under fmus/ do) are the same functions.
    assert_eq!(
        cstr(exported::fmi2_symbols::fmi2GetTypesPlatform()),
        "default"
    );
    assert_eq!(cstr(exported::fmi2_symbols::fmi2GetVersion()), "2.0");
    assert_eq!(x::EXPORTED_SYMBOLS.len(), 34);
}

#[test]
fn full_run_matches_closed_form_and_logs_events() {
    let i = Inst::<Tank>::new(true);
    assert_eq!(i.state(), InstanceState::Instantiated);
    assert_eq!(i.setup(0.0, Some(10.0)), Status::Ok);
    assert_eq!(i.enter(), Status::Ok);
    assert_eq!(i.state(), InstanceState::InitializationMode);
    assert_eq!(i.set_real(vr::AREA, 2.0), Status::Ok);
    assert_eq!(i.set_real(vr::LEVEL_START, 0.05), Status::Ok);
    assert_eq!(i.set_real(vr::K_OUT, 0.02), Status::Ok);
    assert_eq!(i.exit(), Status::Ok);
    assert_eq!(i.state(), InstanceState::StepComplete);
    assert_eq!(i.real(vr::LEVEL), 0.05);
    assert_eq!(i.set_real(vr::Q_IN, 3.0e-3), Status::Ok);

    let h = 0.1;
    let mut t = 0.0;
    for _ in 0..100 {
        assert_eq!(i.step(t, h), Status::Ok, "{}", i.log.dump());
        t += h;
    }
    // h(t) = h_ss + (h0 - h_ss) exp(-k t / A), h_ss = q/k.
    let (q, k, a, h0): (f64, f64, f64, f64) = (3.0e-3, 0.02, 2.0, 0.05);
    let expect = q / k + (h0 - q / k) * (-k * 10.0 / a).exp();
    let level = i.real(vr::LEVEL);
    assert!((level - expect).abs() < 1e-12, "{level} vs {expect}");
    assert!((i.real(vr::Q_OUT) - k * level).abs() < 1e-15);
    assert!((i.real(vr::VOLUME) - a * level).abs() < 1e-15);
    assert_eq!(i.get_bool(vr::OVERFLOW), (Status::Ok, false));
    assert_eq!(st(unsafe { x::terminate::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.state(), InstanceState::Terminated);
    // Getters still work after termination; steps do not.
    assert_eq!(i.real(vr::LEVEL), level);

    let msgs = i.log.messages();
    assert!(msgs.iter().all(|m| m.instance == "inst"));
    assert!(
        i.log.has(Status::Ok, &["instantiated Tank"]),
        "{}",
        i.log.dump()
    );
    assert!(i.log.has(Status::Ok, &["terminated at t = "]));
    assert!(msgs.iter().all(|m| m.status == Status::Ok));
}

#[test]
fn no_event_messages_without_debug_logging() {
    let i = Inst::<Tank>::new(false);
    i.init(0.0);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
    assert!(i.log.messages().is_empty(), "{}", i.log.dump());
    // Errors are always logged.
    assert_eq!(i.step(5.0, 1.0), Status::Error);
    assert!(i
        .log
        .has(Status::Error, &["fmi2DoStep", "currentCommunicationPoint"]));
    // Debug logging switched on later, for one category.
    let i = Inst::<Tank>::new(false);
    let cat = c"logEvents";
    let cats = [cat.as_ptr()];
    assert_eq!(
        st(unsafe { x::set_debug_logging::<Tank>(i.c, fmi2True, 1, cats.as_ptr()) }),
        Status::Ok
    );
    i.init(0.0);
    assert!(i.log.has(Status::Ok, &["initialized"]), "{}", i.log.dump());
    // An unknown category: a warning, and the instance goes on.
    let bad = [c"logNoSuchThing".as_ptr()];
    assert_eq!(
        st(unsafe { x::set_debug_logging::<Tank>(i.c, fmi2True, 1, bad.as_ptr()) }),
        Status::Warning
    );
    assert!(i.log.has(Status::Warning, &["logNoSuchThing"]));
    assert_eq!(i.state(), InstanceState::StepComplete);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
    // NULL category array with n > 0.
    assert_eq!(
        st(unsafe { x::set_debug_logging::<Tank>(i.c, fmi2True, 2, null()) }),
        Status::Error
    );
    assert!(i.log.has(Status::Error, &["categories", "NULL"]));
}

#[test]
fn instantiate_refusals_return_null_with_a_logged_reason() {
    let dir = TempDir::new("refuse");
    let res = dir.path().join("resources");
    std::fs::create_dir(&res).unwrap();
    let uri = TempDir::uri(&res);

    let cases: [(&str, fmi2Type, &str, String, &[&str]); 6] = [
        (
            "wrong guid",
            fmi2CoSimulation,
            "{not-the-guid}",
            uri.clone(),
            &["GUID mismatch", "{not-the-guid}"],
        ),
        (
            "model exchange",
            fmi2ModelExchange,
            Tank::GUID,
            uri.clone(),
            &["co-simulation"],
        ),
        (
            "missing resources",
            fmi2CoSimulation,
            Tank::GUID,
            TempDir::uri(&dir.path().join("nope")),
            &["does not exist"],
        ),
        (
            "http uri",
            fmi2CoSimulation,
            Tank::GUID,
            "http://example.org/resources".into(),
            &["fmuResourceLocation", "not a file: URI"],
        ),
        (
            "remote host",
            fmi2CoSimulation,
            Tank::GUID,
            "file://server/share".into(),
            &["remote host"],
        ),
        (
            "",
            fmi2CoSimulation,
            Tank::GUID,
            uri.clone(),
            &["instanceName is empty"],
        ),
    ];
    for (name, kind, guid, loc, needles) in cases {
        let log = Log::default();
        let c = instantiate_raw::<Tank>(name, kind, guid, &loc, &log, false);
        assert!(c.is_null(), "{name}: instantiated");
        assert!(log.has(Status::Error, needles), "{name}: {}", log.dump());
        assert!(log.has(Status::Error, &["fmi2Instantiate"]));
    }

    // NULL arguments.
    let log = Log::default();
    let cb = callbacks(&log);
    let guid = CString::new(Tank::GUID).unwrap();
    let loc = CString::new(uri.clone()).unwrap();
    let c = unsafe {
        x::instantiate::<Tank>(
            null(),
            fmi2CoSimulation,
            guid.as_ptr(),
            loc.as_ptr(),
            &cb,
            0,
            0,
        )
    };
    assert!(c.is_null());
    assert!(
        log.has(Status::Error, &["instanceName is NULL"]),
        "{}",
        log.dump()
    );
    let c = unsafe {
        x::instantiate::<Tank>(
            c"a".as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            null(),
            &cb,
            0,
            0,
        )
    };
    assert!(c.is_null());
    assert!(log.has(Status::Error, &["fmuResourceLocation is NULL"]));
    let c = unsafe {
        x::instantiate::<Tank>(
            c"a".as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            loc.as_ptr(),
            null(),
            0,
            0,
        )
    };
    assert!(c.is_null(), "NULL callbacks must be refused");
    // No logger at all: refused silently, no crash.
    let mut quiet = callbacks(&log);
    quiet.logger = None;
    let c = unsafe {
        x::instantiate::<Tank>(
            c"a".as_ptr(),
            fmi2CoSimulation,
            c"{x}".as_ptr(),
            loc.as_ptr(),
            &quiet,
            0,
            0,
        )
    };
    assert!(c.is_null());
}

#[test]
fn resource_location_forms_are_accepted() {
    let dir = TempDir::new("uri forms");
    let res = dir.path().join("res 100%");
    std::fs::create_dir(&res).unwrap();
    let plain = res.to_str().unwrap();
    let encoded = plain.replace('%', "%25").replace(' ', "%20");
    for loc in [
        format!("file://{encoded}"),
        format!("file:{encoded}"),
        format!("file://localhost{encoded}/"),
        format!("FILE://{}", encoded.replace("res", "%72es")),
    ] {
        let log = Log::default();
        let c = instantiate_raw::<Tank>("a", fmi2CoSimulation, Tank::GUID, &loc, &log, false);
        assert!(!c.is_null(), "{loc}: {}", log.dump());
        // SAFETY: live instance.
        let inst = unsafe { &*(c as *const Instance<Tank>) };
        assert_eq!(
            inst.resources().canonicalize().unwrap(),
            res.canonicalize().unwrap()
        );
        unsafe { x::free_instance::<Tank>(c) };
    }
}

#[test]
fn calls_in_the_wrong_state_are_refused_and_move_to_error() {
    let i = Inst::<Tank>::new(false);
    // A step before initialisation.
    assert_eq!(i.step(0.0, 0.1), Status::Error);
    assert!(
        i.log.has(
            Status::Error,
            &["fmi2DoStep is not allowed in state Instantiated"]
        ),
        "{}",
        i.log.dump()
    );
    assert_eq!(i.state(), InstanceState::Error);
    // In Error: getters are allowed (diagnostics), the rest is refused.
    assert_eq!(i.get_real(vr::LEVEL).0, Status::Ok);
    assert_eq!(i.enter(), Status::Error);
    assert!(i.log.has(Status::Error, &["not allowed in state Error"]));
    // Reset recovers.
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.state(), InstanceState::Instantiated);
    // Getters are not allowed before initialisation mode.
    assert_eq!(i.get_real(vr::LEVEL).0, Status::Error);
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    // setupExperiment / exitInitializationMode after initialisation.
    assert_eq!(i.setup(0.0, None), Status::Error);
    assert!(i.log.has(
        Status::Error,
        &["fmi2SetupExperiment is not allowed in state StepComplete"]
    ));
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    assert_eq!(i.exit(), Status::Error);
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    assert_eq!(st(unsafe { x::terminate::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.step(0.0, 0.1), Status::Error);
    assert!(i
        .log
        .has(Status::Error, &["not allowed in state Terminated"]));
    // Terminate twice.
    assert_eq!(st(unsafe { x::terminate::<Tank>(i.c) }), Status::Error);
}

#[test]
fn invalid_values_name_the_variable_and_a_saved_state_rolls_back() {
    let i = Inst::<Tank>::new(false);
    i.init(0.0);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
    let mut saved: fmi2FMUstate = null_mut();
    assert_eq!(i.get_state(&mut saved), Status::Ok);
    let before = outputs(&i);

    assert_eq!(i.set_real(vr::Q_IN, f64::NAN), Status::Error);
    assert!(
        i.log.has(Status::Error, &["fmi2SetReal", "q_in", "NaN"]),
        "{}",
        i.log.dump()
    );
    assert_eq!(i.state(), InstanceState::Error);
    assert_eq!(i.step(1.0, 1.0), Status::Error);

    // Roll back from the Error state.
    assert_eq!(i.set_state(saved), Status::Ok, "{}", i.log.dump());
    assert_eq!(i.state(), InstanceState::StepComplete);
    assert_eq!(outputs(&i), before);

    i.log.clear();
    assert_eq!(i.set_real(vr::Q_IN, -1.0), Status::Error);
    assert!(
        i.log.has(Status::Error, &["q_in = -1", ">= 0"]),
        "{}",
        i.log.dump()
    );
    assert_eq!(i.set_state(saved), Status::Ok);
    assert_eq!(i.set_real(vr::Q_IN, f64::INFINITY), Status::Error);
    assert!(i.log.has(Status::Error, &["q_in = inf"]));
    assert_eq!(i.set_state(saved), Status::Ok);
    assert_eq!(i.step(1.0, 1.0), Status::Ok);
    assert_eq!(i.free_state(&mut saved), Status::Ok);
    assert!(saved.is_null());
}

#[test]
fn causality_and_variability_rules_for_setters() {
    let i = Inst::<Tank>::new(false);
    // Outputs can never be set.
    assert_eq!(i.set_real(vr::LEVEL, 1.0), Status::Error);
    assert!(
        i.log
            .has(Status::Error, &["level (vr 6) cannot be set", "output"]),
        "{}",
        i.log.dump()
    );
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    // Parameters and inputs before initialisation.
    assert_eq!(i.set_real(vr::AREA, 1.0), Status::Ok);
    assert_eq!(i.set_real(vr::Q_IN, 1.0e-3), Status::Ok);
    assert_eq!(i.set_bool(vr::OUTLET_OPEN, false), Status::Ok);
    i.init(0.0);
    // After initialisation: a fixed parameter is refused...
    assert_eq!(i.set_real(vr::AREA, 3.0), Status::Error);
    assert!(i.log.has(Status::Error, &["area", "fixed parameter"]));
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    // ...tunable parameters and inputs are accepted.
    assert_eq!(i.set_real(vr::K_OUT, 0.5), Status::Ok);
    assert_eq!(i.set_bool(vr::OUTLET_OPEN, false), Status::Ok);
    assert_eq!(i.set_real(vr::Q_IN, 2.0e-3), Status::Ok);
    assert_eq!(i.get_bool(vr::OUTLET_OPEN), (Status::Ok, false));
    // Closed outlet: the level rises linearly.
    assert_eq!(i.step(0.0, 10.0), Status::Ok);
    assert!((i.real(vr::LEVEL) - 2.0e-3 * 10.0 / 0.5).abs() < 1e-15);
    assert_eq!(i.real(vr::Q_OUT), 0.0);
    // Unknown value references and type mismatches.
    assert_eq!(i.get_real(999).0, Status::Error);
    assert!(i
        .log
        .has(Status::Error, &["unknown Real value reference 999"]));
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    assert_eq!(i.get_bool(vr::LEVEL).0, Status::Error);
    assert!(i
        .log
        .has(Status::Error, &["unknown Boolean value reference 6"]));
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    assert_eq!(i.set_real(vr::OUTLET_OPEN, 1.0), Status::Error);
    // Vectors: several values in one call.
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    let refs = [vr::Q_IN, vr::K_OUT];
    let vals = [4.0e-3, 0.04];
    assert_eq!(
        st(unsafe { x::set_real::<Tank>(i.c, refs.as_ptr(), 2, vals.as_ptr()) }),
        Status::Ok
    );
    let mut out = [0.0; 2];
    assert_eq!(
        st(unsafe { x::get_real::<Tank>(i.c, refs.as_ptr(), 2, out.as_mut_ptr()) }),
        Status::Ok
    );
    assert_eq!(out, vals);
    // Overflow flag.
    assert_eq!(i.set_real(vr::K_OUT, 0.0), Status::Ok);
    assert_eq!(i.step(0.0, 1000.0), Status::Ok);
    assert_eq!(i.get_bool(vr::OVERFLOW), (Status::Ok, true));
}

#[test]
fn do_step_checks_communication_point_and_step_size() {
    let i = Inst::<Tank>::new(false);
    assert_eq!(i.setup(1.5, None), Status::Ok);
    assert_eq!(i.enter(), Status::Ok);
    assert_eq!(i.exit(), Status::Ok);
    for (t, h, needle) in [
        (1.5, 0.0, "communicationStepSize = 0 must be > 0"),
        (1.5, -0.1, "must be > 0"),
        (1.5, f64::NAN, "must be > 0"),
        (
            0.0,
            0.1,
            "currentCommunicationPoint = 0 s, but the FMU is at t = 1.5 s",
        ),
        (1.6, 0.1, "currentCommunicationPoint"),
        (f64::NAN, 0.1, "currentCommunicationPoint"),
    ] {
        assert_eq!(i.step(t, h), Status::Error, "{t} {h}");
        assert!(
            i.log.has(Status::Error, &[needle]),
            "{needle}: {}",
            i.log.dump()
        );
        assert_eq!(i.state(), InstanceState::Error);
        assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
        assert_eq!(i.setup(1.5, None), Status::Ok);
        assert_eq!(i.enter(), Status::Ok);
        assert_eq!(i.exit(), Status::Ok);
        i.log.clear();
    }
    // Accumulated rounding (t += h, 10000 times) is within the tolerance,
    // and a variable step size is fine.
    let mut t = 1.5;
    for k in 0..10_000 {
        let h = if k % 2 == 0 { 0.1 } else { 0.003 };
        assert_eq!(i.step(t, h), Status::Ok, "at {t}: {}", i.log.dump());
        t += h;
    }
}

/// With a stopTime defined in fmi2SetupExperiment a step ending beyond
/// it is fmi2Error naming stopTime (FMI 2.0 section 4.2.1), within a
/// relative 1e-12 for the importer's rounding; without one any step goes.
#[test]
fn steps_beyond_a_defined_stop_time_are_refused() {
    let i = Inst::<Tank>::new(false);
    assert_eq!(i.setup(0.0, Some(1e-3)), Status::Ok);
    assert_eq!(i.enter(), Status::Ok);
    assert_eq!(i.exit(), Status::Ok);
    assert_eq!(i.step(0.0, 1e-3), Status::Ok, "{}", i.log.dump());
    assert_eq!(i.step(1e-3, 1e-3), Status::Error);
    assert!(
        i.log
            .has(Status::Error, &["fmi2DoStep", "beyond stopTime = 0.001 s"]),
        "{}",
        i.log.dump()
    );
    assert_eq!(i.state(), InstanceState::Error);
    // a step that only partly passes it is refused too
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.setup(0.0, Some(1.0)), Status::Ok);
    assert_eq!(i.enter(), Status::Ok);
    assert_eq!(i.exit(), Status::Ok);
    assert_eq!(i.step(0.0, 0.75), Status::Ok);
    assert_eq!(i.step(0.75, 0.5), Status::Error);
    assert!(i.log.has(Status::Error, &["stopTime = 1 s"]));
    // t += h rounding up to the stop time is within the tolerance (1000
    // steps of 1e-3 end at 1.0000000000000007)
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.setup(0.0, Some(1.0)), Status::Ok);
    assert_eq!(i.enter(), Status::Ok);
    assert_eq!(i.exit(), Status::Ok);
    let mut t = 0.0;
    for _ in 0..1000 {
        assert_eq!(i.step(t, 1e-3), Status::Ok, "at {t}: {}", i.log.dump());
        t += 1e-3;
    }
    assert!(t > 1.0, "{t}: the rounding this test means to cover");
    assert_eq!(i.step(t, 1e-3), Status::Error);
    // no stopTime: long steps are the model's business
    let i = Inst::<Tank>::new(false);
    i.init(0.0);
    assert_eq!(i.step(0.0, 1e3), Status::Ok, "{}", i.log.dump());
}

/// fmi2SetBoolean takes fmi2True (1) and fmi2False (0) only; 2, -1, 255
/// are refused naming the variable, the value left as it was.
#[test]
fn set_boolean_takes_only_fmi2true_and_fmi2false() {
    for bad in [2, -1, 255] {
        let i = Inst::<Tank>::new(false);
        let r = vr::OUTLET_OPEN;
        assert_eq!(i.set_bool(r, false), Status::Ok);
        let s = st(unsafe { x::set_boolean::<Tank>(i.c, &r, 1, &bad) });
        assert_eq!(s, Status::Error, "{bad}");
        assert!(
            i.log.has(
                Status::Error,
                &["fmi2SetBoolean", "outlet_open", "fmi2True = 1"]
            ),
            "{bad}: {}",
            i.log.dump()
        );
        assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
        assert_eq!(i.set_bool(r, true), Status::Ok);
        i.init(0.0);
        assert_eq!(i.get_bool(r), (Status::Ok, true));
    }
}

/// fmi2GetDirectionalDerivative is not allowed in Instantiated (FMI 2.0
/// section 4.2.4: from InitializationMode on).
#[test]
fn directional_derivative_is_not_allowed_before_initialization_mode() {
    let i = Inst::<Tank>::new(false);
    let (r, mut out) = (vr::LEVEL, 0.0);
    let s = st(unsafe {
        x::get_directional_derivative::<Tank>(i.c, &r, 1, &vr::Q_IN, 1, &1.0, &mut out)
    });
    assert_eq!(s, Status::Error);
    assert!(
        i.log.has(
            Status::Error,
            &[
                "fmi2GetDirectionalDerivative",
                "not allowed in state Instantiated"
            ]
        ),
        "{}",
        i.log.dump()
    );
}

#[test]
fn fmu_state_get_set_reuses_and_frees() {
    let i = Inst::<Tank>::new(false);
    i.init(0.0);
    assert_eq!(i.set_real(vr::Q_IN, 5.0e-3), Status::Ok);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
    let mut s: fmi2FMUstate = null_mut();
    assert_eq!(i.get_state(&mut s), Status::Ok);
    assert!(!s.is_null());
    assert_eq!(i.step(1.0, 1.0), Status::Ok);
    let a = outputs(&i);
    // Restore: back at t = 1 (a step from t = 2 is refused now).
    assert_eq!(i.set_state(s), Status::Ok);
    assert_eq!(i.real(vr::Q_IN), 5.0e-3);
    assert_eq!(i.step(1.0, 1.0), Status::Ok);
    assert_eq!(outputs(&i), a);
    // Reuse the same object for a later state.
    let first = s;
    assert_eq!(i.get_state(&mut s), Status::Ok);
    assert_eq!(s, first, "an existing FMU state is overwritten in place");
    assert_eq!(i.step(2.0, 1.0), Status::Ok);
    assert_eq!(i.set_state(s), Status::Ok);
    assert_eq!(outputs(&i), a);
    // The state also carries the instance state: restore into a reset instance.
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.set_state(s), Status::Ok);
    assert_eq!(i.state(), InstanceState::StepComplete);
    assert_eq!(i.step(2.0, 1.0), Status::Ok);
    assert_eq!(i.free_state(&mut s), Status::Ok);
    assert!(s.is_null());
    // Freeing NULL is a no-op; setting NULL is an error.
    assert_eq!(i.free_state(&mut s), Status::Ok);
    assert_eq!(i.set_state(null_mut()), Status::Error);
    assert!(i.log.has(Status::Error, &["FMUstate is NULL"]));
}

#[test]
fn serialized_state_restores_in_a_fresh_instance() {
    let bytes;
    let reference;
    {
        let i = Inst::<Tank>::new(false);
        i.init(0.0);
        assert_eq!(i.set_real(vr::K_OUT, 0.03), Status::Ok);
        assert_eq!(i.set_real(vr::Q_IN, 2.0e-3), Status::Ok);
        assert_eq!(i.step(0.0, 3.0), Status::Ok);
        let mut s = null_mut();
        assert_eq!(i.get_state(&mut s), Status::Ok);
        bytes = i.serialize(s);
        assert_eq!(i.free_state(&mut s), Status::Ok);
        assert_eq!(i.step(3.0, 2.0), Status::Ok);
        reference = outputs(&i);
        // A too small buffer is refused.
        let mut s = null_mut();
        assert_eq!(i.get_state(&mut s), Status::Ok);
        let mut small = vec![0u8; 4];
        assert_eq!(
            st(unsafe { x::serialize_fmu_state::<Tank>(i.c, s, small.as_mut_ptr().cast(), 4) }),
            Status::Error
        );
        assert!(i.log.has(Status::Error, &["size = 4 is smaller"]));
    } // instance and its resources folder are gone

    let j = Inst::<Tank>::new(false); // never initialised
    let mut s = null_mut();
    assert_eq!(
        j.deserialize(&bytes, &mut s),
        Status::Ok,
        "{}",
        j.log.dump()
    );
    assert_eq!(j.set_state(s), Status::Ok);
    assert_eq!(j.state(), InstanceState::StepComplete);
    assert_eq!(j.real(vr::K_OUT), 0.03);
    assert_eq!(j.step(3.0, 2.0), Status::Ok);
    assert_eq!(outputs(&j), reference);
    // Serialising the deserialized state gives the same bytes.
    assert_eq!(j.serialize(s), bytes);
    assert_eq!(j.free_state(&mut s), Status::Ok);

    // Garbage, truncated and empty bytes are refused.
    for bad in [&b"not a state at all"[..], &bytes[..bytes.len() - 1], &[]] {
        let k = Inst::<Tank>::new(false);
        let mut s = null_mut();
        assert_eq!(k.deserialize(bad, &mut s), Status::Error);
        assert!(s.is_null());
        assert!(
            k.log.has(Status::Error, &["fmi2DeSerializeFMUstate"]),
            "{}",
            k.log.dump()
        );
    }
}

#[test]
fn reset_restores_start_values() {
    let i = Inst::<Tank>::new(false);
    i.init(0.0);
    assert_eq!(i.set_real(vr::K_OUT, 0.5), Status::Ok);
    assert_eq!(i.set_real(vr::Q_IN, 9.0e-3), Status::Ok);
    assert_eq!(i.step(0.0, 5.0), Status::Ok);
    assert!(i.real(vr::LEVEL) > 0.0);
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    assert_eq!(i.state(), InstanceState::Instantiated);
    assert_eq!(i.enter(), Status::Ok);
    for v in Tank::variables() {
        if let VariableKind::Real { start: Some(s), .. } = v.kind {
            assert_eq!(i.real(v.value_reference), s, "{}", v.name);
        }
    }
    assert_eq!(i.exit(), Status::Ok);
    assert_eq!(i.real(vr::LEVEL), 0.0);
    // Time restarts at 0 after a reset.
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
}

#[test]
fn unsupported_functions_return_error_with_a_message() {
    type Call = Box<dyn Fn(fmi2Component) -> fmi2Status>;
    let mut real = 0.0;
    let mut int = 0;
    let mut boolean = 0;
    let mut string: fmi2String = null();
    let mut status = 0;
    let r = vr::LEVEL;
    let (pr, pi, pb, ps, pst) = (
        &mut real as *mut f64,
        &mut int as *mut i32,
        &mut boolean as *mut i32,
        &mut string as *mut fmi2String,
        &mut status as *mut i32,
    );
    let calls: Vec<(&str, Call)> = vec![
        (
            "fmi2GetDirectionalDerivative",
            Box::new(move |c| unsafe {
                x::get_directional_derivative::<Tank>(c, &r, 1, &r, 1, pr, pr)
            }),
        ),
        (
            "fmi2SetRealInputDerivatives",
            Box::new(move |c| unsafe { x::set_real_input_derivatives::<Tank>(c, &r, 1, pi, pr) }),
        ),
        (
            "fmi2GetRealOutputDerivatives",
            Box::new(move |c| unsafe { x::get_real_output_derivatives::<Tank>(c, &r, 1, pi, pr) }),
        ),
        (
            "fmi2CancelStep",
            Box::new(|c| unsafe { x::cancel_step::<Tank>(c) }),
        ),
        (
            "fmi2GetInteger",
            Box::new(move |c| unsafe { x::get_integer::<Tank>(c, &r, 1, pi) }),
        ),
        (
            "fmi2SetInteger",
            Box::new(move |c| unsafe { x::set_integer::<Tank>(c, &r, 1, pi) }),
        ),
        (
            "fmi2GetString",
            Box::new(move |c| unsafe { x::get_string::<Tank>(c, &r, 1, ps) }),
        ),
        (
            "fmi2SetString",
            Box::new(move |c| unsafe { x::set_string::<Tank>(c, &r, 1, ps) }),
        ),
    ];
    for (name, call) in &calls {
        let i = Inst::<Tank>::new(false);
        i.init(0.0);
        assert_eq!(st(call(i.c)), Status::Error, "{name}");
        assert!(
            i.log.has(Status::Error, &[name]),
            "{name}: {}",
            i.log.dump()
        );
        assert_eq!(i.state(), InstanceState::Error);
        // NULL instance: fmi2Error, no crash.
        assert_eq!(st(call(null_mut())), Status::Error, "{name}");
    }
    // Status queries the slave cannot answer: fmi2Discard, logged, and the
    // instance stays usable (FMI 2.0.2 sections 2.1.3 and 4.2.3).
    let status_calls: Vec<(&str, Call)> = vec![
        (
            "fmi2GetStatus",
            Box::new(move |c| unsafe { x::get_status::<Tank>(c, 0, pst) }),
        ),
        (
            "fmi2GetRealStatus",
            Box::new(move |c| unsafe { x::get_real_status::<Tank>(c, 2, pr) }),
        ),
        (
            "fmi2GetIntegerStatus",
            Box::new(move |c| unsafe { x::get_integer_status::<Tank>(c, 0, pi) }),
        ),
        (
            "fmi2GetBooleanStatus",
            Box::new(move |c| unsafe { x::get_boolean_status::<Tank>(c, 3, pb) }),
        ),
        (
            "fmi2GetStringStatus",
            Box::new(move |c| unsafe { x::get_string_status::<Tank>(c, 1, ps) }),
        ),
    ];
    for (name, call) in &status_calls {
        let i = Inst::<Tank>::new(false);
        i.init(0.0);
        assert_eq!(st(call(i.c)), Status::Discard, "{name}");
        assert!(
            i.log.has(Status::Discard, &[name]),
            "{name}: {}",
            i.log.dump()
        );
        assert_ne!(i.state(), InstanceState::Error, "{name}");
        // the instance still steps
        assert_eq!(i.step(0.0, 0.1), Status::Ok, "{name}");
        assert_eq!(st(call(null_mut())), Status::Error, "{name}");
    }
    // Empty Integer/String calls are harmless.
    let i = Inst::<Tank>::new(false);
    i.init(0.0);
    assert_eq!(
        st(unsafe { x::get_integer::<Tank>(i.c, null(), 0, null_mut()) }),
        Status::Ok
    );
    assert_eq!(
        st(unsafe { x::set_string::<Tank>(i.c, null(), 0, null()) }),
        Status::Ok
    );
}

#[test]
fn null_pointers_are_refused() {
    // NULL component everywhere.
    let c = null_mut();
    let r = vr::LEVEL;
    let mut v = 0.0;
    unsafe {
        assert_eq!(
            st(x::setup_experiment::<Tank>(c, 0, 0.0, 0.0, 0, 0.0)),
            Status::Error
        );
        assert_eq!(st(x::enter_initialization_mode::<Tank>(c)), Status::Error);
        assert_eq!(st(x::exit_initialization_mode::<Tank>(c)), Status::Error);
        assert_eq!(st(x::terminate::<Tank>(c)), Status::Error);
        assert_eq!(st(x::reset::<Tank>(c)), Status::Error);
        assert_eq!(st(x::get_real::<Tank>(c, &r, 1, &mut v)), Status::Error);
        assert_eq!(st(x::do_step::<Tank>(c, 0.0, 1.0, 0)), Status::Error);
        assert_eq!(
            st(x::set_debug_logging::<Tank>(c, 1, 0, null())),
            Status::Error
        );
        x::free_instance::<Tank>(c);
    }
    // NULL arrays with n > 0, NULL output pointers.
    let i = Inst::<Tank>::new(false);
    type Call = Box<dyn Fn(fmi2Component) -> fmi2Status>;
    let calls: Vec<(&str, Call)> = vec![
        (
            "vr is NULL",
            Box::new(|c| unsafe { x::get_real::<Tank>(c, null(), 1, &mut 0.0) }),
        ),
        (
            "value is NULL",
            Box::new(move |c| unsafe { x::get_real::<Tank>(c, &r, 1, null_mut()) }),
        ),
        (
            "value is NULL",
            Box::new(move |c| unsafe { x::set_real::<Tank>(c, &r, 1, null()) }),
        ),
        (
            "value is NULL",
            Box::new(move |c| unsafe { x::get_boolean::<Tank>(c, &r, 1, null_mut()) }),
        ),
        (
            "FMUstate is NULL",
            Box::new(|c| unsafe { x::get_fmu_state::<Tank>(c, null_mut()) }),
        ),
        (
            "FMUstate is NULL",
            Box::new(|c| unsafe { x::free_fmu_state::<Tank>(c, null_mut()) }),
        ),
        (
            "FMUstate is NULL",
            Box::new(|c| unsafe { x::serialized_fmu_state_size::<Tank>(c, null_mut(), &mut 0) }),
        ),
        (
            "serializedState is NULL",
            Box::new(|c| unsafe {
                x::de_serialize_fmu_state::<Tank>(c, null(), 10, &mut null_mut())
            }),
        ),
    ];
    for (needle, call) in calls {
        assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
        i.init(0.0);
        assert_eq!(st(call(i.c)), Status::Error, "{needle}");
        assert!(
            i.log.has(Status::Error, &[needle]),
            "{needle}: {}",
            i.log.dump()
        );
        i.log.clear();
    }
    // An FMU state passed as a component is detected by the tag.
    assert_eq!(st(unsafe { x::reset::<Tank>(i.c) }), Status::Ok);
    i.init(0.0);
    let mut s = null_mut();
    assert_eq!(i.get_state(&mut s), Status::Ok);
    assert_eq!(
        st(unsafe { x::do_step::<Tank>(s, 0.0, 1.0, 0) }),
        Status::Error
    );
    assert_eq!(i.free_state(&mut s), Status::Ok);
}

#[test]
fn instances_on_threads_do_not_interfere() {
    let handles: Vec<_> = (0..8)
        .map(|n| {
            std::thread::spawn(move || {
                let i = Inst::<Tank>::new(n % 2 == 0);
                i.init(0.0);
                let q = 1.0e-3 * (n + 1) as f64;
                assert_eq!(i.set_real(vr::Q_IN, q), Status::Ok);
                let mut t = 0.0;
                for _ in 0..2000 {
                    assert_eq!(i.step(t, 0.01), Status::Ok);
                    t += 0.01;
                }
                let expect = q / 0.01 * (1.0 - (-0.01 * 20.0 / 0.5_f64).exp());
                let level = i.real(vr::LEVEL);
                assert!(
                    (level - expect).abs() < 1e-9 * expect,
                    "{n}: {level} vs {expect}"
                );
                assert!(i.log.messages().iter().all(|m| m.status == Status::Ok));
                level
            })
        })
        .collect();
    let levels: Vec<f64> = handles.into_iter().map(|h| h.join().unwrap()).collect();
    for w in levels.windows(2) {
        assert!(w[1] > w[0]);
    }
}

// ---------------------------------------------------------------------------
// Two more models: one that panics (and warns), one with another GUID.

#[derive(Default)]
struct Panicky {
    x: f64,
    warnings: Vec<String>,
}

static PANICKY_VARS: [Variable; 2] = [
    Variable::real(
        "x",
        1,
        gearpump::fmi2::Causality::Input,
        Variability::Continuous,
        "m",
    )
    .start(0.0),
    Variable::real(
        "y",
        2,
        gearpump::fmi2::Causality::Output,
        Variability::Continuous,
        "m",
    ),
];

impl CoSimModel for Panicky {
    const MODEL_IDENTIFIER: &'static str = "Panicky";
    const GUID: &'static str = "{panicky}";
    const MODEL_NAME: &'static str = "Panicky";
    const DESCRIPTION: &'static str =
        "panics when x > 1 at a step, or on instantiation in a folder named 'boom'";
    fn variables() -> &'static [Variable] {
        &PANICKY_VARS
    }
    fn instantiate(resources: &Path, _: &dyn Fn(&str)) -> Result<Self, ModelError> {
        if resources.ends_with("boom") {
            panic!("boom at instantiation");
        }
        Ok(Panicky::default())
    }
    fn set_real(&mut self, _: u32, v: f64) -> Result<(), ModelError> {
        self.x = v;
        Ok(())
    }
    fn get_real(&self, _: u32) -> Result<f64, ModelError> {
        Ok(self.x)
    }
    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        Ok(())
    }
    fn do_step(&mut self, _: f64, _: f64) -> Result<(), ModelError> {
        if self.x > 1.0 {
            panic!("x = {} is too much for me", self.x);
        }
        if self.x < 0.0 {
            self.warnings
                .push(format!("x = {} is below my range", self.x));
        }
        Ok(())
    }
    fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }
    fn reset(&mut self) -> Result<(), ModelError> {
        self.x = 0.0;
        Ok(())
    }
    fn save_state(&self) -> Vec<u8> {
        StateWriter::new(b"PANICKY1").f64(self.x).finish()
    }
    fn restore_state(&mut self, b: &[u8]) -> Result<(), ModelError> {
        let mut r = StateReader::new(b, b"PANICKY1")?;
        self.x = r.f64()?;
        r.finish()
    }
}

/// A model's warnings reach the logger with status fmi2Warning in their own
/// category, without debug logging, while the call returns fmi2OK.
#[test]
fn model_warnings_are_logged_and_the_step_succeeds() {
    let i = Inst::<Panicky>::new(false);
    i.init(0.0);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
    assert!(i.log.messages().is_empty(), "{}", i.log.dump());
    assert_eq!(i.set_real(1, -0.5), Status::Ok);
    assert_eq!(i.step(1.0, 1.0), Status::Ok);
    let msgs = i.log.messages();
    assert_eq!(msgs.len(), 1, "{}", i.log.dump());
    assert_eq!(msgs[0].status, Status::Warning);
    assert_eq!(msgs[0].category, "logModelWarnings");
    assert!(msgs[0].message.contains("x = -0.5 is below my range"));
    assert_eq!(i.state(), InstanceState::StepComplete);
}

#[test]
fn panics_are_caught_at_the_boundary() {
    let i = Inst::<Panicky>::new(false);
    i.init(0.0);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);
    assert_eq!(i.set_real(1, 2.0), Status::Ok);
    assert_eq!(i.step(1.0, 1.0), Status::Error);
    assert!(
        i.log
            .has(Status::Error, &["fmi2DoStep", "panic", "x = 2 is too much"]),
        "{}",
        i.log.dump()
    );
    assert_eq!(i.state(), InstanceState::Error);
    assert_eq!(st(unsafe { x::reset::<Panicky>(i.c) }), Status::Ok);
    i.init(0.0);
    assert_eq!(i.step(0.0, 1.0), Status::Ok);

    let dir = TempDir::new("boom");
    let res = dir.path().join("boom");
    std::fs::create_dir(&res).unwrap();
    let log = Log::default();
    let c = instantiate_raw::<Panicky>(
        "p",
        fmi2CoSimulation,
        Panicky::GUID,
        &TempDir::uri(&res),
        &log,
        false,
    );
    assert!(c.is_null());
    assert!(
        log.has(Status::Error, &["panic", "boom at instantiation"]),
        "{}",
        log.dump()
    );
}

#[test]
fn states_of_another_model_are_refused() {
    let p = Inst::<Panicky>::new(false);
    p.init(0.0);
    let mut ps = null_mut();
    assert_eq!(p.get_state(&mut ps), Status::Ok);
    let pbytes = p.serialize(ps);

    let t = Inst::<Tank>::new(false);
    t.init(0.0);
    // A state object of another model type.
    assert_eq!(t.set_state(ps), Status::Error);
    assert!(
        t.log
            .has(Status::Error, &["not an FMU state of this model"]),
        "{}",
        t.log.dump()
    );
    // Serialized bytes of another model (another GUID).
    let mut s = null_mut();
    assert_eq!(t.deserialize(&pbytes, &mut s), Status::Error);
    assert!(t.log.has(Status::Error, &["{panicky}"]), "{}", t.log.dump());
    assert_eq!(p.free_state(&mut ps), Status::Ok);
}
