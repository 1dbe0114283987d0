//! The gear pump FMU model through its safe API (`CoSimModel`), without the
//! C layer: co-simulation semantics (conservation over variable step sizes,
//! independence of the step sizes, agreement with the periodic steady state),
//! FMU state, refusals, standstill and the start-up transient.

mod fmu_outputs;
use fmu_outputs::outputs;
use std::sync::{Arc, OnceLock};

use gearpump::fmi2::pump::{vr, GearPumpFmu};
use gearpump::fmi2::{CoSimModel, ModelError};
use gearpump::model::{Inputs, Options, Pump, SampleClearances, Simulation};
use gearpump::units::*;

fn pump() -> Arc<Pump> {
    static PUMP: OnceLock<Arc<Pump>> = OnceLock::new();
    PUMP.get_or_init(|| Arc::new(Pump::new(gearpump::design::load(None, &[]).unwrap())))
        .clone()
}

/// A model at 1000 rpm / 30 bar / 60 degC (the start values), initialised.
fn started(periodic: bool) -> GearPumpFmu {
    let mut m = GearPumpFmu::with_pump(pump());
    m.set_boolean(vr::START_PERIODIC, periodic).unwrap();
    m.exit_initialization().unwrap();
    m
}

fn get(m: &GearPumpFmu, r: u32) -> f64 {
    m.get_real(r).unwrap()
}

/// A deterministic sequence in [0, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

#[test]
fn q_out_times_h_sums_to_v_delivered_over_variable_steps_and_inputs() {
    let mut m = started(true);
    let mut rng = Lcg(7);
    let (mut t, mut sum, mut angle) = (0.0, 0.0, 0.0);
    for k in 0..300 {
        // steps from 0.02 to 3 ms; speed, pressure and temperature change
        let h = 2e-5 + 3e-3 * rng.next();
        if k % 40 == 20 {
            let rpm = 500.0 + 3500.0 * rng.next();
            m.set_real(vr::SPEED, rpm_to_rad_s(rpm)).unwrap();
            m.set_real(vr::P_OUT, bar_to_pa(1.01325 + 10.0 + 30.0 * rng.next()))
                .unwrap();
            m.set_real(vr::T_OIL, celsius_to_kelvin(40.0 + 40.0 * rng.next()))
                .unwrap();
        }
        angle += get(&m, vr::SPEED) * h;
        m.do_step(t, h).unwrap();
        t += h;
        let q = get(&m, vr::Q_OUT);
        assert!(q.is_finite() && q > 0.0, "Q_out = {q} at step {k}");
        sum += q * h;
    }
    let v = get(&m, vr::V_DELIVERED);
    assert!(
        ((sum - v) / v).abs() < 1e-12,
        "sum Q_out h = {sum}, V_delivered = {v}"
    );
    let theta = get(&m, vr::THETA);
    assert!(
        (theta - angle).abs() < 1e-6 * pump().tables.dtheta,
        "theta {theta} vs integrated angle {angle}"
    );
}

#[test]
fn delivered_volume_depends_on_the_angle_not_on_the_step_sizes() {
    // Constant inputs: V(theta) is piecewise linear in theta, whatever the
    // communication steps that reach theta.
    let total = 0.02;
    let mut a = started(true);
    let mut t = 0.0;
    for _ in 0..20 {
        a.do_step(t, total / 20.0).unwrap();
        t += total / 20.0;
    }
    let mut b = started(true);
    let mut rng = Lcg(3);
    let mut t = 0.0;
    while t < total {
        let h = (1e-4 + 2e-3 * rng.next()).min(total - t);
        b.do_step(t, h).unwrap();
        t += h;
        if total - t < 1e-12 {
            break;
        }
    }
    for r in [vr::V_DELIVERED, vr::THETA, vr::Q_OUT_INST] {
        let (x, y) = (get(&a, r), get(&b, r));
        assert!(((x - y) / x).abs() < 1e-9, "vr {r}: {x} vs {y}");
    }
}

