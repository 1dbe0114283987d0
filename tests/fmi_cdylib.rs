//! The built cdylibs as an importer sees them: each FMU's library
//! (`fmus/gear-pump` -> `libGearPump.so`, `fmus/transmission-circuit` ->
//! `libTransmissionCircuit.so`, built by [`fmi_common::cdylib`]) loaded with
//! `dlopen`, every FMI 2.0 common and co-simulation symbol resolved (as
//! fmpy does at load time), and its model run through the C symbols only:
//! instantiate, initialise, step, FMU state save/restore, serialization
//! into a fresh instance, instances on threads, unload and reload; both
//! libraries loaded in one process side by side. Also packages each FMU and
//! checks its content.
//!
//! The checks are model-agnostic (variable table, start values, default
//! experiment), written once as generic functions and run for each model.
#![allow(unsafe_code)]

mod fmi_common;

use std::ffi::{c_char, c_void, CStr, CString};
use std::io::Read;
use std::path::{Path, PathBuf};
use std::ptr::null_mut;

use fmi_common::{callbacks, cdylib, Log, TempDir};
use gearpump::fmi2::types::*;
use std::marker::PhantomData;

use gearpump::fmi2::{
    CircuitModel, CoSimModel, ExportedModel as PumpModel, FmuModel, VariableKind,
};

type Instantiate = unsafe extern "C" fn(
    fmi2String,
    fmi2Type,
    fmi2String,
    fmi2String,
    *const fmi2CallbackFunctions,
    fmi2Boolean,
    fmi2Boolean,
) -> fmi2Component;
type Vrs<T> = unsafe extern "C" fn(fmi2Component, *const u32, usize, T) -> fmi2Status;

/// The library, loaded with dlopen, and the functions the test calls.
struct Lib {
    handle: *mut c_void,
    types_platform: extern "C" fn() -> *const c_char,
    version: extern "C" fn() -> *const c_char,
    instantiate: Instantiate,
    free_instance: unsafe extern "C" fn(fmi2Component),
    setup:
        unsafe extern "C" fn(fmi2Component, fmi2Boolean, f64, f64, fmi2Boolean, f64) -> fmi2Status,
    enter: unsafe extern "C" fn(fmi2Component) -> fmi2Status,
    exit: unsafe extern "C" fn(fmi2Component) -> fmi2Status,
    terminate: unsafe extern "C" fn(fmi2Component) -> fmi2Status,
    get_real: Vrs<*mut f64>,
    get_boolean: Vrs<*mut fmi2Boolean>,
    get_integer: Vrs<*mut fmi2Integer>,
    do_step: unsafe extern "C" fn(fmi2Component, f64, f64, fmi2Boolean) -> fmi2Status,
    get_state: unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status,
    set_state: unsafe extern "C" fn(fmi2Component, fmi2FMUstate) -> fmi2Status,
    free_state: unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status,
    state_size: unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut usize) -> fmi2Status,
    serialize:
        unsafe extern "C" fn(fmi2Component, fmi2FMUstate, *mut fmi2Byte, usize) -> fmi2Status,
    deserialize: unsafe extern "C" fn(
        fmi2Component,
        *const fmi2Byte,
        usize,
        *mut fmi2FMUstate,
    ) -> fmi2Status,
}

// The handle and function pointers may be used from any thread.
unsafe impl Send for Lib {}
unsafe impl Sync for Lib {}

fn dl_error() -> String {
    let e = unsafe { libc::dlerror() };
    if e.is_null() {
        "unknown dl error".into()
    } else {
        unsafe { CStr::from_ptr(e) }.to_string_lossy().into_owned()
    }
}

/// A symbol address as a function pointer of type `F`.
///
/// # Safety
/// `p` is the address of a function of type `F`.
unsafe fn fn_ptr<F: Copy>(p: *mut c_void) -> F {
    assert_eq!(std::mem::size_of::<F>(), std::mem::size_of::<*mut c_void>());
    assert!(!p.is_null());
    // SAFETY: same size; the type is the caller's contract.
    unsafe { std::mem::transmute_copy(&p) }
}

