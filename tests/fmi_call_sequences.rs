//! Random call sequences through the exported FMI 2.0 C functions of both
//! FMUs (GearPump and TransmissionCircuit), driven in-process through the
//! crate's `extern "C"` functions as the importer's C code would call them:
//! calls in and out of order, values in and out of range (NaN, infinities,
//! just outside min/max), step sizes from zero to 1e30, FMU states saved,
//! restored, freed, serialized and corrupted byte by byte (issue 18, "keep
//! the battery"; full test tier).
//!
//! Whatever the sequence, every call returns (no hang: each is timed), no
//! call panics or returns fmi2Fatal/fmi2Pending, every refusal is logged
//! with its status, outputs read with fmi2OK are finite, and GearPump never
//! holds an input or parameter outside its modelDescription min/max (what
//! fmi2SetReal accepts, and what a restored state carries).
#![allow(unsafe_code)]

mod fmi_common;

use std::ffi::CString;
use std::ptr::null_mut;
use std::time::{Duration, Instant};

use fmi_common::{callbacks, Log, TempDir};
use gearpump::fmi2::exports as x;
use gearpump::fmi2::instance::Instance;
use gearpump::fmi2::types::*;
use gearpump::fmi2::{Causality, CircuitModel, CoSimModel, ExportedModel, Variable, VariableKind};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The longest any single call may take. The slowest legitimate calls are
/// GearPump's initialisation to the periodic state and a 10 ms step at
/// 20,000 rpm; a hang (issue 18 point 1) runs for hours.
const CALL_LIMIT: Duration = Duration::from_secs(30);

fn st(raw: fmi2Status) -> Status {
    Status::from_raw(raw).expect("a valid fmi2Status")
}

/// One instance with its log, resources and the FMU states it holds.
struct Inst<M: CoSimModel> {
    c: fmi2Component,
    log: Box<Log>,
    states: Vec<fmi2FMUstate>,
    _dir: TempDir,
    _m: std::marker::PhantomData<M>,
}

impl<M: CoSimModel> Inst<M> {
    fn new() -> Self {
        let dir = TempDir::new("sequences");
        let res = dir.path().join("resources");
        std::fs::create_dir(&res).unwrap();
        for (name, bytes) in M::resource_files() {
            let p = res.join(&name);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, bytes).unwrap();
        }
        let log = Box::<Log>::default();
        let name = CString::new("seq").unwrap();
        let guid = CString::new(M::GUID).unwrap();
        let uri = CString::new(TempDir::uri(&res)).unwrap();
        let cb = callbacks(&log);
        // SAFETY: valid strings and callbacks; `log` outlives the instance.
        let c = unsafe {
            x::instantiate::<M>(
                name.as_ptr(),
                fmi2CoSimulation,
                guid.as_ptr(),
                uri.as_ptr(),
                &cb,
                fmi2False,
                fmi2False,
            )
        };
        assert!(!c.is_null(), "instantiate failed: {}", log.dump());
        Inst {
            c,
            log,
            states: Vec::new(),
            _dir: dir,
            _m: std::marker::PhantomData,
        }
    }

    /// The instance's next communication point.
    fn time(&self) -> f64 {
        // SAFETY: a live instance of M made by x::instantiate::<M>.
        unsafe { &*(self.c as *const Instance<M>) }.time()
    }
}

impl<M: CoSimModel> Drop for Inst<M> {
    fn drop(&mut self) {
        for mut s in std::mem::take(&mut self.states) {
            // SAFETY: states made by this instance, freed once.
            unsafe { x::free_fmu_state::<M>(self.c, &mut s) };
        }
        // SAFETY: a live instance, freed once.
        unsafe { x::free_instance::<M>(self.c) };
    }
}

fn real_range(v: &Variable) -> (Option<f64>, Option<f64>, Option<f64>) {
    match v.kind {
        VariableKind::Real {
            min, max, start, ..
        } => (min, max, start),
        VariableKind::Boolean { .. } | VariableKind::Integer { .. } => (None, None, None),
    }
}