#[test]
fn mean_q_out_over_whole_mesh_periods_matches_the_periodic_steady_state() {
    let p = pump();
    let inputs = Inputs::rig(1000.0, 30.0, 60.0);
    let options = Options { micromotion: true };
    let mut sim = Simulation::new(
        Arc::clone(&p),
        inputs,
        SampleClearances::nominal(&p.design),
        options,
    )
    .unwrap();
    let summary = sim.run_periodic().unwrap();

    let mut m = started(true);
    // the FMU's initial outputs are those of the last mesh period
    let q0 = get(&m, vr::Q_OUT);
    assert!(
        ((q0 - summary.flow) / summary.flow).abs() < 5e-3,
        "{q0} vs {}",
        summary.flow
    );
    let period = 2.0 * std::f64::consts::PI / p.tables.z[0] as f64 / inputs.omega;
    let h: f64 = 1e-3;
    let periods = 10.0;
    let mut t = 0.0;
    while t < periods * period - 1e-12 {
        let step = h.min(periods * period - t);
        m.do_step(t, step).unwrap();
        t += step;
    }
    let mean = get(&m, vr::V_DELIVERED) / t;
    let rel = (mean - summary.flow) / summary.flow;
    assert!(
        rel.abs() < 5e-3,
        "FMU mean {} l/min vs periodic {} l/min ({:+.3} %)",
        m3_s_to_lpm(mean),
        m3_s_to_lpm(summary.flow),
        rel * 100.0
    );
    let eta_v = get(&m, vr::ETA_V);
    assert!(
        (eta_v - summary.eta_v).abs() < 5e-3,
        "{eta_v} vs {}",
        summary.eta_v
    );
    let eta_hm = get(&m, vr::ETA_HM);
    assert!(eta_hm > 0.5 && eta_hm < 1.0, "eta_hm {eta_hm}");
}

#[test]
fn saved_state_restores_exactly_into_another_instance() {
    let mut a = started(true);
    let mut t = 0.0;
    let h = 0.73e-3; // ends inside angular steps
    for _ in 0..5 {
        a.do_step(t, h).unwrap();
        t += h;
    }
    let bytes = a.save_state();
    let t_saved = t;
    a.set_real(vr::SPEED, rpm_to_rad_s(1500.0)).unwrap();
    for _ in 0..5 {
        a.do_step(t, h).unwrap();
        t += h;
    }
    let all = |m: &GearPumpFmu| {
        [
            vr::Q_OUT,
            vr::Q_OUT_INST,
            vr::TORQUE,
            vr::ETA_V,
            vr::ETA_HM,
            vr::V_DELIVERED,
            vr::THETA,
        ]
        .map(|r| get(m, r))
    };
    let reference = all(&a);

    // a fresh instance (as in another process: only the bytes)
    let mut b = GearPumpFmu::with_pump(pump());
    b.restore_state(&bytes).unwrap();
    b.set_real(vr::SPEED, rpm_to_rad_s(1500.0)).unwrap();
    let mut t = t_saved;
    for _ in 0..5 {
        b.do_step(t, h).unwrap();
        t += h;
    }
    assert_eq!(all(&b), reference);

    // bytes that are not a state are refused, the instance is unchanged
    let before = all(&b);
    assert!(matches!(
        b.restore_state(&bytes[..bytes.len() - 3]),
        Err(ModelError::InvalidState(_))
    ));
    assert!(b.restore_state(b"GPUMP001garbage").is_err());
    assert_eq!(all(&b), before);
}

#[test]
fn reset_returns_to_the_start_values() {
    let mut m = started(false);
    m.set_real(vr::SPEED, 300.0).unwrap();
    m.do_step(0.0, 1e-3).unwrap();
    m.reset().unwrap();
    assert_eq!(get(&m, vr::SPEED), rpm_to_rad_s(1000.0));
    assert_eq!(get(&m, vr::V_DELIVERED), 0.0);
    assert!(m.get_boolean(vr::START_PERIODIC).unwrap());
}