impl Lib {
    fn open(path: &Path) -> Lib {
        let p = CString::new(path.to_str().unwrap()).unwrap();
        let handle = unsafe { libc::dlopen(p.as_ptr(), libc::RTLD_NOW | libc::RTLD_LOCAL) };
        assert!(
            !handle.is_null(),
            "dlopen {}: {}",
            path.display(),
            dl_error()
        );
        let missing: Vec<&str> = gearpump::fmi2::exports::EXPORTED_SYMBOLS
            .iter()
            .copied()
            .filter(|s| Self::sym(handle, s).is_null())
            .collect();
        assert!(missing.is_empty(), "missing symbols: {missing:?}");
        macro_rules! f {
            ($name:literal) => {
                // SAFETY: the symbol exists and has the FMI 2.0 signature of
                // the field it is stored in.
                unsafe { fn_ptr(Self::sym(handle, $name)) }
            };
        }
        Lib {
            handle,
            types_platform: f!("fmi2GetTypesPlatform"),
            version: f!("fmi2GetVersion"),
            instantiate: f!("fmi2Instantiate"),
            free_instance: f!("fmi2FreeInstance"),
            setup: f!("fmi2SetupExperiment"),
            enter: f!("fmi2EnterInitializationMode"),
            exit: f!("fmi2ExitInitializationMode"),
            terminate: f!("fmi2Terminate"),
            get_real: f!("fmi2GetReal"),
            get_boolean: f!("fmi2GetBoolean"),
            get_integer: f!("fmi2GetInteger"),
            do_step: f!("fmi2DoStep"),
            get_state: f!("fmi2GetFMUstate"),
            set_state: f!("fmi2SetFMUstate"),
            free_state: f!("fmi2FreeFMUstate"),
            state_size: f!("fmi2SerializedFMUstateSize"),
            serialize: f!("fmi2SerializeFMUstate"),
            deserialize: f!("fmi2DeSerializeFMUstate"),
        }
    }

    fn sym(handle: *mut c_void, name: &str) -> *mut c_void {
        let n = CString::new(name).unwrap();
        unsafe { libc::dlsym(handle, n.as_ptr()) }
    }
}

impl Drop for Lib {
    fn drop(&mut self) {
        unsafe { libc::dlclose(self.handle) };
    }
}

fn ok(s: fmi2Status, what: &str, log: &Log) {
    assert_eq!(
        Status::from_raw(s),
        Some(Status::Ok),
        "{what}: {}",
        log.dump()
    );
}

/// A resources folder with the model's resource files.
fn resources<Model: CoSimModel>(dir: &TempDir) -> PathBuf {
    let res = dir.path().join("resources");
    for (name, bytes) in Model::resource_files() {
        let p = res.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, bytes).unwrap();
    }
    std::fs::create_dir_all(&res).unwrap();
    res
}

fn step_size<Model: CoSimModel>() -> f64 {
    Model::DEFAULT_EXPERIMENT.map_or(1e-3, |e| e.step_size)
}

/// One instance driven through the C symbols.
struct Run<'a, Model> {
    lib: &'a Lib,
    c: fmi2Component,
    log: Box<Log>,
    t: f64,
    model: PhantomData<Model>,
}