/// A value for `v`: mostly within its range (or near its start value),
/// sometimes at or just beyond a bound, sometimes absurd.
fn value(rng: &mut ChaCha8Rng, v: &Variable) -> f64 {
    let (min, max, start) = real_range(v);
    let start = start.unwrap_or(1.0);
    match rng.gen_range(0..12) {
        0..=4 => match (min, max) {
            (Some(lo), Some(hi)) => lo + (hi - lo) * rng.gen::<f64>().powi(3),
            _ => start * rng.gen_range(0.5..2.0),
        },
        5 | 6 => start,
        7 => min.unwrap_or(start),
        8 => max.unwrap_or(start),
        9 => match (min, max) {
            (Some(lo), _) if rng.gen_bool(0.5) => lo - lo.abs() * 1e-6 - 1e-300,
            (_, Some(hi)) => hi + hi.abs() * 1e-6 + 1e-300,
            _ => -start,
        },
        _ => [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e300,
            -1e300,
            1e-300,
            0.0,
            -1.0,
        ][rng.gen_range(0..8)],
    }
}

/// The checks after every call.
fn check_call<M: CoSimModel>(
    inst: &Inst<M>,
    what: &str,
    status: Status,
    logged_before: usize,
    took: Duration,
) {
    let messages = inst.log.messages();
    assert!(
        matches!(
            status,
            Status::Ok | Status::Warning | Status::Discard | Status::Error
        ),
        "{what}: {status:?}"
    );
    assert!(took < CALL_LIMIT, "{what} took {took:?}");
    for m in &messages[logged_before..] {
        assert!(!m.message.contains("panic"), "{what}: {}", m.message);
    }
    if status != Status::Ok {
        assert!(
            messages[logged_before..]
                .iter()
                .any(|m| m.status == status && !m.message.is_empty()),
            "{what} returned {status:?} without saying why: {:#?}",
            &messages[logged_before..]
        );
    }
}

/// Every Real variable read back: finite when read with fmi2OK, and within
/// its min/max (inputs and parameters).
fn check_values<M: CoSimModel>(inst: &Inst<M>, what: &str) {
    for v in M::variables() {
        if !matches!(v.kind, VariableKind::Real { .. }) {
            continue;
        }
        let r = v.value_reference;
        let mut x = f64::NAN;
        // SAFETY: one value reference, one value.
        let s = st(unsafe { x::get_real::<M>(inst.c, &r, 1, &mut x) });
        if s != Status::Ok {
            continue;
        }
        assert!(x.is_finite(), "{what}: {} = {x}", v.name);
        let (min, max, _) = real_range(v);
        if matches!(v.causality, Causality::Input | Causality::Parameter) {
            assert!(
                min.is_none_or(|lo| x >= lo) && max.is_none_or(|hi| x <= hi),
                "{what}: {} = {x} outside [{min:?}, {max:?}]",
                v.name
            );
        }
    }
}