#[test]
fn invalid_values_are_refused_naming_the_variable_and_leave_the_state() {
    let mut m = started(true);
    m.do_step(0.0, 1e-3).unwrap();
    let v = get(&m, vr::V_DELIVERED);
    let name = |e: ModelError| match e {
        ModelError::InvalidValue { name, .. } => name,
        other => panic!("unexpected {other:?}"),
    };
    assert_eq!(name(m.set_real(vr::SPEED, -1.0).unwrap_err()), "speed");
    assert_eq!(
        name(m.set_real(vr::SPEED, f64::INFINITY).unwrap_err()),
        "speed"
    );
    assert_eq!(name(m.set_real(vr::T_OIL, 100.0).unwrap_err()), "T_oil");
    assert_eq!(name(m.set_real(vr::T_OIL, 500.0).unwrap_err()), "T_oil");
    assert_eq!(name(m.set_real(vr::P_IN, 0.0).unwrap_err()), "p_in");
    assert_eq!(
        name(m.set_real(vr::TIP_DRIVE, 0.0).unwrap_err()),
        "tip_clearance_drive"
    );
    assert_eq!(
        name(m.set_real(vr::LATERAL, 0.01).unwrap_err()),
        "lateral_clearance"
    );
    // p_out far below p_in: refused by the step
    m.set_real(vr::P_IN, bar_to_pa(20.0)).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(2.0)).unwrap();
    let e = m.do_step(1e-3, 1e-3).unwrap_err();
    assert_eq!(name(e), "p_out");
    assert_eq!(get(&m, vr::V_DELIVERED), v);
    // a pressure rise above 500 bar (each pressure within its own range)
    m.set_real(vr::P_IN, bar_to_pa(0.5)).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(540.0)).unwrap();
    let e = m.do_step(1e-3, 1e-3).unwrap_err();
    assert!(e.to_string().contains("500 bar"), "{e}");
    assert_eq!(name(e), "p_out");
    // the absurd values are refused by the setter
    assert_eq!(name(m.set_real(vr::P_OUT, 1e9).unwrap_err()), "p_out");
    assert_eq!(
        name(m.set_real(vr::SPEED, rpm_to_rad_s(1e5)).unwrap_err()),
        "speed"
    );
    // a step too long to compute in reasonable time
    m.set_real(vr::P_IN, ATMOSPHERE_PA).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(31.01325)).unwrap();
    let e = m.do_step(1e-3, 1e4).unwrap_err();
    assert!(e.to_string().contains("angular steps"), "{e}");
    assert_eq!(get(&m, vr::V_DELIVERED), v);
    m.do_step(1e-3, 1e-3).unwrap();
    assert!(get(&m, vr::V_DELIVERED) > v);
}

#[test]
fn standstill_holds_the_state() {
    let mut m = started(true);
    m.do_step(0.0, 1e-3).unwrap();
    let (v, th) = (get(&m, vr::V_DELIVERED), get(&m, vr::THETA));
    m.set_real(vr::SPEED, 0.0).unwrap();
    m.do_step(1e-3, 0.5).unwrap();
    assert_eq!(get(&m, vr::Q_OUT), 0.0);
    assert_eq!(get(&m, vr::TORQUE), 0.0);
    assert_eq!((get(&m, vr::V_DELIVERED), get(&m, vr::THETA)), (v, th));
    m.set_real(vr::SPEED, rpm_to_rad_s(1000.0)).unwrap();
    m.do_step(0.501, 1e-3).unwrap();
    assert!(get(&m, vr::Q_OUT) > 0.0);

    // starting at standstill works too
    let mut m = GearPumpFmu::with_pump(pump());
    m.set_real(vr::SPEED, 0.0).unwrap();
    m.exit_initialization().unwrap();
    m.do_step(0.0, 0.1).unwrap();
    m.set_real(vr::SPEED, rpm_to_rad_s(800.0)).unwrap();
    m.do_step(0.1, 1e-3).unwrap();
    assert!(get(&m, vr::V_DELIVERED) > 0.0);
}