impl<'a, Model: CoSimModel> Run<'a, Model> {
    fn new(lib: &'a Lib, res: &Path, name: &str) -> Run<'a, Model> {
        let log = Box::<Log>::default();
        let cb = callbacks(&log);
        let name = CString::new(name).unwrap();
        let guid = CString::new(Model::GUID).unwrap();
        let uri = CString::new(TempDir::uri(res)).unwrap();
        let c = unsafe {
            (lib.instantiate)(
                name.as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                uri.as_ptr(),
                &cb,
                fmi2False,
                fmi2False,
            )
        };
        assert!(!c.is_null(), "instantiate: {}", log.dump());
        Run {
            lib,
            c,
            log,
            t: 0.0,
            model: PhantomData,
        }
    }

    fn init(&mut self) {
        unsafe {
            ok(
                (self.lib.setup)(self.c, fmi2False, 0.0, 0.0, fmi2False, 0.0),
                "setup",
                &self.log,
            );
            ok((self.lib.enter)(self.c), "enter", &self.log);
            ok((self.lib.exit)(self.c), "exit", &self.log);
        }
    }

    fn steps(&mut self, n: usize) {
        let h = step_size::<Model>();
        for _ in 0..n {
            ok(
                unsafe { (self.lib.do_step)(self.c, self.t, h, fmi2True) },
                "doStep",
                &self.log,
            );
            self.t += h;
        }
    }

    /// Every Real, Boolean and Integer variable, in table order.
    fn values(&self) -> Vec<f64> {
        Model::variables()
            .iter()
            .map(|v| {
                let r = v.value_reference;
                match v.kind {
                    VariableKind::Real { .. } => {
                        let mut x = f64::NAN;
                        ok(
                            unsafe { (self.lib.get_real)(self.c, &r, 1, &mut x) },
                            v.name,
                            &self.log,
                        );
                        assert!(x.is_finite(), "{} = {x}", v.name);
                        x
                    }
                    VariableKind::Boolean { .. } => {
                        let mut b = -1;
                        ok(
                            unsafe { (self.lib.get_boolean)(self.c, &r, 1, &mut b) },
                            v.name,
                            &self.log,
                        );
                        assert!(b == fmi2True || b == fmi2False, "{} = {b}", v.name);
                        f64::from(b)
                    }
                    VariableKind::Integer { min, max, .. } => {
                        let mut n = i32::MIN;
                        ok(
                            unsafe { (self.lib.get_integer)(self.c, &r, 1, &mut n) },
                            v.name,
                            &self.log,
                        );
                        assert!(
                            min.is_none_or(|lo| n >= lo) && max.is_none_or(|hi| n <= hi),
                            "{} = {n}",
                            v.name
                        );
                        f64::from(n)
                    }
                }
            })
            .collect()
    }
}

impl<Model> Drop for Run<'_, Model> {
    fn drop(&mut self) {
        unsafe { (self.lib.free_instance)(self.c) };
    }
}

fn all_symbols_resolve_and_versions_are_right(model: FmuModel) {
    let lib = Lib::open(&cdylib(model));
    let s = |p: *const c_char| unsafe { CStr::from_ptr(p) }.to_str().unwrap().to_string();
    assert_eq!(s((lib.types_platform)()), "default");
    assert_eq!(s((lib.version)()), "2.0");
}

fn model_runs_saves_and_restores_through_the_c_symbols<Model: CoSimModel>(model: FmuModel) {
    let lib = Lib::open(&cdylib(model));
    let dir = TempDir::new("cdylib");
    let res = resources::<Model>(&dir);

    let mut a = Run::<Model>::new(&lib, &res, "a");
    a.init();
    a.steps(10);
    let mut s: fmi2FMUstate = null_mut();
    ok(
        unsafe { (lib.get_state)(a.c, &mut s) },
        "getFMUstate",
        &a.log,
    );
    let mut n = 0;
    ok(unsafe { (lib.state_size)(a.c, s, &mut n) }, "size", &a.log);
    let mut bytes = vec![0u8; n];
    ok(
        unsafe { (lib.serialize)(a.c, s, bytes.as_mut_ptr().cast(), n) },
        "serialize",
        &a.log,
    );
    let t_saved = a.t;
    a.steps(10);
    let reference = a.values();

    // Roll back in the same instance.
    ok(unsafe { (lib.set_state)(a.c, s) }, "setFMUstate", &a.log);
    a.t = t_saved;
    a.steps(10);
    assert_eq!(a.values(), reference);
    ok(
        unsafe { (lib.free_state)(a.c, &mut s) },
        "freeFMUstate",
        &a.log,
    );
    ok(unsafe { (lib.terminate)(a.c) }, "terminate", &a.log);
    drop(a);

    // A fresh instance from the serialized bytes only.
    let mut b = Run::<Model>::new(&lib, &res, "b");
    let mut s: fmi2FMUstate = null_mut();
    ok(
        unsafe { (lib.deserialize)(b.c, bytes.as_ptr().cast(), bytes.len(), &mut s) },
        "deserialize",
        &b.log,
    );
    ok(unsafe { (lib.set_state)(b.c, s) }, "setFMUstate", &b.log);
    ok(
        unsafe { (lib.free_state)(b.c, &mut s) },
        "freeFMUstate",
        &b.log,
    );
    b.t = t_saved;
    b.steps(10);
    assert_eq!(b.values(), reference);
}