/// Runs `sequences` random sequences of `calls` calls each on fresh
/// instances of `M`; returns how many calls returned each status.
fn run_sequences<M: CoSimModel>(seed: u64, sequences: usize, calls: usize) -> [usize; 4] {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let reals: Vec<&Variable> = M::variables()
        .iter()
        .filter(|v| matches!(v.kind, VariableKind::Real { .. }))
        .collect();
    let booleans: Vec<&Variable> = M::variables()
        .iter()
        .filter(|v| matches!(v.kind, VariableKind::Boolean { .. }))
        .collect();
    let mut counts = [0usize; 4];
    for sequence in 0..sequences {
        let mut inst = Inst::<M>::new();
        // most sequences start the usual way, so that steps get made
        if rng.gen_bool(0.7) {
            unsafe {
                x::setup_experiment::<M>(inst.c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
                x::enter_initialization_mode::<M>(inst.c);
            }
        }
        for k in 0..calls {
            let before = inst.log.messages().len();
            let t0 = Instant::now();
            let call = rng.gen_range(0..22);
            let mut what = format!("sequence {sequence} call {k}: ");
            let status = match call {
                0 => {
                    let start = if rng.gen_bool(0.8) {
                        0.0
                    } else {
                        rng.gen_range(-1.0..1.0)
                    };
                    what += &format!("setup_experiment({start})");
                    st(unsafe {
                        x::setup_experiment::<M>(inst.c, fmi2False, 0.0, start, fmi2False, 0.0)
                    })
                }
                1 => {
                    what += "enter_initialization_mode";
                    st(unsafe { x::enter_initialization_mode::<M>(inst.c) })
                }
                2 | 3 => {
                    what += "exit_initialization_mode";
                    st(unsafe { x::exit_initialization_mode::<M>(inst.c) })
                }
                4..=7 => {
                    let (r, v) = if rng.gen_bool(0.95) {
                        let var = reals[rng.gen_range(0..reals.len())];
                        (var.value_reference, value(&mut rng, var))
                    } else {
                        (rng.gen_range(0..200), 1.0)
                    };
                    what += &format!("set_real({r}, {v:e})");
                    let s = st(unsafe { x::set_real::<M>(inst.c, &r, 1, &v) });
                    if s == Status::Ok {
                        // what fmi2SetReal accepts lies within min/max
                        let var = reals.iter().find(|x| x.value_reference == r).unwrap();
                        let (min, max, _) = real_range(var);
                        assert!(
                            v.is_finite()
                                && min.is_none_or(|lo| v >= lo)
                                && max.is_none_or(|hi| v <= hi),
                            "{what}: accepted outside [{min:?}, {max:?}]"
                        );
                    }
                    s
                }
                8 if !booleans.is_empty() => {
                    let r = booleans[rng.gen_range(0..booleans.len())].value_reference;
                    let b = if rng.gen_bool(0.5) {
                        fmi2True
                    } else {
                        fmi2False
                    };
                    what += &format!("set_boolean({r}, {b})");
                    st(unsafe { x::set_boolean::<M>(inst.c, &r, 1, &b) })
                }
                9 | 10 => {
                    what += "get_real(all)";
                    check_values(&inst, &what);
                    Status::Ok
                }
                11..=14 => {
                    let t = if rng.gen_bool(0.85) {
                        inst.time()
                    } else {
                        inst.time() + rng.gen_range(-1.0..1.0)
                    };
                    let h = [
                        1e-3,
                        1e-3,
                        1e-3,
                        2.5e-3,
                        1e-4,
                        1e-2,
                        0.0,
                        -1e-3,
                        f64::NAN,
                        f64::INFINITY,
                        1e30,
                        1e3,
                        f64::MAX,
                    ][rng.gen_range(0..13)];
                    what += &format!("do_step({t}, {h:e})");
                    st(unsafe { x::do_step::<M>(inst.c, t, h, fmi2True) })
                }
                15 => {
                    // a new state or an existing one overwritten
                    let mut s: fmi2FMUstate = null_mut();
                    let reuse = !inst.states.is_empty() && rng.gen_bool(0.3);
                    if reuse {
                        s = inst.states[rng.gen_range(0..inst.states.len())];
                    }
                    what += "get_fmu_state";
                    let status = st(unsafe { x::get_fmu_state::<M>(inst.c, &mut s) });
                    if status == Status::Ok && !reuse {
                        inst.states.push(s);
                    }
                    status
                }
                16 | 17 if !inst.states.is_empty() => {
                    let s = inst.states[rng.gen_range(0..inst.states.len())];
                    what += "set_fmu_state";
                    let status = st(unsafe { x::set_fmu_state::<M>(inst.c, s) });
                    if status == Status::Ok {
                        check_values(&inst, &what);
                    }
                    status
                }
                18 if !inst.states.is_empty() => {
                    let i = rng.gen_range(0..inst.states.len());
                    let mut s = inst.states.swap_remove(i);
                    what += "free_fmu_state";
                    let status = st(unsafe { x::free_fmu_state::<M>(inst.c, &mut s) });
                    assert!(s.is_null(), "{what}: not set to NULL");
                    status
                }
                19 if !inst.states.is_empty() => {
                    // serialize, corrupt (or not), deserialize
                    let s = inst.states[rng.gen_range(0..inst.states.len())];
                    let mut n = 0usize;
                    assert_eq!(
                        st(unsafe { x::serialized_fmu_state_size::<M>(inst.c, s, &mut n) }),
                        Status::Ok
                    );
                    let mut bytes = vec![0u8; n];
                    assert_eq!(
                        st(unsafe {
                            x::serialize_fmu_state::<M>(inst.c, s, bytes.as_mut_ptr().cast(), n)
                        }),
                        Status::Ok
                    );
                    let corruption = rng.gen_range(0..5);
                    match corruption {
                        0 | 1 => {}
                        2 => {
                            let i = rng.gen_range(0..bytes.len());
                            bytes[i] ^= 1 << rng.gen_range(0..8);
                        }
                        3 => bytes.truncate(rng.gen_range(0..bytes.len())),
                        _ => rng.fill(&mut bytes[..]),
                    }
                    let mut d: fmi2FMUstate = null_mut();
                    what += &format!("de_serialize_fmu_state(corruption {corruption})");
                    let status = st(unsafe {
                        x::de_serialize_fmu_state::<M>(
                            inst.c,
                            bytes.as_ptr().cast(),
                            bytes.len(),
                            &mut d,
                        )
                    });
                    if corruption >= 2 {
                        // the checksum catches every change
                        assert_eq!(status, Status::Error, "{what}: corrupted bytes accepted");
                    }
                    if status == Status::Ok {
                        inst.states.push(d);
                    }
                    status
                }
                20 => {
                    what += "reset";
                    st(unsafe { x::reset::<M>(inst.c) })
                }
                21 if rng.gen_bool(0.5) => {
                    what += "terminate";
                    st(unsafe { x::terminate::<M>(inst.c) })
                }
                21 => {
                    what += "get_status";
                    let mut s: fmi2Status = -1;
                    // fmi2DoStepStatus = 0
                    let status = st(unsafe { x::get_status::<M>(inst.c, 0, &mut s) });
                    // no asynchronous step: FMI 2.0.2 section 4.2.3, fmi2Discard
                    assert_eq!(status, Status::Discard, "{what}");
                    status
                }
                _ => {
                    what += "set_debug_logging";
                    st(unsafe {
                        x::set_debug_logging::<M>(
                            inst.c,
                            if rng.gen_bool(0.5) {
                                fmi2True
                            } else {
                                fmi2False
                            },
                            0,
                            std::ptr::null(),
                        )
                    })
                }
            };
            check_call(&inst, &what, status, before, t0.elapsed());
            counts[match status {
                Status::Ok => 0,
                Status::Warning => 1,
                Status::Discard => 2,
                _ => 3,
            }] += 1;
        }
    }
    counts
}

/// Each sequence should mostly make progress: a battery whose calls all
/// fail tests nothing.
fn assert_mixed(counts: [usize; 4]) {
    let total: usize = counts.iter().sum();
    assert!(
        counts[0] > total / 3 && counts[3] > total / 20,
        "OK, Warning, Discard, Error: {counts:?}"
    );
}

#[test]
fn gear_pump_survives_random_call_sequences() {
    let counts = run_sequences::<ExportedModel>(18, 24, 60);
    eprintln!("GearPump: OK, Warning, Discard, Error = {counts:?}");
    assert_mixed(counts);
}

#[test]
fn transmission_circuit_survives_random_call_sequences() {
    let counts = run_sequences::<CircuitModel>(1818, 60, 80);
    eprintln!("TransmissionCircuit: OK, Warning, Discard, Error = {counts:?}");
    assert_mixed(counts);
}