/// The start-up transient from the guessed initial state
/// (`start_periodic = false`), mesh period by mesh period: the figures
/// quoted in documentation/index.html (run with `--nocapture` to see them).
#[test]
fn start_up_transient_settles_within_a_few_mesh_periods() {
    let p = pump();
    let omega = rpm_to_rad_s(1000.0);
    let period = 2.0 * std::f64::consts::PI / p.tables.z[0] as f64 / omega;
    let reference = started(true);
    let q_ss = get(&reference, vr::Q_OUT);
    let t_ss = get(&reference, vr::TORQUE);
    let mut m = started(false);
    let mut t = 0.0;
    let mut errs = Vec::new();
    for k in 1..=28 {
        let v0 = get(&m, vr::V_DELIVERED);
        m.do_step(t, period).unwrap();
        t += period;
        let q = (get(&m, vr::V_DELIVERED) - v0) / period;
        let tq = get(&m, vr::TORQUE);
        let e = (q - q_ss) / q_ss;
        println!(
            "mesh period {k:2}: mean Q_out {:+.3} %, torque {:+.3} % from the periodic state",
            e * 100.0,
            (tq - t_ss) / t_ss * 100.0
        );
        errs.push(e.abs());
    }
    assert!(errs[errs.len() - 1] < 2e-3, "{errs:?}");
}

/// Delivered volume over a delivery-pressure ramp from 30 to 40 bar in 1 s
/// at 1000 rpm, 60 degC, with micromotion, stepped at 1 ms from the
/// periodic start: the pressure changes at every step, and every step ends
/// inside an angular step of the model.
fn ramp_volume(pump: Arc<Pump>) -> f64 {
    let mut m = GearPumpFmu::with_pump(pump);
    m.exit_initialization().unwrap();
    let (n, h) = (1000, 1.0e-3);
    for i in 0..n {
        let bar = 30.0 + 10.0 * i as f64 / n as f64;
        m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(bar))
            .unwrap();
        m.do_step(i as f64 * h, h).unwrap();
    }
    get(&m, vr::V_DELIVERED)
}

#[test]
fn a_pressure_ramp_meets_the_result_of_tight_tolerances() {
    // the first angular step after each change of the inputs starts from
    // predictions that miss the jump; the Newton and micromotion tolerances
    // bound how far its accepted state may be from the converged one, and
    // the part of that step a communication step ends in keeps its error.
    // (Newton's error bound trusting a 30-fold shrink of two corrections
    // left 2.2e-5 here, a micromotion tolerance of 1e-3 2.5e-5.)
    let mut tight = gearpump::design::load(None, &[]).unwrap();
    tight.numerics.coupling_tol = 1e-7;
    tight.numerics.newton_tol = 1e-10;
    let v = ramp_volume(pump());
    let v_ref = ramp_volume(Arc::new(Pump::new(tight)));
    let dv = (v - v_ref).abs() / v_ref;
    println!("pressure ramp: delivered volume {v:e} m^3, {dv:.2e} from the tight-tolerance run");
    assert!(dv < 5e-6, "{dv:e}");
}

/// The fmpy example's ramps made five to twenty times faster: 500 -> 4000
/// rpm and 10 -> 40 bar (gauge) over 0.1 s and 0.02 s (35,000 and 175,000
/// rpm/s), 1 ms steps with micromotion, inputs set as fmpy interpolates them.
/// Near 4000 rpm / 40 bar a pocket leaving the mesh falls into the gas
/// release band within one angular step, where the plain Newton iteration
/// and the strongly damped retry both cycled between two pressures (81 kPa
/// and -122 kPa absolute) until the natural monotonicity test damped the
/// retry (`solver::NewtonOptions::monotone`). Every step succeeds and the
/// delivered volume is the sum of `Q_out h`.
#[test]
fn fast_speed_and_pressure_ramps_step_through() {
    for stop in [0.1, 0.02] {
        let mut m = GearPumpFmu::with_pump(pump());
        let signal = |t: f64| {
            let f = t / stop;
            (
                rpm_to_rad_s(500.0 + 3500.0 * f),
                bar_to_pa(1.01325 + 10.0 + 30.0 * f),
            )
        };
        let (w, p) = signal(0.0);
        m.set_boolean(vr::MICROMOTION, true).unwrap();
        m.set_real(vr::SPEED, w).unwrap();
        m.set_real(vr::P_OUT, p).unwrap();
        m.exit_initialization().unwrap();
        let h = 1e-3;
        let mut sum = 0.0;
        for k in 0..(stop / h).round() as usize {
            let t = k as f64 * h;
            let (w, p) = signal(t);
            m.set_real(vr::SPEED, w).unwrap();
            m.set_real(vr::P_OUT, p).unwrap();
            if let Err(e) = m.do_step(t, h) {
                panic!("ramp over {stop} s, step at t = {t:.3} s: {e}");
            }
            sum += get(&m, vr::Q_OUT) * h;
        }
        let v = get(&m, vr::V_DELIVERED);
        assert!((sum - v).abs() < 1e-9 * v, "{sum} against {v}");
        let eta = get(&m, vr::ETA_V);
        assert!(eta > 0.9 && eta < 1.0, "eta_v {eta} at the end of the ramp");
    }
}