fn instances_on_threads_give_identical_results<Model: CoSimModel>(model: FmuModel) {
    let lib = Lib::open(&cdylib(model));
    let dir = TempDir::new("cdylib-threads");
    let res = resources::<Model>(&dir);
    let results: Vec<Vec<f64>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..4)
            .map(|k| {
                let (lib, res) = (&lib, &res);
                scope.spawn(move || {
                    let mut r = Run::<Model>::new(lib, res, &format!("t{k}"));
                    r.init();
                    r.steps(20);
                    r.values()
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for r in &results[1..] {
        assert_eq!(r, &results[0]);
    }
}

fn library_can_be_unloaded_and_reloaded<Model: CoSimModel>(model: FmuModel) {
    let path = cdylib(model);
    let dir = TempDir::new("cdylib-reload");
    let res = resources::<Model>(&dir);
    let mut last = None;
    for _ in 0..3 {
        let lib = Lib::open(&path);
        let mut r = Run::<Model>::new(&lib, &res, "reload");
        r.init();
        r.steps(5);
        let v = r.values();
        drop(r);
        drop(lib); // dlclose, as fmpy does after fmi2FreeInstance
        if let Some(prev) = &last {
            assert_eq!(&v, prev);
        }
        last = Some(v);
    }
}

fn packaged_fmu_has_the_expected_content<Model: CoSimModel>(model: FmuModel) {
    let so = cdylib(model);
    let dir = TempDir::new("package");
    let out = dir
        .path()
        .join("sub dir")
        .join(format!("{}.fmu", Model::MODEL_IDENTIFIER));
    gearpump::fmi2::build_model_fmu::<Model>(&out, &so).unwrap();
    // Written atomically: no temporary file left beside it.
    let names: Vec<String> = std::fs::read_dir(out.parent().unwrap())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec![format!("{}.fmu", Model::MODEL_IDENTIFIER)]);

    let mut zip = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    let mut read = |name: &str| {
        let mut f = zip
            .by_name(name)
            .unwrap_or_else(|_| panic!("{name} missing"));
        let mut buf = Vec::new();
        f.read_to_end(&mut buf).unwrap();
        buf
    };
    let xml = String::from_utf8(read("modelDescription.xml")).unwrap();
    assert_eq!(xml, gearpump::fmi2::model_description_xml::<Model>());
    let bin = read(&format!("binaries/linux64/{}.so", Model::MODEL_IDENTIFIER));
    assert_eq!(bin, std::fs::read(&so).unwrap());
    let doc = String::from_utf8(read("documentation/index.html")).unwrap();
    assert!(doc.contains(Model::GUID));
    for (name, bytes) in Model::resource_files() {
        assert_eq!(read(&format!("resources/{name}")), bytes);
    }
    assert!(zip.by_name("resources/").is_ok(), "resources/ folder entry");

    // Refusals leave nothing behind.
    let bad = dir.path().join("bad.fmu");
    let err = gearpump::fmi2::build_fmu(&bad, "Bad-Id", &xml, &so, &[], "").unwrap_err();
    assert!(err.to_string().contains("Bad-Id"));
    let err = gearpump::fmi2::build_fmu(&bad, "Ok", &xml, &so, &[("../escape".into(), vec![])], "")
        .unwrap_err();
    assert!(err.to_string().contains("../escape"));
    let err = gearpump::fmi2::build_fmu(&bad, "Ok", &xml, &dir.path().join("none.so"), &[], "")
        .unwrap_err();
    assert!(err.to_string().contains("none.so"));
    assert!(!bad.exists());
}

/// Each check for each packaged model.
macro_rules! for_each_model {
    ($($check:ident),* $(,)?) => {
        mod gear_pump {
            use super::*;
            $(#[test]
            fn $check() {
                super::$check::<PumpModel>(FmuModel::GearPump);
            })*
        }
        mod transmission_circuit {
            use super::*;
            $(#[test]
            fn $check() {
                super::$check::<CircuitModel>(FmuModel::TransmissionCircuit);
            })*
        }
    };
}

for_each_model!(
    model_runs_saves_and_restores_through_the_c_symbols,
    instances_on_threads_give_identical_results,
    library_can_be_unloaded_and_reloaded,
    packaged_fmu_has_the_expected_content,
);

#[test]
fn symbols_and_versions_of_both_libraries() {
    for model in FmuModel::ALL {
        all_symbols_resolve_and_versions_are_right(model);
    }
}

/// The two libraries export the same C names; loaded side by side with
/// RTLD_LOCAL each instance runs its own model (the reason each FMU has a
/// library of its own).
#[test]
fn both_libraries_loaded_side_by_side_run_their_own_model() {
    let pump = Lib::open(&cdylib(FmuModel::GearPump));
    let circuit = Lib::open(&cdylib(FmuModel::TransmissionCircuit));
    let (dp, dc) = (TempDir::new("side-pump"), TempDir::new("side-circuit"));
    let (rp, rc) = (resources::<PumpModel>(&dp), resources::<CircuitModel>(&dc));
    let mut a = Run::<PumpModel>::new(&pump, &rp, "pump");
    let mut b = Run::<CircuitModel>::new(&circuit, &rc, "circuit");
    a.init();
    b.init();
    a.steps(3);
    b.steps(3);
    assert_eq!(a.values().len(), PumpModel::variables().len());
    assert_eq!(b.values().len(), CircuitModel::variables().len());
    // the pump's GUID is refused by the circuit's library
    let log = Box::<Log>::default();
    let cb = callbacks(&log);
    let name = CString::new("wrong").unwrap();
    let guid = CString::new(PumpModel::GUID).unwrap();
    let uri = CString::new(TempDir::uri(&rc)).unwrap();
    let c = unsafe {
        (circuit.instantiate)(
            name.as_ptr(),
            fmi2CoSimulation,
            guid.as_ptr(),
            uri.as_ptr(),
            &cb,
            fmi2False,
            fmi2False,
        )
    };
    assert!(c.is_null());
    assert!(log.has(Status::Error, &["GUID"]), "{}", log.dump());
}

type GetDirectionalDerivative = unsafe extern "C" fn(
    fmi2Component,
    *const fmi2ValueReference,
    usize,
    *const fmi2ValueReference,
    usize,
    *const fmi2Real,
    *mut fmi2Real,
) -> fmi2Status;

/// `fmi2GetDirectionalDerivative` of GearPump through its C symbol:
/// d Q_out = dQ_out/dp_out dp_out (the `dQ_out_dp_out` output, negative),
/// linear in the seed, two knowns summed; refused with Status::Error.raw() and a
/// logged reason for a known that is not an input, an unknown without
/// declared dependencies, a NaN seed and a NULL array. The circuit, which
/// provides none, refuses it.
#[test]
fn directional_derivative_through_the_c_symbol() {
    use gearpump::fmi2::pump::vr;
    let lib = Lib::open(&cdylib(FmuModel::GearPump));
    // SAFETY: the symbol exists and has the FMI 2.0 signature.
    let dd: GetDirectionalDerivative =
        unsafe { fn_ptr(Lib::sym(lib.handle, "fmi2GetDirectionalDerivative")) };
    let dir = TempDir::new("cdylib-dd");
    let res = resources::<PumpModel>(&dir);
    let mut run = Run::<PumpModel>::new(&lib, &res, "pump");
    run.init();
    run.steps(3);
    let call = |unknown: &[u32], known: &[u32], seed: &[f64]| -> (fmi2Status, Vec<f64>) {
        let mut out = vec![f64::NAN; unknown.len()];
        let s = unsafe {
            dd(
                run.c,
                unknown.as_ptr(),
                unknown.len(),
                known.as_ptr(),
                known.len(),
                seed.as_ptr(),
                out.as_mut_ptr(),
            )
        };
        (s, out)
    };
    let (s, g) = call(&[vr::Q_OUT], &[vr::P_OUT], &[1.0]);
    assert_eq!(s, Status::Ok.raw(), "{}", run.log.dump());
    let mut out = f64::NAN;
    ok(
        unsafe { (lib.get_real)(run.c, &vr::DQ_OUT_DP_OUT, 1, &mut out) },
        "dQ_out_dp_out",
        &run.log,
    );
    assert!(g[0] < 0.0 && g[0] == out, "{} vs {out}", g[0]);
    let (s, g3) = call(&[vr::Q_OUT], &[vr::P_OUT], &[3.0]);
    assert_eq!((s, g3[0]), (Status::Ok.raw(), 3.0 * g[0]));
    // d Q_out / d speed: positive (a pump delivers more the faster it turns)
    let (s, gs) = call(&[vr::Q_OUT], &[vr::SPEED], &[1.0]);
    assert_eq!(s, Status::Ok.raw());
    assert!(gs[0] > 0.0, "{}", gs[0]);
    let (s, sum) = call(&[vr::Q_OUT], &[vr::SPEED, vr::P_OUT], &[1.0, 1.0]);
    assert_eq!((s, sum[0]), (Status::Ok.raw(), gs[0] + g[0]));
    for (unknown, known, seed, needle) in [
        (vr::Q_OUT, vr::TORQUE, 1.0, "not an input"),
        (vr::TORQUE, vr::P_OUT, 1.0, "no derivatives"),
        (vr::Q_OUT, vr::P_OUT, f64::NAN, "not finite"),
    ] {
        // a fresh instance each time: an error leaves it in the error state
        let mut r = Run::<PumpModel>::new(&lib, &res, "bad");
        r.init();
        let mut out = [0.0];
        let s = unsafe { dd(r.c, &unknown, 1, &known, 1, &seed, out.as_mut_ptr()) };
        assert_eq!(s, Status::Error.raw(), "{needle}");
        assert!(
            r.log.has(Status::Error, &[needle]),
            "{needle}: {}",
            r.log.dump()
        );
    }
    let r = Run::<PumpModel>::new(&lib, &res, "null");
    let s = unsafe { dd(r.c, &vr::Q_OUT, 1, std::ptr::null(), 1, &1.0, &mut 0.0) };
    assert_eq!(s, Status::Error.raw());
    drop(r);
    // the circuit provides none
    let lib = Lib::open(&cdylib(FmuModel::TransmissionCircuit));
    let dd: GetDirectionalDerivative =
        unsafe { fn_ptr(Lib::sym(lib.handle, "fmi2GetDirectionalDerivative")) };
    let dir = TempDir::new("cdylib-dd-circuit");
    let res = resources::<CircuitModel>(&dir);
    let mut c = Run::<CircuitModel>::new(&lib, &res, "circuit");
    c.init();
    let (u, k) = (
        gearpump::fmi2::circuit::vr::P_LINE,
        gearpump::fmi2::circuit::vr::Q_PUMP,
    );
    let s = unsafe { dd(c.c, &u, 1, &k, 1, &1.0, &mut 0.0) };
    assert_eq!(s, Status::Error.raw());
    assert!(
        c.log.has(Status::Error, &["providesDirectionalDerivative"]),
        "{}",
        c.log.dump()
    );
}