/// Where the pump delivers nothing or backwards (100 rpm, 40 bar, 120 degC:
/// the leakage exceeds the displacement) the FMU says so once, with the
/// operating point; the steps still succeed. At the start values it says
/// nothing; `reset` re-arms the message.
#[test]
fn a_pump_delivering_backwards_is_warned_about_once() {
    let mut m = started(true);
    assert!(m.take_warnings().is_empty());
    for k in 0..20 {
        m.do_step(k as f64 * 1e-3, 1e-3).unwrap();
    }
    assert!(m.take_warnings().is_empty());

    let mut m = GearPumpFmu::with_pump(pump());
    m.set_real(vr::SPEED, rpm_to_rad_s(100.0)).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(1.01325 + 40.0)).unwrap();
    m.set_real(vr::T_OIL, celsius_to_kelvin(120.0)).unwrap();
    m.exit_initialization().unwrap();
    let eta = get(&m, vr::ETA_V);
    assert!(eta <= 0.0, "eta_v {eta}");
    let w = m.take_warnings();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("nothing or backwards") && w[0].contains("100 rpm"),
        "{}",
        w[0]
    );
    for k in 0..10 {
        m.do_step(k as f64 * 1e-2, 1e-2).unwrap();
    }
    assert!(get(&m, vr::ETA_V) <= 0.0);
    assert!(m.take_warnings().is_empty(), "sent once");
    m.reset().unwrap();
    m.set_real(vr::SPEED, rpm_to_rad_s(100.0)).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(1.01325 + 40.0)).unwrap();
    m.set_real(vr::T_OIL, celsius_to_kelvin(120.0)).unwrap();
    m.exit_initialization().unwrap();
    assert_eq!(m.take_warnings().len(), 1);
}

/// Results that leave physical sense are flagged, not returned silently
/// (issue 18 point 4): at the largest lateral clearance the FMU accepts
/// (500 um) the pump delivers backwards and the torque model gives eta_hm
/// above 1; each is said once, with the operating point, and the values
/// are still returned.
#[test]
fn results_out_of_physical_sense_are_flagged_once_each() {
    let mut m = GearPumpFmu::with_pump(pump());
    m.set_real(vr::LATERAL, um_to_m(500.0)).unwrap();
    m.exit_initialization().unwrap();
    let (eta_v, eta_hm) = (get(&m, vr::ETA_V), get(&m, vr::ETA_HM));
    assert!(
        eta_v < 0.0 && eta_hm > 1.0,
        "eta_v {eta_v}, eta_hm {eta_hm}"
    );
    let w = m.take_warnings();
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(w[0].contains("nothing or backwards"), "{}", w[0]);
    assert!(
        w[1].contains("eta_hm = ") && w[1].contains("exceeds 1") && w[1].contains("1000 rpm"),
        "{}",
        w[1]
    );
    for k in 0..5 {
        m.do_step(k as f64 * 1e-2, 1e-2).unwrap();
    }
    assert!(get(&m, vr::ETA_HM) > 1.0);
    assert!(m.take_warnings().is_empty(), "sent once");
}

/// The outputs in Initialization mode ([`CoSimModel::initial_outputs`],
/// which the glue calls before an output read there; they read 0 before
/// it): the ones after `exit_initialization` to the bit, and that call
/// keeps the state computed for them (the same saved state as a plain
/// exit, and no time spent on it); a changed input drops them, a setter
/// given the value held keeps them; a pressure rise out of range is an
/// error naming p_out, not a panic.
#[test]
fn outputs_in_initialization_mode_are_the_start_and_exit_keeps_them() {
    for periodic in [true, false] {
        let fresh = started(periodic);
        let mut m = GearPumpFmu::with_pump(pump());
        m.set_boolean(vr::START_PERIODIC, periodic).unwrap();
        assert_eq!(get(&m, vr::Q_OUT), 0.0, "nothing computed yet");
        m.initial_outputs().unwrap();
        // (with the start-up transient the flows and torque are 0 until
        // the first step, the pocket pressures the starting guess's)
        assert_eq!(
            get(&m, vr::Q_OUT) > 0.0 && get(&m, vr::TORQUE) > 0.0,
            periodic
        );
        assert!(get(&m, vr::P_POCKET_MIN) > 0.0);
        assert_eq!(outputs(&m), outputs(&fresh), "periodic {periodic}");
        // read again: nothing recomputed, the same values
        m.initial_outputs().unwrap();
        assert_eq!(outputs(&m), outputs(&fresh), "periodic {periodic}");
        m.exit_initialization().unwrap();
        assert_eq!(outputs(&m), outputs(&fresh), "periodic {periodic}");
        assert_eq!(m.save_state(), fresh.save_state(), "periodic {periodic}");
        // and they step alike
        let mut fresh = fresh;
        m.do_step(0.0, 1e-3).unwrap();
        fresh.do_step(0.0, 1e-3).unwrap();
        assert_eq!(outputs(&m), outputs(&fresh), "periodic {periodic}");
    }

    // the exit after a read does not compute the start again: the LP
    // simulation's work counters (a count, not a time) do not move
    let mut m = GearPumpFmu::with_pump(pump());
    m.initial_outputs().unwrap();
    let read = m.solver_stats().expect("the start computed at the read");
    assert!(read.steps > 0, "{read:?}");
    m.exit_initialization().unwrap();
    assert_eq!(m.solver_stats(), Some(read));

    // an input changed after a read: the outputs read then are dropped
    // (0 until the next read), the next read is at the new input
    let mut m = GearPumpFmu::with_pump(pump());
    m.initial_outputs().unwrap();
    let at30 = outputs(&m);
    let (q30, t30) = (get(&m, vr::Q_OUT), get(&m, vr::TORQUE));
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(30.0))
        .unwrap();
    assert_eq!(outputs(&m), at30, "the value held: kept");
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(60.0))
        .unwrap();
    assert_eq!(get(&m, vr::Q_OUT), 0.0);
    m.initial_outputs().unwrap();
    let (q60, t60) = (get(&m, vr::Q_OUT), get(&m, vr::TORQUE));
    assert!(q60 < q30 && t60 > t30, "{q60} {q30} / {t60} {t30}");
    // a parameter too
    m.set_boolean(vr::START_PERIODIC, false).unwrap();
    m.initial_outputs().unwrap();
    assert_ne!(get(&m, vr::Q_OUT), q60);
    m.set_boolean(vr::START_PERIODIC, true).unwrap();
    // changed without a read before the exit: the exit computes afresh
    m.set_real(vr::P_OUT, ATMOSPHERE_PA + bar_to_pa(30.0))
        .unwrap();
    m.exit_initialization().unwrap();
    assert_eq!(outputs(&m), at30);

    // a pressure rise above 500 bar: an error naming p_out, nothing kept
    let mut m = GearPumpFmu::with_pump(pump());
    m.set_real(vr::P_IN, bar_to_pa(0.5)).unwrap();
    m.set_real(vr::P_OUT, bar_to_pa(540.0)).unwrap();
    match m.initial_outputs() {
        Err(ModelError::InvalidValue { name, reason, .. }) => {
            assert_eq!(name, "p_out");
            assert!(reason.contains("500 bar"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(get(&m, vr::Q_OUT), 0.0);
    m.set_real(vr::P_OUT, bar_to_pa(30.5)).unwrap();
    m.initial_outputs().unwrap();
    assert!(get(&m, vr::Q_OUT) > 0.0);
}
